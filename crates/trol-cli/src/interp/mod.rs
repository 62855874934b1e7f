//! `trol interp`: the command interpreter (the manual's INTERP). One API call per line;
//! interactive in a terminal (line editing, history, completion), or a script from a file or
//! a pipe.

pub mod commands;
pub mod scanner;

use std::io::{BufRead, IsTerminal};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use clap::Args;
use trol::Robot;
use trol_proto::application::FinishMode;
use trol_proto::application::reply::Reply;
use trol_proto::application::request::{Request, long_wait};

use crate::common::{Conn, waiting};
use crate::records;
use commands::{Action, OWN, SPECS, usage};

#[derive(Args, Debug)]
#[command(after_help = "\
Examples:
  trol interp                          # interactive, against trol.cfg's port (or the simulator)
  trol interp pick.trol                # run a script, stop at the first failed command
  trol interp -k pick.trol             # run every line, exit 1 if any failed
  echo 'home 0' | trol interp --port socket://localhost:7000

A line is a command and its arguments, e.g.:
  home 0
  appro test_001 c(-90) straight
  moveii c(400, 0, 150, 0, 1.5708, 0) 1
  getposition cart actual
`help` lists every command with its arguments and ranges.")]
pub struct InterpArgs {
    /// A script: one command per line, `;` starts a comment. Without it, commands come from
    /// the terminal, or line by line from a pipe.
    script: Option<PathBuf>,
    /// Go on after a failed command (the exit status still says that one failed).
    #[arg(short = 'k', long)]
    keep_going: bool,
    #[command(flatten)]
    conn: Conn,
}

/// How one line went.
enum Outcome {
    Ok,
    Failed,
    Quit,
}

struct Session {
    conn: Conn,
    robot: Option<Robot>,
}

impl Session {
    fn robot(&mut self) -> Result<&mut Robot, String> {
        if self.robot.is_none() {
            let (robot, _) = self.conn.robot()?;
            self.robot = Some(robot);
        }
        Ok(self.robot.as_mut().expect("connected"))
    }

    /// Run one line; print its result to stdout, or its error to stderr after `origin`.
    fn line(&mut self, line: &str, origin: &str, echo: bool) -> Outcome {
        let parsed =
            scanner::scan(line).and_then(|tokens| commands::parse(&tokens, line.chars().count()));
        let action = match parsed {
            Ok(a) => a,
            Err(e) => {
                let at = if origin.is_empty() {
                    format!("column {}", e.col)
                } else {
                    format!("{origin}{}", e.col)
                };
                eprintln!("{at}: error: {}\n{}", e.message, e.render(line));
                return Outcome::Failed;
            }
        };
        match action {
            Action::Nothing => Outcome::Ok,
            Action::Quit => Outcome::Quit,
            Action::Help(topic) => match help(topic.as_deref()) {
                Ok(text) => {
                    println!("{text}");
                    Outcome::Ok
                }
                Err(text) => {
                    eprintln!("{}error: {text}", prefix(origin));
                    Outcome::Failed
                }
            },
            Action::Delay(ms) => {
                waiting("delay", || std::thread::sleep(Duration::from_millis(ms)));
                if echo {
                    println!("{}  ->  done", line.trim());
                }
                Outcome::Ok
            }
            Action::Call(req) => match self.call(&req) {
                Ok(text) => {
                    if echo {
                        println!("{}  ->  {text}", line.trim());
                    } else {
                        println!("{text}");
                    }
                    Outcome::Ok
                }
                Err(text) => {
                    if echo {
                        println!("{}  ->  {text}", line.trim());
                    }
                    eprintln!(
                        "{}error: {} failed: {text}",
                        prefix(origin),
                        req.command().api_name()
                    );
                    Outcome::Failed
                }
            },
        }
    }

    /// One API call: Ok(result text) or Err(result text) when it failed.
    fn call(&mut self, req: &Request) -> Result<String, String> {
        let robot = self.robot()?;
        let bytes = req.encode();
        let reply = if long_wait(&bytes).is_some() {
            waiting(&format!("{} ...", req.command().api_name()), || {
                robot.request(req)
            })
        } else {
            robot.request(req)
        };
        match reply {
            Ok(Reply::Code(v)) => {
                let status = matches!(
                    req,
                    Request::Finish {
                        mode: FinishMode::Status
                    }
                );
                if v == 0 || (status && v == 1) {
                    Ok(trol::describe(v))
                } else {
                    let meaning = records::meaning(v);
                    if meaning.is_empty() {
                        Err(trol::describe(v))
                    } else {
                        Err(format!("{}: {meaning}", trol::describe(v)))
                    }
                }
            }
            Ok(other) => Ok(records::reply_text(&other)),
            Err(e) => Err(format!("{}: {e}", trol::describe(e.code()))),
        }
    }
}

/// `file:line: ` before a message, nothing in a terminal.
fn prefix(origin: &str) -> String {
    if origin.is_empty() {
        String::new()
    } else {
        format!("{origin} ")
    }
}

/// The help text: every command, or one.
fn help(topic: Option<&str>) -> Result<String, String> {
    let syntax = "\
Arguments: whole numbers and reals (-90, 1.5708, 1e3); location names (test_001, #park);
location literals c(x, y, z, yaw, pitch, roll) cartesian (mm, rad), j(q1, ..) joint (rad),
p(n1, ..) precision point (encoder counts), numDims = how many values; a bare ( ... ) is the
kind the command expects. The straight flag is 0 / interpolated (default) or 1 / straight.
Commands are case-insensitive, with or without the TROL prefix (TROLMove = move).
Results print as the value and its name (0 (success), -1 (BIOS_NOT_HOMED), ...).";
    match topic {
        None => {
            let mut out = String::from("Commands (the TROL API):\n");
            for s in SPECS {
                out.push_str(&format!("  {:<58} {}\n", usage(s), s.summary));
            }
            out.push_str("Interpreter:\n");
            for (name, args, what) in OWN {
                out.push_str(&format!("  {:<58} {what}\n", format!("{name} {args}")));
            }
            out.push_str(syntax);
            Ok(out)
        }
        Some(t) => {
            if let Some(s) = commands::find(t) {
                return Ok(format!(
                    "{}: {}\n  usage: {}\n{syntax}",
                    s.command.api_name(),
                    s.summary,
                    usage(s)
                ));
            }
            OWN.iter()
                .find(|o| o.0.eq_ignore_ascii_case(t))
                .map(|(n, a, w)| format!("{n} {a}: {w}"))
                .ok_or_else(|| format!("no command `{t}` (`help` lists them)"))
        }
    }
}

pub fn run(a: InterpArgs) -> Result<ExitCode, String> {
    let mut session = Session {
        conn: a.conn.clone(),
        robot: None,
    };
    let interactive = a.script.is_none() && std::io::stdin().is_terminal();
    if interactive {
        return repl(&mut session);
    }
    let (name, reader): (String, Box<dyn BufRead>) = match &a.script {
        Some(path) => {
            let f = std::fs::File::open(path)
                .map_err(|e| format!("cannot read the script {}: {e}", path.display()))?;
            (
                path.display().to_string(),
                Box::new(std::io::BufReader::new(f)),
            )
        }
        None => ("<stdin>".into(), Box::new(std::io::stdin().lock())),
    };
    let mut failed = 0usize;
    for (n, line) in reader.lines().enumerate() {
        let line = line.map_err(|e| format!("{name}: {e}"))?;
        let origin = format!("{name}:{}:", n + 1);
        match session.line(&line, &origin, true) {
            Outcome::Ok => {}
            Outcome::Quit => break,
            Outcome::Failed => {
                failed += 1;
                if !a.keep_going {
                    eprintln!("{name}: stopped at line {} (use -k to go on)", n + 1);
                    return Ok(ExitCode::FAILURE);
                }
            }
        }
    }
    if failed > 0 {
        eprintln!("{name}: {failed} command(s) failed");
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}

/// Completion of command names and keywords.
struct Helper;

impl rustyline::completion::Completer for Helper {
    type Candidate = String;

    fn complete(
        &self,
        line: &str,
        pos: usize,
        _ctx: &rustyline::Context<'_>,
    ) -> rustyline::Result<(usize, Vec<String>)> {
        let head = &line[..pos];
        let start = head
            .rfind(|c: char| c.is_whitespace() || c == '(' || c == ',')
            .map(|i| i + 1)
            .unwrap_or(0);
        let word = head[start..].to_ascii_lowercase();
        let first = head[..start].trim().is_empty();
        let mut words: Vec<String> = Vec::new();
        if first {
            words.extend(
                SPECS
                    .iter()
                    .map(|s| s.command.short_name().to_ascii_lowercase()),
            );
            words.extend(OWN.iter().map(|o| o.0.to_string()));
        } else {
            words.extend(
                [
                    "straight",
                    "interpolated",
                    "wait",
                    "status",
                    "cart",
                    "joint",
                    "prec",
                    "commanded",
                    "actual",
                ]
                .map(String::from),
            );
        }
        let bare = word.strip_prefix("trol").unwrap_or(&word).to_string();
        let found = words.into_iter().filter(|w| w.starts_with(&bare)).collect();
        Ok((start, found))
    }
}

impl rustyline::hint::Hinter for Helper {
    type Hint = String;
}
impl rustyline::highlight::Highlighter for Helper {}
impl rustyline::validate::Validator for Helper {}
impl rustyline::Helper for Helper {}

fn history_file() -> Option<PathBuf> {
    std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".trol_history"))
}

fn repl(session: &mut Session) -> Result<ExitCode, String> {
    use rustyline::error::ReadlineError;
    let mut rl: rustyline::Editor<Helper, rustyline::history::DefaultHistory> =
        rustyline::Editor::new().map_err(|e| format!("cannot start line editing: {e}"))?;
    rl.set_helper(Some(Helper));
    let hist = history_file();
    if let Some(h) = &hist {
        let _ = rl.load_history(h);
    }
    println!("TROL command interpreter. `help` lists the commands, Ctrl-D leaves.");
    loop {
        match rl.readline("trol> ") {
            Ok(line) => {
                if !line.trim().is_empty() {
                    let _ = rl.add_history_entry(line.as_str());
                }
                if let Outcome::Quit = session.line(&line, "", false) {
                    break;
                }
            }
            Err(ReadlineError::Interrupted) => continue,
            Err(ReadlineError::Eof) => break,
            Err(e) => return Err(format!("reading the terminal: {e}")),
        }
    }
    if let Some(h) = &hist {
        let _ = rl.save_history(h);
    }
    Ok(ExitCode::SUCCESS)
}

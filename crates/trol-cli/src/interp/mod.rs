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
use trol::{Robot, Waited};
use trol_proto::application::record::{self, Value};
use trol_proto::application::{Catalog, CommandDef, table};

use crate::common::{
    Conn, catch_interrupts, clear_interrupt, interrupted, sleep_unless_interrupted, stdout_closed,
    waiting,
};
use commands::{Action, OWN, usage};

#[derive(Args, Debug)]
#[command(after_help = "\
Examples:
  trol interp               # interactive, on trol.cfg's port (or the simulator)
  trol interp pick.trol     # run a script, stop at the first failed command
  trol interp -k pick.trol  # run every line, exit 1 if any failed
  echo 'home 0' | trol interp --port socket://localhost:7000

A line is a command and its arguments; the manual's pick example, with
`--locations examples/locations.txt` on the simulator:
  home 0
  finish
  appro test_001 c(-90)
  move test_001 straight
  finish
  close 60
  depart c(-90) straight
  getposition cart actual
`help` lists every command with its arguments and ranges.")]
pub struct InterpArgs {
    /// A script: one command per line, `;` starts a comment. Without it, commands come from
    /// the terminal, or line by line from a pipe.
    script: Option<PathBuf>,
    /// Go on after a failed command (the exit status still says that one failed).
    #[arg(short = 'k', long)]
    keep_going: bool,
    /// Print each command's result as one JSON object per line on stdout (for scripts):
    /// `command`, `ok`, `value` and `name`, and the reply's data (`position`, `status`,
    /// `values`, ...); a failure has `code`, `name`, `error` and, where there is one,
    /// `hint`.
    #[arg(long)]
    json: bool,
    /// Commands an application added, described in FILE (docs/extending.md): the
    /// interpreter reads, checks, sends and shows them like the built-in ones.
    #[arg(long, value_name = "FILE")]
    commands: Option<PathBuf>,
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
    catalog: Catalog,
    json: bool,
    /// The location names completion offers: the location file's at the start, then what
    /// Here, Define, DeleteLocation and ListLocations said (docs/teach.md).
    names: Names,
}

/// Location names, shared with the line editor's completion.
type Names = std::sync::Arc<std::sync::Mutex<Vec<String>>>;

/// A reply as JSON.
fn reply_json(
    def: &CommandDef,
    reply: &trol::Reply,
    codes: &'static trol::CodeTable,
) -> serde_json::Value {
    use serde_json::json;
    let value = reply.value();
    let mut o = json!({
        "command": def.name,
        "ok": true,
        "value": value.0,
        "text": reply.text_for(def, codes),
    });
    // A return value's name; GetStatus's and the position's first word is no code.
    if matches!(
        reply,
        trol::Reply::Code(_) | trol::Reply::Reals { .. } | trol::Reply::Bytes { .. }
    ) && let Some(map) = o.as_object_mut()
    {
        let name = if value.0 == 0 {
            Some("success")
        } else {
            value.name(codes)
        };
        map.insert("name".into(), name.into());
    }
    let extra = match reply {
        trol::Reply::Position(loc) => json!({"position": {
            "form": match loc.tag() {
                trol::Tag::Cart => "cart",
                trol::Tag::Joint => "joint",
                trol::Tag::Prec => "prec",
            },
            "values": loc.to_array6(),
        }}),
        trol::Reply::Status {
            bios_called,
            last,
            transaction,
            epoch,
        } => json!({"status": {
            "bios_called": bios_called,
            "last": last.0,
            "last_name": if last.0 == 0 { Some("success") } else { last.name(codes) },
            "transaction": transaction,
            "epoch": epoch,
        }}),
        trol::Reply::Version { protocol, kind } => json!({"protocol": protocol, "kind": kind}),
        trol::Reply::Codes(codes) => json!({"codes": codes
            .iter()
            .map(|c| json!({"value": c.value, "name": c.name, "meaning": c.meaning}))
            .collect::<Vec<_>>()}),
        trol::Reply::Reals { values, .. } => json!({"values": values}),
        trol::Reply::Bytes { bytes, .. } => json!({"bytes": bytes}),
        trol::Reply::Locations(all) => json!({"locations": all
            .iter()
            .map(|(name, loc)| json!({
                "name": name.as_str(),
                "form": match loc.tag() {
                    trol::Tag::Cart => "cart",
                    trol::Tag::Joint => "joint",
                    trol::Tag::Prec => "prec",
                },
                "values": loc.to_array6(),
            }))
            .collect::<Vec<_>>()}),
        trol::Reply::Gripper(g) => json!({"gripper": {
            "opening_mm": g.opening_mm,
            "held": match &g.held {
                trol::Held::Object(name) => Some(name.as_str()),
                _ => None,
            },
            "known": !matches!(g.held, trol::Held::Unknown),
        }}),
        // The return value alone, or a form this interpreter does not know yet.
        _ => json!({}),
    };
    if let (Some(o), Some(e)) = (o.as_object_mut(), extra.as_object()) {
        o.extend(e.clone());
    }
    o
}

/// Keep the names completion offers up to date after a call that succeeded.
fn note_names(names: &Names, def: &CommandDef, args: &[Value], reply: &trol::Reply) {
    if !reply.value().is_success() {
        return;
    }
    let Ok(mut names) = names.lock() else {
        return;
    };
    let named = match args.first() {
        Some(Value::Name(n)) => Some(n.as_str().to_string()),
        _ => None,
    };
    match (def.code, reply) {
        (_, trol::Reply::Locations(all)) => {
            *names = all.iter().map(|(n, _)| n.as_str().to_string()).collect();
        }
        (table::TROL_HERE | table::TROL_DEFINE, _) => {
            if let Some(n) = named.filter(|n| !names.contains(n)) {
                names.push(n);
                names.sort();
            }
        }
        (table::TROL_DELETE_LOCATION, _) => names.retain(|n| Some(n) != named.as_ref()),
        _ => {}
    }
}

/// A failure as JSON.
fn failure_json(
    def: &CommandDef,
    code: Option<trol::Code>,
    codes: &'static trol::CodeTable,
    error: &str,
) -> serde_json::Value {
    let mut o = serde_json::json!({"command": def.name, "ok": false, "error": error});
    if let (Some(map), Some(code)) = (o.as_object_mut(), code) {
        map.insert("code".into(), code.0.into());
        map.insert("name".into(), code.name(codes).into());
    }
    if let (Some(map), Some(hint)) = (o.as_object_mut(), next_step(error)) {
        map.insert("hint".into(), hint.into());
    }
    o
}

impl Session {
    fn robot(&mut self) -> Result<&mut Robot, String> {
        if self.robot.is_none() {
            let (mut robot, _) = self.conn.robot()?;
            for def in self.catalog.iter() {
                if robot.catalog().get(def.code).is_none() {
                    robot.add_command(*def).map_err(|e| e.to_string())?;
                }
            }
            self.robot = Some(robot);
        }
        Ok(self.robot.as_mut().expect("connected"))
    }

    /// `init`: activate the controller's server with trol.cfg's tool, as
    /// `trol init` does; the connection opened here is kept for what follows.
    fn init(&mut self) -> Result<(), String> {
        let cfg = self.conn.config()?;
        if self.robot.is_none() {
            let mut robot = crate::common::robot_from_config(&cfg, true)?;
            for def in self.catalog.iter() {
                if robot.catalog().get(def.code).is_none() {
                    robot.add_command(*def).map_err(|e| e.to_string())?;
                }
            }
            self.robot = Some(robot);
        }
        let robot = self.robot.as_mut().expect("connected");
        // From now on a reconnect activates a restarted controller again.
        robot.set_reactivate(Some(cfg.tool));
        match trol::activate(robot, &cfg.tool) {
            Ok(()) => Ok(()),
            // The port itself may be dead (the controller restarted): open it again.
            Err(first) => robot.reconnect().map_err(|_| first.to_string()),
        }
    }

    /// `reconnect`: open the port again and check the server.
    fn reconnect(&mut self) -> Result<(), String> {
        match self.robot.as_mut() {
            Some(robot) => robot.reconnect().map_err(|e| e.to_string()),
            // Not connected yet: connecting is the reconnect.
            None => self.robot().map(|_| ()),
        }
    }

    /// Run one line; print its result to stdout, or its error to stderr after `origin`.
    fn line(&mut self, line: &str, origin: &str, echo: bool) -> Outcome {
        let line = line.trim_end_matches(['\r', '\n']);
        if let Some(why) = control_character(line) {
            // Never echoed raw: a NUL or an escape sequence would reach the terminal.
            eprintln!("{}error: {why}", prefix(origin));
            return Outcome::Failed;
        }
        let parsed = scanner::scan(line)
            .and_then(|tokens| commands::parse(&tokens, line.chars().count(), &self.catalog));
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
            Action::Init | Action::Reconnect => {
                let init = matches!(action, Action::Init);
                let result = if init { self.init() } else { self.reconnect() };
                let what = if init { "init" } else { "reconnect" };
                match result {
                    Ok(()) => {
                        say!("{what}  ->  the controller's TROL server answers");
                        Outcome::Ok
                    }
                    Err(e) => {
                        eprintln!("{}error: {what} failed: {e}", prefix(origin));
                        Outcome::Failed
                    }
                }
            }
            Action::Help(topic) => match help(&self.catalog, topic.as_deref()) {
                Ok(text) => {
                    say!("{text}");
                    Outcome::Ok
                }
                Err(text) => {
                    eprintln!("{}error: {text}", prefix(origin));
                    Outcome::Failed
                }
            },
            Action::Delay(ms) => {
                if waiting("delay", || {
                    sleep_unless_interrupted(Duration::from_millis(ms))
                }) {
                    eprintln!("{}error: delay interrupted", prefix(origin));
                    return Outcome::Failed;
                }
                if echo {
                    say!("{}  ->  done", line.trim());
                }
                Outcome::Ok
            }
            Action::Call(def, args) => match self.call_json(&def, &args) {
                Ok((_, j)) if self.json => {
                    say!("{j}");
                    Outcome::Ok
                }
                Ok((text, _)) => {
                    if echo {
                        say!("{}  ->  {text}", line.trim());
                    } else {
                        say!("{text}");
                    }
                    Outcome::Ok
                }
                Err((_, j)) if self.json => {
                    say!("{j}");
                    Outcome::Failed
                }
                Err((text, _)) => {
                    if echo {
                        say!("{}  ->  {text}", line.trim());
                    }
                    eprintln!("{}error: {} failed: {text}", prefix(origin), def.name);
                    // Why, in the words of an embedded real controller's backend (the
                    // profile key a BIOS_UNSETTLED needs, what the controller printed).
                    let why = self
                        .robot
                        .as_mut()
                        .map(|r| r.take_controller_said())
                        .unwrap_or_default();
                    for l in why {
                        eprintln!("  {l}");
                    }
                    if let Some(hint) = next_step(&text) {
                        eprintln!("  hint: {hint}");
                    }
                    Outcome::Failed
                }
            },
        }
    }

    /// One API call: Ok(result text) or Err(result text) when it failed.
    /// One API call: Ok(result text) or Err(result text) when it failed; each with its JSON.
    fn call_json(
        &mut self,
        def: &CommandDef,
        args: &[Value],
    ) -> Result<(String, serde_json::Value), (String, serde_json::Value)> {
        let robot = match self.robot() {
            Ok(r) => r,
            Err(e) => {
                let j = failure_json(
                    def,
                    Some(trol::code::TROL_ERR_COMM),
                    trol::default_codes(),
                    &e,
                );
                return Err((e, j));
            }
        };
        // What the backend said before this call is not this call's reason.
        robot.take_controller_said();
        let codes = robot.codes();
        let plain = !(def.code == table::HOME.code
            || (def.code == table::FINISH.code
                && matches!(args.first(), Some(Value::Int(v)) if *v == table::FINISH_WAIT)));
        if plain {
            let long = record::encode(def, args)
                .map(|bytes| def.extra_wait(&bytes) != Some(Duration::ZERO))
                .unwrap_or(false);
            let reply = if long {
                waiting(&format!("{} ...", def.name), || robot.call(def, args))
            } else {
                robot.call(def, args)
            };
            if let Ok(r) = &reply {
                note_names(&self.names, def, args, r);
            }
            return match reply {
                Ok(r) => Ok((r.text_for(def, codes), reply_json(def, &r, codes))),
                Err(e) => {
                    let code = e.code();
                    let text = match &e {
                        trol::Error::Refused {
                            meaning: Some(m), ..
                        } => {
                            format!("{}: {m}", code.describe(codes))
                        }
                        trol::Error::Refused { .. } => code.describe(codes),
                        e => format!("{}: {e}", code.describe(codes)),
                    };
                    let j = failure_json(def, Some(code), codes, &text);
                    Err((text, j))
                }
            };
        }
        match self.call(def, args) {
            Ok(text) => {
                let j = serde_json::json!({"command": def.name, "ok": true, "value": 0, "name": "success", "text": text});
                Ok((text, j))
            }
            Err(text) => {
                let j = failure_json(def, None, codes, &text);
                Err((text, j))
            }
        }
    }

    fn call(&mut self, def: &CommandDef, args: &[Value]) -> Result<String, String> {
        let robot = self.robot()?;
        // The waits: polled, and Ctrl-C halts the arm and gives the prompt back.
        let wait = def.code == table::FINISH.code
            && matches!(args.first(), Some(Value::Int(v)) if *v == table::FINISH_WAIT);
        if wait || def.code == table::HOME.code {
            let describe = |e: trol::Error, robot: &Robot| {
                format!("{}: {e}", e.code().describe(robot.codes()))
            };
            if !wait {
                // The controller answers Home at once; the wait for the homing follows.
                if let Err(e) = robot.call(def, args) {
                    return Err(match e {
                        trol::Error::Refused { code, .. } => code.describe(robot.codes()),
                        e => describe(e, robot),
                    });
                }
            }
            let label = format!("{} ... (Ctrl-C halts the arm)", def.name);
            return match waiting(&label, || robot.finish_unless(interrupted())) {
                Ok(Waited::Idle) => Ok(trol::Code(0).describe(robot.codes())),
                Ok(Waited::Halted) if !wait => Err("interrupted: Halt sent, the arm has stopped \
                     before it was homed (the axes not yet homed stay so: home again)"
                    .into()),
                Ok(Waited::Halted) => Err("interrupted: Halt sent, the arm has stopped".into()),
                Err(e) => Err(describe(e, robot)),
            };
        }
        let long = record::encode(def, args)
            .map(|bytes| def.extra_wait(&bytes) != Some(Duration::ZERO))
            .unwrap_or(false);
        let reply = if long {
            waiting(&format!("{} ...", def.name), || robot.call(def, args))
        } else {
            robot.call(def, args)
        };
        match reply {
            Ok(r) => Ok(r.text_for(def, robot.codes())),
            Err(trol::Error::Refused { code, meaning, .. }) => {
                let text = code.describe(robot.codes());
                Err(match meaning {
                    Some(m) => format!("{text}: {m}"),
                    None => text,
                })
            }
            Err(e) => Err(format!("{}: {e}", e.code().describe(robot.codes()))),
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
fn help(catalog: &Catalog, topic: Option<&str>) -> Result<String, String> {
    let syntax = "\
Arguments: whole numbers and reals (-90, 1.5708, 1e3); location names (test_001, #park);
location literals c(x, y, z, yaw, pitch, roll) cartesian (mm, rad), j(q1, ..) joint (rad),
p(n1, ..) precision point (encoder counts), numDims = how many values; a bare ( ... ) is the
kind the command expects. The straight flag is 0 / interpolated (default) or 1 / straight.
Commands are case-insensitive, with or without the TROL prefix (TROLMove = move).
Results print as the value and its name (0 (success), -1 (BIOS_NOT_HOMED), ...).";
    // At word boundaries, to the terminal's width (80 columns in a pipe).
    let width = textwrap::termwidth().clamp(40, 200);
    let syntax = textwrap::fill(&syntax.replace('\n', " "), width);
    let entry = |usage: &str, what: &str| {
        const COLUMN: usize = 61;
        if width >= COLUMN + 20 && usage.len() <= COLUMN - 3 {
            let first = format!("  {usage:<58} ");
            let rest = " ".repeat(COLUMN);
            let options = textwrap::Options::new(width)
                .initial_indent(&first)
                .subsequent_indent(&rest);
            textwrap::fill(what, options) + "\n"
        } else {
            let options = textwrap::Options::new(width)
                .initial_indent("      ")
                .subsequent_indent("      ");
            format!("  {usage}\n{}\n", textwrap::fill(what, options))
        }
    };
    match topic {
        None => {
            let mut out = String::from("Commands (the TROL API):\n");
            for d in catalog.iter() {
                out.push_str(&entry(&usage(d), d.help));
            }
            out.push_str("Interpreter:\n");
            for (name, args, what) in OWN {
                out.push_str(&entry(&format!("{name} {args}"), what));
            }
            out.push_str(&syntax);
            Ok(out)
        }
        Some(t) => {
            if let Some(d) = catalog.find(t) {
                return Ok(format!(
                    "{} ({}, code {}): {}\n  usage: {}\n{syntax}",
                    d.name,
                    d.class(),
                    d.code,
                    d.help,
                    usage(d)
                ));
            }
            OWN.iter()
                .find(|o| o.0.eq_ignore_ascii_case(t))
                .map(|(n, a, w)| format!("{n} {a}: {w}"))
                .ok_or_else(|| {
                    format!(
                        "no command `{t}`{} (`help` lists them)",
                        commands::did_you_mean(catalog, &t.to_ascii_lowercase())
                    )
                })
        }
    }
}

pub fn run(a: InterpArgs) -> Result<ExitCode, String> {
    // The configuration is read once, before any command: a bad one is reported now.
    let (cfg, source) = a.conn.config_with_source()?;
    let mut session = Session {
        conn: a.conn.clone(),
        json: a.json,
        robot: None,
        catalog: trol::described::catalog(a.commands.as_deref())?,
        names: Names::default(),
    };
    catch_interrupts();
    let interactive = a.script.is_none() && std::io::stdin().is_terminal();
    if interactive {
        let banner = format!(
            "configuration: {} (port {}, baud {}; `trol config` shows every value)",
            match &source {
                trol::config::ConfigSource::Defaults => "the defaults".to_string(),
                other => other.to_string(),
            },
            cfg.port,
            cfg.baud
        );
        let width = trol_cli::common::wrap_width(std::io::stdout().is_terminal(), || {
            Some(textwrap::termwidth())
        });
        say!("{}", trol_cli::common::wrapped(&banner, width));
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
    for (n, bytes) in reader.split(b'\n').enumerate() {
        let mut bytes = bytes.map_err(|e| format!("{name}: {e}"))?;
        if bytes.last() == Some(&b'\r') {
            bytes.pop();
        }
        let origin = format!("{name}:{}:", n + 1);
        // A comment is never a command, whatever bytes it holds.
        if bytes.iter().find(|b| !b.is_ascii_whitespace()) == Some(&b';') {
            continue;
        }
        // A line that is not text is that line's error, with where it is; -k goes on.
        let outcome = match String::from_utf8(bytes) {
            Ok(line) => session.line(&line, &origin, true),
            Err(e) => {
                let at = e.utf8_error().valid_up_to();
                let byte = e.as_bytes()[at];
                let col = String::from_utf8_lossy(&e.as_bytes()[..at]).chars().count() + 1;
                eprintln!(
                    "{origin}{col}: error: byte 0x{byte:02x} is not UTF-8 text; a script is \
                     plain text (ASCII or UTF-8)"
                );
                Outcome::Failed
            }
        };
        if interrupted().load(std::sync::atomic::Ordering::SeqCst) {
            // Ctrl-C ends a script; the arm is halted whatever the line was doing.
            if let Some(robot) = session.robot.as_mut() {
                let _ = robot.finish_unless(interrupted());
            }
            eprintln!("{name}: interrupted at line {}", n + 1);
            return Ok(ExitCode::from(130));
        }
        if stdout_closed() {
            if let Some(robot) = session.robot.as_mut() {
                let _ = robot.halt();
            }
            eprintln!(
                "{name}: stdout closed at line {}; Halt sent, stopping",
                n + 1
            );
            return Ok(ExitCode::FAILURE);
        }
        match outcome {
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

/// Completion of command names, and, argument by argument, of the words each argument
/// takes: its choices, the straight flag, and location names (those of the location file).
struct Helper {
    catalog: Catalog,
    locations: Names,
}

/// The arguments already typed after the command in `head` (a location literal with its
/// blanks and commas counts as one).
fn args_typed(head: &str) -> usize {
    let mut count: usize = 0;
    let mut depth = 0i32;
    let mut in_word = false;
    for c in head.chars() {
        match c {
            '(' => {
                depth += 1;
                in_word = true;
            }
            ')' => depth -= 1,
            c if c.is_whitespace() && depth <= 0 => {
                if in_word {
                    count += 1;
                }
                in_word = false;
            }
            _ => in_word = true,
        }
    }
    // The command itself is the first word.
    count.saturating_sub(1)
}

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
        let inside = head[..start].matches('(').count() > head[..start].matches(')').count();
        let mut words: Vec<String> = Vec::new();
        if first {
            words.extend(
                self.catalog
                    .iter()
                    .map(|d| d.short_name().to_ascii_lowercase()),
            );
            words.extend(OWN.iter().map(|o| o.0.to_string()));
            words.extend(table::ALIASES.iter().map(|(alias, _)| alias.to_string()));
        } else if inside {
            // Inside a location literal: numbers, nothing to offer.
        } else if let Some(def) = head
            .split_whitespace()
            .next()
            .and_then(|w| self.catalog.find(w))
        {
            let n = args_typed(&head[..start]);
            if let Some(arg) = def.args.get(n) {
                words.extend(commands::words_for(&arg.kind).into_iter().map(String::from));
                if matches!(arg.kind, trol_proto::application::ArgKind::Name)
                    && let Ok(names) = self.locations.lock()
                {
                    words.extend(names.iter().cloned());
                }
            }
        } else if head.trim_start().to_ascii_lowercase().starts_with("help ") {
            words.extend(
                self.catalog
                    .iter()
                    .map(|d| d.short_name().to_ascii_lowercase()),
            );
        }
        let bare = word.strip_prefix("trol").unwrap_or(&word).to_string();
        let found = words
            .into_iter()
            .filter(|w| w.to_ascii_lowercase().starts_with(&bare))
            .collect();
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
    // Location names to offer: the location file's (the embedded simulator's table), then
    // whatever the teaching commands said.
    let locations: Vec<String> = session
        .conn
        .config()
        .ok()
        .and_then(|c| c.locations)
        .and_then(|p| std::fs::read_to_string(p).ok())
        .and_then(|t| trol_a465::arm::parse_locations(&t).ok())
        .map(|l| l.into_iter().map(|(name, _)| name).collect())
        .unwrap_or_default();
    if let Ok(mut names) = session.names.lock() {
        *names = locations;
    }
    rl.set_helper(Some(Helper {
        catalog: session.catalog.clone(),
        locations: session.names.clone(),
    }));
    let hist = history_file();
    if let Some(h) = &hist {
        let _ = rl.load_history(h);
    }
    say!("TROL command interpreter. `help` lists the commands, Ctrl-D leaves.");
    loop {
        match rl.readline("trol> ") {
            Ok(text) => {
                // A bracketed paste of several lines comes as one text: its lines run in
                // order, each as if typed.
                let mut quit = false;
                for line in text.split(['\n', '\r']) {
                    clear_interrupt();
                    if !line.trim().is_empty() {
                        let _ = rl.add_history_entry(line);
                    }
                    let outcome = session.line(line, "", false);
                    if interrupted().load(std::sync::atomic::Ordering::SeqCst) {
                        // Whatever the line did, the arm stops (a wait has halted it already);
                        // the rest of a paste is dropped.
                        if let Some(robot) = session.robot.as_mut() {
                            let _ = robot.finish_unless(interrupted());
                        }
                        break;
                    }
                    if let Outcome::Quit = outcome {
                        quit = true;
                        break;
                    }
                }
                if quit {
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

/// What to do next after a failure, where there is an obvious next step.
fn next_step(failure: &str) -> Option<&'static str> {
    const STEPS: &[(&str, &str)] = &[
        (
            "BIOS_NOT_HOMED",
            "home the arm first: `home 0`, then `finish`",
        ),
        (
            "BIOS_OUT_OF_REACH",
            "the A465 reaches about 711 mm from its shoulder, 330 mm above the base \
             (docs/a465.md); `getposition cart` shows where the tool is. After Home it stands \
             stretched upright (READY), at the edge of its reach: `jog c(0, 0, -100)` or \
             `joint 3 0.5` first",
        ),
        (
            "BIOS_JOINT_LIMIT",
            "`getposition joint` shows the joints; their limits are in docs/a465.md (joint 1 \
             +-175, 2 +-90, 3 +-110, 4 +-180, 5 +-105, 6 +-180 degrees)",
        ),
        (
            "BIOS_BELOW_TABLE",
            "the tool tip would go below the table: aim higher, or lower `table_z` in trol.cfg",
        ),
        (
            "BIOS_TOO_FAST",
            "the trajectory is faster than the arm: give its waypoints later times, or raise \
             `speed` if it is below 100",
        ),
        (
            "BIOS_SINGULAR_PATH",
            "a straight line cannot pass there: leave out `straight`, or go through another point",
        ),
        (
            "TROL_ERR_LOCATION",
            "the controller has no location of that name: give one as c(x, y, z, yaw, pitch, \
             roll), or load a location file (`--locations FILE`, or `locations = FILE` in \
             trol.cfg)",
        ),
        (
            "TROL_ERR_COMM",
            "is the controller there? `trol sim` prints where it serves; a controller in \
             terminal mode needs `init`; after a restart, `reconnect`",
        ),
    ];
    STEPS
        .iter()
        .find(|(name, _)| failure.contains(name))
        .map(|(_, step)| *step)
}

/// Why a line is refused for a control character in it (a NUL, an escape sequence pasted or
/// piped in), with the line shown escaped; `None` for printable text (tabs included).
fn control_character(line: &str) -> Option<String> {
    let (col, c) = line
        .chars()
        .enumerate()
        .find(|(_, c)| c.is_control() && *c != '\t')?;
    Some(format!(
        "the line holds a control character ({}) at column {}: only printable text is read \
         (the line: \"{}\")",
        c.escape_default(),
        col + 1,
        line.escape_default()
    ))
}

#[cfg(test)]
mod control_tests {
    use super::control_character;

    #[test]
    fn control_characters_are_refused_and_shown_escaped() {
        assert_eq!(control_character("home 0"), None);
        assert_eq!(control_character("speed\t50"), None);
        let why = control_character("home\u{1b}[2J 0").unwrap();
        assert!(why.contains("(\\u{1b}) at column 5"), "{why}");
        assert!(!why.contains('\u{1b}'), "shown raw: {why}");
        let why = control_character("ho\0me").unwrap();
        assert!(!why.contains('\0') && why.contains("column 3"), "{why}");
    }
}

//! `trol rapl probe` and `trol rapl term`: first contact with a real C500 (every byte
//! recorded, nothing that can move the arm sent, the conventions fitted from pendant poses),
//! and a plain terminal to it (docs/c500.md, "The first hour with a real arm").

use std::io::{BufRead, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use clap::{Args, Subcommand};
use trol_rapl::backend::Recorder;
use trol_rapl::{Profile, RaplBackend};

#[derive(Subcommand)]
pub enum Rapl {
    /// First contact: open a session, send only commands that cannot move the arm (STATUS,
    /// SERIAL, W0, W2, LISTL) and one unknown word (to learn how this controller refuses),
    /// record every byte with its time (written on every exit, a failed opening included),
    /// and close. With --poses N, ask the operator to move the arm by pendant N times, read
    /// W2 at each pose, and fit the profile's `pulse_scale` and `pulse_zero` (PULSES against
    /// JOINTS), `units`, `angles` and `tool_rotation` (joints against world through the A465
    /// kinematics). What was learned is written to --profile-out.
    #[command(after_help = "\
Examples:
  trol rapl probe --controller /dev/ttyUSB0 --out first.txt \\
    --profile-out contact.toml
  trol rapl probe --controller /dev/ttyUSB0 --profile contact.toml \\
    --out poses.txt --poses 4 --profile-out poses.toml
  trol rapl probe --controller /dev/ttyUSB0 --profile poses.toml \\
    --out home.txt --home-pose --profile-out homed.toml
  trol rapl probe --controller /dev/ttyUSB0 --profile homed.toml \\
    --out steps.txt --measure --profile-out c500.toml

At each pose the probe waits for Enter (end of input stops the poses early). Keep the
controller's tool the bare flange while probing: the fit assumes it.")]
    Probe(ProbeArgs),
    /// A plain terminal to the controller: each line you type goes to the C500 (typed byte by
    /// byte, each echo checked) and its reply is printed. The session is opened (the ACI
    /// switch, NOHELP) and closed (HELP, two Ctrl-Z) for you. Line editing and history in a
    /// terminal; lines from a pipe otherwise. Ctrl-D (or the end of input) leaves.
    #[command(after_help = "\
Examples:
  trol rapl term --controller /dev/ttyUSB0 --profile c500.toml
  printf 'STATUS\\nW2\\n' | trol rapl term --controller /dev/pts/4")]
    Term(TermArgs),
}

#[derive(Args)]
pub struct ProbeArgs {
    /// The C500's host port: a serial device (or socket://HOST:PORT).
    #[arg(long, value_name = "DEVICE")]
    controller: String,
    /// Where to write the transcript: every byte both ways with its time.
    #[arg(long, value_name = "FILE")]
    out: PathBuf,
    /// How to open the session (baud, entry, ...): a RAPL-II profile; default: the safe one.
    #[arg(long, value_name = "FILE")]
    profile: Option<PathBuf>,
    /// Ask for this many poses by pendant and fit the conventions from them.
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u16).range(0..=20))]
    poses: u16,
    /// Right after HOME (typed in `trol rapl term`), with the arm not moved since: record
    /// where it stands as `home_joints` once you confirm it stands at its home marks (reads
    /// only: STATUS, and W2 twice). A Home through TROL is refused until the profile has
    /// them.
    #[arg(long)]
    home_pose: bool,
    /// After first contact (and the poses), settle by supervised motions what no reading
    /// tells: MA/MI's units (MI of 0.05 on joint 6), JOG's frame (JOG 0,0,1, where the tool
    /// does not point up), when a motion's ACK comes (JOINT 6,20) and which stop (HALT,
    /// ABORT, Ctrl-C) stops a running motion, each undone at once, at SPEED 5. The arm must be
    /// homed, in free space, and someone's hand on the emergency stop: the probe asks for
    /// `yes` first and moves nothing without it.
    #[arg(long)]
    measure: bool,
    /// Where to write the profile with what was learned (an existing file is not overwritten).
    #[arg(long, value_name = "FILE", default_value = "c500.toml")]
    profile_out: PathBuf,
}

#[derive(Args)]
pub struct TermArgs {
    /// The C500's host port: a serial device (or socket://HOST:PORT).
    #[arg(long, value_name = "DEVICE")]
    controller: String,
    /// How to open the session (baud, entry, ...): a RAPL-II profile; default: the safe one.
    #[arg(long, value_name = "FILE")]
    profile: Option<PathBuf>,
    /// Record every byte both ways with its time into FILE when the terminal closes.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
}

pub fn run(r: Rapl) -> Result<(), String> {
    match r {
        Rapl::Probe(a) => probe(a),
        Rapl::Term(a) => term(a),
    }
}

fn load_profile(path: Option<&Path>) -> Result<Profile, String> {
    match path {
        Some(p) => Profile::from_file(p).map_err(|e| e.to_string()),
        None => Ok(Profile::default()),
    }
}

/// Open a session on `device` as `profile` says, adding every byte to `record` when given.
fn open(device: &str, profile: Profile, record: Option<Recorder>) -> Result<RaplBackend, String> {
    let settings = trol_port::PortSettings {
        baud: profile.baud,
        ..Default::default()
    };
    let port = trol_port::open(device, &settings).map_err(|e| e.to_string())?;
    RaplBackend::connect_with(
        port,
        profile,
        Some(Box::new(|line: &str| tracing::info!("c500: {line}"))),
        record,
    )
    .map_err(|e| e.to_string())
}

fn write_transcript(record: &Recorder, path: &Path) -> Result<(), String> {
    let text = record.lock().map(|t| t.to_text()).unwrap_or_default();
    std::fs::write(path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

fn probe(a: ProbeArgs) -> Result<(), String> {
    if a.profile_out.exists() {
        return Err(format!(
            "{} exists: name another file with --profile-out, or remove it",
            a.profile_out.display()
        ));
    }
    let base = load_profile(a.profile.as_deref())?;
    let record = Recorder::default();
    let opened = open(&a.controller, base.clone(), Some(record.clone()));
    let mut b = match opened {
        Ok(b) => b,
        Err(e) => {
            // The bytes of a first contact that failed are the ones that matter most.
            write_transcript(&record, &a.out)?;
            return Err(format!(
                "{e}\ntranscript (every byte, with its time): {}",
                a.out.display()
            ));
        }
    };
    say!("trol rapl probe: session open on {}", a.controller);
    let stdin = std::io::stdin();
    let mut input = stdin.lock();
    let contact = trol_rapl::probe::first_contact(&mut b, usize::from(a.poses), &mut |k, n| {
        say!(
            "pose {k} of {n}: move the arm by pendant (vary every joint; tilt the wrist away \
             from straight down), hand control back to the host, then press Enter"
        );
        let mut line = String::new();
        Ok(input.read_line(&mut line)? > 0)
    });
    // Where HOME leaves the arm (issue 62: a Home is done only with the arm seen there),
    // recorded once the person at it has seen it at its home marks.
    let home_pose = if a.home_pose {
        say!(
            "Does the arm stand where HOME left it (not moved since), each joint at its home \
             marks? Type yes to record where it stands as home_joints (a Home is refused \
             until the profile has them), anything else to skip:"
        );
        let mut line = String::new();
        let yes = input.read_line(&mut line).is_ok() && line.trim().eq_ignore_ascii_case("yes");
        if yes {
            match trol_rapl::probe::home_pose(&mut b) {
                Ok(q) => {
                    say!("home_joints = {q:?}");
                    Some(q)
                }
                Err(e) => {
                    say!("home_joints not recorded: {e}");
                    None
                }
            }
        } else {
            say!("home_joints not recorded: a Home stays refused until the profile has them");
            None
        }
    } else {
        None
    };
    let measured = if a.measure {
        say!(
            "the arm will move: SPEED 5, then MI 0,0,0,0,0,0.05 and back, JOG 0,0,1 and back, \
             JOINT 6,20 and back. It must be homed and in free space (not stretched out), with \
             a hand on the emergency stop. Type yes to go on:"
        );
        let mut line = String::new();
        let yes = input.read_line(&mut line).is_ok() && line.trim().eq_ignore_ascii_case("yes");
        if yes {
            let m = trol_rapl::probe::measure(&mut b, &mut |l| say!("  {l}"));
            match &m {
                Ok(m) => say!(
                    "measured: joint_units = \"{}\", jog_frame = \"{}\", motion_ack = \"{}\", \
                     halt = \"{}\"",
                    m.joint_units,
                    m.jog_frame,
                    match m.motion_ack {
                        trol_rapl::profile::MotionAck::Start => "start",
                        trol_rapl::profile::MotionAck::End => "end",
                    },
                    match m.halt {
                        Some(trol_rapl::profile::Halt::Halt) => "halt",
                        Some(trol_rapl::profile::Halt::Abort) => "abort",
                        Some(trol_rapl::profile::Halt::CtrlC) => "ctrl-c",
                        None => "ctrl-c (a motion holds the line)",
                    }
                ),
                Err(e) => say!("the supervised steps stopped: {e}"),
            }
            m.ok()
        } else {
            say!("not confirmed: nothing moved");
            None
        }
    } else {
        None
    };
    b.close();
    write_transcript(&record, &a.out)?;
    for (line, r) in &contact.replies {
        match r {
            Ok(text) => say!("{line}:{}", indent(text)),
            Err(e) => say!("{line}: no answer: {e}"),
        }
    }
    say!(
        "transcript (every byte, with its time): {}",
        a.out.display()
    );
    let mut profile = base.clone();
    let mut learned = Vec::new();
    match &contact.refusal {
        Some(Ok(form)) => {
            say!("refusal form: \"{form}\" (from the answer to an unknown word)");
            profile.refusal = vec![form.clone()];
            learned.push(format!("refusal = [\"{form}\"]"));
        }
        Some(Err(e)) => say!("refusal form not learned: {e}"),
        None => {}
    }
    let fit = match contact.fit {
        Some(Ok(fit)) => {
            profile = fit.apply(&profile);
            match &fit.pulses {
                Ok(_) => learned.push("pulse_scale, pulse_zero".into()),
                Err(e) => say!("pulses not fitted: {e}"),
            }
            learned.push(format!(
                "units = \"{}\", angles = \"{}\", tool_rotation = {:?}",
                match fit.units {
                    trol_rapl::profile::Units::Inch => "inch",
                    _ => "mm",
                },
                fit.angles,
                fit.tool_rotation
            ));
            Some(fit)
        }
        Some(Err(e)) => {
            say!("the conventions could not be fitted: {e}");
            None
        }
        None => None,
    };
    if let Some(m) = &measured {
        profile = m.apply(&profile);
        learned.push("joint_units, jog_frame, motion_ack (supervised steps)".into());
    }
    if let Some(q) = home_pose {
        profile.home_joints = Some(q);
        learned.push("home_joints (where HOME left the arm, confirmed at its marks)".into());
    }
    if learned.is_empty() {
        return Err("nothing was learned: no profile written".into());
    }
    let mut head = format!(
        "# Learned by `trol rapl probe` on {}: {}.\n",
        a.controller,
        learned.join("; ")
    );
    if let Some(fit) = &fit {
        head.push_str(&format!(
            "# {} W2 readings: the WORLD row matched the A465 kinematics within {:.2} mm and \
             {:.2} degrees.\n",
            contact.readings.len(),
            fit.position_error_mm,
            fit.angle_error_deg
        ));
    }
    if measured.is_none() {
        head.push_str(
            "# Not learned by reading: the units of MA and MI (joint_units), JOG's frame\n\
             # (jog_frame) and when a motion's ACK comes (motion_ack); until the first two are\n\
             # set those commands are refused. `trol rapl probe --measure` settles them by\n\
             # supervised motions (docs/c500.md, the first hour, step 5).\n",
        );
    }
    std::fs::write(&a.profile_out, format!("{head}{}", profile.to_toml()))
        .map_err(|e| format!("cannot write {}: {e}", a.profile_out.display()))?;
    say!(
        "learned: {}; profile written to {}",
        learned.join("; "),
        a.profile_out.display()
    );
    Ok(())
}

fn indent(text: &str) -> String {
    let lines: Vec<&str> = text
        .split(['\r', '\n'])
        .filter(|l| !l.trim().is_empty())
        .collect();
    if lines.len() <= 1 {
        return format!(" {}", lines.first().copied().unwrap_or("ok"));
    }
    lines.iter().map(|l| format!("\n  {l}")).collect()
}

/// Ctrl-C in the terminal: stop what runs.
static STOP: AtomicBool = AtomicBool::new(false);
/// A second Ctrl-C: close the session and leave.
static QUIT: AtomicBool = AtomicBool::new(false);

/// Commands that may wait for a motion: their reply gets the profile's motion timeout.
const LONG: &[&str] = &["FINISH", "HOME", "READY"];

fn term(a: TermArgs) -> Result<(), String> {
    let profile = load_profile(a.profile.as_deref())?;
    let (short, long) = (
        Duration::from_millis(profile.reply_timeout_ms),
        Duration::from_secs(profile.motion_timeout_s),
    );
    let record = a.out.is_some().then(Recorder::default);
    let mut b = open(&a.controller, profile, record.clone())?;
    // Ctrl-C while a line runs: the controller's stop; a second one closes the session.
    let installed = ctrlc::set_handler(|| {
        if STOP.swap(true, Ordering::SeqCst) {
            QUIT.store(true, Ordering::SeqCst);
            eprintln!("\ninterrupted twice: closing the session");
        } else {
            eprintln!("\ninterrupted: stopping the controller (Ctrl-C again closes the session)");
        }
    });
    if let Err(e) = installed {
        tracing::warn!("Ctrl-C will end the terminal without stopping the controller: {e}");
    }
    let run_line = |b: &mut RaplBackend, line: &str| {
        let line = line.trim();
        if line.is_empty() {
            return;
        }
        let word = line.split_whitespace().next().unwrap_or("");
        let t = if LONG.iter().any(|k| k.eq_ignore_ascii_case(word)) {
            long
        } else {
            short
        };
        match b.type_line_unless(&line.to_ascii_uppercase(), t, &STOP) {
            Ok(r) => {
                let body: Vec<&str> = r
                    .text
                    .split(['\r', '\n'])
                    .filter(|l| {
                        !l.trim_matches(|c: char| c.is_whitespace() || c == '\0')
                            .is_empty()
                    })
                    .collect();
                for l in body {
                    say!("{l}");
                }
                match b.refusal(&r) {
                    Some(_) => say!("refused"),
                    None => say!("{}", if r.ack { "ok (ACK)" } else { "ok" }),
                }
            }
            Err(e) => say!("error: {e}"),
        }
    };
    // The controller's stop, once per Ctrl-C that no running line took (a motion under way
    // after its line returned).
    let mut stopped = false;
    let stop_between = |b: &mut RaplBackend, stopped: &mut bool| {
        if STOP.load(Ordering::SeqCst) && !*stopped {
            *stopped = true;
            match trol_controller::backend::Backend::halt(b) {
                Ok(0) => say!("stopped (Ctrl-C again closes the session)"),
                Ok(c) => say!("the stop was refused ({c})"),
                Err(e) => say!("error: {e}"),
            }
        }
    };
    if std::io::stdin().is_terminal() {
        use rustyline::error::ReadlineError;
        let mut rl = rustyline::DefaultEditor::new()
            .map_err(|e| format!("cannot start line editing: {e}"))?;
        let hist = std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".trol_rapl_history"));
        if let Some(h) = &hist {
            let _ = rl.load_history(h);
        }
        say!(
            "RAPL-II terminal on {} (session open; Ctrl-D closes it and leaves)",
            a.controller
        );
        loop {
            match rl.readline(">> ") {
                Ok(line) => {
                    if !line.trim().is_empty() {
                        let _ = rl.add_history_entry(line.as_str());
                    }
                    STOP.store(false, Ordering::SeqCst);
                    run_line(&mut b, &line);
                    // A Ctrl-C the line took has stopped the controller already.
                    stopped = STOP.load(Ordering::SeqCst);
                    if QUIT.load(Ordering::SeqCst) {
                        break;
                    }
                }
                Err(ReadlineError::Interrupted) => {
                    // At the prompt: the controller's stop; a second in a row leaves.
                    if STOP.swap(true, Ordering::SeqCst) {
                        break;
                    }
                    stop_between(&mut b, &mut stopped);
                    continue;
                }
                Err(ReadlineError::Eof) => break,
                Err(e) => return Err(format!("reading the terminal: {e}")),
            }
        }
        if let Some(h) = &hist {
            let _ = rl.save_history(h);
        }
    } else {
        // Lines from a pipe, read on their own thread, so a Ctrl-C between two lines is
        // acted on at once.
        let (tx, rx) = std::sync::mpsc::channel::<std::io::Result<String>>();
        std::thread::spawn(move || {
            for line in std::io::stdin().lock().lines() {
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        while !QUIT.load(Ordering::SeqCst) {
            match rx.recv_timeout(Duration::from_millis(20)) {
                Ok(line) => {
                    let line = line.map_err(|e| format!("reading the input: {e}"))?;
                    STOP.store(false, Ordering::SeqCst);
                    run_line(&mut b, &line);
                    stopped = STOP.load(Ordering::SeqCst);
                }
                Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                    stop_between(&mut b, &mut stopped)
                }
                Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => break,
            }
        }
    }
    b.close();
    let _ = std::io::stdout().flush();
    if let (Some(out), Some(record)) = (&a.out, &record) {
        write_transcript(record, out)?;
    }
    say!("session closed (the C500's port is back in ACI mode)");
    Ok(())
}

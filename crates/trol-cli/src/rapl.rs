//! `trol rapl probe` and `trol rapl term`: first contact with a real C500 (every byte
//! recorded, nothing that can move the arm sent, the conventions fitted from pendant poses),
//! and a plain terminal to it (docs/c500.md, "The first hour with a real arm").

use std::io::{BufRead, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

use clap::{Args, Subcommand};
use trol_rapl::{Profile, RaplBackend};

#[derive(Subcommand)]
pub enum Rapl {
    /// First contact: open a session, send only commands that cannot move the arm (STATUS,
    /// SERIAL, W0, W2, LISTL), record every byte with its time, and close. With --poses N,
    /// ask the operator to move the arm by pendant N times, read W2 at each pose, and fit the
    /// profile's `units`, `angles` and `joint_units` (joints against world through the A465
    /// kinematics); the fitted profile is written to --profile-out.
    #[command(after_help = "\
Examples:
  trol rapl probe --controller /dev/ttyUSB0 --out first.txt
  trol rapl probe --controller /dev/ttyUSB0 --out poses.txt --poses 4 --profile-out c500.toml

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
    /// With --poses: where to write the fitted profile (an existing file is not overwritten).
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

/// Open a session on `device` as `profile` says, recording when asked.
fn open(device: &str, profile: Profile, record: bool) -> Result<RaplBackend, String> {
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

fn write_transcript(b: &RaplBackend, path: &Path) -> Result<(), String> {
    let text = b.transcript().map(|t| t.to_text()).unwrap_or_default();
    std::fs::write(path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

fn probe(a: ProbeArgs) -> Result<(), String> {
    if a.poses > 0 && a.profile_out.exists() {
        return Err(format!(
            "{} exists: name another file with --profile-out, or remove it",
            a.profile_out.display()
        ));
    }
    let base = load_profile(a.profile.as_deref())?;
    let mut b = open(&a.controller, base.clone(), true)?;
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
    b.close();
    write_transcript(&b, &a.out)?;
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
    let Some(fit) = contact.fit else {
        return Ok(());
    };
    let fit = fit.map_err(|e| format!("the conventions could not be fitted: {e}"))?;
    let profile = fit.apply(&base);
    let text = format!(
        "# Fitted by `trol rapl probe --poses {}` from {} W2 readings: the WORLD row matched the\n\
         # A465 kinematics within {:.2} mm and {:.2} degrees. joint_units is the unit of the\n\
         # JOINTS row; that MA and MI take the same unit is an assumption: check it with one\n\
         # supervised `mi` at speed 5 (docs/c500.md, \"Settle the conventions\").\n{}",
        a.poses,
        contact.readings.len(),
        fit.position_error_mm,
        fit.angle_error_deg,
        profile.to_toml()
    );
    std::fs::write(&a.profile_out, text)
        .map_err(|e| format!("cannot write {}: {e}", a.profile_out.display()))?;
    say!(
        "fitted: units = \"{}\", angles = \"{}\", joint_units = \"{}\" (within {:.2} mm, \
         {:.2} deg); profile written to {}",
        match fit.units {
            trol_rapl::profile::Units::Inch => "inch",
            _ => "mm",
        },
        fit.angles,
        fit.joint_units,
        fit.position_error_mm,
        fit.angle_error_deg,
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

/// Commands that may wait for a motion: their reply gets the profile's motion timeout.
const LONG: &[&str] = &["FINISH", "HOME", "READY"];

fn term(a: TermArgs) -> Result<(), String> {
    let profile = load_profile(a.profile.as_deref())?;
    let (short, long) = (
        Duration::from_millis(profile.reply_timeout_ms),
        Duration::from_secs(profile.motion_timeout_s),
    );
    let mut b = open(&a.controller, profile, a.out.is_some())?;
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
        match b.type_line(&line.to_ascii_uppercase(), t) {
            Ok(r) => {
                let body: Vec<&str> = r
                    .text
                    .split(['\r', '\n'])
                    .filter(|l| !l.trim().is_empty())
                    .collect();
                for l in body {
                    say!("{l}");
                }
                match r.error {
                    Some((n, t)) => say!("{n:03}-{t}."),
                    None => say!("{}", if r.ack { "ok (ACK)" } else { "ok" }),
                }
            }
            Err(e) => say!("error: {e}"),
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
                    run_line(&mut b, &line);
                }
                Err(ReadlineError::Interrupted) => continue,
                Err(ReadlineError::Eof) => break,
                Err(e) => return Err(format!("reading the terminal: {e}")),
            }
        }
        if let Some(h) = &hist {
            let _ = rl.save_history(h);
        }
    } else {
        for line in std::io::stdin().lock().lines() {
            let line = line.map_err(|e| format!("reading the input: {e}"))?;
            run_line(&mut b, &line);
        }
    }
    b.close();
    let _ = std::io::stdout().flush();
    if let Some(out) = &a.out {
        write_transcript(&b, out)?;
    }
    say!("session closed (the C500's port is back in ACI mode)");
    Ok(())
}

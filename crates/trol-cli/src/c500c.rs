//! `trol c500c`: an A465 on its C500C (docs/c500c.md): first contact that only reads.

use std::path::PathBuf;
use std::time::Duration;

use clap::{Args, Subcommand};

/// An A465 on its C500C.
#[derive(Subcommand, Debug)]
pub enum C500c {
    /// First contact: Ctrl-E and two CR, `crosver`, `ash APP` where it does not run yet,
    /// `robotver`, `armstat`, `w0`, `w2`, `speed`, and `exit` (answered y) only where the
    /// probe started ash; nothing that moves the arm or changes a setting. Every byte goes to
    /// --out, also when the probe stops early.
    #[command(after_help = "\
Examples:
  trol c500c probe --controller /dev/ttyUSB0 --out first.txt
  trol sim --c500c &    # a simulated C500C; then:
  trol c500c probe --controller /dev/pts/4 --out first.txt")]
    Probe(ProbeArgs),
}

#[derive(Args, Debug)]
pub struct ProbeArgs {
    /// The front console's serial device, or socket://HOST:PORT (c500c: may lead).
    #[arg(long, value_name = "DEVICE")]
    controller: String,
    /// Baud rate (the console's: 57600).
    #[arg(long, default_value_t = 57600)]
    baud: u32,
    /// The ash application to read through (the factory one: test).
    #[arg(long, default_value = "test")]
    app: String,
    /// Where the transcript goes (`> ` sent, `< ` read).
    #[arg(long, value_name = "FILE")]
    out: PathBuf,
    /// How long to wait for each answer, ms.
    #[arg(long, default_value_t = 3000)]
    wait_ms: u64,
}

/// Run a `trol c500c` command.
pub fn run(c: C500c) -> Result<(), String> {
    match c {
        C500c::Probe(a) => probe(a),
    }
}

fn probe(a: ProbeArgs) -> Result<(), String> {
    let settings = trol_port::PortSettings {
        baud: a.baud,
        ..Default::default()
    };
    let device = a
        .controller
        .strip_prefix(trol_c500c::PREFIX)
        .unwrap_or(&a.controller);
    let mut port = trol_port::open(device, &settings).map_err(|e| e.to_string())?;
    say!("trol c500c probe: reading the C500C on {device} (nothing moves)");
    let contact =
        trol_c500c::probe::first_contact(port.as_mut(), &a.app, Duration::from_millis(a.wait_ms));
    std::fs::write(&a.out, contact.transcript.text())
        .map_err(|e| format!("cannot write {}: {e}", a.out.display()))?;
    for (cmd, r) in &contact.steps {
        match r {
            Ok(lines) => say!("  {cmd}: {} line(s)", lines.len()),
            Err(e) => say!("  {cmd}: {e}"),
        }
    }
    for f in &contact.findings {
        say!("  {f}");
    }
    say!("  every byte: {}", a.out.display());
    match contact.findings.last() {
        Some(f) if f.starts_with("stopped: ") => Err(f.clone()),
        _ => Ok(()),
    }
}

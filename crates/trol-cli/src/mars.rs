//! `trol mars`: an A465 on a PiKRON MARS 8 (docs/mars.md): first contact that only reads.

use std::path::PathBuf;
use std::time::Duration;

use clap::{Args, Subcommand};

/// An A465 on a MARS 8.
#[derive(Subcommand, Debug)]
pub enum Mars {
    /// First contact: `VER?`, `ST?` and `COORDAP?`, each once; nothing else is sent (not even
    /// `ECHO:0`), so nothing moves and nothing is set. Every byte goes to --out.
    #[command(after_help = "\
Examples:
  trol mars probe --controller /dev/ttyUSB0 --out first.txt
  trol sim --mars &    # a simulated unit; then:
  trol mars probe --controller /dev/pts/4 --out first.txt")]
    Probe(ProbeArgs),
}

#[derive(Args, Debug)]
pub struct ProbeArgs {
    /// The unit's serial device (RTS/CTS), or socket://HOST:PORT.
    #[arg(long, value_name = "DEVICE")]
    controller: String,
    /// Baud rate (CTU's units: 19200).
    #[arg(long, default_value_t = 19200)]
    baud: u32,
    /// Where the transcript goes (`> ` sent, `< ` read).
    #[arg(long, value_name = "FILE")]
    out: PathBuf,
    /// How long to wait for each answer, ms.
    #[arg(long, default_value_t = 2000)]
    wait_ms: u64,
}

/// Run a `trol mars` command.
pub fn run(m: Mars) -> Result<(), String> {
    match m {
        Mars::Probe(a) => probe(a),
    }
}

fn probe(a: ProbeArgs) -> Result<(), String> {
    let settings = trol_port::PortSettings {
        baud: a.baud,
        rts_cts: true,
        ..Default::default()
    };
    let device = a
        .controller
        .strip_prefix(trol_mars::PREFIX)
        .unwrap_or(&a.controller);
    let mut port = trol_port::open(device, &settings).map_err(|e| e.to_string())?;
    say!("trol mars probe: asking the unit on {device} (reads only)");
    let contact = trol_mars::probe::first_contact(port.as_mut(), Duration::from_millis(a.wait_ms));
    std::fs::write(&a.out, contact.transcript.text())
        .map_err(|e| format!("cannot write {}: {e}", a.out.display()))?;
    let mut answered = 0;
    for (q, r) in &contact.answers {
        match r {
            Ok(v) => {
                answered += 1;
                say!("  {q}? -> {q}={v}");
            }
            Err(e) => say!("  {q}? -> {e}"),
        }
    }
    if let Some(w) = contact.status_words() {
        say!("  status: {w}");
    }
    say!("  every byte: {}", a.out.display());
    if answered == 0 {
        return Err(format!(
            "no answer from {device}: check the cable (RTS/CTS wired), the baud rate ({}) and \
             that the unit is on",
            a.baud
        ));
    }
    Ok(())
}

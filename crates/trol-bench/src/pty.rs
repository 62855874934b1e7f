//! `trol bench pty`: a small CAT1 transaction between two processes over a pty pair (`trol sim`
//! on one end, this program on the other), and the anchor in the same run: a libmodbus RTU
//! round trip over a pty pair between two processes (anchors/modbus_rtu.c, built here with the
//! machine's C compiler and libmodbus), in alternating rounds.

use std::process::Command;
use std::time::Instant;

use clap::Args;
use serde::Serialize;

/// The anchor's source, built at run time (so that the benchmark needs libmodbus only when run).
const ANCHOR: &str = include_str!("anchors/modbus_rtu.c");

#[derive(Args)]
pub struct PtyArgs {
    /// Transactions (and round trips) per round.
    #[arg(long, default_value_t = 2000, value_parser = clap::value_parser!(u32).range(10..=1_000_000))]
    count: u32,
    /// Rounds, each TROL then libmodbus.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=100))]
    rounds: u32,
    /// The C compiler that builds the anchor (it links libmodbus).
    #[arg(long, default_value = "cc")]
    cc: String,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct Round {
    trol_us: f64,
    libmodbus_us: f64,
}

#[derive(Serialize)]
struct PtyReport {
    transactions_per_round: u32,
    rounds: Vec<Round>,
    /// Medians over the rounds.
    trol_us: f64,
    libmodbus_us: f64,
    /// TROL's median over libmodbus's.
    ratio: f64,
}

/// `trol sim` serving on a new pty (killed when dropped), and the pty's name.
fn start_sim() -> Result<(super::SimProcess, String), String> {
    let (process, found) = super::start_trol_sim(
        &["sim", "--port", "pty", "--server", "--homed"],
        &["serving on "],
    )?;
    let port = super::first_word(&found[0]);
    Ok((process, port))
}

/// A folder of this run's own, removed when dropped.
pub(super) struct Scratch(std::path::PathBuf);

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Build the anchor in a fresh temporary folder; the error says what is missing.
pub(super) fn build_anchor(cc: &str) -> Result<(Scratch, std::path::PathBuf), String> {
    let dir = Scratch(std::env::temp_dir().join(format!("trol-bench-pty-{}", std::process::id())));
    std::fs::create_dir_all(&dir.0).map_err(|e| format!("no temporary folder: {e}"))?;
    let src = dir.0.join("modbus_rtu.c");
    let exe = dir.0.join("modbus_rtu");
    std::fs::write(&src, ANCHOR).map_err(|e| format!("cannot write the anchor: {e}"))?;
    let flags = Command::new("pkg-config")
        .args(["--cflags", "--libs", "libmodbus"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).into_owned())
        .unwrap_or_else(|| "-I/usr/include/modbus -lmodbus".into());
    let out = Command::new(cc)
        .arg("-O2")
        .arg("-o")
        .arg(&exe)
        .arg(&src)
        .args(flags.split_whitespace())
        .arg("-lutil")
        .output()
        .map_err(|e| format!("cannot run the C compiler `{cc}`: {e} (--cc names another)"))?;
    if !out.status.success() {
        return Err(format!(
            "the libmodbus anchor did not build: it needs libmodbus's headers and library \
             (Debian: apt-get install libmodbus-dev); {cc} said: {}",
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    Ok((dir, exe))
}

/// Run the anchor with `args` (`COUNT [SERVER_DEV CLIENT_DEV]`): microseconds a round trip.
pub(super) fn anchor_run(exe: &std::path::Path, args: &[&str]) -> Result<f64, String> {
    let out = Command::new(exe)
        .args(args)
        .output()
        .map_err(|e| format!("cannot run the libmodbus anchor: {e}"))?;
    let text = String::from_utf8_lossy(&out.stdout);
    if !out.status.success() {
        return Err(format!(
            "the libmodbus anchor failed: {}",
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    text.trim()
        .parse()
        .map_err(|_| format!("the libmodbus anchor printed {text:?}, not microseconds"))
}

fn trol_round(port: &str, count: u32) -> Result<f64, String> {
    let cfg = trol::Config {
        port: port.to_string(),
        baud: 38400,
        ..Default::default()
    };
    let mut robot = trol::Connect::config(&cfg)
        .connect()
        .map_err(|e| e.to_string())?;
    robot.speed(100).map_err(|e| e.to_string())?;
    for _ in 0..50 {
        robot.speed(100).map_err(|e| e.to_string())?;
    }
    let started = Instant::now();
    for _ in 0..count {
        robot.speed(100).map_err(|e| e.to_string())?;
    }
    Ok(started.elapsed().as_secs_f64() * 1e6 / f64::from(count))
}

pub(super) fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    }
}

pub fn pty(a: PtyArgs) -> Result<(), String> {
    let (_dir, exe) = build_anchor(&a.cc)?;
    let (_sim, port) = start_sim()?;
    let mut rounds = Vec::new();
    for _ in 0..a.rounds {
        let trol_us = trol_round(&port, a.count)?;
        let libmodbus_us = anchor_run(&exe, &[&a.count.to_string()])?;
        rounds.push(Round {
            trol_us,
            libmodbus_us,
        });
    }
    let t = median(rounds.iter().map(|r| r.trol_us).collect());
    let m = median(rounds.iter().map(|r| r.libmodbus_us).collect());
    let r = PtyReport {
        transactions_per_round: a.count,
        rounds,
        trol_us: t,
        libmodbus_us: m,
        ratio: t / m,
    };
    super::print_report(&r, a.json, |r| {
        let mut s = format!(
            "over a pty pair between two processes, {} each per round:\n",
            r.transactions_per_round
        );
        for (i, x) in r.rounds.iter().enumerate() {
            s += &format!(
                "  round {}: TROL (TROLSpeed, trol sim) {:.1} us, libmodbus RTU round trip \
                 {:.1} us\n",
                i + 1,
                x.trol_us,
                x.libmodbus_us
            );
        }
        s += &format!(
            "median: TROL {:.1} us, libmodbus {:.1} us: {:.2} times",
            r.trol_us, r.libmodbus_us, r.ratio
        );
        s
    })
}

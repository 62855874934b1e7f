//! `trol bench relay`: the paced line between two processes, as a serial cable between two
//! UARTs carries it (issue 43, item 4).
//!
//! A relay process (`trol-bench paced-relay`, started here) holds two pseudo-terminal pairs
//! and hands every byte from one to the other at the end of its tenth bit time, as a UART
//! hands a received byte over when its stop bit ends: a byte starts on the line when it
//! arrives or when the byte before it has left, whichever is later. It counts the bytes it
//! carried and the line's turns (a byte going the other way from the one before it).
//!
//! On one relay, `trol sim` serves on one end and the application's `Robot` asks on the other
//! (TROLSpeed: a CAT1 transaction, 2-byte request and reply). On a second relay of the same
//! program, in the same run, the libmodbus anchor (anchors/modbus_rtu.c) writes one holding
//! register per round trip (8 bytes each way). Rounds alternate. For each, the share of the
//! line's limit (its bytes' line time over the time taken) and what each turn of the line
//! cost beyond its bytes.

use std::io::{BufRead, Read, Write};
use std::sync::Arc;
use std::sync::atomic::{AtomicU8, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use clap::Args;

use super::pty::{self, median};
use serde::Serialize;
use serialport::{SerialPort, TTYPort};

#[derive(Args)]
pub struct RelayArgs {
    /// The line's baud rate (10 bit times a byte).
    #[arg(long, default_value_t = 38400, value_parser = clap::value_parser!(u32).range(1200..=1_000_000))]
    baud: u32,
    /// Transactions (and round trips) per round.
    #[arg(long, default_value_t = 200, value_parser = clap::value_parser!(u32).range(10..=100_000))]
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

#[derive(Args)]
pub struct PacedRelayArgs {
    /// The line's baud rate (10 bit times a byte).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1200..=1_000_000))]
    baud: u32,
}

/// What the relay carried: bytes, turns, and the direction of the last byte (0: none yet).
#[derive(Default)]
struct Carried {
    bytes: AtomicU64,
    turns: AtomicU64,
    last: AtomicU8,
}

/// `trol-bench paced-relay --baud B`: prints `ends A B` (the two ends' paths), then relays
/// until its standard input ends; each line it reads there is answered with
/// `carried BYTES TURNS` so far.
pub fn paced_relay(a: PacedRelayArgs) -> Result<(), String> {
    let pair = || TTYPort::pair().map_err(|e| format!("no pseudo-terminal pair: {e}"));
    // The other ends stay open here for as long as the relay runs, like a cable's plugs:
    // a process that closes its end does not hang the line up for the other.
    let (a_master, a_end) = pair()?;
    let (b_master, b_end) = pair()?;
    let name = |p: &TTYPort| p.name().unwrap_or_default();
    say!("ends {} {}", name(&a_end), name(&b_end));
    let byte = Duration::from_secs_f64(10.0 / f64::from(a.baud));
    let carried = Arc::new(Carried::default());
    let clone = |p: &TTYPort| {
        p.try_clone_native()
            .map_err(|e| format!("cannot share the pty: {e}"))
    };
    for (dir, from, to) in [
        (1u8, clone(&a_master)?, clone(&b_master)?),
        (2u8, clone(&b_master)?, clone(&a_master)?),
    ] {
        let carried = Arc::clone(&carried);
        std::thread::spawn(move || carry(dir, from, to, byte, &carried));
    }
    let stdin = std::io::stdin();
    for line in stdin.lock().lines() {
        if line.is_err() {
            break;
        }
        say!(
            "carried {} {}",
            carried.bytes.load(Ordering::SeqCst),
            carried.turns.load(Ordering::SeqCst)
        );
    }
    drop((a_end, b_end));
    Ok(())
}

/// One direction of the relay: each byte read from `from` is written to `to` at the end of
/// its tenth bit time on the line.
fn carry(dir: u8, mut from: TTYPort, mut to: TTYPort, byte: Duration, carried: &Carried) {
    let _ = from.set_timeout(Duration::from_secs(1));
    let mut buf = [0u8; 4096];
    // When the line is free for the next byte.
    let mut free_at = Instant::now();
    loop {
        let n = match from.read(&mut buf) {
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::TimedOut => continue,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            // Nobody on that end now (EIO): wait for the next to open it.
            Err(_) => {
                std::thread::sleep(Duration::from_millis(5));
                continue;
            }
        };
        let arrived = Instant::now();
        for &b in &buf[..n] {
            let due = arrived.max(free_at) + byte;
            wait_until(due);
            // Counted before it is written: once written, the other end may answer, and the
            // other direction's thread count its byte, before this thread runs again (a
            // loaded machine lost turns so).
            carried.bytes.fetch_add(1, Ordering::SeqCst);
            if carried.last.swap(dir, Ordering::SeqCst) != dir {
                carried.turns.fetch_add(1, Ordering::SeqCst);
            }
            if to.write_all(&[b]).is_err() {
                break;
            }
            free_at = due;
        }
    }
}

/// Sleep until shortly before `due`, then spin to it: a sleeping thread wakes tens of
/// microseconds late (the timer and the scheduler), where a UART's byte is there when its
/// stop bit ends. Without the spin each turn of the line would pay the wake-up once more,
/// an error of the instrument, not of what it measures.
fn wait_until(due: Instant) {
    const SPIN: Duration = Duration::from_micros(150);
    let left = due.saturating_duration_since(Instant::now());
    if left > SPIN {
        std::thread::sleep(left - SPIN);
    }
    while Instant::now() < due {
        std::hint::spin_loop();
    }
}

/// A relay process, killed when dropped; asks it what it carried. Its `ends`: the two
/// devices a process on either side opens.
pub(super) struct Relay {
    child: std::process::Child,
    ask: std::process::ChildStdin,
    answers: std::io::Lines<std::io::BufReader<std::process::ChildStdout>>,
    pub(super) ends: (String, String),
}

impl Relay {
    pub(super) fn start(baud: u32) -> Result<Relay, String> {
        let me = std::env::current_exe().map_err(|e| format!("cannot find this program: {e}"))?;
        let mut child = std::process::Command::new(me)
            .args(["paced-relay", "--baud", &baud.to_string()])
            .stdin(std::process::Stdio::piped())
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::inherit())
            .spawn()
            .map_err(|e| format!("cannot start the relay: {e}"))?;
        let ask = child.stdin.take().expect("piped");
        let mut answers = std::io::BufReader::new(child.stdout.take().expect("piped")).lines();
        let first = answers
            .next()
            .and_then(Result::ok)
            .ok_or("the relay did not say where its ends are")?;
        let mut words = first.split_whitespace().skip(1);
        let (Some(a), Some(b)) = (words.next(), words.next()) else {
            return Err(format!("the relay said {first:?}, not its ends"));
        };
        let ends = (a.to_string(), b.to_string());
        Ok(Relay {
            child,
            ask,
            answers,
            ends,
        })
    }

    /// Bytes and turns carried so far.
    fn carried(&mut self) -> Result<(u64, u64), String> {
        writeln!(self.ask, "?").map_err(|e| format!("the relay is gone: {e}"))?;
        let line = self
            .answers
            .next()
            .and_then(Result::ok)
            .ok_or("the relay is gone")?;
        let n: Vec<u64> = line
            .split_whitespace()
            .skip(1)
            .filter_map(|w| w.parse().ok())
            .collect();
        match n[..] {
            [bytes, turns] => Ok((bytes, turns)),
            _ => Err(format!("the relay said {line:?}")),
        }
    }
}

impl Drop for Relay {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// One side's figures for a round.
#[derive(Serialize, Clone)]
struct Side {
    /// Microseconds per transaction (round trip).
    us_each: f64,
    /// Bytes the line carried per transaction, both ways.
    bytes_each: f64,
    /// Turns of the line per transaction.
    turns_each: f64,
    /// The bytes' line time over the time taken.
    share_of_line_limit: f64,
    /// Microseconds per turn beyond the bytes' line time.
    us_per_turn_beyond_line: f64,
}

#[derive(Serialize)]
struct Round {
    trol: Side,
    /// `None` where the anchor could not be built (no libmodbus).
    libmodbus: Option<Side>,
}

#[derive(Serialize)]
struct RelayReport {
    baud: u32,
    transactions_per_round: u32,
    rounds: Vec<Round>,
    /// Medians over the rounds.
    trol_share_of_line_limit: f64,
    trol_us_per_turn_beyond_line: f64,
    libmodbus_share_of_line_limit: Option<f64>,
    libmodbus_us_per_turn_beyond_line: Option<f64>,
    /// Why there is no anchor, where there is none.
    no_anchor: Option<String>,
}

/// The figures of `n` transactions that took `us_each` each and carried `bytes` and `turns`.
fn side(baud: u32, us_each: f64, (bytes, turns): (u64, u64), n: f64) -> Side {
    let (bytes_each, turns_each) = (bytes as f64 / n, turns as f64 / n);
    let line_us = bytes_each * 10.0 / f64::from(baud) * 1e6;
    Side {
        us_each,
        bytes_each,
        turns_each,
        share_of_line_limit: line_us / us_each,
        us_per_turn_beyond_line: (us_each - line_us) / turns_each.max(1.0),
    }
}

/// What `relay` carried while `run` ran.
fn carried_by(
    relay: &mut Relay,
    run: impl FnOnce() -> Result<f64, String>,
) -> Result<(f64, (u64, u64)), String> {
    let (b0, t0) = relay.carried()?;
    let us = run()?;
    let (b1, t1) = relay.carried()?;
    Ok((us, (b1 - b0, t1 - t0)))
}

pub fn relay(a: RelayArgs) -> Result<(), String> {
    // TROL is measured even where the anchor cannot be built; the report says why not.
    let anchor = pty::build_anchor(&a.cc);
    let mut trol_relay = Relay::start(a.baud)?;
    let mut modbus_relay = match &anchor {
        Ok(_) => Some(Relay::start(a.baud)?),
        Err(_) => None,
    };
    let baud = a.baud.to_string();
    let (_sim, _) = super::start_trol_sim(
        &[
            "sim",
            "--port",
            &trol_relay.ends.0,
            "--baud",
            &baud,
            "--server",
            "--homed",
        ],
        &["serving on "],
    )?;
    let cfg = trol::Config {
        port: trol_relay.ends.1.clone(),
        baud: a.baud,
        ..Default::default()
    };
    let mut robot = trol::Connect::config(&cfg)
        .connect()
        .map_err(|e| format!("TROL through the relay: {e}"))?;
    let mut rounds = Vec::new();
    for _ in 0..a.rounds {
        for _ in 0..10 {
            robot.speed(100).map_err(|e| e.to_string())?;
        }
        let count = a.count;
        let (us, carried) = carried_by(&mut trol_relay, || {
            let started = Instant::now();
            for _ in 0..count {
                robot.speed(100).map_err(|e| e.to_string())?;
            }
            Ok(started.elapsed().as_secs_f64() * 1e6 / f64::from(count))
        })?;
        let trol = side(a.baud, us, carried, f64::from(count));
        let libmodbus = match (&anchor, &mut modbus_relay) {
            (Ok((_, exe)), Some(relay)) => {
                // The anchor's run includes its 50 warm-up round trips, as the relay's
                // count does.
                let (server, client) = relay.ends.clone();
                let (us, carried) = carried_by(relay, || {
                    pty::anchor_run(exe, &[&count.to_string(), &server, &client])
                })?;
                Some(side(a.baud, us, carried, f64::from(count + 50)))
            }
            _ => None,
        };
        rounds.push(Round { trol, libmodbus });
    }
    let m = |f: fn(&Round) -> f64| median(rounds.iter().map(f).collect());
    let anchored = |f: fn(&Side) -> f64| -> Option<f64> {
        let v: Option<Vec<f64>> = rounds.iter().map(|r| r.libmodbus.as_ref().map(f)).collect();
        v.map(median)
    };
    let r = RelayReport {
        baud: a.baud,
        transactions_per_round: a.count,
        trol_share_of_line_limit: m(|r| r.trol.share_of_line_limit),
        trol_us_per_turn_beyond_line: m(|r| r.trol.us_per_turn_beyond_line),
        libmodbus_share_of_line_limit: anchored(|s| s.share_of_line_limit),
        libmodbus_us_per_turn_beyond_line: anchored(|s| s.us_per_turn_beyond_line),
        no_anchor: anchor.as_ref().err().cloned(),
        rounds,
    };
    super::print_report(&r, a.json, |r| {
        let mut s = format!(
            "through a relay process paced at {} baud, {} each per round:\n",
            r.baud, r.transactions_per_round
        );
        for (i, x) in r.rounds.iter().enumerate() {
            let side = |name: &str, v: &Side| {
                format!(
                    "{name} {:.0} us each, {:.1} bytes and {:.1} turns: {:.1} % of the line's \
                     limit, {:.0} us a turn beyond the bytes",
                    v.us_each,
                    v.bytes_each,
                    v.turns_each,
                    v.share_of_line_limit * 100.0,
                    v.us_per_turn_beyond_line
                )
            };
            s += &format!(
                "  round {}: {}\n",
                i + 1,
                side("TROL (TROLSpeed, trol sim)", &x.trol)
            );
            if let Some(m) = &x.libmodbus {
                s += &format!("           {}\n", side("libmodbus (a register written)", m));
            }
        }
        s += &format!(
            "median: TROL {:.1} % of the line's limit ({:.0} us a turn)",
            r.trol_share_of_line_limit * 100.0,
            r.trol_us_per_turn_beyond_line,
        );
        match (
            r.libmodbus_share_of_line_limit,
            r.libmodbus_us_per_turn_beyond_line,
            &r.no_anchor,
        ) {
            (Some(share), Some(turn), _) => {
                s += &format!(", libmodbus {:.1} % ({turn:.0} us a turn)", share * 100.0)
            }
            (_, _, Some(why)) => s += &format!("; no libmodbus anchor: {why}"),
            _ => {}
        }
        s
    })
}

//! `trol-bench` (also run as `trol bench ...`): the measurements written to
//! docs/performance.md. A binary of its own, so that the shipped `trol` carries no benchmark
//! code; `trol bench ARGS` runs this program from beside it.

// `say!` and `tell!`: output that never panics when nobody reads it (trol-cli's library).
#[macro_use]
extern crate trol_cli;

mod faults;
mod lines;
mod pty;
mod view;

use std::process::ExitCode;
use std::time::{Duration, Instant};

use clap::{Args, Parser, Subcommand};
use serde::Serialize;
use trol_comm::{Driver, receive_data, send_data};
use trol_port::memory;
use trol_proto::link::frame::{self, FRAME_SIZE, MAX_MESSAGE};
use trol_proto::link::{Link, LinkConfig};

/// TROL's benchmarks: each prints its figures (as JSON with --json); docs/performance.md
/// quotes them with the command that made them. Also run as `trol bench ...`.
#[derive(Parser)]
#[command(name = "trol bench", version)]
struct Cli {
    /// More log output (-v, -vv); RUST_LOG overrides.
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    verbose: u8,
    #[command(subcommand)]
    bench: Bench,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    precise_timers();
    trol_cli::common::init_logging(cli.verbose);
    match run(cli.bench) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            tell!("trol bench: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Ask the kernel for 1 us of timer slack, before any thread starts (threads inherit it).
///
/// The paced in-memory line (link, transact --paced, gateway) stands for a UART, whose bytes
/// reach the reader by interrupt at the instant their stop bit ends. The line hands each byte
/// over at its instant by a timed wait instead, which Linux lets run late by the thread's
/// timer slack (50 us by default): at every turn of the half-duplex line the frame's last
/// byte would reach the other end that much late, an error of the instrument, not of TROL
/// (at 38400 baud 0.7 ms of a 7.3 ms transaction). Elsewhere (no /proc) nothing changes.
fn precise_timers() {
    #[cfg(target_os = "linux")]
    {
        let _ = std::fs::write("/proc/self/timerslack_ns", "1000");
    }
}

/// `trol sim` with `args`, as its own process (its output read on a thread), and for each of
/// `markers` the text after it in the first line that has it (within 20 s). The process is
/// killed when the caller drops its [`SimProcess`].
fn start_trol_sim(args: &[&str], markers: &[&str]) -> Result<(SimProcess, Vec<String>), String> {
    use std::io::BufRead;
    let mut child = std::process::Command::new(trol_binary()?)
        .args(args)
        .env_remove("TROL_CONFIG")
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .map_err(|e| format!("cannot start trol sim: {e}"))?;
    let out = child.stdout.take().expect("piped");
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in std::io::BufReader::new(out).lines() {
            let Ok(line) = line else { break };
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    let sim = SimProcess(child);
    let deadline = Instant::now() + Duration::from_secs(20);
    let mut found: Vec<Option<String>> = vec![None; markers.len()];
    while found.iter().any(Option::is_none) {
        let left = deadline.saturating_duration_since(Instant::now());
        let Ok(line) = rx.recv_timeout(left) else {
            return Err(format!(
                "trol sim {} did not say where it serves within 20 s",
                args.join(" ")
            ));
        };
        for (m, f) in markers.iter().zip(found.iter_mut()) {
            if let Some(rest) = line.split(m).nth(1) {
                *f = Some(rest.trim().to_string());
            }
        }
    }
    Ok((sim, found.into_iter().flatten().collect()))
}

/// The first word of `text` (the port in `serving on PORT ...`).
fn first_word(text: &str) -> String {
    text.split_whitespace()
        .next()
        .unwrap_or_default()
        .to_string()
}

/// A `trol sim` process, killed when dropped.
struct SimProcess(std::process::Child);

impl SimProcess {
    fn id(&self) -> u32 {
        self.0.id()
    }
}

impl Drop for SimProcess {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// The `trol` binary beside this one (`trol bench view` starts `trol sim --view`).
fn trol_binary() -> Result<std::path::PathBuf, String> {
    let me = std::env::current_exe().map_err(|e| format!("cannot find this program: {e}"))?;
    let trol = me.with_file_name(format!("trol{}", std::env::consts::EXE_SUFFIX));
    if trol.is_file() {
        Ok(trol)
    } else {
        Err(format!(
            "this benchmark runs the `trol` binary, which is not beside {} (build both: cargo \
             build --release -p trol-cli -p trol-bench)",
            me.display()
        ))
    }
}

#[derive(Subcommand)]
enum Bench {
    /// Send one message over an in-memory line paced at a baud rate (8N1, 10 bits a byte)
    /// and report the time, the bytes the line carried and the efficiency.
    ///
    /// Example: trol bench link --baud 38400 --bytes 65535 --json
    Link(LinkArgs),
    /// Time all-solutions inverse kinematics of the A465 over random reachable poses (made by
    /// forward kinematics from random joints within the limits, with a tool transform), and
    /// check every solution by forward kinematics before timing.
    ///
    /// Example: trol bench ik --poses 100000 --json
    Ik(IkArgs),
    /// Time small transactions (TROLSpeed, a 2-byte request and a 2-byte reply) against a
    /// controller: the embedded simulator by default, or --port.
    ///
    /// Example: trol bench transact --count 2000 --json
    Transact(TransactArgs),
    /// Time a set of standard moves of the simulated A465 (in its own time, no clock), and
    /// compare each with the least time the published joint speeds alone would allow.
    ///
    /// Example: trol bench moves --speed 100 --json
    Moves(MovesArgs),
    /// Straight lines of the simulated A465 (in its own time, no clock) from READY and from
    /// poses with J5 = 0 to everyday targets (the table's working volume, the tool down or
    /// level, reachable by a joint move): the share accepted, each line's duration against
    /// its least time, joint limits along it, and its largest distance from the line.
    ///
    /// Example: trol bench lines --count 300 --json
    Lines(lines::LinesArgs),
    /// The whole stack over a damaged line (noise: bit errors both ways; cut: the line dead
    /// at a random byte of each relative move; soak: mixed moves at time scale 1 for a
    /// while), counting corrupted requests executed, corrupted replies accepted, lost and
    /// repeated relative moves, and (soak) the memory used.
    ///
    /// Examples: trol bench faults --mode noise --ber 1e-3 --count 100000 --json
    ///           trol bench faults --mode cut --side reply --count 1000 --recovery getstatus
    ///           trol bench faults --mode soak --seconds 120
    Faults(FaultsArgs),
    /// The whole path to a C500, on lines paced at a baud rate: an application's Robot, TROL's
    /// link, the PCP server with the RAPL-II backend, the RAPL-II line, and the simulated
    /// C500 in real time. Times a small command's round trip (TROLSpeed), GetPosition, and
    /// how long after the end of a motion Finish(FINISH_WAIT) returns, for each way the
    /// backend can find the end of a motion.
    ///
    /// Example: trol bench gateway --count 50 --moves 20 --json
    Gateway(GatewayArgs),
    /// A small CAT1 transaction (TROLSpeed) between two processes over a pty pair, against
    /// `trol sim` on the other end, and the anchor in the same run: a libmodbus RTU round trip
    /// (a register written, 8 bytes each way) over a pty pair between two processes, built
    /// here from anchors/modbus_rtu.c with the C compiler and libmodbus (Debian:
    /// libmodbus-dev); rounds alternate.
    ///
    /// Example: trol bench pty --count 2000 --rounds 3 --json
    Pty(pty::PtyArgs),
    /// What the live view (`trol sim --view`) costs the controller: its CPU while an
    /// application drives the arm through whole motions, with nobody watching, with event
    /// streams open as a page holds one, and with a browser showing the page (--browser);
    /// and how often a stream gets an update while the arm moves and while it stands.
    ///
    /// Example: trol bench view --seconds 10 --browser /usr/bin/chromium --json
    View(view::ViewArgs),
    /// Run every benchmark of docs/performance.md with the arguments written there, each as
    /// its own `trol bench ...` process, and print the table of their figures (Markdown).
    /// Takes about two minutes.
    ///
    /// Example: trol bench all
    All,
}

/// `trol bench all`: each documented command, and the figure the page quotes from it.
fn all() -> Result<(), String> {
    let me = std::env::current_exe().map_err(|e| format!("cannot find this program: {e}"))?;
    let run = |args: &[&str]| -> Result<serde_json::Value, String> {
        let out = std::process::Command::new(&me)
            .args(args)
            .arg("--json")
            .env_remove("TROL_CONFIG")
            .output()
            .map_err(|e| format!("cannot run trol bench {}: {e}", args.join(" ")))?;
        if !out.status.success() {
            return Err(format!(
                "trol bench {} failed: {}",
                args.join(" "),
                String::from_utf8_lossy(&out.stderr)
            ));
        }
        serde_json::from_slice(&out.stdout)
            .map_err(|e| format!("trol bench {}: not JSON: {e}", args.join(" ")))
    };
    let f = |v: &serde_json::Value, key: &str| v[key].as_f64().unwrap_or(f64::NAN);
    let mut rows: Vec<(String, String, String)> = Vec::new();
    for (args, what) in [
        (
            &["link", "--baud", "38400", "--bytes", "65535"][..],
            "64 KiB at 38400 baud",
        ),
        (
            &["link", "--baud", "9600", "--bytes", "4096"][..],
            "4 KiB at 9600 baud",
        ),
        (
            &["link", "--baud", "38400", "--bytes", "8", "--repeat", "5"][..],
            "8 bytes at 38400 baud",
        ),
    ] {
        let v = run(args)?;
        rows.push((
            format!("link: {what}"),
            format!("trol bench {}", args.join(" ")),
            format!(
                "{:.2} % efficiency ({:.2} % the format allows), {:.4} s",
                100.0 * f(&v, "efficiency"),
                100.0 * f(&v, "format_efficiency"),
                f(&v, "seconds")
            ),
        ));
    }
    // EAIK as the anchor where a Python has it (TROL_BENCH_PYTHON, else python3).
    let python = std::env::var("TROL_BENCH_PYTHON").unwrap_or_else(|_| "python3".into());
    let has_eaik = std::process::Command::new(&python)
        .args(["-c", "import eaik, numpy"])
        .output()
        .is_ok_and(|o| o.status.success());
    let ik_args: Vec<&str> = if has_eaik {
        vec!["ik", "--eaik", python.as_str()]
    } else {
        vec!["ik"]
    };
    let v = run(&ik_args)?;
    rows.push((
        "all-solutions IK of the A465".into(),
        format!("trol bench {}", ik_args.join(" ")),
        match v["times_faster_than_eaik"].as_f64() {
            Some(x) => format!(
                "{:.0} ns per pose, {:.2} solutions per pose; EAIK in the same run {:.0} ns \
                 (batched): {x:.1} times faster",
                f(&v, "ns_per_pose"),
                f(&v, "solutions_per_pose"),
                f(&v["eaik"], "ns_per_pose_batched")
            ),
            None => format!(
                "{:.0} ns per pose, {:.2} solutions per pose (no EAIK anchor: set \
                 TROL_BENCH_PYTHON to a Python with `eaik`)",
                f(&v, "ns_per_pose"),
                f(&v, "solutions_per_pose")
            ),
        },
    ));
    let v = run(&["transact", "--count", "5000", "--port", "sim"])?;
    rows.push((
        "a small transaction, embedded controller".into(),
        "trol bench transact --count 5000 --port sim".into(),
        format!(
            "{:.1} us each, {:.0} per second",
            f(&v, "us_per_transaction"),
            f(&v, "transactions_per_second")
        ),
    ));
    let args = ["pty", "--count", "2000", "--rounds", "3"];
    rows.push((
        "a small transaction over a pty pair, two processes".into(),
        format!("trol bench {}", args.join(" ")),
        match run(&args) {
            Ok(v) => format!(
                "{:.1} us each; libmodbus RTU round trip in the same run {:.1} us: {:.2} times",
                f(&v, "trol_us"),
                f(&v, "libmodbus_us"),
                f(&v, "ratio")
            ),
            Err(e) => format!("not measured: {e}"),
        },
    ));
    for (baud, count) in [("38400", "200"), ("9600", "60")] {
        let args = ["transact", "--paced", baud, "--count", count];
        let v = run(&args)?;
        rows.push((
            format!("a small transaction over a line paced at {baud} baud"),
            format!("trol bench {}", args.join(" ")),
            format!(
                "{:.2} ms each, {:.0} bytes: {:.1} % of the line's limit",
                f(&v, "us_per_transaction") / 1000.0,
                f(&v, "bytes_per_transaction"),
                f(&v, "share_of_line_limit") * 100.0
            ),
        ));
    }
    let v = run(&["moves"])?;
    let moves = v.as_array().cloned().unwrap_or_default();
    let within = moves
        .iter()
        .filter(|m| f(m, "seconds") >= f(m, "speed_bound_seconds"))
        .count();
    rows.push((
        "the standard moves at 100 %".into(),
        "trol bench moves".into(),
        format!(
            "{} moves, {within} no faster than the published speeds allow; {:.2} s in all",
            moves.len(),
            moves.iter().map(|m| f(m, "seconds")).sum::<f64>()
        ),
    ));
    let v = run(&["gateway", "--count", "20", "--moves", "10"])?;
    let finish: Vec<String> = v["finish"]
        .as_array()
        .cloned()
        .unwrap_or_default()
        .iter()
        .map(|x| {
            format!(
                "Finish {:.0} ms after the motion's end ({})",
                f(&x["after_motion_end"], "median_ms"),
                x["completion"].as_str().unwrap_or("?")
            )
        })
        .collect();
    rows.push((
        "the whole path to a C500 at 38400 baud".into(),
        "trol bench gateway --count 20 --moves 10".into(),
        format!(
            "round trip {:.1} ms, GetPosition {:.0} ms, {}; RobWork's way {:.1} ms (anchor)",
            f(&v["speed_round_trip"], "median_ms"),
            f(&v["get_position_cart_actual"], "median_ms"),
            finish.join(", "),
            f(&v["robwork_second_motion"], "median_ms"),
        ),
    ));
    let v = run(&["view", "--seconds", "5"])?;
    let cpu: Vec<String> = v["measurements"]
        .as_array()
        .cloned()
        .unwrap_or_default()
        .iter()
        .map(|m| {
            format!(
                "{:.1} % ({})",
                f(m, "controller_cpu_percent"),
                m["watching"].as_str().unwrap_or("?")
            )
        })
        .collect();
    rows.push((
        "the live view's cost to the controller".into(),
        "trol bench view --seconds 5".into(),
        format!(
            "controller CPU {}; {:.1} updates per second while moving, {} while still",
            cpu.join(", "),
            f(&v, "updates_per_second_moving"),
            v["updates_while_still"]
        ),
    ));
    say!("| figure | command (with --json) | result |");
    say!("|---|---|---|");
    for (what, cmd, result) in rows {
        say!("| {what} | `{cmd}` | {result} |");
    }
    Ok(())
}

#[derive(Args)]
pub struct GatewayArgs {
    /// Baud rate of both lines (TROL's and RAPL-II's).
    #[arg(long, default_value_t = 38400, value_parser = clap::value_parser!(u32).range(1200..=4_000_000))]
    baud: u32,
    /// Round trips to time for each small command.
    #[arg(long, default_value_t = 50, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    count: u32,
    /// Motions whose Finish to time, for each completion.
    #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    moves: u32,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct Spread {
    median_ms: f64,
    mean_ms: f64,
    max_ms: f64,
}

impl Spread {
    fn of(mut v: Vec<f64>) -> Spread {
        v.sort_by(f64::total_cmp);
        let n = v.len().max(1) as f64;
        Spread {
            median_ms: v.get(v.len() / 2).copied().unwrap_or(f64::NAN),
            mean_ms: v.iter().sum::<f64>() / n,
            max_ms: v.last().copied().unwrap_or(f64::NAN),
        }
    }
}

#[derive(Serialize)]
struct FinishReport {
    completion: String,
    moves: u32,
    /// From the end of the motion (the simulated arm stands) to Finish's return.
    after_motion_end: Spread,
    /// From the call of TROLJoint (after the Finish of the motion before) to the simulated
    /// arm starting to move.
    joint_call_to_start: Spread,
    /// The same for TROLMA.
    ma_call_to_start: Spread,
}

#[derive(Serialize)]
struct GatewayReport {
    baud: u32,
    /// RobWork's way, on the RAPL-II line alone: the same absolute motion sent again, its
    /// answer held by the controller until the first ended; from the stand to that answer.
    robwork_second_motion: Spread,
    speed_round_trip: Spread,
    get_position_cart_actual: Spread,
    finish: Vec<FinishReport>,
}

#[derive(Args)]
pub struct FaultsArgs {
    /// What to do to the line.
    #[arg(long, value_enum, default_value_t = crate::faults::FaultMode::Noise)]
    mode: crate::faults::FaultMode,
    /// Calls to make (noise, cut).
    #[arg(long, default_value_t = 10_000)]
    count: u64,
    /// Bit error rate, each direction (noise).
    #[arg(long, default_value_t = 1e-3, value_parser = ber)]
    ber: f64,
    /// Seed of the faults and the traffic: the same seed, the same run.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Which direction a cut hits (cut).
    #[arg(long, value_enum, default_value_t = crate::faults::Side::Request)]
    side: crate::faults::Side,
    /// How the application recovers: the API's repeats, or the manual's GetStatus method.
    #[arg(long, value_enum, default_value_t = crate::faults::Recovery::Api)]
    recovery: crate::faults::Recovery,
    /// The block check: crc16 (TROL's default) or lrc (the manual's).
    #[arg(long, default_value = "crc16", value_parser = check)]
    check: trol_proto::link::BlockCheck,
    /// How long the line stays dead at each cut, ms (cut). The link's timeouts here are
    /// 15 ms (a memory line): a cut up to about 60 ms is ridden through by the repeats, a
    /// longer one ends in a clear failure.
    #[arg(long, default_value_t = 60)]
    cut_ms: u64,
    /// How long to run, seconds (soak).
    #[arg(long, default_value_t = 60.0, value_parser = trol_cli::common::positive)]
    seconds: f64,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

fn ber(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if (0.0..=0.1).contains(&v) => Ok(v),
        _ => Err(format!("`{s}` is not a bit error rate 0..0.1")),
    }
}

fn check(s: &str) -> Result<trol_proto::link::BlockCheck, String> {
    match s.to_ascii_lowercase().as_str() {
        "crc16" => Ok(trol_proto::link::BlockCheck::Crc16),
        "lrc" => Ok(trol_proto::link::BlockCheck::Lrc),
        _ => Err(format!("`{s}` is not a block check: crc16 or lrc")),
    }
}

fn faults(a: FaultsArgs) -> Result<(), String> {
    let plan = crate::faults::Plan {
        mode: a.mode,
        count: a.count,
        ber: a.ber,
        seed: a.seed,
        side: a.side,
        recovery: a.recovery,
        check: a.check,
        seconds: a.seconds,
        cut_length: Duration::from_millis(a.cut_ms),
    };
    let r = crate::faults::run(&plan)?;
    print_report(&r, a.json, |r| {
        let mut t = format!(
            "{} ({} check, recovery {}), seed {}: {} calls in {:.1} s, {} failed\n",
            r.mode, r.check, r.recovery, r.seed, r.transactions, r.seconds, r.failed_calls
        );
        if r.mode == "soak" {
            t += &format!(
                "  memory: {} kB at the start, {} kB at the end",
                r.rss_start_kb.map_or("?".into(), |v| v.to_string()),
                r.rss_end_kb.map_or("?".into(), |v| v.to_string())
            );
            return t;
        }
        if r.mode == "noise" {
            t += &format!("  BER {}: {} bits flipped\n", r.ber, r.flipped_bits);
        } else {
            t += &format!("  {} cuts of {} ms\n", r.cuts, r.cut_ms);
        }
        t += &format!(
            "  corrupted requests executed: {}\n  corrupted replies accepted: {}\n  \
             relative moves: {}, lost {}, repeated {}, failed but ran {}\n  \
             executions the controller's log misses: {}",
            r.corrupted_requests_executed,
            r.corrupted_replies_accepted,
            r.relative_moves,
            r.lost_moves,
            r.repeated_moves,
            r.failed_but_ran,
            r.unlogged_executions
        );
        t
    })
}

#[derive(Args)]
pub struct MovesArgs {
    /// The speed setting, percent (1..150).
    #[arg(long, default_value_t = 100, value_parser = clap::value_parser!(u16).range(1..=150))]
    speed: u16,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct MoveReport {
    name: &'static str,
    seconds: f64,
    /// The least time at the published speeds alone (no acceleration, the slowest joint).
    speed_bound_seconds: f64,
}

#[derive(Args)]
pub struct TransactArgs {
    /// How many transactions.
    #[arg(long, default_value_t = 1000, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    count: u32,
    /// Against the simulator over an in-memory line paced at this baud rate (10 bit times a
    /// byte, as a serial line): also the bytes per transaction, the line's own limit, and the
    /// share of it TROL reaches.
    #[arg(long, value_name = "BAUD", value_parser = clap::value_parser!(u32).range(300..=4_000_000))]
    paced: Option<u32>,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    conn: trol_cli::common::Conn,
}

#[derive(Serialize)]
struct TransactReport {
    port: String,
    transactions: u32,
    seconds: f64,
    us_per_transaction: f64,
    transactions_per_second: f64,
    /// Over a paced line (`--paced`): its baud rate, the bytes of one transaction (both
    /// directions), the time those bytes take on the line, and that time's share of the
    /// measured one.
    baud: Option<u32>,
    bytes_per_transaction: Option<f64>,
    line_limit_us: Option<f64>,
    share_of_line_limit: Option<f64>,
}

/// A port that counts the bytes both ways.
struct Counted<P> {
    inner: P,
    bytes: std::sync::Arc<std::sync::atomic::AtomicU64>,
}

impl<P: trol_port::Port> trol_port::Port for Counted<P> {
    fn send(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.bytes
            .fetch_add(bytes.len() as u64, std::sync::atomic::Ordering::Relaxed);
        self.inner.send(bytes)
    }
    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> std::io::Result<usize> {
        let n = self.inner.recv(buf, deadline)?;
        self.bytes
            .fetch_add(n as u64, std::sync::atomic::Ordering::Relaxed);
        Ok(n)
    }
    fn available(&mut self) -> std::io::Result<usize> {
        self.inner.available()
    }
    fn flush_input(&mut self) -> std::io::Result<()> {
        self.inner.flush_input()
    }
    fn name(&self) -> String {
        self.inner.name()
    }
}

/// The simulator over an in-memory line paced at `baud`, with the host's bytes counted.
fn paced_robot(
    baud: u32,
) -> Result<(trol::Robot, std::sync::Arc<std::sync::atomic::AtomicU64>), String> {
    use trol_controller::{Controller, Embedded, Mode, Pcp};
    let (host, ctl) = memory::pair(Some(baud));
    let cfg = LinkConfig::for_line(baud, Duration::ZERO);
    let controller = Controller::new(
        ctl,
        cfg,
        Pcp::new(trol_sim::SimBackend::new(trol_sim::SimSettings::default())),
        Mode::Server,
    );
    let handle = Embedded::spawn(controller);
    let bytes = std::sync::Arc::new(std::sync::atomic::AtomicU64::new(0));
    let port = Counted {
        inner: host,
        bytes: bytes.clone(),
    };
    let mut robot = trol::Robot::over(Box::new(port), cfg, None);
    robot.keep(handle);
    trol::check_server(&mut robot).map_err(|e| e.to_string())?;
    Ok((robot, bytes))
}

#[derive(Args)]
pub struct IkArgs {
    /// How many random poses.
    #[arg(long, default_value_t = 100_000, value_parser = clap::value_parser!(u32).range(1..=10_000_000))]
    poses: u32,
    /// How many passes over the poses to time (the figure is the best pass).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=100))]
    repeat: u32,
    /// Seed of the random poses.
    #[arg(long, default_value_t = 465)]
    seed: u64,
    /// Time EAIK (the `eaik` package from PyPI) in the same run, with this Python (one that
    /// has `eaik` and `numpy`: `python -m pip install eaik`), as the anchor.
    #[arg(long, value_name = "PYTHON")]
    eaik: Option<String>,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct IkReport {
    poses: usize,
    solutions: usize,
    solutions_per_pose: f64,
    max_position_error_mm: f64,
    seconds: f64,
    ns_per_pose: f64,
    /// EAIK in the same run (`--eaik`): its figures, and how many times faster TROL's is than
    /// its batched call.
    eaik: Option<serde_json::Value>,
    times_faster_than_eaik: Option<f64>,
}

/// The EAIK anchor's script (`--eaik`).
const EAIK_SCRIPT: &str = include_str!("anchors/eaik.py");

/// Run EAIK on `n` poses with `python`: its report.
fn eaik_anchor(python: &str, n: usize, seed: u64) -> Result<serde_json::Value, String> {
    let out = std::process::Command::new(python)
        .arg("-c")
        .arg(EAIK_SCRIPT)
        .arg(n.to_string())
        .arg(seed.to_string())
        .output()
        .map_err(|e| format!("cannot run {python}: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "EAIK did not run with {python} (install it: {python} -m pip install eaik): {}",
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    serde_json::from_slice(&out.stdout).map_err(|e| format!("EAIK's report is not JSON: {e}"))
}

#[derive(Args)]
pub struct LinkArgs {
    /// Baud rate of the line.
    #[arg(long, default_value_t = 38400, value_parser = clap::value_parser!(u32).range(300..=4_000_000))]
    baud: u32,
    /// Payload bytes (0..65535).
    #[arg(long, default_value_t = 65535, value_parser = clap::value_parser!(u32).range(0..=65535))]
    bytes: u32,
    /// How many transfers to time (the figures are per transfer, the best run).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1000))]
    repeat: u32,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct LinkReport {
    baud: u32,
    payload_bytes: usize,
    wire_bytes: u64,
    seconds: f64,
    line_seconds: f64,
    efficiency: f64,
    format_efficiency: f64,
    frame_size: usize,
    payload_bytes_per_second: f64,
}

/// Print a report as JSON, or as the line `text` makes of it.
fn print_report<R: Serialize>(
    r: &R,
    json: bool,
    text: impl FnOnce(&R) -> String,
) -> Result<(), String> {
    if json {
        let out = serde_json::to_string_pretty(r).map_err(|e| e.to_string())?;
        say!("{out}");
    } else {
        say!("{}", text(r));
    }
    Ok(())
}

fn run(b: Bench) -> Result<(), String> {
    match b {
        Bench::Link(a) => link(a),
        Bench::Ik(a) => ik(a),
        Bench::Transact(a) => transact(a),
        Bench::Moves(a) => moves(a),
        Bench::Lines(a) => lines::run(a),
        Bench::Faults(a) => faults(a),
        Bench::Gateway(a) => gateway(a),
        Bench::Pty(a) => pty::pty(a),
        Bench::View(a) => view::view(a),
        Bench::All => all(),
    }
}

fn moves(a: MovesArgs) -> Result<(), String> {
    use trol_a465::arm::{Arm, ArmSettings, Target, code, joint_limits};
    let deg = |d: f64| d.to_radians();
    let down = std::f64::consts::FRAC_PI_2;
    let start = [0.0, deg(30.0), deg(60.0), 0.0, deg(90.0), 0.0];
    type Setup = (&'static str, [f64; 6], Target, bool);
    let moves: Vec<Setup> = vec![
        (
            "J1 by 90 deg",
            start,
            Target::Joints([deg(90.0), start[1], start[2], 0.0, start[4], 0.0]),
            false,
        ),
        (
            "J2 by 45 deg",
            start,
            Target::Joints([0.0, deg(-15.0), start[2], 0.0, start[4], 0.0]),
            false,
        ),
        (
            "J3 by 90 deg",
            start,
            Target::Joints([0.0, start[1], deg(-30.0), 0.0, start[4], 0.0]),
            false,
        ),
        (
            "J6 by 180 deg",
            start,
            Target::Joints([0.0, start[1], start[2], 0.0, start[4], deg(180.0)]),
            false,
        ),
        (
            "all joints by 60 deg",
            start,
            Target::Joints([
                deg(60.0),
                deg(-30.0),
                deg(0.0),
                deg(60.0),
                deg(30.0),
                deg(60.0),
            ]),
            false,
        ),
        (
            "READY from the start pose",
            start,
            Target::Joints([0.0; 6]),
            false,
        ),
        (
            "a 300 mm straight line, tool down",
            [0.0; 6],
            Target::Cart([450.0, -150.0, 300.0, 0.0, down, 0.0]),
            true,
        ),
        (
            "a 300 mm joint-interpolated move, tool down",
            [0.0; 6],
            Target::Cart([450.0, -150.0, 300.0, 0.0, down, 0.0]),
            false,
        ),
    ];
    let mut reports = Vec::new();
    for (name, from, target, straight) in moves {
        let mut arm = Arm::new(ArmSettings {
            homed: true,
            table_z: -1e9,
            ..ArmSettings::default()
        });
        // The tool-down moves start 300 mm along y from their end.
        let from = if matches!(target, Target::Cart(_)) {
            let begin = Target::Cart([450.0, 150.0, 300.0, 0.0, down, 0.0]);
            if arm.move_to(begin, false, 0.0) != code::OK {
                return Err(format!("{name}: cannot reach its start"));
            }
            let done = arm.done_at(0.0);
            arm.commanded(done)
        } else {
            from
        };
        let t0 = 1000.0;
        let mut arm2 = Arm::new(ArmSettings {
            homed: true,
            table_z: -1e9,
            ..ArmSettings::default()
        });
        arm2.ma(from, 0.0);
        arm2.set_speed(f64::from(a.speed));
        let r = arm2.move_to(target, straight, t0);
        if r != code::OK {
            return Err(format!("{name}: refused with {r}"));
        }
        let end = arm2.done_at(t0);
        let q_end = arm2.commanded(end);
        let (v, _) = joint_limits(f64::from(a.speed));
        let bound = (0..6)
            .map(|i| (q_end[i] - from[i]).abs() / v[i])
            .fold(0.0, f64::max);
        reports.push(MoveReport {
            name,
            seconds: end - t0,
            speed_bound_seconds: bound,
        });
    }
    print_report(&reports, a.json, |rs| {
        let mut out = format!("moves of the simulated A465 at {} %:\n", a.speed);
        for r in rs {
            out.push_str(&format!(
                "  {:<44} {:6.3} s  (the speeds alone: {:.3} s)\n",
                r.name, r.seconds, r.speed_bound_seconds
            ));
        }
        out
    })
}

fn link(a: LinkArgs) -> Result<(), String> {
    let len = a.bytes as usize;
    debug_assert!(len <= MAX_MESSAGE);
    let message: Vec<u8> = (0..len).map(|i| (i * 131 + 7) as u8).collect();
    let cfg = LinkConfig::for_line(a.baud, Duration::ZERO);
    let mut best: Option<LinkReport> = None;
    // What it does and how long it will take, before the silence of a paced line.
    let line_s = frame::wire_bytes_for(len) as f64 * 10.0 / f64::from(a.baud);
    eprintln!(
        "trol bench link: {len} bytes at {} baud, {} time(s): about {:.1} s of line time each",
        a.baud, a.repeat, line_s
    );
    for round in 0..a.repeat {
        if a.repeat > 1 {
            eprintln!("  round {} of {}", round + 1, a.repeat);
        }
        let (tx, rx) = memory::pair(Some(a.baud));
        let receiver = std::thread::spawn(move || {
            let mut driver = Driver::new(rx);
            let mut link = Link::new(cfg);
            receive_data(&mut driver, &mut link, Duration::from_secs(30))
                .map(|(_, data)| data)
                .map_err(|e| e.to_string())
        });
        let mut driver = Driver::new(tx);
        let mut link = Link::new(cfg);
        let started = Instant::now();
        send_data(&mut driver, &mut link, &message, 0).map_err(|e| e.to_string())?;
        let received = receiver.join().map_err(|_| "receiver thread failed")??;
        let seconds = started.elapsed().as_secs_f64();
        if received != message {
            return Err("the message arrived damaged".into());
        }
        let line = driver.port().stats();
        let wire = line.total();
        let report = LinkReport {
            baud: a.baud,
            payload_bytes: len,
            wire_bytes: wire,
            seconds,
            line_seconds: wire as f64 * 10.0 / f64::from(a.baud),
            efficiency: if wire == 0 {
                0.0
            } else {
                len as f64 / wire as f64
            },
            format_efficiency: len as f64 / frame::wire_bytes_for(len) as f64,
            frame_size: FRAME_SIZE,
            payload_bytes_per_second: len as f64 / seconds,
        };
        if best.as_ref().is_none_or(|b| report.seconds < b.seconds) {
            best = Some(report);
        }
    }
    let r = best.ok_or("no run")?;
    print_report(&r, a.json, |r| {
        format!(
            "{} payload bytes at {} baud: {} bytes on the line, {:.3} s ({:.3} s of line time), \
                 efficiency {:.2} % (frame format allows {:.2} %), {:.0} payload bytes/s",
            r.payload_bytes,
            r.baud,
            r.wire_bytes,
            r.seconds,
            r.line_seconds,
            r.efficiency * 100.0,
            r.format_efficiency * 100.0,
            r.payload_bytes_per_second
        )
    })
}

fn ik(a: IkArgs) -> Result<(), String> {
    use rand::{Rng, SeedableRng};
    use trol_a465::Kinematics;
    use trol_a465::model::limits;
    // Seeded, so that a run can be repeated.
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(a.seed);
    let mut uniform = move || rng.random::<f64>();
    let kin = Kinematics::new([0.0, 0.0, 120.0, 0.0, 0.0, 0.0]);
    let lim = limits();
    let n = a.poses as usize;
    let mut joints = Vec::with_capacity(n);
    let mut poses = Vec::with_capacity(n);
    for _ in 0..n {
        let q: [f64; 6] = std::array::from_fn(|i| (uniform() * 2.0 - 1.0) * lim[i]);
        poses.push(kin.fk(&q));
        joints.push(q);
    }
    // Check once, untimed: every solution reproduces its pose, and the joints that made the
    // pose are among them.
    let mut solutions = 0;
    let mut max_err: f64 = 0.0;
    for (pose, q) in poses.iter().zip(&joints) {
        let all = kin.ik_all(pose, q);
        if all.is_empty() {
            return Err(format!("no solution for the pose of joints {q:?}"));
        }
        solutions += all.len();
        for s in all.as_slice() {
            max_err = max_err.max((kin.fk(&s.q).pos - pose.pos).length());
        }
    }
    if max_err > 1e-6 {
        return Err(format!("a solution misses its pose by {max_err} mm"));
    }
    let mut best = f64::INFINITY;
    for _ in 0..a.repeat {
        let started = Instant::now();
        let mut count = 0usize;
        for (pose, q) in poses.iter().zip(&joints) {
            count += std::hint::black_box(kin.ik_all(std::hint::black_box(pose), q)).len();
        }
        let seconds = started.elapsed().as_secs_f64();
        std::hint::black_box(count);
        best = best.min(seconds);
    }
    let ns_per_pose = best * 1e9 / n as f64;
    // EAIK is slower: a fifth of the poses does for its figure.
    let eaik = match &a.eaik {
        Some(python) => {
            if !a.json {
                eprintln!("timing EAIK on {} poses with {python} ...", (n / 5).max(1));
            }
            Some(eaik_anchor(python, (n / 5).max(1), a.seed)?)
        }
        None => None,
    };
    let times_faster_than_eaik = eaik
        .as_ref()
        .and_then(|e| e["ns_per_pose_batched"].as_f64())
        .map(|e| e / ns_per_pose);
    let r = IkReport {
        poses: n,
        solutions,
        solutions_per_pose: solutions as f64 / n as f64,
        max_position_error_mm: max_err,
        seconds: best,
        ns_per_pose,
        eaik,
        times_faster_than_eaik,
    };
    print_report(&r, a.json, |r| {
        let mut t = format!(
            "{} poses, {:.2} solutions each (largest position error {:.1e} mm): {:.1} ns per pose",
            r.poses, r.solutions_per_pose, r.max_position_error_mm, r.ns_per_pose
        );
        if let (Some(e), Some(x)) = (&r.eaik, r.times_faster_than_eaik) {
            t += &format!(
                "\nEAIK in the same run ({} poses): {:.0} ns per pose batched, {:.0} ns one call \
                 each; TROL's is {x:.1} times faster than the batched call",
                e["poses"],
                e["ns_per_pose_batched"].as_f64().unwrap_or(f64::NAN),
                e["ns_per_pose_one_call_each"].as_f64().unwrap_or(f64::NAN),
            );
        }
        t
    })
}

fn transact(a: TransactArgs) -> Result<(), String> {
    let (mut robot, port, counted) = match a.paced {
        Some(baud) => {
            let (robot, bytes) = paced_robot(baud)?;
            (
                robot,
                format!("sim over a line paced at {baud} baud"),
                Some(bytes),
            )
        }
        None => {
            let (robot, cfg) = a.conn.robot()?;
            (robot, cfg.port, None)
        }
    };
    // One to warm up (the first transaction on a line pays for its set-up).
    robot.speed(100).map_err(|e| e.to_string())?;
    let before = counted
        .as_ref()
        .map_or(0, |b| b.load(std::sync::atomic::Ordering::Relaxed));
    let started = Instant::now();
    for _ in 0..a.count {
        robot.speed(100).map_err(|e| e.to_string())?;
    }
    let seconds = started.elapsed().as_secs_f64();
    let us = seconds * 1e6 / f64::from(a.count);
    let bytes = counted.map(|b| {
        (b.load(std::sync::atomic::Ordering::Relaxed) - before) as f64 / f64::from(a.count)
    });
    let limit = a
        .paced
        .zip(bytes)
        .map(|(baud, n)| n * 10.0 / f64::from(baud) * 1e6);
    let r = TransactReport {
        port,
        transactions: a.count,
        seconds,
        us_per_transaction: us,
        transactions_per_second: f64::from(a.count) / seconds,
        baud: a.paced,
        bytes_per_transaction: bytes,
        line_limit_us: limit,
        share_of_line_limit: limit.map(|l| l / us),
    };
    print_report(&r, a.json, |r| {
        let mut t = format!(
            "{} transactions on {}: {:.1} us each, {:.0} per second",
            r.transactions, r.port, r.us_per_transaction, r.transactions_per_second
        );
        if let (Some(n), Some(l), Some(share)) = (
            r.bytes_per_transaction,
            r.line_limit_us,
            r.share_of_line_limit,
        ) {
            t += &format!(
                "\n{n:.1} bytes per transaction on the line: {l:.1} us of line time, {:.1} % \
                 of the line's limit",
                share * 100.0
            );
        }
        t
    })
}

/// The whole path: Robot -> TROL line -> PCP server + RAPL-II backend -> RAPL-II line ->
/// simulated C500 (time scale 1). The C500's loop notes when the arm comes to a stand.
struct GatewayPath {
    robot: trol::Robot,
    twin: C500Twin,
}

/// The simulated C500 (time scale 1) serving a line paced at the profile's baud rate; its
/// loop notes when the arm comes to a stand.
struct C500Twin {
    stopped_at: std::sync::Arc<std::sync::Mutex<Option<Instant>>>,
    /// When the arm last started to move.
    started_at: std::sync::Arc<std::sync::Mutex<Option<Instant>>>,
    /// When a command that waited for the arm (a motion behind another) went on.
    released_at: std::sync::Arc<std::sync::Mutex<Option<Instant>>>,
    stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
    c500: Option<std::thread::JoinHandle<()>>,
}

impl Drop for C500Twin {
    fn drop(&mut self) {
        self.stop.store(true, std::sync::atomic::Ordering::Relaxed);
        if let Some(t) = self.c500.take() {
            let _ = t.join();
        }
    }
}

/// The simulated C500 and the RAPL-II backend's session with it.
fn c500_line(profile: trol_rapl::Profile) -> Result<(trol_rapl::RaplBackend, C500Twin), String> {
    use std::sync::atomic::AtomicBool;
    use std::sync::{Arc, Mutex};
    let (rapl_host, mut rapl_ctl) = memory::pair(Some(profile.baud));
    let stop = Arc::new(AtomicBool::new(false));
    let stopped_at = Arc::new(Mutex::new(None));
    let started_at = Arc::new(Mutex::new(None));
    let released_at = Arc::new(Mutex::new(None));
    let (flag, noted, released) = (stop.clone(), stopped_at.clone(), released_at.clone());
    let started = started_at.clone();
    let c500_profile = profile.clone();
    let c500 = std::thread::spawn(move || {
        let arm = trol_a465::arm::Arm::new(trol_a465::arm::ArmSettings {
            homed: true,
            ..Default::default()
        });
        let mut c = trol_rapl::C500::new(c500_profile, arm, Vec::new());
        let mut was_moving = false;
        let mut was_waiting = false;
        let _ = trol_rapl::c500::serve_with(
            &mut rapl_ctl,
            &mut c,
            1.0,
            &flag,
            &mut |_| {},
            &mut |c, now| {
                let moving = c.arm_moving(now);
                if was_moving && !moving {
                    *noted.lock().unwrap() = Some(Instant::now());
                }
                if !was_moving && moving {
                    *started.lock().unwrap() = Some(Instant::now());
                }
                was_moving = moving;
                let waiting = c.is_waiting();
                if was_waiting && !waiting {
                    *released.lock().unwrap() = Some(Instant::now());
                }
                was_waiting = waiting;
            },
        );
    });
    let backend = trol_rapl::RaplBackend::connect(Box::new(rapl_host), profile)
        .map_err(|e| format!("the gateway could not open the simulated C500: {e}"))?;
    Ok((
        backend,
        C500Twin {
            stopped_at,
            started_at,
            released_at,
            stop,
            c500: Some(c500),
        },
    ))
}

/// The completions `trol bench gateway` compares: the profile's name for each and the
/// settings that make it.
fn completions() -> Vec<(&'static str, trol_rapl::Profile)> {
    use trol_rapl::profile::Completion;
    let base = trol_rapl::Profile::simulator();
    let finish = trol_rapl::Profile {
        completion: Completion::Finish,
        ctrl_c_ends_finish: true,
        ..base.clone()
    };
    vec![
        ("status (the default)", base.clone()),
        (
            "w5",
            trol_rapl::Profile {
                completion: Completion::W5,
                ..base.clone()
            },
        ),
        ("finish, W2 confirms", finish.clone()),
        (
            "finish, finish_ack_means_arrived",
            trol_rapl::Profile {
                finish_ack_means_arrived: true,
                twin: trol_rapl::profile::Twin {
                    finish_stopped: 37,
                    ..finish.twin.clone()
                },
                ..finish
            },
        ),
    ]
}

/// RobWork's way (c500-rapl.md §1.1 item 7): the motion, then the same absolute motion
/// again, whose answer the controller holds until the first has ended; the time from the
/// arm's stand to that answer, on the RAPL-II line alone (no TROL link, no server).
fn robwork_anchor(baud: u32, moves: u32) -> Result<Spread, String> {
    let (mut backend, twin) = c500_line(trol_rapl::Profile {
        baud,
        ..trol_rapl::Profile::simulator()
    })?;
    let t = Duration::from_secs(30);
    let mut after = Vec::new();
    for i in 0..moves {
        let deg = if i % 2 == 0 { 17.19 } else { 0.0 };
        let ma = format!("MA 0,0,0,0,0,{deg}");
        *twin.released_at.lock().unwrap() = None;
        for _ in 0..2 {
            let r = backend
                .type_line(&ma, t)
                .map_err(|e| format!("`{ma}`: {e}"))?;
            if !r.ack {
                return Err(format!("`{ma}` was not acknowledged: {:?}", r.text));
            }
        }
        let answered = Instant::now();
        // The second MA waited in the controller until the first motion ended.
        let Some(stood) = *twin.released_at.lock().unwrap() else {
            return Err("the second MA was answered before the first motion ended".into());
        };
        after.push(answered.duration_since(stood).as_secs_f64() * 1e3);
    }
    Ok(Spread::of(after))
}

fn gateway_path(profile: trol_rapl::Profile) -> Result<GatewayPath, String> {
    let baud = profile.baud;
    let (backend, twin) = c500_line(profile)?;
    let (trol_host, trol_ctl) = memory::pair(Some(baud));
    let cfg = LinkConfig::for_line(baud, Duration::ZERO);
    let controller = trol_controller::Controller::new(
        trol_ctl,
        cfg,
        trol_controller::Pcp::new(backend),
        trol_controller::Mode::Server,
    );
    let handle = trol_controller::Embedded::spawn(controller);
    let mut robot = trol::Robot::over(Box::new(trol_host), cfg, Some(handle));
    robot.set_codes(trol_rapl::RAPL_CODES);
    Ok(GatewayPath { robot, twin })
}

fn gateway(a: GatewayArgs) -> Result<(), String> {
    let err = |e: trol::Error| e.to_string();
    let base = trol_rapl::Profile {
        baud: a.baud,
        ..trol_rapl::Profile::simulator()
    };
    let mut path = gateway_path(base)?;
    let robot = &mut path.robot;
    robot.speed(100).map_err(err)?;
    let mut speed = Vec::new();
    let mut position = Vec::new();
    for _ in 0..a.count {
        let t = Instant::now();
        robot.speed(100).map_err(err)?;
        speed.push(t.elapsed().as_secs_f64() * 1e3);
        let t = Instant::now();
        robot
            .position(trol::Tag::Cart, trol::PosMode::Actual)
            .map_err(err)?;
        position.push(t.elapsed().as_secs_f64() * 1e3);
    }
    drop(path);

    let mut finish = Vec::new();
    for (completion, profile) in completions() {
        let mut path = gateway_path(trol_rapl::Profile {
            baud: a.baud,
            ..profile
        })?;
        let mut after = Vec::new();
        let (mut joint_start, mut ma_start) = (Vec::new(), Vec::new());
        for i in 0..a.moves {
            // Joint 6 by 0.3 rad (TROLJoint), and back (TROLMA): about a quarter of a
            // second each at full speed.
            *path.twin.stopped_at.lock().unwrap() = None;
            *path.twin.started_at.lock().unwrap() = None;
            let called = Instant::now();
            if i % 2 == 0 {
                path.robot.joint(6, 0.3).map_err(err)?;
            } else {
                path.robot.ma(&[0.0; 6]).map_err(err)?;
            }
            path.robot.finish().map_err(err)?;
            let returned = Instant::now();
            let Some(started) = *path.twin.started_at.lock().unwrap() else {
                return Err(format!(
                    "Finish returned before the arm started (completion {completion})"
                ));
            };
            let to_start = started.duration_since(called).as_secs_f64() * 1e3;
            if i % 2 == 0 {
                joint_start.push(to_start);
            } else {
                ma_start.push(to_start);
            }
            let Some(stood) = *path.twin.stopped_at.lock().unwrap() else {
                return Err(format!(
                    "Finish returned before the arm stood (completion {completion})"
                ));
            };
            after.push(returned.duration_since(stood).as_secs_f64() * 1e3);
        }
        finish.push(FinishReport {
            completion: completion.to_string(),
            moves: a.moves,
            after_motion_end: Spread::of(after),
            joint_call_to_start: Spread::of(joint_start),
            ma_call_to_start: Spread::of(ma_start),
        });
    }
    let robwork = robwork_anchor(a.baud, a.moves)?;
    let r = GatewayReport {
        baud: a.baud,
        robwork_second_motion: robwork,
        speed_round_trip: Spread::of(speed),
        get_position_cart_actual: Spread::of(position),
        finish,
    };
    print_report(&r, a.json, |r| {
        let line = |what: &str, s: &Spread| {
            format!(
                "  {what}: median {:.1} ms, mean {:.1} ms, max {:.1} ms\n",
                s.median_ms, s.mean_ms, s.max_ms
            )
        };
        let mut t = format!(
            "the whole path to a simulated C500, both lines at {} baud:\n",
            r.baud
        );
        t += &line("TROLSpeed round trip", &r.speed_round_trip);
        t += &line(
            "TROLGetPosition (cart, actual)",
            &r.get_position_cart_actual,
        );
        for f in &r.finish {
            t += &line(
                &format!(
                    "Finish(FINISH_WAIT) after the motion's end, completion = {} ({} moves)",
                    f.completion, f.moves
                ),
                &f.after_motion_end,
            );
            t += &line(
                &format!(
                    "  TROLJoint, the call to the arm's start ({})",
                    f.completion
                ),
                &f.joint_call_to_start,
            );
            t += &line(
                &format!("  TROLMA, the call to the arm's start ({})", f.completion),
                &f.ma_call_to_start,
            );
        }
        t += &line(
            "RobWork's way (the motion sent twice; the RAPL-II line alone), after the end",
            &r.robwork_second_motion,
        );
        t.trim_end().to_string()
    })
}

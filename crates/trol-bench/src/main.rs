//! `trol-bench` (also run as `trol bench ...`): the measurements written to
//! docs/performance.md. A binary of its own, so that the shipped `trol` carries no benchmark
//! code; `trol bench ARGS` runs this program from beside it.

// `say!` and `tell!`: output that never panics when nobody reads it (trol-cli's library).
#[macro_use]
extern crate trol_cli;

mod c500c;
mod faults;
mod lines;
mod mars;
mod pick;
mod pty;
mod relay;
mod restarts;
mod view;
mod watch;

mod gateway;
mod ik;
mod moves;
mod transact;

use gateway::*;
use ik::*;
use moves::*;
use transact::*;

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

/// How long a started `trol sim` or `trol gateway` may take to say where it serves: a gateway
/// first makes contact with its controller (a C500's first lines typed and echoed at its
/// baud rate), and five processes share two cores in the bench through processes; a limit
/// on a start, not a figure (issue 68: 20 s ran out on a loaded machine).
const START_LIMIT: Duration = Duration::from_secs(120);

/// `trol sim` with `args`, as its own process (its output read on a thread), and for each of
/// `markers` the text after it in the first line that has it (within [`START_LIMIT`]). The process is
/// killed when the caller drops its [`SimProcess`].
fn start_trol_sim(args: &[&str], markers: &[&str]) -> Result<(SimProcess, Vec<String>), String> {
    use std::io::BufRead;
    let mut child = std::process::Command::new(trol_binary()?)
        .args(args)
        .env_remove("TROL_CONFIG")
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot start trol {}: {e}", args.join(" ")))?;
    let out = child.stdout.take().expect("piped");
    // Its error output, kept (the last 4 KiB) to say why it did not start.
    let said: std::sync::Arc<std::sync::Mutex<String>> = Default::default();
    {
        let (err, said) = (child.stderr.take().expect("piped"), said.clone());
        std::thread::spawn(move || {
            for line in std::io::BufReader::new(err).lines() {
                let Ok(line) = line else { break };
                let mut s = said.lock().unwrap_or_else(|e| e.into_inner());
                s.push_str(&line);
                s.push('\n');
                if s.len() > 4096 {
                    let cut = s.len() - 4096;
                    let cut = (cut..s.len()).find(|&i| s.is_char_boundary(i)).unwrap_or(0);
                    s.drain(..cut);
                }
            }
        });
    }
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
    let deadline = Instant::now() + START_LIMIT;
    let mut found: Vec<Option<String>> = vec![None; markers.len()];
    while found.iter().any(Option::is_none) {
        let left = deadline.saturating_duration_since(Instant::now());
        let Ok(line) = rx.recv_timeout(left) else {
            // Its output ended (it exited) or the limit passed: what it said on stderr tells why.
            std::thread::sleep(Duration::from_millis(100));
            let said = said.lock().unwrap_or_else(|e| e.into_inner()).clone();
            return Err(format!(
                "trol {} did not say where it serves within {} s{}",
                args.join(" "),
                START_LIMIT.as_secs(),
                if said.trim().is_empty() {
                    String::new()
                } else {
                    format!("; it said: {}", said.trim())
                }
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
    /// `trol gateway` (in front of a simulated MARS 8 served here) killed at a random
    /// instant of each relative move and started again on the same address (and journal),
    /// the application recovering trol.h's way or the manual's; where the arm went (read
    /// from the unit, not through TROL) counts each move as run once, lost, run twice or
    /// gone elsewhere.
    ///
    /// Examples: trol bench restarts --moves 500 --recovery getstatus --json
    ///           trol bench restarts --moves 500 --recovery manual --no-journal
    Restarts(restarts::RestartsArgs),
    /// The whole path to a C500, on lines paced at a baud rate: an application's Robot, TROL's
    /// link, the PCP server with the RAPL-II backend, the RAPL-II line, and the simulated
    /// C500 in real time. Times a small command's round trip (TROLSpeed), GetPosition, and
    /// how long after the end of a motion Finish(FINISH_WAIT) returns, for each way the
    /// backend can find the end of a motion.
    ///
    /// Example: trol bench gateway --count 50 --moves 20 --json
    Gateway(GatewayArgs),
    /// A simulated MARS 8 (CTU's CRS93) through a relay paced at 19200 baud: from the call to
    /// the arm's start and from its stand to the wait's return, for TROL (TROLMA, Finish)
    /// and, in the same run on the same unit, for CTU Prague's own client (ctu-crs:
    /// move_to_q, wait_for_motion_stop), in a Python that has it (--python).
    ///
    /// Example: trol bench mars --moves 10 --python target/py/bin/python --json
    Mars(mars::MarsArgs),
    /// A simulated C500C through a relay paced at its console's 57600 baud: from the call to
    /// the arm's start and from its stand to Finish's return, for TROL (`c500c:`, TROLJoint,
    /// Finish) and, in the same run on the same controller, for ash typed bare (`joint 1,D`
    /// and `finish`, each ended by ash's prompt, with no check of any kind: the anchor).
    ///
    /// Example: trol bench c500c --moves 10 --json
    C500c(c500c::C500cArgs),
    /// The manual's pick example (examples/pick.py: two approaches and a move back to back,
    /// the gripper, the depart, each followed by Finish) through a line paced at a baud rate,
    /// the simulated A465 in real time, against the arm's own limit (the same calls on the
    /// arm model, each motion starting the instant the one before ended).
    ///
    /// Example: trol bench pick --baud 38400 --cycles 5 --json
    Pick(pick::PickArgs),
    /// A small CAT1 transaction (TROLSpeed) between two processes over a pty pair, against
    /// `trol sim` on the other end, and the anchor in the same run: a libmodbus RTU round trip
    /// (a register written, 8 bytes each way) over a pty pair between two processes, built
    /// here from anchors/modbus_rtu.c with the C compiler and libmodbus (Debian:
    /// libmodbus-dev); rounds alternate.
    ///
    /// Example: trol bench pty --count 2000 --rounds 3 --json
    Pty(pty::PtyArgs),
    /// The paced line between two processes: a relay process hands each byte from one
    /// pseudo-terminal pair to another at the end of its tenth bit time, as a UART does;
    /// `trol sim` serves on one end, the application asks on the other (TROLSpeed), and the
    /// libmodbus anchor (a register written, 8 bytes each way) runs through a second relay
    /// of the same program in the same run. Reports each one's share of the line's limit
    /// and what each turn of the half-duplex line costs beyond its bytes.
    ///
    /// Example: trol bench relay --baud 38400 --count 200 --rounds 3 --json
    Relay(relay::RelayArgs),
    /// The relay process of `trol bench relay` (prints its two ends, relays until its input
    /// ends).
    #[command(hide = true)]
    PacedRelay(relay::PacedRelayArgs),
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
    for (baud, count) in [("38400", "200"), ("9600", "60")] {
        let args = ["relay", "--baud", baud, "--count", count, "--rounds", "3"];
        let v = run(&args)?;
        rows.push((
            format!("the line between two processes through a relay paced at {baud} baud"),
            format!("trol bench {}", args.join(" ")),
            format!(
                "TROL {:.1} % of the line's limit ({:.0} us a turn beyond the bytes); {}",
                f(&v, "trol_share_of_line_limit") * 100.0,
                f(&v, "trol_us_per_turn_beyond_line"),
                match v["no_anchor"].as_str() {
                    Some(why) => format!("no libmodbus anchor: {why}"),
                    None => format!(
                        "libmodbus in the same run {:.1} % ({:.0} us a turn)",
                        f(&v, "libmodbus_share_of_line_limit") * 100.0,
                        f(&v, "libmodbus_us_per_turn_beyond_line")
                    ),
                }
            ),
        ));
    }
    let args = ["mars", "--moves", "10", "--python", python.as_str()];
    let v = run(&args)?;
    let client = |c: &serde_json::Value| {
        format!(
            "call to start {:.1} ms, end to return {:.1} ms",
            f(&c["call_to_start"], "median_ms"),
            f(&c["end_to_return"], "median_ms")
        )
    };
    rows.push((
        "a MARS 8 at 19200 baud through a relay".into(),
        format!("trol bench {}", args.join(" ")),
        match v["no_anchor"].as_str() {
            Some(why) => format!("TROL {}; no ctu-crs anchor: {why}", client(&v["trol"])),
            None => format!(
                "TROL {}; CTU's ctu-crs in the same run {}: {:.2} and {:.2} times",
                client(&v["trol"]),
                client(&v["ctu_crs"]),
                f(&v, "start_ratio"),
                f(&v, "end_ratio")
            ),
        },
    ));
    let args = ["c500c", "--moves", "10"];
    let v = run(&args)?;
    rows.push((
        "a C500C at 57600 baud through a relay".into(),
        format!("trol bench {}", args.join(" ")),
        format!(
            "TROL {}; ash typed bare in the same run {}: {:.2} and {:.2} times",
            client(&v["trol"]),
            client(&v["bare_ash"]),
            f(&v, "start_ratio"),
            f(&v, "end_ratio")
        ),
    ));
    let args = ["pick", "--baud", "38400", "--cycles", "5"];
    let v = run(&args)?;
    rows.push((
        "the pick example's cycle at 38400 baud".into(),
        format!("trol bench {}", args.join(" ")),
        format!(
            "{:.1} % over the arm's own limit of {:.3} s ({} transactions a cycle)",
            f(&v, "over_limit") * 100.0,
            f(&v, "arm_limit_s"),
            v["transactions_per_cycle"]
        ),
    ));
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
    let args = ["gateway", "--count", "20", "--moves", "10", "--processes"];
    let v = run(&args)?;
    let cell = |x: &serde_json::Value| {
        format!(
            "{}: Finish {:.0} ms after the end, TROLJoint starts {:.1} ms and TROLMA {:.1} ms \
             after the call",
            x["completion"].as_str().unwrap_or("?"),
            f(&x["after_motion_end"], "median_ms"),
            f(&x["joint_call_to_start"], "median_ms"),
            f(&x["ma_call_to_start"], "median_ms")
        )
    };
    rows.push((
        "the whole path to a C500 at 38400 baud through real processes".into(),
        format!("trol bench {}", args.join(" ")),
        format!(
            "{}; RobWork's way {:.1} ms (anchor)",
            v["finish"]
                .as_array()
                .cloned()
                .unwrap_or_default()
                .iter()
                .map(cell)
                .collect::<Vec<_>>()
                .join("; "),
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
    /// Through real processes: `trol gateway` as a process of its own, both lines through
    /// relays paced at the baud rate (`trol bench relay`'s), the simulated C500 and the
    /// application here. Without it, all in this process over paced in-memory lines.
    #[arg(long)]
    processes: bool,
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
    /// How the application recovers: the API's repeats, trol.h's GetStatus method (with the
    /// transaction), or the manual's plain GetStatus method.
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
        Bench::Restarts(a) => restarts::restarts(a),
        Bench::Gateway(a) => gateway(a),
        Bench::Mars(a) => mars::mars(a),
        Bench::C500c(a) => c500c::c500c(a),
        Bench::Pick(a) => pick::pick(a),
        Bench::Pty(a) => pty::pty(a),
        Bench::Relay(a) => relay::relay(a),
        Bench::PacedRelay(a) => relay::paced_relay(a),
        Bench::View(a) => view::view(a),
        Bench::All => all(),
    }
}

//! `trol bench restarts`: `trol gateway` killed at random instants of relative moves, started
//! again, and the application's recovery (trol.h's GetStatus method or the manual's) judged
//! by where the arm went (issue 67, item 1).
//!
//! The arm is a simulated MARS 8 (CTU's CRS93, homed) served here on a pty pair; `trol
//! gateway --controller mars:PTY --server` is a process of its own between it and the
//! application's `Robot` (over TCP), optionally with `--journal FILE`. For each move the
//! bench reads the arm's joint 1 straight from the unit (not through TROL), starts a timer
//! that kills the gateway (SIGKILL) at a random instant of the move's call and starts it
//! again 100 ms later on the same address and journal, and lets the application call TROLMI
//! and recover the documented way (docs/reliability.md, "Across a restart"):
//!
//! - `getstatus` (trol.h's worked example): TROLGetStatusOf; the call's transaction and not
//!   called: send it again; called with TROL_ERR_ROBOT_UNSURE: wait, read the arm
//!   (TROLGetPosition) and send it again only if it did not move; called: it ran;
//! - `manual` (the manual's plain method): TROLGetStatus's BIOSCalled and its value, the same
//!   three ways.
//!
//! When the arm stands again, its joint 1 says how often the move ran: once, never (lost),
//! twice, or somewhere else (a wrong motion).

use std::sync::{Arc, Mutex};

use super::*;
use rand::{Rng, SeedableRng};
use trol::{PosMode, Tag};
use trol_mars::mars8::{self, Mars8};

#[derive(Args)]
pub struct RestartsArgs {
    /// Relative moves, each with one kill of the gateway at a random instant of its call.
    #[arg(long, default_value_t = 100, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    moves: u32,
    /// How the application recovers from a failed move.
    #[arg(long, value_enum, default_value_t = crate::faults::Recovery::Getstatus)]
    recovery: crate::faults::Recovery,
    /// Run the gateway without --journal (a restarted gateway then cannot place the call in
    /// doubt, and every recovery of a move that may have run reads the arm).
    #[arg(long)]
    no_journal: bool,
    /// The host's repeats (TROLSetRepeats): trol.h's default is 2.
    #[arg(long, default_value_t = trol_comm::DEFAULT_REPEATS)]
    repeats: u8,
    /// Seed of the kill instants.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The simulated unit's time scale (its motions this many times faster than real).
    #[arg(long, default_value_t = 10.0, value_parser = trol_cli::common::positive)]
    time_scale: f64,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

#[derive(Default, Serialize)]
pub struct RestartsReport {
    recovery: String,
    journal: bool,
    repeats: u8,
    seed: u64,
    moves: u32,
    /// Gateways killed (one per move, at a random instant of its call; some land after
    /// the call returned).
    kills: u32,
    /// Moves whose call failed (the kill came while it was under way).
    failed_calls: u32,
    /// Recoveries by what GetStatus said: not called (sent again), ran, may have run (the
    /// arm read, and sent again only where it had not moved).
    said_not_called: u32,
    said_ran: u32,
    said_unsure: u32,
    /// Of the unsure ones, those the arm showed had not run (sent again).
    unsure_not_moved: u32,
    /// What the arm showed in the end, per move.
    ran_once: u32,
    lost: u32,
    twice: u32,
    /// Moves after which the arm stood neither where it was nor one or two moves on.
    wrong: u32,
    /// The kill instants' range, ms after the call (the median undisturbed call times 1.5).
    kill_window_ms: f64,
    seconds: f64,
}

/// The gateway process and how to start it again.
struct Gateway {
    args: Vec<String>,
    process: Option<SimProcess>,
}

impl Gateway {
    fn start(args: Vec<String>) -> Result<Gateway, String> {
        let mut g = Gateway {
            args,
            process: None,
        };
        g.restart()?;
        Ok(g)
    }

    fn restart(&mut self) -> Result<(), String> {
        let args: Vec<&str> = self.args.iter().map(String::as_str).collect();
        self.process = Some(start_trol_sim(&args, &["serving on"])?.0);
        Ok(())
    }

    /// SIGKILL (a dropped SimProcess is killed and waited for).
    fn kill(&mut self) {
        self.process = None;
    }
}

/// A free TCP port on this machine (the gateway listens there, each time it starts).
fn free_port() -> Result<u16, String> {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .map_err(|e| format!("no free port: {e}"))
}

/// Where the unit's joint 1 is once the arm stands (within 20 s).
fn settled_j1(unit: &mars8::Shared) -> Result<f64, String> {
    let deadline = Instant::now() + Duration::from_secs(20);
    loop {
        {
            let mut u = unit.lock().unwrap_or_else(|e| e.into_inner());
            if !u.is_moving() {
                return Ok(u.joints()[0]);
            }
        }
        if Instant::now() > deadline {
            return Err("the arm did not come to a stand within 20 s".into());
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// A call retried while the gateway is down (TROL_ERR_COMM), for at most 30 s.
fn through<T>(
    what: &str,
    robot: &mut trol::Robot,
    mut f: impl FnMut(&mut trol::Robot) -> trol::Result<T>,
) -> Result<T, String> {
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        match f(robot) {
            Ok(v) => return Ok(v),
            Err(e) if e.is_refusal() => return Err(format!("{what} was refused: {e}")),
            Err(e) if Instant::now() > deadline => {
                return Err(format!("{what} failed for 30 s: {e}"));
            }
            Err(_) => std::thread::sleep(Duration::from_millis(50)),
        }
    }
}

pub fn restarts(a: RestartsArgs) -> Result<(), String> {
    use crate::faults::Recovery;
    if a.recovery == Recovery::Api {
        return Err(
            "--recovery api has no recovery after a failed call; choose getstatus or \
                    manual"
                .into(),
        );
    }
    let started = Instant::now();
    let profile = trol_mars::Profile {
        assume_homed: true,
        ..trol_mars::Profile::crs93()
    };
    let unit: mars8::Shared = Arc::new(Mutex::new(Mars8::new(
        profile.clone(),
        mars8::Switches::default(),
        true,
        a.time_scale,
    )));
    let (master, slave, path) = trol_port::serial::SerialLine::pty_pair()
        .map_err(|e| format!("cannot create a pty: {e}"))?;
    let stop = Arc::new(std::sync::atomic::AtomicBool::new(false));
    let serving = {
        let (u, s) = (unit.clone(), stop.clone());
        std::thread::spawn(move || {
            // The other end stays open here, so a gateway's death is no hang-up.
            let _keep = slave;
            let _ = mars8::serve(Box::new(master), u, s);
        })
    };
    let dir = std::env::temp_dir().join(format!("trol-bench-restarts-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot make {}: {e}", dir.display()))?;
    let profile_file = dir.join("crs93.toml");
    std::fs::write(&profile_file, profile.to_toml())
        .map_err(|e| format!("cannot write the profile: {e}"))?;
    let port = free_port()?;
    let mut args: Vec<String> = [
        "gateway",
        "--controller",
        &format!("mars:{path}"),
        "--profile",
        &profile_file.to_string_lossy(),
        "--server",
        "--port",
        &format!("listen://127.0.0.1:{port}"),
    ]
    .map(String::from)
    .to_vec();
    if !a.no_journal {
        args.push("--journal".into());
        args.push(dir.join("arm.journal").to_string_lossy().into());
    }
    let result = (|| {
        let gateway = Arc::new(Mutex::new(Gateway::start(args)?));
        let mut robot = trol::Connect::port(&format!("socket://127.0.0.1:{port}"))
            .connect()
            .map_err(|e| format!("TROL on the gateway: {e}"))?;
        robot.set_repeats(a.repeats);
        run_moves(&a, &unit, &gateway, &mut robot)
    })();
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    let _ = serving.join();
    let _ = std::fs::remove_dir_all(&dir);
    let mut r = result?;
    r.seconds = started.elapsed().as_secs_f64();
    print_report(&r, a.json, |r| {
        format!(
            "{} moves through `trol gateway --controller mars:` {} journal, recovery {}, \
             repeats {}, seed {}: {} kills in {:.0} s\n  calls failed: {} (GetStatus: not \
             called {}, ran {}, may have run {}, of which the arm showed {} had not)\n  the \
             arm: ran once {}, lost {}, twice {}, elsewhere {}",
            r.moves,
            if r.journal { "with a" } else { "without a" },
            r.recovery,
            r.repeats,
            r.seed,
            r.kills,
            r.seconds,
            r.failed_calls,
            r.said_not_called,
            r.said_ran,
            r.said_unsure,
            r.unsure_not_moved,
            r.ran_once,
            r.lost,
            r.twice,
            r.wrong
        )
    })
}

fn run_moves(
    a: &RestartsArgs,
    unit: &mars8::Shared,
    gateway: &Arc<Mutex<Gateway>>,
    robot: &mut trol::Robot,
) -> Result<RestartsReport, String> {
    let mut r = RestartsReport {
        recovery: format!("{:?}", a.recovery).to_lowercase(),
        journal: !a.no_journal,
        repeats: a.repeats,
        seed: a.seed,
        moves: a.moves,
        ..RestartsReport::default()
    };
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(a.seed);
    let step = 0.02;
    // Undisturbed calls first: their time sets the window the kills fall in.
    let mut times = Vec::new();
    for k in 0..6 {
        let dq = if k % 2 == 0 { step } else { -step };
        let t = Instant::now();
        robot
            .mi(&[dq, 0.0, 0.0, 0.0, 0.0, 0.0])
            .map_err(|e| format!("an undisturbed move failed: {e}"))?;
        times.push(t.elapsed().as_secs_f64());
        robot
            .finish()
            .map_err(|e| format!("an undisturbed Finish failed: {e}"))?;
    }
    times.sort_by(f64::total_cmp);
    let window = times[times.len() / 2] * 1.5;
    r.kill_window_ms = window * 1e3;
    for k in 0..a.moves {
        let dq = if k % 2 == 0 { step } else { -step };
        let before = settled_j1(unit)?;
        let app_before = through("GetPosition before the move", robot, |r| {
            r.position(Tag::Joint, PosMode::Actual)
        })?
        .to_array6()[0];
        let at = Duration::from_secs_f64(rng.random_range(0.0..window));
        let killer = {
            let g = gateway.clone();
            std::thread::spawn(move || -> Result<(), String> {
                std::thread::sleep(at);
                let mut g = g.lock().unwrap_or_else(|e| e.into_inner());
                g.kill();
                std::thread::sleep(Duration::from_millis(100));
                g.restart()
            })
        };
        let call = robot.mi(&[dq, 0.0, 0.0, 0.0, 0.0, 0.0]);
        if let Err(e) = call {
            if e.is_refusal() {
                return Err(format!("move {k} was refused: {e}"));
            }
            r.failed_calls += 1;
            recover(a.recovery, robot, dq, app_before, &mut r)?;
        }
        killer
            .join()
            .map_err(|_| "the killer's thread panicked")??;
        r.kills += 1;
        through("Finish after the move", robot, |r| r.finish())?;
        let after = settled_j1(unit)?;
        let runs = (after - before) / dq;
        if (runs - 1.0).abs() < 0.05 {
            r.ran_once += 1;
        } else if runs.abs() < 0.05 {
            r.lost += 1;
            tell!("move {k}: lost (joint 1 {before:.5} -> {after:.5} rad, step {dq})");
        } else if (runs - 2.0).abs() < 0.05 {
            r.twice += 1;
            tell!("move {k}: ran twice (joint 1 {before:.5} -> {after:.5} rad, step {dq})");
        } else {
            r.wrong += 1;
            tell!(
                "move {k}: the arm went elsewhere (joint 1 {before:.5} -> {after:.5} rad, step {dq})"
            );
        }
    }
    Ok(r)
}

/// The documented recovery after a failed relative move of `dq` on joint 1 (`before`: where
/// the application read joint 1 before the call).
fn recover(
    how: crate::faults::Recovery,
    robot: &mut trol::Robot,
    dq: f64,
    before: f64,
    r: &mut RestartsReport,
) -> Result<(), String> {
    use crate::faults::Recovery;
    let deadline = Instant::now() + Duration::from_secs(60);
    // TROLLastTransaction right after the failed call: the GetStatus calls below, which may
    // fail while the gateway starts again, number transactions too.
    let mut n = robot.last_transaction();
    loop {
        if Instant::now() > deadline {
            return Err("the recovery did not end within 60 s".into());
        }
        let (called, last, about) = match how {
            Recovery::Manual => match robot.status() {
                Ok((called, last)) => (called, last, n),
                Err(_) => {
                    std::thread::sleep(Duration::from_millis(50));
                    continue;
                }
            },
            _ => match robot.status_record() {
                Ok(s) => (s.bios_called, s.last, s.transaction),
                Err(_) => {
                    std::thread::sleep(Duration::from_millis(50));
                    continue;
                }
            },
        };
        tracing::info!(
            "GetStatus: called {called}, last {}, transaction {about} (the call's {n}), epoch {:?}",
            last.0,
            robot.controller_epoch()
        );
        let again = if about != n || !called {
            r.said_not_called += 1;
            true
        } else if last == trol::code::TROL_ERR_ROBOT_UNSURE {
            r.said_unsure += 1;
            through("Finish before reading the arm", robot, |r| r.finish())?;
            let now = through("GetPosition after the restart", robot, |r| {
                r.position(Tag::Joint, PosMode::Actual)
            })?
            .to_array6()[0];
            let moved = ((now - before) / dq).abs() > 0.5;
            if !moved {
                r.unsure_not_moved += 1;
            }
            !moved
        } else {
            r.said_ran += 1;
            false
        };
        if !again {
            return Ok(());
        }
        match robot.mi(&[dq, 0.0, 0.0, 0.0, 0.0, 0.0]) {
            Ok(()) => return Ok(()),
            Err(e) if e.is_refusal() => {
                return Err(format!("the move sent again was refused: {e}"));
            }
            // Failed again (the gateway still starting): GetStatus about this one.
            Err(_) => {
                n = robot.last_transaction();
                std::thread::sleep(Duration::from_millis(50));
            }
        }
    }
}

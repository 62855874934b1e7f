//! `trol bench mars`: a MARS 8 from the call to the arm's start and from the arm's stand to
//! the wait's return, for TROL (`mars:`) and for CTU Prague's own client (ctu-crs, the
//! anchor) on the same simulated unit, in the same run (issue 43, item 5).
//!
//! The simulated MARS 8 (CTU's CRS93 profile, homed, real time) serves here on one end of a
//! relay paced at the unit's 19200 baud (`trol bench relay`'s, a process of its own); the
//! clients take the other end in turn. A thread watches the unit's arm every millisecond and
//! notes when it starts and when it stands. Each client moves joint 1 back and forth and
//! waits for each motion: TROL with TROLMA and Finish, CTU's with move_to_q and
//! wait_for_motion_stop (anchors/ctu_crs_moves.py, in a Python that has ctu-crs).

use std::sync::{Arc, Mutex};

use super::watch::{ArmWatch, Client};
use super::*;
use trol_mars::mars8::{self, Mars8};

/// The anchor's script, written out at run time.
const ANCHOR: &str = include_str!("anchors/ctu_crs_moves.py");

#[derive(Args)]
pub struct MarsArgs {
    /// Motions per client (joint 1 there and back, alternately).
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(2..=1000))]
    moves: u32,
    /// How far joint 1 goes, degrees.
    #[arg(long, default_value_t = 10.0)]
    degrees: f64,
    /// A Python with ctu-crs (pip install --no-deps ctu-crs==1.0.6
    /// ctu-mars-control-unit==0.1.3; pip install numpy pyserial pyyaml): the anchor. Default:
    /// $TROL_BENCH_PYTHON, else python3.
    #[arg(long)]
    python: Option<String>,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct MarsReport {
    baud: u32,
    moves: u32,
    trol: Client,
    /// CTU's client; `None` where no Python with ctu-crs was found (`no_anchor` says why).
    ctu_crs: Option<Client>,
    no_anchor: Option<String>,
    /// TROL's medians over the anchor's.
    start_ratio: Option<f64>,
    end_ratio: Option<f64>,
}

/// The simulated unit (CTU's CRS93, homed, real time) on a relay's end, watched.
fn unit(device: &str, baud: u32) -> Result<ArmWatch, String> {
    let unit: mars8::Shared = Arc::new(Mutex::new(Mars8::new(
        trol_mars::Profile::crs93(),
        mars8::Switches::default(),
        true,
        1.0,
    )));
    let port = trol_port::serial::SerialLine::open(device, baud)
        .map_err(|e| format!("the unit's end {device}: {e}"))?;
    let u = unit.clone();
    Ok(ArmWatch::start(
        move |stop| {
            let _ = mars8::serve(Box::new(port), u, stop);
        },
        move || unit.lock().unwrap_or_else(|e| e.into_inner()).is_moving(),
    ))
}

/// TROL's motions: TROLMA of joint 1 there and back, each followed by Finish.
fn trol_moves(
    device: &str,
    baud: u32,
    moves: u32,
    step: f64,
) -> Result<Vec<(Instant, Instant)>, String> {
    let e = |e: trol::Error| format!("TROL on mars:{device}: {e}");
    let mut robot = trol::Connect::port(&format!("mars:{device}"))
        .baud(baud)
        // The unit was homed when it started (CTU's client, which homes by itself, is told
        // not to): the profile says so, as for an arm homed by a program before.
        .mars_profile(trol_mars::Profile {
            assume_homed: true,
            ..trol_mars::Profile::crs93()
        })
        .connect()
        .map_err(e)?;
    let here = robot
        .position(trol::Tag::Joint, trol::PosMode::Actual)
        .map_err(e)?
        .to_array6();
    let mut pairs = Vec::new();
    for k in 0..moves {
        let mut q = here;
        if k % 2 == 0 {
            q[0] += step;
        }
        let call = Instant::now();
        robot.ma(&q).map_err(e)?;
        robot.finish().map_err(e)?;
        pairs.push((call, Instant::now()));
    }
    Ok(pairs)
}

/// CTU's client's motions (the anchor script), or why there are none.
fn ctu_moves(
    python: &str,
    device: &str,
    moves: u32,
    step: f64,
) -> Result<Vec<(Instant, Instant)>, String> {
    use std::io::BufRead;
    let has = std::process::Command::new(python)
        .args([
            "-c",
            "import importlib.util as u, sys; \
             sys.exit(any(u.find_spec(m) is None for m in ('ctu_crs', 'numpy', 'serial', 'yaml')))",
        ])
        .output()
        .is_ok_and(|o| o.status.success());
    if !has {
        return Err(format!(
            "{python} has no ctu-crs (pip install --no-deps ctu-crs==1.0.6 \
             ctu-mars-control-unit==0.1.3; pip install numpy pyserial pyyaml; or --python \
             names one that has it)"
        ));
    }
    let script = std::env::temp_dir().join(format!("trol-bench-ctu-{}.py", std::process::id()));
    std::fs::write(&script, ANCHOR).map_err(|e| format!("cannot write the anchor: {e}"))?;
    let child = std::process::Command::new(python)
        .arg(&script)
        .args([device, &moves.to_string(), &step.to_string()])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn();
    let mut child = match child {
        Ok(c) => c,
        Err(e) => {
            let _ = std::fs::remove_file(&script);
            return Err(format!("cannot run {python}: {e}"));
        }
    };
    let out = child.stdout.take().expect("piped");
    let mut pairs = Vec::new();
    let mut call = None;
    for line in std::io::BufReader::new(out).lines() {
        let Ok(line) = line else { break };
        let now = Instant::now();
        match line.trim() {
            "call" => call = Some(now),
            "returned" => {
                if let Some(c) = call.take() {
                    pairs.push((c, now));
                }
            }
            _ => {}
        }
    }
    let done = child.wait_with_output();
    let _ = std::fs::remove_file(&script);
    let done = done.map_err(|e| format!("the anchor: {e}"))?;
    if !done.status.success() || pairs.len() != moves as usize {
        return Err(format!(
            "the anchor (ctu-crs) failed after {} of {moves} motions: {}",
            pairs.len(),
            String::from_utf8_lossy(&done.stderr).trim()
        ));
    }
    Ok(pairs)
}

pub fn mars(a: MarsArgs) -> Result<(), String> {
    let baud = trol_mars::Profile::crs93().baud;
    let relay = super::relay::Relay::start(baud)?;
    let (unit_end, client_end) = relay.ends.clone();
    let unit = unit(&unit_end, baud)?;
    let step = a.degrees.to_radians();
    let trol = unit.timings(&trol_moves(&client_end, baud, a.moves, step)?)?;
    let python = a
        .python
        .clone()
        .or_else(|| std::env::var("TROL_BENCH_PYTHON").ok())
        .unwrap_or_else(|| "python3".into());
    let (ctu, no_anchor) = match ctu_moves(&python, &client_end, a.moves, step) {
        Ok(pairs) => (Some(unit.timings(&pairs)?), None),
        Err(why) => (None, Some(why)),
    };
    let ratio = |f: fn(&Client) -> f64| ctu.as_ref().map(|c| f(&trol) / f(c));
    let r = MarsReport {
        baud,
        moves: a.moves,
        start_ratio: ratio(|c| c.call_to_start.median_ms),
        end_ratio: ratio(|c| c.end_to_return.median_ms),
        trol,
        ctu_crs: ctu,
        no_anchor,
    };
    print_report(&r, a.json, |r| {
        let line = |name: &str, c: &Client| {
            format!(
                "  {name}: call to start {:.1} ms (max {:.1}), end to return {:.1} ms (max {:.1})\n",
                c.call_to_start.median_ms,
                c.call_to_start.max_ms,
                c.end_to_return.median_ms,
                c.end_to_return.max_ms
            )
        };
        let mut s = format!(
            "a simulated MARS 8 (CTU's CRS93) through a relay paced at {} baud, {} motions \
             each (median, largest):\n",
            r.baud, r.moves
        );
        s += &line("TROL (TROLMA, Finish)", &r.trol);
        match (&r.ctu_crs, &r.no_anchor) {
            (Some(c), _) => {
                s += &line("ctu-crs (move_to_q, wait_for_motion_stop)", c);
                s += &format!(
                    "  TROL over ctu-crs: {:.2} times to start, {:.2} times after the end",
                    r.start_ratio.unwrap_or(f64::NAN),
                    r.end_ratio.unwrap_or(f64::NAN)
                );
            }
            (None, Some(why)) => s += &format!("  no ctu-crs anchor: {why}"),
            _ => {}
        }
        s
    })
}

//! `trol bench view`: what the live view costs the controller, and how often it updates.
//!
//! A `trol sim --view` process serves the view; an application drives its arm back and forth
//! through whole motions (TROLJoint, then Finish(FINISH_WAIT)) for a while, three times: with
//! nobody watching, with event streams held open the way a page holds one, and (with
//! `--browser`) with a headless browser showing the page. Each time the process's CPU time
//! (user and system, from /proc, all its threads) is read before and after. The event
//! streams' readers time the updates they get while the arm moves and count those while it
//! stands.

use std::io::{BufRead, BufReader, Write};
use std::net::TcpStream;
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use clap::Args;
use serde::Serialize;

use super::print_report;

#[derive(Args)]
pub struct ViewArgs {
    /// Seconds of motion in each measurement
    #[arg(long, default_value_t = 10.0)]
    seconds: f64,
    /// Event streams held open in the second measurement (a page holds one)
    #[arg(long, default_value_t = 1)]
    viewers: usize,
    /// Also measure with this browser showing the page, headless (Debian's Chromium:
    /// /usr/bin/chromium)
    #[arg(long)]
    browser: Option<PathBuf>,
    /// Print the report as JSON
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct Measurement {
    /// Who watched.
    watching: String,
    /// Wall-clock seconds of the measurement.
    seconds: f64,
    /// Motions completed.
    motions: u32,
    /// The controller process's CPU time over the wall-clock time, percent of one core.
    controller_cpu_percent: f64,
}

#[derive(Serialize)]
struct ViewReport {
    measurements: Vec<Measurement>,
    /// Updates one stream got while the arm moved, per second (from the gaps between them).
    updates_per_second_moving: f64,
    /// The longest gap between two updates while the arm moved, ms.
    longest_gap_moving_ms: f64,
    /// Updates one stream got in 3 s with the arm standing, after it stopped.
    updates_while_still: usize,
}

/// The `trol sim --view` process (killed when dropped), where it serves, and its view.
struct Sim {
    process: super::SimProcess,
    port: String,
    url: String,
}

fn start_sim() -> Result<Sim, String> {
    let (process, found) = super::start_trol_sim(
        &[
            "sim",
            "--port",
            "listen://127.0.0.1:0",
            "--server",
            "--homed",
            "--view",
            "127.0.0.1:0",
        ],
        &["serving on ", "the view: "],
    )?;
    let port = super::first_word(&found[0]);
    Ok(Sim {
        process,
        port,
        url: found[1].clone(),
    })
}

/// The CPU time of process `pid` so far (user and system, every thread, dead ones too), s.
fn cpu_seconds(pid: u32) -> Result<f64, String> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat"))
        .map_err(|e| format!("cannot read /proc/{pid}/stat: {e}"))?;
    // After the command name in parentheses: state, then fields 4.. ; utime and stime are
    // fields 14 and 15, in USER_HZ ticks (100 a second on Linux).
    let rest = stat.rsplit_once(')').map(|(_, r)| r).unwrap_or("");
    let f: Vec<&str> = rest.split_whitespace().collect();
    let tick = |i: usize| f.get(i).and_then(|v| v.parse::<f64>().ok());
    match (tick(11), tick(12)) {
        (Some(u), Some(s)) => Ok((u + s) / 100.0),
        _ => Err(format!("/proc/{pid}/stat has no CPU times: {stat}")),
    }
}

/// Drive the arm through whole motions for `seconds`: (motions, wall seconds, CPU seconds).
fn drive(robot: &mut trol::Robot, pid: u32, seconds: f64) -> Result<(u32, f64, f64), String> {
    let err = |e: trol::Error| e.to_string();
    let (cpu0, t0) = (cpu_seconds(pid)?, Instant::now());
    let mut motions = 0;
    while t0.elapsed().as_secs_f64() < seconds {
        // Joint 1 by 0.8 rad and joint 3 by 0.5 rad, back and forth: about half a second each.
        let (a, b) = if motions % 2 == 0 {
            (0.8, 0.5)
        } else {
            (0.0, 0.0)
        };
        robot.ma(&[a, 0.0, b, 0.0, 0.0, 0.0]).map_err(err)?;
        robot.finish().map_err(err)?;
        motions += 1;
    }
    let wall = t0.elapsed().as_secs_f64();
    Ok((motions, wall, cpu_seconds(pid)? - cpu0))
}

/// An event stream's reader: the arrival time of each update and whether it said "moving".
struct Viewer {
    stop: Arc<AtomicBool>,
    thread: std::thread::JoinHandle<Vec<(Instant, bool)>>,
}

fn watch(addr: &str) -> Result<Viewer, String> {
    let mut s = TcpStream::connect(addr).map_err(|e| format!("cannot reach the view: {e}"))?;
    s.set_read_timeout(Some(Duration::from_millis(200)))
        .map_err(|e| e.to_string())?;
    write!(s, "GET /events HTTP/1.1\r\nHost: {addr}\r\n\r\n").map_err(|e| e.to_string())?;
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    let thread = std::thread::spawn(move || {
        let mut seen = Vec::new();
        let mut reader = BufReader::new(s);
        let mut line = String::new();
        while !flag.load(Ordering::Relaxed) {
            line.clear();
            match reader.read_line(&mut line) {
                Ok(0) => break,
                Ok(_) => {
                    if let Some(data) = line.strip_prefix("data: ") {
                        let moving = data.contains("\"moving\":true");
                        seen.push((Instant::now(), moving));
                    }
                }
                // The read timeout: look at the stop flag again.
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    ) => {}
                Err(_) => break,
            }
        }
        seen
    });
    Ok(Viewer { stop, thread })
}

impl Viewer {
    fn end(self) -> Vec<(Instant, bool)> {
        self.stop.store(true, Ordering::Relaxed);
        self.thread.join().unwrap_or_default()
    }
}

pub fn view(a: ViewArgs) -> Result<(), String> {
    if !(a.seconds.is_finite() && a.seconds > 0.0 && a.seconds <= 3600.0) {
        return Err("--seconds: give 0 to 3600 seconds".into());
    }
    if a.viewers == 0 || a.viewers > trol_view::MAX_CLIENTS {
        return Err(format!("--viewers: give 1 to {}", trol_view::MAX_CLIENTS));
    }
    let sim = start_sim()?;
    let pid = sim.process.id();
    let addr = sim
        .url
        .trim_start_matches("http://")
        .trim_end_matches('/')
        .to_string();
    let mut robot = trol::Robot::connect(&sim.port, 38400).map_err(|e| e.to_string())?;
    robot.speed(100).map_err(|e| e.to_string())?;
    let mut measurements = Vec::new();
    let mut measure = |who: String, robot: &mut trol::Robot| -> Result<(), String> {
        let (motions, wall, cpu) = drive(robot, pid, a.seconds)?;
        measurements.push(Measurement {
            watching: who,
            seconds: wall,
            motions,
            controller_cpu_percent: 100.0 * cpu / wall,
        });
        Ok(())
    };

    measure("nobody".into(), &mut robot)?;

    let viewers = (0..a.viewers)
        .map(|_| watch(&addr))
        .collect::<Result<Vec<_>, _>>()?;
    measure(
        format!(
            "{} event stream{}",
            a.viewers,
            if a.viewers == 1 { "" } else { "s" }
        ),
        &mut robot,
    )?;
    // The arm stands now: what does a stream get in 3 s?
    let still_from = Instant::now();
    std::thread::sleep(Duration::from_secs(3));
    let mut seen = Vec::new();
    for (i, v) in viewers.into_iter().enumerate() {
        let s = v.end();
        if i == 0 {
            seen = s;
        }
    }
    // An update that came within 0.2 s of the stop is the one that says "stopped".
    let updates_while_still = seen
        .iter()
        .filter(|(t, _)| *t > still_from + Duration::from_millis(200))
        .count();
    let gaps: Vec<f64> = seen
        .windows(2)
        .filter(|w| w[0].1 && w[1].1)
        .map(|w| w[1].0.duration_since(w[0].0).as_secs_f64())
        // A gap of more than half a second spans the pause between two motions.
        .filter(|g| *g < 0.5)
        .collect();
    if gaps.is_empty() {
        return Err("the event stream got no updates while the arm moved".into());
    }
    let mean = gaps.iter().sum::<f64>() / gaps.len() as f64;
    let longest = gaps.iter().copied().fold(0.0, f64::max);

    if let Some(browser) = &a.browser {
        let profile = std::env::temp_dir().join(format!("trol-bench-view-{}", std::process::id()));
        let mut page = Command::new(browser)
            .args([
                "--headless",
                "--no-sandbox",
                "--use-angle=swiftshader",
                "--enable-unsafe-swiftshader",
                "--no-first-run",
                "--disable-background-networking",
                "--window-size=1000,650",
            ])
            .arg(format!("--user-data-dir={}", profile.display()))
            .arg(&sim.url)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .map_err(|e| format!("cannot start {}: {e}", browser.display()))?;
        // Let it load the page and open its event stream.
        std::thread::sleep(Duration::from_secs(3));
        let r = measure(format!("a page in {}", browser.display()), &mut robot);
        let _ = page.kill();
        let _ = page.wait();
        let _ = std::fs::remove_dir_all(&profile);
        r?;
    }

    let r = ViewReport {
        measurements,
        updates_per_second_moving: 1.0 / mean,
        longest_gap_moving_ms: longest * 1e3,
        updates_while_still,
    };
    print_report(&r, a.json, |r| {
        let mut t = String::from("the live view's cost to the controller (trol sim --view):\n");
        for m in &r.measurements {
            t += &format!(
                "  {}: controller CPU {:.1} % of a core over {:.1} s ({} motions)\n",
                m.watching, m.controller_cpu_percent, m.seconds, m.motions
            );
        }
        t += &format!(
            "  updates while the arm moves: {:.1} per second (longest gap {:.0} ms); \
             while it stands: {} in 3 s",
            r.updates_per_second_moving, r.longest_gap_moving_ms, r.updates_while_still
        );
        t
    })
}

//! `trol bench c500c`: an A465 on its C500C from the call to the arm's start and from the
//! arm's stand to Finish's return, through TROL (`c500c:`) and, in the same run on the same
//! simulated controller, through ash typed bare (the anchor: `joint 1,D` then `finish`, each
//! ended by ash's prompt, as a person at a terminal or A255ROS drives it, with no check of
//! any kind).
//!
//! The simulated C500C (default variant, homed, real time) serves on one end of a relay
//! paced at the console's 57600 baud (`trol bench relay`'s, a process of its own); the two
//! clients take the other end in turn. A thread watches the arm every millisecond and notes
//! when it starts and when it stands (the MARS 8's bench does the same).

use std::sync::{Arc, Mutex};

use super::watch::{ArmWatch, Client};
use super::*;
use trol_c500c::c500c::{self, C500c};

#[derive(Args)]
pub struct C500cArgs {
    /// Motions per client (joint 1 there and back, alternately).
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(2..=1000))]
    moves: u32,
    /// How far joint 1 goes, degrees.
    #[arg(long, default_value_t = 10.0)]
    degrees: f64,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct C500cReport {
    baud: u32,
    moves: u32,
    trol: Client,
    /// ash typed bare: `joint 1,D`, its prompt, `finish`, its prompt.
    bare_ash: Client,
    /// TROL's medians over the anchor's.
    start_ratio: f64,
    end_ratio: f64,
}

/// The simulated controller (default variant, homed, real time) on a relay's end, watched.
fn unit(device: &str, baud: u32) -> Result<ArmWatch, String> {
    let unit: c500c::Shared = Arc::new(Mutex::new(C500c::new(
        c500c::Switches::default(),
        true,
        1.0,
    )));
    let port = trol_port::serial::SerialLine::open(device, baud)
        .map_err(|e| format!("the controller's end {device}: {e}"))?;
    let u = unit.clone();
    Ok(ArmWatch::start(
        move |stop| {
            let _ = c500c::serve(Box::new(port), u, stop);
        },
        move || unit.lock().unwrap_or_else(|e| e.into_inner()).is_moving(),
    ))
}

/// TROL's motions: TROLJoint of joint 1 there and back, each followed by Finish, with the
/// profile that matches the controller.
fn trol_moves(
    device: &str,
    baud: u32,
    moves: u32,
    step: f64,
) -> Result<Vec<(Instant, Instant)>, String> {
    let e = |e: trol::Error| format!("TROL on c500c:{device}: {e}");
    let mut robot = trol::Connect::port(&format!("c500c:{device}"))
        .baud(baud)
        .c500c_profile(c500c::matching_profile(&c500c::Switches::default()))
        .connect()
        .map_err(e)?;
    robot.speed(100).map_err(e)?;
    let mut pairs = Vec::new();
    for k in 0..moves {
        let d = if k % 2 == 0 { step } else { -step };
        let call = Instant::now();
        robot.joint(1, d).map_err(e)?;
        robot.finish().map_err(e)?;
        pairs.push((call, Instant::now()));
    }
    Ok(pairs)
}

/// Read from `port` until `prompt` ends what came, within 30 s.
fn until_prompt(port: &mut dyn trol_port::Port, prompt: &str) -> Result<String, String> {
    let deadline = Instant::now() + Duration::from_secs(30);
    let mut got = Vec::new();
    let mut buf = [0u8; 256];
    while !got.ends_with(prompt.as_bytes()) {
        if Instant::now() > deadline {
            return Err(format!(
                "no `{prompt}` within 30 s: {:?}",
                String::from_utf8_lossy(&got)
            ));
        }
        let n = port
            .recv(&mut buf, Instant::now() + Duration::from_millis(50))
            .map_err(|e| e.to_string())?;
        got.extend_from_slice(&buf[..n]);
    }
    Ok(String::from_utf8_lossy(&got).into_owned())
}

/// The anchor's motions: `joint 1,D` and `finish` typed bare, each ended by ash's prompt.
fn bare_moves(
    device: &str,
    baud: u32,
    moves: u32,
    degrees: f64,
) -> Result<Vec<(Instant, Instant)>, String> {
    let mut port = trol_port::serial::SerialLine::open(device, baud)
        .map_err(|e| format!("the anchor on {device}: {e}"))?;
    let prompt = format!("{}> ", c500c::APP);
    let send = |p: &mut trol_port::serial::SerialLine, s: &str| {
        trol_port::Port::send(p, s.as_bytes()).map_err(|e| e.to_string())
    };
    // TROL left ash running; a CR shows its prompt.
    send(&mut port, "\r")?;
    let got = until_prompt(&mut port, " ")?;
    if got.ends_with("$ ") {
        send(&mut port, &format!("ash {}\r", c500c::APP))?;
        until_prompt(&mut port, &prompt)?;
    } else if !got.ends_with(&prompt) {
        until_prompt(&mut port, &prompt)?;
    }
    let mut pairs = Vec::new();
    for k in 0..moves {
        let d = if k % 2 == 0 { degrees } else { -degrees };
        let call = Instant::now();
        send(&mut port, &format!("joint 1,{d}\r"))?;
        until_prompt(&mut port, &prompt)?;
        send(&mut port, "finish\r")?;
        until_prompt(&mut port, &prompt)?;
        pairs.push((call, Instant::now()));
    }
    Ok(pairs)
}

pub fn c500c(a: C500cArgs) -> Result<(), String> {
    let baud = trol_c500c::Profile::default().baud;
    let relay = super::relay::Relay::start(baud)?;
    let (unit_end, client_end) = relay.ends.clone();
    let unit = unit(&unit_end, baud)?;
    let trol = unit.timings(&trol_moves(
        &client_end,
        baud,
        a.moves,
        a.degrees.to_radians(),
    )?)?;
    let bare = unit.timings(&bare_moves(&client_end, baud, a.moves, a.degrees)?)?;
    let r = C500cReport {
        baud,
        moves: a.moves,
        start_ratio: trol.call_to_start.median_ms / bare.call_to_start.median_ms,
        end_ratio: trol.end_to_return.median_ms / bare.end_to_return.median_ms,
        trol,
        bare_ash: bare,
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
            "a simulated C500C through a relay paced at {} baud, {} motions each (median, \
             largest):\n",
            r.baud, r.moves
        );
        s += &line("TROL (TROLJoint, Finish)", &r.trol);
        s += &line("ash typed bare (joint, finish)", &r.bare_ash);
        s += &format!(
            "  TROL over bare ash: {:.2} times to start, {:.2} times after the end",
            r.start_ratio, r.end_ratio
        );
        s
    })
}

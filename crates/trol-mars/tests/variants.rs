//! The MARS 8 backend across every unit the public sources allow (`trol_mars::mars8::VARIANTS`:
//! echo, power-up noise, a lagging moving bit, the three ways of refusing, a STOP that
//! latches, LF line ends, another COORDAP form, an R: that blocks, a STOP: that does not stop,
//! a unit nothing stops), each driven through TROL's
//! API: first contact reads only; nothing moves before TROLHome; every motion that succeeds
//! leaves the arm where it asked; a refused, interrupted or powerless motion never succeeds;
//! a line nobody asked for makes the next call UNSURE and moves nothing; a silent unit ends
//! a call in TROL_ERR_ROBOT in bounded time, and the next call works.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use trol::{Location, PosMode, Robot, Tag};
use trol_a465::kinematics::Kinematics;
use trol_mars::backend::{ARM_POWER, MARS_ERROR, MOTION_STOP, NOT_AT_TARGET};
use trol_mars::mars8::{self, Mars8, Switches};
use trol_mars::{MARS_CODES, MarsBackend, Profile};
use trol_port::memory;
use trol_proto::application::code::{TROL_ERR_NOT_STOPPED, TROL_ERR_ROBOT, TROL_ERR_ROBOT_UNSURE};

struct Twin {
    unit: mars8::Shared,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Drop for Twin {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Twin {
    fn with<R>(&self, f: impl FnOnce(&mut Mars8) -> R) -> R {
        f(&mut self.unit.lock().unwrap())
    }
    fn joints(&self) -> [f64; 6] {
        self.with(|u| u.joints())
    }
    fn wait_moving(&self) {
        let end = Instant::now() + Duration::from_secs(30);
        while !self.with(|u| u.is_moving()) {
            assert!(Instant::now() < end, "the twin never started");
            std::thread::sleep(Duration::from_millis(2));
        }
    }
    fn wait_still(&self) {
        let end = Instant::now() + Duration::from_secs(30);
        while self.with(|u| u.is_moving()) {
            assert!(Instant::now() < end, "the twin never stopped");
            std::thread::sleep(Duration::from_millis(5));
        }
    }
}

/// CTU's CRS93 with every axis ten times as fast (REGMS x 10), for the backend: the unit runs
/// at ten times real time, and the backend plans at a unit's speeds (issue 43), so its plan
/// (what Finish waits by) is ten times as fast as the real arm's too. The unit, set up with
/// these speeds, runs at least as fast as the plan.
fn fast() -> Profile {
    let mut p = Profile::crs93();
    p.speed = p.speed.map(|v| v * 10);
    p
}

fn start(sw: Switches, homed: bool) -> (Robot, Twin) {
    let (host, unit_side) = memory::pair(Some(115_200));
    let unit = Arc::new(Mutex::new(Mars8::new(Profile::crs93(), sw, homed, 10.0)));
    let stop = Arc::new(AtomicBool::new(false));
    let thread = {
        let (unit, stop) = (unit.clone(), stop.clone());
        std::thread::spawn(move || {
            let _ = mars8::serve(Box::new(unit_side), unit, stop);
        })
    };
    let backend = MarsBackend::connect(
        Box::new(host),
        fast(),
        Some(Box::new(|l: &str| eprintln!("mars: {l}"))),
        None,
        Vec::new(),
    )
    .expect("the session opens");
    let cfg = trol_proto::link::LinkConfig::default();
    let (line, handle) = trol_controller::embedded_with(trol_controller::Pcp::new(backend), cfg);
    let mut robot = Robot::over(Box::new(line), cfg, Some(handle));
    robot.set_codes(MARS_CODES);
    (
        robot,
        Twin {
            unit,
            stop,
            thread: Some(thread),
        },
    )
}

fn code(r: trol::Result<()>) -> i16 {
    match r {
        Ok(()) => 0,
        Err(e) => e.code().0,
    }
}

fn near(a: &[f64; 6], b: &[f64; 6], tol: f64) -> bool {
    (0..6).all(|i| (a[i] - b[i]).abs() <= tol)
}

const READ_ONLY: [&str; 5] = ["ECHO:0", "VER?", "ST?", "COORDAP?", "STAMP"];

fn the_variant(name: &str) {
    let sw = mars8::variant(name).unwrap();
    let (mut r, twin) = start(sw.clone(), false);
    let p = fast();
    let at_start = twin.joints();

    // First contact reads only.
    for l in twin.with(|u| u.received().to_vec()) {
        assert!(
            READ_ONLY.iter().any(|w| l.starts_with(w)),
            "{name}: first contact sent {l}"
        );
    }
    // Nothing moves before TROLHome: the counters mean nothing yet.
    assert_eq!(code(r.ma(&[0.0, 0.0, 0.5, 0.0, 0.5, 0.0])), -1, "{name}");
    assert!(near(&twin.joints(), &at_start, 1e-9), "{name}");

    // Home: hard home in CTU's order, then to the profile's home pose.
    assert_eq!(code(r.home(0)), 0, "{name}");
    let home = p.home_pose_deg.map(f64::to_radians);
    assert!(
        near(&twin.joints(), &home, 2e-3),
        "{name}: {:?}",
        twin.joints()
    );
    let hh: Vec<String> = twin.with(|u| {
        u.received()
            .iter()
            .filter(|l| l.starts_with("HH"))
            .cloned()
            .collect()
    });
    assert_eq!(
        hh,
        ["HHB:", "HHA:", "HHC:", "HHD:", "HHE:", "HHF:"],
        "{name}"
    );
    // Each group went only once the one before was home (issue 37: on a unit that does
    // not raise its moving bit while homing, the next group went after 1 s).
    let overlaps = twin.with(|u| u.overlaps().to_vec());
    assert!(overlaps.is_empty(), "{name}: {overlaps:?}");

    // A Home halted on the way fails (BIOS_NOT_HOMED at the Finish after it); nothing moves
    // before a Home that ends.
    r.call(&trol::table::HOME, &[trol::Value::Int(0)]).unwrap();
    twin.wait_moving();
    std::thread::sleep(Duration::from_millis(50));
    assert_eq!(code(r.halt()), 0, "{name}");
    assert_eq!(code(r.finish()), -1, "{name}: Finish after a halted Home");
    assert_eq!(code(r.ma(&[0.0, 0.0, 0.5, 0.0, 0.5, 0.0])), -1, "{name}");
    assert_eq!(code(r.home(0)), 0, "{name}");

    // A joint move, then the actual position.
    let q1 = [0.3, 0.2, 0.9, -0.4, 0.6, 0.5];
    assert_eq!(code(r.ma(&q1)), 0, "{name}");
    assert_eq!(code(r.finish()), 0, "{name}");
    assert!(
        near(&twin.joints(), &q1, 2e-3),
        "{name}: {:?}",
        twin.joints()
    );
    let got = r.position(Tag::Joint, PosMode::Actual).unwrap().to_array6();
    assert!(near(&got, &q1, 2e-3), "{name}: {got:?}");
    // A precision point is the unit's own IRC counts (issue 38: the A465 controller's were
    // answered), and one given back is where the arm goes.
    let irc = r.position(Tag::Prec, PosMode::Actual).unwrap().to_array6();
    let want = p.joints_to_irc(&twin.joints());
    assert!(near(&irc, &want, 1.5), "{name}: {irc:?} for {want:?}");
    let q2 = [0.2, 0.1, 0.8, -0.3, 0.5, 0.4];
    let target: Vec<i32> = p.joints_to_irc(&q2).map(|v| v.round() as i32).to_vec();
    assert_eq!(
        code(r.move_ii(&Location::Prec(target.clone()), false)),
        0,
        "{name}"
    );
    assert_eq!(code(r.finish()), 0, "{name}");
    assert!(
        near(&twin.joints(), &q2, 2e-3),
        "{name}: {:?}",
        twin.joints()
    );
    assert_eq!(
        code(r.define("#pp", &Location::Prec(target.clone()))),
        0,
        "{name}"
    );
    let listed = r.locations().unwrap();
    let pp = listed
        .iter()
        .find(|(n, _)| n.as_str() == "#pp")
        .map(|(_, l)| l.to_array6());
    let back = pp.unwrap_or([f64::NAN; 6]);
    let sent: [f64; 6] = std::array::from_fn(|i| f64::from(target[i]));
    assert!(near(&back, &sent, 1.5), "{name}: {back:?} for {sent:?}");
    assert_eq!(code(r.ma(&q1)), 0, "{name}");
    assert_eq!(code(r.finish()), 0, "{name}");

    // A straight line to a cartesian location: the tool stays on the line.
    let kin = Kinematics::default();
    let from = kin.fk_xyzypr(&q1);
    let mut to = from;
    to[0] += 60.0;
    to[2] -= 40.0;
    let n0 = twin.with(|u| u.received().len());
    assert_eq!(
        code(r.move_ii(&Location::from_array6(Tag::Cart, to), true)),
        0,
        "{name}"
    );
    assert_eq!(code(r.finish()), 0, "{name}");
    let at = kin.fk_xyzypr(&twin.joints());
    assert!(
        (0..3).all(|i| (at[i] - to[i]).abs() <= 1.0),
        "{name}: {at:?}"
    );
    let segments = twin.with(|u| {
        u.received()[n0..]
            .iter()
            .filter(|l| l.starts_with("COORDMVT:"))
            .count()
    });
    assert!(
        segments > 1,
        "{name}: a straight line in {segments} segment(s)"
    );

    // Beyond the profile's range (J2 at 89.9 deg: inside the A465 model's 90, outside
    // CRS93's -90.31..89.69 in TROL's signs): refused, nothing sent.
    let before = twin.joints();
    let n0 = twin.with(|u| u.received().len());
    let c = code(r.ma(&[0.0, 89.9f64.to_radians(), 0.5, 0.0, 0.5, 0.0]));
    assert_eq!(c, -3, "{name}");
    let sent: Vec<String> = twin.with(|u| u.received()[n0..].to_vec());
    assert!(
        sent.iter().all(|l| !l.starts_with("COORDMV")),
        "{name}: {sent:?}"
    );
    assert!(near(&twin.joints(), &before, 1e-9), "{name}");

    // The gripper: closing on an object stops at it, and Finish waits for it.
    twin.with(|u| u.set_object(Some(400.0)));
    assert_eq!(code(r.close_gripper(50)), 0, "{name}");
    assert_eq!(code(r.finish()), 0, "{name}");
    assert_eq!(
        twin.with(|u| u.feed(b"\nAPG?\n")),
        b"APG=400\r\n"
            .iter()
            .copied()
            .filter(|&b| !(sw.lf_only && b == b'\r'))
            .collect::<Vec<u8>>(),
        "{name}"
    );
    // GetGripper: the unit reads the opening, not what is between the fingers.
    let g = r.gripper().unwrap();
    assert_eq!(g.held, trol::Held::Unknown, "{name}");
    assert!(
        g.opening_mm > 0.0 && g.opening_mm < trol_a465::arm::FINGER_MAX,
        "{name}: {g:?}"
    );
    twin.with(|u| u.set_object(None));
    // Open, Finish, then a motion, as a 1998 program does (issue 38: the motion was refused
    // BIOS_BUSY now and then, Finish having taken the fingers as arrived while the unit
    // still drove them).
    let here = twin.joints();
    let mut there = here;
    there[0] += 0.05;
    for i in 0..6 {
        assert_eq!(code(r.open_gripper(50)), 0, "{name}: open {i}");
        assert_eq!(code(r.finish()), 0, "{name}: finish {i}");
        assert_eq!(code(r.ma(&there)), 0, "{name}: ma {i}");
        assert_eq!(code(r.close_gripper(50)), 0, "{name}: close {i}");
        assert_eq!(code(r.finish()), 0, "{name}: finish {i}");
        assert_eq!(code(r.ma(&here)), 0, "{name}: ma after close {i}");
        assert_eq!(code(r.finish()), 0, "{name}: finish after ma {i}");
    }

    // Halt mid-motion: the arm stops short, and Halt says done only with the arm standing;
    // nothing reports the motion as done. (At 1 % speed the motion takes about 5 s, longer
    // than a Halt that tries every stop, so the Halt finds it under way on a busy machine.)
    let far = [-1.6, -0.2, 0.4, 0.5, 0.2, -0.5];
    assert_eq!(code(r.speed(1)), 0, "{name}");
    assert_eq!(code(r.ma(&far)), 0, "{name}");
    twin.wait_moving();
    let h = code(r.halt());
    if sw.stop_stops || sw.purge_stops {
        assert_eq!(h, 0, "{name}");
        assert!(
            !twin.with(|u| u.is_moving()),
            "{name}: Halt said done while the arm moved"
        );
        let stopped = twin.joints();
        assert!(!near(&stopped, &far, 0.01), "{name}");
        assert_eq!(
            code(r.finish()),
            0,
            "{name}: nothing is under way after Halt"
        );
        if !sw.stop_stops {
            // PURGE: reset the motors: nothing moves before the arm is homed again.
            assert_eq!(code(r.ma(&q1)), trol_a465::arm::code::NOT_HOMED, "{name}");
            assert!(near(&twin.joints(), &stopped, 1e-9), "{name}");
            assert_eq!(code(r.home(0)), 0, "{name}");
        }
    } else {
        // No stop stops this unit: Halt says so, and Finish reports the arm as it goes on.
        assert_eq!(h, TROL_ERR_NOT_STOPPED.0, "{name}");
        assert!(
            twin.with(|u| u.is_moving()),
            "{name}: the arm was still moving"
        );
        assert_eq!(code(r.finish()), 0, "{name}");
        assert!(near(&twin.joints(), &far, 2e-3), "{name}");
        assert_eq!(code(r.home(0)), 0, "{name}");
    }
    if sw.stop_latches {
        // The latched error refuses the next motion, and Home clears it.
        assert_eq!(code(r.ma(&q1)), MARS_ERROR, "{name}");
        assert_eq!(code(r.home(0)), 0, "{name}");
    }

    // A unit that refuses a motion (here: COORDGRP forgotten by a unit restarted behind
    // TROL's back) never makes it a success.
    twin.with(|u| u.feed(b"COORDGRP:A\n"));
    let before = twin.joints();
    let c = code(r.ma(&q1));
    let c = if c == 0 { code(r.finish()) } else { c };
    match sw.refusal {
        mars8::Refusal::Silent => assert_eq!(c, NOT_AT_TARGET, "{name}"),
        mars8::Refusal::Line => assert_eq!(c, TROL_ERR_ROBOT_UNSURE.0, "{name}"),
        mars8::Refusal::ErrorBit => assert_eq!(c, MARS_ERROR, "{name}"),
    }
    assert!(near(&twin.joints(), &before, 1e-6), "{name}");
    // Home sets the unit up again.
    assert_eq!(code(r.home(0)), 0, "{name}");

    // Arm power lost mid-motion: Finish says so.
    assert_eq!(code(r.ma(&q1)), 0, "{name}");
    twin.wait_moving();
    twin.with(|u| u.set_power_off(true));
    assert_eq!(code(r.finish()), ARM_POWER, "{name}");
    assert_eq!(code(r.ma(&q1)), ARM_POWER, "{name}");
    twin.with(|u| u.set_power_off(false));
    // The motion stop, likewise.
    twin.with(|u| u.set_motion_stop(true));
    assert_eq!(code(r.ma(&q1)), MOTION_STOP, "{name}");
    twin.with(|u| u.set_motion_stop(false));

    assert_eq!(code(r.speed(100)), 0, "{name}");

    // A line nobody asked for: the next call is UNSURE and sends nothing.
    assert_eq!(code(r.home(0)), 0, "{name}");
    twin.with(|u| u.say("OVERCURRENT B"));
    std::thread::sleep(Duration::from_millis(50));
    let before = twin.joints();
    assert_eq!(code(r.ma(&q1)), TROL_ERR_ROBOT_UNSURE.0, "{name}");
    twin.wait_still();
    assert!(near(&twin.joints(), &before, 1e-9), "{name}");

    // A silent unit: TROL_ERR_ROBOT within the reply limit, nothing moves; then it works.
    twin.with(|u| u.set_silent(true));
    let t = Instant::now();
    assert_eq!(code(r.ma(&q1)), TROL_ERR_ROBOT.0, "{name}");
    assert!(t.elapsed() < Duration::from_secs(20), "{name}");
    twin.with(|u| u.set_silent(false));
    assert_eq!(code(r.ma(&q1)), 0, "{name}");
    assert_eq!(code(r.finish()), 0, "{name}");
    assert!(near(&twin.joints(), &q1, 2e-3), "{name}");
}

/// Every variant at once, one thread each: the time is the twins' and the waits', not the
/// machine's (a few seconds of CPU in all), so a busy machine only slows them alike.
#[test]
fn every_variant_works_or_fails_safe() {
    let runs: Vec<_> = mars8::VARIANTS
        .iter()
        .map(|(name, _)| (*name, std::thread::spawn(move || the_variant(name))))
        .collect();
    let failed: Vec<&str> = runs
        .into_iter()
        .filter_map(|(name, t)| t.join().is_err().then_some(name))
        .collect();
    assert!(
        failed.is_empty(),
        "failed: {failed:?} (their panics are above)"
    );
}

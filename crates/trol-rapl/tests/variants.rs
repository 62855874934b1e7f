//! The RAPL-II backend across every controller the public sources allow
//! (`trol_rapl::c500::VARIANTS`: refusal forms, ACK at the end, DONE lag, an emergency stop
//! with and without a line, not homed, MA/MI in radians, inches, a WORLD frame offset, another
//! pulse table, the bytes after a digit, echo off), each driven through TROL's API twice: with
//! the profile that matches it, and with the safe default a first contact starts from.
//!
//! Every call either works right or fails safe: a success (the call and the Finish after it)
//! leaves the arm where the call asked; a refusal or a failure of the line leaves it where it
//! was; an UNSURE leaves it at one of the two. Never a success for a failure, never a motion
//! nobody asked for. Where TROL is meant to work (the matching profile on every variant but
//! those it cannot drive safely), every step must also succeed as the user expects.

mod common;

use std::time::Duration;

use common::{Sim, TEST_001, start_scaled};
use trol::{Location, PosMode, Robot, Tag};
use trol_a465::kinematics::{Kinematics, Pose};
use trol_proto::application::code::{TROL_ERR_NOT_STOPPED, TROL_ERR_ROBOT_UNSURE};
use trol_rapl::backend::{ARM_POWER, NOT_AT_TARGET};
use trol_rapl::{C500, Profile, RAPL_CODES, RaplBackend};

/// The line's speed in these tests (the paced in-memory line and the twin).
const BAUD: u32 = 115_200;

/// Where a call should leave the arm.
#[derive(Clone, Copy, Debug)]
enum Want {
    /// At this tool pose (x y z mm, yaw pitch roll rad).
    Pose([f64; 6]),
    /// At these joints (rad).
    Joints([f64; 6]),
    /// Where it was: the call is refused.
    Refused,
    /// Motions one after the other: at the last on success; at any of them, or where it
    /// was, on UNSURE.
    Chain(&'static [Want]),
}

struct Run<'a> {
    label: String,
    sim: &'a Sim,
    robot: Robot,
    /// The twin's pulse convention.
    pulses: trol_rapl::frames::Frames,
    /// Where TROL is meant to work: every step must succeed as the user expects.
    works: bool,
    /// Halt must reach the arm while a motion runs.
    halt_must_work: bool,
    /// No stop stops this controller's arm: Halt must say TROL_ERR_NOT_STOPPED.
    halt_cannot: bool,
    /// This controller's JOG moves along the tool's axes.
    jog_tool: bool,
    /// Where this controller's HOME leaves the arm (radians).
    home: [f64; 6],
    false_success: Vec<String>,
    unasked: Vec<String>,
    missed: Vec<String>,
    outcomes: Vec<String>,
    /// Motion calls: succeeded (call and Finish), refused or not run, UNSURE, accepted but
    /// ended in a named code at Finish.
    tally: [usize; 4],
}

impl Run<'_> {
    /// Whether the twin's arm is seen standing within a few of its turns (its flag lags the
    /// line by one turn).
    fn standing_soon(&self) -> bool {
        let until = std::time::Instant::now() + Duration::from_millis(300);
        while self.sim.moving() {
            if std::time::Instant::now() > until {
                return false;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        true
    }
}

fn pose_of(q: &[f64; 6]) -> Pose {
    Kinematics::new([0.0; 6]).fk(q)
}

fn near_pose(q: &[f64; 6], p: &[f64; 6]) -> bool {
    let a = pose_of(q);
    let b = Pose::from_xyzypr(*p);
    let d = a.pos.distance(b.pos);
    d < 1.0 && trol_rapl::probe::rotation_distance_deg(&a, &b) < 0.3
}

fn near_joints(a: &[f64; 6], b: &[f64; 6]) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() < 0.005)
}

fn at(q: &[f64; 6], want: &Want, before: &[f64; 6]) -> bool {
    match want {
        Want::Pose(p) => near_pose(q, p),
        Want::Joints(j) => near_joints(q, j),
        Want::Refused => near_joints(q, before),
        Want::Chain(all) => all.last().is_some_and(|w| at(q, w, before)),
    }
}

/// Where an UNSURE may leave the arm: where it was, or where it was asked to go.
fn unsure_at(q: &[f64; 6], want: &Want, before: &[f64; 6]) -> bool {
    match want {
        Want::Chain(all) => all.iter().any(|w| at(q, w, before)),
        w => at(q, w, before),
    }
}

impl Run<'_> {
    /// A motion call and the Finish after it, checked against where the arm ends.
    fn motion(
        &mut self,
        what: &str,
        want: Want,
        call: impl FnOnce(&mut Robot) -> trol::Result<()>,
    ) {
        let before = self.sim.planned_end();
        let r = call(&mut self.robot);
        let f = self.robot.finish();
        let after = self.sim.planned_end();
        let here = format!("{}: {what}", self.label);
        let expect_refusal = matches!(want, Want::Refused);
        self.outcomes.push(format!(
            "{what}: {} / finish {}",
            r.as_ref()
                .map(|_| "ok".into())
                .unwrap_or_else(|e| e.to_string()),
            f.as_ref()
                .map(|_| "ok".into())
                .unwrap_or_else(|e| e.to_string())
        ));
        // Finish said the motion ended: the arm stands (or is within its last second of
        // controller time: the twin's flag is read a moment after Finish answered).
        if f.is_ok() && self.sim.moving() {
            std::thread::sleep(Duration::from_millis(50));
            if self.sim.moving() {
                self.false_success.push(format!(
                    "{here}: Finish succeeded while the arm still moves"
                ));
            }
        }
        self.tally[match (&r, &f) {
            (Ok(()), Ok(())) => 0,
            (Err(e), _) if e.code() == TROL_ERR_ROBOT_UNSURE => 2,
            (Err(_), _) => 1,
            (Ok(()), Err(_)) => 3,
        }] += 1;
        match (&r, &f) {
            (Ok(()), Ok(())) => {
                if expect_refusal || !at(&after, &want, &before) {
                    self.false_success.push(format!(
                        "{here}: success, but the arm ends at {after:?} (wanted {want:?}, was at {before:?})"
                    ));
                }
            }
            (Ok(()), Err(e)) => {
                // The motion was accepted and its end is not a success: a named code, and the
                // arm nowhere else than before, partway or at the target. A motion the
                // controller refused must not have been reported accepted.
                if expect_refusal && !near_joints(&after, &before) {
                    self.unasked
                        .push(format!("{here}: the arm moved to {after:?}"));
                }
                if expect_refusal {
                    // The arm cannot do it (below the table, past a limit): the call's 0 said
                    // it was accepted.
                    self.false_success.push(format!(
                        "{here}: the call succeeded though the arm cannot do it ({e} at Finish)"
                    ));
                }
                if self.works && !expect_refusal {
                    self.missed.push(format!("{here}: finish failed: {e}"));
                }
            }
            (Err(e), _) => {
                let unsure = e.code() == TROL_ERR_ROBOT_UNSURE;
                let stayed = near_joints(&after, &before);
                // A step of a chain refused: the steps before it ran, as asked.
                let chain_step = matches!(want, Want::Chain(_)) && e.is_refusal();
                let explained =
                    stayed || ((unsure || chain_step) && unsure_at(&after, &want, &before));
                if !explained {
                    self.unasked.push(format!(
                        "{here}: failed ({e}) but the arm went from {before:?} to {after:?}"
                    ));
                }
                if self.works && !(expect_refusal && e.is_refusal()) {
                    self.missed.push(format!("{here}: {e}"));
                }
            }
        }
        if self.works && expect_refusal && r.is_ok() {
            self.missed.push(format!("{here}: not refused"));
        }
    }

    /// A call that moves nothing.
    fn plain(&mut self, what: &str, call: impl FnOnce(&mut Robot) -> trol::Result<()>) {
        let before = self.sim.planned_end();
        let r = call(&mut self.robot);
        let after = self.sim.planned_end();
        self.outcomes.push(format!(
            "{what}: {}",
            r.as_ref()
                .map(|_| "ok".into())
                .unwrap_or_else(|e| e.to_string())
        ));
        if !near_joints(&after, &before) {
            self.unasked
                .push(format!("{}: {what} moved the arm", self.label));
        }
        if let Err(e) = r {
            if self.works {
                self.missed.push(format!("{}: {what}: {e}", self.label));
            }
        }
    }

    /// Wait until the controller has taken a motion (its planned end moved), within 20 s.
    fn accepted(&self, before: &[f64; 6]) -> bool {
        for _ in 0..4000 {
            if !near_joints(&self.sim.planned_end(), before) {
                return true;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        false
    }

    fn script(&mut self) {
        self.plain("speed 50", |r| r.speed(50));
        self.motion("home", Want::Joints(self.home), |r| r.home(0));
        self.motion("move test_001", Want::Pose(TEST_001), |r| {
            r.move_to("test_001", false)
        });
        let a = [380.0, 20.0, 200.0, 0.0, std::f64::consts::FRAC_PI_2, 0.0];
        self.motion("moveii A straight", Want::Pose(a), |r| {
            r.move_ii(&Location::from_array6(Tag::Cart, a), true)
        });
        let mut p = pose_of(&self.sim.planned_end()).to_xyzypr();
        p[2] += 20.0;
        // A controller whose JOG moves along the tool's axes: TROL's straight Jog (world
        // axes) is refused before anything is sent.
        let want = if self.jog_tool {
            Want::Refused
        } else {
            Want::Pose(p)
        };
        self.motion("jog z+20 straight", want, |r| {
            r.jog(&[0.0, 0.0, 20.0], true)
        });
        // The manual's check: a move below the table is refused and the arm stays (no
        // earlier target replayed).
        let below = [380.0, 20.0, -40.0, 0.0, std::f64::consts::FRAC_PI_2, 0.0];
        self.motion("moveii below the table", Want::Refused, |r| {
            r.move_ii(&Location::from_array6(Tag::Cart, below), false)
        });
        let mut q = self.sim.planned_end();
        q[5] += 0.2;
        self.motion("joint 6 +0.2", Want::Joints(q), |r| r.joint(6, 0.2));
        self.motion("joint 1 +3.3 (past its limit)", Want::Refused, |r| {
            r.joint(1, 3.3)
        });
        let m = [0.1, 0.2, 0.3, 0.1, 0.5, 0.2];
        self.motion("ma", Want::Joints(m), |r| r.ma(&m));
        let mut q = self.sim.planned_end();
        q[4] -= 0.1;
        self.motion("mi", Want::Joints(q), |r| {
            r.mi(&[0.0, 0.0, 0.0, 0.0, -0.1, 0.0])
        });
        // A precision point in this controller's own pulses.
        let jt = [0.2, 0.3, 0.4, 0.0, 0.6, 0.0];
        let pulses = self
            .pulses
            .joints_to_pulses(jt.map(f64::to_degrees))
            .expect("the twin's pulses");
        self.motion("moveii precision point", Want::Joints(jt), |r| {
            r.move_ii(
                &Location::Prec(pulses.iter().map(|p| *p as i32).collect()),
                false,
            )
        });
        // A 1998 program's relative motions back to back, no Finish between them (issue
        // 38): each queues and is computed from where the one before it ends.
        // Computed from where the arm stands (with the safe default, earlier motions were
        // refused); a step refused leaves the arm where the steps before it took it.
        let chain: &'static [Want] = {
            let mut q = self.sim.planned_end();
            let mut steps = Vec::new();
            for (j, d) in [(1, 0.3), (2, 0.6), (4, 0.5)] {
                q[j] += d;
                steps.push(Want::Joints(q));
            }
            q[4] -= 0.1;
            steps.push(Want::Joints(q));
            let depart = pose_of(&q)
                .then(&Pose::from_xyzypr([-30.0, 0.0, 0.0, 0.0, 0.0, 0.0]))
                .to_xyzypr();
            steps.push(Want::Pose(depart));
            Box::leak(steps.into_boxed_slice())
        };
        // Slowly, so that each is sent while the one before runs.
        self.plain("speed 5", |r| r.speed(5));
        self.motion(
            "joint 2, joint 3, joint 5, mi, depart: back to back",
            Want::Chain(chain),
            |r| {
                r.joint(2, 0.3)?;
                r.joint(3, 0.6)?;
                r.joint(5, 0.5)?;
                r.mi(&[0.0, 0.0, 0.0, 0.0, -0.1, 0.0])?;
                r.depart(&[-30.0], false)
            },
        );
        self.plain("speed 50", |r| r.speed(50));
        // Three motions back to back: they queue, and Finish waits for the last.
        static APPRO: std::sync::OnceLock<[Want; 2]> = std::sync::OnceLock::new();
        let chain = APPRO.get_or_init(|| {
            let appro = Pose::from_xyzypr(TEST_001)
                .then(&Pose::from_xyzypr([-90.0, 0.0, 0.0, 0.0, 0.0, 0.0]))
                .to_xyzypr();
            [Want::Pose(appro), Want::Pose(TEST_001)]
        });
        self.motion(
            "appro, appro straight, move straight",
            Want::Chain(chain),
            |r| {
                r.appro("test_001", &[-90.0], false)?;
                r.appro("test_001", &[-90.0], true)?;
                r.move_to("test_001", true)
            },
        );
        let depart = pose_of(&self.sim.planned_end())
            .then(&Pose::from_xyzypr([-50.0, 0.0, 0.0, 0.0, 0.0, 0.0]))
            .to_xyzypr();
        self.motion("depart 50 straight", Want::Pose(depart), |r| {
            r.depart(&[-50.0], true)
        });
        self.plain("close 60, finish", |r| {
            r.close_gripper(60)?;
            r.finish()
        });
        self.plain("open 50, finish", |r| {
            r.open_gripper(50)?;
            r.finish()
        });
        self.plain("getposition", |r| {
            r.position(Tag::Joint, PosMode::Actual).map(|_| ())
        });

        // Halt gets through while a long motion runs, and stops it short. At 1 % (about 2.4
        // s at the twin's time scale 20), so that the motion outlasts a controller's reply
        // window (ack-at-end: TROLJoint returns only once it has passed) and the Halt's way
        // to the arm on a loaded machine: at 2 %, a loaded run saw the Halt land at 1.40 rad
        // of 1.5, where 1.4 means it came too late to tell.
        self.plain("speed 1", |r| r.speed(1));
        let before = self.sim.planned_end();
        let r = self.robot.joint(1, 1.5);
        let under_way = r.is_ok() && self.accepted(&before) && self.sim.moving();
        if under_way {
            let h = self.robot.halt();
            if h.is_ok() && !self.standing_soon() {
                self.false_success.push(format!(
                    "{}: Halt said done while the arm still moved",
                    self.label
                ));
            }
            if self.halt_cannot && !h.as_ref().is_err_and(|e| e.code() == TROL_ERR_NOT_STOPPED) {
                self.missed.push(format!(
                    "{}: Halt on an arm no stop stops: {h:?}",
                    self.label
                ));
            }
            if let Err(e) = &h {
                if e.code() != TROL_ERR_NOT_STOPPED && e.code() != TROL_ERR_ROBOT_UNSURE {
                    self.false_success
                        .push(format!("{}: Halt failed with {e}", self.label));
                }
            }
            let f = self.robot.finish();
            let turned = (self.sim.planned_end()[0] - before[0]).abs();
            self.outcomes.push(format!(
                "halt: {h:?} / finish {f:?} / turned {turned:.3} rad"
            ));
            if h.is_ok() && f.is_ok() && turned > 1.4 {
                self.false_success.push(format!(
                    "{}: Halt said done but the joint turned {turned:.3} of 1.5 rad",
                    self.label
                ));
            }
            if self.halt_must_work && (h.is_err() || f.is_err() || turned > 1.4) {
                self.missed.push(format!(
                    "{}: halt {h:?}, finish {f:?}, turned {turned}",
                    self.label
                ));
            }
        } else {
            let _ = self.robot.finish();
            if self.halt_must_work {
                self.missed.push(format!(
                    "{}: joint 1 for the halt did not return while the arm moved: {r:?}",
                    self.label
                ));
            }
        }

        // Halt while Finish waits (as a Ctrl-C handler or another thread asks): with
        // `completion = "finish"` a FINISH holds the controller's interpreter then.
        let before = self.sim.planned_end();
        let r = self.robot.joint(1, -1.5);
        if r.is_ok() && self.accepted(&before) && self.sim.moving() {
            let cancel = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
            let flag = cancel.clone();
            let t = std::thread::spawn(move || {
                // A twentieth of the motion's controller time, at the twin's time scale 20.
                std::thread::sleep(Duration::from_millis(100));
                flag.store(true, std::sync::atomic::Ordering::SeqCst);
            });
            let w = self.robot.finish_unless(&cancel);
            t.join().expect("the canceller");
            let turned = (self.sim.planned_end()[0] - before[0]).abs();
            self.outcomes.push(format!(
                "halt while finish waits: {w:?} / turned {turned:.3} rad"
            ));
            let halted = matches!(w, Ok(trol::Waited::Halted));
            if w.is_ok() && turned > 1.4 {
                self.false_success.push(format!(
                    "{}: Halt while Finish waited said done, but the joint turned {turned:.3} \
                     of 1.5 rad",
                    self.label
                ));
            }
            if self.halt_must_work && (!halted || turned > 1.4) {
                self.missed.push(format!(
                    "{}: halt while finish waits: {w:?}, turned {turned}",
                    self.label
                ));
            }
            let _ = self.robot.finish();
        } else if self.halt_must_work {
            self.missed.push(format!(
                "{}: joint 1 for the halt while finish waits: {r:?}",
                self.label
            ));
        }

        // A silent stop mid-motion (a servo fault: DONE, no LIMP, nothing printed): Finish
        // fails with BIOS_NOT_AT_TARGET within the motion's time and settle_ms, not after
        // the 120 s motion timeout.
        // At 1 %, so that the motion outlasts a controller's reply window (ack-at-end).
        self.plain("speed 1", |r| r.speed(1));
        let before = self.sim.planned_end();
        let r = self.robot.joint(1, 1.0);
        if r.is_ok() && self.accepted(&before) && self.sim.moving() {
            // A few degrees into the motion (at the twin's time scale).
            std::thread::sleep(Duration::from_millis(100));
            self.sim.stall();
            let t = std::time::Instant::now();
            let f = self.robot.finish();
            let took = t.elapsed();
            self.outcomes
                .push(format!("silent stop: finish {f:?} after {took:?}"));
            match &f {
                Ok(()) => self.false_success.push(format!(
                    "{}: Finish succeeded after a silent stop mid-motion",
                    self.label
                )),
                // BIOS_NOT_AT_TARGET, or the controller's own word for it (FINISH's error
                // where the profile trusts it).
                Err(e) if self.works && e.code().0 != NOT_AT_TARGET && e.code().is_trol() => self
                    .missed
                    .push(format!("{}: silent stop gave {e}", self.label)),
                Err(_) => {}
            }
            // settle_ms (1 s) and the polls; far below motion_timeout_s (120 s).
            if self.works && took > Duration::from_secs(30) {
                self.missed.push(format!(
                    "{}: a silent stop was noticed after {took:?}",
                    self.label
                ));
            }
        } else if self.works {
            self.missed.push(format!(
                "{}: joint 1 for the silent stop: {r:?}",
                self.label
            ));
        }

        // An emergency stop mid-motion: Finish fails with a named code.
        let before = self.sim.planned_end();
        let r = self.robot.joint(1, -1.0);
        if r.is_ok() && self.accepted(&before) {
            self.sim.emergency_stop();
            while self.sim.has_power() {
                std::thread::sleep(Duration::from_millis(2));
            }
            let f = self.robot.finish();
            self.outcomes.push(format!("emergency stop: finish {f:?}"));
            match &f {
                Ok(()) => self.false_success.push(format!(
                    "{}: Finish succeeded after an emergency stop mid-motion",
                    self.label
                )),
                Err(e) => {
                    let named = e.code().0 == ARM_POWER || e.code() == TROL_ERR_ROBOT_UNSURE;
                    if !named {
                        self.false_success
                            .push(format!("{}: emergency stop gave {e}", self.label));
                    }
                }
            }
            // With the power off, a motion is refused before anything is sent.
            self.motion("joint after the emergency stop", Want::Refused, |r| {
                r.joint(2, 0.1)
            });
        } else if self.works {
            self.missed
                .push(format!("{}: joint 1 for the e-stop: {r:?}", self.label));
        }
    }
}

/// Variants the matching profile cannot drive in full: TROL must fail safe there. A warning
/// line before ACK leaves every motion UNSURE; a controller that echoes nothing cannot be
/// typed to.
const FAIL_SAFE: &[&str] = &["warning-then-ack", "no-echo", "finish-deaf"];

/// Variants where the first stop does not stop the arm: Halt tries the next.
const ESCALATED: &[&str] = &[
    "halt-ignored",
    "ctrl-c-cancels-line",
    "unstoppable",
    "finish-deaf",
];

/// Variants no stop stops: Halt must say so (TROL_ERR_NOT_STOPPED), never done.
const UNSTOPPABLE: &[&str] = &["unstoppable"];

/// Which profile the backend gets: the one that describes the variant, or the safe default.
#[derive(Clone, Copy, PartialEq)]
enum Given {
    Matching,
    SafeDefault,
}

fn run_variant(name: &str, given: Given) {
    let (twin, homed) = trol_rapl::c500::variant(name).expect("a variant");
    let twin = Profile { baud: BAUD, ..twin };
    let alike = C500::new(
        twin.clone(),
        trol_a465::arm::Arm::new(Default::default()),
        Vec::new(),
    )
    .describe();
    let safe = Profile {
        baud: BAUD,
        ..Profile::default()
    };
    let mut report = Vec::new();
    let mut bad = Vec::new();
    let runs = match given {
        Given::Matching => [("matching profile", alike)],
        Given::SafeDefault => [("safe default", safe)],
    };
    for (which, gateway) in runs {
        let label = format!("{name} with the {which}");
        // Where a stop must be escalated, the twin's arm runs slower, so that its motion
        // outlasts the Halt's real-time windows, as a real arm's does.
        let scale = if ESCALATED.contains(&name) { 4.0 } else { 20.0 };
        let (port, sim) = start_scaled(twin.clone(), homed, None, scale);
        let backend = match RaplBackend::connect(port, gateway) {
            Ok(b) => b,
            Err(e) => {
                let text = e.to_string();
                report.push(format!("{label}: no session: {text}"));
                if name == "no-echo" {
                    assert!(text.contains("echo"), "{label}: {text}");
                } else {
                    bad.push(format!("{label}: the session did not open: {text}"));
                }
                assert!(sim.ran().iter().all(|l| !l.starts_with("MOVE")));
                continue;
            }
        };
        let cfg = trol_proto::link::LinkConfig::default();
        let (line, handle) =
            trol_controller::embedded_with(trol_controller::Pcp::new(backend), cfg);
        let mut robot = Robot::over(Box::new(line), cfg, Some(handle));
        robot.set_codes(RAPL_CODES);
        let mut run = Run {
            label: label.clone(),
            sim: &sim,
            robot,
            pulses: trol_rapl::frames::Frames::of(&twin),
            works: which == "matching profile" && !FAIL_SAFE.contains(&name),
            halt_must_work: which == "matching profile"
                && !FAIL_SAFE.contains(&name)
                && !UNSTOPPABLE.contains(&name),
            halt_cannot: UNSTOPPABLE.contains(&name),
            jog_tool: twin.twin.jog_tool,
            home: twin.twin.home_deg.map(f64::to_radians),
            false_success: Vec::new(),
            unasked: Vec::new(),
            missed: Vec::new(),
            outcomes: Vec::new(),
            tally: [0; 4],
        };
        run.script();
        if which == "matching profile" && name.starts_with("finish") {
            let finishes = sim.ran().iter().filter(|l| l.as_str() == "FINISH").count();
            if finishes == 0 {
                bad.push(format!("{label}: FINISH was never typed"));
            }
            run.outcomes.push(format!("FINISH typed {finishes} times"));
        }
        let [ok, refused, unsure, at_finish] = run.tally;
        // The figure docs/reliability.md cites (`-- --nocapture` shows it).
        eprintln!(
            "variant {label}: {} motion calls: {ok} succeeded, {refused} refused or not run, \
             {unsure} UNSURE, {at_finish} ended at Finish with a named code; {} false \
             successes, {} unasked motions",
            ok + refused + unsure + at_finish,
            run.false_success.len(),
            run.unasked.len()
        );
        report.push(format!("{label}:\n  {}", run.outcomes.join("\n  ")));
        if std::env::var_os("TROL_SHOW").is_some() {
            eprintln!("{}", report.last().unwrap());
        }
        bad.extend(run.false_success);
        bad.extend(run.unasked);
        bad.extend(run.missed);
    }
    assert!(
        bad.is_empty(),
        "{}\n\nwhat happened:\n{}",
        bad.join("\n"),
        report.join("\n")
    );
}

macro_rules! variants {
    ($($test:ident => $name:literal),* $(,)?) => {
        // Each variant with each profile is a test of its own, so that the slow ones (an
        // escalated Halt runs the twin at a quarter of the others' speed) run side by side.
        $(
            mod $test {
                #[test]
                fn with_the_matching_profile() {
                    super::run_variant($name, super::Given::Matching);
                }

                #[test]
                fn with_the_safe_default() {
                    super::run_variant($name, super::Given::SafeDefault);
                }
            }
        )*

        #[test]
        fn every_variant_has_a_test() {
            let tested = [$($name),*];
            for (name, _) in trol_rapl::c500::VARIANTS {
                assert!(tested.contains(name), "variant {name} has no test here");
            }
        }
    };
}

variants! {
    default => "default",
    colon_refusal => "colon-refusal",
    stars_refusal => "stars-refusal",
    no_period => "no-period",
    ack_at_end => "ack-at-end",
    done_lag => "done-lag",
    estop_line => "estop-line",
    warning_then_ack => "warning-then-ack",
    no_ack => "no-ack",
    ma_radians => "ma-radians",
    inch => "inch",
    world_offset => "world-offset",
    pulses_g3000 => "pulses-g3000",
    nul_after_digit => "nul-after-digit",
    no_echo => "no-echo",
    not_homed => "not-homed",
    home_elsewhere => "home-elsewhere",
    jog_tool => "jog-tool",
    halt_ignored => "halt-ignored",
    ctrl_c_cancels_line => "ctrl-c-cancels-line",
    unstoppable => "unstoppable",
    finish => "finish",
    finish_trusted => "finish-trusted",
    finish_at_once => "finish-at-once",
    finish_refused => "finish-refused",
    finish_deaf => "finish-deaf",
}

//! The controllers under test, each with its twin and its differences: the one place where
//! a backend's documented differences are listed.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

use trol::Robot;
use trol_a465::arm::{Arm, ArmSettings};
use trol_controller::Pcp;
use trol_port::memory;
use trol_proto::link::LinkConfig;

use crate::{Differences, Subject, Twin};

/// The twins run faster than real time, so that the suite is quick, but slow enough that a
/// far motion lasts longer than it takes to see it move and Halt it.
const SCALE: f64 = 4.0;

/// The line between the backend and a simulated controller.
const BAUD: u32 = 115_200;

/// A twin's thread, stopped when the subject is dropped.
struct Runs {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Drop for Runs {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn robot_over<B: trol_controller::Backend + 'static>(
    backend: B,
    codes: &'static trol_proto::application::CodeTable,
) -> Robot {
    let cfg = LinkConfig::default();
    let (line, handle) = trol_controller::embedded_with(Pcp::new(backend), cfg);
    let mut robot = Robot::over(Box::new(line), cfg, Some(handle));
    robot.set_codes(codes);
    robot
}

// ---- the simulated A465 (port `sim`) ----

struct SimTwin(trol_sim::SharedArm, trol_sim::PowerSwitch);

impl SimTwin {
    /// Switch the power and wait (bounded) until the simulator has taken it.
    fn power(&self, on: bool) {
        let n = self.1.set(on);
        let until = std::time::Instant::now() + std::time::Duration::from_secs(10);
        while self.1.applied() < n && std::time::Instant::now() < until {
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
    }
}

impl Twin for SimTwin {
    fn joints(&self) -> [f64; 6] {
        let mut v = self.0.lock().unwrap();
        let v = v.as_mut().expect("the simulator shares its arm");
        let now = v.now();
        v.arm.actual(now)
    }
    fn moving(&self) -> bool {
        let mut v = self.0.lock().unwrap();
        let v = v.as_mut().expect("the simulator shares its arm");
        let now = v.now();
        v.arm.is_moving(now)
    }
    fn say_unasked(&self, _text: &str) -> bool {
        false
    }
    fn can_lose_power(&self, announced: bool) -> bool {
        // The embedded simulator is its own controller: it always knows.
        announced
    }
    fn cut_power(&self, _announced: bool) {
        self.power(false);
    }
    fn power_on(&self) {
        self.power(true);
    }
}

/// The simulated A465, not homed at start (the differences: none; it has no line of its
/// own, so no line comes unasked).
pub fn sim() -> Subject {
    let mut b = trol_sim::SimBackend::new(trol_sim::SimSettings {
        arm: ArmSettings {
            homed: false,
            ..Default::default()
        },
        time_scale: SCALE,
        ..Default::default()
    });
    let view = b.share();
    let power = b.power_switch();
    Subject {
        label: "the simulated A465".into(),
        robot: robot_over(b, trol_sim::SIM_CODES),
        twin: Box::new(SimTwin(view, power)),
        differences: Differences {
            starts_unhomed: true,
            ..Differences::default()
        },
    }
}

// ---- a C500 in RAPL-II (`rapl:`) ----

/// C500 variants the suite does not drive, each with its reason: the matching profile
/// cannot drive them in full, and TROL must fail safe there, which
/// crates/trol-rapl/tests/variants.rs checks (every call refused or UNSURE, nothing moved).
pub const C500_FAIL_SAFE: &[(&str, &str)] = &[
    (
        "warning-then-ack",
        "a warning line before ACK leaves every motion UNSURE",
    ),
    (
        "no-echo",
        "a controller that echoes nothing cannot be typed to",
    ),
    (
        "finish-deaf",
        "FINISH never answers: every Finish ends UNSURE",
    ),
];

struct C500Twin {
    joints: Arc<Mutex<[f64; 6]>>,
    moving: Arc<AtomicBool>,
    /// Power switched by the suite, taken by the serving thread (Some(on)).
    power: Arc<Mutex<Option<bool>>>,
    /// Whether the variant prints a line when the power goes.
    announces: bool,
    _runs: Runs,
}

impl C500Twin {
    fn power(&self, on: bool) {
        *self.power.lock().unwrap() = Some(on);
        let until = std::time::Instant::now() + std::time::Duration::from_secs(10);
        while self.power.lock().unwrap().is_some() && std::time::Instant::now() < until {
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
    }
}

impl Twin for C500Twin {
    fn joints(&self) -> [f64; 6] {
        *self.joints.lock().unwrap()
    }
    fn moving(&self) -> bool {
        self.moving.load(Ordering::SeqCst)
    }
    fn say_unasked(&self, _text: &str) -> bool {
        // The simulated C500 prints unasked only where its variant does (estop-line).
        false
    }
    fn can_lose_power(&self, announced: bool) -> bool {
        // A variant either prints its e-stop line or says nothing (STATUS's LIMP row shows it).
        announced == self.announces
    }
    fn cut_power(&self, _announced: bool) {
        self.power(false);
    }
    fn power_on(&self) {
        self.power(true);
    }
}

/// A simulated C500 of variant `name` (`trol_rapl::c500::VARIANTS`), driven with the
/// profile that matches it. Differences: a variant may start not homed; on `unstoppable`
/// no stop stops the arm.
pub fn c500(name: &str) -> Subject {
    let (twin, homed) = trol_rapl::c500::variant(name).expect("a C500 variant");
    let twin = trol_rapl::Profile { baud: BAUD, ..twin };
    let arm = Arm::new(ArmSettings {
        homed,
        ..Default::default()
    });
    let announces = !twin.twin.estop_line.is_empty();
    let mut c = trol_rapl::C500::new(twin, arm, Vec::new());
    let matching = c.describe();
    let power = Arc::new(Mutex::new(None::<bool>));
    let (host, ctl) = memory::pair(Some(BAUD));
    let stop = Arc::new(AtomicBool::new(false));
    let joints = Arc::new(Mutex::new([0.0; 6]));
    let moving = Arc::new(AtomicBool::new(false));
    let thread = {
        let (stop, joints, moving, power) =
            (stop.clone(), joints.clone(), moving.clone(), power.clone());
        std::thread::spawn(move || {
            let mut port = ctl;
            let _ = trol_rapl::c500::serve_with(
                &mut port,
                &mut c,
                SCALE,
                &stop,
                &mut |_| {},
                &mut |c, now| {
                    match power.lock().unwrap().take() {
                        Some(false) => c.power_off(now),
                        Some(true) => c.power_on(),
                        None => {}
                    }
                    *joints.lock().unwrap() = c.arm_mut().actual(now);
                    moving.store(c.arm_moving(now), Ordering::SeqCst);
                },
            );
        })
    };
    let runs = Runs {
        stop,
        thread: Some(thread),
    };
    let backend = trol_rapl::RaplBackend::connect(Box::new(host), matching)
        .unwrap_or_else(|e| panic!("C500 {name}: the session opens: {e}"));
    Subject {
        label: format!("C500 {name}"),
        robot: robot_over(backend, trol_rapl::RAPL_CODES),
        twin: Box::new(C500Twin {
            joints,
            moving,
            power,
            announces,
            _runs: runs,
        }),
        differences: Differences {
            starts_unhomed: !homed,
            unstoppable: name == "unstoppable",
            untimed_trajectory: true,
            ..Differences::default()
        },
    }
}

// ---- the units served on a line of their own: a MARS 8, a C500C ----

/// A simulated controller that serves its line on a thread (a MARS 8, a C500C), as its twin
/// reads it.
trait Unit: Send + 'static {
    fn joints(&mut self) -> [f64; 6];
    fn is_moving(&mut self) -> bool;
    fn say(&mut self, text: &str);
    fn can_lose_power(&self, announced: bool) -> bool;
    fn set_power(&mut self, on: bool);
}

impl Unit for trol_mars::Mars8 {
    fn joints(&mut self) -> [f64; 6] {
        trol_mars::Mars8::joints(self)
    }
    fn is_moving(&mut self) -> bool {
        trol_mars::Mars8::is_moving(self)
    }
    fn say(&mut self, text: &str) {
        trol_mars::Mars8::say(self, text)
    }
    fn can_lose_power(&self, announced: bool) -> bool {
        // The unit's status word has the power bit, which TROL reads: always told.
        announced
    }
    fn set_power(&mut self, on: bool) {
        self.set_power_off(!on)
    }
}

impl Unit for trol_c500c::C500c {
    fn joints(&mut self) -> [f64; 6] {
        trol_c500c::C500c::joints(self)
    }
    fn is_moving(&mut self) -> bool {
        trol_c500c::C500c::is_moving(self)
    }
    fn say(&mut self, text: &str) {
        trol_c500c::C500c::say(self, text)
    }
    fn can_lose_power(&self, announced: bool) -> bool {
        // ash prints `Lost robot power` or, on power-loss-silent, nothing (armstat shows it).
        announced == self.switches().power_loss_line
    }
    fn set_power(&mut self, on: bool) {
        if on {
            self.set_power_on()
        } else {
            self.set_power_off()
        }
    }
}

/// How a unit serves its line until told to stop.
type Serve<U> = fn(Box<dyn trol_port::Port>, Arc<Mutex<U>>, Arc<AtomicBool>) -> std::io::Result<()>;

struct UnitTwin<U> {
    unit: Arc<Mutex<U>>,
    _runs: Runs,
}

impl<U: Unit> UnitTwin<U> {
    /// `unit` serving `port` with `serve` on a thread of its own.
    fn serving(unit: U, port: Box<dyn trol_port::Port>, serve: Serve<U>) -> UnitTwin<U> {
        let unit = Arc::new(Mutex::new(unit));
        let stop = Arc::new(AtomicBool::new(false));
        let thread = {
            let (unit, stop) = (unit.clone(), stop.clone());
            std::thread::spawn(move || {
                let _ = serve(port, unit, stop);
            })
        };
        UnitTwin {
            unit,
            _runs: Runs {
                stop,
                thread: Some(thread),
            },
        }
    }
}

impl<U: Unit> Twin for UnitTwin<U> {
    fn joints(&self) -> [f64; 6] {
        self.unit.lock().unwrap().joints()
    }
    fn moving(&self) -> bool {
        self.unit.lock().unwrap().is_moving()
    }
    fn say_unasked(&self, text: &str) -> bool {
        self.unit.lock().unwrap().say(text);
        true
    }
    fn can_lose_power(&self, announced: bool) -> bool {
        self.unit.lock().unwrap().can_lose_power(announced)
    }
    fn cut_power(&self, _announced: bool) {
        self.unit.lock().unwrap().set_power(false);
    }
    fn power_on(&self) {
        self.unit.lock().unwrap().set_power(true);
    }
}

// ---- a MARS 8 (`mars:`) ----

/// A simulated MARS 8 of variant `name` (`trol_mars::mars8::VARIANTS`), CTU's CRS93 profile
/// with every axis' speed ten times as fast and the unit at ten times real time. Differences:
/// it starts not homed (a MARS 8 hard-homes each axis); on `unstoppable` no stop stops the
/// arm.
pub fn mars(name: &str) -> Subject {
    let sw = trol_mars::mars8::variant(name).expect("a MARS 8 variant");
    let mut fast = trol_mars::Profile::crs93();
    fast.speed = fast.speed.map(|v| v * 10);
    let (host, unit_side) = memory::pair(Some(BAUD));
    let twin = UnitTwin::serving(
        trol_mars::Mars8::new(trol_mars::Profile::crs93(), sw, false, 10.0),
        Box::new(unit_side),
        trol_mars::mars8::serve,
    );
    let backend = trol_mars::MarsBackend::connect(Box::new(host), fast, None, None, Vec::new())
        .unwrap_or_else(|e| panic!("MARS 8 {name}: the session opens: {e}"));
    Subject {
        label: format!("MARS 8 {name}"),
        robot: robot_over(backend, trol_mars::MARS_CODES),
        twin: Box::new(twin),
        differences: Differences {
            starts_unhomed: true,
            unstoppable: name == "unstoppable",
            ..Differences::default()
        },
    }
}

// ---- a C500C (`c500c:`) ----

/// C500C variants the suite does not drive, each with its reason: where TROL fails safe
/// (crates/trol-c500c's own variant tests check every motion refused, nothing moved), and
/// where a variant differs only in calls the suite makes none of (locations by name,
/// cartesian motions, the gripper: those variant tests, and the pick example on every
/// variant in crates/trol-cli/tests/c500c.rs, drive them).
pub const C500C_FAIL_SAFE: &[(&str, &str)] = &[
    (
        "echo-off",
        "a console that echoes nothing: TROL cannot see a line whole before ash runs it, and \
         types only reads; every other call is BIOS_UNSUPPORTED",
    ),
    (
        "ctrl-c-keeps-line",
        "Ctrl-C keeps a typed line: TROL could not take a damaged line back, and types only \
         reads; every other call is BIOS_UNSUPPORTED",
    ),
    (
        "pendant-holds",
        "the pendant holds the point of control: every motion is refused until it hands it \
         back",
    ),
    (
        "print-braced",
        "differs only in how `print` shows a location, which the suite reads none of",
    ),
    (
        "gripper-air",
        "differs only in the gripper, which the suite does not move",
    ),
    (
        "gripper-none",
        "differs only in the gripper, which the suite does not move",
    ),
    (
        "grip-return-at-end",
        "differs only in the gripper, which the suite does not move",
    ),
    (
        "world-xyz",
        "differs only in the WORLD row's angles, which only cartesian motions read",
    ),
    (
        "setvalid-silent",
        "differs only in how `setvalid` answers, which only cartesian motions type",
    ),
    (
        "cloc-reversed",
        "differs only in how a cartesian location holds its angles, which only cartesian \
         motions write and read",
    ),
    (
        "world-flange",
        "differs only in the frame the WORLD row's angles turn, which only cartesian motions \
         read",
    ),
    (
        "pulses-offset",
        "differs only in how the PULSES row counts, which only an approach to a precision \
         point converts; the suite makes none",
    ),
];

/// A simulated C500C of variant `name` (`trol_c500c::c500c::VARIANTS`) in real time (its
/// motions are joint moves at the A465's speeds: faster than real time, a far one ends
/// before a Halt could be tried), driven with the profile that matches it. Differences:
/// one joint at a time, one motion at a time, a trajectory of one waypoint, nothing sent
/// after UNSURE until reconnect (docs/c500c.md); on `unstoppable` no stop stops the arm.
pub fn c500c(name: &str) -> Subject {
    use trol_c500c::c500c;
    let sw = c500c::variant(name).expect("a C500C variant");
    let profile = c500c::matching_profile(&sw);
    let (host, ctl) = memory::pair(Some(profile.baud));
    let twin = UnitTwin::serving(
        trol_c500c::C500c::new(sw, false, 1.0),
        Box::new(ctl),
        c500c::serve,
    );
    let backend = trol_c500c::C500cBackend::connect(Box::new(host), profile, None)
        .unwrap_or_else(|e| panic!("C500C {name}: the session opens: {e}"));
    Subject {
        label: format!("C500C {name}"),
        robot: robot_over(backend, trol_c500c::C500C_CODES),
        twin: Box::new(twin),
        differences: Differences {
            starts_unhomed: true,
            unstoppable: name == "unstoppable",
            untimed_trajectory: true,
            one_joint_at_a_time: true,
            one_motion_at_a_time: true,
            one_waypoint: true,
            unsure_until_reconnect: true,
            ..Differences::default()
        },
    }
}

//! The C500C backend through TROL's API against the simulated C500C, across every variant of
//! the points the public sources leave open, with a profile that agrees with the controller,
//! one that does not, and one that settles nothing. What the user checks: a call that says
//! success left the arm where it was asked to be; every other call moved nothing it was not
//! asked to, and said what to do; never a false success, never an unasked motion.

use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use trol::{PosMode, Robot, Tag};
use trol_c500c::c500c::{self, Return, Switches};
use trol_c500c::profile::{Angles, MotionReturn, Profile};
use trol_c500c::{C500C_CODES, C500c, C500cBackend, backend};
use trol_controller::Pcp;
use trol_port::faulty::{Flip, FlipSwitch};
use trol_port::memory;
use trol_proto::application::code::{TROL_ERR_NOT_STOPPED, TROL_ERR_ROBOT_UNSURE};
use trol_proto::link::LinkConfig;

/// The twin's clock against real time: motions of seconds take a fraction.
const SCALE: f64 = 10.0;

struct Rig {
    robot: Robot,
    unit: Arc<Mutex<C500c>>,
    /// What the backend said in its log (its notes: why it refused).
    said: Arc<Mutex<Vec<String>>>,
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Drop for Rig {
    fn drop(&mut self) {
        self.stop.store(true, std::sync::atomic::Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Rig {
    fn joints(&self) -> [f64; 6] {
        self.unit.lock().unwrap().joints()
    }
    fn moving(&self) -> bool {
        self.unit.lock().unwrap().is_moving()
    }
    fn received(&self) -> Vec<String> {
        self.unit.lock().unwrap().received().to_vec()
    }
    fn said(&self) -> String {
        self.said.lock().unwrap().join("\n")
    }
}

fn rig(sw: Switches, homed: bool, profile: Profile) -> Rig {
    rig_at(sw, homed, profile, SCALE)
}

/// A rig whose twin runs `scale` times real time (1: as TROL plans, for the tests that need
/// a motion's planned end to be the twin's).
fn rig_at(sw: Switches, homed: bool, profile: Profile, scale: f64) -> Rig {
    rig_on(sw, homed, profile, scale, FlipSwitch::default())
}

/// A rig whose twin's console line damages a bit when `flip` says so.
fn rig_on(sw: Switches, homed: bool, profile: Profile, scale: f64, flip: FlipSwitch) -> Rig {
    let (host, ctl) = memory::pair(Some(57600));
    let ctl = Flip::new(ctl, flip);
    let unit = Arc::new(Mutex::new(C500c::new(sw, homed, scale)));
    let stop = Arc::new(AtomicBool::new(false));
    let thread = {
        let (unit, stop) = (unit.clone(), stop.clone());
        std::thread::spawn(move || {
            let _ = c500c::serve(Box::new(ctl), unit, stop);
        })
    };
    let said = Arc::new(Mutex::new(Vec::new()));
    let log = said.clone();
    let backend = C500cBackend::connect(
        Box::new(host),
        profile,
        Some(Box::new(move |l: &str| {
            eprintln!("c500c: {l}");
            log.lock().unwrap().push(l.to_string());
        })),
    )
    .unwrap_or_else(|e| panic!("the session opens: {e}"));
    let cfg = LinkConfig::default();
    let (line, handle) = trol_controller::embedded_with(Pcp::new(backend), cfg);
    let mut robot = Robot::over(Box::new(line), cfg, Some(handle));
    robot.set_codes(C500C_CODES);
    trol::check_server(&mut robot).unwrap();
    Rig {
        robot,
        unit,
        said,
        stop,
        thread: Some(thread),
    }
}

fn profile(ret: Option<MotionReturn>) -> Profile {
    Profile {
        motion_return: ret,
        ..Profile::default()
    }
}

/// A profile that disagrees with the controller on every point it states.
fn contrary_profile(sw: &Switches) -> Profile {
    Profile {
        motion_return: contrary(sw),
        world_angles: Some(match sw.world_angles {
            Angles::Zyx => Angles::Xyz,
            Angles::Xyz => Angles::Zyx,
        }),
        // TROL's tool frame where the controller's angles turn another (`world-flange`).
        tool_rotation: Some([0.0; 3]),
        // A home pose the controller's is not.
        home_joints: Some(sw.home_deg.map(|d| if d == 0.0 { 10.0 } else { 0.0 })),
        ..Profile::default()
    }
}

fn contrary(sw: &Switches) -> Option<MotionReturn> {
    Some(match sw.motion_return {
        Return::AtStart => MotionReturn::End,
        Return::AtEnd => MotionReturn::Start,
    })
}

/// Wait until `cond` holds, within a bound a loaded machine keeps.
fn wait_until(what: &str, mut cond: impl FnMut() -> bool) {
    let start = std::time::Instant::now();
    while !cond() {
        assert!(start.elapsed() < Duration::from_secs(30), "{what}: never");
        std::thread::sleep(Duration::from_millis(2));
    }
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 2e-3
}

/// The arm where it was, within the encoders' dither.
fn unmoved(a: &[f64; 6], b: &[f64; 6]) -> bool {
    (0..6).all(|j| (a[j] - b[j]).abs() < 1e-3)
}

/// One joint motion with its Finish, as a user runs it: success only with the arm at its
/// end; anything else with the arm unmoved or standing, and a code that is not success.
fn one_motion(r: &mut Rig, what: &str) -> bool {
    let before = r.joints();
    let sent = r.robot.joint(1, 0.3);
    let done = sent.and_then(|_| r.robot.finish());
    let after = r.joints();
    match done {
        Ok(()) => {
            assert!(
                close(after[0], before[0] + 0.3),
                "{what}: success with joint 1 at {} (from {})",
                after[0],
                before[0]
            );
            true
        }
        Err(e) => {
            eprintln!("{what}: the motion failed: {e}");
            assert_ne!(e.code().0, 0, "{what}");
            // Whatever went wrong, the arm did not go anywhere else than asked.
            assert!(
                close(after[0], before[0]) || close(after[0], before[0] + 0.3) || r.moving(),
                "{what}: {e} with joint 1 at {}",
                after[0]
            );
            false
        }
    }
}

fn run_variant(name: &str) {
    let sw = c500c::variant(name).expect("a variant");

    // A profile that settles nothing: refused before sending, saying which key.
    let mut r = rig(sw.clone(), true, profile(None));
    let e = r.robot.joint(1, 0.3).unwrap_err();
    assert_eq!(e.code().0, backend::UNSETTLED, "{name}: {e}");
    assert!(
        !r.received().iter().any(|l| l.starts_with("joint")),
        "{name}"
    );
    assert!(!r.moving());
    drop(r);

    // The profile that agrees: the motion works, unless the pendant holds the control, which
    // is said with its code.
    let mut r = rig(sw.clone(), true, c500c::matching_profile(&sw));
    if !sw.echo || sw.ctrl_c_keeps_line {
        // A console where TROL cannot see a line whole before ash runs it (issue 62): reads
        // work; anything else is refused before sending, and nothing moves.
        let q = r.robot.position(Tag::Joint, PosMode::Actual).unwrap();
        assert!(close(q.to_array6()[0], r.joints()[0]), "{name}");
        let typed = r.received();
        for e in [
            r.robot.speed(100).unwrap_err(),
            r.robot.joint(1, 0.3).unwrap_err(),
        ] {
            assert_eq!(e.code().0, backend::UNSUPPORTED, "{name}: {e}");
        }
        assert!(
            r.said().contains("sends only reads"),
            "{name}: {}",
            r.said()
        );
        let reads = trol_c500c::probe::READS;
        assert!(
            r.received()[typed.len()..]
                .iter()
                .all(|l| reads.contains(&l.as_str())),
            "{name}: only reads typed: {:?}",
            r.received()
        );
        assert!(!r.moving(), "{name}");
        return;
    }
    r.robot.speed(100).unwrap();
    if sw.pendant_holds {
        let e = r.robot.joint(1, 0.3).unwrap_err();
        assert_eq!(e.code().0, backend::NO_CONTROL, "{name}: {e}");
        assert!(!r.moving());
        return;
    }
    assert!(
        one_motion(&mut r, name),
        "{name}: the agreeing profile drives the arm"
    );
    let q = r.robot.position(Tag::Joint, PosMode::Actual).unwrap();
    assert!(
        close(q.to_array6()[0], r.joints()[0]),
        "{name}: GetPosition agrees"
    );
    // Back to back: the second waits for the first and both arrive.
    let start = r.joints()[0];
    r.robot.joint(1, 0.1).unwrap();
    r.robot.joint(1, 0.1).unwrap();
    r.robot.finish().unwrap();
    assert!(close(r.joints()[0], start + 0.2), "{name}: back to back");
    teach_and_return(&mut r, &sw, name);
    grip_round(&mut r, &sw, name);
    cart_round(&mut r, &sw, name);
    // A joint limit: refused with its code, nothing moves.
    let before = r.joints();
    let e = r.robot.joint(2, 3.0).unwrap_err();
    assert_eq!(e.code().0, trol_a465::arm::code::JOINT_LIMIT, "{name}: {e}");
    assert!(unmoved(&before, &r.joints()), "{name}");
    // Halt during a long motion (about 6 s scaled, longer than a Halt may take): success
    // only with the arm standing.
    r.robot.speed(1).unwrap();
    r.robot.joint(1, -2.0).unwrap();
    wait_until("the motion starts", || r.moving());
    match r.robot.halt() {
        Ok(()) => {
            assert!(
                sw.ctrl_c_stops,
                "{name}: Halt said done for an arm that does not stop"
            );
            assert!(!r.moving(), "{name}: Halt said done with the arm moving");
        }
        Err(e) => {
            assert!(!sw.ctrl_c_stops, "{name}: {e}");
            assert_eq!(e.code(), TROL_ERR_NOT_STOPPED, "{name}: {e}");
        }
    }
    drop(r);

    // The contrary profile: right, or UNSURE with nothing further sent; never a false
    // success.
    let mut r = rig(sw.clone(), true, contrary_profile(&sw));
    r.robot.speed(100).unwrap();
    if !one_motion(&mut r, name) {
        let e = r.robot.joint(1, 0.1).unwrap_err();
        assert_eq!(
            e.code(),
            TROL_ERR_ROBOT_UNSURE,
            "{name}: after a failure: {e}"
        );
        return;
    }
    // A move to a taught point under the contrary profile: there, or a failure with the
    // arm where it was or at the point.
    if r.robot.here("#back", Tag::Prec).is_err() {
        return;
    }
    let taught = r.joints();
    if r.robot
        .joint(1, 0.2)
        .and_then(|_| r.robot.finish())
        .is_err()
    {
        return;
    }
    let away = r.joints();
    let done = r
        .robot
        .move_to("#back", false)
        .and_then(|_| r.robot.finish());
    let at = r.joints();
    match done {
        Ok(()) => assert!(unmoved(&taught, &at), "{name}: success at {at:?}"),
        Err(e) => {
            assert_ne!(e.code().0, 0, "{name}");
            assert!(
                unmoved(&taught, &at) || unmoved(&away, &at) || r.moving(),
                "{name}: {e} with the arm at {at:?}"
            );
            return;
        }
    }
    // Cartesian motions under the other reading of the WORLD row's angles: a pose both
    // readings agree on goes right; one they differ on is refused, the arm unmoved (the
    // WORLD row disagrees where the arm stands, or TROL has not seen it agree anywhere).
    use std::f64::consts::FRAC_PI_2;
    for target in [
        [400.0, 0.0, 240.0, 0.0, FRAC_PI_2, 0.0],
        [420.0, -30.0, 200.0, 0.3, 1.3, 0.2],
    ] {
        let before = r.joints();
        let done = r
            .robot
            .move_ii(&trol::Location::Cart(target.to_vec()), false)
            .and_then(|_| r.robot.finish());
        match done {
            Ok(()) => assert!(self::at(&r, &target), "{name}: success at {:?}", tcp(&r)),
            Err(e) => {
                assert_ne!(e.code().0, 0, "{name}");
                assert!(
                    unmoved(&before, &r.joints()),
                    "{name}: {e}, and the arm moved"
                );
            }
        }
    }
}

mod flips;
mod rounds;
mod rules;

use rounds::{at, cart_round, grip_round, tcp, teach_and_return};

macro_rules! each {
    ($($test:ident => $name:literal,)*) => {
        $(
            #[test]
            fn $test() {
                run_variant($name);
            }
        )*

        #[test]
        fn every_variant_has_a_test() {
            let tested = [$($name),*];
            for (name, _) in c500c::VARIANTS {
                assert!(tested.contains(name), "no test runs the variant {name}");
            }
        }
    };
}

each! {
    default => "default",
    return_at_end => "return-at-end",
    error_prefixed => "error-prefixed",
    error_bracketed => "error-bracketed",
    echo_off => "echo-off",
    ctrl_c_keeps_line => "ctrl-c-keeps-line",
    lf_only => "lf-only",
    pendant_holds => "pendant-holds",
    unstoppable => "unstoppable",
    ctrl_c_no_prompt => "ctrl-c-no-prompt",
    power_loss_silent => "power-loss-silent",
    print_braced => "print-braced",
    gripper_air => "gripper-air",
    gripper_none => "gripper-none",
    grip_return_at_end => "grip-return-at-end",
    world_xyz => "world-xyz",
    world_flange => "world-flange",
    pulses_offset => "pulses-offset",
    rows_apart => "rows-apart",
    home_elsewhere => "home-elsewhere",
    cloc_reversed => "cloc-reversed",
    setvalid_silent => "setvalid-silent",
}

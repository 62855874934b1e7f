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
    let (host, ctl) = memory::pair(Some(57600));
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

/// Teach a precision point where the arm stands (an ash `ploc`), move away, move back to it
/// by name, list it, save, delete it: each right, or (where `print` shows a precision point
/// in a form TROL does not read) UNSURE with the arm where it was.
fn teach_and_return(r: &mut Rig, sw: &Switches, name: &str) {
    let home = r.joints();
    let taught = r.robot.here("#pick1", Tag::Prec);
    if sw.loc_print != c500c::LocPrint::Row {
        let e = taught.unwrap_err();
        assert_eq!(e.code(), TROL_ERR_ROBOT_UNSURE, "{name}: {e}");
        assert!(unmoved(&home, &r.joints()), "{name}");
        // Nothing further is sent, a motion least of all.
        let before = r.received().len();
        assert!(r.robot.joint(1, 0.1).is_err());
        assert!(unmoved(&home, &r.joints()), "{name}");
        assert_eq!(r.received().len(), before, "{name}: sent after UNSURE");
        // The rest of the run needs a fresh session.
        *r = rig(sw.clone(), true, c500c::matching_profile(sw));
        r.robot.speed(100).unwrap();
        return;
    }
    taught.unwrap_or_else(|e| panic!("{name}: Here: {e}"));
    let held = r.unit.lock().unwrap().plocs();
    assert_eq!(held.len(), 1, "{name}: {held:?}");
    assert_eq!(held[0].0, "pick1", "{name}");
    // Away (two joints, so only the named move brings it back in one motion).
    r.robot.joint(2, 0.2).unwrap();
    r.robot.finish().unwrap();
    r.robot.joint(1, -0.2).unwrap();
    r.robot.finish().unwrap();
    assert!(!unmoved(&home, &r.joints()), "{name}");
    r.robot
        .move_to("#pick1", false)
        .unwrap_or_else(|e| panic!("{name}: Move: {e}"));
    r.robot
        .finish()
        .unwrap_or_else(|e| panic!("{name}: Finish: {e}"));
    let back = r.joints();
    assert!(
        (0..6).all(|j| (back[j] - home[j]).abs() < 1e-3),
        "{name}: back at {back:?}, taught at {home:?}"
    );
    let listed = r.robot.locations().unwrap();
    assert_eq!(listed.len(), 1, "{name}: {listed:?}");
    assert_eq!(listed[0].0, "#pick1", "{name}");
    r.robot.save_locations().unwrap();
    assert_eq!(r.unit.lock().unwrap().saved_plocs().len(), 1, "{name}");
    r.robot.delete_location("#pick1").unwrap();
    assert!(r.unit.lock().unwrap().plocs().is_empty(), "{name}");
    let e = r.robot.move_to("#pick1", false).unwrap_err();
    assert_eq!(
        e.code(),
        trol_proto::application::code::TROL_ERR_LOCATION,
        "{name}: {e}"
    );
    let moves = r
        .received()
        .iter()
        .filter(|l| l.starts_with("move"))
        .count();
    assert_eq!(
        moves, 1,
        "{name}: a move to a name ash no longer has was sent"
    );
}

/// Where the twin's tool is (TROL's tool is the null one here): TROL's x y z yaw pitch roll.
fn tcp(r: &Rig) -> [f64; 6] {
    trol_a465::kinematics::Kinematics::new([0.0; 6]).fk_xyzypr(&r.joints())
}

/// The tool at `v` (mm, and 0.1 degree: the end rule's tolerance).
fn at(r: &Rig, v: &[f64; 6]) -> bool {
    use trol_a465::kinematics::Pose;
    let (mm, deg) = trol_c500c::world::gap(&Pose::from_xyzypr(tcp(r)), &Pose::from_xyzypr(*v));
    mm < 0.5 && deg < 0.1
}

/// Cartesian motions as the manual's pick example makes them, from READY: a joint-
/// interpolated move above the place, straight moves, a jog, a cartesian location taught
/// with Here and approached, departed from and moved to by name. Each ends with the tool
/// where TROL's kinematics put the end.
fn cart_round(r: &mut Rig, sw: &Switches, name: &str) {
    use std::f64::consts::FRAC_PI_2;
    use trol::Location;
    let down = [400.0, 0.0, 240.0, 0.0, FRAC_PI_2, 0.0];
    if sw.loc_print != c500c::LocPrint::Row {
        // TROL reads its own location back before moving, and cannot: UNSURE, unmoved.
        let before = r.joints();
        let e = r
            .robot
            .move_ii(&Location::Cart(down.to_vec()), false)
            .unwrap_err();
        assert_eq!(e.code(), TROL_ERR_ROBOT_UNSURE, "{name}: {e}");
        assert!(unmoved(&before, &r.joints()), "{name}");
        assert!(
            !r.received().iter().any(|l| l.starts_with("move")),
            "{name}"
        );
        *r = rig(sw.clone(), true, c500c::matching_profile(sw));
        r.robot.speed(100).unwrap();
        return;
    }
    let go = |r: &mut Rig, what: &str, res: trol::Result<()>| {
        res.and_then(|_| r.robot.finish())
            .unwrap_or_else(|e| panic!("{name}: {what}: {e}"));
    };
    let res = r.robot.move_ii(&Location::Cart(down.to_vec()), false);
    go(r, "MoveII above the place", res);
    assert!(at(r, &down), "{name}: at {:?}", tcp(r));
    // A pose both readings of the angles agree on, then one where they differ: TROL reads
    // the WORLD row there, and from then on moves to such poses too.
    let turned = [420.0, -30.0, 200.0, 0.3, 1.3, 0.2];
    let res = r.robot.move_ii(&Location::Cart(turned.to_vec()), true);
    match res {
        Err(e) => {
            assert_eq!(e.code().0, backend::UNSETTLED, "{name}: {e}");
            // A wrist joint turned: the WORLD row now tells the readings apart.
            let res = r.robot.joint(4, 0.3);
            go(r, "Joint 4", res);
            let res = r.robot.move_ii(&Location::Cart(turned.to_vec()), true);
            go(r, "MoveII straight, turned", res);
        }
        Ok(()) => go(r, "MoveII straight, turned", Ok(())),
    }
    assert!(at(r, &turned), "{name}: at {:?}", tcp(r));
    let res = r.robot.jog(&[0.0, 20.0, -10.0], true);
    go(r, "Jog", res);
    let mut jogged = turned;
    jogged[1] += 20.0;
    jogged[2] -= 10.0;
    assert!(at(r, &jogged), "{name}: at {:?}", tcp(r));
    r.robot
        .here("spot", Tag::Cart)
        .unwrap_or_else(|e| panic!("{name}: Here: {e}"));
    let res = r.robot.depart(&[-30.0, 0.0, 0.0, 0.0, 0.0, 0.0], true);
    go(r, "Depart", res);
    assert!(!at(r, &jogged), "{name}");
    let res = r
        .robot
        .appro("spot", &[-10.0, 0.0, 0.0, 0.0, 0.0, 0.0], false);
    go(r, "Appro", res);
    use trol_a465::kinematics::Pose;
    let near = Pose::from_xyzypr(jogged)
        .then(&Pose::from_xyzypr([-10.0, 0.0, 0.0, 0.0, 0.0, 0.0]))
        .to_xyzypr();
    assert!(at(r, &near), "{name}: at {:?}, not {near:?}", tcp(r));
    let res = r.robot.move_to("spot", true);
    go(r, "Move spot", res);
    assert!(at(r, &jogged), "{name}: at {:?}", tcp(r));
    let listed = r.robot.locations().unwrap();
    let spot = listed
        .iter()
        .find(|(n, _)| n == "spot")
        .unwrap_or_else(|| panic!("{name}: {listed:?}"));
    let v = spot.1.to_array6();
    assert!(
        (0..3).all(|j| (v[j] - jogged[j]).abs() < 0.1),
        "{name}: listed {v:?}"
    );
    r.robot.delete_location("spot").unwrap();
    // A precision point taught here, left, and approached: its joints by the profile's
    // pulses, which every joint has been seen to agree with by now.
    r.robot
        .here("#over", Tag::Prec)
        .unwrap_or_else(|e| panic!("{name}: Here #over: {e}"));
    let res = r.robot.depart(&[-30.0, 0.0, 0.0, 0.0, 0.0, 0.0], true);
    go(r, "Depart #over", res);
    let res = r
        .robot
        .appro("#over", &[-10.0, 0.0, 0.0, 0.0, 0.0, 0.0], true);
    go(r, "Appro #over", res);
    assert!(at(r, &near), "{name}: at {:?}, not {near:?}", tcp(r));
    r.robot.delete_location("#over").unwrap();
    // Back to READY's joints for what follows, one joint at a time.
    for j in (1..=6u16).rev() {
        let q = r.joints()[j as usize - 1];
        if q.abs() > 1e-4 {
            let res = r.robot.joint(j, -q);
            go(r, "back", res);
        }
    }
}

/// The gripper as the manual uses it: Grip, Close and Open, each with its Finish; on a servo
/// gripper each ends with the jaws seen standing where asked; an air gripper opens and
/// closes but cannot be read; with none set, every grip call is refused before sending.
fn grip_round(r: &mut Rig, sw: &Switches, name: &str) {
    let jaws = |r: &Rig| r.unit.lock().unwrap().jaws();
    match sw.grip_type {
        c500c::GripType::Servo => {
            r.robot
                .grip(20)
                .unwrap_or_else(|e| panic!("{name}: Grip: {e}"));
            r.robot
                .finish()
                .unwrap_or_else(|e| panic!("{name}: Finish: {e}"));
            assert!((jaws(r) - 20.0).abs() < 0.1, "{name}: jaws at {}", jaws(r));
            let g = r.robot.gripper().unwrap();
            assert!((g.opening_mm - 20.0).abs() < 0.1, "{name}: {g:?}");
            r.robot.close_gripper(60).unwrap();
            // The arm does not move while the jaws do, and a second grip waits its turn.
            let before = r.joints();
            if r.unit.lock().unwrap().jaws_moving() {
                let e = r.robot.joint(1, 0.1).unwrap_err();
                assert_eq!(e.code().0, backend::BUSY, "{name}: {e}");
                assert!(unmoved(&before, &r.joints()), "{name}");
            }
            r.robot.finish().unwrap();
            assert!(jaws(r) < 0.1, "{name}: closed at {}", jaws(r));
            r.robot.open_gripper(50).unwrap();
            r.robot.finish().unwrap();
            assert!(jaws(r) > 49.9, "{name}: open at {}", jaws(r));
        }
        c500c::GripType::Air => {
            r.robot.close_gripper(60).unwrap();
            r.robot.finish().unwrap();
            let e = r.robot.grip(20).unwrap_err();
            assert_eq!(e.code().0, backend::UNSUPPORTED, "{name}: {e}");
            assert!(r.robot.gripper().is_err(), "{name}");
            r.robot.open_gripper(60).unwrap();
            r.robot.finish().unwrap();
        }
        c500c::GripType::None => {
            let e = r.robot.close_gripper(60).unwrap_err();
            assert_eq!(e.code().0, backend::UNSUPPORTED, "{name}: {e}");
            assert!(
                !r.received().iter().any(|l| l.starts_with("grip_")),
                "{name}: a grip command was sent"
            );
        }
    }
}

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
    lf_only => "lf-only",
    pendant_holds => "pendant-holds",
    unstoppable => "unstoppable",
    power_loss_silent => "power-loss-silent",
    print_braced => "print-braced",
    gripper_air => "gripper-air",
    gripper_none => "gripper-none",
    grip_return_at_end => "grip-return-at-end",
    world_xyz => "world-xyz",
    pulses_offset => "pulses-offset",
}

/// Not homed at power-on: a motion is refused with BIOS_NOT_HOMED and nothing is sent;
/// TROLHome homes the arm, and its success waits for armstat to say so.
#[test]
fn home_is_success_only_once_armstat_says_homed() {
    let sw = Switches::default();
    let mut r = rig(sw.clone(), false, c500c::matching_profile(&sw));
    let e = r.robot.joint(1, 0.3).unwrap_err();
    assert_eq!(e.code().0, trol_a465::arm::code::NOT_HOMED, "{e}");
    assert!(!r.received().iter().any(|l| l.starts_with("joint")));
    r.robot.home(0).unwrap();
    r.robot.finish().unwrap();
    assert!(!r.moving());
    assert!(one_motion(&mut r, "after Home"));
}

/// The arm's power lost during a motion: Finish is never success; with ash's line the next
/// call says UNSURE, and nothing further is sent.
#[test]
fn power_lost_mid_motion_is_never_success() {
    for name in ["default", "power-loss-silent", "return-at-end"] {
        let sw = c500c::variant(name).unwrap();
        // In real time, as TROL plans it: a motion of about 1.6 s, cut well before its end.
        let mut r = rig_at(sw.clone(), true, c500c::matching_profile(&sw), 1.0);
        r.robot.speed(20).unwrap();
        r.robot.joint(1, 1.0).unwrap();
        wait_until("the motion starts", || r.moving());
        r.unit.lock().unwrap().set_power_off();
        let e = r.robot.finish().unwrap_err();
        assert_ne!(e.code().0, 0, "{name}");
        assert!(!r.moving(), "{name}");
        let sent = r.received().len();
        let e = r.robot.joint(1, 0.1).unwrap_err();
        assert_ne!(e.code().0, 0, "{name}: {e}");
        assert!(
            !r.received()[sent..].iter().any(|l| l.starts_with("joint")),
            "{name}: a motion went out after the power loss"
        );
    }
}

/// A line nobody asked for: the next call is UNSURE and sends nothing.
#[test]
fn an_unasked_line_makes_the_next_call_unsure() {
    let sw = Switches::default();
    let mut r = rig(sw.clone(), true, c500c::matching_profile(&sw));
    r.unit.lock().unwrap().say("[test: Caught SIGABRT]");
    wait_until("the line is sent", || !r.unit.lock().unwrap().has_unsent());
    // Its time on the paced 57600 Bd line (25 bytes, 4.3 ms): a lower bound, which a loaded
    // machine only makes longer.
    std::thread::sleep(Duration::from_millis(20));
    let sent = r.received().len();
    let e = r.robot.joint(1, 0.3).unwrap_err();
    assert_eq!(e.code(), TROL_ERR_ROBOT_UNSURE, "{e}");
    assert_eq!(r.received().len(), sent, "nothing was sent");
    assert!(!r.moving());
}

/// A collision during a motion: Finish answers with CRS's error as BIOS_C500C_ERROR, the
/// motion queued behind it is dropped unsent, and the next motion works from where the arm
/// stopped.
#[test]
fn a_collision_ends_the_motion_with_its_error_and_drops_the_queue() {
    for name in ["default", "return-at-end", "error-bracketed"] {
        let sw = c500c::variant(name).unwrap();
        let mut r = rig_at(sw.clone(), true, c500c::matching_profile(&sw), 1.0);
        r.robot.speed(20).unwrap();
        r.robot.joint(1, 1.0).unwrap();
        r.robot.joint(1, 0.5).unwrap();
        wait_until("the motion starts", || r.moving());
        r.unit.lock().unwrap().collide(2);
        let e = r.robot.finish().unwrap_err();
        assert_eq!(e.code().0, backend::C500C_ERROR, "{name}: {e}");
        assert!(!r.moving(), "{name}");
        let stopped = r.joints()[0];
        assert!(stopped < 0.9, "{name}: stopped at {stopped}");
        assert!(
            !r.received().iter().any(|l| l == "joint 1,28.648"),
            "{name}: the queued motion went out"
        );
        r.robot.joint(1, 0.1).unwrap();
        r.robot.finish().unwrap();
        assert!(close(r.joints()[0], stopped + 0.1), "{name}");
    }
}

/// MA after the arm was moved by hand: computed from where the arm is read, not from where
/// TROL last left it, so it ends where it was asked to.
#[test]
fn ma_after_a_move_by_hand_ends_where_asked() {
    let sw = Switches::default();
    let mut r = rig(sw.clone(), true, c500c::matching_profile(&sw));
    r.robot.speed(100).unwrap();
    r.robot.joint(1, 0.2).unwrap();
    r.robot.finish().unwrap();
    r.unit
        .lock()
        .unwrap()
        .move_by_hand([0.5, 0.0, 0.0, 0.0, 0.0, 0.0]);
    // Past the window in which where the arm was seen to rest stands in for `w2` (a lower
    // bound: a loaded machine only makes it longer).
    std::thread::sleep(trol_controller::real::SEEN_FOR + Duration::from_millis(50));
    r.robot.ma(&[0.1, 0.0, 0.0, 0.0, 0.0, 0.0]).unwrap();
    r.robot.finish().unwrap();
    assert!(close(r.joints()[0], 0.1), "{:?}", r.joints());
}

/// MA of one joint goes as one `joint`; of several, refused before sending (never a
/// series of `joint` commands); a cartesian motion names what is not settled.
#[test]
fn several_joints_never_go_as_a_series() {
    let sw = Switches::default();
    let mut r = rig(sw.clone(), true, c500c::matching_profile(&sw));
    let q0 = r.joints();
    let mut q = q0;
    q[2] += 0.2;
    r.robot.ma(&q).unwrap();
    r.robot.finish().unwrap();
    assert!(close(r.joints()[2], q[2]));
    let sent = r.received().len();
    let e = r.robot.ma(&[0.1, 0.1, 0.1, 0.0, 0.0, 0.0]).unwrap_err();
    assert_eq!(e.code().0, backend::UNSETTLED, "{e}");
    assert!(!r.received()[sent..].iter().any(|l| l.starts_with("joint")));
    // Without `world-angles` a cartesian motion is refused too, before anything is typed.
    let sw = Switches::default();
    let mut r = rig(
        sw.clone(),
        true,
        Profile {
            world_angles: None,
            ..c500c::matching_profile(&sw)
        },
    );
    let sent = r.received().len();
    let e = r
        .robot
        .move_ii(
            &trol::Location::Cart(vec![400.0, 0.0, 400.0, 0.0, 1.57, 0.0]),
            false,
        )
        .unwrap_err();
    assert_eq!(e.code().0, backend::UNSETTLED, "{e}");
    assert_eq!(r.received()[sent..].len(), 0, "{:?}", &r.received()[sent..]);
}

/// A trajectory's one waypoint goes at the speed setting: one whose time is shorter than
/// the move takes there is BIOS_TOO_FAST, one at time 0 away from the arm
/// BIOS_BAD_ARGUMENT, both before anything is sent; one with time enough runs (untimed) and
/// ends at the waypoint. (Found by the conformance suite: a 0.05 s waypoint 1.5 rad away ran
/// at full speed and Finish said success.)
#[test]
fn a_trajectory_faster_than_the_speed_setting_is_refused_unsent() {
    let sw = Switches::default();
    let mut r = rig(sw.clone(), true, c500c::matching_profile(&sw));
    r.robot.speed(20).unwrap();
    let q0 = r.joints();
    let mut far = q0;
    far[0] += 1.0;
    let sent = r.received().len();
    for (time, want) in [
        (0.05, trol_a465::arm::code::TOO_FAST),
        (0.0, trol_a465::arm::code::BAD_ARGUMENT),
    ] {
        let e = r
            .robot
            .trajectory(&[trol::Waypoint { time, joints: far }])
            .unwrap_err();
        assert_eq!(e.code().0, want, "{time} s: {e}");
    }
    assert!(!r.received()[sent..].iter().any(|l| l.starts_with("joint")));
    assert!(close(r.joints()[0], q0[0]));
    // Time enough at 20 % (the A465's joint 1 does 180 deg/s at 100 %: 1 rad takes 1.6 s).
    let t = r
        .robot
        .trajectory(&[trol::Waypoint {
            time: 5.0,
            joints: far,
        }])
        .unwrap();
    assert_eq!(t, trol::Timing::Untimed);
    r.robot.finish().unwrap();
    assert!(close(r.joints()[0], far[0]), "{:?}", r.joints());
}

/// Where the arm was seen to rest, and the gate's `armstat`, stand in for the `w2` and the
/// `armstat` before the next motion only while nothing but reads went to ash since
/// (trol_controller::real::Recent): a `speed p` between makes the next motion read both
/// first; a power loss in between that nobody read is ash's refusal, with its code, and
/// nothing moves.
#[test]
fn a_line_that_is_not_a_read_makes_the_next_motion_read_w2_again() {
    use trol_controller::Backend;
    let sw = Switches::default();
    let (host, ctl) = memory::pair(Some(57600));
    let unit = Arc::new(Mutex::new(C500c::new(sw.clone(), true, SCALE)));
    let stop = Arc::new(AtomicBool::new(false));
    let server = {
        let (unit, stop) = (unit.clone(), stop.clone());
        std::thread::spawn(move || {
            let _ = c500c::serve(Box::new(ctl), unit, stop);
        })
    };
    let mut b = C500cBackend::connect(Box::new(host), c500c::matching_profile(&sw), None).unwrap();
    // However busy the machine, the sighting stands (no wall-clock bound in the test).
    b.set_seen_for(Duration::from_secs(600));
    let finish = |b: &mut C500cBackend| {
        let until = std::time::Instant::now() + Duration::from_secs(60);
        while b.moving().unwrap() {
            assert!(std::time::Instant::now() < until, "the motion ends");
        }
    };
    let typed_since = |n: usize| unit.lock().unwrap().received()[n..].to_vec();
    assert_eq!(b.joint(1, 0.05).unwrap(), 0);
    finish(&mut b);
    // Straight after the end it saw: the motion goes on what was seen, no w2 first.
    let mark = unit.lock().unwrap().received().len();
    assert_eq!(b.joint(1, -0.05).unwrap(), 0);
    let typed = typed_since(mark);
    let joint = typed
        .iter()
        .position(|l| l.starts_with("joint 1,"))
        .expect("sent");
    assert!(
        !typed[..joint].iter().any(|l| l == "w2" || l == "armstat"),
        "{typed:?}"
    );
    finish(&mut b);
    // A `speed p` between: w2 and armstat before the next motion.
    assert_eq!(b.speed(20).unwrap(), 0);
    let mark = unit.lock().unwrap().received().len();
    assert_eq!(b.joint(1, 0.05).unwrap(), 0);
    let typed = typed_since(mark);
    let joint = typed
        .iter()
        .position(|l| l.starts_with("joint 1,"))
        .expect("sent");
    assert!(typed[..joint].iter().any(|l| l == "w2"), "{typed:?}");
    assert!(typed[..joint].iter().any(|l| l == "armstat"), "{typed:?}");
    finish(&mut b);
    // The power lost silently right after the end TROL saw: the motion goes on what was
    // seen, ash refuses it, and that is the refusal with its code; the arm stays.
    unit.lock().unwrap().set_power_off();
    let before = unit.lock().unwrap().joints();
    match b.joint(1, 0.05) {
        Err(trol_controller::BackendError::Refused(c)) => assert_eq!(c, backend::ARM_POWER),
        other => panic!("{other:?}"),
    }
    assert!(unmoved(&unit.lock().unwrap().joints(), &before));
    assert!(!unit.lock().unwrap().is_moving());
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    drop(b);
    server.join().unwrap();
}

/// What the pendant taught: TROL lists it (through ash's pager, which it answers because it
/// asked for the whole list), moves to it by name and ends at its pulses; a name ash has but
/// has not taught is TROL_ERR_LOCATION, and no `move` goes out.
#[test]
fn points_taught_on_the_pendant_are_listed_and_reached() {
    let sw = Switches::default();
    let mut r = rig(sw.clone(), true, c500c::matching_profile(&sw));
    r.robot.speed(100).unwrap();
    let target = [0.3, -0.2, 0.4, 0.1, -0.3, 0.2];
    let pulses = trol_a465::model::joints_to_counts(&target).map(i64::from);
    {
        let mut u = r.unit.lock().unwrap();
        // More than one page of `list`.
        for i in 0..(c500c::PAGE_ROWS + 5) {
            u.set_ploc(&format!("p{i:02}"), Some(pulses));
        }
        u.set_ploc("blank", None);
        u.set_ploc("averyveryverylongname", Some(pulses));
    }
    let listed = r.robot.locations().unwrap();
    assert_eq!(listed.len(), c500c::PAGE_ROWS + 5, "{listed:?}");
    assert!(
        listed
            .iter()
            .all(|(n, l)| n.starts_with("#p") && l.to_array6().map(|v| v.round() as i64) == pulses)
    );
    let before = r.joints();
    let e = r.robot.move_to("#blank", false).unwrap_err();
    assert_eq!(
        e.code(),
        trol_proto::application::code::TROL_ERR_LOCATION,
        "{e}"
    );
    let e = r.robot.move_to("#nothere", false).unwrap_err();
    assert_eq!(
        e.code(),
        trol_proto::application::code::TROL_ERR_LOCATION,
        "{e}"
    );
    assert!(unmoved(&before, &r.joints()));
    assert!(!r.received().iter().any(|l| l.starts_with("move")));
    r.robot.move_to("#p07", false).unwrap();
    r.robot.finish().unwrap();
    assert!(unmoved(&target, &r.joints()), "{:?}", r.joints());
}

/// An approach to a precision point of the pendant's needs its joints, which need the
/// pulses per degree: unset in the profile, refused naming the keys and the step; a profile
/// whose pulses are not the arm's, refused at the first `w2` that shows it; the right ones,
/// refused for a joint not yet seen away from its zero, then the approach ends where TROL's
/// kinematics put it. Never a motion on a value TROL has not seen hold on the arm.
#[test]
fn an_approach_to_a_precision_point_trusts_the_pulses_only_as_far_as_seen() {
    use trol_a465::kinematics::Pose;
    let sw = c500c::variant("pulses-offset").unwrap();
    let target = [0.3, -0.2, 0.9, 0.1, 0.6, 0.2];
    let pulses = c500c::offset_pulses().pulses(&target.map(f64::to_degrees));
    let disp = [-30.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    let approach = |r: &mut Rig| r.robot.appro("#bin", &disp, false);
    let refused_unmoved = |r: &mut Rig, res: trol::Result<()>, says: &str| {
        let e = res.unwrap_err();
        assert_eq!(e.code().0, backend::UNSETTLED, "{e}");
        let why = r.said();
        assert!(why.contains(says), "{why}");
        assert!(!r.received().iter().any(|l| l.starts_with("move")));
        assert!(!r.moving());
    };

    let unset = Profile {
        pulses_per_degree: None,
        pulses_at_zero: None,
        ..c500c::matching_profile(&sw)
    };
    let mut r = rig(sw.clone(), true, unset);
    r.unit.lock().unwrap().set_ploc("bin", Some(pulses));
    let res = approach(&mut r);
    refused_unmoved(&mut r, res, "trol c500c step pulses");
    drop(r);

    // The A465 model's pulses, where this controller counts from elsewhere.
    let wrong = c500c::matching_profile(&Switches::default());
    let mut r = rig(sw.clone(), true, wrong);
    r.unit.lock().unwrap().set_ploc("bin", Some(pulses));
    let res = approach(&mut r);
    refused_unmoved(&mut r, res, "not this arm's");
    drop(r);

    let mut r = rig(sw.clone(), true, c500c::matching_profile(&sw));
    r.robot.speed(100).unwrap();
    r.unit.lock().unwrap().set_ploc("bin", Some(pulses));
    // The arm has stood at READY only: no joint's ratio seen yet.
    let res = approach(&mut r);
    refused_unmoved(&mut r, res, "move joint 1 by a degree");
    for j in 1..=6u16 {
        r.robot.joint(j, 0.05).unwrap();
        r.robot.finish().unwrap();
    }
    approach(&mut r)
        .and_then(|_| r.robot.finish())
        .unwrap_or_else(|e| panic!("Appro #bin: {e}"));
    let kin = trol_a465::kinematics::Kinematics::new([0.0; 6]);
    let want = Pose::from_xyzypr(kin.fk_xyzypr(&target))
        .then(&Pose::from_xyzypr(disp))
        .to_xyzypr();
    assert!(at(&r, &want), "at {:?}, not {want:?}", tcp(&r));
    // And to the point itself, by its pulses.
    r.robot.move_to("#bin", false).unwrap();
    r.robot.finish().unwrap();
    assert!(unmoved(&target, &r.joints()), "{:?}", r.joints());
}

/// Joint locations, motions to a precision point's values, names ash does not take and
/// Define have no ash form: each refused before anything is typed.
#[test]
fn what_ash_cannot_be_asked_safely_is_refused_unsent() {
    let sw = Switches::default();
    let mut r = rig(sw.clone(), true, c500c::matching_profile(&sw));
    r.robot.here("#p1", Tag::Prec).unwrap();
    let typed = r.received().len();
    let e = r.robot.here("spot", Tag::Joint).unwrap_err();
    assert_eq!(e.code().0, backend::UNSUPPORTED, "{e}");
    let e = r
        .robot
        .move_ii(&trol::Location::Prec(vec![0; 6]), false)
        .unwrap_err();
    assert_eq!(e.code().0, backend::UNSUPPORTED, "{e}");
    let e = r.robot.here("#1ab", Tag::Prec).unwrap_err();
    assert_eq!(e.code().0, trol_a465::arm::code::BAD_ARGUMENT, "{e}");
    let loc = trol::Location::Prec(vec![0; 6]);
    let e = r.robot.define("#p2", &loc).unwrap_err();
    assert_eq!(e.code().0, backend::UNSUPPORTED, "{e}");
    assert_eq!(r.received().len(), typed, "{:?}", &r.received()[typed..]);
}

/// A move to a point that ash says is done with the arm short of the point's pulses (held
/// by hand as it returns) is not success: the end is the arm read at the pulses read back.
#[test]
fn a_move_that_ends_short_of_the_point_is_not_success() {
    let sw = Switches {
        motion_return: Return::AtEnd,
        ..Switches::default()
    };
    let mut r = rig(sw.clone(), true, c500c::matching_profile(&sw));
    r.robot.here("#p1", Tag::Prec).unwrap();
    r.robot.joint(1, 0.3).unwrap();
    r.robot.finish().unwrap();
    // The arm is stopped short by hand as it returns: ash says done, w2 says elsewhere.
    r.robot.move_to("#p1", false).unwrap();
    r.unit
        .lock()
        .unwrap()
        .move_by_hand([0.15, 0.0, 0.0, 0.0, 0.0, 0.0]);
    let e = r.robot.finish().unwrap_err();
    assert_ne!(e.code().0, 0, "{e}");
}

/// While the jaws close, the arm does not move: a motion is BIOS_BUSY and sends nothing, and
/// TROLFinish waits for the jaws, after which the motion goes.
#[test]
fn the_arm_waits_for_the_jaws() {
    let sw = Switches::default();
    // Half real time: the jaws take 2.5 s to close, within JAWS_WITHIN.
    let mut r = rig_at(sw.clone(), true, c500c::matching_profile(&sw), 0.5);
    r.robot.close_gripper(60).unwrap();
    let before = r.joints();
    let e = r.robot.joint(1, 0.1).unwrap_err();
    assert_eq!(e.code().0, backend::BUSY, "{e}");
    assert!(
        r.unit.lock().unwrap().jaws_moving(),
        "the test outran the jaws"
    );
    assert!(unmoved(&before, &r.joints()));
    assert!(!r.received().iter().any(|l| l.starts_with("joint")));
    r.robot.finish().unwrap();
    assert!(r.unit.lock().unwrap().jaws() < 0.1);
    r.robot.joint(1, 0.01).unwrap();
    r.robot.finish().unwrap();
}

/// After the backup battery died: `backup` read every location variable as ash held it;
/// `restore` without writing says what it would do and types nothing but reads; with
/// writing, it sets each cartesian location (read back), creates the names of the precision
/// points untaught and lists them to teach again, saves, and never moves the arm.
#[test]
fn a_backup_restores_what_a_dead_battery_lost() {
    use trol_c500c::backend::Saved;
    let sw = Switches::default();
    let (host, ctl) = memory::pair(Some(57600));
    let unit = Arc::new(Mutex::new(C500c::new(sw.clone(), true, SCALE)));
    {
        let mut u = unit.lock().unwrap();
        u.set_ploc("pick1", Some([19101, 1, 2, 1, 1, -2]));
        u.set_ploc("blank", None);
        u.set_cloc(
            "test_001",
            Some([400.0, 0.0, 150.0, 0.0, std::f64::consts::FRAC_PI_2, 0.0]),
        );
    }
    let stop = Arc::new(AtomicBool::new(false));
    let thread = {
        let (unit, stop) = (unit.clone(), stop.clone());
        std::thread::spawn(move || {
            let _ = c500c::serve(Box::new(ctl), unit, stop);
        })
    };
    let mut b = C500cBackend::connect(Box::new(host), c500c::matching_profile(&sw), None).unwrap();
    let saved = b.backup().unwrap();
    assert_eq!(saved.vars.len(), 3, "{saved:?}");
    assert_eq!(
        saved.vars[1],
        ("pick1".into(), Saved::Ploc(Some([19101, 1, 2, 1, 1, -2])))
    );
    let text = saved.to_text();
    let file = trol_c500c::backend::Backup::parse(&text).unwrap();

    unit.lock().unwrap().forget_variables();
    let typed = unit.lock().unwrap().received().len();
    let plan = b.restore(&file, false).unwrap();
    assert_eq!(plan.written, ["test_001"]);
    assert_eq!(plan.created, ["blank", "pick1"]);
    assert_eq!(
        plan.to_teach,
        [("pick1".to_string(), [19101, 1, 2, 1, 1, -2])]
    );
    let reads = unit.lock().unwrap().received()[typed..].to_vec();
    assert!(reads.iter().all(|l| l.starts_with("list ")), "{reads:?}");
    assert!(unit.lock().unwrap().clocs().is_empty());

    let before = unit.lock().unwrap().joints();
    let done = b.restore(&file, true).unwrap();
    assert_eq!(done, plan);
    let clocs = unit.lock().unwrap().clocs();
    let want = match &file.vars[2].1 {
        Saved::Cloc(Some(w)) => *w,
        other => panic!("{other:?}"),
    };
    assert_eq!(clocs.len(), 1);
    assert!(clocs[0].2, "valid");
    let got = clocs[0].1.unwrap();
    assert!((0..6).all(|j| (got[j] - want[j]).abs() < 1e-3), "{got:?}");
    let plocs = unit.lock().unwrap().plocs();
    assert_eq!(plocs, [("blank".into(), None), ("pick1".into(), None)]);
    assert_eq!(unit.lock().unwrap().saved_plocs().len(), 2, "saved");
    assert!(unmoved(&before, &unit.lock().unwrap().joints()));
    let typed: Vec<String> = unit.lock().unwrap().received().to_vec();
    assert!(
        !typed
            .iter()
            .any(|l| ["move", "joint", "home", "ready", "here"]
                .iter()
                .any(|m| l.starts_with(m))),
        "{typed:?}"
    );
    // Again: the cartesian one is as the file has it; the precision point still to teach.
    let again = b.restore(&file, true).unwrap();
    assert!(
        again.written.is_empty() && again.created.is_empty(),
        "{again:?}"
    );
    assert_eq!(again.to_teach.len(), 1);
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    let _ = thread.join();
}

//! The rounds every variant's run goes through after its motions (`run_variant`): a
//! precision point taught and reached again, a cartesian round, the gripper.

use super::*;

/// Teach a precision point where the arm stands (an ash `ploc`), move away, move back to it
/// by name, list it, save, delete it: each right, or (where `print` shows a precision point
/// in a form TROL does not read) UNSURE with the arm where it was.
pub(crate) fn teach_and_return(r: &mut Rig, sw: &Switches, name: &str) {
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
pub(crate) fn tcp(r: &Rig) -> [f64; 6] {
    trol_a465::kinematics::Kinematics::new([0.0; 6]).fk_xyzypr(&r.joints())
}

/// The tool at `v` (mm, and 0.1 degree: the end rule's tolerance).
pub(crate) fn at(r: &Rig, v: &[f64; 6]) -> bool {
    use trol_a465::kinematics::Pose;
    let (mm, deg) = trol_c500c::world::gap(&Pose::from_xyzypr(tcp(r)), &Pose::from_xyzypr(*v));
    mm < 0.5 && deg < 0.1
}

/// Cartesian motions as the manual's pick example makes them, from READY: a joint-
/// interpolated move above the place, straight moves, a jog, a cartesian location taught
/// with Here and approached, departed from and moved to by name. Each ends with the tool
/// where TROL's kinematics put the end.
pub(crate) fn cart_round(r: &mut Rig, sw: &Switches, name: &str) {
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
    if sw.cloc_reversed {
        // A location's constant holds the angles in another order than the WORLD row: TROL
        // sees it (`here`, `print` of its own location) and writes none, nothing moved.
        // A wrist turned, and the tool away from pointing straight down (the WORLD row's
        // middle angle away from 90 degrees): where the arm stands tells the order.
        let res = r.robot.joint(4, 0.3);
        go(r, "Joint 4", res);
        let res = r.robot.joint(5, -0.6);
        go(r, "Joint 5", res);
        let before = r.joints();
        let sent = r.received().len();
        let turned = [420.0, -30.0, 200.0, 0.3, 1.3, 0.2];
        let e = r
            .robot
            .move_ii(&Location::Cart(turned.to_vec()), false)
            .unwrap_err();
        assert_eq!(e.code().0, backend::UNSETTLED, "{name}: {e}");
        assert!(r.said().contains("do not hold"), "{name}: {}", r.said());
        assert!(unmoved(&before, &r.joints()), "{name}");
        assert!(
            !r.received()[sent..]
                .iter()
                .any(|l| l.starts_with("set _") || l.starts_with("move")),
            "{name}: {:?}",
            &r.received()[sent..]
        );
        let e = r.robot.move_to("test_001", false).unwrap_err();
        assert_ne!(e.code().0, 0, "{name}");
        assert!(unmoved(&before, &r.joints()), "{name}");
        return;
    }
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
pub(crate) fn grip_round(r: &mut Rig, sw: &Switches, name: &str) {
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
            // The arm does not move while the jaws do: a motion then waits its turn, and
            // goes once they stand.
            let before = r.joints();
            let waited = r.unit.lock().unwrap().jaws_moving();
            if waited {
                r.robot.joint(1, 0.1).unwrap();
            }
            r.robot.finish().unwrap();
            assert!(jaws(r) < 0.1, "{name}: closed at {}", jaws(r));
            if waited {
                assert!(close(r.joints()[0], before[0] + 0.1), "{name}");
                r.robot.joint(1, -0.1).unwrap();
                r.robot.finish().unwrap();
            }
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

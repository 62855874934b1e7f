//! A motion called while the fingers still move waits for them, as a motion behind a motion
//! waits for it (issue 62, item 6): the manual's TROLClose then TROLDepart, with no
//! TROLFinish between, runs both on a C500, in-process as through the gateway.

mod common;

use std::time::Duration;

use common::start;
use trol_rapl::Profile;

#[test]
fn a_motion_behind_the_gripper_waits_for_the_fingers_and_runs() {
    let profile = Profile::simulator();
    let (port, sim) = start(profile.clone(), None);
    let mut robot = common::robot(port, profile);
    robot.speed(50).unwrap();
    robot
        .move_ii(&trol::Location::Cart(common::TEST_001.to_vec()), false)
        .unwrap();
    robot.finish().unwrap();
    // The 1998 program: Close, then Depart at once.
    let before = sim.planned_end();
    robot.close_gripper(60).unwrap();
    robot
        .depart(&[0.0, 0.0, -20.0, 0.0, 0.0, 0.0], false)
        .unwrap();
    robot.finish().unwrap();
    let after = sim.planned_end();
    assert!(
        (0..6).any(|j| (after[j] - before[j]).abs() > 1e-3),
        "the Depart ran: {before:?} -> {after:?}"
    );
    let ran = sim.ran();
    let close = ran.iter().position(|l| l.starts_with("CLOSE")).unwrap();
    assert!(
        ran[close..]
            .iter()
            .any(|l| l.starts_with("MOVE") || l.starts_with("MA")),
        "{ran:?}"
    );
    // Open, then a relative joint motion, then Grip, then another: each waits and runs.
    for (grip, deg) in [("open", 2.0f64), ("grip", -2.0)] {
        let from = sim.planned_end();
        match grip {
            "open" => robot.open_gripper(60).unwrap(),
            _ => robot.grip(30).unwrap(),
        }
        robot.joint(1, deg.to_radians()).unwrap();
        robot.finish().unwrap();
        let to = sim.planned_end();
        assert!(
            (to[0] - from[0] - deg.to_radians()).abs() < 1e-3,
            "{grip}: joint 1 {} -> {}",
            from[0],
            to[0]
        );
    }
    // And with no motion of TROL's after, a Finish waits for the fingers alone.
    robot.close_gripper(60).unwrap();
    robot.finish().unwrap();
    std::thread::sleep(Duration::from_millis(10));
    assert!(!sim.moving());
}

//! The simulated arm in time.

use trol_a465::arm::{Arm, ArmSettings, Target, Which, code, joint_profile};
use trol_a465::model::max_speeds;

fn homed_arm() -> Arm {
    Arm::new(ArmSettings {
        homed: true,
        ..ArmSettings::default()
    })
}

#[test]
fn motion_needs_home_first() {
    let mut arm = Arm::new(ArmSettings::default());
    assert_eq!(arm.joint(1, 0.5, 0.0), code::NOT_HOMED);
    assert_eq!(arm.commanded(10.0), [0.0; 6]);
    assert_eq!(arm.home(0, 0.0), code::OK);
    assert_eq!(arm.finish_status(0.1), code::MOVING);
    assert_eq!(arm.joint(1, 0.5, 0.1), code::OK);
}

#[test]
fn a_joint_move_takes_its_profile_time_and_joints_end_together() {
    let mut arm = homed_arm();
    let target = [1.0, 0.5, -0.5, 0.2, 0.3, 0.4];
    let (t, ta) = joint_profile(&[0.0; 6], &target, 100.0);
    // Joint 1 limits: 1 rad at pi rad/s plus the acceleration time.
    assert!((t - (1.0 / max_speeds()[0] + ta)).abs() < 1e-12);
    assert_eq!(arm.ma(target, 0.0), code::OK);
    let mid = arm.commanded(t / 2.0);
    // Every joint has done the same fraction of its way.
    let frac: Vec<f64> = (0..6).map(|i| mid[i] / target[i]).collect();
    assert!(frac.iter().all(|f| (f - 0.5).abs() < 1e-9), "{frac:?}");
    assert_eq!(arm.finish_status(t - 1e-3), code::MOVING);
    assert_eq!(arm.finish_status(t + 1e-6), code::OK);
    assert_eq!(arm.commanded(t + 1e-6), target);
    // Half the speed, twice the time.
    let (t2, _) = joint_profile(&[0.0; 6], &target, 50.0);
    assert!((t2 - 2.0 * t).abs() < 1e-9);
}

#[test]
fn halt_stops_where_the_arm_is() {
    let mut arm = homed_arm();
    arm.ma([1.0, 0.0, 0.0, 0.0, 0.0, 0.0], 0.0);
    let at = arm.commanded(0.2);
    arm.halt(0.2);
    assert_eq!(arm.commanded(5.0), at);
    assert_eq!(arm.finish_status(0.2), code::OK);
    assert!(at[0] > 0.0 && at[0] < 1.0);
}

#[test]
fn a_second_motion_waits_for_the_first() {
    let mut arm = homed_arm();
    arm.joint(1, 0.5, 0.0);
    let (t1, _) = joint_profile(&[0.0; 6], &[0.5, 0.0, 0.0, 0.0, 0.0, 0.0], 100.0);
    arm.joint(2, 0.3, 0.0);
    // Joint 2 has not moved while joint 1 runs.
    assert_eq!(arm.commanded(t1 * 0.9)[1], 0.0);
    let end = arm.done_at(0.0);
    assert_eq!(arm.commanded(end + 1e-9), [0.5, 0.3, 0.0, 0.0, 0.0, 0.0]);
}

#[test]
fn the_table_refusal_changes_nothing() {
    let mut arm = homed_arm();
    // Tool pointing down at x 330.2, z 558.8 (all in radians).
    let down = [0.0, 0.0, 90f64.to_radians(), 0.0, 90f64.to_radians(), 0.0];
    arm.ma(down, 0.0);
    let t = arm.done_at(0.0);
    let before = arm.commanded(t);
    // A 600 mm long tool reaches below the table there.
    arm.set_tool([600.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    assert_eq!(arm.joint(1, 0.1, t), code::BELOW_TABLE);
    assert_eq!(
        arm.depart([-10.0, 0.0, 0.0, 0.0, 0.0, 0.0], true, t),
        code::BELOW_TABLE
    );
    assert_eq!(arm.commanded(t + 10.0), before);
    assert_eq!(arm.finish_status(t), code::OK);
}

#[test]
fn straight_lines_stay_on_the_line() {
    let mut arm = homed_arm();
    arm.ma([0.2, 0.3, 1.2, 0.0, 0.2, 0.0], 0.0);
    let t0 = arm.done_at(0.0);
    let k = *arm.kinematics();
    let a = k.fk(&arm.commanded(t0));
    let to = [a.pos.x + 100.0, a.pos.y - 50.0, a.pos.z + 30.0];
    assert_eq!(arm.jog([100.0, -50.0, 30.0], true, t0), code::OK);
    let t1 = arm.done_at(t0);
    for i in 0..=100 {
        let t = t0 + (t1 - t0) * i as f64 / 100.0;
        let p = k.fk(&arm.commanded(t)).pos;
        let ab = glam::DVec3::from_array(to) - a.pos;
        let ap = p - a.pos;
        let off = (ap - ab * (ap.dot(ab) / ab.dot(ab))).length();
        assert!(off < 0.01, "{off} mm off the line at {i}%");
    }
    let end = k.fk(&arm.commanded(t1)).pos;
    assert!((end - glam::DVec3::from_array(to)).length() < 1e-6);
}

#[test]
fn the_gripper_takes_time_and_stops_at_an_object() {
    let mut arm = Arm::new(ArmSettings {
        object_width: Some(20.0),
        ..ArmSettings::default()
    });
    assert_eq!(arm.fingers(0.0), 50.0);
    arm.close(60.0, 0.0);
    assert_eq!(arm.finish_status(0.1), code::MOVING);
    assert!(arm.fingers(0.25) > 20.0);
    assert_eq!(arm.fingers(5.0), 20.0);
    assert_eq!(arm.finish_status(5.0), code::OK);
    arm.grip(30.0, 5.0);
    assert_eq!(arm.fingers(10.0), 30.0);
}

#[test]
fn precision_points_round_trip() {
    let mut arm = homed_arm();
    arm.ma([0.3, 0.2, 0.5, 0.1, 0.4, -0.2], 0.0);
    let t = arm.done_at(0.0);
    let q = arm.position(t, Which::Commanded);
    let counts = trol_a465::arm::counts_of(&q).map(|c| c as f64);
    arm.ready(t);
    let t2 = arm.done_at(t);
    assert_eq!(arm.move_to(Target::Prec(counts), false, t2), code::OK);
    let t3 = arm.done_at(t2);
    let back = arm.commanded(t3);
    let per_rad = trol_a465::model::counts_per_radian();
    for i in 0..6 {
        // Within half an encoder count.
        assert!(
            (back[i] - q[i]).abs() <= 0.5 / per_rad[i] + 1e-12,
            "{back:?} {q:?}"
        );
    }
}

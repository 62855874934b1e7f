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

/// What a refusal must leave alone: the planned end, when the motions end, and where the arm
/// is commanded to be now and later.
fn snapshot(arm: &mut Arm, t: f64) -> ([f64; 6], f64, [f64; 6], [f64; 6], i16) {
    (
        arm.planned_end(),
        arm.done_at(t),
        arm.commanded(t),
        arm.commanded(t + 100.0),
        arm.finish_status(t),
    )
}

const DOWN: f64 = std::f64::consts::FRAC_PI_2;

/// Move (joint-interpolated) to a cartesian location and wait for it.
fn settle_at(arm: &mut Arm, loc: [f64; 6], t: f64) -> f64 {
    assert_eq!(
        arm.move_to(Target::Cart(loc), false, t),
        code::OK,
        "{loc:?}"
    );
    arm.done_at(t)
}

#[test]
fn a_turn_in_place_that_swings_the_wrist_out_of_reach_is_refused_and_changes_nothing() {
    let mut arm = homed_arm();
    // The tool tip 674.6 mm from the shoulder, beyond the wrist's 635 mm reach, so the tool
    // must point away from the arm. Turning it in place (a straight move of length 0 with
    // the orientation interpolated) swings the wrist centre around the tip, out of reach,
    // although both ends can be reached.
    let from = [617.7, 0.0, 601.4, 0.0, 0.5, -3.1];
    let to = [617.7, 0.0, 601.4, -1.0, -0.4, 1.2];
    let t = settle_at(&mut arm, to, 0.0);
    let t = settle_at(&mut arm, from, t);
    let before = snapshot(&mut arm, t);
    assert_eq!(arm.move_to(Target::Cart(to), true, t), code::OUT_OF_REACH);
    assert_eq!(snapshot(&mut arm, t), before);
    assert_eq!(arm.move_to(Target::Cart(to), false, t), code::OK);
}

#[test]
fn a_line_past_a_joint_limit_is_refused_although_both_ends_are_within_limits() {
    let mut arm = homed_arm();
    // J1 at 170°: a line in -y turns J1 through 180°, beyond its ±175° limit, while its end
    // (J1 = -170° in the same configuration) lies within the limits.
    let q = [170f64.to_radians(), 0.6, 0.8, 0.0, 0.5, 0.0];
    assert_eq!(arm.ma(q, 0.0), code::OK);
    let t = arm.done_at(0.0);
    let wrist_y = arm.kinematics().fk(&q).pos.y;
    let before = snapshot(&mut arm, t);
    assert_eq!(
        arm.jog([0.0, -2.0 * wrist_y, 0.0], true, t),
        code::JOINT_LIMIT
    );
    assert_eq!(snapshot(&mut arm, t), before);
    // A target beyond a limit itself, by joints.
    assert_eq!(arm.joint(1, 0.2, t), code::JOINT_LIMIT);
    assert_eq!(arm.joint(5, -3.0, t), code::JOINT_LIMIT);
    assert_eq!(snapshot(&mut arm, t), before);
}

#[test]
fn a_line_across_the_base_axis_is_a_singular_path_and_changes_nothing() {
    let mut arm = homed_arm();
    // Tool pointing up, the wrist passing 5 mm from the base axis: J1 would swing half a
    // turn in an instant.
    let t = settle_at(&mut arm, [5.0, 100.0, 950.0, 0.0, -DOWN, 0.0], 0.0);
    let before = snapshot(&mut arm, t);
    assert_eq!(arm.jog([0.0, -200.0, 0.0], true, t), code::SINGULAR_PATH);
    assert_eq!(snapshot(&mut arm, t), before);
}

#[test]
fn an_unreachable_target_is_refused_and_changes_nothing() {
    let mut arm = homed_arm();
    let t = settle_at(&mut arm, [400.0, 0.0, 300.0, 0.0, DOWN, 0.0], 0.0);
    let before = snapshot(&mut arm, t);
    for straight in [false, true] {
        assert_eq!(
            arm.move_to(
                Target::Cart([900.0, 0.0, 300.0, 0.0, DOWN, 0.0]),
                straight,
                t
            ),
            code::OUT_OF_REACH
        );
        assert_eq!(
            arm.appro(
                Target::Cart([400.0, 0.0, 300.0, 0.0, DOWN, 0.0]),
                [-600.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                straight,
                t
            ),
            code::OUT_OF_REACH,
            "600 mm back along the tool, pointing down: 900 mm up"
        );
        assert_eq!(arm.jog([0.0, 0.0, -400.0], straight, t), code::BELOW_TABLE);
    }
    assert_eq!(snapshot(&mut arm, t), before);
}

#[test]
fn bad_axes_and_values_are_refused() {
    let mut arm = homed_arm();
    let before = snapshot(&mut arm, 0.0);
    assert_eq!(arm.home(7, 0.0), code::BAD_ARGUMENT);
    assert_eq!(arm.joint(0, 0.1, 0.0), code::BAD_ARGUMENT);
    assert_eq!(arm.joint(7, 0.1, 0.0), code::BAD_ARGUMENT);
    assert_eq!(arm.joint(1, f64::NAN, 0.0), code::BAD_ARGUMENT);
    assert_eq!(
        arm.ma([0.0, f64::INFINITY, 0.0, 0.0, 0.0, 0.0], 0.0),
        code::BAD_ARGUMENT
    );
    for straight in [false, true] {
        let nan = [400.0, f64::NAN, 300.0, 0.0, DOWN, 0.0];
        assert_eq!(
            arm.move_to(Target::Cart(nan), straight, 0.0),
            code::BAD_ARGUMENT
        );
        assert_eq!(
            arm.jog([0.0, 0.0, f64::INFINITY], straight, 0.0),
            code::BAD_ARGUMENT
        );
    }
    assert_eq!(snapshot(&mut arm, 0.0), before);
}

#[test]
fn the_actual_position_lags_while_moving_and_settles_when_stopped() {
    use trol_a465::arm::SERVO_LAG;
    use trol_a465::model::counts_per_radian;
    let mut arm = homed_arm();
    let target = [1.0, 0.4, -0.3, 0.2, 0.3, 0.4];
    arm.ma(target, 0.0);
    let end = arm.done_at(0.0);
    let per_rad = counts_per_radian();
    let t = end / 2.0;
    let commanded = arm.position(t, Which::Commanded);
    let actual = arm.position(t, Which::Actual);
    // Mid-move, joint 1 (the longest way) is behind the command by about speed × lag.
    let behind = commanded[0] - actual[0];
    assert!(behind > 0.0, "actual {actual:?} commanded {commanded:?}");
    let expected = commanded[0] - arm.commanded(t - SERVO_LAG)[0];
    assert!(
        (behind - expected).abs() <= 0.5 / per_rad[0] + 1e-12,
        "{behind} vs {expected}"
    );
    // Stopped: the encoders read the commanded position to within half a count.
    let after = end + SERVO_LAG + 1e-6;
    let a = arm.position(after, Which::Actual);
    for i in 0..6 {
        assert!(
            (a[i] - target[i]).abs() <= 0.5 / per_rad[i] + 1e-12,
            "{a:?}"
        );
    }
    assert_eq!(arm.position(after, Which::Commanded), target);
}

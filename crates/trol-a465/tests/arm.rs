//! The simulated arm in time.

use trol_a465::arm::{Arm, ArmSettings, MOTION_QUEUE, Target, Which, code, joint_limits};

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
    // Axes count as homed when homing ends, not when it is accepted; a motion sent during
    // the homing queues behind it (the controller answers Home at once, and a program that
    // does not wait for it still moves only a homed arm).
    let done = arm.done_at(0.1);
    assert!(done >= 12.0, "six axes take at least 2 s each: {done}");
    assert_eq!(arm.homed(), [false; 6]);
    assert_eq!(arm.joint(1, 0.5, 0.1), code::OK);
    assert_eq!(
        arm.commanded(done - 0.01)[0],
        0.0,
        "it waits for the homing"
    );
    let end = arm.done_at(done);
    assert!(end > done);
    assert_eq!(arm.homed(), [true; 6]);
    assert!((arm.commanded(end + 1.0)[0] - 0.5).abs() < 1e-12);
}

#[test]
fn a_halt_during_homing_leaves_the_axes_unhomed() {
    let mut arm = Arm::new(ArmSettings::default());
    arm.ma([0.3, 0.0, 0.0, 0.0, 0.0, 0.0], 0.0);
    assert_eq!(arm.home(1, 0.0), code::OK);
    assert_eq!(arm.halt(1.0), code::OK);
    let stopped = arm.done_at(1.0);
    assert_eq!(arm.finish_status(stopped + 1e-9), code::OK);
    assert_eq!(arm.homed(), [false; 6]);
    assert_eq!(arm.joint(1, 0.1, stopped + 1.0), code::NOT_HOMED);
}

/// The power lost during a Home (an e-stop; issue 62, item 1): the arm stops where it is,
/// the homing's axes stay unhomed (on an arm homed before too), and the Finish after it says
/// BIOS_ARM_POWER; with the power off every motion, Home and gripper motion is refused and
/// nothing moves; with it back the Home runs to its end, and the Finish is success.
#[test]
fn a_power_loss_during_home_is_the_power_s_failure() {
    let mut arm = homed_arm();
    arm.ma([0.3, 0.2, 0.4, 0.0, 0.0, 0.0], 0.0);
    let t0 = arm.done_at(0.0);
    assert_eq!(arm.home(0, t0), code::OK);
    arm.power_off(t0 + 1.0);
    assert!(!arm.has_power());
    let stopped = arm.done_at(t0 + 1.0);
    let at = arm.commanded(stopped);
    assert_ne!(at, [0.0; 6], "stopped on its way");
    assert_eq!(arm.finish_status(stopped + 1e-9), code::ARM_POWER);
    assert!(!arm.homed()[1]);
    let later = stopped + 1.0;
    assert_eq!(arm.home(0, later), code::ARM_POWER);
    assert_eq!(arm.ma([0.0; 6], later), code::ARM_POWER);
    assert_eq!(arm.close(10.0, later), code::ARM_POWER);
    assert_eq!(arm.commanded(later + 10.0), at, "nothing moved");
    arm.power_on();
    // The next call works: a gripper motion, then the Home.
    assert_eq!(arm.open(50.0, later), code::OK);
    assert_eq!(arm.finish_status(later + 5.0), code::OK);
    assert_eq!(arm.home(0, later), code::OK);
    let end = arm.done_at(later);
    assert_eq!(arm.finish_status(end + 1e-9), code::OK);
    assert_eq!(arm.homed(), [true; 6]);
    assert_eq!(arm.commanded(end), [0.0; 6]);
}

/// Home(0) homes in CTU's groups, one after the other (issue 37, item 6): joint 2, then
/// joints 1 and 3, then 4, 5 and 6, each group's axes homed when its motion ends; halted
/// in the second group, joint 2 stays homed and the rest do not.
#[test]
fn home_all_goes_group_by_group() {
    use trol_a465::arm::HOME_GROUPS;
    assert_eq!(HOME_GROUPS, &[&[1][..], &[0, 2], &[3, 4, 5]]);
    let mut arm = Arm::new(ArmSettings::default());
    assert_eq!(arm.home(0, 0.0), code::OK);
    // Each group takes at least 2 s per axis: 2 s, then 4 s, then 6 s.
    let _ = arm.finish_status(2.05);
    assert_eq!(arm.homed(), [false, true, false, false, false, false]);
    let _ = arm.finish_status(6.05);
    assert_eq!(arm.homed(), [true, true, true, false, false, false]);
    let _ = arm.finish_status(12.05);
    assert_eq!(arm.homed(), [true; 6]);

    let mut arm = Arm::new(ArmSettings::default());
    arm.home(0, 0.0);
    assert_eq!(arm.halt(3.0), code::OK);
    let stopped = arm.done_at(3.0);
    assert_eq!(arm.finish_status(stopped + 1e-9), code::OK);
    assert_eq!(arm.homed(), [false, true, false, false, false, false]);
    assert_eq!(arm.joint(2, 0.1, stopped + 1.0), code::NOT_HOMED);
}

/// A halted homing stands as soon as the arm can brake: at the home pose (nothing moves,
/// the homing only takes its time) at once, elsewhere within the A465's 0.4 s. At the home
/// pose it took half the group's time (3 s in the last group), so Ctrl-C during `home 0`
/// after `trol sim` came back seconds later (issue 44, item 5).
#[test]
fn a_halted_homing_stands_at_once() {
    for from in [[0.0; 6], [0.3, -0.4, 0.6, 1.0, -0.8, 2.0]] {
        for halt in [1.0, 3.0, 5.0, 8.0, 9.0, 11.5] {
            // There, and unhomed (as after a power cycle).
            let mut arm = homed_arm();
            assert_eq!(arm.ma(from, 0.0), code::OK);
            let t0 = arm.done_at(0.0);
            assert_eq!(arm.commanded(t0), from);
            arm.set_homed([false; 6]);
            assert_eq!(arm.home(0, t0), code::OK);
            let halt = t0 + halt;
            assert_eq!(arm.halt(halt), code::OK);
            let stopped = arm.done_at(halt);
            assert!(
                stopped - halt <= 0.4,
                "from {from:?}, halted at {halt} s: stands {:.3} s later",
                stopped - halt
            );
            if from == [0.0; 6] {
                assert!(
                    stopped - halt < 0.05,
                    "at the home pose: {}",
                    stopped - halt
                );
            }
            assert_eq!(arm.finish_status(stopped + 1e-9), code::OK);
        }
    }
}

#[test]
fn a_joint_move_ends_together_and_the_slowest_joint_sets_the_time() {
    let mut arm = homed_arm();
    let target = [1.0, 0.5, -0.5, 0.2, 0.3, 0.4];
    assert_eq!(arm.ma(target, 0.0), code::OK);
    let t = arm.done_at(0.0);
    // Joint 1 has the longest way for its speed: at least 1 rad at its full speed.
    let (v, _) = joint_limits(100.0);
    assert!(t > 1.0 / v[0], "{t}");
    for k in 1..10 {
        let q = arm.commanded(t * k as f64 / 10.0);
        // Every joint has done the same fraction of its way.
        let frac: Vec<f64> = (0..6).map(|i| q[i] / target[i]).collect();
        assert!(frac.iter().all(|f| (f - frac[0]).abs() < 1e-9), "{frac:?}");
    }
    assert_eq!(arm.finish_status(t - 1e-3), code::MOVING);
    assert_eq!(arm.finish_status(t + 1e-6), code::OK);
    assert_eq!(arm.commanded(t + 1e-6), target);
    // Half the speed takes longer; above 100 % no faster than at 100 %.
    let mut slow = homed_arm();
    slow.set_speed(50.0);
    slow.ma(target, 0.0);
    assert!(slow.done_at(0.0) > 1.5 * t);
    let mut fast = homed_arm();
    fast.set_speed(150.0);
    fast.ma(target, 0.0);
    assert!((fast.done_at(0.0) - t).abs() < 1e-12);
}

#[test]
fn halt_brakes_along_the_path_without_a_jump_in_the_actual_position() {
    use trol_a465::arm::DITHER_COUNTS;
    use trol_a465::model::counts_per_radian;
    // The actual position across the halt, sampled every millisecond: no step larger than
    // the joint's speed allows, plus the dither.
    let mut arm = homed_arm();
    arm.ma([1.0, 0.5, 0.0, 0.0, 0.0, 0.0], 0.0);
    let mut probe = arm.clone();
    probe.halt(0.3);
    let (v, _) = joint_limits(100.0);
    let dither = 2.0 * DITHER_COUNTS as f64 / counts_per_radian()[0];
    let mut prev = probe.clone().position(0.25, Which::Actual);
    for k in 1..400 {
        let t = 0.25 + k as f64 * 1e-3;
        let q = probe.clone().position(t, Which::Actual);
        assert!(
            (q[0] - prev[0]).abs() <= v[0] * 1e-3 * 1.0001 + dither,
            "a jump of {} rad at {t}",
            q[0] - prev[0]
        );
        prev = q;
    }
    // The commanded position.
    let at = arm.commanded(0.3);
    let before = arm.commanded(0.3 - 1e-4);
    arm.halt(0.3);
    // No jump: the commanded position moves on smoothly from where it was.
    let (v, a) = joint_limits(100.0);
    assert!((arm.commanded(0.3 + 1e-4)[0] - at[0]).abs() <= v[0] * 1e-4 * 1.0001);
    let stop = arm.done_at(0.3);
    assert!(stop > 0.3, "it brakes, it does not stop dead");
    let rest = arm.commanded(stop + 1.0);
    // Within the braking distance the limits allow, on the same joint-space line.
    let speed = (at[0] - before[0]) / 1e-4;
    assert!(rest[0] - at[0] <= speed * speed / (2.0 * a[0]) * 1.01 + 1e-9);
    assert!(speed <= v[0] * 1.0001);
    assert!((rest[1] / rest[0] - 0.5).abs() < 1e-9, "{rest:?}");
    assert_eq!(arm.finish_status(stop + 1e-6), code::OK);
}

#[test]
fn a_second_motion_waits_for_the_first() {
    let mut arm = homed_arm();
    arm.joint(1, 0.5, 0.0);
    let t1 = arm.done_at(0.0);
    arm.joint(2, 0.3, 0.0);
    // Joint 2 has not moved while joint 1 runs.
    assert_eq!(arm.commanded(t1 * 0.9)[1], 0.0);
    let end = arm.done_at(0.0);
    assert!(end > t1);
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
    // A 600 mm long tool would reach below the table there: refused, nothing changes.
    assert_eq!(
        arm.set_tool([600.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
        code::BELOW_TABLE
    );
    // A 550 mm one ends 8.8 mm above it; 20 mm further down along the tool is below.
    assert_eq!(arm.set_tool([550.0, 0.0, 0.0, 0.0, 0.0, 0.0]), code::OK);
    assert_eq!(
        arm.depart([20.0, 0.0, 0.0, 0.0, 0.0, 0.0], true, t),
        code::BELOW_TABLE
    );
    assert_eq!(
        arm.depart([20.0, 0.0, 0.0, 0.0, 0.0, 0.0], false, t),
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

/// Distance of `p` from the segment a-b, mm.
fn off_segment(p: glam::DVec3, a: glam::DVec3, b: glam::DVec3) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
    (p - (a + ab * t)).length()
}

/// From READY (stretched, the wrist centre on the base axis, J5 = 0: singular three ways),
/// a straight line leaves (issue 42; it was refused with SINGULAR_PATH): the joints the pose
/// leaves free (J1, J4, J6) first turn, the tool standing still, to where the line leaves,
/// then the tool follows the line, the elbow and shoulder easing out of the stretch.
#[test]
fn a_line_leaves_ready_the_free_joints_turning_first_with_the_tool_still() {
    let mut arm = homed_arm();
    let kin = *arm.kinematics();
    let from = kin.fk(&[0.0; 6]).pos;
    let to = [560.0, 100.0, 450.0, 0.0, DOWN, 0.0];
    assert_eq!(arm.move_to(Target::Cart(to), true, 0.0), code::OK);
    let end = arm.done_at(0.0);
    let (line_start, line_end, _) = arm.last_motion().unwrap();
    assert!(line_start > 0.0, "a turn of the free joints comes first");
    // The turn: the tool stands still while J1, J4 and J6 turn.
    let q_turned = arm.commanded(line_start);
    assert!(
        q_turned[0].abs() > 0.1,
        "J1 turned toward the target: {q_turned:?}"
    );
    let n = 200;
    for i in 0..=n {
        let t = line_start * i as f64 / n as f64;
        let p = kin.fk(&arm.commanded(t)).pos;
        assert!(
            (p - from).length() < 1e-6,
            "the tool moved during the turn at {t}: {p}"
        );
    }
    // The line: on it throughout, within the limits.
    let target = trol_a465::Pose::from_xyzypr(to).pos;
    let lim = trol_a465::model::limits();
    for i in 0..=n {
        let t = line_start + (line_end - line_start) * i as f64 / n as f64;
        let q = arm.commanded(t);
        assert!(q.iter().zip(lim).all(|(v, l)| v.abs() <= l + 1e-9), "{q:?}");
        let off = off_segment(kin.fk(&q).pos, from, target);
        assert!(off < 0.02, "{off} mm off the line at {t}");
    }
    assert!((kin.fk(&arm.commanded(end)).pos - target).length() < 1e-3);
}

/// At J5 = 0 with the elbow bent (issue 42's own case): a 50 mm sideways straight jog from
/// MA(0, 30 deg, 60 deg, 0, 0, 0) was refused; J4 now turns first, J6 against it.
#[test]
fn a_sideways_jog_at_j5_zero_turns_j4_first_and_goes() {
    let mut arm = homed_arm();
    let q = [0.0, 30f64.to_radians(), 60f64.to_radians(), 0.0, 0.0, 0.0];
    assert_eq!(arm.ma(q, 0.0), code::OK);
    let t = arm.done_at(0.0);
    assert_eq!(arm.jog([0.0, 50.0, 0.0], true, t), code::OK);
    let end = arm.done_at(t);
    let (start, _, _) = arm.last_motion().unwrap();
    let turned = arm.commanded(start);
    assert!((turned[3] - q[3]).abs() > 0.5, "J4 turned: {turned:?}");
    assert!(
        ((turned[3] + turned[5]) - (q[3] + q[5])).abs() < 1e-9,
        "J6 turned against it"
    );
    let kin = *arm.kinematics();
    let moved = kin.fk(&arm.commanded(end)).pos - kin.fk(&q).pos;
    assert!(
        (moved - glam::DVec3::new(0.0, 50.0, 0.0)).length() < 1e-3,
        "{moved}"
    );
}

/// A line no configuration can follow is refused with the joint that stops it, where on
/// the line, and what to do (for the controller's log); nothing moves. From READY straight
/// down to the table near the base the line passes so near the shoulder that the elbow
/// would fold past its 110 deg.
#[test]
fn a_line_no_arm_can_follow_is_refused_with_where_and_what_to_do() {
    let mut arm = homed_arm();
    let before = snapshot(&mut arm, 0.0);
    let to = [300.0, -200.0, 60.0, 0.5, DOWN, 0.0];
    assert_eq!(arm.move_to(Target::Cart(to), true, 0.0), code::JOINT_LIMIT);
    let why = arm.take_refusal().expect("a reason");
    assert!(
        why.contains("the elbow (J3) would pass its ±110 deg"),
        "{why}"
    );
    assert!(why.contains("% of the straight line"), "{why}");
    assert!(why.contains("move there in joints"), "{why}");
    assert_eq!(arm.take_refusal(), None, "said once");
    assert_eq!(snapshot(&mut arm, 0.0), before);
    // Joint-interpolated, it goes.
    assert_eq!(arm.move_to(Target::Cart(to), false, 0.0), code::OK);
}

#[test]
fn a_line_near_the_base_axis_is_followed_slowly_within_j1s_speed() {
    let mut arm = homed_arm();
    // 5 mm from the base axis J1 swings half a turn over a few millimetres: the line is
    // continuous, so the arm follows it, as slowly as J1's speed requires.
    let t = settle_at(&mut arm, [5.0, 100.0, 950.0, 0.0, -DOWN, 0.0], 0.0);
    assert_eq!(arm.jog([0.0, -200.0, 0.0], true, t), code::OK);
    let end = arm.done_at(t);
    let (v, _) = joint_limits(100.0);
    let dt = 1e-3;
    let mut prev = arm.commanded(t);
    let mut turned: f64 = 0.0;
    let mut now = t;
    while now < end {
        now += dt;
        let q = arm.commanded(now);
        assert!(
            (q[0] - prev[0]).abs() <= v[0] * dt * 1.001,
            "J1 too fast at {now}"
        );
        turned += (q[0] - prev[0]).abs();
        prev = q;
    }
    assert!(turned > 2.5, "J1 turned {turned} rad");
    assert!(
        end - t > 1.0,
        "half a turn of J1 takes over a second: {}",
        end - t
    );
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
fn the_actual_position_lags_while_moving_and_dithers_at_rest() {
    use trol_a465::arm::{DITHER_COUNTS, SERVO_LAG};
    use trol_a465::model::counts_per_radian;
    let mut arm = homed_arm();
    let target = [1.0, 0.4, -0.3, 0.2, 0.3, 0.4];
    arm.ma(target, 0.0);
    let end = arm.done_at(0.0);
    let per_rad = counts_per_radian();
    let slack = |i: usize| (DITHER_COUNTS as f64 + 0.5) / per_rad[i] + 1e-12;
    let t = end / 2.0;
    let commanded = arm.position(t, Which::Commanded);
    let actual = arm.position(t, Which::Actual);
    // Mid-move, joint 1 (the longest way) is behind the command by about speed × lag.
    let behind = commanded[0] - actual[0];
    let expected = commanded[0] - arm.commanded(t - SERVO_LAG)[0];
    assert!(expected > 10.0 * slack(0), "{expected}");
    assert!(
        (behind - expected).abs() <= slack(0),
        "{behind} vs {expected}"
    );
    // At rest: close to the command, within the dither, and never equal to it.
    for k in 0..50 {
        let after = end + SERVO_LAG + 0.1 + k as f64 * 0.0123;
        let a = arm.position(after, Which::Actual);
        for i in 0..6 {
            assert!((a[i] - target[i]).abs() <= slack(i), "{a:?}");
            assert!(a[i] != target[i], "joint {} equals its command", i + 1);
        }
    }
    assert_eq!(arm.position(end + 1.0, Which::Commanded), target);
}

/// Right after the commanded motion ended, the actual position is still a servo lag behind
/// whatever was asked before: it used to snap to the end as soon as the commanded position
/// had been read past it.
#[test]
fn the_actual_position_reaches_the_end_a_servo_lag_after_the_command() {
    use trol_a465::arm::{DITHER_COUNTS, SERVO_LAG};
    use trol_a465::model::counts_per_radian;
    let mut arm = homed_arm();
    let target = [1.0, 0.4, -0.3, 0.2, 0.3, 0.4];
    arm.ma(target, 0.0);
    // The command ends a lag before the motion counts as done (the actual position there).
    let end = arm.done_at(0.0) - SERVO_LAG;
    let per_rad = counts_per_radian();
    let t = end + SERVO_LAG / 2.0;
    assert!(
        arm.is_moving(t),
        "not done before the actual position arrived"
    );
    // The command has ended, and was read so.
    assert_eq!(arm.position(t, Which::Commanded), target);
    let actual = arm.position(t, Which::Actual);
    let lagging = arm.planned_at(t - SERVO_LAG);
    for i in 0..6 {
        let slack = (DITHER_COUNTS as f64 + 0.5) / per_rad[i] + 1e-12;
        assert!(
            (actual[i] - lagging[i]).abs() <= slack,
            "{actual:?} vs {lagging:?}"
        );
    }
    // Half a lag before its end, joint 1 (decelerating at 720 °/s²) is still more than the
    // dither away from it: a snap would show.
    let slack0 = (DITHER_COUNTS as f64 + 0.5) / per_rad[0];
    assert!(
        (lagging[0] - target[0]).abs() > 2.0 * slack0,
        "{} rad from the end, dither {slack0}",
        (lagging[0] - target[0]).abs()
    );
}

#[test]
fn the_pick_example_carries_the_object_and_open_drops_it_on_the_table() {
    use trol_a465::arm::{WorldObject, parse_objects};
    // The cube's base at z 135 (on a table there): its centre, where the fingers take it,
    // is test_001's 150.
    let objects = parse_objects("; name x y z width\ncube 400 0 135 30\nfar 0 400 0 20\n").unwrap();
    assert_eq!(objects[0].name, "cube");
    let mut arm = Arm::new(ArmSettings {
        homed: true,
        objects,
        table_z: 135.0,
        ..ArmSettings::default()
    });
    let test_001 = [400.0, 0.0, 150.0, 0.0, DOWN, 0.0];
    // The manual's pick example (TROLAppro): approach, move onto it, close, depart.
    let mut t = settle_at(&mut arm, [400.0, 0.0, 300.0, 0.0, DOWN, 0.0], 0.0);
    let appro = [400.0, 0.0, 240.0, 0.0, DOWN, 0.0];
    assert_eq!(arm.move_to(Target::Cart(appro), true, t), code::OK);
    assert_eq!(arm.move_to(Target::Cart(test_001), true, t), code::OK);
    t = arm.done_at(t);
    assert_eq!(arm.close(60.0, t), code::OK);
    t = arm.done_at(t);
    assert_eq!(arm.held(), Some("cube"));
    assert_eq!(
        arm.fingers(t),
        30.0,
        "the fingers stop at the object's width"
    );
    assert_eq!(
        arm.depart([-90.0, 0.0, 0.0, 0.0, 0.0, 0.0], true, t),
        code::OK
    );
    t = arm.done_at(t);
    // Its centre is at the tool centre point, so its base half a width below.
    let at = &arm.objects(t)[0];
    for (got, want) in at.pos.iter().zip([400.0, 0.0, 225.0]) {
        assert!((got - want).abs() < 1e-6, "{at:?}");
    }
    // A held object's underside may not go below the table either: the tool centre point
    // 10 mm above the table would put the cube 5 mm into it.
    assert_eq!(
        arm.move_to(Target::Cart([400.0, 0.0, 145.0, 0.0, DOWN, 0.0]), false, t),
        code::BELOW_TABLE
    );
    assert_eq!(
        arm.move_to(Target::Cart([400.0, 0.0, 145.0, 0.0, DOWN, 0.0]), true, t),
        code::BELOW_TABLE
    );
    // Open: it drops onto the table below the tool; the other object never moved.
    assert_eq!(arm.open(50.0, t), code::OK);
    assert_eq!(arm.held(), None);
    let objects: Vec<WorldObject> = arm.objects(t + 1.0);
    for (got, want) in objects[0].pos.iter().zip([400.0, 0.0, 135.0]) {
        assert!((got - want).abs() < 1e-9, "{:?}", objects[0]);
    }
    assert_eq!(objects[1].pos, [0.0, 400.0, 0.0]);
    // Closing where there is nothing takes nothing.
    assert_eq!(arm.close(60.0, t + 2.0), code::OK);
    assert_eq!(arm.held(), None);
    assert_eq!(arm.fingers(t + 10.0), 0.0);
    // Bad object files say where.
    for bad in [
        "cube 1 2 3",
        "cube 1 2 3 x",
        "cube 1 2 3 60",
        "cube 1 2 3 0",
    ] {
        assert!(
            parse_objects(bad).unwrap_err().starts_with("line 1:"),
            "{bad}"
        );
    }
}

/// Fingers that are narrower than an object at the tool centre point are not around it and
/// cannot close through it: Close and Grip are refused with GRIPPER_BLOCKED and nothing
/// moves; opened wider than the object first, they take it.
#[test]
fn the_fingers_do_not_close_through_an_object_wider_than_their_opening() {
    use trol_a465::arm::parse_objects;
    let mut arm = Arm::new(ArmSettings {
        homed: true,
        objects: parse_objects("cube 400 0 135 30\n").unwrap(),
        table_z: 135.0,
        ..ArmSettings::default()
    });
    // Half closed (20 mm), then onto the cube's centre.
    assert_eq!(arm.grip(20.0, 0.0), code::OK);
    let mut t = settle_at(&mut arm, [400.0, 0.0, 150.0, 0.0, DOWN, 0.0], 0.0);
    assert_eq!(arm.fingers(t), 20.0);
    assert_eq!(arm.close(60.0, t), code::GRIPPER_BLOCKED);
    assert_eq!(arm.grip(5.0, t), code::GRIPPER_BLOCKED);
    assert_eq!(arm.fingers(t + 5.0), 20.0, "nothing moved");
    assert_eq!(arm.held(), None);
    // Opening is never blocked; wider than the cube, closing takes it.
    assert_eq!(arm.grip(40.0, t), code::OK);
    t = arm.done_at(t);
    assert_eq!(arm.close(60.0, t), code::OK);
    t = arm.done_at(t);
    assert_eq!(arm.held(), Some("cube"));
    assert_eq!(arm.fingers(t), 30.0);
}

/// The motion queue is bounded: a motion beyond it is refused and changes nothing; once the
/// arm has worked some off, motions are accepted again.
#[test]
fn a_full_motion_queue_refuses_the_next_motion_and_changes_nothing() {
    let mut arm = homed_arm();
    for _ in 0..MOTION_QUEUE {
        assert_eq!(arm.joint(1, 0.01, 0.0), code::OK);
    }
    let planned = arm.planned_end();
    let done = arm.done_at(0.0);
    assert_eq!(arm.joint(1, 0.01, 0.0), code::QUEUE_FULL);
    assert_eq!(arm.home(0, 0.0), code::QUEUE_FULL);
    assert_eq!(arm.planned_end(), planned);
    assert_eq!(arm.done_at(0.0), done);
    // All done: the queue is empty again.
    assert_eq!(arm.joint(1, 0.01, done), code::OK);
    assert!((arm.planned_end()[0] - (MOTION_QUEUE as f64 + 1.0) * 0.01).abs() < 1e-9);
}

#[test]
fn a_joint_at_its_limit_sent_as_a_c_float_is_the_limit() {
    // 175, 90, 110, 180, 105, 180 degrees, as the manual's SLocData carries them (float):
    // each rounds up to 1.2e-7 rad past its limit. They mean the limit, and the arm ends
    // exactly there, never beyond.
    let limits = trol_a465::model::LIMITS_RAD;
    let as_f32: [f64; 6] = std::array::from_fn(|i| f64::from(limits[i] as f32));
    assert!(
        (0..6).any(|i| as_f32[i] > limits[i]),
        "the test needs a value past a limit"
    );
    let mut arm = homed_arm();
    let at_the_limit = |end: [f64; 6], sign: f64| {
        (0..6).all(|i| end[i] * sign <= limits[i] && (end[i] * sign - limits[i]).abs() < 1e-6)
    };
    assert_eq!(arm.ma(as_f32, 0.0), code::OK);
    assert!(
        at_the_limit(arm.planned_end(), 1.0),
        "{:?}",
        arm.planned_end()
    );
    let negative = as_f32.map(|v| -v);
    assert_eq!(arm.ma(negative, 0.0), code::OK);
    assert!(
        at_the_limit(arm.planned_end(), -1.0),
        "{:?}",
        arm.planned_end()
    );
    // A value truly past a limit is still refused.
    let mut beyond = limits;
    beyond[1] += 1e-4;
    let mut arm = homed_arm();
    assert_eq!(arm.ma(beyond, 0.0), code::JOINT_LIMIT);
}

#[test]
fn a_location_file_in_degrees_is_refused_with_the_line_and_the_radians() {
    use trol_a465::arm::parse_locations;
    let ok = parse_locations("test_001 400 0 150 0 1.5707963 0\n").unwrap();
    assert_eq!(ok.len(), 1);
    let e = parse_locations("; a comment\ntest_001 400 0 150 0 90 0\n").unwrap_err();
    assert!(
        e.starts_with("line 2: pitch 90 is more than a full turn"),
        "{e}"
    );
    assert!(e.contains("1.5707963"), "{e}");
    // A precision point's counts are not angles.
    assert!(parse_locations("#park 1000 -2000 3000 0 0 9000\n").is_ok());
}

/// A tool that would put the tool centre point below the table where the arm stands is
/// refused and changes nothing (it used to be taken, and then every move but Home was
/// refused); a shorter one is taken.
#[test]
fn a_tool_that_reaches_below_the_table_is_refused_and_changes_nothing() {
    let mut arm = Arm::new(ArmSettings {
        homed: true,
        ..ArmSettings::default()
    });
    // The tool pointing down, 150 mm above the table.
    let t = settle_at(&mut arm, [400.0, 0.0, 150.0, 0.0, DOWN, 0.0], 0.0);
    let before = arm.position(t, Which::Commanded);
    assert_eq!(
        arm.set_tool([200.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
        code::BELOW_TABLE
    );
    // Nothing changed: the same moves work.
    assert_eq!(
        arm.move_to(Target::Cart([400.0, 0.0, 100.0, 0.0, DOWN, 0.0]), false, t),
        code::OK
    );
    assert_eq!(arm.position(t, Which::Commanded), before);
    assert_eq!(arm.set_tool([50.0, 0.0, 0.0, 0.0, 0.0, 0.0]), code::OK);
}

/// A trajectory (TROLTrajectory) passes each waypoint at its time, starts and ends at rest,
/// and keeps every joint within its speed and acceleration limits all along (sampled every
/// millisecond).
#[test]
fn a_trajectory_passes_each_waypoint_at_its_time_within_the_limits() {
    let mut arm = homed_arm();
    let points = [
        (1.0, [0.3, 0.2, -0.2, 0.0, 0.1, 0.0]),
        (2.0, [0.6, 0.3, -0.4, 0.2, 0.2, 0.1]),
        (3.5, [0.2, 0.1, -0.1, 0.0, 0.0, 0.0]),
    ];
    let start = 10.0;
    assert_eq!(arm.trajectory(&points, start), code::OK);
    for (t, q) in points {
        let at = arm.clone().commanded(start + t);
        for i in 0..6 {
            assert!((at[i] - q[i]).abs() < 1e-9, "{t} s: {at:?} against {q:?}");
        }
    }
    assert_eq!(arm.clone().finish_status(start + 3.4), code::MOVING);
    assert_eq!(arm.clone().finish_status(start + 3.6), code::OK);
    let (v, a) = joint_limits(100.0);
    let dt = 1e-3;
    let q = |t: f64| arm.clone().commanded(t);
    let mut prev_speed = [0.0; 6];
    for k in 0..=3600 {
        let t = start + k as f64 * dt;
        let (q0, q1) = (q(t), q(t + dt));
        for i in 0..6 {
            let speed = (q1[i] - q0[i]) / dt;
            assert!(
                speed.abs() <= v[i] * 1.001,
                "joint {} at {t}: {speed}",
                i + 1
            );
            if k > 0 {
                let accel = (speed - prev_speed[i]) / dt;
                assert!(
                    accel.abs() <= a[i] * 1.01,
                    "joint {} at {t}: {accel}",
                    i + 1
                );
            }
            prev_speed[i] = speed;
        }
    }
    // At rest at both ends: the first and last millisecond move almost nothing.
    let (s0, s1) = (q(start), q(start + dt));
    let (e0, e1) = (q(start + 3.5 - dt), q(start + 3.5));
    for i in 0..6 {
        assert!((s1[i] - s0[i]).abs() < 1e-4 && (e1[i] - e0[i]).abs() < 1e-4);
    }
}

/// What the arm cannot do as asked is refused before anything moves, with the reason for the
/// log: too fast (at 100 % and at a lower speed setting), a joint past its limit between the
/// waypoints, a waypoint at time 0 that is not where it starts, an arm not homed.
#[test]
fn a_trajectory_the_arm_cannot_run_is_refused_and_nothing_moves() {
    let mut arm = homed_arm();
    let refused = |arm: &mut Arm, points: &[(f64, [f64; 6])], want: i16| {
        assert_eq!(arm.trajectory(points, 0.0), want);
        let why = arm.take_refusal().unwrap_or_default();
        assert_eq!(arm.commanded(5.0), [0.0; 6], "nothing moved");
        assert_eq!(arm.finish_status(5.0), code::OK);
        why
    };
    let fast = [(0.1, [1.5, 0.0, 0.0, 0.0, 0.0, 0.0])];
    let why = refused(&mut arm, &fast, code::TOO_FAST);
    assert!(
        why.contains("joint 1") && why.contains("more time"),
        "{why}"
    );
    // Fine at 100 %, too fast at 10 %.
    let gentle = [(2.0, [0.5, 0.0, 0.0, 0.0, 0.0, 0.0])];
    arm.set_speed(10.0);
    refused(&mut arm, &gentle, code::TOO_FAST);
    arm.set_speed(100.0);
    // Joint 2's limit is 90 degrees: a waypoint past it is snapped, but an overshoot of the
    // spline between two waypoints near it is not.
    let past = [
        (1.0, [0.0, 1.55, 0.0, 0.0, 0.0, 0.0]),
        (1.2, [0.0, 1.57, 0.0, 0.0, 0.0, 0.0]),
        (1.3, [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
    ];
    let code_past = arm.trajectory(&past, 0.0);
    assert!(
        [code::JOINT_LIMIT, code::TOO_FAST].contains(&code_past),
        "{code_past}"
    );
    arm.take_refusal();
    assert_eq!(arm.commanded(5.0), [0.0; 6]);
    let far = [(2.0, [0.0, 2.0, 0.0, 0.0, 0.0, 0.0])];
    refused(&mut arm, &far, code::JOINT_LIMIT);
    let elsewhere = [(0.0, [0.1, 0.0, 0.0, 0.0, 0.0, 0.0]), (2.0, [0.5; 6])];
    let why = refused(&mut arm, &elsewhere, code::BAD_ARGUMENT);
    assert!(why.contains("time 0"), "{why}");
    // The same starting where the arm stands is taken, and the point at 0 is the start.
    let here = [(0.0, [0.0; 6]), (2.0, [0.5, 0.0, 0.0, 0.0, 0.0, 0.0])];
    assert_eq!(arm.trajectory(&here, 0.0), code::OK);
    assert!((arm.commanded(2.0 + 1e-9)[0] - 0.5).abs() < 1e-12);
    let mut cold = Arm::new(ArmSettings::default());
    assert_eq!(cold.trajectory(&gentle, 0.0), code::NOT_HOMED);
}

/// A trajectory queues behind a motion under way and starts where it ends; a Halt brakes it
/// along its path.
#[test]
fn a_trajectory_waits_for_the_motion_before_it_and_halts_along_its_path() {
    let mut arm = homed_arm();
    assert_eq!(arm.joint(1, 0.5, 0.0), code::OK);
    // The first motion's commanded end (done_at counts the servo's lag after it).
    let t1 = arm.done_at(0.0) - trol_a465::arm::SERVO_LAG;
    let points = [(1.0, [0.5, 0.3, 0.0, 0.0, 0.0, 0.0])];
    assert_eq!(arm.trajectory(&points, 0.0), code::OK);
    assert_eq!(arm.clone().commanded(t1)[1], 0.0);
    let at = arm.clone().commanded(t1 + 1.0);
    assert!((at[1] - 0.3).abs() < 1e-9, "{at:?}");
    // Halt half way: it stands before the end, short of the waypoint.
    arm.halt(t1 + 0.5);
    let stop = arm.done_at(t1 + 0.5);
    assert!(stop < t1 + 1.0, "{stop}");
    let rest = arm.commanded(stop + 1.0);
    assert!(rest[1] > 0.0 && rest[1] < 0.3, "{rest:?}");
}

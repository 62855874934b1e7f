//! Motion within the arm's limits, sampled finely in the arm's own time: random
//! joint-interpolated moves at several speeds, and 10,000 random straight lines (from READY,
//! near the base axis, near the wrist singularity, and anywhere). No joint exceeds its speed
//! or acceleration, nothing jumps, joints of a joint move start and end together, and the
//! tool stays on its line within its linear speed.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use trol_a465::Joints;
use trol_a465::arm::{
    Arm, ArmSettings, LINE_MAX_FACTOR, MAX_LINEAR_ACCEL, MAX_LINEAR_SPEED, SERVO_LAG, Target, code,
    joint_limits,
};
use trol_a465::model::LIMITS_RAD;

fn homed_arm() -> Arm {
    Arm::new(ArmSettings {
        homed: true,
        table_z: -1e9,
        ..ArmSettings::default()
    })
}

/// Check the motion from `t0` to its end at `steps` samples: every joint within its speed
/// and acceleration limits at `percent` (a small slack for rounding), and no step larger than
/// the speed allows. Returns the samples.
fn check_limits(arm: &mut Arm, t0: f64, percent: f64, steps: usize, what: &str) -> Vec<Joints> {
    let end = arm.done_at(t0);
    let (v, a) = joint_limits(percent);
    let dt = (end - t0) / steps as f64;
    let q: Vec<Joints> = (0..=steps + 2)
        .map(|k| arm_at(arm, t0 + (k as f64 - 1.0) * dt))
        .collect();
    for k in 1..q.len() - 1 {
        for i in 0..6 {
            let speed = (q[k + 1][i] - q[k][i]).abs() / dt;
            assert!(
                speed <= v[i] * (1.0 + 1e-6) + 1e-9,
                "{what}: joint {} at {:.1} % of its speed",
                i + 1,
                100.0 * speed / v[i]
            );
            let accel = (q[k + 1][i] - 2.0 * q[k][i] + q[k - 1][i]).abs() / (dt * dt);
            assert!(
                accel <= a[i] * (1.0 + 1e-3) + 1e-6,
                "{what}: joint {} at {:.1} % of its acceleration",
                i + 1,
                100.0 * accel / a[i]
            );
        }
    }
    q
}

/// The commanded joints at `t` without retiring motions (the arm is asked in any order).
fn arm_at(arm: &Arm, t: f64) -> Joints {
    let mut copy = arm.clone();
    copy.commanded(t)
}

fn random_joints(rng: &mut ChaCha8Rng, margin: f64) -> Joints {
    std::array::from_fn(|i| rng.random_range(-LIMITS_RAD[i] + margin..LIMITS_RAD[i] - margin))
}

#[test]
fn joint_moves_stay_within_every_joints_limits_and_end_together() {
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    for n in 0..300 {
        let percent = [1.0, 10.0, 50.0, 100.0, 150.0][n % 5];
        let mut arm = homed_arm();
        let from = random_joints(&mut rng, 0.05);
        arm.ma(from, 0.0);
        // Some time after the first motion, so that the samples before t0 are at rest.
        let t0 = arm.done_at(0.0) + 0.1;
        arm.set_speed(percent);
        let to = random_joints(&mut rng, 0.05);
        assert_eq!(arm.ma(to, t0), code::OK);
        let q = check_limits(
            &mut arm,
            t0,
            percent,
            400,
            &format!("move {n} at {percent} %"),
        );
        // All joints start and end together: each has done the same fraction of its way.
        for p in &q[1..q.len() - 2] {
            let fractions: Vec<f64> = (0..6)
                .filter(|i| (to[*i] - from[*i]).abs() > 1e-3)
                .map(|i| (p[i] - from[i]) / (to[i] - from[i]))
                .collect();
            for f in &fractions {
                assert!((f - fractions[0]).abs() < 1e-9, "move {n}: {fractions:?}");
            }
        }
        assert_eq!(q[q.len() - 1], to);
    }
}

/// A start for a straight line: READY, near the base axis, near the wrist singularity, or
/// anywhere.
fn start(rng: &mut ChaCha8Rng, kind: usize) -> Joints {
    match kind {
        0 => [0.0; 6],
        1 => {
            // The wrist centre near the base axis: the forearm folded back over the shoulder.
            let j2 = rng.random_range(-0.3..0.3);
            [
                rng.random_range(-2.0..2.0),
                j2,
                rng.random_range(1.2..1.9),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            ]
        }
        2 => {
            let mut q = random_joints(rng, 0.3);
            q[4] = rng.random_range(-0.05..0.05);
            q
        }
        _ => random_joints(rng, 0.2),
    }
}

#[test]
fn ten_thousand_random_straight_lines_never_jump_and_stay_within_the_limits() {
    let mut rng = ChaCha8Rng::seed_from_u64(1313);
    let mut accepted = 0;
    let mut refusals = std::collections::BTreeMap::new();
    let mut factors = Vec::new();
    for n in 0..10_000 {
        let percent = [25.0, 100.0, 150.0][n % 3];
        let mut arm = homed_arm();
        let q0 = start(&mut rng, n % 4);
        if arm.ma(q0, 0.0) != code::OK {
            continue;
        }
        // Some time after the first motion, so that the samples before t0 are at rest.
        let t0 = arm.done_at(0.0) + 0.1;
        arm.set_speed(percent);
        let from = arm.kinematics().fk_xyzypr(&q0);
        let mut to = from;
        for v in to.iter_mut().take(3) {
            *v += rng.random_range(-200.0..200.0);
        }
        for v in to.iter_mut().skip(3) {
            *v += rng.random_range(-0.6..0.6);
        }
        let before = arm.clone();
        let before_line = arm.clone();
        let r = arm.move_to(Target::Cart(to), true, t0);
        if r != code::OK {
            *refusals.entry(r).or_insert(0) += 1;
            // A refusal changes nothing.
            assert!(!arm.is_moving(t0), "line {n}: refused ({r}) but moving");
            continue;
        }
        accepted += 1;
        let q = check_limits(
            &mut arm,
            t0,
            percent,
            300,
            &format!("line {n} at {percent} %"),
        );
        // The tool stays on its line, within its linear speed.
        let end = arm.done_at(t0);
        let dt = (end - t0) / 300.0;
        let line =
            |s: f64| -> [f64; 3] { std::array::from_fn(|i| from[i] + (to[i] - from[i]) * s) };
        let length = (0..3)
            .map(|i| (to[i] - from[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        // A point's distance from the line's segment.
        let off_line = |pos: glam::DVec3| -> f64 {
            let d = pos - glam::DVec3::from_array(line(0.0));
            let dir = glam::DVec3::from_array(line(1.0)) - glam::DVec3::from_array(line(0.0));
            if length > 0.0 {
                (d - dir * (d.dot(dir) / dir.length_squared()).clamp(0.0, 1.0)).length()
            } else {
                d.length()
            }
        };
        let mut prev = arm.kinematics().fk(&q[1]).pos;
        for p in &q[2..q.len() - 1] {
            let pos = arm.kinematics().fk(p).pos;
            let step = (pos - prev).length();
            assert!(
                step <= MAX_LINEAR_SPEED * percent.min(100.0) / 100.0 * dt * 1.001 + 1e-6,
                "line {n}: the tool at {:.0} mm/s",
                step / dt
            );
            prev = pos;
            let off = off_line(pos);
            assert!(off < 0.02, "line {n}: {off} mm off the line");
        }
        let last = arm.kinematics().fk_xyzypr(&q[q.len() - 1]);
        for i in 0..3 {
            assert!((last[i] - to[i]).abs() < 1e-6, "line {n}: ends at {last:?}");
        }
        // Its duration against the least time it needs: the joint move between the same
        // ends (made by the same arm), or the line at the linear limits (a trapezoid).
        let mut joint_move = before;
        assert_eq!(joint_move.ma(q[q.len() - 1], t0), code::OK, "line {n}");
        let joints = joint_move.done_at(t0) - t0 - SERVO_LAG;
        let f = percent.min(100.0) / 100.0;
        let (lv, la) = (MAX_LINEAR_SPEED * f, MAX_LINEAR_ACCEL * f);
        let linear = if lv * lv / la >= length {
            2.0 * (length / la).sqrt()
        } else {
            length / lv + lv / la
        };
        let least = joints.max(linear);
        let took = end - t0 - SERVO_LAG;
        let factor = if least > 0.0 { took / least } else { 1.0 };
        assert!(
            factor <= LINE_MAX_FACTOR * (1.0 + 1e-9) || took <= LINE_MAX_FACTOR * least + 0.1,
            "line {n}: {took:.3} s where {least:.3} s would do ({factor:.1}x)"
        );
        factors.push(factor);
        // Halted on the way (every fifth line): it brakes within the limits, on the line.
        if accepted % 5 == 0 {
            let mut halted = before_line.clone();
            assert_eq!(halted.move_to(Target::Cart(to), true, t0), code::OK);
            let at = t0 + rng.random_range(0.0..1.0) * took;
            halted.halt(at);
            let stop = halted.done_at(at) - SERVO_LAG;
            assert!(
                stop <= end - SERVO_LAG + 1e-9,
                "line {n}: a halt that ends later"
            );
            let q = check_limits(
                &mut halted,
                t0,
                percent,
                300,
                &format!("line {n} at {percent} %, halted"),
            );
            for p in &q {
                let off = off_line(arm.kinematics().fk(p).pos);
                assert!(off < 0.02, "line {n}, halted: {off} mm off the line");
            }
        }
    }
    factors.sort_by(f64::total_cmp);
    assert_eq!(factors.len(), accepted);
    let at = |p: f64| factors[((factors.len() - 1) as f64 * p) as usize];
    let over = |x: f64| factors.iter().filter(|f| **f > x).count();
    println!(
        "duration / least time of the {} accepted lines: median {:.2}, 90 % {:.2}, 99 % {:.2}, \
         max {:.2}; over 2x: {}, over 5x: {}, over 10x: {}",
        factors.len(),
        at(0.5),
        at(0.9),
        at(0.99),
        at(1.0),
        over(2.0),
        over(5.0),
        over(10.0)
    );
    // Most lines are possible; the rest are refused with a reason, before anything moved.
    assert!(
        accepted > 2_500,
        "only {accepted} of 10000 lines accepted: {refusals:?}"
    );
    println!("accepted {accepted} of 10000; refused: {refusals:?}");
    // docs/a465.md, "Straight lines", gives this distribution.
    assert!(
        at(0.99) < 3.0,
        "a line at the arm's pace takes about its least time"
    );
    assert!(refusals.contains_key(&code::SINGULAR_PATH), "{refusals:?}");
}

/// The lines that crawled when a line was timed by its worst point (issue 27: a jog of
/// 100 mm down from READY took 335 s, a line from READY to (600, 0, 300) tool down 1,562 s,
/// a line toward full stretch 799 s) run within LINE_MAX_FACTOR of their least time, or are
/// refused before anything moves.
#[test]
fn lines_from_ready_run_at_the_arms_pace() {
    use std::f64::consts::FRAC_PI_2;
    enum Line {
        Jog([f64; 3]),
        To([f64; 6]),
    }
    let cases = [
        ("jog 100 mm down", Line::Jog([0.0, 0.0, -100.0])),
        (
            "to (600, 0, 300) tool down",
            Line::To([600.0, 0.0, 300.0, 0.0, FRAC_PI_2, 0.0]),
        ),
        ("toward full stretch", Line::Jog([300.0, 0.0, -300.0])),
    ];
    for (what, line) in cases {
        let mut arm = homed_arm();
        let q0 = arm.commanded(0.0);
        let r = match line {
            Line::Jog(d) => arm.jog(d, true, 0.0),
            Line::To(c) => arm.move_to(Target::Cart(c), true, 0.0),
        };
        if r == code::SINGULAR_PATH {
            assert!(!arm.is_moving(0.0), "{what}: refused but moving");
            println!("{what}: refused (SINGULAR_PATH)");
            continue;
        }
        assert_eq!(r, code::OK, "{what}");
        let took = arm.done_at(0.0) - SERVO_LAG;
        let end = arm.commanded(took + 1.0);
        let length = (arm.kinematics().fk(&end).pos - arm.kinematics().fk(&q0).pos).length();
        let least = arm.line_least_time(q0, end, length);
        println!("{what}: {took:.3} s, least {least:.3} s");
        assert!(
            took <= LINE_MAX_FACTOR * least,
            "{what}: {took} s, least {least} s"
        );
        assert!(took < 5.0, "{what}: {took} s");
    }
}

/// A straight line to where the arm already is (an Appro of 0 after a joint-interpolated
/// Appro, say) is no line at all: accepted, and it takes no time to speak of.
#[test]
fn a_straight_line_to_where_the_arm_is_is_accepted() {
    let mut arm = homed_arm();
    let here = [400.0, 0.0, 240.0, 0.0, std::f64::consts::FRAC_PI_2, 0.0];
    assert_eq!(arm.move_to(Target::Cart(here), false, 0.0), code::OK);
    let t = arm.done_at(0.0);
    assert_eq!(arm.move_to(Target::Cart(here), true, t), code::OK);
    assert!(arm.done_at(t) - t < 0.02, "{}", arm.done_at(t) - t);
}

//! Forward/inverse kinematics round trips over many random poses.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use trol_a465::kinematics::wrap;
use trol_a465::model::limits;
use trol_a465::{IkError, Kinematics, Pose};

fn random_joints(rng: &mut ChaCha8Rng) -> [f64; 6] {
    let lim = limits();
    std::array::from_fn(|i| rng.random_range(-lim[i]..lim[i]))
}

fn pose_error(a: &Pose, b: &Pose) -> (f64, f64) {
    let dp = (a.pos - b.pos).length();
    let dr = (a.rot - b.rot)
        .to_cols_array()
        .iter()
        .map(|x| x.abs())
        .fold(0.0, f64::max);
    (dp, dr)
}

#[test]
fn every_solution_reaches_the_pose_and_one_is_the_original() {
    let mut rng = ChaCha8Rng::seed_from_u64(465);
    for tool in [[0.0; 6], [0.0, 10.0, 120.0, 0.1, -0.2, 0.3]] {
        let k = Kinematics::new(tool);
        for _ in 0..20_000 {
            let q = random_joints(&mut rng);
            let pose = k.fk(&q);
            let sols = k.ik_all(&pose, &q);
            assert!(!sols.is_empty(), "{q:?}");
            let mut found = false;
            for s in sols.as_slice() {
                let (dp, dr) = pose_error(&k.fk(&s.q), &pose);
                assert!(dp < 1e-6 && dr < 1e-9, "{q:?} -> {s:?}: {dp} mm, {dr}");
                if s.q.iter().zip(q).all(|(a, b)| wrap(a - b).abs() < 1e-7) {
                    found = true;
                }
            }
            assert!(
                found,
                "the original joints are not among {sols:?} for {q:?}"
            );
            let near = k.ik_nearest(&pose, &q).unwrap();
            assert!(near.iter().zip(q).all(|(a, b)| wrap(a - b).abs() < 1e-7));
        }
    }
}

#[test]
fn a_generic_pose_has_eight_distinct_configurations() {
    let k = Kinematics::default();
    let q = [0.3, 0.4, 0.5, 0.6, 0.7, 0.8];
    let sols = k.ik_all(&k.fk(&q), &q);
    assert_eq!(sols.len(), 8);
    let mut configs: Vec<String> = sols
        .as_slice()
        .iter()
        .map(|s| s.config.to_string())
        .collect();
    configs.sort();
    configs.dedup();
    assert_eq!(configs.len(), 8);
}

#[test]
fn singular_cases_keep_the_current_joint() {
    let k = Kinematics::default();
    // Wrist centre on the base axis: J1 keeps its value.
    let q = [0.7, 0.0, 0.0, 0.2, 0.5, 0.1];
    let pose = k.fk(&q);
    let near = k.ik_nearest(&pose, &q).unwrap();
    assert!((near[0] - 0.7).abs() < 1e-9, "{near:?}");
    // J5 = 0: J4 keeps its value, J6 takes the rest.
    let q = [0.1, 0.2, 0.3, 0.9, 0.0, -0.4];
    let pose = k.fk(&q);
    let near = k.ik_nearest(&pose, &q).unwrap();
    assert!(
        (near[3] - 0.9).abs() < 1e-9 && (near[5] + 0.4).abs() < 1e-9,
        "{near:?}"
    );
    let (dp, _) = pose_error(&k.fk(&near), &pose);
    assert!(dp < 1e-6);
}

#[test]
fn out_of_reach_and_limits_are_reported() {
    let k = Kinematics::default();
    let far = Pose::from_xyzypr([2000.0, 0.0, 300.0, 0.0, 0.0, 0.0]);
    assert_eq!(k.ik_nearest(&far, &[0.0; 6]), Err(IkError::OutOfReach));
    assert!(k.ik_all(&far, &[0.0; 6]).is_empty());
    // Straight down below the base: reachable in principle only with J2 beyond ±90°.
    let under = Pose::from_xyzypr([100.0, 0.0, -150.0, 0.0, std::f64::consts::FRAC_PI_2, 0.0]);
    match k.ik_nearest(&under, &[0.0; 6]) {
        Err(IkError::JointLimit { joint }) => assert!((1..=6).contains(&joint)),
        other => panic!("{other:?}"),
    }
}

/// A pose with J5 = 0 that crossed the line as f32 (about 1e-7 of rounding) still counts as
/// the singular wrist: J4 keeps its value and J6 takes the rest, instead of J4 jumping to
/// whatever the rounding says (issue: a cartesian move to such a pose reset J4 to 0).
#[test]
fn at_j5_zero_j4_keeps_its_value_after_f32_rounding() {
    let k = Kinematics::default();
    let q = [0.0, 0.5, 1.0, 0.7, 0.0, 0.2];
    let v = k.fk_xyzypr(&q).map(|x| x as f32 as f64);
    let current = [0.0, 0.5, 1.0, 0.4, 0.3, 0.2];
    let got = k.ik_nearest(&Pose::from_xyzypr(v), &current).unwrap();
    assert!((got[3] - 0.4).abs() < 1e-9, "J4 {got:?}");
    assert!(got[4].abs() < 1e-9, "J5 {got:?}");
    assert!((got[5] - 0.5).abs() < 1e-5, "J6 {got:?}");
    // The pose is the one asked, to f32's precision.
    let (dp, dr) = pose_error(&k.fk(&got), &Pose::from_xyzypr(v));
    assert!(dp < 1e-3 && dr < 1e-5, "{dp} mm, {dr}");
}

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
    assert!(got[4].abs() < 1e-6, "J5 {got:?}");
    assert!((got[5] - 0.5).abs() < 1e-5, "J6 {got:?}");
    // The pose is the one asked, to f32's precision.
    let (dp, dr) = pose_error(&k.fk(&got), &Pose::from_xyzypr(v));
    assert!(dp < 1e-3 && dr < 1e-5, "{dp} mm, {dr}");
}

/// READY read as f32 (GetPosition: z 1041.4000244) is reachable: the rounding puts the wrist
/// centre a few hundredths of a micrometre beyond the full reach, within the tolerance
/// (issue 42: MoveII of READY's own cartesian position was refused BIOS_OUT_OF_REACH). A
/// pose 0.01 mm beyond is not.
#[test]
fn ready_read_as_f32_is_reachable_and_a_hundredth_beyond_is_not() {
    let k = Kinematics::default();
    let ready = k.fk_xyzypr(&[0.0; 6]);
    let v = ready.map(|x| x as f32 as f64);
    assert!(v[2] > ready[2], "the rounding is outward: {v:?}");
    let got = k.ik_nearest(&Pose::from_xyzypr(v), &[0.0; 6]).unwrap();
    let (dp, _) = pose_error(&k.fk(&got), &Pose::from_xyzypr(ready));
    assert!(dp < 1e-3, "{dp} mm");
    let mut beyond = ready;
    beyond[2] += 0.01;
    assert_eq!(
        k.ik_nearest(&Pose::from_xyzypr(beyond), &[0.0; 6]),
        Err(IkError::OutOfReach)
    );
}

/// J4 keeps its value at J5 = 0 near the stretched elbow too (issue 42: over 400 such poses
/// sent as f32, J4 changed in 94 % with |J3| < 0.5 deg, the wrist swinging up to 68 deg for
/// nothing): the rounding puts J5 a little off 0 there, within the band that counts as 0.
/// The elbow keeps its side, and the pose is the one asked to what the rounding allows.
#[test]
fn at_j5_zero_near_the_stretched_elbow_j4_keeps_its_value() {
    let k = Kinematics::default();
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    let (mut worst_mm, mut worst_rad) = (0.0f64, 0.0f64);
    for i in 0..400 {
        let j3 = rng.random_range(-0.5f64..0.5).to_radians() * if i % 2 == 0 { 1.0 } else { 0.2 };
        let q = [
            rng.random_range(-2.5..2.5),
            rng.random_range(-0.5..1.2),
            j3,
            rng.random_range(-3.0..3.0),
            0.0,
            rng.random_range(-3.0..3.0),
        ];
        let v = k.fk_xyzypr(&q).map(|x| x as f32 as f64);
        let asked = Pose::from_xyzypr(v);
        let got = k.ik_nearest(&asked, &q).unwrap();
        assert!(
            (got[3] - q[3]).abs() < 1e-9,
            "case {i}: J4 {q:?} -> {got:?}"
        );
        assert!(
            got[2] * q[2] >= 0.0 || q[2].abs() < 1e-4,
            "case {i}: the elbow flipped"
        );
        let (dp, dr) = pose_error(&k.fk(&got), &asked);
        worst_mm = worst_mm.max(dp);
        worst_rad = worst_rad.max(dr);
    }
    eprintln!("worst pose error: {worst_mm:.2e} mm, {worst_rad:.2e} of rotation");
    assert!(
        worst_mm < 1e-3 && worst_rad < 1e-5,
        "{worst_mm} mm, {worst_rad}"
    );
}

/// A 4x4 transform as rows.
type M4 = [[f64; 4]; 4];

fn mul(a: &M4, b: &M4) -> M4 {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..4).map(|k| a[i][k] * b[k][j]).sum()))
}

/// Standard DH: Rz(theta) Tz(d) Tx(a) Rx(alpha).
fn dh(theta: f64, d: f64, a: f64, alpha: f64) -> M4 {
    let (st, ct, sa, ca) = (theta.sin(), theta.cos(), alpha.sin(), alpha.cos());
    [
        [ct, -st * ca, st * sa, a * ct],
        [st, ct * ca, -ct * sa, a * st],
        [0.0, sa, ca, d],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

/// The flange of CTU's DH table (ctu_crs: offsets 0, -270, -90, 0, 0, 0 deg; alpha 90, 0,
/// 270, 90, 270, 0 deg), with TROL's lengths, in mm.
fn ctu_flange(q: &[f64; 6]) -> [f64; 3] {
    let t = ctu_frame(q, 330.2);
    [t[0][3], t[1][3], t[2][3]]
}

/// The flange frame of CTU's DH table with its base length `d1` (TROL's 330.2 mm, or
/// ctu_crs's own 305.2).
fn ctu_frame(q: &[f64; 6], d1: f64) -> M4 {
    let r = f64::to_radians;
    let off = [0.0, r(-270.0), r(-90.0), 0.0, 0.0, 0.0];
    let alpha = [r(90.0), 0.0, r(270.0), r(90.0), r(270.0), 0.0];
    let d = [d1, 0.0, 0.0, 330.2, 0.0, 76.2];
    let a = [0.0, 304.8, 0.0, 0.0, 0.0, 0.0];
    let mut t: M4 = std::array::from_fn(|i| std::array::from_fn(|j| f64::from(i == j)));
    for i in 0..6 {
        t = mul(&t, &dh(q[i] + off[i], d[i], a[i], alpha[i]));
    }
    t
}

/// The flange of the public ROS 2 URDF's chain (AlfZuck1/ROS2-Workspace-CRSA465: joint axes
/// z, +y, -y, z, -y, z along a straight-up arm), with TROL's lengths, in mm.
fn urdf_flange(q: &[f64; 6]) -> [f64; 3] {
    let axes = [
        [0.0, 0.0, 1.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    let up = [330.2, 0.0, 304.8, 0.0, 330.2, 76.2];
    let mut t: M4 = std::array::from_fn(|i| std::array::from_fn(|j| f64::from(i == j)));
    for i in 0..6 {
        let mut lift: M4 = std::array::from_fn(|r| std::array::from_fn(|c| f64::from(r == c)));
        lift[2][3] = up[i];
        // Rodrigues' rotation about a unit axis.
        let [x, y, z] = axes[i];
        let (s, c) = q[i].sin_cos();
        let k = [[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]];
        let mut rot: M4 = std::array::from_fn(|r| std::array::from_fn(|c| f64::from(r == c)));
        for r in 0..3 {
            for col in 0..3 {
                let kk: f64 = (0..3).map(|m| k[r][m] * k[m][col]).sum();
                rot[r][col] += s * k[r][col] + (1.0 - c) * kk;
            }
        }
        t = mul(&mul(&t, &lift), &rot);
    }
    // The flange is the last lift's end: already in `up[5]` before J6's turn.
    [t[0][3], t[1][3], t[2][3]]
}

/// docs/a465.md, "Joints, the zero pose and signs": the public models' joint values are
/// TROL's with some signs turned. CTU's DH reaches TROL's flange with J2, J3 and J5
/// negated; the ROS 2 URDF with J3 and J5 negated; neither with TROL's values as they are.
#[test]
fn the_public_models_match_trols_joints_with_the_documented_signs() {
    let k = Kinematics::new([0.0; 6]);
    let mut rng = ChaCha8Rng::seed_from_u64(93);
    let mut worst_as_is: f64 = 0.0;
    for _ in 0..1000 {
        let q = random_joints(&mut rng);
        let trol = k.fk(&q).pos;
        let dist = |p: [f64; 3]| (glam::DVec3::from_array(p) - trol).length();
        let ctu = [q[0], -q[1], -q[2], q[3], -q[4], q[5]];
        assert!(dist(ctu_flange(&ctu)) < 1e-9, "CTU at {q:?}");
        let ros = [q[0], q[1], -q[2], q[3], -q[4], q[5]];
        assert!(dist(urdf_flange(&ros)) < 1e-9, "URDF at {q:?}");
        worst_as_is = worst_as_is.max(dist(ctu_flange(&q)).min(dist(urdf_flange(&q))));
    }
    assert!(
        worst_as_is > 100.0,
        "the values as they are miss: {worst_as_is} mm"
    );
}

/// docs/a465.md and docs/mars.md: CTU's flange frame (ctu_crs's DH, its joints TROL's with
/// J2, J3, J5 negated) is TROL's turned by Ry(90 deg) about its own y axis, R_CTU = R_TROL
/// Ry(90 deg), at every pose (1,000 random ones); the docs said 180 deg about the flange's
/// normal (issue 38). With ctu_crs's own base length (d1 = 305.2 mm against TROL's 330.2) a
/// point's z in CTU's frame is TROL's minus 25 mm.
#[test]
fn ctus_flange_frame_is_trols_turned_90_deg_about_y() {
    let k = Kinematics::new([0.0; 6]);
    let mut rng = ChaCha8Rng::seed_from_u64(90);
    let r = f64::to_radians;
    let ry90 = glam::DMat3::from_rotation_y(r(90.0));
    for _ in 0..1000 {
        let q = random_joints(&mut rng);
        let p = k.fk(&q);
        let ctu = [q[0], -q[1], -q[2], q[3], -q[4], q[5]];
        // ctu_crs's own lengths: d1 305.2 mm.
        let t = ctu_frame(&ctu, 305.2);
        let rot = glam::DMat3::from_cols_array_2d(&[
            [t[0][0], t[1][0], t[2][0]],
            [t[0][1], t[1][1], t[2][1]],
            [t[0][2], t[1][2], t[2][2]],
        ]);
        let want = p.rot * ry90;
        let off_rot = (0..3)
            .map(|c| (rot.col(c) - want.col(c)).length())
            .fold(0.0, f64::max);
        assert!(off_rot < 1e-9, "{q:?}: {off_rot}");
        let pos = glam::DVec3::new(t[0][3], t[1][3], t[2][3]);
        assert!(
            (pos - (p.pos - glam::DVec3::new(0.0, 0.0, 25.0))).length() < 1e-9,
            "{q:?}"
        );
    }
}

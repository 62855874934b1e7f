//! The URDF `trol urdf` prints, read back by a URDF parser (urdf-rs): its chain from
//! `base_link` to `tool0`, multiplied out at random joint values, is trol-a465's forward
//! kinematics; its joints' limits and speeds are the model's.

use glam::{DMat3, DVec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use trol_a465::kinematics::Kinematics;
use trol_a465::model::{LIMITS_RAD, max_speeds};

/// `origin` as a rotation and a translation (m).
fn origin(p: &urdf_rs::Pose) -> (DMat3, DVec3) {
    let [roll, pitch, yaw] = *p.rpy;
    let rot =
        DMat3::from_rotation_z(yaw) * DMat3::from_rotation_y(pitch) * DMat3::from_rotation_x(roll);
    (rot, DVec3::from_array(*p.xyz))
}

/// The pose of `tip` in `base_link` at joint values `q` (joint_k takes q[k-1]).
fn chain(robot: &urdf_rs::Robot, tip: &str, q: &[f64; 6]) -> (DMat3, DVec3) {
    let mut joints = Vec::new();
    let mut link = tip.to_string();
    while link != "base_link" {
        let j = robot
            .joints
            .iter()
            .find(|j| j.child.link == link)
            .unwrap_or_else(|| panic!("no joint leads to {link}"));
        joints.push(j);
        link = j.parent.link.clone();
    }
    let (mut rot, mut pos) = (DMat3::IDENTITY, DVec3::ZERO);
    for j in joints.iter().rev() {
        let (r, t) = origin(&j.origin);
        pos += rot * t;
        rot *= r;
        if matches!(j.joint_type, urdf_rs::JointType::Revolute) {
            let k: usize = j.name.strip_prefix("joint_").unwrap().parse().unwrap();
            let axis = DVec3::from_array(*j.axis.xyz);
            rot *= DMat3::from_axis_angle(axis.normalize(), q[k - 1]);
        }
    }
    (rot, pos)
}

#[test]
fn the_urdf_is_the_models_kinematics() {
    let text = trol_a465::urdf::urdf();
    let robot = urdf_rs::read_from_string(&text).expect("a URDF the parser reads");
    let names: Vec<&str> = robot.links.iter().map(|l| l.name.as_str()).collect();
    for n in [
        "base_link",
        "link_1",
        "link_2",
        "link_3",
        "link_4",
        "link_5",
        "link_6",
        "flange",
        "tool0",
    ] {
        assert!(names.contains(&n), "no link {n}: {names:?}");
    }
    // Limits and speeds are the model's.
    let speeds = max_speeds();
    for k in 1..=6 {
        let j = robot
            .joints
            .iter()
            .find(|j| j.name == format!("joint_{k}"))
            .unwrap();
        assert!((j.limit.upper - LIMITS_RAD[k - 1]).abs() < 1e-6);
        assert!((j.limit.lower + LIMITS_RAD[k - 1]).abs() < 1e-6);
        assert!((j.limit.velocity - speeds[k - 1]).abs() < 1e-6);
    }
    // Forward kinematics at random joint values within the limits.
    let kin = Kinematics::new([0.0; 6]);
    let mut rng = ChaCha8Rng::seed_from_u64(465);
    for _ in 0..500 {
        let q: [f64; 6] = std::array::from_fn(|i| rng.random_range(-LIMITS_RAD[i]..LIMITS_RAD[i]));
        let (rot, pos) = chain(&robot, "tool0", &q);
        let want = kin.fk(&q);
        assert!(
            (pos * 1000.0 - want.pos).length() < 1e-4,
            "{q:?}: {} mm against {} mm",
            pos * 1000.0,
            want.pos
        );
        for c in 0..3 {
            assert!(
                (rot.col(c) - want.rot.col(c)).length() < 1e-7,
                "{q:?}: rotation column {c}"
            );
        }
    }
}

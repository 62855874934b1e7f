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

/// A link's collision shapes as capsules (segment ends and radius, m, in the link's frame),
/// each containing its shape: a cylinder is the capsule of its axis and radius; a box, that of
/// its longest side through its centre and the half diagonal of its cross-section.
fn capsules(robot: &urdf_rs::Robot, link: &str) -> Vec<(DVec3, DVec3, f64)> {
    let l = robot.links.iter().find(|l| l.name == link).unwrap();
    l.collision
        .iter()
        .map(|c| {
            let (rot, at) = origin(&c.origin);
            match &c.geometry {
                urdf_rs::Geometry::Cylinder { radius, length } => {
                    let half = rot * DVec3::new(0.0, 0.0, length / 2.0);
                    (at - half, at + half, *radius)
                }
                urdf_rs::Geometry::Box { size } => {
                    let [x, y, z] = **size;
                    let half = rot * DVec3::new(x / 2.0, 0.0, 0.0);
                    (at - half, at + half, (y * y + z * z).sqrt() / 2.0)
                }
                other => panic!("{link}: a shape this check does not know: {other:?}"),
            }
        })
        .collect()
}

/// The distance between segments p0-p1 and q0-q1.
fn segment_distance(p0: DVec3, p1: DVec3, q0: DVec3, q1: DVec3) -> f64 {
    let (d1, d2, r) = (p1 - p0, q1 - q0, p0 - q0);
    let (a, e, f) = (d1.dot(d1), d2.dot(d2), d2.dot(r));
    let c = d1.dot(r);
    let b = d1.dot(d2);
    let denom = a * e - b * b;
    let mut s = if denom > 1e-12 {
        ((b * f - c * e) / denom).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let mut t = (b * s + f) / e;
    if t < 0.0 {
        t = 0.0;
        s = (-c / a).clamp(0.0, 1.0);
    } else if t > 1.0 {
        t = 1.0;
        s = ((b - c) / a).clamp(0.0, 1.0);
    }
    ((p0 + d1 * s) - (q0 + d2 * t)).length()
}

/// The collision shapes of links joined by a joint (directly, or through a joint's own link
/// of no length, which has none) never touch at any pose within the limits, with 10 mm to
/// spare (issue 42: they overlapped at every pose, and held the arm in MuJoCo, turned J1 in
/// pybullet). 20,000 random poses, and each joint at both its limits.
#[test]
fn adjacent_collision_shapes_never_touch() {
    let robot = urdf_rs::read_from_string(&trol_a465::urdf::urdf()).unwrap();
    // The foot plate and the column: both about the base's vertical axis, about which J1
    // turns the column, so their gap is the same at every pose: the column's lowest point
    // above the plate's top (a capsule round the flat plate would not say it).
    let (plate, column) = (capsules(&robot, "base_link"), capsules(&robot, "link_1"));
    let (pa, pb, _) = plate[0];
    let (ca, cb, _) = column[0];
    for v in [pb - pa, cb - ca] {
        assert!(
            v.x.abs() < 1e-9 && v.y.abs() < 1e-9,
            "not about the vertical axis"
        );
    }
    let gap = ca.z.min(cb.z) - pa.z.max(pb.z);
    assert!(
        gap >= 0.010 - 1e-9,
        "the column {} mm above the plate",
        gap * 1000.0
    );
    let joined = [
        ("link_1", "link_2"),
        ("link_2", "link_4"),
        ("link_4", "tool0"),
    ];
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    let mut closest = f64::INFINITY;
    let mut poses: Vec<[f64; 6]> = (0..20_000)
        .map(|_| std::array::from_fn(|i| rng.random_range(-LIMITS_RAD[i]..LIMITS_RAD[i])))
        .collect();
    for i in 0..6 {
        for sign in [-1.0, 1.0] {
            let mut q = [0.0; 6];
            q[i] = sign * LIMITS_RAD[i];
            poses.push(q);
            // The elbow and the wrist folded together.
            q[2] = sign * LIMITS_RAD[2];
            q[4] = sign * LIMITS_RAD[4];
            poses.push(q);
        }
    }
    for q in &poses {
        let world = |link: &str| -> Vec<(DVec3, DVec3, f64)> {
            let (rot, pos) = if link == "base_link" {
                (DMat3::IDENTITY, DVec3::ZERO)
            } else {
                chain(&robot, link, q)
            };
            capsules(&robot, link)
                .into_iter()
                .map(|(a, b, r)| (pos + rot * a, pos + rot * b, r))
                .collect()
        };
        for (a, b) in joined {
            for (p0, p1, ra) in world(a) {
                for (q0, q1, rb) in world(b) {
                    let gap = segment_distance(p0, p1, q0, q1) - ra - rb;
                    closest = closest.min(gap);
                    assert!(
                        gap > 0.010,
                        "{a} and {b} at {q:?}: {} mm apart",
                        gap * 1000.0
                    );
                }
            }
        }
    }
    eprintln!(
        "the closest two joined links came: {:.1} mm",
        closest * 1000.0
    );
}

/// The SRDF beside the URDF (`trol urdf --srdf`, for MoveIt): every pair of links joined by
/// a joint is listed (MoveIt need not check them), each name is a link of the URDF, and the
/// group is the chain from `base_link` to `tool0`.
#[test]
fn the_srdf_names_every_joined_pair_of_the_urdf() {
    let robot = urdf_rs::read_from_string(&trol_a465::urdf::urdf()).unwrap();
    let srdf = trol_a465::urdf::srdf();
    assert!(srdf.contains("<chain base_link=\"base_link\" tip_link=\"tool0\"/>"));
    let links: Vec<&str> = robot.links.iter().map(|l| l.name.as_str()).collect();
    let pairs: Vec<(String, String)> = srdf
        .lines()
        .filter_map(|l| l.trim().strip_prefix("<disable_collisions link1=\""))
        .map(|rest| {
            let (a, rest) = rest.split_once('"').unwrap();
            let b = rest.split('"').nth(1).unwrap();
            (a.to_string(), b.to_string())
        })
        .collect();
    for (a, b) in &pairs {
        assert!(
            links.contains(&a.as_str()) && links.contains(&b.as_str()),
            "{a} {b}"
        );
    }
    for j in &robot.joints {
        let (p, c) = (j.parent.link.clone(), j.child.link.clone());
        assert!(
            pairs.contains(&(p.clone(), c.clone())) || pairs.contains(&(c.clone(), p.clone())),
            "{p} and {c} are not listed"
        );
    }
}

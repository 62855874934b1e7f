//! The URDF `trol urdf` prints, read back by a URDF parser (urdf-rs): its chain from
//! `base_link` to `tool0`, multiplied out at random joint values, is trol-a465's forward
//! kinematics; its joints' limits and speeds are the model's.

use glam::{DMat3, DQuat, DVec3};
use parry3d_f64::math::Pose;
use parry3d_f64::shape::Shape;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use trol_a465::kinematics::Kinematics;
use trol_a465::model::{D1, LIMITS_RAD, max_speeds};
use trol_a465::urdf::RADIUS_MM;

/// `origin` as a rotation and a translation (m).
fn origin(p: &urdf_rs::Pose) -> (DMat3, DVec3) {
    let [roll, pitch, yaw] = *p.rpy;
    let rot =
        DMat3::from_rotation_z(yaw) * DMat3::from_rotation_y(pitch) * DMat3::from_rotation_x(roll);
    (rot, DVec3::from_array(*p.xyz))
}

/// The pose of `tip` in `base_link` at joint values `q` (joint_k takes q[k-1]).
fn chain(robot: &urdf_rs::Robot, tip: &str, q: &[f64; 6]) -> (DMat3, DVec3) {
    chain_gripped(robot, tip, q, 0.0)
}

/// The pose of `tip` at joint values `q` and the gripper's gap `gap` (m): `gripper_joint`
/// takes it, a mimic joint its multiple.
fn chain_gripped(robot: &urdf_rs::Robot, tip: &str, q: &[f64; 6], gap: f64) -> (DMat3, DVec3) {
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
    let value = |j: &urdf_rs::Joint| -> f64 {
        if let Some(m) = &j.mimic {
            assert_eq!(m.joint, "gripper_joint", "{}", j.name);
            return m.multiplier.unwrap_or(1.0) * gap + m.offset.unwrap_or(0.0);
        }
        match j.name.strip_prefix("joint_") {
            Some(k) => q[k.parse::<usize>().unwrap() - 1],
            None => gap,
        }
    };
    let (mut rot, mut pos) = (DMat3::IDENTITY, DVec3::ZERO);
    for j in joints.iter().rev() {
        let (r, t) = origin(&j.origin);
        pos += rot * t;
        rot *= r;
        let axis = DVec3::from_array(*j.axis.xyz).normalize();
        match j.joint_type {
            urdf_rs::JointType::Revolute => rot *= DMat3::from_axis_angle(axis, value(j)),
            urdf_rs::JointType::Prismatic => pos += rot * (axis * value(j)),
            urdf_rs::JointType::Fixed => {}
            ref other => panic!("{}: a joint this check does not know: {other:?}", j.name),
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
                urdf_rs::Geometry::Sphere { radius } => (at, at, *radius),
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
    // A segment of no length (a sphere's): a point against the other segment.
    if a < 1e-12 && e < 1e-12 {
        return (p0 - q0).length();
    }
    if a < 1e-12 {
        let t = (f / e).clamp(0.0, 1.0);
        return (p0 - (q0 + d2 * t)).length();
    }
    if e < 1e-12 {
        let s = (-c / a).clamp(0.0, 1.0);
        return ((p0 + d1 * s) - q0).length();
    }
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
    // Each link and the next through a revolute joint, and the links either side of the
    // elbow's and the wrist's spheres, where the arm folds.
    let joined = [
        ("link_1", "link_2"),
        ("link_2", "link_3"),
        ("link_3", "link_4"),
        ("link_2", "link_4"),
        ("link_4", "link_5"),
        ("link_5", "link_6"),
        ("link_5", "flange"),
        ("link_5", "tool0"),
        ("link_4", "link_6"),
        ("link_4", "flange"),
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

/// Where each of a link's collision shapes lies along the axis it shares with the arm at
/// READY (mm, in `base_link`): the shapes rigidly joined at the flange (link_6's stub, the
/// flange's plate, the tool's box) follow each other along it without touching, so that a
/// simulator that checks them against each other finds no contact.
#[test]
fn the_shapes_fixed_together_at_the_flange_keep_apart_along_its_axis() {
    let robot = urdf_rs::read_from_string(&trol_a465::urdf::urdf()).unwrap();
    let q = trol_a465::model::READY;
    let extent = |link: &str| -> (f64, f64) {
        let (rot, pos) = chain(&robot, link, &q);
        let l = robot.links.iter().find(|l| l.name == link).unwrap();
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for c in &l.collision {
            let (r, at) = origin(&c.origin);
            let (rot, at) = (rot * r, pos + rot * at);
            let half = match &c.geometry {
                urdf_rs::Geometry::Cylinder { length, .. } => {
                    (rot * DVec3::Z * length / 2.0).z.abs()
                }
                urdf_rs::Geometry::Box { size } => {
                    (0..3).map(|i| (rot.col(i) * size[i] / 2.0).z.abs()).sum()
                }
                other => panic!("{other:?}"),
            };
            lo = lo.min(at.z - half);
            hi = hi.max(at.z + half);
        }
        (lo * 1000.0, hi * 1000.0)
    };
    let (stub, plate, tool) = (extent("link_6"), extent("flange"), extent("tool0"));
    assert!(plate.0 - stub.1 >= 4.0, "stub {stub:?}, plate {plate:?}");
    assert!(tool.0 - plate.1 >= 4.0, "plate {plate:?}, tool {tool:?}");
}

/// The pairs the SRDF tells MoveIt not to check.
fn disabled(srdf: &str) -> Vec<(String, String)> {
    srdf.lines()
        .filter_map(|l| l.trim().strip_prefix("<disable_collisions link1=\""))
        .map(|rest| {
            let (a, rest) = rest.split_once('"').unwrap();
            let b = rest.split('"').nth(1).unwrap();
            (a.to_string(), b.to_string())
        })
        .collect()
}

/// A link's collision shapes as parry3d shapes, each with its pose in the link's frame.
fn solids(robot: &urdf_rs::Robot, link: &str) -> Vec<(parry3d_f64::math::Pose, Box<dyn Shape>)> {
    use parry3d_f64::shape::{Ball, Cuboid, Cylinder};
    let l = robot.links.iter().find(|l| l.name == link).unwrap();
    l.collision
        .iter()
        .map(|c| {
            let (rot, at) = origin(&c.origin);
            let mut pose = Pose::from_parts(at, DQuat::from_mat3(&rot));
            let shape: Box<dyn Shape> = match &c.geometry {
                urdf_rs::Geometry::Sphere { radius } => Box::new(Ball::new(*radius)),
                urdf_rs::Geometry::Box { size } => {
                    Box::new(Cuboid::new(DVec3::new(size[0], size[1], size[2]) / 2.0))
                }
                urdf_rs::Geometry::Cylinder { radius, length } => {
                    // parry's cylinder stands on its y axis, URDF's on its z.
                    pose *=
                        Pose::from_rotation(DQuat::from_rotation_x(std::f64::consts::FRAC_PI_2));
                    Box::new(Cylinder::new(length / 2.0, *radius))
                }
                other => panic!("{link}: a shape this check does not know: {other:?}"),
            };
            (pose, shape)
        })
        .collect()
}

/// With the gripper, no two links that MoveIt checks (every pair the SRDF does not disable)
/// touch at READY nor at any corner of the joints' range (each joint at one of its limits,
/// 64 poses), the fingers closed or open: a planner sees the arm as free there, as it is.
/// Except where the arm itself runs into itself: with J2 and J3 at their limits one way and
/// J5 at its limit the other, the forearm folds down beside the base and the wrist turns the
/// tool back into the column; there the tool's tip is inside the column's radius, and a
/// planner must see the contact. Distances are exact (parry3d's, of the URDF's own shapes).
#[test]
fn no_two_links_moveit_checks_touch_at_ready_or_at_the_range_s_corners() {
    let robot = urdf_rs::read_from_string(&trol_a465::urdf::urdf_with_gripper()).unwrap();
    let off = disabled(&trol_a465::urdf::srdf_with_gripper());
    let links: Vec<&str> = robot.links.iter().map(|l| l.name.as_str()).collect();
    let mut poses = vec![trol_a465::model::READY];
    for corner in 0..64u32 {
        poses.push(std::array::from_fn(|i| {
            if corner & (1 << i) == 0 {
                -LIMITS_RAD[i]
            } else {
                LIMITS_RAD[i]
            }
        }));
    }
    let mut closest = (f64::INFINITY, String::new());
    let tool_side = ["tool0", "finger_left", "finger_right"];
    let tip_m = (trol_a465::urdf::TOOL_BOX_MM.0.1 + trol_a465::urdf::FINGER_MM.0) / 1000.0;
    let mut folded = std::collections::HashSet::new();
    for q in &poses {
        for gap in [0.0, trol_a465::urdf::GRIP_MAX_MM / 1000.0] {
            let world = |link: &str| -> Vec<(Pose, Box<dyn Shape>)> {
                let (rot, pos) = if link == "base_link" {
                    (DMat3::IDENTITY, DVec3::ZERO)
                } else {
                    chain_gripped(&robot, link, q, gap)
                };
                let at = Pose::from_parts(pos, DQuat::from_mat3(&rot));
                solids(&robot, link)
                    .into_iter()
                    .map(|(p, s)| (at * p, s))
                    .collect()
            };
            for (i, a) in links.iter().enumerate() {
                for b in &links[i + 1..] {
                    let pair = |x: &str, y: &str| (x.to_string(), y.to_string());
                    if off.contains(&pair(a, b)) || off.contains(&pair(b, a)) {
                        continue;
                    }
                    for (pa, sa) in world(a) {
                        for (pb, sb) in world(b) {
                            let d = parry3d_f64::query::distance(&pa, &*sa, &pb, &*sb).unwrap();
                            if d > 0.0 && d < closest.0 {
                                closest = (d, format!("{a} and {b} at {q:?}, gap {gap}"));
                            }
                            if d <= 0.0 {
                                // Only the tool folded back into its own column: a true
                                // contact, which the arm's tool also makes there.
                                assert!(
                                    *a == "link_1" && tool_side.contains(b),
                                    "{a} and {b} touch at {q:?} with the fingers {gap} m apart"
                                );
                                let (rot, pos) = chain(&robot, "tool0", q);
                                let tip = (pos + rot.col(0) * tip_m) * 1000.0;
                                assert!(
                                    tip.truncate().length() < RADIUS_MM[1]
                                        && (0.0..D1).contains(&tip.z),
                                    "{b} touches the column at {q:?}, but the tool's tip is \
                                     not in it: {tip}"
                                );
                                folded.insert(q.map(f64::to_bits));
                            }
                        }
                    }
                }
            }
        }
    }
    eprintln!(
        "the closest two links apart: {:.1} mm, {}",
        closest.0 * 1000.0,
        closest.1
    );
    // The corners with J2 and J3 at their limits one way and J5 the other: the arm folded
    // down beside its base, the tool turned back into it (16 of the 64).
    assert_eq!(folded.len(), 16, "{folded:?}");
}

/// Whether `p` (in the shape's frame, m) lies in `geometry` (1 µm given).
fn inside(geometry: &urdf_rs::Geometry, p: DVec3) -> bool {
    let e = 1e-6;
    match geometry {
        urdf_rs::Geometry::Sphere { radius } => p.length() <= radius + e,
        urdf_rs::Geometry::Cylinder { radius, length } => {
            p.z.abs() <= length / 2.0 + e && (p.x * p.x + p.y * p.y).sqrt() <= radius + e
        }
        urdf_rs::Geometry::Box { size } => (0..3).all(|i| p[i].abs() <= size[i] / 2.0 + e),
        other => panic!("a shape this check does not know: {other:?}"),
    }
}

/// A ray up the stretched arm (READY: every joint 0, the arm straight up the base's axis),
/// from the floor to past the fingers, passes through a collision shape of every link: no
/// part of the arm is left without one for MoveIt to plan through.
#[test]
fn a_ray_along_the_stretched_arm_hits_every_link() {
    let robot = urdf_rs::read_from_string(&trol_a465::urdf::urdf_with_gripper()).unwrap();
    let q = trol_a465::model::READY;
    for l in &robot.links {
        let (rot, pos) = if l.name == "base_link" {
            (DMat3::IDENTITY, DVec3::ZERO)
        } else {
            chain(&robot, &l.name, &q)
        };
        let hit = (0..=1400).any(|mm| {
            let p = DVec3::new(0.0, 0.0, mm as f64 / 1000.0);
            l.collision.iter().any(|c| {
                let (r, at) = origin(&c.origin);
                let (rot, at) = (rot * r, pos + rot * at);
                inside(&c.geometry, rot.transpose() * (p - at))
            })
        });
        assert!(hit, "the ray up the arm misses {}", l.name);
    }
}

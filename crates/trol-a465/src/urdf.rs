//! The A465 as a URDF (Unified Robot Description Format), generated from this crate's model,
//! so that its joints are TROL's: `joint_1` .. `joint_6` have their zero and their positive
//! direction where TROL's joint values have them (no offsets to add), their limits are the
//! model's, and `tool0` is TROL's tool frame at the flange (x out of the flange, docs/a465.md).
//!
//! Links: `base_link`, `link_1` .. `link_6`, `flange` (the DH frame 6: z out of the flange),
//! `tool0`. Lengths in metres, as URDF has them. The geometry is simple (a cylinder from each
//! joint to the next, sized from the published link lengths; a box for the gripper), enough to
//! see the arm move, not a model of its casting.
//!
//! Each revolute joint turns about its z axis. Its fixed origin is the rest of the DH step
//! before it (Tz(d)·Tx(a)·Rx(α)) and the joint's DH offset (Rz(θ₀)), so that the chain
//! `base_link` → `flange` multiplies out to [`crate::kinematics::flange_dh`].

use std::f64::consts::FRAC_PI_2;
use std::fmt::Write;

use glam::{DMat3, DVec3};

use crate::kinematics::Pose;
use crate::model::{A2, D1, D4, D6, LIMITS_RAD, max_speeds};

/// The joints' effort limits, N·m: not published; an assumption of ours (URDF needs a value).
pub const EFFORT_NM: [f64; 6] = [60.0, 60.0, 60.0, 20.0, 20.0, 20.0];

/// The links' masses, kg, `base_link`, `link_1` .. `link_6`, `tool0`: **assumptions** (the
/// A465's weight is not published; about 31 kg in all is ours), so that simulators that
/// need mass and inertia (MuJoCo, pybullet) load the arm. Each link's inertia is that of its
/// cylinder (or sphere), solid, of this mass.
pub const MASS_KG: [f64; 8] = [10.0, 7.0, 6.0, 4.0, 2.0, 1.0, 0.5, 0.5];

/// The flange frame's mass, kg: next to nothing, but given, since a simulator gives a link
/// without one a mass of its own (pybullet: 1 kg and 1 kg m²).
pub const FLANGE_KG: f64 = 0.001;

/// One DH step's fixed part (after the joint's rotation): Tz(d)·Tx(a)·Rx(α).
fn dh_fixed(d: f64, a: f64, alpha: f64) -> Pose {
    Pose {
        rot: DMat3::from_rotation_x(alpha),
        pos: DVec3::new(a, 0.0, d),
    }
}

fn rz(theta: f64) -> Pose {
    Pose {
        rot: DMat3::from_rotation_z(theta),
        pos: DVec3::ZERO,
    }
}

/// The DH table of [`crate::kinematics::flange_dh`]: (offset θ₀, d, a, α) per joint, mm.
const DH: [(f64, f64, f64, f64); 6] = [
    (0.0, D1, 0.0, -FRAC_PI_2),
    (-FRAC_PI_2, 0.0, A2, 0.0),
    (-FRAC_PI_2, 0.0, 0.0, -FRAC_PI_2),
    (0.0, D4, 0.0, FRAC_PI_2),
    (0.0, 0.0, 0.0, -FRAC_PI_2),
    (0.0, D6, 0.0, 0.0),
];

/// The fixed origin of each revolute joint (in its parent link's frame, mm), and of the
/// flange in `link_6`.
pub fn joint_origins() -> ([Pose; 6], Pose) {
    let mut origins = [Pose::IDENTITY; 6];
    for (i, origin) in origins.iter_mut().enumerate() {
        let before = if i == 0 {
            Pose::IDENTITY
        } else {
            let (_, d, a, alpha) = DH[i - 1];
            dh_fixed(d, a, alpha)
        };
        *origin = before.then(&rz(DH[i].0));
    }
    let (_, d, a, alpha) = DH[5];
    (origins, dh_fixed(d, a, alpha))
}

/// The tool frame in the flange's (DH 6) frame: tool x = DH z, tool y = -DH y, tool z = DH x.
pub fn tool_in_flange() -> Pose {
    Pose {
        rot: DMat3::from_cols(DVec3::Z, DVec3::NEG_Y, DVec3::X),
        pos: DVec3::ZERO,
    }
}

/// `xyz="..." rpy="..."` of a pose (mm → m; URDF's rpy is roll about x, pitch about y, yaw
/// about z, R = Rz(yaw)·Ry(pitch)·Rx(roll), the same product as TROL's).
fn origin_attrs(p: &Pose) -> String {
    let v = p.to_xyzypr();
    let n = |x: f64| {
        let s = format!("{x:.9}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        if s == "-0" {
            "0".to_string()
        } else {
            s.to_string()
        }
    };
    format!(
        "xyz=\"{} {} {}\" rpy=\"{} {} {}\"",
        n(v[0] / 1000.0),
        n(v[1] / 1000.0),
        n(v[2] / 1000.0),
        n(v[5]),
        n(v[4]),
        n(v[3])
    )
}

/// How much of each link's length its collision cylinder leaves out at its start and its
/// end, mm (`base_link`, `link_1` .. `link_6`): so that the shapes of links joined by a joint
/// never touch at any pose within the limits (a simulator with contacts on then moves the arm
/// as with them off), with 10 mm to spare at least. The column starts 10 mm above the foot
/// plate and ends 100 mm below the shoulder, where the upper arm starts 80 mm out; the upper
/// arm and the forearm keep 100 mm from the elbow (at J3 = ±110° their ends are
/// 115 mm apart, their radii 95 mm), the forearm 70 mm from the wrist (at J5 = ±105° the
/// tool's box starts 93 mm from it, the radii 76 mm). The stub from the wrist to the flange
/// (link_6) keeps 55 mm from the wrist and 12.2 mm from the flange. Checked over 20,000 random
/// poses by `adjacent_collision_shapes_never_touch` (crates/trol-a465/tests/urdf.rs).
pub const COLLISION_TRIM_MM: [(f64, f64); 7] = [
    (0.0, 0.0),
    (40.0, 100.0),
    (80.0, 100.0),
    (0.0, 0.0),
    (100.0, 70.0),
    (0.0, 0.0),
    (55.0, 12.2),
];

/// The links' radii, mm (`base_link`, `link_1` .. `link_6`): the foot plate's, the column's and
/// the upper arm's 55, the forearm's 40 (the drawing's; the casting is not modelled).
pub const RADIUS_MM: [f64; 7] = [100.0, 55.0, 55.0, 55.0, 40.0, 35.0, 35.0];

/// The radii of the links' collision shapes, mm (`base_link`, `link_1` .. `link_6`): their
/// cylinders' where they have length, else a sphere's at the joint (the elbow's link_3 and
/// the wrist's link_5), each as large as the shapes of the links it joins leave room for with
/// 10 mm to spare; the stub to the flange narrower than its drawing, so that it keeps clear of
/// the forearm with the wrist bent to its limit. Every link of the arm has a shape: MoveIt
/// plans around the whole arm (issue 61).
pub const COLLISION_RADIUS_MM: [f64; 7] = [100.0, 55.0, 55.0, 30.0, 40.0, 12.0, 25.0];

/// The flange's own shape: a plate of this radius and thickness (mm), 1 mm behind the flange
/// face (the tool's box starts 4 mm in front of it; the stub ends 12.2 mm behind it).
pub const FLANGE_PLATE_MM: (f64, f64) = (30.0, 4.0);

/// Where the tool's box (the gripper's body) starts and ends along the tool's x axis, mm from
/// the flange face, and its size across (y, z).
pub const TOOL_BOX_MM: ((f64, f64), (f64, f64)) = ((4.0, 80.0), (60.0, 40.0));

/// A link's collision shape: its radius, and what its cylinder leaves out at each end (mm).
#[derive(Clone, Copy)]
struct Shape {
    radius: f64,
    trim: (f64, f64),
}

/// The collision shape of link `i` (0: `base_link`).
fn shape(i: usize) -> Shape {
    Shape {
        radius: COLLISION_RADIUS_MM[i],
        trim: COLLISION_TRIM_MM[i],
    }
}

/// A cylinder from this link's origin to `to` (mm, in the link's frame): its visual, and its
/// inertia as a solid of `mass` kg; its collision a cylinder of `shape`'s radius, less its
/// trim (none where the trim leaves nothing); a link of no length, a sphere.
fn segment(out: &mut String, to: DVec3, radius_mm: f64, colour: &str, mass: f64, shape: Shape) {
    let len = to.length();
    if len < 1e-6 {
        let r = radius_mm * 1.2 / 1000.0;
        let visual = format!("<geometry><sphere radius=\"{r:.4}\"/></geometry>");
        let i = 0.4 * mass * r * r;
        let _ = writeln!(
            out,
            "    <visual>{visual}<material name=\"{colour}\"/></visual>\n    \
             <inertial><mass value=\"{mass}\"/><inertia ixx=\"{i:.6}\" ixy=\"0\" \
             ixz=\"0\" iyy=\"{i:.6}\" iyz=\"0\" izz=\"{i:.6}\"/></inertial>\n    \
             <collision><geometry><sphere radius=\"{:.4}\"/></geometry></collision>",
            shape.radius / 1000.0
        );
        return;
    }
    // The cylinder's axis (z) along `to`, centred halfway.
    let z = to / len;
    let helper = if z.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let x = helper.cross(z).normalize();
    let y = z.cross(x);
    let pose = Pose {
        rot: DMat3::from_cols(x, y, z),
        pos: to / 2.0,
    };
    let (r, l) = (radius_mm / 1000.0, len / 1000.0);
    let origin = origin_attrs(&pose);
    let visual = format!("<geometry><cylinder radius=\"{r:.4}\" length=\"{l:.4}\"/></geometry>");
    // A solid cylinder about its own axis (z) and across it.
    let (across, along) = (mass * (3.0 * r * r + l * l) / 12.0, mass * r * r / 2.0);
    let _ = writeln!(
        out,
        "    <visual><origin {origin}/>{visual}<material name=\"{colour}\"/></visual>\n    \
         <inertial><origin {origin}/><mass value=\"{mass}\"/><inertia ixx=\"{across:.6}\" \
         ixy=\"0\" ixz=\"0\" iyy=\"{across:.6}\" iyz=\"0\" izz=\"{along:.6}\"/></inertial>"
    );
    let trim = shape.trim;
    let kept = len - trim.0 - trim.1;
    if kept > 1.0 {
        let centre = Pose {
            rot: pose.rot,
            pos: z * (trim.0 + kept / 2.0),
        };
        let _ = writeln!(
            out,
            "    <collision><origin {}/><geometry><cylinder radius=\"{:.4}\" \
             length=\"{:.4}\"/></geometry></collision>",
            origin_attrs(&centre),
            shape.radius / 1000.0,
            kept / 1000.0
        );
    }
}

/// The URDF of the A465, as `trol urdf` prints it.
pub fn urdf() -> String {
    let (origins, flange) = joint_origins();
    let speeds = max_speeds();
    let mut s = String::new();
    s.push_str(
        "<?xml version=\"1.0\"?>\n\
         <!-- The CRS A465, generated by `trol urdf` from trol-a465's model (docs/a465.md):\n     \
         the joints' zero and direction are TROL's; lengths in m, angles in rad. -->\n\
         <robot name=\"crs_a465\">\n  \
         <material name=\"body\"><color rgba=\"0.85 0.85 0.8 1\"/></material>\n  \
         <material name=\"joint\"><color rgba=\"0.3 0.3 0.35 1\"/></material>\n  \
         <material name=\"gripper\"><color rgba=\"0.2 0.45 0.8 1\"/></material>\n",
    );
    // base_link: the foot plate (its size is ours); link_1 is the column up to the shoulder.
    s.push_str("  <link name=\"base_link\">\n");
    segment(
        &mut s,
        DVec3::new(0.0, 0.0, 30.0),
        RADIUS_MM[0],
        "joint",
        MASS_KG[0],
        shape(0),
    );
    s.push_str("  </link>\n");
    let names = [
        "base_link",
        "link_1",
        "link_2",
        "link_3",
        "link_4",
        "link_5",
        "link_6",
    ];
    for i in 0..6 {
        // The link after joint i+1 reaches to the next joint's origin (or the flange).
        let next = if i < 5 {
            origins[i + 1].pos
        } else {
            flange.pos
        };
        let _ = writeln!(s, "  <link name=\"{}\">", names[i + 1]);
        segment(
            &mut s,
            next,
            RADIUS_MM[i + 1],
            if i % 2 == 0 { "body" } else { "joint" },
            MASS_KG[i + 1],
            shape(i + 1),
        );
        s.push_str("  </link>\n");
        let _ = writeln!(
            s,
            "  <joint name=\"joint_{}\" type=\"revolute\">\n    <parent link=\"{}\"/>\n    \
             <child link=\"{}\"/>\n    <origin {}/>\n    <axis xyz=\"0 0 1\"/>\n    \
             <limit lower=\"{:.6}\" upper=\"{:.6}\" velocity=\"{:.6}\" effort=\"{}\"/>\n  \
             </joint>",
            i + 1,
            names[i],
            names[i + 1],
            origin_attrs(&origins[i]),
            -LIMITS_RAD[i],
            LIMITS_RAD[i],
            speeds[i],
            EFFORT_NM[i]
        );
    }
    // The flange's plate, just behind its face (z out of the flange).
    let (plate_r, plate_t) = FLANGE_PLATE_MM;
    let plate = Pose {
        rot: DMat3::IDENTITY,
        pos: DVec3::new(0.0, 0.0, -1.0 - plate_t / 2.0),
    };
    let _ = writeln!(
        s,
        "  <link name=\"flange\">\n    <inertial><mass value=\"{FLANGE_KG}\"/><inertia \
         ixx=\"1e-7\" ixy=\"0\" ixz=\"0\" iyy=\"1e-7\" iyz=\"0\" izz=\"1e-7\"/>\
         </inertial>\n    <collision><origin {}/><geometry><cylinder radius=\"{:.4}\" \
         length=\"{:.4}\"/></geometry></collision>\n  </link>\n  <joint name=\"flange_joint\" \
         type=\"fixed\">\n    <parent link=\"link_6\"/>\n    <child link=\"flange\"/>\n    \
         <origin {}/>\n  </joint>",
        origin_attrs(&plate),
        plate_r / 1000.0,
        plate_t / 1000.0,
        origin_attrs(&flange)
    );
    let ((from, to), (wide, high)) = TOOL_BOX_MM;
    let (l, w, h) = ((to - from) / 1000.0, wide / 1000.0, high / 1000.0);
    let gripper = Pose {
        rot: DMat3::IDENTITY,
        pos: DVec3::new((from + to) / 2.0, 0.0, 0.0),
    };
    let size = format!("{l:.3} {w:.3} {h:.3}");
    let _ = writeln!(
        s,
        "  <link name=\"tool0\">\n    <visual><origin {g}/><geometry><box size=\"{size}\"/>\
         </geometry><material name=\"gripper\"/></visual>\n    <collision><origin \
         {g}/><geometry><box size=\"{size}\"/></geometry></collision>\n    \
         <inertial><origin {g}/><mass value=\"{m}\"/><inertia ixx=\"{ix:.6}\" ixy=\"0\" \
         ixz=\"0\" iyy=\"{iy:.6}\" iyz=\"0\" izz=\"{iz:.6}\"/></inertial>\n  </link>\n  \
         <joint name=\"tool0_joint\" type=\"fixed\">\n    <parent link=\"flange\"/>\n    \
         <child link=\"tool0\"/>\n    <origin {t}/>\n  </joint>",
        g = origin_attrs(&gripper),
        m = MASS_KG[7],
        // A solid box.
        ix = MASS_KG[7] * (w * w + h * h) / 12.0,
        iy = MASS_KG[7] * (l * l + h * h) / 12.0,
        iz = MASS_KG[7] * (l * l + w * w) / 12.0,
        t = origin_attrs(&tool_in_flange())
    );
    s.push_str("</robot>\n");
    s
}

/// The pairs of links MoveIt need not check (`trol urdf --srdf`): each link and the one it
/// hangs from (none of them touch, `COLLISION_TRIM_MM`, but a planner checks what may touch
/// and these cannot without a joint between them breaking).
pub fn srdf() -> String {
    let pairs = [
        ("base_link", "link_1"),
        ("link_1", "link_2"),
        ("link_2", "link_3"),
        ("link_3", "link_4"),
        ("link_4", "link_5"),
        ("link_5", "link_6"),
        ("link_6", "flange"),
        ("flange", "tool0"),
        ("link_6", "tool0"),
    ];
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n\
         <!-- The CRS A465's semantic description for MoveIt, printed by `trol urdf` with its\n     \
         srdf option, beside the URDF (docs/ros2.md). -->\n\
         <robot name=\"crs_a465\">\n  \
         <group name=\"arm\">\n    <chain base_link=\"base_link\" tip_link=\"tool0\"/>\n  \
         </group>\n  \
         <group_state name=\"ready\" group=\"arm\">\n",
    );
    for i in 1..=6 {
        let _ = writeln!(s, "    <joint name=\"joint_{i}\" value=\"0\"/>");
    }
    s.push_str("  </group_state>\n");
    for (a, b) in pairs {
        let _ = writeln!(
            s,
            "  <disable_collisions link1=\"{a}\" link2=\"{b}\" reason=\"Adjacent\"/>"
        );
    }
    s.push_str("</robot>\n");
    s
}

/// The widest gap of the gripper's fingers, mm (the range of TROLGrip's `dist`).
pub const GRIP_MAX_MM: f64 = 50.0;

/// Each finger's box, mm: its length along the tool's x axis (from the end of the tool's box),
/// its thickness across the gap (y), its height (z). An assumption: the fingers' size is not
/// published.
pub const FINGER_MM: (f64, f64, f64) = (40.0, 10.0, 20.0);

/// The fingers as links for a description with the gripper (`trol ros2`, MoveIt): the joint
/// `gripper_joint` whose value is the gap in metres (0 .. [`GRIP_MAX_MM`], GripperCommand's
/// `position`), the fingers apart by it and symmetric about the tool's axis. `finger_right`
/// hangs from `tool0` by `finger_right_joint`, which mimics `gripper_joint` times -0.5 (it
/// stands at -gap/2), and `finger_left` from it by `gripper_joint` (at +gap/2); a program
/// publishes `gripper_joint` only (robot_state_publisher and MoveIt follow the mimic).
pub fn gripper_links() -> String {
    let ((_, tool_end), _) = TOOL_BOX_MM;
    let (len, thick, high) = FINGER_MM;
    let mass = 0.05;
    let (l, t, h) = (len / 1000.0, thick / 1000.0, high / 1000.0);
    let inertia = format!(
        "<inertia ixx=\"{:.8}\" ixy=\"0\" ixz=\"0\" iyy=\"{:.8}\" iyz=\"0\" izz=\"{:.8}\"/>",
        mass * (t * t + h * h) / 12.0,
        mass * (l * l + h * h) / 12.0,
        mass * (l * l + t * t) / 12.0
    );
    let finger = |name: &str, side: f64| {
        let at = Pose {
            rot: DMat3::IDENTITY,
            pos: DVec3::new(tool_end + len / 2.0, side * thick / 2.0, 0.0),
        };
        let o = origin_attrs(&at);
        format!(
            "  <link name=\"{name}\">\n    <visual><origin {o}/><geometry><box size=\"{l:.3} \
             {t:.3} {h:.3}\"/></geometry><material name=\"gripper\"/></visual>\n    \
             <collision><origin {o}/><geometry><box size=\"{l:.3} {t:.3} {h:.3}\"/></geometry>\
             </collision>\n    <inertial><origin {o}/><mass value=\"{mass}\"/>{inertia}\
             </inertial>\n  </link>\n"
        )
    };
    let max = GRIP_MAX_MM / 1000.0;
    format!(
        "{}  <joint name=\"finger_right_joint\" type=\"prismatic\">\n    <parent \
         link=\"tool0\"/>\n    <child link=\"finger_right\"/>\n    <axis xyz=\"0 1 0\"/>\n    \
         <limit lower=\"{:.3}\" upper=\"0\" velocity=\"0.02\" effort=\"50\"/>\n    <mimic \
         joint=\"gripper_joint\" multiplier=\"-0.5\" offset=\"0\"/>\n  </joint>\n{}  <joint \
         name=\"gripper_joint\" type=\"prismatic\">\n    <parent link=\"finger_right\"/>\n    \
         <child link=\"finger_left\"/>\n    <axis xyz=\"0 1 0\"/>\n    <limit lower=\"0\" \
         upper=\"{max:.3}\" velocity=\"0.04\" effort=\"50\"/>\n  </joint>\n",
        finger("finger_right", -1.0),
        -max / 2.0,
        finger("finger_left", 1.0),
    )
}

/// [`urdf`] with the gripper's fingers ([`gripper_links`]).
pub fn urdf_with_gripper() -> String {
    urdf().replacen("</robot>", &format!("{}</robot>", gripper_links()), 1)
}

/// [`srdf`] for [`urdf_with_gripper`]: the group `gripper` (the fingers), the
/// end effector on `tool0`, and the fingers' pairs with the tool and each other (they touch
/// when closed, and cannot part from the tool).
pub fn srdf_with_gripper() -> String {
    // The group by its links, as MoveIt's own examples give a hand: both fingers' joints,
    // the mimic one too.
    let extra = "  <group name=\"gripper\">\n    <link name=\"finger_right\"/>\n    <link \
                 name=\"finger_left\"/>\n  </group>\n  \
                 <group_state name=\"open\" group=\"gripper\">\n    <joint \
                 name=\"gripper_joint\" value=\"0.05\"/>\n  </group_state>\n  \
                 <group_state name=\"closed\" group=\"gripper\">\n    <joint \
                 name=\"gripper_joint\" value=\"0\"/>\n  </group_state>\n  \
                 <end_effector name=\"hand\" parent_link=\"tool0\" group=\"gripper\" \
                 parent_group=\"arm\"/>\n  \
                 <disable_collisions link1=\"tool0\" link2=\"finger_right\" reason=\"Adjacent\"/>\n  \
                 <disable_collisions link1=\"tool0\" link2=\"finger_left\" reason=\"Adjacent\"/>\n  \
                 <disable_collisions link1=\"finger_right\" link2=\"finger_left\" \
                 reason=\"Adjacent\"/>\n";
    srdf().replacen("</robot>", &format!("{extra}</robot>"), 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_comment_holds_two_dashes_which_xml_forbids_there() {
        for doc in [urdf(), srdf()] {
            for comment in doc.split("<!--").skip(1) {
                let body = comment.split("-->").next().unwrap();
                assert!(!body.contains("--"), "an XML comment with `--`: {body}");
            }
        }
    }
    use crate::kinematics::{Kinematics, flange_dh};

    fn rot_diff(a: &Pose, b: &Pose) -> f64 {
        (0..3)
            .map(|c| (a.rot.col(c) - b.rot.col(c)).abs().max_element())
            .fold(0.0, f64::max)
    }

    #[test]
    fn every_link_has_a_collision_shape_and_a_mass() {
        let u = urdf();
        // Every link: base_link, link_1 .. link_6, flange, tool0.
        assert_eq!(u.matches("<collision>").count(), 9, "{u}");
        let g = urdf_with_gripper();
        assert_eq!(g.matches("<collision>").count(), 11, "{g}");
        // Every link has a mass, the flange frame too.
        assert_eq!(u.matches("<inertial>").count(), 9, "{u}");
        assert!(!u.contains("<mass value=\"0\""), "{u}");
    }

    #[test]
    fn the_chain_multiplies_out_to_the_dh_kinematics() {
        let (origins, flange) = joint_origins();
        for q in [
            [0.0; 6],
            [0.3, -0.4, 0.9, 1.2, -0.7, 2.0],
            [-2.5, 1.1, -1.5, -3.0, 1.6, -0.2],
        ] {
            let mut t = Pose::IDENTITY;
            for i in 0..6 {
                t = t.then(&origins[i]).then(&rz(q[i]));
            }
            let f = t.then(&flange);
            let want = flange_dh(&q);
            assert!((f.pos - want.pos).length() < 1e-9, "{q:?}");
            assert!(rot_diff(&f, &want) < 1e-12, "{q:?}");
            let tool = f.then(&tool_in_flange());
            let fk = Kinematics::new([0.0; 6]).fk(&q);
            assert!(rot_diff(&tool, &fk) < 1e-12);
        }
    }
}

//! Forward and closed-form inverse kinematics of the A465, with a tool transform.
//!
//! Conventions (docs/a465.md has the figures):
//! - joint frames follow the standard Denavit-Hartenberg table of `../shared/reference/a465.md`
//!   (θ offsets 0, -90°, -90°, 0, 0, 0; d 330.2, 0, 0, 330.2, 0, 76.2; a 0, 304.8, 0...; α -90°,
//!   0, -90°, +90°, -90°, 0). All joints 0: the arm points straight up. +J1 turns +x toward +y;
//!   +J2 tilts the arm toward +x; +J3 bends the forearm forward.
//! - the *tool frame* sits at the flange centre with its x axis along the last segment, out of
//!   the flange (manual, "Das Roboter-Koordinatensystem", Abbildung 3); y along the world's
//!   y axis when J1 = J4 = J6 = 0 (our choice: the manual does not fix y and z).
//! - a cartesian location is the tool centre point's pose in the world frame:
//!   x y z in mm, and R = Rz(yaw)·Ry(pitch)·Rx(roll) (angles about the world's z, y, x axes).
//!   All joints 0 is (0, 0, 1041.4, 0, -π/2, 0): the tool's x axis points up.
//! - the tool transform places the tool tip in the tool frame (same six-number form); every
//!   cartesian computation goes through it.

use glam::{DMat3, DVec3};
use std::f64::consts::PI;

use crate::model::{A2, D1, D4, D6, limits, within_limits};

/// Six joint angles in radians, joint 1 first.
pub type Joints = [f64; 6];

/// How near pitch ±90° (rad) a pose reads with roll 0 and the whole turn about z as yaw. Nearer
/// the singular pitch yaw and roll turn about almost the same axis, and their split is
/// dominated by noise (an actual pose 0.006° off read yaw 0.3066, roll 0.3066); reading roll 0
/// there changes the orientation by at most twice this angle (1 mrad, 0.06°).
pub const GIMBAL_ZONE: f64 = 5e-4;

/// A rigid transform: rotation then translation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Rotation (columns are the frame's axes in the parent frame).
    pub rot: DMat3,
    /// Origin in the parent frame, mm.
    pub pos: DVec3,
}

impl Pose {
    /// The identity.
    pub const IDENTITY: Pose = Pose {
        rot: DMat3::IDENTITY,
        pos: DVec3::ZERO,
    };

    /// From x y z (mm) and yaw pitch roll (radians), R = Rz(yaw)·Ry(pitch)·Rx(roll).
    pub fn from_xyzypr(v: [f64; 6]) -> Pose {
        let rot = DMat3::from_rotation_z(v[3])
            * DMat3::from_rotation_y(v[4])
            * DMat3::from_rotation_x(v[5]);
        Pose {
            rot,
            pos: DVec3::new(v[0], v[1], v[2]),
        }
    }

    /// x y z yaw pitch roll. At and near pitch ±90° (gimbal lock: within
    /// [`GIMBAL_ZONE`] rad) the roll is 0 and the yaw takes the whole turn about z, for
    /// commanded and actual poses alike (docs/a465.md, "Orientation near pitch ±90°").
    pub fn to_xyzypr(&self) -> [f64; 6] {
        let r = |i: usize, j: usize| self.rot.col(j)[i];
        let cp = (r(0, 0) * r(0, 0) + r(1, 0) * r(1, 0)).sqrt();
        let pitch = (-r(2, 0)).atan2(cp);
        // cos(pitch) = sin(the distance from ±90°).
        let (yaw, roll) = if cp >= GIMBAL_ZONE.sin() {
            (r(1, 0).atan2(r(0, 0)), r(2, 1).atan2(r(2, 2)))
        } else {
            // R = Rz(yaw)·Ry(±90°): the roll cannot be told from the yaw.
            ((-r(0, 1)).atan2(r(1, 1)), 0.0)
        };
        [self.pos.x, self.pos.y, self.pos.z, yaw, pitch, roll]
    }

    /// `self` followed by `other` (other expressed in self's frame).
    pub fn then(&self, other: &Pose) -> Pose {
        Pose {
            rot: self.rot * other.rot,
            pos: self.pos + self.rot * other.pos,
        }
    }

    /// The inverse transform.
    pub fn inverse(&self) -> Pose {
        let rt = self.rot.transpose();
        Pose {
            rot: rt,
            pos: -(rt * self.pos),
        }
    }
}

/// One DH step: Rz(θ)·Tz(d)·Tx(a)·Rx(α).
fn dh(theta: f64, d: f64, a: f64, alpha: f64) -> Pose {
    let (st, ct) = theta.sin_cos();
    let (sa, ca) = alpha.sin_cos();
    Pose {
        rot: DMat3::from_cols(
            DVec3::new(ct, st, 0.0),
            DVec3::new(-st * ca, ct * ca, sa),
            DVec3::new(st * sa, -ct * sa, ca),
        ),
        pos: DVec3::new(a * ct, a * st, d),
    }
}

const HALF_PI: f64 = PI / 2.0;

/// DH frame 6 (the flange, z out of it) in the base frame.
pub fn flange_dh(q: &Joints) -> Pose {
    dh(q[0], D1, 0.0, -HALF_PI)
        .then(&dh(q[1] - HALF_PI, 0.0, A2, 0.0))
        .then(&dh(q[2] - HALF_PI, 0.0, 0.0, -HALF_PI))
        .then(&dh(q[3], D4, 0.0, HALF_PI))
        .then(&dh(q[4], 0.0, 0.0, -HALF_PI))
        .then(&dh(q[5], D6, 0.0, 0.0))
}

/// The tool frame's axes in DH frame 6: tool x = DH z (out of the flange), tool y = -DH y,
/// tool z = DH x. With J4 = J6 = 0 and J1 = 0 the tool's y axis is the world's y axis, so
/// the upright zero pose is (yaw 0, pitch -90°, roll 0) and the tool pointing straight down
/// is (yaw 0, pitch 90°, roll 0), both with J4 and J6 in the middle of their ranges.
fn tool_in_dh6() -> DMat3 {
    DMat3::from_cols(DVec3::Z, DVec3::NEG_Y, DVec3::X)
}

/// Wrap an angle into (-π, π].
pub fn wrap(a: f64) -> f64 {
    let mut x = (a + PI).rem_euclid(2.0 * PI) - PI;
    if x <= -PI {
        x += 2.0 * PI;
    }
    x
}

/// Wrap an angle within one turn of (-π, π] into it (cheaper than [`wrap`]).
#[inline]
fn wrap_once(a: f64) -> f64 {
    if a > PI {
        a - 2.0 * PI
    } else if a <= -PI {
        a + 2.0 * PI
    } else {
        a
    }
}

/// Which of the arm's configurations a solution is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Config {
    /// Reaching backward, over the head (J1 turned half a turn from the wrist's direction).
    pub backward: bool,
    /// Elbow below the line from shoulder to wrist.
    pub elbow_down: bool,
    /// Wrist flipped (J5 negative in the forward sense).
    pub flip: bool,
}

impl std::fmt::Display for Config {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // CRS's own letters: Forward/Backward, Up/Down, Noflip/Flip.
        write!(
            f,
            "{}{}{}",
            if self.backward { 'B' } else { 'F' },
            if self.elbow_down { 'D' } else { 'U' },
            if self.flip { 'F' } else { 'N' }
        )
    }
}

/// One inverse-kinematics solution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Solution {
    /// The joint angles, each wrapped into (-π, π].
    pub q: Joints,
    /// Its configuration.
    pub config: Config,
    /// Whether every joint is within its limits.
    pub within_limits: bool,
}

/// Every solution for a pose: up to 8.
#[derive(Clone, Copy, Debug)]
pub struct Solutions {
    items: [Solution; 8],
    len: usize,
}

impl Solution {
    /// A placeholder in the unused part of [`Solutions`].
    const NONE: Solution = Solution {
        q: [0.0; 6],
        config: Config {
            backward: false,
            elbow_down: false,
            flip: false,
        },
        within_limits: false,
    };
}

impl Solutions {
    /// No solution (the pose is out of reach).
    fn none() -> Solutions {
        Solutions {
            items: [Solution::NONE; 8],
            len: 0,
        }
    }

    /// The solutions.
    pub fn as_slice(&self) -> &[Solution] {
        &self.items[..self.len]
    }

    /// How many.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether there are none (the pose is out of reach).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

/// Why no joint angles reach a pose.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IkError {
    /// The wrist centre is farther from (or nearer to) the shoulder than the arm can reach.
    OutOfReach,
    /// Every solution has a joint outside its limits; `joint` (1..6) of the nearest one.
    JointLimit {
        /// The joint, 1-based.
        joint: usize,
    },
}

impl std::fmt::Display for IkError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            IkError::OutOfReach => write!(f, "the pose is out of the arm's reach"),
            IkError::JointLimit { joint } => {
                write!(f, "every configuration puts joint {joint} beyond its limit")
            }
        }
    }
}

impl std::error::Error for IkError {}

/// How far outside the arm's reach (or inside its inner limit) a wrist centre may lie and
/// still count as on the edge: 0.001 mm, the precision TROL prints (a pose read over the
/// line as f32 carries about 2.5e-5 mm of rounding at the full reach).
pub const REACH_TOLERANCE_MM: f64 = 1e-3;

/// Below this the wrist centre counts as on the base axis (a singular case).
const SINGULAR: f64 = 1e-9;

/// Below this sin(J5) counts as 0, where only J4 + J6 is fixed and J4 keeps its value. A pose
/// that crossed the line as f32 (TROL's wire format) carries about 1e-7 of rounding, which
/// must not pick an arbitrary J4; 1e-6 rad of wrist is 0.0002 mm at a 200 mm tool.
const WRIST_SINGULAR: f64 = 1e-6;

/// Solve the 5x5 system in `a` (each row its five coefficients and the right-hand side) by
/// elimination with partial pivoting; `None` when it is singular.
fn solve5(mut a: [[f64; 6]; 5]) -> Option<[f64; 5]> {
    for col in 0..5 {
        let pivot = (col..5).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[pivot][col].abs() < 1e-300 {
            return None;
        }
        a.swap(col, pivot);
        let pivot_row = a[col];
        for row in a.iter_mut().skip(col + 1) {
            let f = row[col] / pivot_row[col];
            for (x, p) in row.iter_mut().zip(pivot_row).skip(col) {
                *x -= f * p;
            }
        }
    }
    let mut x = [0.0; 5];
    for row in (0..5).rev() {
        let sum: f64 = (row + 1..5).map(|k| a[row][k] * x[k]).sum();
        x[row] = (a[row][5] - sum) / a[row][row];
    }
    Some(x)
}

/// How far J5 may be from 0 and still count as 0, where J4 keeps its value ([`wrist_band`]):
/// the rounding of a pose sent as f32 (TROL's wire), about 1e-7 of it, which near a
/// stretched elbow becomes a wrist angle of up to this much.
const WRIST_BAND_MAX: f64 = 2e-3;

/// How much J5 the f32 rounding of a pose can cause at an elbow whose |sin J3| is
/// `s3_abs`: about 3e-7 / |sin J3| (the law of cosines turns a length's error into an
/// angle's divided by sin J3), at least [`WRIST_SINGULAR`] and at most [`WRIST_BAND_MAX`].
/// Within it J4 keeps its value (issue 42: near the stretched elbow it took whatever the
/// rounding said in 94 % of 400 cases).
fn wrist_band(s3_abs: f64) -> f64 {
    (3e-7 / s3_abs.max(1e-12)).clamp(WRIST_SINGULAR, WRIST_BAND_MAX)
}

/// The arm's kinematics with a tool transform.
#[derive(Clone, Copy, Debug)]
pub struct Kinematics {
    tool: Pose,
    tool_inv: Pose,
    /// The tool's inverse rotation into DH frame 6, once (the inverse kinematics' first
    /// product).
    tool_inv_dh6: DMat3,
}

impl Default for Kinematics {
    fn default() -> Self {
        Kinematics::new([0.0; 6])
    }
}

/// Four atan2(y, x) at once (SIMD; within 2 ulp of `f64::atan2`): the inverse kinematics
/// makes its ten in three such batches.
#[inline]
fn atan2x4(y: [f64; 4], x: [f64; 4]) -> [f64; 4] {
    wide::f64x4::from(y).atan2(wide::f64x4::from(x)).to_array()
}

impl Kinematics {
    /// Kinematics with the tool transform `tool` (x y z mm, yaw pitch roll rad, in the tool
    /// frame).
    pub fn new(tool: [f64; 6]) -> Kinematics {
        let tool = Pose::from_xyzypr(tool);
        let tool_inv = tool.inverse();
        Kinematics {
            tool,
            tool_inv,
            tool_inv_dh6: tool_inv.rot * tool_in_dh6().transpose(),
        }
    }

    /// The tool transform.
    pub fn tool(&self) -> [f64; 6] {
        self.tool.to_xyzypr()
    }

    /// Forward kinematics: the tool centre point's pose.
    pub fn fk(&self, q: &Joints) -> Pose {
        let f = flange_dh(q);
        let flange_tool = Pose {
            rot: f.rot * tool_in_dh6(),
            pos: f.pos,
        };
        flange_tool.then(&self.tool)
    }

    /// Forward kinematics as a cartesian location.
    pub fn fk_xyzypr(&self, q: &Joints) -> [f64; 6] {
        self.fk(q).to_xyzypr()
    }

    /// Every joint solution for the tool centre point at `tcp`. `current` settles the
    /// singular cases: on the base axis J1 keeps its value, at J5 = 0 J4 keeps its value.
    ///
    /// Closed form, with as few trigonometric calls as the geometry allows:
    /// - the wrist centre gives J1, and J2, J3 two ways (elbow up, down) by the law of
    ///   cosines; the sines and cosines of J2 + J3 follow by angle addition, not by calls;
    /// - J2 and J3 turn about parallel axes, so the arm's rotation R03 depends on J1 and
    ///   J2 + J3 only and is written out; the wrist's rotation R03ᵀ·R06 = Rz(J4)·Ry(-J5)·Rz(J6)
    ///   gives J4..J6, and the flipped wrist is (J4 + 180°, -J5, J6 + 180°);
    /// - reaching backward mirrors the arm: (J1 + 180°, -J2, -J3) has R03·Rz(180°), so its
    ///   wrist is (J4 + 180°, J5, J6) of the forward one with the same elbow.
    pub fn ik_all(&self, tcp: &Pose, current: &Joints) -> Solutions {
        self.ik_all_with(tcp, current, true)
    }

    /// [`Kinematics::ik_all`] without the rounding band: J5 counts as 0 only within
    /// [`WRIST_SINGULAR`]. For the samples of a path, whose J4 must follow the pose
    /// continuously rather than stay put near J5 = 0.
    pub fn ik_all_exact(&self, tcp: &Pose, current: &Joints) -> Solutions {
        self.ik_all_with(tcp, current, false)
    }

    fn ik_all_with(&self, tcp: &Pose, current: &Joints, rounding_band: bool) -> Solutions {
        let flange_pos = tcp.pos + tcp.rot * self.tool_inv.pos;
        let r06 = tcp.rot * self.tool_inv_dh6;
        let w = flange_pos - r06.z_axis * D6;
        let out = Solutions::none();
        let rxy = (w.x * w.x + w.y * w.y).sqrt();
        let s = w.z - D1;
        let l2 = rxy * rxy + s * s;
        let c3 = (l2 - A2 * A2 - D4 * D4) / (2.0 * A2 * D4);
        // A pose at the edge of the reach that came over the line as f32 (READY read with
        // GetPosition and sent back) lies a few hundredths of a micrometre outside it: within
        // REACH_TOLERANCE_MM of the edge counts as on it.
        let tol = l2.sqrt() * REACH_TOLERANCE_MM / (A2 * D4) + 1e-12;
        if !(-1.0 - tol..=1.0 + tol).contains(&c3) {
            return out;
        }
        let c3 = c3.clamp(-1.0, 1.0);
        let s3_abs = (1.0 - c3 * c3).sqrt();
        let l = l2.sqrt();
        if l < SINGULAR {
            // The wrist centre on the shoulder axis: unreachable while A2 ≠ D4 (c3 < -1
            // above); kept so that the divisions below never divide by zero.
            return out;
        }
        // J1; the shoulder-wrist line's angle φ from the vertical toward the reach; J3; and
        // the upper arm's angle β from that line (positive sin J3; the elbow down mirrors β
        // and J3): four atan2 at once.
        let [q1_base, phi, q3_pos, beta_pos] =
            atan2x4([w.y, rxy, s3_abs, D4 * s3_abs], [w.x, s, c3, A2 + D4 * c3]);
        let (q1, s1, c1) = if rxy > SINGULAR {
            (q1_base, w.y / rxy, w.x / rxy)
        } else {
            let (s1, c1) = current[0].sin_cos();
            (current[0], s1, c1)
        };
        let (sphi, cphi) = (rxy / l, s / l);
        let (sbeta_pos, cbeta_pos) = (D4 * s3_abs / l, (A2 + D4 * c3) / l);
        let z6 = r06.z_axis;
        // Per elbow: J2, J3 and the wrist forward and backward (None where J5 = ±180°).
        type Wrist = (f64, f64, f64);
        // Both elbows' frame 3 first, then their eight atan2 (J4, J5, J6, and J4 + J6 for
        // J5 = 0) back to back.
        let mut q23 = [(0.0, 0.0); 2];
        let mut wrist_y = [[0.0; 4]; 2];
        let mut wrist_x = [[0.0; 4]; 2];
        let mut e22s = [0.0; 2];
        let mut sws = [0.0; 2];
        for (e, sign) in [1.0, -1.0].into_iter().enumerate() {
            let q3 = sign * q3_pos;
            let q2 = wrap_once(phi - sign * beta_pos);
            // sin, cos of J2 = φ - β, then of J2 + J3.
            let (sb, cb) = (sign * sbeta_pos, cbeta_pos);
            let (s2, c2) = (sphi * cb - cphi * sb, cphi * cb + sphi * sb);
            let (s3, c3) = (sign * s3_abs, c3);
            let (s23, c23) = (s2 * c3 + c2 * s3, c2 * c3 - s2 * s3);
            // DH frame 3 in the base frame: Rz(J1)·Rx(-90°)·Rz(J2 + J3 - 180°)·Rx(-90°).
            let (c, sn) = (-c23, -s23);
            let x3 = DVec3::new(c1 * c, s1 * c, -sn);
            let y3 = DVec3::new(s1, -c1, 0.0);
            let z3 = DVec3::new(-c1 * sn, -s1 * sn, -c);
            let e02 = x3.dot(z6);
            let e12 = y3.dot(z6);
            let e22 = z3.dot(z6);
            let sw = (e02 * e02 + e12 * e12).sqrt();
            q23[e] = (q2, q3);
            e22s[e] = e22;
            sws[e] = sw;
            wrist_y[e] = [e12, sw, z3.dot(r06.y_axis), y3.dot(r06.x_axis)];
            wrist_x[e] = [e02, e22, -z3.dot(r06.x_axis), x3.dot(r06.x_axis)];
        }
        let angles = [
            atan2x4(wrist_y[0], wrist_x[0]),
            atan2x4(wrist_y[1], wrist_x[1]),
        ];
        let mut elbows: [Option<(f64, f64, Wrist, Wrist)>; 2] = [None, None];
        // Elbows whose J5 was taken as 0 within the rounding band: refined below.
        let mut banded = [false; 2];
        for e in 0..2 {
            let [q4, q5_neg, q6, sum] = angles[e];
            let (q2, q3) = q23[e];
            // Within the band the rounding of a pose can put J5 in at this elbow angle, J5
            // counts as 0 (see wrist_band).
            let band = if rounding_band {
                wrist_band(s3_abs)
            } else {
                WRIST_SINGULAR
            };
            banded[e] = sws[e] > WRIST_SINGULAR && sws[e] <= band;
            // (J4, J5, J6) forward and backward.
            elbows[e] = if sws[e] > band {
                let q5 = -q5_neg;
                Some((q2, q3, (q4, q5, q6), (wrap_once(q4 + PI), q5, q6)))
            } else if e22s[e] > 0.0 {
                // J5 = 0: only J4 + J6 is fixed; keep J4, and take what J5 the pose has in
                // its plane (0 at the singular pose itself).
                let q4 = wrap(current[3]);
                let (s4, c4) = q4.sin_cos();
                let q5 = -(wrist_x[e][0] * c4 + wrist_y[e][0] * s4)
                    .clamp(-1.0, 1.0)
                    .asin();
                Some((
                    q2,
                    q3,
                    (q4, q5, wrap_once(sum - q4)),
                    (q4, q5, wrap(sum + PI - q4)),
                ))
            } else {
                // J5 = ±180°: beyond its ±105° limit, so no usable solution.
                None
            };
        }
        let q1_back = wrap_once(q1 + PI);
        let mut out = Solutions::none();
        for (e, el) in elbows.iter().enumerate() {
            let Some((q2, q3, fwd, bwd)) = *el else {
                continue;
            };
            for backward in [false, true] {
                let ([a1, a2, a3], (q4, q5, q6)) = if backward {
                    ([q1_back, -q2, -q3], bwd)
                } else {
                    ([q1, q2, q3], fwd)
                };
                for flip in [false, true] {
                    let mut q = if flip {
                        [a1, a2, a3, wrap_once(q4 + PI), -q5, wrap_once(q6 + PI)]
                    } else {
                        [a1, a2, a3, q4, q5, q6]
                    };
                    if banded[e] {
                        q = self.refine_keeping_j4(tcp, q);
                    }
                    out.items[out.len] = Solution {
                        q,
                        config: Config {
                            backward,
                            elbow_down: e == 1,
                            flip,
                        },
                        within_limits: within_limits(&q),
                    };
                    out.len += 1;
                }
            }
        }
        out
    }

    /// `q` moved so that its pose is `tcp` as nearly as the other five joints allow, J4 kept
    /// (Gauss-Newton with a little damping, a few steps): where J5 was taken as 0 within the
    /// rounding band, the closed form's split between the elbow and the wrist is off by that
    /// rounding, magnified near the stretched elbow; this puts the pose back to what the
    /// rounding allows.
    fn refine_keeping_j4(&self, tcp: &Pose, mut q: Joints) -> Joints {
        // Orientation counts as the distance it moves a point 100 mm away.
        const R: f64 = 100.0;
        const FREE: [usize; 5] = [0, 1, 2, 4, 5];
        let error = |q: &Joints| -> [f64; 6] {
            let p = self.fk(q);
            let d = tcp.pos - p.pos;
            let rot = glam::DQuat::from_mat3(&(tcp.rot * p.rot.transpose())).to_scaled_axis();
            [d.x, d.y, d.z, rot.x * R, rot.y * R, rot.z * R]
        };
        let norm = |e: &[f64; 6]| e.iter().map(|x| x * x).sum::<f64>().sqrt();
        let mut e = error(&q);
        for _ in 0..8 {
            if norm(&e) < 1e-9 {
                break;
            }
            let h = 1e-7;
            let mut jac = [[0.0; 5]; 6];
            for (c, &j) in FREE.iter().enumerate() {
                let mut qh = q;
                qh[j] += h;
                let eh = error(&qh);
                for r in 0..6 {
                    // d(pose)/dq = -d(error)/dq
                    jac[r][c] = (e[r] - eh[r]) / h;
                }
            }
            // (JᵀJ + λI) dq = Jᵀe
            let mut a = [[0.0; 6]; 5];
            for i in 0..5 {
                for k in 0..5 {
                    a[i][k] = (0..6).map(|r| jac[r][i] * jac[r][k]).sum::<f64>();
                }
                a[i][i] += 1e-9;
                a[i][5] = (0..6).map(|r| jac[r][i] * e[r]).sum::<f64>();
            }
            let Some(dq) = solve5(a) else {
                break;
            };
            let mut next = q;
            for (c, &j) in FREE.iter().enumerate() {
                next[j] += dq[c];
            }
            let e_next = error(&next);
            if norm(&e_next) >= norm(&e) {
                break;
            }
            q = next;
            e = e_next;
        }
        q
    }

    /// The solution within the limits nearest to `current` (the one a motion takes).
    pub fn ik_nearest(&self, tcp: &Pose, current: &Joints) -> Result<Joints, IkError> {
        let all = self.ik_all(tcp, current);
        if all.is_empty() {
            return Err(IkError::OutOfReach);
        }
        let dist = |q: &Joints| -> f64 {
            q.iter()
                .zip(current)
                .map(|(a, b)| wrap(a - b).powi(2))
                .sum()
        };
        let best = all
            .as_slice()
            .iter()
            .filter(|s| s.within_limits)
            .min_by(|a, b| dist(&a.q).total_cmp(&dist(&b.q)));
        match best {
            Some(s) => Ok(s.q),
            None => {
                let nearest = all
                    .as_slice()
                    .iter()
                    .min_by(|a, b| dist(&a.q).total_cmp(&dist(&b.q)))
                    .expect("not empty");
                let lim = limits();
                let joint = (0..6)
                    .find(|&i| nearest.q[i].abs() > lim[i] + 1e-9)
                    .unwrap_or(0);
                Err(IkError::JointLimit { joint: joint + 1 })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: [f64; 3], b: [f64; 3]) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-9)
    }

    #[test]
    fn fk_matches_the_published_checks() {
        let k = Kinematics::default();
        let deg = |v: [f64; 6]| v.map(f64::to_radians);
        let p = |q| {
            let x = k.fk_xyzypr(&deg(q));
            [x[0], x[1], x[2]]
        };
        assert!(close(p([0.0; 6]), [0.0, 0.0, 1041.4]));
        assert!(close(
            p([0.0, 90.0, 0.0, 0.0, 0.0, 0.0]),
            [711.2, 0.0, 330.2]
        ));
        assert!(close(
            p([0.0, 0.0, 90.0, 0.0, 0.0, 0.0]),
            [406.4, 0.0, 635.0]
        ));
        assert!(close(
            p([90.0, 0.0, 90.0, 0.0, 0.0, 0.0]),
            [0.0, 406.4, 635.0]
        ));
        // (0,0,90,0,90,0): tool straight down at x 330.2, z 558.8.
        let down = k.fk_xyzypr(&deg([0.0, 0.0, 90.0, 0.0, 90.0, 0.0]));
        assert!(
            close([down[0], down[1], down[2]], [330.2, 0.0, 558.8]),
            "{down:?}"
        );
        assert!((down[4] - HALF_PI).abs() < 1e-9, "pitch {down:?}");
        assert!(
            down[3].abs() < 1e-9 && down[5].abs() < 1e-9,
            "yaw, roll {down:?}"
        );
        let up = k.fk_xyzypr(&[0.0; 6]);
        assert!((up[4] + HALF_PI).abs() < 1e-9, "zero pose pitch {up:?}");
        assert!(up[3].abs() < 1e-9 && up[5].abs() < 1e-9, "yaw, roll {up:?}");
        // Off the gimbal lock: J5 at 30° tilts the tool 30° forward from up; J6 turns it
        // about its own x axis (the roll).
        let tilt = k.fk_xyzypr(&deg([0.0, 0.0, 0.0, 0.0, 30.0, 0.0]));
        assert!((tilt[4] + 60f64.to_radians()).abs() < 1e-9, "{tilt:?}");
        assert!(tilt[3].abs() < 1e-9 && tilt[5].abs() < 1e-9, "{tilt:?}");
    }

    /// The rule near pitch ±90° (docs/a465.md): roll 0 within GIMBAL_ZONE, the orientation
    /// kept to within twice that angle; outside it, the angles as given.
    #[test]
    fn near_the_singular_pitch_the_roll_reads_0_and_the_orientation_is_kept() {
        // The angle between two rotations, from the Frobenius norm of their difference
        // (2√2·sin(θ/2)): exact for small angles, where acos of the trace is not.
        let angle_between = |a: &Pose, b: &Pose| {
            let d = a.rot - b.rot;
            let f =
                (d.x_axis.length_squared() + d.y_axis.length_squared() + d.z_axis.length_squared())
                    .sqrt();
            2.0 * (f / (2.0 * std::f64::consts::SQRT_2)).min(1.0).asin()
        };
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for i in 0..2000 {
            let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
            let off = GIMBAL_ZONE * 3.0 * next();
            let v = [
                1.0,
                2.0,
                3.0,
                (next() * 2.0 - 1.0) * 3.1,
                sign * (std::f64::consts::FRAC_PI_2 - off),
                (next() * 2.0 - 1.0) * 3.1,
            ];
            let pose = Pose::from_xyzypr(v);
            let read = pose.to_xyzypr();
            let back = Pose::from_xyzypr(read);
            if off < GIMBAL_ZONE * 0.999 {
                assert_eq!(read[5], 0.0, "{v:?} -> {read:?}");
                assert!(
                    angle_between(&pose, &back) <= 2.0 * GIMBAL_ZONE,
                    "{v:?} -> {read:?}: {}",
                    angle_between(&pose, &back)
                );
            } else if off > GIMBAL_ZONE * 1.001 {
                assert!(angle_between(&pose, &back) < 1e-9, "{v:?} -> {read:?}");
            }
        }
    }

    #[test]
    fn xyzypr_round_trips() {
        for v in [
            [1.0, 2.0, 3.0, 0.3, -0.4, 1.2],
            [0.0, 0.0, 0.0, -2.0, 1.0, -3.0],
        ] {
            let back = Pose::from_xyzypr(v).to_xyzypr();
            for i in 0..6 {
                assert!((back[i] - v[i]).abs() < 1e-12, "{v:?} {back:?}");
            }
        }
    }
}

//! The WORLD row's angles and a cartesian location's (`cloc`) values: x, y, z (mm), then
//! three angles (degrees) headed `Z-Rot Y-Rot X-Rot`. How they compose is an open point
//! (docs/c500c.md, "Every assumption"); the two readings of that header are [`Angles`].
//! TROL's own convention is R = Rz(yaw)·Ry(pitch)·Rx(roll) ([`Pose::from_xyzypr`]).

use serde::{Deserialize, Serialize};
use trol_a465::kinematics::Pose;

/// How the three printed angles (a, b, c, in the order printed) make the rotation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Angles {
    /// R = Rz(a)·Ry(b)·Rx(c): rotations about z, then the new y, then the new x (TROL's
    /// yaw, pitch, roll).
    Zyx,
    /// R = Rx(c)·Ry(b)·Rz(a): about z, then the fixed y, then the fixed x, in the order
    /// printed.
    Xyz,
}

impl Angles {
    /// Both readings.
    pub const ALL: [Angles; 2] = [Angles::Zyx, Angles::Xyz];

    /// The profile's word for it.
    pub fn word(self) -> &'static str {
        match self {
            Angles::Zyx => "zyx",
            Angles::Xyz => "xyz",
        }
    }
}

/// How ash's WORLD row and a cartesian location's values read: the order of the three
/// angles, and the frame they turn. That frame is the flange's as ash's kinematics set its
/// axes: TROL's tool frame turned by a fixed rotation (`frame`, yaw pitch roll in degrees,
/// right angles; R_ash = R_TROL · R(frame)). Public kinematic models of the A465 have their
/// flange frame's axes along the world's with every joint at 0, where TROL's tool frame is
/// pitched by -90 degrees: such a controller's frame is [0, 90, 0]. Which one ash uses is not
/// public (docs/c500c.md): `trol c500c step world-angles` reads it off the arm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reading {
    /// The angles' order.
    pub angles: Angles,
    /// The frame's turn against TROL's tool frame, yaw pitch roll, degrees.
    pub frame: [f64; 3],
}

impl From<Angles> for Reading {
    fn from(angles: Angles) -> Reading {
        Reading {
            angles,
            frame: [0.0; 3],
        }
    }
}

impl Reading {
    fn turn(&self) -> glam::DMat3 {
        Pose::from_xyzypr([
            0.0,
            0.0,
            0.0,
            self.frame[0].to_radians(),
            self.frame[1].to_radians(),
            self.frame[2].to_radians(),
        ])
        .rot
    }

    /// In words, as the profile writes it.
    pub fn words(&self) -> String {
        format!(
            "world-angles = \"{}\", tool-rotation = [{}, {}, {}]",
            self.angles.word(),
            self.frame[0],
            self.frame[1],
            self.frame[2]
        )
    }
}

/// A right-angle turn (yaw pitch roll, degrees) and how far a rotation is from it (degrees).
pub type Fit = ([f64; 3], f64);

/// The right-angle rotation nearest `r` (each element rounded to -1, 0 or 1), where that is
/// a rotation, and the angle between the two (degrees).
pub fn nearest_right_angles(r: &glam::DMat3) -> Option<Fit> {
    let snap = |v: glam::DVec3| glam::DVec3::new(v.x.round(), v.y.round(), v.z.round());
    let s = glam::DMat3::from_cols(snap(r.x_axis), snap(r.y_axis), snap(r.z_axis));
    let unit = |v: glam::DVec3| (v.length() - 1.0).abs() < 1e-9;
    if !(unit(s.x_axis) && unit(s.y_axis) && unit(s.z_axis)) || (s.determinant() - 1.0).abs() > 1e-9
    {
        return None;
    }
    let d = s.transpose() * *r;
    let cos = ((d.x_axis.x + d.y_axis.y + d.z_axis.z - 1.0) / 2.0).clamp(-1.0, 1.0);
    let ypr = Pose {
        rot: s,
        pos: glam::DVec3::ZERO,
    }
    .to_xyzypr();
    // Right angles, in whole degrees (and never -0).
    let deg = |a: f64| ((a.to_degrees() / 90.0).round() * 90.0) + 0.0;
    Some((
        [deg(ypr[3]), deg(ypr[4]), deg(ypr[5])],
        cos.acos().to_degrees(),
    ))
}

/// A pose as ash prints it: x, y, z (mm), the angles in degrees.
pub fn to_ash(p: &Pose, reading: impl Into<Reading>) -> [f64; 6] {
    let r = reading.into();
    let p = &Pose {
        rot: p.rot * r.turn(),
        pos: p.pos,
    };
    let v = match r.angles {
        Angles::Zyx => p.to_xyzypr(),
        Angles::Xyz => {
            // Rx(c)·Ry(b)·Rz(a) is the transpose of Rz(-a)·Ry(-b)·Rx(-c).
            let t = Pose {
                rot: p.rot.transpose(),
                pos: p.pos,
            }
            .to_xyzypr();
            [t[0], t[1], t[2], -t[3], -t[4], -t[5]]
        }
    };
    [
        v[0],
        v[1],
        v[2],
        v[3].to_degrees(),
        v[4].to_degrees(),
        v[5].to_degrees(),
    ]
}

/// The pose (TROL's tool frame) of values as ash prints them.
pub fn from_ash(v: &[f64; 6], reading: impl Into<Reading>) -> Pose {
    let r = reading.into();
    let (a, b, c) = (v[3].to_radians(), v[4].to_radians(), v[5].to_radians());
    let printed = match r.angles {
        Angles::Zyx => Pose::from_xyzypr([v[0], v[1], v[2], a, b, c]),
        Angles::Xyz => {
            let t = Pose::from_xyzypr([v[0], v[1], v[2], -a, -b, -c]);
            Pose {
                rot: t.rot.transpose(),
                pos: t.pos,
            }
        }
    };
    Pose {
        rot: printed.rot * r.turn().transpose(),
        pos: printed.pos,
    }
}

/// How far apart two poses are: the distance of their origins (mm) and the angle of the
/// rotation between them (degrees).
pub fn gap(a: &Pose, b: &Pose) -> (f64, f64) {
    let d = (a.pos - b.pos).length();
    let r = a.rot.transpose() * b.rot;
    let cos = ((r.x_axis.x + r.y_axis.y + r.z_axis.z - 1.0) / 2.0).clamp(-1.0, 1.0);
    (d, cos.acos().to_degrees())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_reading_goes_there_and_back() {
        let p = Pose::from_xyzypr([400.0, -20.0, 150.0, 0.3, 1.1, -0.4]);
        for a in Angles::ALL {
            let v = to_ash(&p, a);
            let (d, deg) = gap(&from_ash(&v, a), &p);
            assert!(d < 1e-9 && deg < 1e-6, "{a:?}: {d} {deg}");
            // And in a frame turned by right angles: the printed values differ, the pose
            // read back is the same, and the turn is found again from the two.
            for frame in [[0.0, 90.0, 0.0], [90.0, 0.0, 180.0], [-90.0, 0.0, 90.0]] {
                let r = Reading { angles: a, frame };
                let turned = to_ash(&p, r);
                let (d, deg) = gap(&from_ash(&turned, r), &p);
                assert!(d < 1e-9 && deg < 1e-6, "{r:?}: {d} {deg}");
                assert!(gap(&from_ash(&turned, a), &p).1 > 1.0, "{r:?}");
                let (found, off) =
                    nearest_right_angles(&(p.rot.transpose() * from_ash(&turned, a).rot))
                        .expect("a right-angle turn");
                let again = Reading {
                    angles: a,
                    frame: found,
                };
                assert!(off < 1e-6, "{r:?}: {off}");
                assert!(
                    gap(&from_ash(&turned, again), &p).1 < 1e-6,
                    "{r:?} as {found:?}"
                );
            }
        }
        // A turn that is no right angle has none.
        let odd = Pose::from_xyzypr([0.0, 0.0, 0.0, 0.3, 0.0, 0.0]).rot;
        assert!(nearest_right_angles(&odd).is_none_or(|(_, off)| off > 10.0));
        // The readings differ where two angles are not 0, and agree where one alone is.
        let (_, deg) = gap(
            &from_ash(&[0.0, 0.0, 0.0, 30.0, 20.0, 0.0], Angles::Zyx),
            &from_ash(&[0.0, 0.0, 0.0, 30.0, 20.0, 0.0], Angles::Xyz),
        );
        assert!(deg > 1.0, "{deg}");
        let (_, deg) = gap(
            &from_ash(&[0.0, 0.0, 0.0, 0.0, 90.0, 0.0], Angles::Zyx),
            &from_ash(&[0.0, 0.0, 0.0, 0.0, 90.0, 0.0], Angles::Xyz),
        );
        assert!(deg < 1e-6, "{deg}");
    }
}

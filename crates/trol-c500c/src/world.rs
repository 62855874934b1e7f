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

/// A pose as ash prints it: x, y, z (mm), the angles in degrees.
pub fn to_ash(p: &Pose, angles: Angles) -> [f64; 6] {
    let v = match angles {
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

/// The pose of values as ash prints them.
pub fn from_ash(v: &[f64; 6], angles: Angles) -> Pose {
    let (a, b, c) = (v[3].to_radians(), v[4].to_radians(), v[5].to_radians());
    match angles {
        Angles::Zyx => Pose::from_xyzypr([v[0], v[1], v[2], a, b, c]),
        Angles::Xyz => {
            let t = Pose::from_xyzypr([v[0], v[1], v[2], -a, -b, -c]);
            Pose {
                rot: t.rot.transpose(),
                pos: t.pos,
            }
        }
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
        }
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

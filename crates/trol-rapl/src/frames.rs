//! TROL's units and angles against the controller's: TROL gives x y z in mm and yaw pitch
//! roll in radians with R = Rz(yaw)·Ry(pitch)·Rx(roll) (docs/a465.md); a C500 writes x y z
//! in its units (mm or inches) and three angles in degrees, in an order and with signs the
//! profile gives.

use trol_a465::kinematics::Pose;

use crate::profile::{Angle, Profile};

/// What the profile has not settled yet.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum Unsettled {
    /// The length units (STATUS did not say, and `units = "auto"`).
    #[error(
        "the controller's length units are not known: STATUS did not say; set units = \"mm\" or \"inch\" in the RAPL-II profile"
    )]
    Units,
    /// The order and signs of the angles.
    #[error(
        "the order and signs of the controller's angles are not known: set angles in the RAPL-II profile \
         (docs/c500.md, section Settle the conventions)"
    )]
    Angles,
    /// The pulse scale, sign and zero.
    #[error(
        "the controller's pulses per degree, their signs and zeros are not known, so TROL cannot \
         write a precision point or a joint target as pulses: set pulse_scale and pulse_zero in the \
         RAPL-II profile (`trol rapl probe --poses 4` fits them; docs/c500.md, section Settle the \
         conventions)"
    )]
    Pulses,
}

/// The conversion between TROL's cartesian values and the controller's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frames {
    /// Millimetres per controller unit, once known.
    pub mm: Option<f64>,
    /// The controller's angles, once known.
    pub angles: Option<[Angle; 3]>,
    /// The fixed rotation from TROL's tool frame to the controller's (yaw pitch roll, rad).
    pub tool_rotation: [f64; 3],
    /// Per joint: pulses per degree of the JOINTS row and the pulses at its zero, once known.
    pub pulses: Option<[(f64, f64); 6]>,
}

impl Frames {
    /// The conversions a profile establishes (length units as it says; `auto` is settled by
    /// the session's STATUS).
    pub fn of(profile: &Profile) -> Frames {
        Frames {
            mm: profile.units.mm(),
            angles: profile.angles(),
            tool_rotation: profile.tool_rotation.map(f64::to_radians),
            pulses: profile.pulses().ok().flatten(),
        }
    }

    fn rotated(&self, v: [f64; 6], inverse: bool) -> [f64; 6] {
        if self.tool_rotation == [0.0; 3] {
            return v;
        }
        let [y, p, r] = self.tool_rotation;
        let off = Pose::from_xyzypr([0.0, 0.0, 0.0, y, p, r]);
        let off = if inverse { off.inverse() } else { off };
        let mut out = Pose::from_xyzypr(v);
        out.rot *= off.rot;
        let a = out.to_xyzypr();
        [v[0], v[1], v[2], a[3], a[4], a[5]]
    }

    /// TROL's x y z yaw pitch roll (mm, rad) as the controller writes them.
    pub fn to_rapl(&self, v: [f64; 6]) -> Result<[f64; 6], Unsettled> {
        let mm = self.mm.ok_or(Unsettled::Units)?;
        let a = self.angles.ok_or(Unsettled::Angles)?;
        let v = self.rotated(v, false);
        Ok([
            v[0] / mm,
            v[1] / mm,
            v[2] / mm,
            a[0].sign * v[3 + a[0].which].to_degrees(),
            a[1].sign * v[3 + a[1].which].to_degrees(),
            a[2].sign * v[3 + a[2].which].to_degrees(),
        ])
    }

    /// The controller's six values as TROL's.
    pub fn from_rapl(&self, r: [f64; 6]) -> Result<[f64; 6], Unsettled> {
        let mm = self.mm.ok_or(Unsettled::Units)?;
        let a = self.angles.ok_or(Unsettled::Angles)?;
        let mut v = [r[0] * mm, r[1] * mm, r[2] * mm, 0.0, 0.0, 0.0];
        for (i, ang) in a.iter().enumerate() {
            v[3 + ang.which] = ang.sign * r[3 + i].to_radians();
        }
        Ok(self.rotated(v, true))
    }

    /// The controller's JOINTS values (degrees) as its pulses.
    pub fn joints_to_pulses(&self, deg: [f64; 6]) -> Result<[i64; 6], Unsettled> {
        let p = self.pulses.ok_or(Unsettled::Pulses)?;
        Ok(std::array::from_fn(|i| {
            (p[i].1 + p[i].0 * deg[i]).round() as i64
        }))
    }

    /// Pulses as the controller's JOINTS values (degrees).
    pub fn pulses_to_joints(&self, pulses: [i64; 6]) -> Result<[f64; 6], Unsettled> {
        let p = self.pulses.ok_or(Unsettled::Pulses)?;
        Ok(std::array::from_fn(|i| {
            (pulses[i] as f64 - p[i].1) / p[i].0
        }))
    }

    /// A length in TROL's mm as controller units.
    pub fn length_to_rapl(&self, mm: f64) -> Result<f64, Unsettled> {
        Ok(mm / self.mm.ok_or(Unsettled::Units)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::profile::parse_angles;

    #[test]
    fn round_trip_in_every_order() {
        for spec in ["yaw pitch roll", "roll -pitch yaw", "-pitch roll yaw"] {
            let f = Frames {
                mm: Some(25.4),
                angles: parse_angles(spec).unwrap(),
                tool_rotation: [0.3, -1.0, 2.0],
                pulses: None,
            };
            let v = [400.0, -20.0, 150.0, 0.1, -1.2, 2.5];
            let back = f.from_rapl(f.to_rapl(v).unwrap()).unwrap();
            for i in 0..6 {
                assert!((back[i] - v[i]).abs() < 1e-9, "{spec}: {back:?}");
            }
        }
        let f = Frames {
            mm: Some(1.0),
            angles: None,
            tool_rotation: [0.0; 3],
            pulses: None,
        };
        assert_eq!(f.to_rapl([0.0; 6]), Err(Unsettled::Angles));
        assert_eq!(f.joints_to_pulses([0.0; 6]), Err(Unsettled::Pulses));
    }
}

//! TROL's units and angles against the controller's: TROL gives x y z in mm and yaw pitch
//! roll in radians with R = Rz(yaw)·Ry(pitch)·Rx(roll) (docs/a465.md); a C500 writes x y z
//! in its units (mm or inches) and three angles in degrees, in an order and with signs the
//! profile gives.

use crate::profile::Angle;

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
}

/// The conversion between TROL's cartesian values and the controller's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frames {
    /// Millimetres per controller unit, once known.
    pub mm: Option<f64>,
    /// The controller's angles, once known.
    pub angles: Option<[Angle; 3]>,
}

impl Frames {
    /// TROL's x y z yaw pitch roll (mm, rad) as the controller writes them.
    pub fn to_rapl(&self, v: [f64; 6]) -> Result<[f64; 6], Unsettled> {
        let mm = self.mm.ok_or(Unsettled::Units)?;
        let a = self.angles.ok_or(Unsettled::Angles)?;
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
        Ok(v)
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
            };
            let v = [400.0, -20.0, 150.0, 0.1, -1.2, 2.5];
            let back = f.from_rapl(f.to_rapl(v).unwrap()).unwrap();
            for i in 0..6 {
                assert!((back[i] - v[i]).abs() < 1e-12, "{spec}: {back:?}");
            }
        }
        let f = Frames {
            mm: Some(1.0),
            angles: None,
        };
        assert_eq!(f.to_rapl([0.0; 6]), Err(Unsettled::Angles));
    }
}

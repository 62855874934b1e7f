//! How `w2`'s PULSES row relates to its JOINTS row on one C500C: joint by joint, `pulses =
//! at_zero + per_degree * degrees`. The A465's pulses per degree on a C500C, and where each
//! axis counts from, are not public (an open point): `trol c500c step pulses` measures them on
//! the arm, into the profile's `pulses-per-degree` and `pulses-at-zero`; the backend checks
//! them against every `w2` of the arm at rest before it converts a precision point's pulses to
//! joints (docs/c500c.md, "The profile").

/// How far a PULSES reading may stand from what the relation gives and still agree: the
/// rounding of both rows and of a measured ratio (assumed: 25 pulses, about 0.03 degrees
/// at an A465's 561 to 1,111 pulses per degree, and 0.05 % of the pulses from zero).
pub fn tolerance(pulses_from_zero: f64) -> f64 {
    25.0 + 0.0005 * pulses_from_zero.abs()
}

/// How far from zero (degrees) a joint must stand for a reading to test its ratio, not
/// only where it counts from.
pub const TESTS_RATIO_DEG: f64 = 1.0;

/// The relation, joint by joint.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pulses {
    /// Pulses per degree (negative where the axis counts the other way).
    pub per_degree: [f64; 6],
    /// The PULSES row with the joint at 0 degrees.
    pub at_zero: [i64; 6],
}

impl Pulses {
    /// The A465 model's encoder counts, 0 at zero (TROL's own assumption for the simulated
    /// controller, `trol_a465::model`).
    pub fn a465_model() -> Pulses {
        let c = trol_a465::model::counts_per_radian();
        Pulses {
            per_degree: c.map(|v| v.to_radians()),
            at_zero: [0; 6],
        }
    }

    /// The PULSES row for joints at `deg`.
    pub fn pulses(&self, deg: &[f64; 6]) -> [i64; 6] {
        std::array::from_fn(|j| self.at_zero[j] + (self.per_degree[j] * deg[j]).round() as i64)
    }

    /// The joints, degrees, for a PULSES row.
    pub fn degrees(&self, p: &[i64; 6]) -> [f64; 6] {
        std::array::from_fn(|j| (p[j] - self.at_zero[j]) as f64 / self.per_degree[j])
    }

    /// Which joints of a reading (JOINTS `deg`, PULSES `p`) the relation agrees with.
    pub fn agrees(&self, deg: &[f64; 6], p: &[i64; 6]) -> [bool; 6] {
        std::array::from_fn(|j| {
            let from_zero = (p[j] - self.at_zero[j]) as f64;
            (self.per_degree[j] * deg[j] - from_zero).abs() <= tolerance(from_zero)
        })
    }

    /// Whether the values can be a C500C's: ratios finite, 10 to 100,000 pulses per degree
    /// either way.
    pub fn check(&self) -> Result<(), String> {
        for (j, k) in self.per_degree.iter().enumerate() {
            if !k.is_finite() || !(10.0..=100_000.0).contains(&k.abs()) {
                return Err(format!(
                    "pulses-per-degree: joint {}'s {k} is not 10 to 100000 pulses per degree \
                     (either sign)",
                    j + 1
                ));
            }
        }
        if self.at_zero.iter().any(|v| v.abs() > 100_000_000) {
            return Err("pulses-at-zero: a value beyond 100000000".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_relation_goes_both_ways_and_tells_a_wrong_one() {
        let p = Pulses {
            per_degree: [1000.0, -800.0, 600.0, 561.0, 700.0, 1111.1],
            at_zero: [1200, -800, 400, -2000, 500, 300],
        };
        let deg = [10.0, -20.0, 30.5, 0.0, -45.25, 170.0];
        let row = p.pulses(&deg);
        assert_eq!(row[0], 11_200);
        assert_eq!(row[1], 15_200);
        let back = p.degrees(&row);
        for j in 0..6 {
            assert!((back[j] - deg[j]).abs() < 1e-3, "{back:?}");
        }
        assert_eq!(p.agrees(&deg, &row), [true; 6]);
        // One joint's ratio off by 1 %: that joint, and only where it stands off zero.
        let mut wrong = p;
        wrong.per_degree[0] *= 1.01;
        assert_eq!(
            wrong.agrees(&deg, &row),
            [false, true, true, true, true, true]
        );
        assert!(wrong.agrees(&[0.0; 6], &p.pulses(&[0.0; 6]))[0]);
        // Counting from elsewhere: wrong at zero too.
        let mut off = p;
        off.at_zero[3] += 500;
        assert!(!off.agrees(&[0.0; 6], &p.pulses(&[0.0; 6]))[3]);
        assert!(p.check().is_ok());
        assert!(Pulses::a465_model().check().is_ok());
        let mut bad = p;
        bad.per_degree[2] = 0.0;
        assert!(bad.check().is_err());
        bad.per_degree[2] = f64::NAN;
        assert!(bad.check().is_err());
    }

    #[test]
    fn the_model_counts_as_the_a465_model_does() {
        let q = [0.3, -0.2, 1.0, 0.5, -0.7, 2.0];
        let counts = trol_a465::model::joints_to_counts(&q).map(i64::from);
        let p = Pulses::a465_model().pulses(&q.map(f64::to_degrees));
        for j in 0..6 {
            assert!((p[j] - counts[j]).abs() <= 1, "{p:?} {counts:?}");
        }
    }
}

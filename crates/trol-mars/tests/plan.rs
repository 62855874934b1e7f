//! The plan matches the unit (issue 43, item 3): a MARS 8 holds each axis to its REGMS, so
//! the backend plans at those speeds, and a motion's planned time (what Finish, the view and
//! a trajectory's timing go by) is the unit's.

use trol_a465::arm::{Arm, ArmSettings};
use trol_mars::Profile;

/// The time the unit takes for a single-axis move of `deg` on joint `j` at its REGMS
/// (IRC*256/ms), as the simulated unit times a coordinated segment: the slowest axis at its
/// top speed.
fn unit_time(p: &Profile, j: usize, deg: f64) -> f64 {
    let irc = (deg * p.irc_per_deg(j)).abs();
    irc / (p.speed[j] as f64 / 256.0 * 1000.0)
}

#[test]
fn a_joint_move_is_planned_at_the_units_speeds() {
    for p in [Profile::crs93(), Profile::crs97()] {
        for j in 0..6 {
            let mut arm = Arm::new(ArmSettings {
                homed: true,
                joint_speeds: Some(p.top_speeds()),
                ..ArmSettings::default()
            });
            let mut q = [0.0; 6];
            q[j] = 30f64.to_radians();
            assert_eq!(arm.ma(q, 0.0), 0);
            let (start, end, _) = arm.last_motion().expect("a motion");
            let planned = end - start;
            let unit = unit_time(&p, j, 30.0);
            // The unit keeps up with the plan, and the plan is no slower than the unit plus
            // the model's acceleration ramps.
            assert!(
                unit <= planned * (1.0 + 1e-9),
                "{} joint {}: the unit needs {unit:.3} s, the plan {planned:.3} s",
                p.name,
                j + 1
            );
            let top = p.top_speeds()[j].min(trol_a465::model::max_speeds()[j]);
            let ramp = top / trol_a465::model::max_accels()[j];
            assert!(
                planned <= unit + ramp + 1e-6,
                "{} joint {}: the plan takes {planned:.3} s, the unit {unit:.3} s",
                p.name,
                j + 1
            );
        }
    }
}

#[test]
fn without_the_units_speeds_the_plan_is_far_shorter() {
    // The anchor: the published A465 speeds, as before issue 43. J2 at the unit's 2048
    // IRC*256/ms is about 7 deg/s; the model's 180 deg/s would plan a 30 degree move in a
    // small part of the time the unit takes.
    let p = Profile::crs93();
    let mut arm = Arm::new(ArmSettings {
        homed: true,
        ..ArmSettings::default()
    });
    assert_eq!(
        arm.ma([0.0, 30f64.to_radians(), 0.0, 0.0, 0.0, 0.0], 0.0),
        0
    );
    let (start, end, _) = arm.last_motion().expect("a motion");
    assert!(end - start < unit_time(&p, 1, 30.0) / 3.0);
}

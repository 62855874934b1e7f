//! `trol bench moves`: the pick example's motions on the embedded simulator and through a
//! paced line, against the arm's own limit.

use super::*;

#[derive(Serialize)]
pub(super) struct MoveReport {
    pub(super) name: &'static str,
    pub(super) seconds: f64,
    /// The least time at the published speeds alone (no acceleration, the slowest joint).
    pub(super) speed_bound_seconds: f64,
}

pub(super) fn moves(a: MovesArgs) -> Result<(), String> {
    use trol_a465::arm::{Arm, ArmSettings, Target, code, joint_limits};
    let deg = |d: f64| d.to_radians();
    let down = std::f64::consts::FRAC_PI_2;
    let start = [0.0, deg(30.0), deg(60.0), 0.0, deg(90.0), 0.0];
    type Setup = (&'static str, [f64; 6], Target, bool);
    let moves: Vec<Setup> = vec![
        (
            "J1 by 90 deg",
            start,
            Target::Joints([deg(90.0), start[1], start[2], 0.0, start[4], 0.0]),
            false,
        ),
        (
            "J2 by 45 deg",
            start,
            Target::Joints([0.0, deg(-15.0), start[2], 0.0, start[4], 0.0]),
            false,
        ),
        (
            "J3 by 90 deg",
            start,
            Target::Joints([0.0, start[1], deg(-30.0), 0.0, start[4], 0.0]),
            false,
        ),
        (
            "J6 by 180 deg",
            start,
            Target::Joints([0.0, start[1], start[2], 0.0, start[4], deg(180.0)]),
            false,
        ),
        (
            "all joints by 60 deg",
            start,
            Target::Joints([
                deg(60.0),
                deg(-30.0),
                deg(0.0),
                deg(60.0),
                deg(30.0),
                deg(60.0),
            ]),
            false,
        ),
        (
            "READY from the start pose",
            start,
            Target::Joints([0.0; 6]),
            false,
        ),
        (
            "a 300 mm straight line, tool down",
            [0.0; 6],
            Target::Cart([450.0, -150.0, 300.0, 0.0, down, 0.0]),
            true,
        ),
        (
            "a 300 mm joint-interpolated move, tool down",
            [0.0; 6],
            Target::Cart([450.0, -150.0, 300.0, 0.0, down, 0.0]),
            false,
        ),
    ];
    let mut reports = Vec::new();
    for (name, from, target, straight) in moves {
        let mut arm = Arm::new(ArmSettings {
            homed: true,
            table_z: -1e9,
            ..ArmSettings::default()
        });
        // The tool-down moves start 300 mm along y from their end.
        let from = if matches!(target, Target::Cart(_)) {
            let begin = Target::Cart([450.0, 150.0, 300.0, 0.0, down, 0.0]);
            if arm.move_to(begin, false, 0.0) != code::OK {
                return Err(format!("{name}: cannot reach its start"));
            }
            let done = arm.done_at(0.0);
            arm.commanded(done)
        } else {
            from
        };
        let t0 = 1000.0;
        let mut arm2 = Arm::new(ArmSettings {
            homed: true,
            table_z: -1e9,
            ..ArmSettings::default()
        });
        arm2.ma(from, 0.0);
        arm2.set_speed(f64::from(a.speed));
        let r = arm2.move_to(target, straight, t0);
        if r != code::OK {
            return Err(format!("{name}: refused with {r}"));
        }
        let end = arm2.done_at(t0);
        let q_end = arm2.commanded(end);
        let (v, _) = joint_limits(f64::from(a.speed));
        let bound = (0..6)
            .map(|i| (q_end[i] - from[i]).abs() / v[i])
            .fold(0.0, f64::max);
        reports.push(MoveReport {
            name,
            seconds: end - t0,
            speed_bound_seconds: bound,
        });
    }
    print_report(&reports, a.json, |rs| {
        let mut out = format!("moves of the simulated A465 at {} %:\n", a.speed);
        for r in rs {
            out.push_str(&format!(
                "  {:<44} {:6.3} s  (the speeds alone: {:.3} s)\n",
                r.name, r.seconds, r.speed_bound_seconds
            ));
        }
        out
    })
}

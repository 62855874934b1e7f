//! `trol bench pick`: the manual's pick example (examples/pick.py and pick.c: approach
//! test_001, move onto it, close the gripper, depart) through a line paced at a baud rate,
//! against the simulated A465 in real time, beside the arm's own limit: the same calls on the
//! arm model, each motion starting the instant the one before it ended (issue 43, item 5).

use super::*;
use trol_a465::arm::{self, Arm, ArmSettings, Stored};

/// The example's locations (examples/locations.txt), as the example loads them.
const LOCATIONS: &str = include_str!("../../../examples/locations.txt");

#[derive(Args)]
pub struct PickArgs {
    /// The line's baud rate (8N1, 10 bit times a byte).
    #[arg(long, default_value_t = 38400, value_parser = clap::value_parser!(u32).range(1200..=4_000_000))]
    baud: u32,
    /// Cycles to time (the arm is brought back to READY, gripper open, between them).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=100))]
    cycles: u32,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct PickReport {
    baud: u32,
    /// The arm's own time for the cycle, s: every motion (and the gripper) starting when the
    /// one before ended.
    arm_limit_s: f64,
    /// Each cycle's time through the line, s.
    cycles_s: Vec<f64>,
    /// The median cycle over the arm's limit, minus one (0.03 = 3 % over).
    over_limit: f64,
    /// Transactions per cycle.
    transactions_per_cycle: u32,
}

/// The example's cycle, as pick.py calls it (after its Home): two approaches and the move
/// queued back to back, then Finish; the gripper; the depart.
fn cycle(robot: &mut trol::Robot) -> trol::Result<()> {
    robot.appro("test_001", &[-150.0], false)?;
    robot.appro("test_001", &[-90.0], true)?;
    robot.move_to("test_001", true)?;
    robot.finish()?;
    robot.close_gripper(60)?;
    robot.finish()?;
    robot.depart(&[-90.0], true)?;
    robot.finish()
}

/// The arm model's time for the same cycle, from READY with the gripper open: what no
/// controller and no line can beat.
fn arm_limit(locations: &[(String, Stored)]) -> Result<f64, String> {
    let mut arm = Arm::new(ArmSettings {
        homed: true,
        ..ArmSettings::default()
    });
    for (name, loc) in locations {
        arm.set_location(name, *loc);
    }
    let target = match arm.location("test_001") {
        Some(Stored::Cart(v)) => arm::Target::Cart(v),
        other => return Err(format!("test_001 is not a cartesian location: {other:?}")),
    };
    let along_x = |d: f64| [d, 0.0, 0.0, 0.0, 0.0, 0.0];
    let ok = |name: &str, c: i16| {
        if c == arm::code::OK {
            Ok(())
        } else {
            Err(format!("the arm model refused {name}: {c}"))
        }
    };
    ok("Open", arm.open(50.0, 0.0))?;
    let start = arm.done_at(0.0);
    // The two approaches and the move go back to back, as the example sends them.
    ok(
        "Appro -150",
        arm.appro(target, along_x(-150.0), false, start),
    )?;
    ok("Appro -90", arm.appro(target, along_x(-90.0), true, start))?;
    ok("Move", arm.move_to(target, true, start))?;
    let t = arm.done_at(start);
    ok("Close", arm.close(60.0, t))?;
    let t = arm.done_at(t);
    ok("Depart", arm.depart(along_x(-90.0), true, t))?;
    let t = arm.done_at(t);
    Ok(t - start)
}

pub fn pick(a: PickArgs) -> Result<(), String> {
    let locations = arm::parse_locations(LOCATIONS)?;
    let limit = arm_limit(&locations)?;
    // Homed from the start: the example's Home is not part of its cycle.
    let settings = trol_sim::SimSettings {
        locations: locations.clone(),
        arm: ArmSettings {
            homed: true,
            ..ArmSettings::default()
        },
        ..trol_sim::SimSettings::default()
    };
    let (mut robot, _) = paced_robot_with(a.baud, settings)?;
    let e = |e: trol::Error| e.to_string();
    let mut cycles = Vec::new();
    let mut transactions = 0;
    for _ in 0..a.cycles {
        robot.open_gripper(50).map_err(e)?;
        robot.ma(&[0.0; 6]).map_err(e)?;
        robot.finish().map_err(e)?;
        let before = robot.last_transaction();
        let started = Instant::now();
        cycle(&mut robot).map_err(e)?;
        cycles.push(started.elapsed().as_secs_f64());
        transactions = u32::from(robot.last_transaction().wrapping_sub(before));
    }
    let mut sorted = cycles.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    let r = PickReport {
        baud: a.baud,
        arm_limit_s: limit,
        over_limit: median / limit - 1.0,
        cycles_s: cycles,
        transactions_per_cycle: transactions,
    };
    print_report(&r, a.json, |r| {
        format!(
            "the pick example's cycle through a line paced at {} baud, the simulated A465 in \
             real time: {} (median {:.3} s, {} transactions); the arm's own limit {:.3} s: \
             {:.1} % over",
            r.baud,
            r.cycles_s
                .iter()
                .map(|c| format!("{c:.3} s"))
                .collect::<Vec<_>>()
                .join(", "),
            median,
            r.transactions_per_cycle,
            r.arm_limit_s,
            r.over_limit * 100.0
        )
    })
}

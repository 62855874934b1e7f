//! The manual's pick example (TROLAppro) with the Rust API, against the embedded controller:
//! approach test_001 along the tool x axis, move onto it, close the gripper, depart.
//!
//!     cargo run --release -p trol --example pick

use trol::{PosMode, Robot, SimSettings, Tag};
use trol_a465::arm::Stored;

fn step(name: &str, r: trol::Result<()>) -> trol::Result<()> {
    match &r {
        Ok(()) => println!("{name:<30} -> 0 (success)"),
        Err(e) => println!("{name:<30} -> {} ({e})", e.code()),
    }
    r
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let down = std::f64::consts::FRAC_PI_2;
    let mut robot = Robot::embedded(SimSettings {
        time_scale: 20.0,
        locations: vec![(
            "test_001".into(),
            Stored::Cart([400.0, 0.0, 150.0, 0.0, down, 0.0]),
        )],
        ..SimSettings::default()
    });
    step("Home(0)", robot.home(0))?;
    step("Finish(FINISH_WAIT)", robot.finish())?;
    step(
        "Appro(test_001, -90, joint)",
        robot.appro("test_001", &[-90.0], false),
    )?;
    // The manual's example:
    step(
        "Appro(test_001, -90, straight)",
        robot.appro("test_001", &[-90.0], true),
    )?;
    step("Move(test_001, straight)", robot.move_to("test_001", true))?;
    step("Finish(FINISH_WAIT)", robot.finish())?;
    step("Close(60)", robot.close_gripper(60))?;
    step("Finish(FINISH_WAIT)", robot.finish())?;
    step("Depart(-90, straight)", robot.depart(&[-90.0], true))?;
    step("Finish(FINISH_WAIT)", robot.finish())?;
    let at = robot.position(Tag::Cart, PosMode::Actual)?.to_array6();
    println!(
        "arm at x {:.1} y {:.1} z {:.1} mm, yaw {:.3} pitch {:.3} roll {:.3} rad",
        at[0], at[1], at[2], at[3], at[4], at[5]
    );
    Ok(())
}

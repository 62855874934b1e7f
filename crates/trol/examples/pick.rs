//! The manual's pick example (TROLAppro) with the Rust API, against the embedded controller:
//! approach test_001 along the tool x axis, move onto it, close the gripper, depart.
//!
//!     cargo run --release -p trol --example pick

use trol::{Connect, PosMode, SimSettings, Tag};
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
    let mut robot = Connect::sim(SimSettings {
        time_scale: 20.0,
        locations: vec![(
            "test_001".into(),
            Stored::Cart([400.0, 0.0, 150.0, 0.0, down, 0.0]),
        )],
        ..SimSettings::default()
    })
    .connect()?;
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
    // x, y, z in mm, yaw, pitch, roll in rad, to the arm's precision.
    let at = robot.position(Tag::Cart, PosMode::Actual)?;
    println!("arm at {at}");
    Ok(())
}

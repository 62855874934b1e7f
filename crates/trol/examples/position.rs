//! Read the position in all three forms and use GetStatus, with the Rust API.
//!
//!     cargo run -p trol --example position

use trol::{Connect, PosMode, SimSettings, Tag};

fn main() -> Result<(), trol::Error> {
    let mut robot = Connect::sim(SimSettings {
        time_scale: 20.0,
        ..SimSettings::default()
    })
    .connect()?;
    robot.home(0)?;
    robot.joint(1, 0.5)?;
    robot.finish()?;
    let (called, value) = robot.status()?;
    println!("Joint(1, 0.5): BIOS called {called}, returned {value}");
    for (tag, mode) in [
        (Tag::Cart, PosMode::Commanded),
        (Tag::Joint, PosMode::Commanded),
        (Tag::Prec, PosMode::Actual),
    ] {
        println!(
            "{:<9} {:?}: {:?}",
            tag.name(),
            mode,
            robot.position(tag, mode)?
        );
    }
    if let Err(e) = robot.move_to("nowhere", false) {
        let (called, why) = robot.status()?;
        println!(
            "Move(nowhere): {e}; BIOS called {called}, reason {}",
            why.describe(robot.codes())
        );
    }
    Ok(())
}

//! The guide's client (docs/extending.md, step 3): the added commands called from Rust,
//! against a controller process (its port as the first argument), or, without one, against
//! an in-process controller with the commands registered.
//!
//!     cargo run -p trol --example extending_client -- /dev/pts/N

mod extending;

use extending::commands::{FORWARD_KIN, JOINT_ABS, forward_kin_of, joint_abs_to, server};
use trol::{PosMode, Robot, SimSettings, Tag};
use trol_proto::link::LinkConfig;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut robot = match std::env::args().nth(1) {
        Some(port) => Robot::connect(&port, 9600)?,
        None => {
            let settings = SimSettings {
                time_scale: 20.0,
                ..SimSettings::default()
            };
            let (line, controller) =
                trol_controller::embedded_with(server(settings)?, LinkConfig::default());
            Robot::over(Box::new(line), LinkConfig::default(), Some(controller))
        }
    };
    robot.add_command(FORWARD_KIN)?;
    robot.add_command(JOINT_ABS)?;

    let pose = forward_kin_of(&mut robot, &[0.0, 0.5, 1.0])?;
    println!("TROLForwardKin j(0, 0.5, 1) -> {pose:?}");
    robot.home(0)?;
    joint_abs_to(&mut robot, 2, 0.25)?;
    robot.finish()?;
    let q = robot.position(Tag::Joint, PosMode::Commanded)?;
    println!("after TROLJointAbs 2 0.25: {q:?}");
    let e = joint_abs_to(&mut robot, 7, 0.0).unwrap_err();
    println!("TROLJointAbs 7 0: {e}");
    Ok(())
}

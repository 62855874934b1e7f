//! A controller program of an application's own (docs/extending.md, step 2): the simulated
//! A465 behind the PCP server, with the guide's commands registered, serving on a new
//! pseudo-terminal (or the device named as the first argument) until it is stopped.
//!
//!     cargo run -p trol --example extending_controller
//!     # prints: serving on /dev/pts/N

mod extending;

use std::sync::atomic::AtomicBool;

use extending::commands::server;
use trol_controller::{Controller, Mode};
use trol_proto::link::LinkConfig;
use trol_sim::SimSettings;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let settings = SimSettings {
        time_scale: 20.0,
        ..SimSettings::default()
    };
    let pcp = server(settings)?;

    let (port, _keep, name): (
        Box<dyn trol_port::Port>,
        Option<Box<dyn trol_port::Port>>,
        String,
    ) = match std::env::args().nth(1) {
        Some(device) => (trol_port::open(&device, &Default::default())?, None, device),
        None => {
            let (master, slave, path) = trol_port::serial::SerialLine::pty_pair()?;
            (Box::new(master), Some(Box::new(slave)), path)
        }
    };
    let mut controller = Controller::new(port, LinkConfig::default(), pcp, Mode::Server);
    controller.set_log(Box::new(|e| {
        let codes = trol_sim::SIM_CODES;
        println!(
            "{} -> {}",
            e.catalog.request_text(e.request),
            e.catalog.reply_text(e.request, e.reply, codes)
        );
    }));
    println!("serving on {name}");
    controller.run(&AtomicBool::new(false))?;
    Ok(())
}

//! An A465 on its CRS C500C (docs/c500c.md): the later controller of the A465, running CROS
//! and RAPL-3. TROL drives it through the front console's application shell `ash`, as a
//! person at a terminal would:
//!
//! - [`console`]: the console, sans-IO (lines, prompts, questions out of bytes);
//! - [`reports`]: what ash prints (`w0`/`w2`, `armstat`, `robotver`, `speed`) and its error
//!   texts;
//! - [`probe`]: first contact that only reads, every byte recorded;
//! - [`profile`]: what only the arm settles, one TOML file per controller;
//! - [`pulses`]: how the PULSES row relates to the JOINTS row, joint by joint;
//! - [`world`]: the WORLD row's and a cartesian location's angles, in each reading;
//! - [`backend`]: the robot backend behind the PCP server (`c500c:DEVICE`), on the shared
//!   core for real controllers;
//! - [`c500c`]: a simulated C500C (`trol sim --c500c`), with a switch for each point the
//!   public sources leave open.

#![forbid(unsafe_code)]
#![warn(missing_docs, missing_debug_implementations)]

pub mod backend;
pub mod c500c;
pub mod console;
pub mod probe;
pub mod profile;
pub mod pulses;
pub mod reports;
pub mod world;

pub use backend::{C500C_CODES, C500cBackend, C500cError};
pub use c500c::C500c;
pub use profile::Profile;

/// The port prefix that embeds the controller with the C500C backend (`c500c:/dev/ttyUSB0`).
pub const PREFIX: &str = "c500c:";

//! An A465 on a PiKRON MARS 8 (docs/mars.md): most A465s still in use lost their C500, and
//! CTU Prague drives theirs through MARS 8 units with the public Python packages
//! ctu-mars-control-unit and ctu-crs. This crate is TROL's side of that line:
//!
//! - [`line`]: the unit's line, sans-IO (lines in, replies out, commands' bytes);
//! - [`profile`]: the arm on the unit's axes (IRC per degree, zero, range, homing), one TOML
//!   file per arm;
//! - [`backend`]: the robot backend behind the PCP server (`mars:DEVICE`, `trol gateway`);
//! - [`probe`]: first contact that only reads, with every byte recorded;
//! - [`mars8`]: a simulated MARS 8 (`trol sim --mars`), with a switch for each point the
//!   public sources leave open.

#![forbid(unsafe_code)]
#![warn(missing_docs, missing_debug_implementations)]

pub mod backend;
pub mod line;
pub mod mars8;
pub mod probe;
pub mod profile;

pub use backend::{MARS_CODES, MarsBackend, MarsError};
pub use mars8::Mars8;
pub use profile::Profile;

/// The port prefix that embeds the controller with the MARS 8 backend (`mars:/dev/ttyUSB0`).
pub const PREFIX: &str = "mars:";

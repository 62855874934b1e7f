//! Driving a real CRS C500 in its own language, RAPL-II, and a simulated C500 that speaks it
//! (docs/c500.md; what public drivers know: ../shared/reference/c500-rapl.md).
//!
//! Sans-IO like the protocol core: bytes in, bytes out, time passed in.
//!
//! - [`profile`]: everything the public sources leave open, one TOML file per controller;
//! - [`aci`]: the ACI steps that switch the host port from ACI mode to terminal mode (master
//!   and slave);
//! - [`session`]: the terminal session: paced typing with echo check, the tolerant reply
//!   reader, resynchronisation;
//! - [`text`]: numbers, and the text of W0/W2/W5, STATUS and LISTL;
//! - [`frames`]: TROL's units and angles against the controller's;
//! - [`backend`]: the robot backend on the PCP server's contract, over a port;
//! - [`probe`]: first contact: the commands that cannot move the arm, and the fit of the
//!   conventions from readings at poses set by pendant;
//! - [`c500`]: the simulated C500 in RAPL-II mode, backed by the simulated A465.

#![forbid(unsafe_code)]
#![warn(missing_docs, missing_debug_implementations)]

pub mod aci;
pub mod backend;
pub mod c500;
pub mod frames;
pub mod probe;
pub mod profile;
pub mod session;
pub mod text;

pub use backend::{RAPL_CODES, RaplBackend, RaplError};
pub use c500::C500;
pub use profile::Profile;

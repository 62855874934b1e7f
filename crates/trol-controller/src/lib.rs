//! The TROL controller: what runs on the C500 side of the line.
//!
//! - [`bios`]: the RAPL-BIOS interface, one method per call;
//! - [`pcp`]: the PCP server's layer 4 (dispatch tables per class, handlers, GetStatus
//!   bookkeeping), sans-IO;
//! - [`terminal`]: terminal mode and the activation sequence;
//! - [`controller`]: the loop that runs both modes over a port, and the embedded controller;
//! - [`sim_bios`]: the simulated A465 behind the BIOS interface.
//!
//! [`embedded`] starts the controller the host's port `sim` talks to.

#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod bios;
pub mod controller;
pub mod pcp;
pub mod sim_bios;
pub mod terminal;

pub use bios::Bios;
pub use controller::{Controller, Embedded, LogFn, Mode};
pub use pcp::{Context, Handler, Pcp, Status};
pub use sim_bios::{SimBios, SimSettings};

use trol_port::memory::{self, MemoryLine};
use trol_proto::link::LinkConfig;

/// Start the embedded controller (port `sim`): the simulated A465 behind the PCP server, in
/// server mode, on a thread, over an in-memory line. Returns the host's end of the line.
pub fn embedded(settings: SimSettings, cfg: LinkConfig) -> (MemoryLine, Embedded) {
    embedded_with(Pcp::new(SimBios::new(settings)), cfg)
}

/// Like [`embedded`], with a server of the caller's (for added commands).
pub fn embedded_with(pcp: Pcp<SimBios>, cfg: LinkConfig) -> (MemoryLine, Embedded) {
    let (host, ctl) = memory::pair(None);
    let controller = Controller::new(ctl, cfg, pcp, Mode::Server);
    (host, Embedded::spawn(controller))
}

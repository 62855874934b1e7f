//! The TROL controller: what runs on the C500 side of the line.
//!
//! - [`backend`]: the robot backend contract (the manual's RAPL-BIOS), one method per call;
//! - [`pcp`]: the PCP server's layer 4 (dispatch tables per class, handlers on decoded
//!   arguments, GetStatus bookkeeping, replies that wait for an idle arm), sans-IO;
//! - [`terminal`]: terminal mode and the activation sequence;
//! - [`controller`]: the loop that runs both modes over a port, and the embedded controller;
//! - [`sim`]: the simulated A465 as a backend.
//!
//! A controller program of an application's own adds commands with [`Pcp::register`] and
//! runs the server with [`embedded_with`] or [`Controller`] (docs/extending.md).
//!
//! [`embedded`] starts the controller the host's port `sim` talks to.

#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod backend;
pub mod controller;
pub mod pcp;
pub mod sim;
pub mod terminal;

pub use backend::{ArmReport, Backend, BackendError, BiosResult, PosMode, SharedReport, Target};
pub use controller::{Controller, Embedded, LogEntry, LogFn, Mode, WatchdogTrip};
pub use pcp::{Call, Context, Executed, Handled, Handler, Pcp, RegisterError, Status};
pub use sim::{ArmView, SIM_CODES, SharedArm, SimBackend, SimSettings};

use trol_port::memory::{self, MemoryLine};
use trol_proto::link::LinkConfig;

/// Start the embedded controller (port `sim`): the simulated A465 behind the PCP server, in
/// server mode, on a thread, over an in-memory line. Returns the host's end of the line.
pub fn embedded(settings: SimSettings, cfg: LinkConfig) -> (MemoryLine, Embedded) {
    embedded_with(Pcp::new(SimBackend::new(settings)), cfg)
}

/// Like [`embedded`], with a server of the caller's: any backend, commands added.
pub fn embedded_with<B: Backend + 'static>(pcp: Pcp<B>, cfg: LinkConfig) -> (MemoryLine, Embedded) {
    let (host, ctl) = memory::pair(None);
    let controller = Controller::new(ctl, cfg, pcp, Mode::Server);
    (host, Embedded::spawn(controller))
}

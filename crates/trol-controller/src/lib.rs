//! The TROL controller: what runs on the C500 side of the line.
//!
//! - [`backend`]: the robot backend contract (the manual's RAPL-BIOS), one method per call;
//! - [`pcp`]: the PCP server's layer 4 (dispatch tables per class, handlers on decoded
//!   arguments, GetStatus bookkeeping, replies that wait for an idle arm), sans-IO;
//! - [`terminal`]: terminal mode and the activation sequence;
//! - [`controller`]: the loop that runs both modes over a port, and the embedded controller;
//! - [`real`]: what every backend for a real controller does the same way (Halt as the arm
//!   shows it);
//!
//! The simulated A465 is a backend in its own crate, `trol-sim`.
//!
//! A controller program of an application's own adds commands with [`Pcp::register`] and
//! runs the server with [`embedded_with`] or [`Controller`] (docs/extending.md).

#![forbid(unsafe_code)]
#![warn(missing_docs, missing_debug_implementations)]

pub mod backend;
pub mod controller;
pub mod journal;
pub mod pcp;
pub mod real;
pub mod terminal;

pub use backend::{
    ArmReport, Backend, BackendError, BiosResult, PosMode, ReportedObject, SharedReport, Target,
    UNTIMED_WAYPOINTS, untimed_count, untimed_trajectory,
};
pub use controller::{
    Controller, Embedded, FollowUp, LogEntry, LogFn, Mode, Pendant, PendantError, PendantInbox,
    WatchdogTrip,
};
pub use pcp::{Call, Context, Executed, Handled, Handler, Pcp, RegisterError, Status};

use trol_port::memory::{self, MemoryLine};
use trol_proto::link::LinkConfig;

/// Start an embedded controller: `pcp` (any backend, commands added) in server mode, on a
/// thread, over an in-memory line. Returns the host's end of the line.
pub fn embedded_with<B: Backend + 'static>(pcp: Pcp<B>, cfg: LinkConfig) -> (MemoryLine, Embedded) {
    let (host, ctl) = memory::pair(None);
    let controller = Controller::new(ctl, cfg, pcp, Mode::Server);
    (host, Embedded::spawn(controller))
}

/// [`embedded_with`], the backend reporting its arm into `slot` at most every `every`
/// ([`Controller::report_into`]): what a live view reads.
pub fn embedded_reporting<B: Backend + 'static>(
    pcp: Pcp<B>,
    cfg: LinkConfig,
    slot: SharedReport,
    every: std::time::Duration,
) -> (MemoryLine, Embedded) {
    let (host, ctl) = memory::pair(None);
    let mut controller = Controller::new(ctl, cfg, pcp, Mode::Server);
    controller.report_into(slot, every);
    (host, Embedded::spawn(controller))
}

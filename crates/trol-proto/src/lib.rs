//! The TROL protocol core, shared by the host library and the controller.
//!
//! TROL (TU Vienna Robot Control Library) talks to a CRS A465's C500 controller over a serial
//! line in four layers (manual, chapter "Kommunikation"). This crate holds layers 2 to 4 as
//! sans-IO code: no I/O, no clock, no sleeps. Bytes come in, bytes go out, and the caller
//! passes in the time.
//!
//! - [`link`]: layer 2, the BSC-like link (SendData / ReceiveData);
//! - [`transaction`]: layer 3, transactions (TransSR on the PC, TransRS on the controller).
//!
//! Layer 1 (ports) and the drivers that run these machines live in `trol-port` and
//! `trol-comm`. The byte-exact specification is docs/protocol.md.

#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod link;
pub mod time;
pub mod transaction;

pub use time::Instant;

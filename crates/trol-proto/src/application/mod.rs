//! Layer 4, the presentation and application layer (manual, "Darstellungs- und
//! Anwendungs-Schicht", "Erweiterung von TROL um eigene Kommandos").
//!
//! Every API call becomes one request record; the controller answers with one reply record.
//! Both are byte-exact and shared by the host and the controller:
//!
//! - [`codes`]: command codes and transaction classes CAT1..CAT4;
//! - [`location`]: locations (SLocData) and location names (TLocName);
//! - [`request`]: the request records, their encoding, decoding and range checks;
//! - [`reply`]: the reply records;
//! - [`errors`]: TROL's return codes.
//!
//! The layouts are written out in docs/protocol.md ("Layer 4") with test vectors.

pub mod codes;
pub mod errors;
pub mod location;
pub mod reply;
pub mod request;

pub use codes::{Class, Command};
pub use location::{LocName, Location, Tag};
pub use reply::{Reply, ReplyError};
pub use request::{FinishMode, PosMode, Request, RequestError};

//! Layer 4, the presentation and application layer (manual, "Darstellungs- und
//! Anwendungs-Schicht", "Erweiterung von TROL um eigene Kommandos").
//!
//! Every API call becomes one request record; the controller answers with one reply record.
//! Both are byte-exact and shared by the host and the controller, and both follow from the
//! command's description:
//!
//! - [`command`]: what a command is ([`CommandDef`]: code and class, arguments and ranges,
//!   reply form, success values, reply wait, help);
//! - [`table`]: the built-in commands, each described once;
//! - [`record`]: the one layout rule that turns a description and values into bytes and back,
//!   with the range checks, and the text form of a call;
//! - [`reply`]: the reply records;
//! - [`catalog`]: the commands one side knows, built-in and added;
//! - [`location`]: locations (SLocData) and location names (TLocName);
//! - [`code`]: return values as a type, with TROL's names and meanings.
//!
//! The layouts are written out in docs/protocol.md ("Layer 4") with test vectors.

pub mod catalog;
pub mod code;
pub mod command;
pub mod location;
pub mod record;
pub mod reply;
pub mod table;

pub use catalog::{Catalog, CatalogError};
pub use code::{Code, CodeInfo, CodeTable};
pub use command::{Arg, ArgKind, Choice, Class, CommandDef, ReplyKind, Wait};
pub use location::{LocName, Location, MAX_WAYPOINTS, Tag, Waypoint};
pub use record::{RequestError, Value};
pub use reply::{CodeEntry, Gripper, Held, Reply, ReplyError};

//! What every backend for a real controller does the same way, written once: the rules the
//! brief sets for real controllers, which a backend must not word or weigh its own way.
//!
//! - [`gate`]: whether a motion may go now, be queued, or is refused (power, point of
//!   control, homing, a motion not of TROL's doing), from one status snapshot;
//! - [`MotionQueue`]: the motions that wait behind the one under way, bounded; when one
//!   fails, what waits behind it is dropped unsent, and that is said;
//! - [`EndWatch`]: Finish's end rule. A motion has ended only when the controller says so
//!   *and* the arm is read at the motion's end; standing short of it is a stop short; a
//!   controller that says done while the arm is neither there nor standing is given up as
//!   unsure after the motion's time and a margin;
//! - [`halt`]: Halt as the arm shows it. Each of the controller's stops in turn, mildest
//!   first, until two readings [`STILL_GAP`] apart agree; success only then, and only
//!   within the Halt's time. No profile key makes a stop count that was not seen.
//! - [`pace`]: the speed setting of each joint move of a trajectory on a controller with no
//!   timed path, from its waypoints' times, never above the user's setting;
//! - [`seen_standing`]: the "standing" test Halt and the supervised steps use;
//! - [`Recent`]: what was seen of the arm a moment ago, standing in for the same read
//!   before the next motion for [`SEEN_FOR`], forgotten on any line that is not a read;
//! - [`Transcript`]: every byte of a session both ways, for a first contact's record.
//!
//! A backend supplies its line, its commands, its readings and its clock; the rules here
//! never sleep or read a clock of their own, so their tests run in virtual time.

mod finish;
mod gate;
mod halt;
mod pace;
mod recent;
mod transcript;

pub use finish::{End, EndTimes, EndWatch};
pub use gate::{Gate, MotionQueue, Refusal, Snapshot, gate};
pub use halt::{HaltTimes, Halted, STILL_DEG, STILL_GAP, Stopping, halt, seen_standing};
pub use pace::{Pace, pace};
pub use recent::{Recent, SEEN_FOR};
pub use transcript::{Transcript, printable};

//! The robot's firmware as the PCP server sees it: one method per RAPL-BIOS call
//! (manual, "PCP\BIOSCALL.C": the C interface to the RAPL BIOS).
//!
//! A real C500 answers these from its firmware; here [`crate::SimBios`] answers them from
//! the simulated A465. Return values above -32000 are the BIOS's own; 0 means success.

use trol_proto::application::{FinishMode, LocName, Location, PosMode, Tag};

/// The RAPL-BIOS calls the server makes. Coordinates arrive with all six values (the server
/// has set the ones not sent to 0).
pub trait Bios: Send {
    /// Approach `target` displaced by `disp` in its tool frame.
    fn appro(&mut self, target: &Location, disp: [f64; 6], straight: bool) -> i16;
    /// Close the gripper with `force` percent.
    fn close(&mut self, force: u8) -> i16;
    /// Move away from here by `disp` in the tool frame.
    fn depart(&mut self, disp: [f64; 6], straight: bool) -> i16;
    /// FINISH_STATUS: 1 while the arm moves, else 0. FINISH_WAIT: return when it is done.
    fn finish(&mut self, mode: FinishMode) -> i16;
    /// Set the finger distance, mm.
    fn grip(&mut self, dist: u8) -> i16;
    /// Stop all motion.
    fn halt(&mut self) -> i16;
    /// Home one axis (1..6) or all (0).
    fn home(&mut self, axis: u8) -> i16;
    /// Move the tool by dx dy dz in the world frame.
    fn jog(&mut self, d: [f64; 3], straight: bool) -> i16;
    /// Move one joint (1..6) by an increment, radians.
    fn joint(&mut self, joint: u8, radians: f64) -> i16;
    /// All joints to absolute angles.
    fn ma(&mut self, q: [f64; 6]) -> i16;
    /// All joints by increments.
    fn mi(&mut self, dq: [f64; 6]) -> i16;
    /// Move to `target` (cartesian or precision point).
    fn move_to(&mut self, target: &Location, straight: bool) -> i16;
    /// Open the gripper with `force` percent.
    fn open(&mut self, force: u8) -> i16;
    /// Go to the READY pose.
    fn ready(&mut self) -> i16;
    /// Set the tool transform.
    fn set_tool(&mut self, tool: [f64; 6]) -> i16;
    /// Set the speed, percent.
    fn speed(&mut self, percent: u8) -> i16;
    /// Read the position in the form `tag`, commanded or actual (six values).
    fn position(&mut self, tag: Tag, mode: PosMode) -> Location;
    /// Look a name up in the controller's location table.
    fn location(&self, name: &LocName) -> Option<Location>;
}

//! The activation sequence that brings a controller from terminal mode into TROL's server
//! mode (docs/protocol.md, "The controller's modes"): the line the host types and the answer
//! it waits for, both naming the block check the two ends agree on.

use crate::link::BlockCheck;

/// The line that starts server mode, followed by the block check's word (`PCP TROL CRC16`);
/// bare, it means the manual's LRC.
pub const ACTIVATE: &str = "PCP TROL";
/// The controller's answer to it, followed by the block check it agreed to.
pub const ACTIVATED: &str = "PCP TROL ACTIVE";

/// The activation line for `check`.
pub fn activation_line(check: BlockCheck) -> String {
    format!("{ACTIVATE} {}", check.word())
}

/// The controller's answer for `check`.
pub fn activated_line(check: BlockCheck) -> String {
    format!("{ACTIVATED} {}", check.word())
}

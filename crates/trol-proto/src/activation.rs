//! The activation sequence that brings a controller from terminal mode into TROL's server
//! mode (docs/protocol.md, "The controller's modes"): the line the host types and the answer
//! it waits for, both naming the block check the two ends agree on.
//!
//! A bare `PCP TROL` is what a host that speaks only the manual's protocol types (a 1998
//! inittrol): it gets the manual's LRC, the manual's record sizes and the bare answer
//! `PCP TROL ACTIVE`. A controller that speaks only the manual's protocol answers a line with
//! a block check's word as any unknown line (`012-COMMAND ERROR.`); this host then falls back
//! to the bare line.

use crate::link::BlockCheck;

/// The line that starts server mode, followed by the block check's word (`PCP TROL CRC16`);
/// bare, it is a 1998 host's, and means the manual's LRC and record sizes.
pub const ACTIVATE: &str = "PCP TROL";
/// The controller's answer to it, followed by the block check it agreed to (bare to the bare
/// line).
pub const ACTIVATED: &str = "PCP TROL ACTIVE";
/// What a controller answers a line it does not know (RAPL's and the manual's terminal).
pub const COMMAND_ERROR: &str = "COMMAND ERROR";

/// The activation line for `check`.
pub fn activation_line(check: BlockCheck) -> String {
    format!("{ACTIVATE} {}", check.word())
}

/// The controller's answer for `check`.
pub fn activated_line(check: BlockCheck) -> String {
    format!("{ACTIVATED} {}", check.word())
}

/// Who asked for server mode, by the activation line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Activation {
    /// A bare `PCP TROL`: a host that speaks only the manual's protocol (LRC, the manual's
    /// record sizes).
    Manual,
    /// `PCP TROL` with a block check's word: a TROL host of this protocol.
    Trol(BlockCheck),
}

impl Activation {
    /// The block check the link uses from then on.
    pub fn check(self) -> BlockCheck {
        match self {
            Activation::Manual => BlockCheck::Lrc,
            Activation::Trol(check) => check,
        }
    }

    /// The controller's answer.
    pub fn answer(self) -> String {
        match self {
            Activation::Manual => ACTIVATED.to_string(),
            Activation::Trol(check) => activated_line(check),
        }
    }

    /// The activation line of `line` (already trimmed and in capitals), if it is one.
    pub fn of_line(line: &str) -> Option<Activation> {
        match line.strip_prefix(ACTIVATE).map(str::trim) {
            Some("") => Some(Activation::Manual),
            Some(word) => BlockCheck::from_word(word).map(Activation::Trol),
            None => None,
        }
    }
}

//! What a command is: its description ([`CommandDef`]), from which every surface works.
//!
//! The manual adds a command in five places ("Modifikation der betroffenen Source-Dateien"):
//! a record type and a code in commands.h, an API function in send.c, a handler in
//! pcptrol.c, BIOS calls, and the error handlers. Here a command is one [`CommandDef`]: its
//! code (which gives its class), its arguments in the API's order with their kinds and
//! ranges, the form of its reply, which reply values count as success, how long the host
//! waits for the reply, and its help text. The record's bytes follow from the arguments by
//! one rule (see [`crate::application::record`]), so the host, the controller, the
//! interpreter, the trace and the logs all read and write a command from its description.
//!
//! The built-in commands are in [`crate::application::table`]; an application describes its
//! own the same way (docs/extending.md).

use std::time::Duration;

use super::location::Tag;

/// A transaction class (manual, "Kommandocodes und Transaktionsklassen").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Class {
    /// Commands that become one RAPL-BIOS call; the reply is one 16-bit integer.
    Cat1,
    /// Like CAT1, with replies of any length (for example a float vector).
    Cat2,
    /// Commands the BIOS does not offer directly (GetPosition).
    Cat3,
    /// TROL's own commands (TerminatePCP, GetStatus).
    Cat4,
}

impl Class {
    /// The class of a command code: CAT1 from 0, CAT2 from 64, CAT3 from 128, CAT4 from 192.
    pub const fn of(code: u8) -> Class {
        match code >> 6 {
            0 => Class::Cat1,
            1 => Class::Cat2,
            2 => Class::Cat3,
            _ => Class::Cat4,
        }
    }

    /// The first code of the class.
    pub const fn base(self) -> u8 {
        self.index() as u8 * 64
    }

    /// 0 for CAT1 .. 3 for CAT4 (the dispatch table's number).
    pub const fn index(self) -> usize {
        match self {
            Class::Cat1 => 0,
            Class::Cat2 => 1,
            Class::Cat3 => 2,
            Class::Cat4 => 3,
        }
    }

    /// All four, in order.
    pub const ALL: [Class; 4] = [Class::Cat1, Class::Cat2, Class::Cat3, Class::Cat4];
}

impl std::fmt::Display for Class {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "CAT{}", self.index() + 1)
    }
}

/// A word of a [`ArgKind::Choice`]: what the interpreter reads, the manual's constant, and
/// the byte on the wire.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Choice {
    /// The interpreter's word (`wait`).
    pub word: &'static str,
    /// The manual's constant (`FINISH_WAIT`).
    pub constant: &'static str,
    /// The byte sent.
    pub value: u8,
}

/// The kind of an argument, and with it its range and its place in the record.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ArgKind {
    /// A whole number in `min..=max`, one byte.
    Int {
        /// Smallest value.
        min: u8,
        /// Largest value.
        max: u8,
    },
    /// One of a few words, one byte; the first is the interpreter's default.
    Choice(&'static [Choice]),
    /// The straight-line flag (0 joint-interpolated, 1 straight); the interpreter's default
    /// is 0. It rides in bit 0 of the first location's dims byte, or has a byte of its own in
    /// a command without locations.
    Straight,
    /// A location name (TLocName), 8 bytes.
    Name,
    /// A real number, 4 bytes (the manual's `float`).
    Real,
    /// A location of one of `tags` with `min..=max` values: a dims byte, and the values at
    /// the record's end.
    Loc {
        /// The tags accepted.
        tags: &'static [Tag],
        /// Fewest values (numDims).
        min: u8,
        /// Most values.
        max: u8,
    },
    /// A trajectory: `1..=max` waypoints, each a time and six joint angles (an addition,
    /// TROLTrajectory): a count of two bytes, and the waypoints at the record's end, after
    /// any location's values.
    Path {
        /// Most waypoints.
        max: u16,
    },
}

/// One argument of a command.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Arg {
    /// Its name, as the manual's prototype has it (`perForce`, `pDisp`).
    pub name: &'static str,
    /// Its kind.
    pub kind: ArgKind,
}

/// The form of a command's reply (after the first word, the return value). More forms may
/// come with more commands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ReplyKind {
    /// The return value alone (CAT1).
    Code,
    /// The return value and `min..=max` f32 values (a CAT2 float vector).
    Reals {
        /// Fewest values.
        min: u8,
        /// Most values.
        max: u8,
    },
    /// GetPosition's: 0, tag, numDims, six values.
    Position,
    /// GetStatus's: BIOSCalled, lastErrorCode.
    Status,
    /// GetVersion's: 0, the protocol version, and the controller's kind in words.
    Version,
    /// GetCodes': 0, then for each of the controller's BIOS codes its value, its name and
    /// its meaning (docs/protocol.md, "Codes").
    Codes,
    /// GetGripper's: 0, the opening (f32, mm), what is held (0 nothing, 1 an object, 2
    /// unknown) and the object's name (0 to 32 printable bytes, with 1 only).
    Gripper,
    /// ListLocations': 0, then for each location its name (8 bytes, NUL-padded), its tag and
    /// six values as in GetPosition (docs/protocol.md, "Locations").
    Locations,
    /// The return value and any bytes (read by the application itself).
    Bytes,
}

/// How long the host waits for the reply (the manual's default ErrAppTimeOut: 90 s more for
/// Home, no limit for Finish(FINISH_WAIT), nothing more for the others).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wait {
    /// The reply timeout (SetL3_TO_Intervall) and no more.
    Reply,
    /// The reply timeout and this many seconds more.
    Extra(u16),
    /// Without limit while the controller works (it replies when the arm is done).
    Unlimited,
    /// Without limit when argument `arg` has the wire value `value`; else [`Wait::Reply`].
    UnlimitedWhen {
        /// The argument's index.
        arg: u8,
        /// Its value.
        value: u8,
    },
}

/// A command's description.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CommandDef {
    /// The command code (the request's first byte); it gives the class.
    pub code: u8,
    /// The API function's name as in the manual (`TROLMove`).
    pub name: &'static str,
    /// The arguments, in the API's order.
    pub args: &'static [Arg],
    /// The reply's form.
    pub reply: ReplyKind,
    /// Return values besides 0 that count as success (Finish's 1 = still moving).
    pub success: &'static [i16],
    /// How long the host waits for the reply.
    pub wait: Wait,
    /// One line for `help`.
    pub help: &'static str,
}

impl CommandDef {
    /// The transaction class.
    pub const fn class(&self) -> Class {
        Class::of(self.code)
    }

    /// The name without the TROL prefix (`Move`).
    pub fn short_name(&self) -> &'static str {
        self.name.strip_prefix("TROL").unwrap_or(self.name)
    }

    /// Whether this name (any case, with or without the TROL prefix) names it.
    pub fn is_named(&self, name: &str) -> bool {
        let bare = |s: &str| {
            let lower = s.to_ascii_lowercase();
            lower.strip_prefix("trol").unwrap_or(&lower).to_string()
        };
        bare(name) == bare(self.name)
    }

    /// Whether a return value counts as success.
    pub fn is_success(&self, value: i16) -> bool {
        value == 0 || self.success.contains(&value)
    }

    /// How long the host waits for the reply to a request with these bytes, beyond the
    /// reply timeout: `None` without limit.
    pub fn extra_wait(&self, request: &[u8]) -> Option<Duration> {
        match self.wait {
            Wait::Reply => Some(Duration::ZERO),
            Wait::Extra(s) => Some(Duration::from_secs(u64::from(s))),
            Wait::Unlimited => None,
            Wait::UnlimitedWhen { arg, value } => {
                let byte = super::record::byte_of(self, arg as usize, request);
                if byte == Some(value) {
                    None
                } else {
                    Some(Duration::ZERO)
                }
            }
        }
    }
}

impl std::fmt::Display for CommandDef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name)
    }
}

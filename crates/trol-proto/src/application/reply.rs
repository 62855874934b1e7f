//! Reply records: what the controller sends back.
//!
//! The first 16-bit word is always the return value. A reply of exactly that word with a
//! TROL code (<= -32000) is valid for every command: it is how the controller refuses a
//! request it could not decode (TROL_ERR_UNKNOWN, TROL_ERR_BAD_CSIZE, ...).

use super::codes::{Class, Command};
use super::errors::{TROL_ERR_BAD_RSIZE, is_trol_code};
use super::location::{Location, Tag};

/// A reply of a built-in command, decoded.
#[derive(Clone, Debug, PartialEq)]
pub enum Reply {
    /// CAT1 (and every refusal): the return value alone.
    Code(i16),
    /// TROLGetPosition: 0 and the position, with numDims 6.
    Position(Location),
    /// TROLGetStatus: whether the BIOS was called (the return value, 0 or 1) and the last
    /// BIOS value or the TROL code that kept it from being called.
    Status {
        /// BIOSCalled.
        bios_called: bool,
        /// lastErrorCode.
        last: i16,
    },
}

impl Reply {
    /// The return value (the first word).
    pub fn value(&self) -> i16 {
        match self {
            Reply::Code(v) => *v,
            Reply::Position(_) => 0,
            Reply::Status { bios_called, .. } => *bios_called as i16,
        }
    }

    /// The record's bytes.
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(28);
        out.extend_from_slice(&self.value().to_le_bytes());
        match self {
            Reply::Code(_) => {}
            Reply::Position(loc) => {
                out.push(loc.tag() as u8);
                out.push(loc.num_dims() as u8);
                match loc {
                    Location::Prec(v) => v
                        .iter()
                        .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
                    Location::Joint(v) | Location::Cart(v) => v
                        .iter()
                        .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
                }
            }
            Reply::Status { last, .. } => out.extend_from_slice(&last.to_le_bytes()),
        }
        out
    }

    /// Decode the reply to `command` as the PC does; a size that does not fit gives
    /// TROL_ERR_BAD_RSIZE (as `Err`).
    pub fn decode(command: Command, bytes: &[u8]) -> Result<Reply, ReplyError> {
        let bad = || ReplyError {
            command,
            len: bytes.len(),
        };
        if bytes.len() < 2 {
            return Err(bad());
        }
        let value = i16::from_le_bytes([bytes[0], bytes[1]]);
        if bytes.len() == 2 && is_trol_code(value) {
            return Ok(Reply::Code(value));
        }
        match command {
            Command::GetPosition => {
                if bytes.len() < 4 || value != 0 {
                    return Err(bad());
                }
                let tag = Tag::from_u8(bytes[2]).ok_or_else(bad)?;
                let n = bytes[3] as usize;
                if n > super::location::MAX_DIMS || bytes.len() != 4 + 4 * n {
                    return Err(bad());
                }
                let words = bytes[4..].chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]);
                Ok(Reply::Position(match tag {
                    Tag::Prec => Location::Prec(words.map(i32::from_le_bytes).collect()),
                    Tag::Joint => Location::Joint(words.map(f32::from_le_bytes).collect()),
                    Tag::Cart => Location::Cart(words.map(f32::from_le_bytes).collect()),
                }))
            }
            Command::GetStatus => {
                if bytes.len() != 4 || !(value == 0 || value == 1) {
                    return Err(bad());
                }
                Ok(Reply::Status {
                    bios_called: value == 1,
                    last: i16::from_le_bytes([bytes[2], bytes[3]]),
                })
            }
            c if c.class() == Class::Cat1 || c == Command::TerminatePcp => {
                if bytes.len() == 2 {
                    Ok(Reply::Code(value))
                } else {
                    Err(bad())
                }
            }
            _ => Err(bad()),
        }
    }
}

/// A reply that does not fit its command: TROL_ERR_BAD_RSIZE.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReplyError {
    /// The command answered.
    pub command: Command,
    /// The reply's length.
    pub len: usize,
}

impl ReplyError {
    /// TROL_ERR_BAD_RSIZE.
    pub fn code(&self) -> i16 {
        TROL_ERR_BAD_RSIZE
    }
}

impl std::fmt::Display for ReplyError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "TROL_ERR_BAD_RSIZE: a reply of {} bytes does not fit {}",
            self.len, self.command
        )
    }
}

impl std::error::Error for ReplyError {}

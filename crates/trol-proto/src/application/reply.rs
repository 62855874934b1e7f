//! Reply records: what the controller sends back, in the form its command's
//! [`ReplyKind`] gives.
//!
//! The first 16-bit word is always the return value. A reply of exactly that word with a
//! TROL code (<= -32000) is valid for every command: it is how the controller refuses a
//! request it could not decode (TROL_ERR_UNKNOWN, TROL_ERR_BAD_CSIZE, ...).

use super::code::{Code, CodeInfo, CodeTable, TROL_ERR_BAD_RSIZE};
use super::command::{CommandDef, ReplyKind};
use super::location::{ARM_DIMS, LocName, Location, Tag};
use super::record::{
    MM_DECIMALS, RAD_DECIMALS, format_fixed, format_location, format_number, get_location,
    put_location,
};

/// The longest kind a GetVersion reply carries, bytes.
pub const MAX_KIND: usize = 32;
/// The longest code name a GetCodes reply carries, bytes.
pub const MAX_CODE_NAME: usize = 32;
/// The longest meaning a GetCodes reply carries for a code, bytes.
pub const MAX_CODE_MEANING: usize = 160;
/// The most codes a GetCodes reply carries.
pub const MAX_CODES: usize = 64;

/// One of a controller's BIOS codes as its GetCodes reply tells it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CodeEntry {
    /// The value (a BIOS code: above TROL's codes, not 0).
    pub value: i16,
    /// Its name (`BIOS_NOT_HOMED`): printable ASCII, 1 to [`MAX_CODE_NAME`] bytes.
    pub name: String,
    /// What it means: printable ASCII, at most [`MAX_CODE_MEANING`] bytes.
    pub meaning: String,
}

impl From<&CodeInfo> for CodeEntry {
    fn from(c: &CodeInfo) -> CodeEntry {
        CodeEntry {
            value: c.value,
            name: c.name.to_string(),
            meaning: c.meaning.to_string(),
        }
    }
}

/// What the gripper's fingers hold, as GetGripper tells it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Held {
    /// Nothing: the fingers closed on air, or are open.
    Nothing,
    /// An object, by its name where the controller knows one (a simulator does; empty
    /// otherwise): printable ASCII, at most [`MAX_KIND`] bytes.
    Object(String),
    /// The controller cannot tell (it reads the fingers' opening, not what is between them).
    Unknown,
}

/// GetGripper's answer: the fingers' opening and what they hold.
#[derive(Clone, Debug, PartialEq)]
pub struct Gripper {
    /// The opening between the fingers, mm.
    pub opening_mm: f64,
    /// What they hold.
    pub held: Held,
}

fn printable(b: &u8) -> bool {
    (0x20..0x7f).contains(b)
}

/// A reply, decoded. More forms may come with more commands.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum Reply {
    /// CAT1 (and every refusal): the return value alone.
    Code(Code),
    /// A CAT2 float vector: the return value and the values.
    Reals {
        /// The return value.
        value: Code,
        /// The values (f32 on the wire).
        values: Vec<f64>,
    },
    /// TROLGetPosition: 0 and the position, with numDims 6.
    Position(Location),
    /// TROLGetStatus: whether the BIOS was called (the return value, 0 or 1) and the last
    /// BIOS value or the TROL code that kept it from being called; which transaction that
    /// status belongs to, and the controller's epoch (it changes when the controller
    /// restarts).
    Status {
        /// BIOSCalled.
        bios_called: bool,
        /// lastErrorCode.
        last: Code,
        /// The transaction number (the PCI's low byte) of the CAT1/CAT2 request the status
        /// belongs to; 0 before the first.
        transaction: u8,
        /// The controller's epoch: a number it draws when it starts, never 0. Epoch 0 is the
        /// manual's 4-byte reply, which has neither a transaction nor an epoch (a 1998
        /// controller's, or the answer to a 1998 host): `transaction` is then 0 too, and the
        /// reply encodes as the manual's `BIOSCalled, lastErrorCode`.
        epoch: u16,
    },
    /// TROLGetVersion: the protocol version the controller speaks and what it is (`simulated
    /// A465`, `C500 over RAPL-II`; printable ASCII, 1 to [`MAX_KIND`] bytes).
    Version {
        /// The protocol version ([`super::table::PROTOCOL_VERSION`] on both ends).
        protocol: u16,
        /// The controller's kind.
        kind: String,
    },
    /// TROLGetCodes: the controller's BIOS codes, each with its name and meaning.
    Codes(Vec<CodeEntry>),
    /// TROLGetGripper: the fingers' opening and what they hold.
    Gripper(Gripper),
    /// TROLListLocations: the controller's table, each name with its location (six values).
    Locations(Vec<(LocName, Location)>),
    /// The return value and bytes the application reads itself.
    Bytes {
        /// The return value.
        value: Code,
        /// The rest of the reply.
        bytes: Vec<u8>,
    },
}

impl Reply {
    /// The return value (the first word).
    pub fn value(&self) -> Code {
        match self {
            Reply::Code(v) | Reply::Reals { value: v, .. } | Reply::Bytes { value: v, .. } => *v,
            Reply::Position(_)
            | Reply::Version { .. }
            | Reply::Codes(_)
            | Reply::Gripper(_)
            | Reply::Locations(_) => Code(0),
            Reply::Status { bios_called, .. } => Code(i16::from(*bios_called)),
        }
    }

    /// The record's bytes.
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(28);
        out.extend_from_slice(&self.value().0.to_le_bytes());
        match self {
            Reply::Code(_) => {}
            Reply::Reals { values, .. } => values
                .iter()
                .for_each(|x| out.extend_from_slice(&(*x as f32).to_le_bytes())),
            Reply::Position(loc) => {
                out.push(loc.tag() as u8);
                out.push(loc.num_dims() as u8);
                put_location(&mut out, loc);
            }
            Reply::Status {
                last,
                transaction,
                epoch,
                ..
            } => {
                out.extend_from_slice(&last.0.to_le_bytes());
                if *epoch != 0 {
                    out.extend_from_slice(&u16::from(*transaction).to_le_bytes());
                    out.extend_from_slice(&epoch.to_le_bytes());
                }
            }
            Reply::Version { protocol, kind } => {
                out.extend_from_slice(&protocol.to_le_bytes());
                out.extend(
                    kind.bytes()
                        .filter(|b| (0x20..0x7f).contains(b))
                        .take(MAX_KIND),
                );
            }
            Reply::Codes(codes) => {
                for c in codes.iter().take(MAX_CODES) {
                    out.extend_from_slice(&c.value.to_le_bytes());
                    for (text, most) in [(&c.name, MAX_CODE_NAME), (&c.meaning, MAX_CODE_MEANING)] {
                        let bytes: Vec<u8> = text.bytes().filter(printable).take(most).collect();
                        out.push(bytes.len() as u8);
                        out.extend_from_slice(&bytes);
                    }
                }
            }
            Reply::Gripper(g) => {
                out.extend_from_slice(&(g.opening_mm as f32).to_le_bytes());
                match &g.held {
                    Held::Nothing => out.push(0),
                    Held::Unknown => out.push(2),
                    Held::Object(name) => {
                        out.push(1);
                        out.extend(name.bytes().filter(printable).take(MAX_KIND));
                    }
                }
            }
            Reply::Locations(all) => {
                for (name, loc) in all.iter().take(super::table::MAX_LOCATIONS) {
                    out.extend_from_slice(&name.bytes());
                    out.push(loc.tag() as u8);
                    put_location(&mut out, &Location::from_array6(loc.tag(), loc.to_array6()));
                }
            }
            Reply::Bytes { bytes, .. } => out.extend_from_slice(bytes),
        }
        out
    }

    /// Decode the reply to a request of `def` as the PC does: only the size and form the
    /// command allows are accepted; anything else is TROL_ERR_BAD_RSIZE (as `Err`).
    pub fn decode(def: &CommandDef, bytes: &[u8]) -> Result<Reply, ReplyError> {
        let bad = || ReplyError {
            command: def.name,
            len: bytes.len(),
        };
        if bytes.len() < 2 {
            return Err(bad());
        }
        let value = Code(i16::from_le_bytes([bytes[0], bytes[1]]));
        if bytes.len() == 2 && value.is_trol() {
            return Ok(Reply::Code(value));
        }
        let rest = &bytes[2..];
        match def.reply {
            ReplyKind::Code if rest.is_empty() => Ok(Reply::Code(value)),
            ReplyKind::Code => Err(bad()),
            // A CAT2 command that failed may answer with its value alone.
            // And GetPosition refused by the robot (BIOS_BUSY while a controller runs a motion
            // and reads nothing: issue 62) answers with that BIOS code alone.
            ReplyKind::Reals { .. } | ReplyKind::Bytes | ReplyKind::Position
                if rest.is_empty() && value.0 != 0 =>
            {
                Ok(Reply::Code(value))
            }
            ReplyKind::Reals { min, max } => {
                let n = rest.len() / 4;
                if rest.len() % 4 != 0 || n < min as usize || n > max as usize {
                    return Err(bad());
                }
                let values = rest
                    .chunks_exact(4)
                    .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64)
                    .collect();
                Ok(Reply::Reals { value, values })
            }
            ReplyKind::Bytes => Ok(Reply::Bytes {
                value,
                bytes: rest.to_vec(),
            }),
            ReplyKind::Position => {
                let [tag, n, values @ ..] = rest else {
                    return Err(bad());
                };
                let tag = Tag::from_u8(*tag).ok_or_else(bad)?;
                if value.0 != 0 || *n as usize != ARM_DIMS || values.len() != 4 * ARM_DIMS {
                    return Err(bad());
                }
                Ok(Reply::Position(get_location(tag, values)))
            }
            ReplyKind::Version => {
                let [lo, hi, kind @ ..] = rest else {
                    return Err(bad());
                };
                if value.0 != 0
                    || kind.is_empty()
                    || kind.len() > MAX_KIND
                    || !kind.iter().all(|b| (0x20..0x7f).contains(b))
                {
                    return Err(bad());
                }
                Ok(Reply::Version {
                    protocol: u16::from_le_bytes([*lo, *hi]),
                    kind: String::from_utf8_lossy(kind).into_owned(),
                })
            }
            ReplyKind::Gripper => {
                let [a, b, c, d, held, name @ ..] = rest else {
                    return Err(bad());
                };
                let opening_mm = f64::from(f32::from_le_bytes([*a, *b, *c, *d]));
                let name_ok = name.len() <= MAX_KIND && name.iter().all(printable);
                let held = match held {
                    0 if name.is_empty() => Held::Nothing,
                    1 if name_ok => Held::Object(String::from_utf8_lossy(name).into_owned()),
                    2 if name.is_empty() => Held::Unknown,
                    _ => return Err(bad()),
                };
                if value.0 != 0 || !opening_mm.is_finite() || opening_mm < 0.0 {
                    return Err(bad());
                }
                Ok(Reply::Gripper(Gripper { opening_mm, held }))
            }
            ReplyKind::Locations => {
                const ENTRY: usize = 8 + 1 + 4 * ARM_DIMS;
                if value.0 != 0
                    || rest.len() % ENTRY != 0
                    || rest.len() / ENTRY > super::table::MAX_LOCATIONS
                {
                    return Err(bad());
                }
                let mut all = Vec::with_capacity(rest.len() / ENTRY);
                for entry in rest.chunks_exact(ENTRY) {
                    let name = LocName::from_bytes(&entry[..8]).map_err(|_| bad())?;
                    let tag = Tag::from_u8(entry[8]).ok_or_else(bad)?;
                    all.push((name, get_location(tag, &entry[9..])));
                }
                Ok(Reply::Locations(all))
            }
            ReplyKind::Codes => {
                if value.0 != 0 {
                    return Err(bad());
                }
                let mut codes = Vec::new();
                let mut rest = rest;
                while !rest.is_empty() {
                    let [lo, hi, more @ ..] = rest else {
                        return Err(bad());
                    };
                    let code = Code(i16::from_le_bytes([*lo, *hi]));
                    let mut texts = [String::new(), String::new()];
                    let mut more = more;
                    for (i, most) in [MAX_CODE_NAME, MAX_CODE_MEANING].into_iter().enumerate() {
                        let [n, after @ ..] = more else {
                            return Err(bad());
                        };
                        let n = *n as usize;
                        if n > most || after.len() < n || !after[..n].iter().all(printable) {
                            return Err(bad());
                        }
                        texts[i] = String::from_utf8_lossy(&after[..n]).into_owned();
                        more = &after[n..];
                    }
                    let [name, meaning] = texts;
                    // BIOS codes only: TROL's own codes and success are the host's.
                    if name.is_empty() || code.is_trol() || code.is_success() {
                        return Err(bad());
                    }
                    codes.push(CodeEntry {
                        value: code.0,
                        name,
                        meaning,
                    });
                    if codes.len() > MAX_CODES {
                        return Err(bad());
                    }
                    rest = more;
                }
                Ok(Reply::Codes(codes))
            }
            ReplyKind::Status => {
                if !(value.0 == 0 || value.0 == 1) {
                    return Err(bad());
                }
                if rest.len() == 2 {
                    // The manual's reply: BIOSCalled and lastErrorCode only.
                    return Ok(Reply::Status {
                        bios_called: value.0 == 1,
                        last: Code(i16::from_le_bytes([rest[0], rest[1]])),
                        transaction: 0,
                        epoch: 0,
                    });
                }
                // A controller never draws epoch 0, which stands for the manual's reply.
                if rest.len() != 6 || rest[3] != 0 || rest[4..6] == [0, 0] {
                    return Err(bad());
                }
                Ok(Reply::Status {
                    bios_called: value.0 == 1,
                    last: Code(i16::from_le_bytes([rest[0], rest[1]])),
                    transaction: rest[2],
                    epoch: u16::from_le_bytes([rest[4], rest[5]]),
                })
            }
        }
    }

    /// The reply in words, with the command's own meaning of a success value besides 0
    /// (TROLTrajectory's 1: TRAJECTORY_UNTIMED), else as [`Reply::text`].
    pub fn text_for(&self, def: &CommandDef, bios: &CodeTable) -> String {
        match (self, super::table::success_meaning(def.code)) {
            (Reply::Code(v), Some((value, meaning))) if v.0 == value => {
                format!("{} ({meaning})", v.0)
            }
            _ => self.text(bios),
        }
    }

    /// The reply in words: `0 (success)`, `c(400, 0, ...)`, `BIOSCalled 1, lastErrorCode 0
    /// (success)`, `0 (success), 1.5 2`; BIOS codes named from `bios`.
    pub fn text(&self, bios: &CodeTable) -> String {
        match self {
            Reply::Code(v) => v.describe(bios),
            Reply::Position(loc) => format_location(loc),
            Reply::Status {
                bios_called,
                last,
                transaction,
                epoch,
            } if *epoch == 0 => format!(
                "BIOSCalled {}, lastErrorCode {} (the manual's reply: no transaction, no epoch)",
                u8::from(*bios_called),
                last.describe(bios)
            ),
            Reply::Status {
                bios_called,
                last,
                transaction,
                epoch,
            } => format!(
                "BIOSCalled {}, lastErrorCode {}, transaction {transaction}, epoch {epoch:#06x}",
                u8::from(*bios_called),
                last.describe(bios)
            ),
            Reply::Version { protocol, kind } => format!("protocol {protocol}, {kind}"),
            Reply::Gripper(g) => format!(
                "opening {} mm, {}",
                format_fixed(g.opening_mm, MM_DECIMALS),
                match &g.held {
                    Held::Nothing => "holding nothing".to_string(),
                    Held::Object(name) if name.is_empty() => "holding an object".to_string(),
                    Held::Object(name) => format!("holding {name}"),
                    Held::Unknown => "what it holds unknown to the controller".to_string(),
                }
            ),
            Reply::Locations(all) if all.is_empty() => "no locations".to_string(),
            Reply::Locations(all) => {
                let each: Vec<String> = all
                    .iter()
                    .map(|(name, loc)| format!("{name} {}", format_location(loc)))
                    .collect();
                each.join("; ")
            }
            Reply::Codes(codes) => {
                let each: Vec<String> = codes
                    .iter()
                    .map(|c| format!("{} {}", c.value, c.name))
                    .collect();
                if each.is_empty() {
                    "BIOS codes: none".to_string()
                } else {
                    format!("BIOS codes: {}", each.join(", "))
                }
            }
            Reply::Reals { value, values } => {
                // As a person reads numbers on every surface: to 1e-6, no exponent for what
                // rounds to zero (a pose's 6.745675e-15 is 0); huge values as they are.
                let v: Vec<String> = values
                    .iter()
                    .map(|x| {
                        if x.abs() < 1e9 {
                            format_fixed(*x, RAD_DECIMALS)
                        } else {
                            format_number(*x)
                        }
                    })
                    .collect();
                format!("{}, values ({})", value.describe(bios), v.join(", "))
            }
            Reply::Bytes { value, bytes } => {
                format!("{}, bytes {bytes:02x?}", value.describe(bios))
            }
        }
    }
}

/// A reply that does not fit its command: TROL_ERR_BAD_RSIZE.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReplyError {
    /// The command answered.
    pub command: &'static str,
    /// The reply's length.
    pub len: usize,
}

impl ReplyError {
    /// TROL_ERR_BAD_RSIZE.
    pub fn code(&self) -> Code {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The fingers' opening reads as every other length does: to 0.001 mm, no exponent,
    /// no -0 (issue 44, item 2).
    #[test]
    fn the_opening_reads_to_the_micrometre() {
        for (mm, text) in [
            (3.0e-9, "0"),
            (-1e-12, "0"),
            (41.99999, "42"),
            (12.3456, "12.346"),
        ] {
            let r = Reply::Gripper(Gripper {
                opening_mm: mm,
                held: Held::Nothing,
            });
            assert_eq!(r.text(&[]), format!("opening {text} mm, holding nothing"));
        }
    }

    /// GetPosition refused by the robot answers with its BIOS code alone (issue 62: BIOS_BUSY
    /// was TROL_ERR_BAD_RSIZE); a success with no position, or a short record, is still
    /// the wrong size.
    #[test]
    fn a_getposition_refused_by_the_robot_is_its_bios_code() {
        let def = &crate::application::table::GET_POSITION;
        let busy = (-16i16).to_le_bytes();
        assert_eq!(Reply::decode(def, &busy), Ok(Reply::Code(Code(-16))));
        assert!(Reply::decode(def, &0i16.to_le_bytes()).is_err());
        assert!(Reply::decode(def, &[0, 0, 2, 6]).is_err());
    }

    /// Reals read to 1e-6 without an exponent (issue 44, item 2).
    #[test]
    fn reals_read_to_a_millionth() {
        let r = Reply::Reals {
            value: Code(0),
            values: vec![f64::from(551.51086f32), 6.745675e-15, -1e-9, 0.5, 2.5e12],
        };
        assert_eq!(
            r.text(&[]),
            "0 (success), values (551.510864, 0, 0, 0.5, 2500000000000)"
        );
    }
}

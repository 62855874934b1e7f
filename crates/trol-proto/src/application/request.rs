//! Request records: what the PC sends, byte-exact (docs/protocol.md, "Layer 4").
//!
//! Rules from the manual ("Deklaration neuer TROL Datentypen"): the first byte is the command
//! code; fields are little-endian and start on even offsets; arrays of variable length come
//! last and carry only numDims values (the controller sets the rest to 0).
//!
//! A location travels as one *dims byte* followed by its values: numDims in the high nibble,
//! the tag in bits 1-2 and the straight flag in bit 0, as the manual packs numDims and
//! straight into STROL_DEPART_DATA's second byte. Small integer arguments (force, distance,
//! speed, axis, joint, modes) fit one byte each.

use super::codes::{self, Command};
use super::errors::{TROL_ERR_ARG_RANGE, TROL_ERR_BAD_CSIZE, TROL_ERR_UNKNOWN};
use super::location::{ARM_DIMS, LocName, Location, Tag};

/// TROLFinish's mode: FINISH_STATUS (0) asks, FINISH_WAIT (1) waits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum FinishMode {
    /// FINISH_STATUS: return 1 while the arm moves, 0 when it is done.
    Status = 0,
    /// FINISH_WAIT: return when the arm is done.
    Wait = 1,
}

/// TROLGetPosition's mode: POS_COMMANDED (0) or POS_ACT (1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum PosMode {
    /// POS_COMMANDED: where the firmware tells the arm to be.
    Commanded = 0,
    /// POS_ACT: where the encoders say it is.
    Actual = 1,
}

/// A request of a built-in command, decoded.
#[derive(Clone, Debug, PartialEq)]
pub enum Request {
    /// TROLAppro(locName, pDisp, straight).
    Appro {
        /// The location approached.
        name: LocName,
        /// Displacement in the tool frame (cartesian, 1..6 values).
        disp: Vec<f32>,
        /// Straight-line motion.
        straight: bool,
    },
    /// TROLApproII(pTarget, pDisp, straight).
    ApproII {
        /// The target (precision point or cartesian).
        target: Location,
        /// Displacement in the tool frame (cartesian).
        disp: Vec<f32>,
        /// Straight-line motion.
        straight: bool,
    },
    /// TROLClose(perForce), 1..100 %.
    Close {
        /// Percent of the maximum force.
        force: u8,
    },
    /// TROLDepart(pDisp, straight).
    Depart {
        /// Displacement in the tool frame (cartesian).
        disp: Vec<f32>,
        /// Straight-line motion.
        straight: bool,
    },
    /// TROLFinish(mode).
    Finish {
        /// Ask or wait.
        mode: FinishMode,
    },
    /// TROLGrip(dist), 0..50 mm.
    Grip {
        /// Finger distance in mm.
        dist: u8,
    },
    /// TROLHalt().
    Halt,
    /// TROLHome(axis), 0 = all, 1..6 one axis.
    Home {
        /// The axis.
        axis: u8,
    },
    /// TROLJog(pDisp, straight), 1..3 values in the world frame.
    Jog {
        /// dx, dy, dz in mm.
        disp: Vec<f32>,
        /// Straight-line motion.
        straight: bool,
    },
    /// TROLJoint(jointNum, radians).
    Joint {
        /// 1..6.
        joint: u8,
        /// Increment in radians.
        radians: f32,
    },
    /// TROLMA(pTarget): absolute joint angles.
    Ma {
        /// Radians, joint 1 first.
        joints: Vec<f32>,
    },
    /// TROLMI(pDisp): joint increments.
    Mi {
        /// Radians, joint 1 first.
        joints: Vec<f32>,
    },
    /// TROLMove(locName, straight).
    Move {
        /// The location.
        name: LocName,
        /// Straight-line motion.
        straight: bool,
    },
    /// TROLMoveII(pTarget, straight).
    MoveII {
        /// The target (precision point or cartesian).
        target: Location,
        /// Straight-line motion.
        straight: bool,
    },
    /// TROLOpen(perForce), 1..100 %.
    Open {
        /// Percent of the maximum force.
        force: u8,
    },
    /// TROLReady().
    Ready,
    /// TROLSetToolTransform(md): cartesian, mm and radians.
    SetToolTransform {
        /// x y z yaw pitch roll (1..6 values, the rest 0).
        tool: Vec<f32>,
    },
    /// TROLSpeed(perMaxSpeed), 1..150 %.
    Speed {
        /// Percent of the maximum speed.
        percent: u8,
    },
    /// TROLGetPosition(pos, mode).
    GetPosition {
        /// The form wanted.
        tag: Tag,
        /// Commanded or actual.
        mode: PosMode,
    },
    /// TROLTerminatePCP().
    TerminatePcp,
    /// TROLGetStatus(&lastBIOSRetVal).
    GetStatus,
}

/// Why a request was refused, with the manual's code.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RequestError {
    /// TROL_ERR_UNKNOWN: no such command (or an empty request).
    Unknown(Option<u8>),
    /// TROL_ERR_BAD_CSIZE: the size does not fit the command.
    BadSize {
        /// The command.
        command: Command,
        /// What arrived.
        got: usize,
        /// What its header asks for.
        expected: usize,
    },
    /// TROL_ERR_ARG_RANGE: a field is out of its range.
    Range {
        /// The command.
        command: Command,
        /// Which field and why.
        what: String,
    },
}

impl RequestError {
    /// The manual's code.
    pub fn code(&self) -> i16 {
        match self {
            RequestError::Unknown(_) => TROL_ERR_UNKNOWN,
            RequestError::BadSize { .. } => TROL_ERR_BAD_CSIZE,
            RequestError::Range { .. } => TROL_ERR_ARG_RANGE,
        }
    }
}

impl std::fmt::Display for RequestError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RequestError::Unknown(None) => write!(f, "TROL_ERR_UNKNOWN: empty request"),
            RequestError::Unknown(Some(c)) => {
                write!(f, "TROL_ERR_UNKNOWN: unknown command code {c}")
            }
            RequestError::BadSize {
                command,
                got,
                expected,
            } => write!(
                f,
                "TROL_ERR_BAD_CSIZE: {command} request of {got} bytes, expected {expected}"
            ),
            RequestError::Range { command, what } => {
                write!(f, "TROL_ERR_ARG_RANGE: {command}: {what}")
            }
        }
    }
}

impl std::error::Error for RequestError {}

/// Pack numDims, tag and straight into one byte.
pub fn dims_byte(num_dims: usize, tag: Tag, straight: bool) -> u8 {
    ((num_dims as u8) << 4) | ((tag as u8) << 1) | straight as u8
}

/// Unpack a dims byte: (numDims, tag bits, straight, reserved bit 3 set).
fn split_dims(b: u8) -> (usize, u8, bool, bool) {
    ((b >> 4) as usize, (b >> 1) & 3, b & 1 != 0, b & 8 != 0)
}

fn put_f32s(out: &mut Vec<u8>, v: &[f32]) {
    for x in v {
        out.extend_from_slice(&x.to_le_bytes());
    }
}

fn put_location(out: &mut Vec<u8>, loc: &Location) {
    match loc {
        Location::Prec(v) => v
            .iter()
            .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        Location::Joint(v) | Location::Cart(v) => put_f32s(out, v),
    }
}

impl Request {
    /// The command.
    pub fn command(&self) -> Command {
        match self {
            Request::Appro { .. } => Command::Appro,
            Request::ApproII { .. } => Command::ApproII,
            Request::Close { .. } => Command::Close,
            Request::Depart { .. } => Command::Depart,
            Request::Finish { .. } => Command::Finish,
            Request::Grip { .. } => Command::Grip,
            Request::Halt => Command::Halt,
            Request::Home { .. } => Command::Home,
            Request::Jog { .. } => Command::Jog,
            Request::Joint { .. } => Command::Joint,
            Request::Ma { .. } => Command::Ma,
            Request::Mi { .. } => Command::Mi,
            Request::Move { .. } => Command::Move,
            Request::MoveII { .. } => Command::MoveII,
            Request::Open { .. } => Command::Open,
            Request::Ready => Command::Ready,
            Request::SetToolTransform { .. } => Command::SetToolTransform,
            Request::Speed { .. } => Command::Speed,
            Request::GetPosition { .. } => Command::GetPosition,
            Request::TerminatePcp => Command::TerminatePcp,
            Request::GetStatus => Command::GetStatus,
        }
    }

    /// Check every field against its range (the host does this before sending, the
    /// controller again after receiving).
    pub fn validate(&self) -> Result<(), RequestError> {
        let command = self.command();
        let range = |what: String| Err(RequestError::Range { command, what });
        let dims = |name: &str, n: usize, max: usize| {
            if (1..=max).contains(&n) {
                Ok(())
            } else {
                Err(RequestError::Range {
                    command,
                    what: format!("{name} has numDims {n}, allowed 1..{max}"),
                })
            }
        };
        let finite = |name: &str, v: &[f32]| {
            if v.iter().all(|x| x.is_finite()) {
                Ok(())
            } else {
                Err(RequestError::Range {
                    command,
                    what: format!("{name} holds a value that is not a finite number"),
                })
            }
        };
        let target = |loc: &Location| -> Result<(), RequestError> {
            if loc.tag() == Tag::Joint {
                return Err(RequestError::Range {
                    command,
                    what: "the target must be POS_CART or POS_PREC, not POS_JOINT".into(),
                });
            }
            dims("the target", loc.num_dims(), ARM_DIMS)?;
            if !loc.is_finite() {
                return Err(RequestError::Range {
                    command,
                    what: "the target holds a value that is not a finite number".into(),
                });
            }
            Ok(())
        };
        match self {
            Request::Appro { disp, .. } | Request::Depart { disp, .. } => {
                dims("the displacement", disp.len(), ARM_DIMS)?;
                finite("the displacement", disp)
            }
            Request::ApproII {
                target: t, disp, ..
            } => {
                target(t)?;
                dims("the displacement", disp.len(), ARM_DIMS)?;
                finite("the displacement", disp)
            }
            Request::Close { force } | Request::Open { force } => {
                if (1..=100).contains(force) {
                    Ok(())
                } else {
                    range(format!("perForce {force} out of 1..100"))
                }
            }
            Request::Grip { dist } => {
                if *dist <= 50 {
                    Ok(())
                } else {
                    range(format!("dist {dist} out of 0..50 mm"))
                }
            }
            Request::Home { axis } => {
                if *axis <= 6 {
                    Ok(())
                } else {
                    range(format!("axis {axis} out of 0..6"))
                }
            }
            Request::Jog { disp, .. } => {
                dims("the displacement", disp.len(), 3)?;
                finite("the displacement", disp)
            }
            Request::Joint { joint, radians } => {
                if !(1..=6).contains(joint) {
                    range(format!("jointNum {joint} out of 1..6"))
                } else if !radians.is_finite() {
                    range("radians is not a finite number".into())
                } else {
                    Ok(())
                }
            }
            Request::Ma { joints } | Request::Mi { joints } => {
                dims("the joint location", joints.len(), ARM_DIMS)?;
                finite("the joint location", joints)
            }
            Request::MoveII { target: t, .. } => target(t),
            Request::SetToolTransform { tool } => {
                dims("the tool transform", tool.len(), ARM_DIMS)?;
                finite("the tool transform", tool)
            }
            Request::Speed { percent } => {
                if (1..=150).contains(percent) {
                    Ok(())
                } else {
                    range(format!("perMaxSpeed {percent} out of 1..150"))
                }
            }
            Request::Finish { .. }
            | Request::Halt
            | Request::Move { .. }
            | Request::Ready
            | Request::GetPosition { .. }
            | Request::TerminatePcp
            | Request::GetStatus => Ok(()),
        }
    }

    /// Append the record's bytes to `out`.
    pub fn encode_into(&self, out: &mut Vec<u8>) {
        out.push(self.command().code());
        match self {
            Request::Appro {
                name,
                disp,
                straight,
            } => {
                out.push(dims_byte(disp.len(), Tag::Cart, *straight));
                out.extend_from_slice(&name.bytes());
                put_f32s(out, disp);
            }
            Request::ApproII {
                target,
                disp,
                straight,
            } => {
                out.push(dims_byte(disp.len(), Tag::Cart, *straight));
                out.push(dims_byte(target.num_dims(), target.tag(), false));
                out.push(0);
                put_location(out, target);
                put_f32s(out, disp);
            }
            Request::Close { force } | Request::Open { force } => out.push(*force),
            Request::Depart { disp, straight } | Request::Jog { disp, straight } => {
                out.push(dims_byte(disp.len(), Tag::Cart, *straight));
                put_f32s(out, disp);
            }
            Request::Finish { mode } => out.push(*mode as u8),
            Request::Grip { dist } => out.push(*dist),
            Request::Home { axis } => out.push(*axis),
            Request::Joint { joint, radians } => {
                out.push(*joint);
                out.extend_from_slice(&radians.to_le_bytes());
            }
            Request::Ma { joints } | Request::Mi { joints } => {
                out.push(dims_byte(joints.len(), Tag::Joint, false));
                put_f32s(out, joints);
            }
            Request::Move { name, straight } => {
                out.push(*straight as u8);
                out.extend_from_slice(&name.bytes());
            }
            Request::MoveII { target, straight } => {
                out.push(dims_byte(target.num_dims(), target.tag(), *straight));
                put_location(out, target);
            }
            Request::SetToolTransform { tool } => {
                out.push(dims_byte(tool.len(), Tag::Cart, false));
                put_f32s(out, tool);
            }
            Request::Speed { percent } => out.push(*percent),
            Request::GetPosition { tag, mode } => {
                out.push(*tag as u8);
                out.push(*mode as u8);
            }
            Request::Halt | Request::Ready | Request::TerminatePcp | Request::GetStatus => {}
        }
    }

    /// The record's bytes.
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(32);
        self.encode_into(&mut out);
        out
    }

    /// Decode a request as the controller does: size first (TROL_ERR_BAD_CSIZE), then the
    /// fields (TROL_ERR_ARG_RANGE), for a built-in code (else TROL_ERR_UNKNOWN).
    pub fn decode(bytes: &[u8]) -> Result<Request, RequestError> {
        let Some(&code) = bytes.first() else {
            return Err(RequestError::Unknown(None));
        };
        let command = Command::from_code(code).ok_or(RequestError::Unknown(Some(code)))?;
        let mut d = Decoder {
            bytes,
            command,
            pos: 1,
        };
        let req = d.request()?;
        req.validate()?;
        Ok(req)
    }
}

struct Decoder<'a> {
    bytes: &'a [u8],
    command: Command,
    pos: usize,
}

impl Decoder<'_> {
    fn size(&self, expected: usize) -> Result<(), RequestError> {
        if self.bytes.len() == expected {
            Ok(())
        } else {
            Err(RequestError::BadSize {
                command: self.command,
                got: self.bytes.len(),
                expected,
            })
        }
    }

    fn range(&self, what: impl Into<String>) -> RequestError {
        RequestError::Range {
            command: self.command,
            what: what.into(),
        }
    }

    fn u8(&mut self) -> Result<u8, RequestError> {
        let b = *self.bytes.get(self.pos).ok_or(RequestError::BadSize {
            command: self.command,
            got: self.bytes.len(),
            expected: self.pos + 1,
        })?;
        self.pos += 1;
        Ok(b)
    }

    fn word(&mut self) -> [u8; 4] {
        let w = [
            self.bytes[self.pos],
            self.bytes[self.pos + 1],
            self.bytes[self.pos + 2],
            self.bytes[self.pos + 3],
        ];
        self.pos += 4;
        w
    }

    fn f32s(&mut self, n: usize) -> Vec<f32> {
        (0..n).map(|_| f32::from_le_bytes(self.word())).collect()
    }

    fn location(&mut self, tag: Tag, n: usize) -> Location {
        match tag {
            Tag::Prec => Location::Prec((0..n).map(|_| i32::from_le_bytes(self.word())).collect()),
            Tag::Joint => Location::Joint(self.f32s(n)),
            Tag::Cart => Location::Cart(self.f32s(n)),
        }
    }

    /// A dims byte whose tag must be `want` (or any of `allowed`); returns (n, tag, straight).
    fn dims(
        &mut self,
        allowed: &[Tag],
        straight_allowed: bool,
    ) -> Result<(usize, Tag, bool), RequestError> {
        let b = self.u8()?;
        let (n, tag_bits, straight, reserved) = split_dims(b);
        let tag = Tag::from_u8(tag_bits).filter(|t| allowed.contains(t));
        let Some(tag) = tag else {
            return Err(self.range(format!("location tag {tag_bits} not accepted here")));
        };
        if reserved || (straight && !straight_allowed) {
            return Err(self.range(format!("dims byte {b:#04x} has reserved bits set")));
        }
        Ok((n, tag, straight))
    }

    fn name(&mut self) -> Result<LocName, RequestError> {
        let raw = &self.bytes[self.pos..self.pos + 8];
        self.pos += 8;
        if raw.contains(&0) {
            return Err(self.range("a location name on the line is blank-padded, without NUL"));
        }
        LocName::from_bytes(raw).map_err(|e| self.range(e.to_string()))
    }

    fn flag(&mut self) -> Result<bool, RequestError> {
        match self.u8()? {
            0 => Ok(false),
            1 => Ok(true),
            v => Err(self.range(format!("straight flag {v}, expected 0 or 1"))),
        }
    }

    fn request(&mut self) -> Result<Request, RequestError> {
        use Command as C;
        let cart = &[Tag::Cart][..];
        let target_tags = &[Tag::Cart, Tag::Prec][..];
        let req = match self.command {
            C::Appro => {
                let (n, _, straight) = self.dims(cart, true)?;
                self.size(10 + 4 * n)?;
                let name = self.name()?;
                Request::Appro {
                    name,
                    disp: self.f32s(n),
                    straight,
                }
            }
            C::ApproII => {
                let (n, _, straight) = self.dims(cart, true)?;
                let (m, tag, _) = self.dims(target_tags, false)?;
                if self.u8()? != 0 {
                    return Err(self.range("reserved byte 3 is not 0"));
                }
                self.size(4 + 4 * m + 4 * n)?;
                let target = self.location(tag, m);
                Request::ApproII {
                    target,
                    disp: self.f32s(n),
                    straight,
                }
            }
            C::Close | C::Open | C::Grip | C::Home | C::Speed | C::Finish => {
                self.size(2)?;
                let v = self.u8()?;
                match self.command {
                    C::Close => Request::Close { force: v },
                    C::Open => Request::Open { force: v },
                    C::Grip => Request::Grip { dist: v },
                    C::Home => Request::Home { axis: v },
                    C::Speed => Request::Speed { percent: v },
                    _ => Request::Finish {
                        mode: match v {
                            0 => FinishMode::Status,
                            1 => FinishMode::Wait,
                            _ => return Err(self.range(format!("mode {v}, expected 0 or 1"))),
                        },
                    },
                }
            }
            C::Depart | C::Jog => {
                let (n, _, straight) = self.dims(cart, true)?;
                self.size(2 + 4 * n)?;
                let disp = self.f32s(n);
                if self.command == C::Depart {
                    Request::Depart { disp, straight }
                } else {
                    Request::Jog { disp, straight }
                }
            }
            C::Halt | C::Ready | C::TerminatePcp | C::GetStatus => {
                self.size(1)?;
                match self.command {
                    C::Halt => Request::Halt,
                    C::Ready => Request::Ready,
                    C::TerminatePcp => Request::TerminatePcp,
                    _ => Request::GetStatus,
                }
            }
            C::Joint => {
                self.size(6)?;
                let joint = self.u8()?;
                Request::Joint {
                    joint,
                    radians: f32::from_le_bytes(self.word()),
                }
            }
            C::Ma | C::Mi => {
                let (n, _, _) = self.dims(&[Tag::Joint], false)?;
                self.size(2 + 4 * n)?;
                let joints = self.f32s(n);
                if self.command == C::Ma {
                    Request::Ma { joints }
                } else {
                    Request::Mi { joints }
                }
            }
            C::Move => {
                self.size(10)?;
                let straight = self.flag()?;
                Request::Move {
                    name: self.name()?,
                    straight,
                }
            }
            C::MoveII => {
                let (n, tag, straight) = self.dims(target_tags, true)?;
                self.size(2 + 4 * n)?;
                Request::MoveII {
                    target: self.location(tag, n),
                    straight,
                }
            }
            C::SetToolTransform => {
                let (n, _, _) = self.dims(cart, false)?;
                self.size(2 + 4 * n)?;
                Request::SetToolTransform { tool: self.f32s(n) }
            }
            C::GetPosition => {
                self.size(3)?;
                let t = self.u8()?;
                let tag = Tag::from_u8(t).ok_or_else(|| self.range(format!("tag {t}")))?;
                let mode = match self.u8()? {
                    0 => PosMode::Commanded,
                    1 => PosMode::Actual,
                    m => return Err(self.range(format!("mode {m}, expected 0 or 1"))),
                };
                Request::GetPosition { tag, mode }
            }
        };
        Ok(req)
    }
}

/// The code a request starts with, if any.
pub fn request_code(bytes: &[u8]) -> Option<u8> {
    bytes.first().copied()
}

/// Whether a request waits on the arm for long (Home, Finish(FINISH_WAIT)): the manual's
/// default ErrAppTimeOut waits 90 s more for Home and without limit for Finish(FINISH_WAIT).
pub fn long_wait(bytes: &[u8]) -> Option<Option<std::time::Duration>> {
    match bytes {
        [codes::TROL_HOME, ..] => Some(Some(std::time::Duration::from_secs(90))),
        [codes::TROL_FINISH, m] if *m == FinishMode::Wait as u8 => Some(None),
        _ => None,
    }
}

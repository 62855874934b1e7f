//! Request records from descriptions: one layout rule for every command, its checks, and its
//! text (docs/protocol.md, "Layer 4").
//!
//! # The layout rule
//!
//! A request is laid out from its command's arguments, in the API's order, in three parts,
//! following the manual's rules for TROL records ("Deklaration neuer TROL Datentypen": the
//! code first, wide fields word-aligned, arrays of variable length last):
//!
//! 1. the command code, then one byte for each [`ArgKind::Int`] and [`ArgKind::Choice`],
//!    one *dims byte* for each [`ArgKind::Loc`], and one byte for [`ArgKind::Straight`] if the
//!    command has no location (otherwise the flag rides in bit 0 of the first location's
//!    dims byte, as the manual packs numDims and straight into STROL_DEPART_DATA);
//! 2. a zero byte if needed to reach an even offset, then 8 bytes for each
//!    [`ArgKind::Name`] and 4 (an f32) for each [`ArgKind::Real`];
//! 3. the values of each location, numDims of them, 4 bytes each (f32, or i32 counts);
//!    then a trajectory's waypoints ([`ArgKind::Path`]), each its time and six joint angles
//!    (seven f32), whose count (two bytes, little-endian) is in the first part.
//!
//! A dims byte holds numDims in bits 7..4, 0 in bit 3, the tag in bits 2..1 and the straight
//! flag (or 0) in bit 0. Fields are little-endian.
//!
//! Decoding checks the size first (TROL_ERR_BAD_CSIZE), then every field's range
//! (TROL_ERR_ARG_RANGE); encoding checks the ranges before a byte is written, so a host never
//! sends what the controller would refuse.

use super::code::{Code, TROL_ERR_ARG_RANGE, TROL_ERR_BAD_CSIZE, TROL_ERR_UNKNOWN};
use super::command::{Arg, ArgKind, CommandDef};
use super::location::{LocName, Location, MAX_TRAJECTORY_S, Tag, Waypoint};

/// A decoded argument.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    /// An [`ArgKind::Int`], or the wire value of an [`ArgKind::Choice`].
    Int(u8),
    /// An [`ArgKind::Straight`].
    Flag(bool),
    /// An [`ArgKind::Name`].
    Name(LocName),
    /// An [`ArgKind::Real`]: f64 in memory, f32 on the wire.
    Real(f64),
    /// An [`ArgKind::Loc`].
    Loc(Location),
    /// An [`ArgKind::Path`]: f64 in memory, f32 on the wire.
    Path(Vec<Waypoint>),
}

/// Why a request was refused, with the manual's code.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RequestError {
    /// TROL_ERR_UNKNOWN: no such command (or an empty request).
    Unknown(Option<u8>),
    /// TROL_ERR_BAD_CSIZE: the size does not fit the command.
    BadSize {
        /// The command's name.
        command: &'static str,
        /// What arrived.
        got: usize,
        /// What its fields ask for.
        expected: usize,
    },
    /// TROL_ERR_ARG_RANGE: an argument is out of its range or of the wrong kind.
    Range {
        /// The command's name.
        command: &'static str,
        /// The argument's name.
        arg: &'static str,
        /// What is wrong.
        what: String,
    },
}

impl RequestError {
    /// The manual's code.
    pub fn code(&self) -> Code {
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
            RequestError::Range { command, arg, what } => {
                write!(f, "TROL_ERR_ARG_RANGE: {command}: `{arg}` {what}")
            }
        }
    }
}

impl std::error::Error for RequestError {}

/// Pack numDims, tag and straight into a dims byte.
pub fn dims_byte(num_dims: usize, tag: Tag, straight: bool) -> u8 {
    ((num_dims as u8) << 4) | ((tag as u8) << 1) | straight as u8
}

/// Where each argument lives in the record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Place {
    /// A byte of the first part, at this offset (Int, Choice, a Loc's dims byte, Straight).
    Byte(usize),
    /// In bit 0 of the dims byte at this offset.
    Bit0(usize),
    /// A wide field of the second part, at this offset.
    Wide(usize),
    /// A two-byte count of the first part, at this offset (a trajectory's waypoints).
    Count(usize),
}

struct Layout {
    places: Vec<Place>,
    /// The pad byte's offset, if there is one.
    pad: Option<usize>,
    /// Where the locations' values start.
    tail: usize,
}

fn layout(def: &CommandDef) -> Layout {
    let carrier = def
        .args
        .iter()
        .position(|a| matches!(a.kind, ArgKind::Loc { .. }));
    let mut places = vec![Place::Byte(0); def.args.len()];
    let mut at = 1;
    for (i, a) in def.args.iter().enumerate() {
        match a.kind {
            ArgKind::Int { .. } | ArgKind::Choice(_) | ArgKind::Loc { .. } => {
                places[i] = Place::Byte(at);
                at += 1;
            }
            ArgKind::Straight if carrier.is_none() => {
                places[i] = Place::Byte(at);
                at += 1;
            }
            ArgKind::Path { .. } => {
                places[i] = Place::Count(at);
                at += 2;
            }
            _ => {}
        }
    }
    let has_wide = def
        .args
        .iter()
        .any(|a| matches!(a.kind, ArgKind::Name | ArgKind::Real));
    let has_loc = carrier.is_some()
        || def
            .args
            .iter()
            .any(|a| matches!(a.kind, ArgKind::Path { .. }));
    let pad = (at % 2 == 1 && (has_wide || has_loc)).then_some(at);
    if pad.is_some() {
        at += 1;
    }
    for (i, a) in def.args.iter().enumerate() {
        match a.kind {
            ArgKind::Name => {
                places[i] = Place::Wide(at);
                at += 8;
            }
            ArgKind::Real => {
                places[i] = Place::Wide(at);
                at += 4;
            }
            ArgKind::Straight => {
                if let Some(c) = carrier {
                    let Place::Byte(o) = places[c] else {
                        unreachable!("a location has a dims byte")
                    };
                    places[i] = Place::Bit0(o);
                }
            }
            _ => {}
        }
    }
    Layout {
        places,
        pad,
        tail: at,
    }
}

/// The byte of one-byte argument `arg` in `request`, if it has one (for [`CommandDef::extra_wait`]).
pub(crate) fn byte_of(def: &CommandDef, arg: usize, request: &[u8]) -> Option<u8> {
    match layout(def).places.get(arg)? {
        Place::Byte(o) => request.get(*o).copied(),
        _ => None,
    }
}

fn range(def: &CommandDef, arg: &Arg, what: impl Into<String>) -> RequestError {
    RequestError::Range {
        command: def.name,
        arg: arg.name,
        what: what.into(),
    }
}

/// Check one value against its argument's kind and range.
fn check(def: &CommandDef, arg: &Arg, value: &Value) -> Result<(), RequestError> {
    match (arg.kind, value) {
        (ArgKind::Int { min, max }, Value::Int(v)) => {
            if (min..=max).contains(v) {
                Ok(())
            } else {
                Err(range(def, arg, format!("{v} out of {min}..{max}")))
            }
        }
        (ArgKind::Choice(options), Value::Int(v)) => {
            if options.iter().any(|c| c.value == *v) {
                Ok(())
            } else {
                let names: Vec<String> = options
                    .iter()
                    .map(|c| format!("{} ({})", c.constant, c.value))
                    .collect();
                Err(range(
                    def,
                    arg,
                    format!("{v} is none of {}", names.join(", ")),
                ))
            }
        }
        (ArgKind::Name, Value::Name(n)) if n.reserved() => {
            Err(range(def, arg, super::location::reserved_message(n)))
        }
        (ArgKind::Straight, Value::Flag(_)) | (ArgKind::Name, Value::Name(_)) => Ok(()),
        (ArgKind::Real, Value::Real(x)) => {
            if (*x as f32).is_finite() {
                Ok(())
            } else {
                Err(range(
                    def,
                    arg,
                    format!("{x} is not a finite 32-bit number"),
                ))
            }
        }
        (ArgKind::Loc { tags, min, max }, Value::Loc(loc)) => {
            if !tags.contains(&loc.tag()) {
                let names: Vec<&str> = tags.iter().map(|t| t.name()).collect();
                return Err(range(
                    def,
                    arg,
                    format!("is {}, expected {}", loc.tag().name(), names.join(" or ")),
                ));
            }
            let n = loc.num_dims();
            if n < min as usize || n > max as usize {
                return Err(range(
                    def,
                    arg,
                    format!("has numDims {n}, allowed {min}..{max}"),
                ));
            }
            if !loc.is_finite() {
                return Err(range(
                    def,
                    arg,
                    "holds a value that is not a finite 32-bit number",
                ));
            }
            if let Location::Cart(v) = loc
                && let Some(why) = super::location::orientation_beyond_a_turn(v)
            {
                return Err(range(def, arg, why));
            }
            Ok(())
        }
        (ArgKind::Path { max }, Value::Path(points)) => check_path(def, arg, max, points),
        (kind, v) => Err(range(
            def,
            arg,
            format!("expects {}, got {v:?}", kind_word(kind)),
        )),
    }
}

/// A trajectory's checks: 1..=max waypoints, every value a finite f32, the times from 0 to
/// [`MAX_TRAJECTORY_S`] and strictly increasing (as they travel: two times that round to
/// the same f32 are one).
fn check_path(
    def: &CommandDef,
    arg: &Arg,
    max: u16,
    points: &[Waypoint],
) -> Result<(), RequestError> {
    if points.is_empty() || points.len() > usize::from(max) {
        return Err(range(
            def,
            arg,
            format!("has {} waypoints, allowed 1..{max}", points.len()),
        ));
    }
    let mut last: Option<f32> = None;
    for (k, p) in points.iter().enumerate() {
        let t = p.time as f32;
        if !t.is_finite() || p.joints.iter().any(|q| !(*q as f32).is_finite()) {
            return Err(range(
                def,
                arg,
                format!("waypoint {}: a value is not a finite 32-bit number", k + 1),
            ));
        }
        if !(0.0..=MAX_TRAJECTORY_S).contains(&f64::from(t)) {
            return Err(range(
                def,
                arg,
                format!(
                    "waypoint {}: time {} s is outside 0..{MAX_TRAJECTORY_S} s",
                    k + 1,
                    p.time
                ),
            ));
        }
        if let Some(before) = last {
            if t <= before {
                return Err(range(
                    def,
                    arg,
                    format!(
                        "waypoint {}: time {} s does not come after {} s (times must increase)",
                        k + 1,
                        p.time,
                        before
                    ),
                ));
            }
        }
        last = Some(t);
    }
    Ok(())
}

fn kind_word(kind: ArgKind) -> &'static str {
    match kind {
        ArgKind::Int { .. } => "a whole number",
        ArgKind::Choice(_) => "one of its words",
        ArgKind::Straight => "the straight flag",
        ArgKind::Name => "a location name",
        ArgKind::Real => "a number",
        ArgKind::Loc { .. } => "a location",
        ArgKind::Path { .. } => "a trajectory (waypoints)",
    }
}

/// Check `values` against `def`'s arguments: their number, kinds and ranges.
pub fn validate(def: &CommandDef, values: &[Value]) -> Result<(), RequestError> {
    if values.len() != def.args.len() {
        return Err(RequestError::Range {
            command: def.name,
            arg: "(arguments)",
            what: format!("{} given, {} expected", values.len(), def.args.len()),
        });
    }
    for (arg, v) in def.args.iter().zip(values) {
        check(def, arg, v)?;
    }
    Ok(())
}

/// The request of `def` with `values`, checked first.
pub fn encode(def: &CommandDef, values: &[Value]) -> Result<Vec<u8>, RequestError> {
    validate(def, values)?;
    let lay = layout(def);
    let mut out = vec![0u8; lay.tail];
    out[0] = def.code;
    for ((arg, v), place) in def.args.iter().zip(values).zip(&lay.places) {
        match (v, *place) {
            (Value::Int(b), Place::Byte(o)) => out[o] = *b,
            (Value::Flag(s), Place::Byte(o)) => out[o] = u8::from(*s),
            (Value::Flag(s), Place::Bit0(o)) => out[o] |= u8::from(*s),
            (Value::Loc(l), Place::Byte(o)) => out[o] |= dims_byte(l.num_dims(), l.tag(), false),
            (Value::Name(n), Place::Wide(o)) => out[o..o + 8].copy_from_slice(&n.bytes()),
            (Value::Real(x), Place::Wide(o)) => {
                out[o..o + 4].copy_from_slice(&(*x as f32).to_le_bytes())
            }
            (Value::Path(points), Place::Count(o)) => {
                let n = points.len() as u16;
                out[o..o + 2].copy_from_slice(&n.to_le_bytes());
            }
            _ => unreachable!("{} checked against {:?}", arg.name, arg.kind),
        }
    }
    for v in values {
        if let Value::Loc(l) = v {
            put_location(&mut out, l);
        }
    }
    for v in values {
        if let Value::Path(points) = v {
            put_waypoints(&mut out, points);
        }
    }
    Ok(out)
}

/// Append a location's values (f32, or i32 counts).
pub fn put_location(out: &mut Vec<u8>, loc: &Location) {
    match loc {
        Location::Prec(v) => v
            .iter()
            .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        Location::Joint(v) | Location::Cart(v) => v
            .iter()
            .for_each(|x| out.extend_from_slice(&(*x as f32).to_le_bytes())),
    }
}

/// Append a trajectory's waypoints: each its time and six joint angles, f32.
pub fn put_waypoints(out: &mut Vec<u8>, points: &[Waypoint]) {
    for p in points {
        out.extend_from_slice(&(p.time as f32).to_le_bytes());
        p.joints
            .iter()
            .for_each(|q| out.extend_from_slice(&(*q as f32).to_le_bytes()));
    }
}

/// The bytes of one waypoint on the wire.
pub const WAYPOINT_BYTES: usize = 28;

/// Read waypoints from `bytes` ([`WAYPOINT_BYTES`] each); f32 widen exactly to f64.
pub fn get_waypoints(bytes: &[u8]) -> Vec<Waypoint> {
    bytes
        .chunks_exact(WAYPOINT_BYTES)
        .map(|c| {
            let f = |i: usize| f32::from_le_bytes([c[i], c[i + 1], c[i + 2], c[i + 3]]) as f64;
            Waypoint {
                time: f(0),
                joints: std::array::from_fn(|j| f(4 + 4 * j)),
            }
        })
        .collect()
}

/// Read `n` values of `tag` from `bytes` (4 each); f32 widen exactly to f64.
pub fn get_location(tag: Tag, bytes: &[u8]) -> Location {
    let words = bytes.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]);
    match tag {
        Tag::Prec => Location::Prec(words.map(i32::from_le_bytes).collect()),
        Tag::Joint => Location::Joint(words.map(|w| f32::from_le_bytes(w) as f64).collect()),
        Tag::Cart => Location::Cart(words.map(|w| f32::from_le_bytes(w) as f64).collect()),
    }
}

/// Decode a request of `def` as the controller does: size first (TROL_ERR_BAD_CSIZE), then
/// the fields (TROL_ERR_ARG_RANGE).
pub fn decode(def: &CommandDef, bytes: &[u8]) -> Result<Vec<Value>, RequestError> {
    match bytes.first() {
        None => return Err(RequestError::Unknown(None)),
        Some(&c) if c != def.code => return Err(RequestError::Unknown(Some(c))),
        _ => {}
    }
    let lay = layout(def);
    let bad_size = |expected: usize| RequestError::BadSize {
        command: def.name,
        got: bytes.len(),
        expected,
    };
    if bytes.len() < lay.tail {
        return Err(bad_size(lay.tail));
    }
    // The locations' sizes come from their dims bytes, a trajectory's from its count.
    let mut expected = lay.tail;
    for (arg, place) in def.args.iter().zip(&lay.places) {
        match (arg.kind, place) {
            (ArgKind::Loc { .. }, Place::Byte(o)) => expected += 4 * usize::from(bytes[*o] >> 4),
            (ArgKind::Path { .. }, Place::Count(o)) => {
                expected +=
                    WAYPOINT_BYTES * usize::from(u16::from_le_bytes([bytes[*o], bytes[o + 1]]))
            }
            _ => {}
        }
    }
    if bytes.len() != expected {
        return Err(bad_size(expected));
    }
    if let Some(p) = lay.pad {
        if bytes[p] != 0 {
            return Err(RequestError::Range {
                command: def.name,
                arg: "(reserved)",
                what: format!("byte {p} is {}, not 0", bytes[p]),
            });
        }
    }
    let straight_bit = def.args.iter().any(|a| a.kind == ArgKind::Straight);
    let mut values = Vec::with_capacity(def.args.len());
    let mut tail = lay.tail;
    // A trajectory's waypoints follow every location's values.
    let mut path_at = lay.tail
        + def
            .args
            .iter()
            .zip(&lay.places)
            .filter_map(|(a, p)| match (a.kind, p) {
                (ArgKind::Loc { .. }, Place::Byte(o)) => Some(4 * usize::from(bytes[*o] >> 4)),
                _ => None,
            })
            .sum::<usize>();
    let mut first_loc = true;
    for (arg, place) in def.args.iter().zip(&lay.places) {
        let v = match (arg.kind, *place) {
            (ArgKind::Int { .. } | ArgKind::Choice(_), Place::Byte(o)) => Value::Int(bytes[o]),
            (ArgKind::Straight, Place::Byte(o)) => match bytes[o] {
                0 => Value::Flag(false),
                1 => Value::Flag(true),
                b => return Err(range(def, arg, format!("is {b}, expected 0 or 1"))),
            },
            (ArgKind::Straight, Place::Bit0(o)) => Value::Flag(bytes[o] & 1 != 0),
            (ArgKind::Name, Place::Wide(o)) => {
                let raw = &bytes[o..o + 8];
                if raw.contains(&0) {
                    return Err(range(
                        def,
                        arg,
                        "is not blank-padded (a name on the line has no NUL)",
                    ));
                }
                Value::Name(LocName::from_bytes(raw).map_err(|e| range(def, arg, e.to_string()))?)
            }
            (ArgKind::Real, Place::Wide(o)) => {
                Value::Real(
                    f32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]) as f64,
                )
            }
            (ArgKind::Loc { .. }, Place::Byte(o)) => {
                let b = bytes[o];
                let n = usize::from(b >> 4);
                let carries = first_loc && straight_bit;
                first_loc = false;
                if b & 0x08 != 0 || (b & 1 != 0 && !carries) {
                    return Err(range(
                        def,
                        arg,
                        format!("dims byte {b:#04x} has reserved bits set"),
                    ));
                }
                let Some(tag) = Tag::from_u8((b >> 1) & 3) else {
                    return Err(range(def, arg, format!("dims byte {b:#04x} has tag 3")));
                };
                let loc = get_location(tag, &bytes[tail..tail + 4 * n]);
                tail += 4 * n;
                Value::Loc(loc)
            }
            (ArgKind::Path { .. }, Place::Count(o)) => {
                let n = usize::from(u16::from_le_bytes([bytes[o], bytes[o + 1]]));
                let points = get_waypoints(&bytes[path_at..path_at + WAYPOINT_BYTES * n]);
                path_at += WAYPOINT_BYTES * n;
                Value::Path(points)
            }
            _ => unreachable!("the layout places every argument"),
        };
        values.push(v);
    }
    for (arg, v) in def.args.iter().zip(&values) {
        check(def, arg, v)?;
    }
    Ok(values)
}

/// A number as the interpreter reads it back exactly: the shortest text of the f32 when the
/// value is one (as everything from the wire is), else of the f64; an exponent for very
/// small or large values, no `.0` on whole numbers (`400`, `1.5707964`, `3.591889e-14`).
pub fn format_number(x: f64) -> String {
    let text = if (x as f32) as f64 == x {
        format!("{:?}", x as f32)
    } else {
        format!("{x:?}")
    };
    match text.strip_suffix(".0") {
        Some(whole) => whole.to_string(),
        None => text,
    }
}

/// The interpreter's letter of a location literal: `c`, `j` or `p`.
pub fn literal_prefix(tag: Tag) -> &'static str {
    match tag {
        Tag::Cart => "c",
        Tag::Joint => "j",
        Tag::Prec => "p",
    }
}

/// Decimals a length in millimetres is printed with: the arm's 0.001 mm.
pub const MM_DECIMALS: usize = 3;
/// Decimals an angle in radians is printed with: 1e-6 rad (0.0002 mm at a 200 mm tool).
pub const RAD_DECIMALS: usize = 6;

/// `x` to `decimals` places, as a person reads it: trailing zeros and a lone point dropped,
/// no exponent, no `-0` (what rounds to zero is `0`). Where a person reads a location: the
/// interpreter, the pendant, the logs, the locations file (issues 42 and 44); a program
/// gets the full value (`--json`, the API's floats).
pub fn format_fixed(x: f64, decimals: usize) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    let text = format!("{x:.decimals$}");
    let text = if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.')
    } else {
        &text
    };
    if text == "-0" {
        "0".to_string()
    } else {
        text.to_string()
    }
}

/// The six values of a location of `tag` as a person reads them ([`format_fixed`]):
/// millimetres to [`MM_DECIMALS`], radians to [`RAD_DECIMALS`], counts whole.
pub fn format_values(tag: Tag, v: &[f64]) -> Vec<String> {
    v.iter()
        .enumerate()
        .map(|(i, x)| match tag {
            Tag::Cart if i < 3 => format_fixed(*x, MM_DECIMALS),
            Tag::Cart | Tag::Joint => format_fixed(*x, RAD_DECIMALS),
            Tag::Prec => format_fixed(*x, 0),
        })
        .collect()
}

/// A location as the interpreter reads it: `c(400, 0, 150, 0, 1.570796, 0)`, to the
/// precision the arm has ([`format_values`]).
pub fn format_location(loc: &Location) -> String {
    let values: Vec<String> = match loc {
        Location::Prec(c) => c.iter().map(|v| v.to_string()).collect(),
        Location::Cart(v) | Location::Joint(v) => format_values(loc.tag(), v),
    };
    format!("{}({})", literal_prefix(loc.tag()), values.join(", "))
}

/// A location prints as the interpreter reads it ([`format_location`]): `println!("{loc}")`
/// gives `c(400, 0, 150, 0, 1.570796, 0)`; the values themselves keep their full precision.
impl std::fmt::Display for Location {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&format_location(self))
    }
}

/// A trajectory as the interpreter reads it: one `w(time, q1, ..., q6)` per waypoint,
/// seconds to 0.001 and radians to [`RAD_DECIMALS`]: `w(0.5, 0, 0.1, ...) w(1, ...)`.
pub fn format_path(points: &[Waypoint]) -> String {
    points
        .iter()
        .map(|p| {
            let mut v = vec![format_fixed(p.time, MM_DECIMALS)];
            v.extend(p.joints.iter().map(|q| format_fixed(*q, RAD_DECIMALS)));
            format!("w({})", v.join(", "))
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// A call as the interpreter reads it: `TROLAppro test_001 c(-90) straight`.
pub fn format_call(def: &CommandDef, values: &[Value]) -> String {
    let mut s = def.name.to_string();
    for (arg, v) in def.args.iter().zip(values) {
        let text = match (arg.kind, v) {
            (ArgKind::Choice(options), Value::Int(b)) => options
                .iter()
                .find(|c| c.value == *b)
                .map(|c| c.word.to_string())
                .unwrap_or_else(|| b.to_string()),
            (_, Value::Int(b)) => b.to_string(),
            (_, Value::Flag(true)) => "straight".into(),
            (_, Value::Flag(false)) => continue,
            (_, Value::Name(n)) => n.to_string(),
            (_, Value::Real(x)) => format_number(*x),
            (_, Value::Loc(l)) => format_location(l),
            (_, Value::Path(points)) => format_path(points),
        };
        s.push(' ');
        s.push_str(&text);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::application::table::*;

    /// A pose typed in degrees (an angle past a full turn) is refused where the record is
    /// made and where it is decoded, with the locations file's words; a full turn itself,
    /// rounded to f32 on its way, is not (issue 67, item 6).
    #[test]
    fn an_orientation_past_a_full_turn_is_refused_on_both_ends() {
        let degrees = Location::Cart(vec![400.0, 0.0, 240.0, 0.0, 90.0, 0.0]);
        let e = encode(&MOVE_II, &[Value::Loc(degrees.clone()), Value::Flag(false)]).unwrap_err();
        assert_eq!(e.code(), TROL_ERR_ARG_RANGE);
        let text = e.to_string();
        assert!(
            text.contains("pitch 90 is more than a full turn: angles are radians"),
            "{text}"
        );
        // The same bytes from a host that does not check (a 1998 program): the controller's
        // decode refuses them.
        let mut bytes = encode(
            &MOVE_II,
            &[
                Value::Loc(Location::Cart(vec![400.0, 0.0, 240.0, 0.0, 1.0, 0.0])),
                Value::Flag(false),
            ],
        )
        .unwrap();
        let at = bytes.len() - 4 * 2;
        bytes[at..at + 4].copy_from_slice(&90f32.to_le_bytes());
        assert_eq!(
            decode(&MOVE_II, &bytes).unwrap_err().code(),
            TROL_ERR_ARG_RANGE
        );
        for disp in [
            vec![-90.0, 0.0, 0.0, -400.0],
            vec![0.0, 0.0, 0.0, 0.0, 0.0, 7.0],
        ] {
            let e = encode(
                &DEPART,
                &[Value::Loc(Location::Cart(disp)), Value::Flag(false)],
            );
            assert_eq!(e.unwrap_err().code(), TROL_ERR_ARG_RANGE);
        }
        let turn = std::f64::consts::TAU;
        for ok in [
            vec![0.0, 0.0, 0.0, turn, -turn, 3.1],
            vec![1e4, -1e4, 500.0],
        ] {
            let bytes = encode(
                &MOVE_II,
                &[Value::Loc(Location::Cart(ok)), Value::Flag(false)],
            );
            decode(&MOVE_II, &bytes.unwrap()).unwrap();
        }
    }

    #[test]
    fn a_real_and_a_location_keep_their_f32_exactly() {
        let target = Location::Cart(vec![400.123456789, 0.0, 300.0]);
        let bytes = encode(&MOVE_II, &[Value::Loc(target), Value::Flag(true)]).unwrap();
        let Value::Loc(back) = &decode(&MOVE_II, &bytes).unwrap()[0] else {
            panic!()
        };
        let x = back.values()[0];
        assert_eq!(x, f64::from(400.123_456_789_f64 as f32));
        assert_eq!(format_number(x), "400.12344");
        assert_eq!(format_number(0.1), "0.1");
        assert_eq!(format_number(0.1f32 as f64), "0.1");
        assert_eq!(format_number(-90.0), "-90");
        assert_eq!(format_number(3.591889e-14f32 as f64), "3.591889e-14");
    }
}

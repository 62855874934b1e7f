//! Locations and location names (manual, "Locations", "Verwendete Datentypen").

/// The coordinate system of a location: the manual's POS_PREC, POS_JOINT, POS_CART.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Tag {
    /// POS_PREC (0): a precision point, encoder counts per joint (TLONG).
    Prec = 0,
    /// POS_JOINT (1): joint angles in radians.
    Joint = 1,
    /// POS_CART (2): x y z in mm, yaw pitch roll in radians.
    Cart = 2,
}

impl Tag {
    /// The tag with this value.
    pub fn from_u8(v: u8) -> Option<Tag> {
        match v {
            0 => Some(Tag::Prec),
            1 => Some(Tag::Joint),
            2 => Some(Tag::Cart),
            _ => None,
        }
    }

    /// The manual's constant name.
    pub fn name(self) -> &'static str {
        match self {
            Tag::Prec => "POS_PREC",
            Tag::Joint => "POS_JOINT",
            Tag::Cart => "POS_CART",
        }
    }
}

/// Most coordinates a location holds (SLocData has 8; the last two are for a gantry's extra
/// axes, which the A465 here does not have).
pub const MAX_DIMS: usize = 8;
/// Coordinates of the A465's six axes: numDims may be 1..=6 on the wire.
pub const ARM_DIMS: usize = 6;

/// One point of a trajectory (TROLTrajectory, an addition: docs/protocol.md "Trajectory"):
/// when, counted from the trajectory's start, the arm is to be at these joint angles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Waypoint {
    /// Seconds after the trajectory's start: 0 or more, strictly increasing along a
    /// trajectory (a point at 0 is where the arm stands when it starts).
    pub time: f64,
    /// The six joint angles, radians.
    pub joints: [f64; 6],
}

/// The most waypoints one TROLTrajectory carries: 28 bytes each on the wire, 14 KB for
/// all (about 15 s of line at 9600 Bd; assumption: enough for MoveIt's plans, which are
/// tens of points).
pub const MAX_WAYPOINTS: u16 = 500;
/// The latest time a waypoint may have, s (an hour: longer is a mistake of units).
pub const MAX_TRAJECTORY_S: f64 = 3600.0;

/// A location: the manual's SLocData, with numDims = the number of values.
///
/// Only the given values travel; the controller sets the rest to 0. Values are kept as f64
/// from the API to the robot backend; the wire carries the manual's 32-bit `float`, so a
/// value is rounded once, when it is encoded, and a decoded value widens back exactly.
#[derive(Clone, Debug, PartialEq)]
pub enum Location {
    /// POS_PREC: encoder counts.
    Prec(Vec<i32>),
    /// POS_JOINT: radians.
    Joint(Vec<f64>),
    /// POS_CART: mm and radians.
    Cart(Vec<f64>),
}

impl Location {
    /// Its tag.
    pub fn tag(&self) -> Tag {
        match self {
            Location::Prec(_) => Tag::Prec,
            Location::Joint(_) => Tag::Joint,
            Location::Cart(_) => Tag::Cart,
        }
    }

    /// numDims.
    pub fn num_dims(&self) -> usize {
        match self {
            Location::Prec(v) => v.len(),
            Location::Joint(v) | Location::Cart(v) => v.len(),
        }
    }

    /// The six arm coordinates as f64, missing ones 0 (counts stay counts).
    pub fn to_array6(&self) -> [f64; 6] {
        let mut out = [0.0; 6];
        match self {
            Location::Prec(v) => v
                .iter()
                .take(6)
                .enumerate()
                .for_each(|(i, x)| out[i] = *x as f64),
            Location::Joint(v) | Location::Cart(v) => {
                v.iter().take(6).enumerate().for_each(|(i, x)| out[i] = *x)
            }
        }
        out
    }

    /// A location of `tag` from six values (counts are rounded to the nearest integer).
    pub fn from_array6(tag: Tag, v: [f64; 6]) -> Location {
        match tag {
            Tag::Prec => Location::Prec(v.iter().map(|x| x.round() as i32).collect()),
            Tag::Joint => Location::Joint(v.to_vec()),
            Tag::Cart => Location::Cart(v.to_vec()),
        }
    }

    /// Whether every value is finite (no NaN or infinity) and stays finite as the wire's
    /// 32-bit float.
    pub fn is_finite(&self) -> bool {
        match self {
            Location::Prec(_) => true,
            Location::Joint(v) | Location::Cart(v) => v.iter().all(|x| (*x as f32).is_finite()),
        }
    }

    /// The values as f64 (counts converted), numDims of them.
    pub fn values(&self) -> Vec<f64> {
        match self {
            Location::Prec(v) => v.iter().map(|x| *x as f64).collect(),
            Location::Joint(v) | Location::Cart(v) => v.clone(),
        }
    }

    /// A location of `tag` with these values; counts must be whole numbers in 32-bit range.
    pub fn from_values(tag: Tag, v: &[f64]) -> Option<Location> {
        Some(match tag {
            Tag::Prec => Location::Prec(
                v.iter()
                    .map(|x| {
                        (x.fract() == 0.0 && *x >= i32::MIN as f64 && *x <= i32::MAX as f64)
                            .then_some(*x as i32)
                    })
                    .collect::<Option<Vec<i32>>>()?,
            ),
            Tag::Joint => Location::Joint(v.to_vec()),
            Tag::Cart => Location::Cart(v.to_vec()),
        })
    }
}

/// A location name (TLocName): 8 bytes, blank-padded, not NUL-terminated.
///
/// Up to 8 characters; the first a letter or `#`, the rest letters, digits or `_` (the
/// manual, "Location-Namen"). A name starting with `#` holds a precision point, any other a
/// cartesian location. One rule on every backend, the strictest real controller's
/// (docs/teach.md, "Names"): case does not tell two names apart (RAPL-II upper-cases what it
/// is typed: `up` and `UP` are one location, [`LocName::same`]), and `T1` to `T18` (and
/// `#T1` to `#T18`) are the controller's own ([`LocName::reserved`]).
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct LocName([u8; 8]);

/// Why a name is not a location name.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BadLocName(pub String);

impl std::fmt::Display for BadLocName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "bad location name {:?}: up to 8 characters, the first a letter or '#', \
             the rest letters, digits or '_'",
            self.0
        )
    }
}

impl std::error::Error for BadLocName {}

impl LocName {
    /// A name from text (checked; a NUL anywhere is refused, not taken as the end).
    pub fn new(name: &str) -> Result<LocName, BadLocName> {
        if name.contains('\0') {
            return Err(BadLocName(name.to_string()));
        }
        LocName::from_bytes(name.as_bytes())
    }

    /// A name from the 8 wire bytes or a shorter slice: blanks (or a NUL, as C strings
    /// end) close it.
    pub fn from_bytes(raw: &[u8]) -> Result<LocName, BadLocName> {
        let bad = || BadLocName(String::from_utf8_lossy(raw).into_owned());
        let end = raw
            .iter()
            .position(|&b| b == b' ' || b == 0)
            .unwrap_or(raw.len());
        let name = &raw[..end];
        // After the name only blanks (or the C string's end) may follow.
        let rest = &raw[end..];
        let rest_ok = match rest.iter().position(|&b| b == 0) {
            Some(nul) => rest[..nul].iter().all(|&b| b == b' '),
            None => rest.iter().all(|&b| b == b' '),
        };
        if name.is_empty() || name.len() > 8 || !rest_ok {
            return Err(bad());
        }
        let first_ok = name[0].is_ascii_alphabetic() || name[0] == b'#';
        let rest_chars_ok = name[1..]
            .iter()
            .all(|&b| b.is_ascii_alphanumeric() || b == b'_');
        if !first_ok || !rest_chars_ok {
            return Err(bad());
        }
        let mut out = [b' '; 8];
        out[..name.len()].copy_from_slice(name);
        Ok(LocName(out))
    }

    /// The 8 wire bytes.
    pub fn bytes(&self) -> [u8; 8] {
        self.0
    }

    /// The name without padding.
    pub fn as_str(&self) -> &str {
        let end = self.0.iter().position(|&b| b == b' ').unwrap_or(8);
        // Only ASCII was let in.
        std::str::from_utf8(&self.0[..end]).unwrap_or("")
    }

    /// Whether it names a precision point (starts with `#`).
    pub fn is_precision(&self) -> bool {
        self.0[0] == b'#'
    }

    /// Whether it names the same location as `other`: case does not count.
    pub fn same(&self, other: &LocName) -> bool {
        self.0.eq_ignore_ascii_case(&other.0)
    }

    /// Whether it is one of the names a controller keeps for itself: `T1` to
    /// [`RESERVED_SCRATCH`] (any case, with or without `#`), the scratch locations a C500
    /// backend defines for MoveII and Appro. A program's location of such a name would be
    /// overwritten there; every backend refuses it, so a program behaves the same on each.
    pub fn reserved(&self) -> bool {
        let name = self.as_str();
        let name = name.strip_prefix('#').unwrap_or(name);
        name.strip_prefix(['T', 't'])
            .filter(|n| !n.starts_with('0'))
            .and_then(|n| n.parse::<u8>().ok())
            .is_some_and(|n| (1..=RESERVED_SCRATCH).contains(&n))
    }
}

/// The highest scratch name a controller keeps for itself (`T18`, [`LocName::reserved`]).
pub const RESERVED_SCRATCH: u8 = 18;

/// Why a cartesian location's orientation is refused: one of yaw, pitch, roll (values 3..6)
/// beyond a full turn, which was almost surely written in degrees (`c(400, 0, 240, 0, 90,
/// 0)` turned the tool to pitch 1.106, 90 rad less 14 turns). The words the locations file
/// uses too. `None`: each angle within a full turn.
pub fn orientation_beyond_a_turn(values: &[f64]) -> Option<String> {
    let turn = 2.0 * std::f64::consts::PI + 1e-6;
    values
        .iter()
        .zip(["x", "y", "z", "yaw", "pitch", "roll"])
        .skip(3)
        .find(|(v, _)| v.abs() > turn)
        .map(|(v, label)| {
            format!(
                "{label} {v} is more than a full turn: angles are radians here ({v} degrees \
                 would be {:.7})",
                v.to_radians()
            )
        })
}

/// Why a reserved name is refused, with what to do.
pub fn reserved_message(name: &LocName) -> String {
    format!(
        "{name} is reserved: T1 to T{RESERVED_SCRATCH} (and #T1 to #T{RESERVED_SCRATCH}) are \
         the controller's scratch locations on a C500; choose another name"
    )
}

impl std::fmt::Debug for LocName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "LocName({:?})", self.as_str())
    }
}

impl std::fmt::Display for LocName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for LocName {
    type Err = BadLocName;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        LocName::new(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_follow_the_manual() {
        assert_eq!(LocName::new("test_001").unwrap().bytes(), *b"test_001");
        assert_eq!(LocName::new("p1").unwrap().bytes(), *b"p1      ");
        assert!(LocName::new("#home").unwrap().is_precision());
        assert_eq!(LocName::from_bytes(b"ab\0garbage").unwrap().as_str(), "ab");
        for bad in ["", "1abc", "toolong_9", "a-b", "_x", "a b", "##"] {
            assert!(LocName::new(bad).is_err(), "{bad:?}");
        }
        assert!(LocName::from_bytes(b"ab  c   ").is_err());
        assert!(LocName::new("ab\0cd").is_err());
    }

    #[test]
    fn one_rule_for_case_and_reserved_names() {
        let n = |s: &str| LocName::new(s).unwrap();
        assert!(n("up").same(&n("UP")));
        assert!(n("Test_001").same(&n("test_001")));
        assert!(!n("up").same(&n("up2")));
        for r in ["T1", "t1", "T18", "#T1", "#t18", "T9"] {
            assert!(n(r).reserved(), "{r}");
        }
        for ok in [
            "T0", "T19", "T01", "TL", "T", "T1A", "TOOL", "#T", "#T19", "p1",
        ] {
            assert!(!n(ok).reserved(), "{ok}");
        }
        assert!(reserved_message(&n("t3")).contains("t3 is reserved"));
    }
}

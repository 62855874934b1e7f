//! Return values of layer 4 (manual, "Rückgabewerte und Fehlercodes", "Fehlercodes der
//! Schicht 4").
//!
//! The first 16-bit word of every reply is a return value, a [`Code`]. Values above -32000
//! are the robot firmware's (the RAPL-BIOS's) own codes, 0 meaning success; values at or
//! below -32000 are TROL's. A BIOS value that falls into TROL's range is replaced by
//! [`TROL_RETVAL_RANGE`] on the controller, and the real value stays readable through
//! GetStatus.
//!
//! TROL's codes have their names and meanings here ([`TROL_CODES`]). The BIOS codes belong
//! to the robot backend behind the controller: each backend publishes a [`CodeTable`] of the
//! codes it can return, and [`Code::describe`] looks a value up in TROL's table and then in
//! the backend's.

/// A return value: a BIOS code (> -32000, 0 = success) or a TROL code (<= -32000).
#[derive(Clone, Copy, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Code(pub i16);

/// A code's name and the manual's (or the backend's) meaning.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CodeInfo {
    /// The value.
    pub value: i16,
    /// Its name (`TROL_ERR_COMM`, `BIOS_NOT_HOMED`).
    pub name: &'static str,
    /// What it means, in a sentence without a full stop.
    pub meaning: &'static str,
}

/// A list of codes with their names, as a backend publishes it.
pub type CodeTable = [CodeInfo];

/// The entries of `table` that TROLGetCodes could not carry whole (a name longer than
/// [`super::reply::MAX_CODE_NAME`] bytes, a meaning longer than
/// [`super::reply::MAX_CODE_MEANING`]), each as `NAME: what is too long`: a host would read
/// them cut off mid-word. Every backend's test asks for none.
pub fn too_long_for_the_wire(table: &CodeTable) -> Vec<String> {
    use super::reply::{MAX_CODE_MEANING, MAX_CODE_NAME};
    table
        .iter()
        .flat_map(|c| {
            let name = (c.name.len() > MAX_CODE_NAME)
                .then(|| format!("{}: name of {} bytes", c.name, c.name.len()));
            let meaning = (c.meaning.len() > MAX_CODE_MEANING).then(|| {
                format!(
                    "{}: meaning of {} bytes (at most {MAX_CODE_MEANING}): {:?}",
                    c.name,
                    c.meaning.len(),
                    c.meaning
                )
            });
            name.into_iter().chain(meaning)
        })
        .collect()
}

/// 0: success.
pub const SUCCESS: Code = Code(0);
/// A communication error that the layer-3 error handler could not mend (host).
pub const TROL_ERR_COMM: Code = Code(-32001);
/// The reply has not the size (or form) the command expects (host).
pub const TROL_ERR_BAD_RSIZE: Code = Code(-32002);
/// An argument of an API call is out of its range (host; the controller also uses it for a
/// request whose fields are out of range).
pub const TROL_ERR_ARG_RANGE: Code = Code(-32003);
/// No connection: the C API was called before InitTROL succeeded, or after CleanupTROL;
/// nothing was sent (host; not in the manual, where such a call failed as TROL_ERR_COMM).
pub const TROL_ERR_NOT_INIT: Code = Code(-32004);
/// The controller does not know the command code, or its robot cannot do the command
/// (controller).
pub const TROL_ERR_UNKNOWN: Code = Code(-32051);
/// The request has not the size its command expects (controller).
pub const TROL_ERR_BAD_CSIZE: Code = Code(-32052);
/// The controller could not get the command to the robot's firmware: its link failed, the
/// robot's answer to a read before it was not in the form the controller reads, or the
/// command line came back damaged and was taken back. It did not run (controller; not in
/// the manual, whose PCP called the BIOS directly).
pub const TROL_ERR_ROBOT: Code = Code(-32053);
/// The controller lost its link to the robot's firmware after the command was sent: it may
/// have run, and GetStatus reports the BIOS as called (controller; not in the manual).
pub const TROL_ERR_ROBOT_UNSURE: Code = Code(-32054);
/// The controller sent every stop it has (for a C500: HALT, ABORT, Ctrl-C) and did not see
/// the arm standing: it may still be moving (controller, Halt; not in the manual).
pub const TROL_ERR_NOT_STOPPED: Code = Code(-32055);
/// The motion this Finish waited for was halted by someone else (the pendant, another
/// program on the controller, the watchdog): the arm stands short of its target
/// (controller, Finish; not in the manual).
pub const TROL_ERR_HALTED: Code = Code(-32056);
/// The BIOS returned a value in TROL's range; GetStatus has the real one (controller, CAT1/2).
pub const TROL_RETVAL_RANGE: Code = Code(-32101);
/// The named location does not exist (controller, Move and Appro).
pub const TROL_ERR_LOCATION: Code = Code(-32102);

/// The boundary: return values at or below it are TROL codes.
pub const TROL_CODE_LIMIT: i16 = -32000;

/// Every TROL code, with its name and the manual's meaning.
pub const TROL_CODES: &CodeTable = &[
    CodeInfo {
        value: TROL_ERR_COMM.0,
        name: "TROL_ERR_COMM",
        meaning: "a communication error occurred and the error handler could not mend it",
    },
    CodeInfo {
        value: TROL_ERR_BAD_RSIZE.0,
        name: "TROL_ERR_BAD_RSIZE",
        meaning: "the reply received by the PC has not the expected size",
    },
    CodeInfo {
        value: TROL_ERR_ARG_RANGE.0,
        name: "TROL_ERR_ARG_RANGE",
        meaning: "an argument of the API call is out of range",
    },
    CodeInfo {
        value: TROL_ERR_NOT_INIT.0,
        name: "TROL_ERR_NOT_INIT",
        meaning: "no connection: InitTROL has not succeeded (or CleanupTROL ended it); \
                  nothing was sent",
    },
    CodeInfo {
        value: TROL_ERR_UNKNOWN.0,
        name: "TROL_ERR_UNKNOWN",
        meaning: "the controller cannot do this command: it does not know its code, or its \
                  robot cannot do it (a C500 in RAPL-II reads no gripper; the controller's \
                  page in docs/ says what it does); nothing ran",
    },
    CodeInfo {
        value: TROL_ERR_BAD_CSIZE.0,
        name: "TROL_ERR_BAD_CSIZE",
        meaning: "the request received by the controller has not the expected size",
    },
    CodeInfo {
        value: TROL_ERR_ROBOT.0,
        name: "TROL_ERR_ROBOT",
        meaning: "the controller could not get the command to the robot (its link failed, \
                  or the robot answered in a form it cannot read): it did not run",
    },
    CodeInfo {
        value: TROL_ERR_ROBOT_UNSURE.0,
        name: "TROL_ERR_ROBOT_UNSURE",
        meaning: "the controller cannot tell whether the command ran (its link to the robot \
                  failed after the command was sent, or the request came again after the \
                  controller restarted or with its repeat mark damaged): check the position \
                  before sending it again",
    },
    CodeInfo {
        value: TROL_ERR_NOT_STOPPED.0,
        name: "TROL_ERR_NOT_STOPPED",
        meaning: "the controller sent every stop it has and did not see the arm standing: it \
                  may still be moving; use the emergency stop",
    },
    CodeInfo {
        value: TROL_ERR_HALTED.0,
        name: "TROL_ERR_HALTED",
        meaning: "the motion was halted by someone else (the pendant, another program, the \
                  watchdog): the arm stands short of its target",
    },
    CodeInfo {
        value: TROL_RETVAL_RANGE.0,
        name: "TROL_RETVAL_RANGE",
        meaning: "the BIOS returned a value in TROL's range; GetStatus gives the real one",
    },
    CodeInfo {
        value: TROL_ERR_LOCATION.0,
        name: "TROL_ERR_LOCATION",
        meaning: "the named location does not exist",
    },
];

impl Code {
    /// The value on the wire.
    pub const fn value(self) -> i16 {
        self.0
    }

    /// Whether it is one of TROL's codes rather than the BIOS's.
    pub const fn is_trol(self) -> bool {
        self.0 <= TROL_CODE_LIMIT
    }

    /// Whether it means success.
    pub const fn is_success(self) -> bool {
        self.0 == 0
    }

    /// Its entry in TROL's table, then in `bios` (the backend's table).
    pub fn info(self, bios: &CodeTable) -> Option<&CodeInfo> {
        let table = if self.is_trol() { TROL_CODES } else { bios };
        table.iter().find(|c| c.value == self.0)
    }

    /// Its name, if TROL's table or `bios` knows it.
    pub fn name(self, bios: &CodeTable) -> Option<&'static str> {
        self.info(bios).map(|c| c.name)
    }

    /// Its meaning, if TROL's table or `bios` knows it.
    pub fn meaning(self, bios: &CodeTable) -> Option<&'static str> {
        self.info(bios).map(|c| c.meaning)
    }

    /// The value with its name: `0 (success)`, `-32102 (TROL_ERR_LOCATION)`,
    /// `-1 (BIOS_NOT_HOMED)`, `-77 (BIOS code)`.
    pub fn describe(self, bios: &CodeTable) -> String {
        match self.name(bios) {
            _ if self.is_success() => "0 (success)".to_string(),
            Some(name) => format!("{} ({name})", self.0),
            None if self.is_trol() => format!("{} (TROL code)", self.0),
            None => format!("{} (BIOS code)", self.0),
        }
    }
}

impl std::fmt::Display for Code {
    /// The value with TROL's name, if it is a TROL code: `-32102 (TROL_ERR_LOCATION)`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.describe(&[]))
    }
}

impl std::fmt::Debug for Code {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Code({})", self)
    }
}

impl From<i16> for Code {
    fn from(v: i16) -> Code {
        Code(v)
    }
}

impl From<Code> for i16 {
    fn from(c: Code) -> i16 {
        c.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_name_themselves_from_trol_and_from_the_backend() {
        const BIOS: &CodeTable = &[CodeInfo {
            value: -1,
            name: "BIOS_NOT_HOMED",
            meaning: "home first",
        }];
        assert_eq!(TROL_ERR_LOCATION.to_string(), "-32102 (TROL_ERR_LOCATION)");
        assert_eq!(Code(-1).describe(BIOS), "-1 (BIOS_NOT_HOMED)");
        assert_eq!(Code(-1).describe(&[]), "-1 (BIOS code)");
        assert_eq!(SUCCESS.describe(BIOS), "0 (success)");
        assert_eq!(Code(-32500).describe(BIOS), "-32500 (TROL code)");
        assert_eq!(Code(-1).meaning(BIOS), Some("home first"));
        // A backend cannot rename TROL's codes.
        assert_eq!(TROL_ERR_COMM.name(BIOS), Some("TROL_ERR_COMM"));
        let mut values: Vec<i16> = TROL_CODES.iter().map(|c| c.value).collect();
        values.dedup();
        assert_eq!(values.len(), TROL_CODES.len());
        assert!(TROL_CODES.iter().all(|c| Code(c.value).is_trol()));
    }
}

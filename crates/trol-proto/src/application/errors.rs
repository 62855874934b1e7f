//! Return values of layer 4 (manual, "Rückgabewerte und Fehlercodes", "Fehlercodes der
//! Schicht 4").
//!
//! The first 16-bit word of every reply is a return value. Values above -32000 are the RAPL
//! BIOS's own return codes (0 = success); values at or below -32000 are TROL's codes. A BIOS
//! value that falls into TROL's range is replaced by [`TROL_RETVAL_RANGE`] on the controller,
//! and the real value stays readable through GetStatus.

/// A communication error that the layer-3 error handler could not mend (host).
pub const TROL_ERR_COMM: i16 = -32001;
/// The reply has not the size the command expects (host).
pub const TROL_ERR_BAD_RSIZE: i16 = -32002;
/// An argument of an API call is out of its range (host; the controller also uses it for a
/// request whose fields are out of range).
pub const TROL_ERR_ARG_RANGE: i16 = -32003;
/// The controller does not know the command code (controller).
pub const TROL_ERR_UNKNOWN: i16 = -32051;
/// The request has not the size its command expects (controller).
pub const TROL_ERR_BAD_CSIZE: i16 = -32052;
/// The BIOS returned a value in TROL's range; GetStatus has the real one (controller, CAT1/2).
pub const TROL_RETVAL_RANGE: i16 = -32101;
/// The named location does not exist (controller, Move and Appro).
pub const TROL_ERR_LOCATION: i16 = -32102;

/// The boundary: return values at or below it are TROL codes.
pub const TROL_CODE_LIMIT: i16 = -32000;

/// Whether a return value is one of TROL's codes rather than the BIOS's.
pub fn is_trol_code(value: i16) -> bool {
    value <= TROL_CODE_LIMIT
}

/// Every TROL code, with its name and the manual's meaning.
pub const TROL_CODES: &[(i16, &str, &str)] = &[
    (
        TROL_ERR_COMM,
        "TROL_ERR_COMM",
        "a communication error occurred and the error handler could not mend it",
    ),
    (
        TROL_ERR_BAD_RSIZE,
        "TROL_ERR_BAD_RSIZE",
        "the reply received by the PC has not the expected size",
    ),
    (
        TROL_ERR_ARG_RANGE,
        "TROL_ERR_ARG_RANGE",
        "an argument of the API call is out of range",
    ),
    (
        TROL_ERR_UNKNOWN,
        "TROL_ERR_UNKNOWN",
        "the controller does not know the command code",
    ),
    (
        TROL_ERR_BAD_CSIZE,
        "TROL_ERR_BAD_CSIZE",
        "the request received by the controller has not the expected size",
    ),
    (
        TROL_RETVAL_RANGE,
        "TROL_RETVAL_RANGE",
        "the BIOS returned a value in TROL's range; GetStatus gives the real one",
    ),
    (
        TROL_ERR_LOCATION,
        "TROL_ERR_LOCATION",
        "the named location does not exist",
    ),
];

/// The name of a TROL code (`TROL_ERR_COMM`), if it is one.
pub fn trol_code_name(value: i16) -> Option<&'static str> {
    TROL_CODES
        .iter()
        .find(|(v, _, _)| *v == value)
        .map(|(_, n, _)| *n)
}

/// The manual's meaning of a TROL code, if it is one.
pub fn trol_code_meaning(value: i16) -> Option<&'static str> {
    TROL_CODES
        .iter()
        .find(|(v, _, _)| *v == value)
        .map(|(_, _, m)| *m)
}

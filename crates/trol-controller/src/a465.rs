//! What every backend that plans with the A465 model ([`trol_a465::arm`]) shares: the
//! planner's BIOS codes and the translation of a backend target into the model's.

use trol_a465::arm::{self, Arm, Stored, code};
use trol_proto::application::{CodeInfo, CodeTable, Location};

use crate::backend::{BackendError, Target};

/// The BIOS codes of the A465's planner (docs/a465.md, "BIOS codes"): the simulated arm's
/// table, and the first part of every backend's that plans with the model.
pub const A465_CODES: &CodeTable = &[
    CodeInfo {
        value: code::MOVING,
        name: "BIOS_MOVING",
        meaning: "the arm or the gripper still moves",
    },
    CodeInfo {
        value: code::NOT_HOMED,
        name: "BIOS_NOT_HOMED",
        meaning: "the arm must be homed first (TROLHome)",
    },
    CodeInfo {
        value: code::OUT_OF_REACH,
        name: "BIOS_OUT_OF_REACH",
        meaning: "the target or path is out of reach",
    },
    CodeInfo {
        value: code::JOINT_LIMIT,
        name: "BIOS_JOINT_LIMIT",
        meaning: "the target or path passes a joint limit",
    },
    CodeInfo {
        value: code::BELOW_TABLE,
        name: "BIOS_BELOW_TABLE",
        meaning: "the tool tip would go below the table",
    },
    CodeInfo {
        value: code::SINGULAR_PATH,
        name: "BIOS_SINGULAR_PATH",
        meaning: "the straight line passes a singularity and cannot be followed",
    },
    CodeInfo {
        value: code::BAD_ARGUMENT,
        name: "BIOS_BAD_ARGUMENT",
        meaning: "an axis number out of range or a value that is not a number",
    },
    CodeInfo {
        value: code::QUEUE_FULL,
        name: "BIOS_QUEUE_FULL",
        meaning: "the motion queue is full: wait with TROLFinish, then send the motion again",
    },
    CodeInfo {
        value: code::GRIPPER_BLOCKED,
        name: "BIOS_GRIPPER_BLOCKED",
        meaning: "an object wider than the fingers' opening is at the tool: open the gripper \
                  wider than the object before moving onto it",
    },
];

/// A backend's target as the A465 model takes it: a name from `arm`'s location table
/// (TROL_ERR_LOCATION if it has none), or the coordinates. For every backend that plans with
/// the model (the simulator, the MARS 8).
pub fn arm_target(arm: &Arm, t: &Target) -> Result<arm::Target, BackendError> {
    Ok(match t {
        Target::Name(name) => match arm.location(name.as_str()) {
            Some(Stored::Cart(v)) => arm::Target::Cart(v),
            Some(Stored::Prec(c)) => arm::Target::Prec(c.map(f64::from)),
            None => return Err(BackendError::UnknownLocation(*name)),
        },
        Target::Location(loc @ Location::Cart(_)) => arm::Target::Cart(loc.to_array6()),
        Target::Location(loc @ Location::Prec(_)) => arm::Target::Prec(loc.to_array6()),
        Target::Location(loc @ Location::Joint(_)) => arm::Target::Joints(loc.to_array6()),
    })
}

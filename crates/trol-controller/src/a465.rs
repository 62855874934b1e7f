//! What every backend that plans with the A465 model ([`trol_a465::arm`]) shares: the
//! planner's BIOS codes and the translation of a backend target into the model's.

use trol_a465::arm::{self, Arm, HereForm, Stored, code};
use trol_proto::application::table::MAX_LOCATIONS;
use trol_proto::application::{CodeInfo, CodeTable, LocName, Location, Tag};

use crate::backend::{BackendError, BiosResult, Target};

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
        value: code::TABLE_FULL,
        name: "BIOS_TABLE_FULL",
        meaning: "the location table is full (1000 locations): delete one first",
    },
    CodeInfo {
        value: code::NO_FILE,
        name: "BIOS_NO_FILE",
        meaning: "the simulator keeps no locations file: start it with --locations FILE \
                  (trol.cfg: locations = FILE) to save",
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
            Some(Stored::Joints(q)) => arm::Target::Joints(q),
            None => return Err(BackendError::UnknownLocation(*name)),
        },
        Target::Location(loc @ Location::Cart(_)) => arm::Target::Cart(loc.to_array6()),
        Target::Location(loc @ Location::Prec(_)) => arm::Target::Prec(loc.to_array6()),
        Target::Location(loc @ Location::Joint(_)) => arm::Target::Joints(loc.to_array6()),
    })
}

/// A stored location as the wire carries it.
pub fn stored_location(s: Stored) -> Location {
    match s {
        Stored::Cart(v) => Location::from_array6(Tag::Cart, v),
        Stored::Joints(q) => Location::from_array6(Tag::Joint, q),
        Stored::Prec(c) => Location::Prec(c.to_vec()),
    }
}

/// The location table of a backend that keeps it in the A465 model (the simulator, the
/// MARS 8): TROL's own, written to its locations file by Save (docs/teach.md).
pub mod table {
    use super::*;

    fn room(arm: &Arm, name: LocName) -> Result<(), BackendError> {
        if arm.locations().len() >= MAX_LOCATIONS && arm.location(name.as_str()).is_none() {
            return Err(BackendError::Refused(code::TABLE_FULL));
        }
        Ok(())
    }

    /// Here: where the arm is commanded to be at `now`, in the form `tag`, under `name`.
    pub fn here(arm: &mut Arm, name: LocName, tag: Tag, now: f64) -> BiosResult {
        room(arm, name)?;
        let form = match tag {
            Tag::Cart => HereForm::Cart,
            Tag::Joint => HereForm::Joints,
            Tag::Prec => HereForm::Prec,
        };
        let here = arm.here(form, now);
        arm.set_location(name.as_str(), here);
        Ok(code::OK)
    }

    /// Define: `loc` under `name` (counts as counts; joints and cartesian as sent).
    pub fn define(arm: &mut Arm, name: LocName, loc: &Location) -> BiosResult {
        room(arm, name)?;
        let v = loc.to_array6();
        let stored = match loc {
            Location::Cart(_) => Stored::Cart(v),
            Location::Joint(_) => Stored::Joints(v),
            Location::Prec(c) => {
                Stored::Prec(std::array::from_fn(|i| c.get(i).copied().unwrap_or(0)))
            }
        };
        arm.set_location(name.as_str(), stored);
        Ok(code::OK)
    }

    /// Delete `name`: TROL_ERR_LOCATION when there is none.
    pub fn delete(arm: &mut Arm, name: LocName) -> BiosResult {
        if arm.delete_location(name.as_str()) {
            Ok(code::OK)
        } else {
            Err(BackendError::UnknownLocation(name))
        }
    }

    /// The table, sorted by name.
    pub fn list(arm: &Arm) -> Vec<(LocName, Location)> {
        let mut all: Vec<(LocName, Location)> = arm
            .locations()
            .iter()
            .filter_map(|(n, s)| Some((LocName::new(n).ok()?, stored_location(*s))))
            .collect();
        all.sort_by(|a, b| a.0.as_str().cmp(b.0.as_str()));
        all
    }

    /// Save: write the table to `file` (through a temporary file beside it, so that a crash
    /// never leaves half a file); NO_FILE where there is none.
    pub fn save(arm: &Arm, file: Option<&std::path::Path>) -> BiosResult {
        let Some(file) = file else {
            return Ok(code::NO_FILE);
        };
        let tmp = file.with_extension("trol-tmp");
        std::fs::write(&tmp, arm.locations_text())
            .and_then(|()| std::fs::rename(&tmp, file))
            .map_err(|e| BackendError::Link(format!("cannot write {}: {e}", file.display())))?;
        Ok(code::OK)
    }
}

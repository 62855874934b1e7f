//! What every controller backend that plans with the A465 model ([`crate::arm`]) shares: the
//! planner's BIOS codes, the translation of a backend target into the model's, and the
//! location table. Here, with the arm, so that the controller's contract (trol-controller)
//! knows no arm (feature `backend`).

use crate::arm::{self, Arm, HereForm, Stored, code};
use trol_proto::application::table::MAX_LOCATIONS;
use trol_proto::application::{CodeInfo, CodeTable, LocName, Location, Tag};

use trol_controller::{BackendError, BiosResult, Target};

/// The BIOS codes every real controller's backend has beside the planner's (each backend
/// names them in its own words in its table): one number each, on every backend.
pub mod real {
    /// The arm has no power (LIMP, an e-stop, the unit's power bit).
    pub const ARM_POWER: i16 = crate::arm::code::ARM_POWER;
    /// The call has no form on this controller.
    pub const UNSUPPORTED: i16 = -11;
    /// A call that needs the arm at rest while a motion or homing has not ended.
    pub const BUSY: i16 = -16;
    /// The controller calls a motion done, and the arm stands short of its end.
    pub const NOT_AT_TARGET: i16 = -22;
}

/// The A465 planner's codes followed by a backend's own (`extra`), as one table built at
/// compile time: `N` is `A465_CODES.len() + extra.len()` (checked). Every backend that plans
/// with the model names its codes so.
pub const fn with_a465_codes<const N: usize>(extra: &[CodeInfo]) -> [CodeInfo; N] {
    assert!(
        N == A465_CODES.len() + extra.len(),
        "N must be the two tables' lengths"
    );
    let mut all = [A465_CODES[0]; N];
    let mut i = 0;
    while i < A465_CODES.len() {
        all[i] = A465_CODES[i];
        i += 1;
    }
    while i < N {
        all[i] = extra[i - A465_CODES.len()];
        i += 1;
    }
    all
}

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
        value: code::FILE_DENIED,
        name: "BIOS_FILE_DENIED",
        meaning: "the locations file may not be written (permission denied, or read-only): \
                  it was left as it is",
    },
    CodeInfo {
        value: code::DISK_FULL,
        name: "BIOS_DISK_FULL",
        meaning: "no room on the disk for the locations file: it was left as it was",
    },
    CodeInfo {
        value: code::NO_FOLDER,
        name: "BIOS_NO_FOLDER",
        meaning: "the folder of the locations file does not exist",
    },
    CodeInfo {
        value: code::SAVE_FAILED,
        name: "BIOS_SAVE_FAILED",
        meaning: "the locations file could not be written (the controller's log says why): \
                  it was left as it was",
    },
    CodeInfo {
        value: code::TOO_FAST,
        name: "BIOS_TOO_FAST",
        meaning: "the trajectory asks more speed or acceleration of a joint than it has at the \
                  speed setting: nothing moved; give it more time",
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

    /// The locations of the file at `path` for a backend's table (docs/teach.md): a file
    /// that does not exist yet, in a folder that does, is an empty table that Save creates;
    /// a missing folder, a file too large for the table, a bad line or a reserved name
    /// ([`LocName::reserved`]) is refused with what to do.
    pub fn load(path: &std::path::Path) -> Result<Vec<(String, Stored)>, String> {
        let folder = path.parent().filter(|d| !d.as_os_str().is_empty());
        if !path.exists() {
            return match folder {
                Some(d) if !d.is_dir() => Err(format!(
                    "{}: the folder {} does not exist: create it, or name a locations file \
                     in a folder that does",
                    path.display(),
                    d.display()
                )),
                _ => Ok(Vec::new()),
            };
        }
        let all = arm::read_locations(path)?;
        for (name, _) in &all {
            if let Ok(n) = LocName::new(name)
                && n.reserved()
            {
                return Err(format!(
                    "{}: {}",
                    path.display(),
                    trol_proto::application::location::reserved_message(&n)
                ));
            }
        }
        Ok(all)
    }

    /// Save: write the table to `file` (docs/teach.md, "Saving"): a temporary file beside
    /// it, written and synced, then renamed over it and the folder synced, so that neither
    /// a crash nor a full disk leaves half a file; a read-only file is not replaced. NO_FILE
    /// where there is none; each failure has its code (FILE_DENIED, DISK_FULL, NO_FOLDER,
    /// SAVE_FAILED) and its cause in the error's text.
    pub fn save(arm: &Arm, file: Option<&std::path::Path>) -> BiosResult {
        let Some(file) = file else {
            return Ok(code::NO_FILE);
        };
        write_safely(file, arm.locations_text().as_bytes())
            .map_err(|(code, why)| BackendError::Explained(code, why))?;
        Ok(code::OK)
    }

    fn write_safely(file: &std::path::Path, text: &[u8]) -> Result<(), (i16, String)> {
        use std::io::Write;
        let fail = |e: std::io::Error, what: &str| {
            let code = match e.kind() {
                std::io::ErrorKind::PermissionDenied | std::io::ErrorKind::ReadOnlyFilesystem => {
                    code::FILE_DENIED
                }
                std::io::ErrorKind::StorageFull | std::io::ErrorKind::QuotaExceeded => {
                    code::DISK_FULL
                }
                std::io::ErrorKind::NotFound => code::NO_FOLDER,
                _ => code::SAVE_FAILED,
            };
            (code, format!("cannot {what} {}: {e}", file.display()))
        };
        let old = std::fs::metadata(file).ok();
        if old.as_ref().is_some_and(|m| m.permissions().readonly()) {
            return Err((
                code::FILE_DENIED,
                format!(
                    "{} is read-only: it was left as it is (make it writable to save)",
                    file.display()
                ),
            ));
        }
        let tmp = file.with_extension("trol-tmp");
        let written = (|| {
            let mut f = std::fs::File::create(&tmp)?;
            f.write_all(text)?;
            if let Some(m) = &old {
                f.set_permissions(m.permissions())?;
            }
            f.sync_all()
        })();
        if let Err(e) = written {
            let _ = std::fs::remove_file(&tmp);
            return Err(fail(e, "write"));
        }
        if let Err(e) = std::fs::rename(&tmp, file) {
            let _ = std::fs::remove_file(&tmp);
            return Err(fail(e, "replace"));
        }
        // The rename itself outlives a crash once the folder is synced (where a folder can
        // be opened to sync, as on Unix).
        if let Some(dir) = file.parent().filter(|d| !d.as_os_str().is_empty())
            && let Ok(d) = std::fs::File::open(dir)
        {
            let _ = d.sync_all();
        }
        Ok(())
    }
}

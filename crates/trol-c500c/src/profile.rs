//! The C500C profile (docs/c500c.md, "The profile"): what the public sources leave open and
//! only the arm can settle, one TOML file per controller. A key that is not set is not
//! guessed: the calls that need it are refused before anything is sent, naming the key and
//! the probe step that measures it.

use std::path::Path;

use serde::{Deserialize, Serialize};

pub use crate::pulses::Pulses;
pub use crate::world::Angles;

/// When ash gives its prompt back after a motion command.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MotionReturn {
    /// As the motion starts: its end is waited for with `finish`.
    Start,
    /// Once it has ended.
    End,
}

/// A profile (the keys of the TOML file).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields, rename_all = "kebab-case")]
pub struct Profile {
    /// Baud rate of the front console (57600 8N1, the public sources agree).
    pub baud: u32,
    /// The ash application TROL runs (`test`, the factory one).
    pub app: String,
    /// When the prompt returns after a motion command (unset: motions are refused; `trol
    /// c500c probe`'s supervised step "motion return" measures it).
    pub motion_return: Option<MotionReturn>,
    /// How long the arm must stand short of a motion's end, with ash done, before that counts
    /// as a stop short, ms.
    pub settle_ms: u64,
    /// How long past a motion's planned end its end is looked for before it is given up as
    /// unsure, s (assumed).
    pub end_margin_s: u64,
    /// How the WORLD row's and a cartesian location's three angles compose (unset:
    /// cartesian motions are refused; `trol c500c step world-angles` reads it off the arm).
    pub world_angles: Option<Angles>,
    /// The frame the WORLD row's angles turn: TROL's tool frame turned by these right
    /// angles, yaw pitch roll in degrees (R_ash = R_TROL · R(tool-rotation); [0, 90, 0] where
    /// ash's flange frame has the world's axes with every joint at 0, as public A465 models
    /// do). Unset with `world-angles` set: TROL's tool frame itself (what the step settled
    /// before it read the frame). Either way each cartesian motion first checks the WORLD row
    /// against TROL's kinematics and refuses when they disagree; `trol c500c step
    /// world-angles` reads both off the arm.
    pub tool_rotation: Option<[f64; 3]>,
    /// A cartesian location's constant holds the WORLD row's values in the row's order, as
    /// `trol c500c step world-angles` saw on this arm (`here trolgo`, then `print trolgo`,
    /// where the first and last angles differ). Unset, TROL sees it itself at the first
    /// pose that tells, and refuses a cartesian motion that depends on it before then; set or
    /// not, a pose that tells otherwise refuses every cartesian motion.
    pub cloc_world_order: bool,
    /// The A465's encoder pulses per degree, joints 1 to 6, on this C500C (unset: an
    /// approach to a precision point is refused; `trol c500c step pulses` measures it).
    pub pulses_per_degree: Option<[f64; 6]>,
    /// `w2`'s PULSES row with every joint at 0 degrees (set with `pulses-per-degree`, by the
    /// same step).
    pub pulses_at_zero: Option<[i64; 6]>,
    /// Where the arm stands once homed, joints in degrees (not public for an A465 on a
    /// C500C): a Home is done only with the arm read there; unset, a Home is refused
    /// (BIOS_UNSETTLED) before anything is sent (`trol c500c step home-pose` reads it).
    pub home_joints: Option<[f64; 6]>,
    /// How far (degrees) each joint may stand from `home-joints` and be home (0.1, assumed).
    pub home_within_deg: f64,
}

impl Default for Profile {
    fn default() -> Profile {
        Profile {
            baud: 57600,
            app: "test".into(),
            motion_return: None,
            settle_ms: 300,
            end_margin_s: 10,
            world_angles: None,
            tool_rotation: None,
            cloc_world_order: false,
            pulses_per_degree: None,
            pulses_at_zero: None,
            home_joints: None,
            home_within_deg: 0.1,
        }
    }
}

/// The longest profile file read.
pub const MAX_FILE: u64 = 64 * 1024;

/// A profile file that cannot be used.
#[derive(Debug, thiserror::Error)]
#[error("C500C profile {file}: {message}")]
pub struct ProfileError {
    /// The file.
    pub file: String,
    /// What is wrong.
    pub message: String,
}

impl Profile {
    /// Read a profile file.
    pub fn from_file(path: &Path) -> Result<Profile, ProfileError> {
        use std::io::Read;
        let file = path.display().to_string();
        let err = |message: String| ProfileError {
            file: file.clone(),
            message,
        };
        let mut text = String::new();
        std::fs::File::open(path)
            .and_then(|f| f.take(MAX_FILE + 1).read_to_string(&mut text))
            .map_err(|e| {
                err(format!(
                    "cannot read it ({e}); `trol sim --c500c --print-profile` prints one to \
                     start from"
                ))
            })?;
        if text.len() as u64 > MAX_FILE {
            return Err(err(format!("longer than {MAX_FILE} bytes: not a profile")));
        }
        Profile::parse(&text).map_err(err)
    }

    /// Parse a profile's text.
    pub fn parse(text: &str) -> Result<Profile, String> {
        let p: Profile = toml::from_str(text).map_err(|e| e.to_string().trim().to_string())?;
        if ![9600, 19200, 38400, 57600, 115200].contains(&p.baud) {
            return Err(format!(
                "baud = {}: the C500C's console runs at 57600 (one of 9600, 19200, 38400, \
                 57600, 115200)",
                p.baud
            ));
        }
        let word = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == '-';
        if p.app.is_empty() || p.app.len() > 32 || !p.app.chars().all(word) {
            return Err(format!(
                "app = {:?}: the name of an ash application (`test`, the factory one)",
                p.app
            ));
        }
        if !(50..=5000).contains(&p.settle_ms) {
            return Err(format!("settle-ms = {}: 50 to 5000", p.settle_ms));
        }
        if !(1..=120).contains(&p.end_margin_s) {
            return Err(format!("end-margin-s = {}: 1 to 120", p.end_margin_s));
        }
        if !(0.01..=5.0).contains(&p.home_within_deg) {
            return Err(format!(
                "home-within-deg = {}: 0.01 to 5 degrees",
                p.home_within_deg
            ));
        }
        if let Some(r) = p.tool_rotation {
            if r.iter()
                .any(|a| !a.is_finite() || a.abs() > 180.0 || a % 90.0 != 0.0)
            {
                return Err(format!(
                    "tool-rotation = {r:?}: yaw, pitch and roll in right angles (-180, -90, 0,                      90 or 180 degrees each); `trol c500c step world-angles` writes it"
                ));
            }
        }
        if let Some(h) = p.home_joints {
            if h.iter().any(|v| !v.is_finite() || v.abs() > 360.0) {
                return Err(format!(
                    "home-joints = {h:?}: six joint angles in degrees, each within 360"
                ));
            }
        }
        match (p.pulses_per_degree, p.pulses_at_zero) {
            (None, None) => {}
            (Some(_), Some(_)) => p.pulses().iter().try_for_each(Pulses::check)?,
            _ => {
                return Err(
                    "pulses-per-degree and pulses-at-zero go together (`trol c500c step pulses` \
                     writes both)"
                        .into(),
                );
            }
        }
        Ok(p)
    }

    /// How the PULSES row relates to the JOINTS row, where both keys are set.
    pub fn pulses(&self) -> Option<Pulses> {
        Some(Pulses {
            per_degree: self.pulses_per_degree?,
            at_zero: self.pulses_at_zero?,
        })
    }

    /// How the WORLD row reads, where the profile says (`world-angles`, with
    /// `tool-rotation`).
    pub fn reading(&self) -> Option<crate::world::Reading> {
        self.world_angles.map(|angles| crate::world::Reading {
            angles,
            frame: self.tool_rotation.unwrap_or([0.0; 3]),
        })
    }

    /// The profile as TOML.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_are_checked_and_unknown_ones_refused() {
        assert_eq!(Profile::parse("").unwrap(), Profile::default());
        let p = Profile::parse("motion-return = \"end\"\napp = \"cell\"\nworld-angles = \"xyz\"\n")
            .unwrap();
        assert_eq!(p.motion_return, Some(MotionReturn::End));
        assert_eq!(p.world_angles, Some(Angles::Xyz));
        assert_eq!(p.app, "cell");
        assert_eq!(Profile::parse(&p.to_toml()).unwrap(), p);
        let p = Profile::parse(
            "pulses-per-degree = [1000.0, -800.0, 600.5, 561.0, 700.0, 1111.1]\n\
             pulses-at-zero = [1200, -800, 400, -2000, 500, 300]\n",
        )
        .unwrap();
        assert_eq!(p.pulses().unwrap().at_zero[3], -2000);
        assert_eq!(Profile::parse(&p.to_toml()).unwrap(), p);
        for bad in [
            "motion-return = \"later\"",
            "baud = 1200",
            "app = \"a b\"",
            "settle-ms = 0",
            "angles = \"zyx\"",
            "world-angles = \"yzx\"",
            "pulses-per-degree = [1000.0, 1000.0, 1000.0, 1000.0, 1000.0, 1000.0]",
            "pulses-at-zero = [0, 0, 0, 0, 0, 0]",
            "pulses-per-degree = [1000.0, 0.0, 1000.0, 1000.0, 1000.0, 1000.0]\n\
             pulses-at-zero = [0, 0, 0, 0, 0, 0]",
            "pulses-per-degree = [1000.0, 1000.0]\npulses-at-zero = [0, 0]",
        ] {
            assert!(Profile::parse(bad).is_err(), "{bad}");
        }
    }
}

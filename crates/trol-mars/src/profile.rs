//! The arm profile: what a MARS 8 needs to know about the A465 on its axes (docs/mars.md), one
//! TOML file per arm. CTU Prague's two arms are examples (crates/trol-mars/profiles/crs93.toml and
//! crs97.toml, every value taken from the public package ctu-crs).
//!
//! There is no safe default: without the IRC count at joint zero a coordinated move goes
//! somewhere no one asked, so `mars:` without a profile is refused at connect.

use std::path::Path;

use serde::{Deserialize, Serialize};

/// The gripper on an analog axis of the unit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Gripper {
    /// The unit's axis letter (G on CRS93, H on CRS97).
    pub axis: String,
    /// The axis position with the fingers open (TROL's 50 mm).
    pub open: f64,
    /// The axis position with the fingers closed (0 mm).
    pub closed: f64,
}

/// The regulator constants sent before the first motion (ctu-crs's initialize()).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Regulator {
    /// REGME: maximal energy per axis.
    pub me: [i64; 6],
    /// REGCFG: the axis configuration word.
    pub cfg: [i64; 6],
    /// REGP, REGI, REGD: the PID constants.
    pub p: [i64; 6],
    /// REGI.
    pub i: [i64; 6],
    /// REGD.
    pub d: [i64; 6],
    /// IDLEREL, ms.
    pub idlerel: i64,
}

/// One arm on one MARS 8.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Profile {
    /// The arm's name, for logs.
    pub name: String,
    /// Where the values come from.
    #[serde(default)]
    pub source: String,
    /// Baud rate (19200 on CTU's arms; 8N1, RTS/CTS).
    #[serde(default = "default_baud")]
    pub baud: u32,
    /// The unit's axis letters of joints 1..6.
    #[serde(default = "default_axes")]
    pub axes: String,
    /// Encoder lines per motor turn.
    pub lines: [f64; 6],
    /// Gear ratios.
    pub gears: [f64; 6],
    /// +1 or -1: whether the IRC count grows with TROL's joint angle.
    pub direction: [f64; 6],
    /// The IRC count at TROL's joint zero.
    pub irc_zero: [i64; 6],
    /// One end of each axis's range, IRC.
    pub lower_irc: [i64; 6],
    /// The other end, IRC.
    pub upper_irc: [i64; 6],
    /// REGMS per axis, IRC*256/ms.
    pub speed: [i64; 6],
    /// REGACC per axis, IRC/ms.
    pub accel: [i64; 6],
    /// Hard home: the groups of axes, in order.
    pub hh_sequence: Vec<String>,
    /// Where TROLHome(0) moves after the hard home, TROL's joints in degrees.
    pub home_pose_deg: [f64; 6],
    /// The gripper, if the arm has one.
    #[serde(default)]
    pub gripper: Option<Gripper>,
    /// The regulator constants.
    pub regulator: Regulator,
    /// A motion has arrived when every axis is this close to its end, IRC.
    #[serde(default = "default_arrive")]
    pub arrive_irc: f64,
    /// How long the unit may take to report a motion as started or an arm as settled, ms.
    #[serde(default = "default_settle")]
    pub settle_ms: u64,
    /// A straight line or spline is sent as coordinated segments this long, ms.
    #[serde(default = "default_segment")]
    pub segment_ms: u64,
    /// Take the arm as homed at connect (only if it certainly is: a unit that was homed and
    /// never lost power since). Default: motions are refused until TROLHome.
    #[serde(default)]
    pub assume_homed: bool,
}

fn default_baud() -> u32 {
    19200
}
fn default_axes() -> String {
    "ABCDEF".into()
}
fn default_arrive() -> f64 {
    50.0
}
fn default_settle() -> u64 {
    1000
}
fn default_segment() -> u64 {
    100
}

/// A profile file that cannot be used.
#[derive(Debug, thiserror::Error)]
#[error("arm profile {file}: {message}")]
pub struct ProfileError {
    /// The file.
    pub file: String,
    /// What is wrong and what to do.
    pub message: String,
}

/// The largest profile file read.
const MAX_FILE: u64 = 64 * 1024;

impl Profile {
    /// CTU Prague's CRS93 (crates/trol-mars/profiles/crs93.toml).
    pub fn crs93() -> Profile {
        Profile::parse(include_str!("../profiles/crs93.toml")).expect("crs93.toml")
    }

    /// CTU Prague's CRS97 (crates/trol-mars/profiles/crs97.toml).
    pub fn crs97() -> Profile {
        Profile::parse(include_str!("../profiles/crs97.toml")).expect("crs97.toml")
    }

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
                    "cannot read it ({e}); crates/trol-mars/profiles/crs93.toml is one to start from, \
                     `trol sim --mars --print-profile` prints the simulated arm's"
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
        p.check()?;
        Ok(p)
    }

    /// The profile as TOML.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("a profile is TOML")
    }

    /// Check what the types cannot.
    pub fn check(&self) -> Result<(), String> {
        if !(300..=4_000_000).contains(&self.baud) {
            return Err(format!("`baud = {}`: expected 300 to 4000000", self.baud));
        }
        let letters: Vec<char> = self.axes.chars().collect();
        if letters.len() != 6 || letters.iter().any(|c| !c.is_ascii_uppercase()) {
            return Err(format!(
                "`axes = \"{}\"`: expected six axis letters, joint 1 first (\"ABCDEF\")",
                self.axes
            ));
        }
        for j in 0..6 {
            let n = j + 1;
            if !(self.lines[j] > 0.0 && self.lines[j].is_finite()) {
                return Err(format!("`lines`: joint {n} needs a positive count"));
            }
            if !(self.gears[j] > 0.0 && self.gears[j].is_finite()) {
                return Err(format!("`gears`: joint {n} needs a positive ratio"));
            }
            if self.direction[j] != 1.0 && self.direction[j] != -1.0 {
                return Err(format!("`direction`: joint {n} must be 1 or -1"));
            }
            let (lo, hi) = self.range_irc(j);
            if !(lo..=hi).contains(&self.irc_zero[j]) {
                return Err(format!(
                    "joint {n}: `irc_zero` {} lies outside its range {lo}..{hi}",
                    self.irc_zero[j]
                ));
            }
            if self.speed[j] <= 0 || self.accel[j] <= 0 {
                return Err(format!("joint {n}: `speed` and `accel` must be positive"));
            }
        }
        for g in &self.hh_sequence {
            if g.is_empty() || g.chars().any(|c| !self.axes.contains(c)) {
                return Err(format!(
                    "`hh_sequence`: group \"{g}\" names no axis of `axes = \"{}\"`",
                    self.axes
                ));
            }
        }
        if self.hh_sequence.concat().len() != 6
            || !self
                .axes
                .chars()
                .all(|c| self.hh_sequence.concat().contains(c))
        {
            return Err("`hh_sequence`: every axis must be homed once".into());
        }
        if let Some(g) = &self.gripper {
            if g.axis.len() != 1 || self.axes.contains(g.axis.as_str()) {
                return Err(format!(
                    "`gripper.axis = \"{}\"`: one letter, not one of the arm's axes",
                    g.axis
                ));
            }
            if !(g.open.is_finite() && g.closed.is_finite()) || g.open == g.closed {
                return Err(
                    "`gripper`: `open` and `closed` must be two different positions".into(),
                );
            }
        }
        if self.arrive_irc.is_nan() || self.arrive_irc <= 0.0 {
            return Err("`arrive_irc` must be positive".into());
        }
        if !(10..=1000).contains(&self.segment_ms) {
            return Err(format!(
                "`segment_ms = {}`: expected 10 to 1000",
                self.segment_ms
            ));
        }
        if !self.home_pose_deg.iter().all(|v| v.is_finite()) {
            return Err("`home_pose_deg`: six numbers".into());
        }
        let home = self.joints_to_irc(&self.home_pose_deg.map(f64::to_radians));
        if let Some(j) = self.outside(&home) {
            return Err(format!(
                "`home_pose_deg`: joint {} lies outside its range",
                j + 1
            ));
        }
        Ok(())
    }

    /// The axis letter of joint `j` (0-based).
    pub fn axis(&self, j: usize) -> char {
        self.axes.as_bytes()[j] as char
    }

    /// IRC counts per degree of joint `j`, signed.
    pub fn irc_per_deg(&self, j: usize) -> f64 {
        self.lines[j] * 4.0 * self.gears[j] / 360.0 * self.direction[j]
    }

    /// Each joint's top speed as the unit holds it (REGMS, IRC*256/ms), TROL's rad/s: what the
    /// planner plans with, so that a motion's time is the unit's (issue 43).
    pub fn top_speeds(&self) -> [f64; 6] {
        std::array::from_fn(|j| {
            let irc_per_s = self.speed[j] as f64 / 256.0 * 1000.0;
            (irc_per_s / self.irc_per_deg(j).abs()).to_radians()
        })
    }

    /// Joint `j`'s range, IRC, low end first.
    pub fn range_irc(&self, j: usize) -> (i64, i64) {
        let (a, b) = (self.lower_irc[j], self.upper_irc[j]);
        (a.min(b), a.max(b))
    }

    /// TROL's joints (radians) as IRC counts.
    pub fn joints_to_irc(&self, q: &[f64; 6]) -> [f64; 6] {
        std::array::from_fn(|j| self.irc_zero[j] as f64 + q[j].to_degrees() * self.irc_per_deg(j))
    }

    /// IRC counts as TROL's joints, radians.
    pub fn irc_to_joints(&self, irc: &[f64; 6]) -> [f64; 6] {
        std::array::from_fn(|j| {
            ((irc[j] - self.irc_zero[j] as f64) / self.irc_per_deg(j)).to_radians()
        })
    }

    /// The first joint (0-based) outside its range.
    pub fn outside(&self, irc: &[f64; 6]) -> Option<usize> {
        (0..6).find(|&j| {
            let (lo, hi) = self.range_irc(j);
            !(irc[j] >= lo as f64 && irc[j] <= hi as f64)
        })
    }

    /// The gripper's axis position for a finger distance, mm (0 = closed, 50 = open).
    pub fn gripper_position(&self, mm: f64) -> Option<f64> {
        self.gripper.as_ref().map(|g| {
            let f = (mm / trol_a465::arm::FINGER_MAX).clamp(0.0, 1.0);
            (g.closed + (g.open - g.closed) * f).round()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ctu_s_arms_convert_as_ctu_crs_does() {
        let p = Profile::crs93();
        // ctu-crs: IRC = deg(q_ctu) * irc*dir*gear*4/360 + hh_irc, and TROL's J2, J3, J5
        // are CTU's negated. Its soft home q_home = (0, 0, -45, 0, -45, 0) deg:
        let ctu_k = [1111.111, 1111.111, -1111.111, -561.111, -555.556, -561.111];
        let q_home_ctu = [0.0, 0.0, -45.0, 0.0, -45.0, 0.0];
        let theirs: Vec<f64> = (0..6)
            .map(|j| q_home_ctu[j] * ctu_k[j] + p.irc_zero[j] as f64)
            .collect();
        let ours = p.joints_to_irc(&p.home_pose_deg.map(f64::to_radians));
        for j in 0..6 {
            assert!(
                (ours[j] - theirs[j]).abs() < 1.0,
                "{j}: {ours:?} {theirs:?}"
            );
        }
        let back = p.irc_to_joints(&ours);
        for (b, h) in back.iter().zip(p.home_pose_deg) {
            assert!((b.to_degrees() - h).abs() < 1e-9);
        }
        assert_eq!(Profile::parse(&p.to_toml()).unwrap(), p);
        assert_eq!(Profile::crs97().gripper.unwrap().axis, "H");
    }

    #[test]
    fn a_profile_that_would_move_the_arm_wrongly_is_refused_with_its_key() {
        let text = include_str!("../profiles/crs93.toml");
        for (from, to, key) in [
            ("direction = [1, -1", "direction = [2, -1", "direction"),
            ("axes = \"ABCDEF\"", "axes = \"ABCDE\"", "axes"),
            (
                "hh_sequence = [\"B\", \"AC\", \"DEF\"]",
                "hh_sequence = [\"B\", \"AC\"]",
                "hh_sequence",
            ),
            ("irc_zero = [-181650", "irc_zero = [-481650", "irc_zero"),
            ("axis = \"G\"", "axis = \"A\"", "gripper.axis"),
            ("name = \"CRS93\"", "nmae = \"CRS93\"", "nmae"),
        ] {
            let bad = text.replace(from, to);
            assert_ne!(bad, text);
            let e = Profile::parse(&bad).unwrap_err();
            assert!(e.contains(key), "{key}: {e}");
        }
    }
}

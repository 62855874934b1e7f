//! First contact with a controller (`trol rapl probe`, c500-rapl.md §1.6): a session that sends
//! only commands that cannot move the arm, records every byte, and, from W2 readings taken at
//! poses the operator sets by pendant, fits what the public sources leave open: the length
//! units, the order and signs of the WORLD angles, and the units of the JOINTS row.
//!
//! The fit compares each reading with itself: the PULSES row gives the joints through the
//! A465 model (docs/a465.md), the joints give the pose through trol-a465's forward kinematics,
//! and that pose must be what the WORLD row says under the fitted conventions. It assumes the
//! controller's tool is the bare flange (no TOOL set); a reading taken with another tool fits
//! nothing, and the fit says so.

use trol_a465::kinematics::{Kinematics, Pose};
use trol_a465::model::counts_to_joints;

use crate::backend::RaplBackend;
use crate::frames::Frames;
use crate::profile::{Profile, Units, parse_angles};
use crate::text::{Position, read_position};

/// The keywords of the commands the probe sends: none of them moves the arm or changes a
/// setting.
pub const READ_ONLY: &[&str] = &["STATUS", "SERIAL", "W0", "W2", "W5", "LISTL", "LLOC"];

/// The lines the probe sends at first contact, in order.
pub const FIRST_CONTACT: &[&str] = &["STATUS", "SERIAL", "W0", "W2", "LISTL"];

/// How far the WORLD position may be from the kinematics' (mm).
pub const POSITION_TOLERANCE_MM: f64 = 2.0;
/// How far the WORLD orientation may be from the kinematics' (degrees).
pub const ANGLE_TOLERANCE_DEG: f64 = 0.5;
/// How far the JOINTS row may be from the PULSES row's joints, in its own units (degrees, or
/// radians scaled alike).
const JOINT_TOLERANCE_DEG: f64 = 0.05;
/// A joint turned at least this far (degrees) in some reading tells degrees from radians.
const TELLING_JOINT_DEG: f64 = 5.0;

/// What the readings settle.
#[derive(Clone, Debug, PartialEq)]
pub struct Fit {
    /// The length units.
    pub units: Units,
    /// The order and signs of the WORLD angles, as the profile's `angles` writes them.
    pub angles: String,
    /// The units of the JOINTS row (`degrees` or `radians`).
    pub joint_units: String,
    /// The largest position difference over the readings, mm.
    pub position_error_mm: f64,
    /// The largest orientation difference over the readings, degrees.
    pub angle_error_deg: f64,
}

impl Fit {
    /// `profile` with the fitted keys set.
    pub fn apply(&self, profile: &Profile) -> Profile {
        Profile {
            units: self.units,
            angles: self.angles.clone(),
            joint_units: self.joint_units.clone(),
            ..profile.clone()
        }
    }
}

/// Every order and sign of the three angles, as the profile writes them.
pub fn every_angle_order() -> Vec<String> {
    const PERMS: [[usize; 3]; 6] = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    const NAMES: [&str; 3] = ["yaw", "pitch", "roll"];
    let mut out = Vec::new();
    for p in PERMS {
        for signs in 0..8u8 {
            let words: Vec<String> = (0..3)
                .map(|i| {
                    let minus = if signs & (1 << i) != 0 { "-" } else { "" };
                    format!("{minus}{}", NAMES[p[i]])
                })
                .collect();
            out.push(words.join(" "));
        }
    }
    out
}

/// The angle between two rotations, degrees.
fn rotation_distance_deg(a: &Pose, b: &Pose) -> f64 {
    let m = a.rot.transpose() * b.rot;
    let trace = m.x_axis.x + m.y_axis.y + m.z_axis.z;
    ((trace - 1.0) / 2.0).clamp(-1.0, 1.0).acos().to_degrees()
}

/// Fit the conventions from W2 (or W0) readings taken at different poses. Needs at least two
/// readings, and poses different enough to tell the candidates apart; says what to do when
/// they are not.
pub fn fit(readings: &[Position]) -> Result<Fit, String> {
    if readings.len() < 2 {
        return Err(format!(
            "{} reading(s): the fit needs at least two poses (--poses 4 is a good start)",
            readings.len()
        ));
    }
    let joints: Vec<[f64; 6]> = readings
        .iter()
        .map(|r| counts_to_joints(&r.pulses.map(|p| p as f64)))
        .collect();

    // The JOINTS row: degrees or radians of the joints the pulses give.
    let telling = joints
        .iter()
        .flatten()
        .any(|q| q.to_degrees().abs() >= TELLING_JOINT_DEG);
    if !telling {
        return Err(format!(
            "every joint stayed within {TELLING_JOINT_DEG} degrees of zero: move the arm \
             further from its zero pose in at least one reading"
        ));
    }
    let matches = |scale: f64, tol: f64| {
        readings.iter().zip(&joints).all(|(r, q)| {
            r.joints
                .iter()
                .zip(q)
                .all(|(shown, q)| (shown - q * scale).abs() <= tol)
        })
    };
    let joint_units = if matches(180.0 / std::f64::consts::PI, JOINT_TOLERANCE_DEG) {
        "degrees"
    } else if matches(1.0, JOINT_TOLERANCE_DEG.to_radians()) {
        "radians"
    } else {
        return Err(
            "the JOINTS row matches the PULSES row in neither degrees nor radians: this \
             controller's encoder counts differ from the A465 model (docs/a465.md), so the \
             fit cannot use them"
                .into(),
        );
    };

    // The poses must differ, or nothing is told apart.
    let spread = joints
        .iter()
        .skip(1)
        .map(|q| {
            q.iter()
                .zip(&joints[0])
                .map(|(a, b)| (a - b).abs().to_degrees())
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max);
    if spread < TELLING_JOINT_DEG {
        return Err(format!(
            "the poses differ by less than {TELLING_JOINT_DEG} degrees at every joint: move \
             the arm further between readings"
        ));
    }

    let kin = Kinematics::new([0.0; 6]);
    let fk: Vec<Pose> = joints.iter().map(|q| kin.fk(q)).collect();

    // Length units: the WORLD position against the kinematics'.
    let position_error = |mm: f64| {
        readings
            .iter()
            .zip(&fk)
            .map(|(r, p)| {
                let d = [
                    r.world[0] * mm - p.pos.x,
                    r.world[1] * mm - p.pos.y,
                    r.world[2] * mm - p.pos.z,
                ];
                (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
            })
            .fold(0.0, f64::max)
    };
    let (e_mm, e_inch) = (position_error(1.0), position_error(25.4));
    let (units, mm, position_error_mm) = if e_mm <= POSITION_TOLERANCE_MM {
        (Units::Mm, 1.0, e_mm)
    } else if e_inch <= POSITION_TOLERANCE_MM {
        (Units::Inch, 25.4, e_inch)
    } else {
        return Err(format!(
            "the WORLD row's x y z match the kinematics neither in mm (off by up to {e_mm:.1} mm) \
             nor in inches (off by up to {e_inch:.1} mm): check that the controller's tool is \
             the bare flange (no TOOL set) while probing"
        ));
    };

    // The angles: every order and sign, against the kinematics' rotation.
    let mut fitting = Vec::new();
    let mut best = f64::INFINITY;
    for words in every_angle_order() {
        let frames = Frames {
            mm: Some(mm),
            angles: parse_angles(&words).ok().flatten(),
        };
        let mut worst: f64 = 0.0;
        for (r, p) in readings.iter().zip(&fk) {
            let Ok(trol) = frames.from_rapl(r.world) else {
                worst = f64::INFINITY;
                break;
            };
            worst = worst.max(rotation_distance_deg(&Pose::from_xyzypr(trol), p));
        }
        best = best.min(worst);
        if worst <= ANGLE_TOLERANCE_DEG {
            fitting.push((words, worst));
        }
    }
    match fitting.len() {
        1 => {
            let (angles, angle_error_deg) = fitting.remove(0);
            Ok(Fit {
                units,
                angles,
                joint_units: joint_units.into(),
                position_error_mm,
                angle_error_deg,
            })
        }
        0 => Err(format!(
            "no order and signs of the WORLD angles match the kinematics (the best is off by \
             {best:.1} degrees): the controller's angles may have another convention or an \
             offset to TROL's (docs/a465.md); keep the transcript and set `angles` by hand"
        )),
        _ => Err(format!(
            "{} orders of the WORLD angles fit these poses ({}): tilt the wrist (joint 5 away \
             from 0 and from 90 degrees) and turn joints 4 and 6 differently in each pose, \
             then probe again",
            fitting.len(),
            fitting
                .iter()
                .map(|(w, _)| format!("\"{w}\""))
                .collect::<Vec<_>>()
                .join(", ")
        )),
    }
}

/// What first contact brought back.
#[derive(Debug, Default)]
pub struct Contact {
    /// Each line sent and its reply's text (or why it has none).
    pub replies: Vec<(String, Result<String, String>)>,
    /// The W2 readings: the one at first contact, then one per pose.
    pub readings: Vec<Position>,
    /// The fit, when poses were asked for.
    pub fit: Option<Result<Fit, String>>,
}

/// Run first contact on an open session: the lines of [`FIRST_CONTACT`], then `poses` times
/// `operator(k, poses)` (which returns once the operator has moved the arm by pendant to pose
/// k, `false` to stop early) and a W2 reading; then the fit, when `poses` > 0. Nothing sent
/// can move the arm: every line goes through [`RaplBackend::read_only`].
pub fn first_contact(
    b: &mut RaplBackend,
    poses: usize,
    operator: &mut dyn FnMut(usize, usize) -> std::io::Result<bool>,
) -> Contact {
    let mut c = Contact::default();
    for line in FIRST_CONTACT {
        let r = b
            .read_only(line)
            .map(|r| match r.error {
                Some((n, t)) => format!("{n:03}-{t}."),
                None => r.text,
            })
            .map_err(|e| e.to_string());
        if *line == "W2" {
            if let Ok(p) = r
                .as_ref()
                .map_err(|e| e.clone())
                .and_then(|t| read_position(t))
            {
                c.readings.push(p);
            }
        }
        c.replies.push((line.to_string(), r));
    }
    if poses == 0 {
        return c;
    }
    for k in 1..=poses {
        match operator(k, poses) {
            Ok(true) => {}
            Ok(false) => break,
            Err(e) => {
                c.replies.push(("(operator)".into(), Err(e.to_string())));
                break;
            }
        }
        let r = b
            .read_only("W2")
            .map_err(|e| e.to_string())
            .and_then(|r| read_position(&r.text).map(|p| (r.text, p)));
        match r {
            Ok((text, p)) => {
                c.readings.push(p);
                c.replies.push(("W2".into(), Ok(text)));
            }
            Err(e) => c.replies.push(("W2".into(), Err(e))),
        }
    }
    c.fit = Some(fit(&c.readings));
    c
}

#[cfg(test)]
mod tests {
    use super::*;
    use trol_a465::model::joints_to_counts;

    /// A reading as a controller with these conventions would print it.
    fn reading(q: [f64; 6], mm: f64, angles: &str, joints_in_degrees: bool) -> Position {
        let frames = Frames {
            mm: Some(mm),
            angles: parse_angles(angles).unwrap(),
        };
        let pose = Kinematics::new([0.0; 6]).fk_xyzypr(&q);
        Position {
            pulses: joints_to_counts(&q).map(i64::from),
            joints: if joints_in_degrees {
                q.map(f64::to_degrees)
            } else {
                q
            },
            world: frames.to_rapl(pose).unwrap(),
        }
    }

    fn poses() -> Vec<[f64; 6]> {
        [
            [10.0, 20.0, 40.0, 30.0, 50.0, -20.0],
            [-35.0, 5.0, 70.0, -60.0, 30.0, 45.0],
            [60.0, -15.0, 30.0, 15.0, -40.0, 100.0],
            [0.0, 30.0, 20.0, 90.0, 60.0, -90.0],
        ]
        .iter()
        .map(|d| d.map(f64::to_radians))
        .collect()
    }

    #[test]
    fn every_convention_is_found_from_four_poses() {
        for angles in every_angle_order() {
            for (mm, units) in [(1.0, Units::Mm), (25.4, Units::Inch)] {
                let r: Vec<Position> = poses()
                    .into_iter()
                    .map(|q| reading(q, mm, &angles, true))
                    .collect();
                let f = fit(&r).unwrap_or_else(|e| panic!("{angles} {mm}: {e}"));
                assert_eq!(f.angles, angles);
                assert_eq!(f.units, units);
                assert_eq!(f.joint_units, "degrees");
            }
        }
        let r: Vec<Position> = poses()
            .into_iter()
            .map(|q| reading(q, 1.0, "roll pitch yaw", false))
            .collect();
        assert_eq!(fit(&r).unwrap().joint_units, "radians");
    }

    #[test]
    fn poses_that_cannot_tell_say_what_to_do() {
        // The tool straight down at every pose: yaw and roll cannot be told apart.
        let kin = Kinematics::new([0.0; 6]);
        let down: Vec<Position> = [
            (400.0, 0.0, 0.0),
            (350.0, 120.0, 40.0),
            (420.0, -80.0, -60.0),
        ]
        .iter()
        .map(|&(x, y, yaw): &(f64, f64, f64)| {
            let target = Pose::from_xyzypr([
                x,
                y,
                250.0,
                yaw.to_radians(),
                std::f64::consts::FRAC_PI_2,
                0.0,
            ]);
            let q = kin.ik_nearest(&target, &[0.0; 6]).unwrap();
            reading(q, 1.0, "yaw pitch roll", true)
        })
        .collect();
        let e = fit(&down).unwrap_err();
        assert!(e.contains("tilt the wrist"), "{e}");

        let one = vec![reading(poses()[0], 1.0, "yaw pitch roll", true)];
        assert!(fit(&one).unwrap_err().contains("at least two poses"));

        let same = vec![
            reading(poses()[0], 1.0, "yaw pitch roll", true),
            reading(poses()[0], 1.0, "yaw pitch roll", true),
        ];
        assert!(fit(&same).unwrap_err().contains("move the arm further"));

        // A tool on the controller: the positions match in no units.
        let mut tooled: Vec<Position> = poses()
            .into_iter()
            .map(|q| reading(q, 1.0, "yaw pitch roll", true))
            .collect();
        for r in &mut tooled {
            r.world[2] += 100.0;
        }
        assert!(fit(&tooled).unwrap_err().contains("bare flange"));
    }
}

//! First contact with a controller (`trol rapl probe`, c500-rapl.md §1.6): a session that sends
//! only commands that cannot move the arm, records every byte, provokes one harmless refusal
//! (an unknown word) to learn the controller's refusal form, and, from W2 readings taken at
//! poses the operator sets by pendant, fits what the public sources leave open: the pulse
//! scale, sign and zero of each joint, the length units, the order and signs of the WORLD
//! angles, and a fixed rotation between the controller's tool frame and TROL's.
//!
//! The fit compares each reading with itself: the PULSES row against the JOINTS row (degrees,
//! as RobWork and the W2 sample read it) gives the pulse convention; the joints give the pose
//! through trol-a465's forward kinematics, and that pose must be what the WORLD row says under
//! the fitted conventions. It assumes the controller's tool is the bare flange (no TOOL set);
//! a reading taken with another tool fits nothing, and the fit says so. It does not set MA and
//! MI's units, nor JOG's frame: the JOINTS row does not tell them (RobWork and the RAPL-II
//! reference send MA in radians); docs/c500.md has the supervised step that does.

use trol_a465::kinematics::{Kinematics, Pose};

use crate::backend::RaplBackend;
use crate::frames::Frames;
use crate::profile::{Profile, RefusalForm, Units, parse_angles};
use crate::text::{Position, read_position};

/// The keywords of the commands the probe sends: none of them moves the arm or changes a
/// setting.
pub const READ_ONLY: &[&str] = &[
    "STATUS", "SERIAL", "W0", "W2", "W5", "LISTL", "LLOC", PROBE_WORD,
];

/// The lines the probe sends at first contact, in order.
pub const FIRST_CONTACT: &[&str] = &["STATUS", "SERIAL", "W0", "W2", "LISTL"];

/// The unknown word the probe types to see how this controller refuses (no RAPL-II keyword,
/// and not a name a program would have: an assumption, docs/c500.md).
pub const PROBE_WORD: &str = "QZXTROL";

/// How far the WORLD position may be from the kinematics' (mm).
pub const POSITION_TOLERANCE_MM: f64 = 2.0;
/// How far the WORLD orientation may be from the kinematics' (degrees).
pub const ANGLE_TOLERANCE_DEG: f64 = 0.5;
/// A joint turned at least this far (degrees) between two readings tells its pulse scale.
const TELLING_JOINT_DEG: f64 = 5.0;
/// How far (pulses) a reading may be from the fitted line.
const PULSE_TOLERANCE: f64 = 2.5;

/// What the readings settle.
#[derive(Clone, Debug, PartialEq)]
pub struct Fit {
    /// The length units.
    pub units: Units,
    /// The order and signs of the WORLD angles, as the profile's `angles` writes them.
    pub angles: String,
    /// The fixed rotation between TROL's tool frame and the controller's (yaw pitch roll,
    /// degrees), as the profile's `tool_rotation`.
    pub tool_rotation: [f64; 3],
    /// Per joint: pulses per degree and pulses at zero, when every joint turned far enough.
    pub pulses: Result<([f64; 6], [f64; 6]), String>,
    /// The largest position difference over the readings, mm.
    pub position_error_mm: f64,
    /// The largest orientation difference over the readings, degrees.
    pub angle_error_deg: f64,
}

impl Fit {
    /// `profile` with the fitted keys set.
    pub fn apply(&self, profile: &Profile) -> Profile {
        let (pulse_scale, pulse_zero) = match &self.pulses {
            Ok((s, z)) => (s.to_vec(), z.to_vec()),
            Err(_) => (profile.pulse_scale.clone(), profile.pulse_zero.clone()),
        };
        Profile {
            units: self.units,
            angles: self.angles.clone(),
            tool_rotation: self.tool_rotation,
            pulse_scale,
            pulse_zero,
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
pub fn rotation_distance_deg(a: &Pose, b: &Pose) -> f64 {
    let m = a.rot.transpose() * b.rot;
    let trace = m.x_axis.x + m.y_axis.y + m.z_axis.z;
    ((trace - 1.0) / 2.0).clamp(-1.0, 1.0).acos().to_degrees()
}

/// At pitch +-90 degrees only yaw - roll (or yaw + roll) counts: the same rotation with roll 0,
/// so a fitted offset reads the plain way (`[0, 90, 0]`, not `[-90, 90, -90]`).
fn canonical(r: [f64; 3]) -> [f64; 3] {
    let pose = |r: [f64; 3]| Pose::from_xyzypr([0.0, 0.0, 0.0, r[0], r[1], r[2]]);
    if (r[1].abs() - std::f64::consts::FRAC_PI_2).abs() > 1e-6 || r[2] == 0.0 {
        return r;
    }
    for yaw in [r[0] - r[2], r[0] + r[2]] {
        let wrapped = trol_a465::kinematics::wrap(yaw);
        let c = [if wrapped.abs() < 1e-9 { 0.0 } else { wrapped }, r[1], 0.0];
        if rotation_distance_deg(&pose(c), &pose(r)) < 1e-6 {
            return c;
        }
    }
    r
}

/// The pulse convention from the PULSES and JOINTS rows: per joint, the least-squares line
/// through the readings (every reading must lie on it within a few pulses).
pub fn fit_pulses(readings: &[Position]) -> Result<([f64; 6], [f64; 6]), String> {
    let mut scale = [0.0; 6];
    let mut zero = [0.0; 6];
    for j in 0..6 {
        let (mut lo, mut hi) = (&readings[0], &readings[0]);
        for r in readings {
            if r.joints[j] < lo.joints[j] {
                lo = r;
            }
            if r.joints[j] > hi.joints[j] {
                hi = r;
            }
        }
        let dj = hi.joints[j] - lo.joints[j];
        if dj < TELLING_JOINT_DEG {
            return Err(format!(
                "joint {} turned less than {TELLING_JOINT_DEG} degrees over the poses, so its \
                 pulses per degree are not told: turn every joint between poses",
                j + 1
            ));
        }
        // Least squares over every reading.
        let n = readings.len() as f64;
        let mj = readings.iter().map(|r| r.joints[j]).sum::<f64>() / n;
        let mp = readings.iter().map(|r| r.pulses[j] as f64).sum::<f64>() / n;
        let sjj: f64 = readings.iter().map(|r| (r.joints[j] - mj).powi(2)).sum();
        let sjp: f64 = readings
            .iter()
            .map(|r| (r.joints[j] - mj) * (r.pulses[j] as f64 - mp))
            .sum();
        let k = sjp / sjj;
        let z = mp - k * mj;
        // The JOINTS row has four decimals: the line holds within its rounding.
        let tol = PULSE_TOLERANCE + k.abs() * 0.0001;
        if let Some(r) = readings
            .iter()
            .find(|r| (r.pulses[j] as f64 - (z + k * r.joints[j])).abs() > tol)
        {
            return Err(format!(
                "joint {}: the PULSES and JOINTS rows are not proportional (pulses {} at {} \
                 degrees, {k:.4} pulses per degree elsewhere)",
                j + 1,
                r.pulses[j],
                r.joints[j]
            ));
        }
        scale[j] = k;
        zero[j] = z.round();
    }
    Ok((scale, zero))
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
        .map(|r| r.joints.map(f64::to_radians))
        .collect();

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
    let pulses = fit_pulses(readings);

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

    // The angles: every order and sign, each with the fixed rotation the first reading
    // gives, against the kinematics' rotation at every reading.
    let mut fitting = Vec::new();
    let mut best = f64::INFINITY;
    for words in every_angle_order() {
        let plain = Frames {
            mm: Some(mm),
            angles: parse_angles(&words).ok().flatten(),
            tool_rotation: [0.0; 3],
            pulses: None,
        };
        let Ok(first) = plain.from_rapl(readings[0].world) else {
            continue;
        };
        // R_controller = R_TROL * R_off.
        let off = Pose {
            rot: fk[0].rot.transpose() * Pose::from_xyzypr(first).rot,
            pos: Default::default(),
        };
        let a = off.to_xyzypr();
        let mut rot = [a[3], a[4], a[5]];
        for x in &mut rot {
            // Whole tenths of a degree: an offset between models is a designed angle.
            *x = ((x.to_degrees() * 10.0).round() / 10.0).to_radians();
            if x.abs() < 1e-9 {
                *x = 0.0;
            }
        }
        let rot = canonical(rot);
        let frames = Frames {
            tool_rotation: rot,
            ..plain
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
            fitting.push((words, rot.map(f64::to_degrees), worst));
        }
    }
    // Where the readings cannot tell an order with no rotation from one with a rotation,
    // the one without is the plain reading.
    if fitting.len() > 1 && fitting.iter().filter(|f| f.1 == [0.0; 3]).count() == 1 {
        fitting.retain(|f| f.1 == [0.0; 3]);
    }
    match fitting.len() {
        1 => {
            let (angles, tool_rotation, angle_error_deg) = fitting.remove(0);
            Ok(Fit {
                units,
                angles,
                tool_rotation,
                pulses,
                position_error_mm,
                angle_error_deg,
            })
        }
        0 => Err(format!(
            "no order and signs of the WORLD angles match the kinematics, even with a fixed \
             rotation of the tool frame (the best is off by {best:.1} degrees): the controller's \
             joints may turn the other way than TROL's (docs/a465.md); keep the transcript and \
             set `angles` by hand"
        )),
        _ => Err(format!(
            "{} orders of the WORLD angles fit these poses ({}): tilt the wrist (joint 5 away \
             from 0 and from 90 degrees) and turn joints 4 and 6 differently in each pose, \
             then probe again",
            fitting.len(),
            fitting
                .iter()
                .map(|(w, _, _)| format!("\"{w}\""))
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
    /// The refusal form learned from the answer to [`PROBE_WORD`] (a template for the
    /// profile's `refusal`), or why none was.
    pub refusal: Option<Result<String, String>>,
    /// The W2 readings: the one at first contact, then one per pose.
    pub readings: Vec<Position>,
    /// The fit, when poses were asked for.
    pub fit: Option<Result<Fit, String>>,
}

/// Run first contact on an open session: the lines of [`FIRST_CONTACT`], the unknown word,
/// then `poses` times `operator(k, poses)` (which returns once the operator has moved the arm
/// by pendant to pose k, `false` to stop early) and a W2 reading; then the fit, when `poses`
/// > 0. Nothing sent can move the arm: every line goes through [`RaplBackend::read_only`].
pub fn first_contact(
    b: &mut RaplBackend,
    poses: usize,
    operator: &mut dyn FnMut(usize, usize) -> std::io::Result<bool>,
) -> Contact {
    let mut c = Contact::default();
    for line in FIRST_CONTACT {
        let r = b.read_only(line).map(|r| r.text).map_err(|e| e.to_string());
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
    let refused = b.read_only(PROBE_WORD).map_err(|e| e.to_string());
    c.refusal = Some(refused.as_ref().map_err(|e| e.clone()).and_then(|r| {
        let said = r
            .text
            .split(['\r', '\n'])
            .map(str::trim)
            .find(|l| !l.is_empty())
            .unwrap_or_default()
            .to_string();
        if r.ack {
            return Err(format!(
                "the unknown word {PROBE_WORD} was answered with ACK ({said:?}): this controller \
                 does not refuse it as expected; keep the transcript"
            ));
        }
        RefusalForm::learn(&said).ok_or_else(|| {
            format!(
                "the answer to the unknown word {PROBE_WORD}, {said:?}, has no form TROL can learn"
            )
        })
    }));
    c.replies.push((PROBE_WORD.into(), refused.map(|r| r.text)));
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

/// What the supervised steps measured ([`measure`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Measured {
    /// MA and MI's units (`degrees` or `radians`).
    pub joint_units: String,
    /// JOG's frame (`world` or `tool`).
    pub jog_frame: String,
    /// When a motion's ACK comes.
    pub motion_ack: crate::profile::MotionAck,
    /// The first stop seen to stop a running motion (HALT, ABORT, Ctrl-C in that order);
    /// `None` where a motion holds the line (only Ctrl-C gets through then).
    pub halt: Option<crate::profile::Halt>,
}

impl Measured {
    /// `profile` with the measured keys set (a controller that answers at the end halts by
    /// Ctrl-C).
    pub fn apply(&self, profile: &Profile) -> Profile {
        let end = self.motion_ack == crate::profile::MotionAck::End;
        Profile {
            joint_units: self.joint_units.clone(),
            // Not measured (a pose where it cannot be told): the profile's, if it has one.
            jog_frame: if self.jog_frame.is_empty() {
                profile.jog_frame.clone()
            } else {
                self.jog_frame.clone()
            },
            motion_ack: self.motion_ack,
            halt: if end {
                crate::profile::Halt::CtrlC
            } else {
                self.halt.unwrap_or(profile.halt)
            },
            ..profile.clone()
        }
    }
}

/// The least angle between the tool's z axis and the world's +z at which JOG's frame is
/// measured, degrees (JOG 0,0,1 then moves at least 0.34 units apart in the two frames).
pub const MIN_JOG_TILT_DEG: f64 = 20.0;

/// The controller's tool z axis in the world, from a reading's JOINTS row through the A465's
/// kinematics and the profile's `tool_rotation`.
fn tool_z_axis(p: &Position, profile: &Profile) -> [f64; 3] {
    let q: [f64; 6] = p.joints.map(f64::to_radians);
    let flange = Kinematics::default().fk(&q);
    let [y, pi, r] = profile.tool_rotation.map(f64::to_radians);
    let off = Pose::from_xyzypr([0.0, 0.0, 0.0, y, pi, r]);
    let z = (flange.rot * off.rot).z_axis;
    [z.x, z.y, z.z]
}

/// The lines the supervised steps send, in order (each motion undone by the next).
pub const MEASURE: &[&str] = &[
    "SPEED 5",
    "MI 0,0,0,0,0,0.05",
    "MI 0,0,0,0,0,-0.05",
    "JOG 0,0,1",
    "JOG 0,0,-1",
    "JOINT 6,20",
    "JOINT 6,-20",
    "HALT",
    "ABORT",
];

/// Where the arm stands homed: STATUS must show it powered, homed and at rest (a HOME under
/// way is waited for), and two W2 a quarter
/// second apart must put each joint within 0.01 of each other (the JOINTS row, in the
/// controller's units). Reads only. Whether that is where HOME left it, at the arm's home
/// marks, only the person at the arm can say: the caller asks before recording it as
/// `home_joints`.
pub fn home_pose(b: &mut RaplBackend) -> Result<[f64; 6], String> {
    // A HOME still under way (a terminal's HOME returns at its ACK) is waited for, within
    // the profile's motion timeout.
    let until =
        std::time::Instant::now() + std::time::Duration::from_secs(b.profile().motion_timeout_s);
    loop {
        let st = b.read_only("STATUS").map_err(|e| e.to_string())?;
        let st = crate::text::read_status(&st.text)?;
        if st.limp.iter().any(|l| *l) {
            return Err("the arm has no power (LIMP): nothing read".into());
        }
        if st.homed.iter().all(|h| *h) && st.done.iter().all(|d| *d) {
            break;
        }
        if std::time::Instant::now() >= until {
            return Err(format!(
                "the arm was not homed and at rest within {} s (STATUS's HOMED and DONE rows): \
                 HOME it first",
                b.profile().motion_timeout_s
            ));
        }
        std::thread::sleep(std::time::Duration::from_millis(200));
    }
    let a = read_position(&b.read_only("W2").map_err(|e| e.to_string())?.text)?;
    std::thread::sleep(std::time::Duration::from_millis(250));
    let p = read_position(&b.read_only("W2").map_err(|e| e.to_string())?.text)?;
    if (0..6).any(|j| (a.joints[j] - p.joints[j]).abs() > 0.01) {
        return Err(format!(
            "the arm read {:?} then {:?} a quarter second later: it does not stand",
            a.joints, p.joints
        ));
    }
    Ok(p.joints)
}

/// Settle by supervised motions what no reading tells (c500-rapl.md §1.6; docs/c500.md step
/// 5), once the operator has confirmed the arm is free to move: at SPEED 5, `MI` of 0.05 on
/// joint 6 (0.05 degrees or 2.9: the units of MA and MI), `JOG 0,0,1` (one unit: along the
/// world's z or not), `JOINT 6,20` (its answer while the joint still turns, or only when it
/// stands), each undone at once. Every step needs the success form; the first failure stops
/// them, and the arm is left where that step left it.
pub fn measure(b: &mut RaplBackend, log: &mut dyn FnMut(&str)) -> Result<Measured, String> {
    let short = std::time::Duration::from_millis(b.profile().reply_timeout_ms);
    let long = std::time::Duration::from_secs(b.profile().motion_timeout_s);
    let st = b.read_only("STATUS").map_err(|e| e.to_string())?;
    let st = crate::text::read_status(&st.text)?;
    if st.limp.iter().any(|l| *l) || !st.homed.iter().all(|h| *h) {
        return Err("the arm must have power and be homed before the supervised steps".into());
    }
    let step = |b: &mut RaplBackend, line: &str, t| -> Result<(), String> {
        let r = b.type_line(line, t).map_err(|e| format!("`{line}`: {e}"))?;
        let printed: Vec<&str> = r
            .text
            .split(['\r', '\n'])
            .map(|l| l.trim_matches(|c: char| c.is_whitespace() || c == '\0'))
            .filter(|l| !l.is_empty())
            .collect();
        if !printed.is_empty() || (b.expects_ack() && !r.ack) {
            return Err(format!(
                "`{line}` was not answered with the success form ({printed:?}): steps stopped"
            ));
        }
        Ok(())
    };
    let still = |b: &mut RaplBackend| -> Result<Position, String> {
        let until = std::time::Instant::now() + long;
        loop {
            let st = b.read_only("STATUS").map_err(|e| e.to_string())?;
            let st = crate::text::read_status(&st.text)?;
            if st.done.iter().all(|d| *d) {
                let a = read_position(&b.read_only("W2").map_err(|e| e.to_string())?.text)?;
                std::thread::sleep(std::time::Duration::from_millis(200));
                let c = read_position(&b.read_only("W2").map_err(|e| e.to_string())?.text)?;
                if a.joints
                    .iter()
                    .zip(&c.joints)
                    .all(|(x, y)| (x - y).abs() < 0.01)
                {
                    return Ok(c);
                }
            }
            if std::time::Instant::now() > until {
                return Err("the arm did not come to rest within motion_timeout_s".into());
            }
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
    };
    step(b, "SPEED 5", short)?;

    let before = still(b)?;
    log("MI 0,0,0,0,0,0.05");
    step(b, "MI 0,0,0,0,0,0.05", long)?;
    let after = still(b)?;
    step(b, "MI 0,0,0,0,0,-0.05", long)?;
    still(b)?;
    let turned = (after.joints[5] - before.joints[5]).abs();
    let joint_units = if (turned - 0.05).abs() < 0.02 {
        "degrees"
    } else if (turned - 0.05f64.to_degrees()).abs() < 0.2 {
        "radians"
    } else {
        return Err(format!(
            "MI of 0.05 turned joint 6 by {turned:.4} degrees: neither degrees nor radians"
        ));
    };

    // JOG's frame can be told only where the tool's z axis is not the world's: at all
    // joints zero (the homed pose) both point up, and a JOG in either frame moves the same
    // (issue 37: the probe wrote "world" there for a flange-frame JOG).
    let tool_z = tool_z_axis(&after, b.profile());
    // Pointing down (-z) tells as well as sideways: only the world's +z cannot.
    let tilt = tool_z[2].clamp(-1.0, 1.0).acos().to_degrees();
    let jog_frame = if b.profile().angles().is_none() {
        log(
            "JOG's frame is measured once the poses have fitted `angles` and `tool_rotation` \
             (--poses, docs/c500.md step 4; give that profile with --profile): jog_frame stays \
             unset (a straight Jog is refused)",
        );
        ""
    } else if tilt < MIN_JOG_TILT_DEG {
        log(&format!(
            "JOG's frame cannot be told at this pose: the tool's z axis is {tilt:.0} degrees \
             from the world's +z (at least {MIN_JOG_TILT_DEG:.0} needed). Turn joint 5 by 45 \
             degrees by pendant, so that the tool does not point up, and run --measure again; \
             jog_frame stays unset (a straight Jog is refused)"
        ));
        ""
    } else {
        log("JOG 0,0,1");
        step(b, "JOG 0,0,1", long)?;
        let jogged = still(b)?;
        step(b, "JOG 0,0,-1", long)?;
        still(b)?;
        let d: [f64; 3] = std::array::from_fn(|i| jogged.world[i] - after.world[i]);
        let near = |v: [f64; 3]| (0..3).all(|i| (d[i] - v[i]).abs() < 0.2);
        if near([0.0, 0.0, 1.0]) {
            "world"
        } else if near(tool_z) {
            "tool"
        } else {
            return Err(format!(
                "JOG 0,0,1 moved the tool by {d:?} (WORLD row): neither along the world's z \
                 nor along the tool's {tool_z:?}; jog_frame stays unset"
            ));
        }
    };

    // Typed with the long timeout: a controller that answers at the end answers then. The
    // next STATUS tells whether the joint still turned when the answer came.
    log("JOINT 6,20");
    step(b, "JOINT 6,20", long)?;
    let st = b.read_only("STATUS").map_err(|e| e.to_string())?;
    let moving = !crate::text::read_status(&st.text)?.done.iter().all(|d| *d);
    still(b)?;
    step(b, "JOINT 6,-20", long)?;
    still(b)?;

    // Which stop stops a running motion: each tried on a JOINT 6,20 of its own (2.3 s at
    // SPEED 5), 0.3 s into it, and counted only when W2 shows the arm standing within a
    // second; the joint is turned back by what it turned. A controller that answers a motion
    // at its end takes nothing but Ctrl-C while it runs: Halt then checks Ctrl-C on the arm
    // each time, and the next stops after it (docs/c500.md, "Halt").
    let halt = if moving {
        let mut found = None;
        for stop in ["HALT", "ABORT", "Ctrl-C"] {
            let before = still(b)?;
            log(&format!("JOINT 6,20, and {stop} 0.3 s into it"));
            step(b, "JOINT 6,20", long)?;
            std::thread::sleep(std::time::Duration::from_millis(300));
            let stood = b.stop_with(stop).map_err(|e| format!("{stop}: {e}"))?;
            let rest = still(b)?;
            let turned = rest.joints[5] - before.joints[5];
            step(b, &format!("JOINT 6,{}", crate::text::num(-turned)), long)?;
            still(b)?;
            match stood {
                Ok(_) if turned.abs() < 19.5 => {
                    log(&format!(
                        "{stop} stopped the joint after {turned:.2} degrees"
                    ));
                    found = Some(stop);
                    break;
                }
                Ok(_) => log(&format!("{stop}: the joint ran on to its end")),
                Err(why) => log(&format!("{stop} did not stop it: {why}")),
            }
        }
        match found {
            Some("HALT") => Some(crate::profile::Halt::Halt),
            Some("ABORT") => Some(crate::profile::Halt::Abort),
            Some(_) => Some(crate::profile::Halt::CtrlC),
            None => {
                return Err(
                    "no stop (HALT, ABORT, Ctrl-C) stopped a running motion: TROL cannot halt \
                     this arm; do not drive it through TROL, and check the controller"
                        .into(),
                );
            }
        }
    } else {
        None
    };
    Ok(Measured {
        joint_units: joint_units.into(),
        jog_frame: jog_frame.into(),
        motion_ack: if moving {
            crate::profile::MotionAck::Start
        } else {
            crate::profile::MotionAck::End
        },
        halt,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A reading as a controller with these conventions would print it.
    fn reading_with(q: [f64; 6], mm: f64, angles: &str, rot: [f64; 3], scale: f64) -> Position {
        let frames = Frames {
            mm: Some(mm),
            angles: parse_angles(angles).unwrap(),
            tool_rotation: rot.map(f64::to_radians),
            pulses: Some(std::array::from_fn(|i| {
                (scale * (i as f64 + 1.0), 10.0 * i as f64)
            })),
        };
        let pose = Kinematics::new([0.0; 6]).fk_xyzypr(&q);
        let joints = q.map(|x| (x.to_degrees() * 1e4).round() / 1e4);
        Position {
            pulses: frames.joints_to_pulses(joints).unwrap(),
            joints,
            world: frames.to_rapl(pose).unwrap(),
        }
    }

    fn reading(q: [f64; 6], mm: f64, angles: &str, _deg: bool) -> Position {
        reading_with(q, mm, angles, [0.0; 3], 100.0)
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
                assert_eq!(f.tool_rotation, [0.0; 3]);
            }
        }
    }

    #[test]
    fn a_fixed_tool_rotation_and_a_negative_pulse_table_are_found() {
        for rot in [[0.0, 90.0, 0.0], [90.0, 0.0, -90.0], [0.0, -90.0, 180.0]] {
            let r: Vec<Position> = poses()
                .into_iter()
                .map(|q| reading_with(q, 1.0, "roll -pitch yaw", rot, -140.3))
                .collect();
            let f = fit(&r).unwrap_or_else(|e| panic!("{rot:?}: {e}"));
            assert_eq!(f.angles, "roll -pitch yaw", "{rot:?}");
            let back = Pose::from_xyzypr([
                0.0,
                0.0,
                0.0,
                f.tool_rotation[0].to_radians(),
                f.tool_rotation[1].to_radians(),
                f.tool_rotation[2].to_radians(),
            ]);
            let want = Pose::from_xyzypr([
                0.0,
                0.0,
                0.0,
                rot[0].to_radians(),
                rot[1].to_radians(),
                rot[2].to_radians(),
            ]);
            assert!(
                rotation_distance_deg(&back, &want) < 0.01,
                "{rot:?}: {:?}",
                f.tool_rotation
            );
            let (scale, zero) = f.pulses.unwrap();
            for i in 0..6 {
                assert!(
                    (scale[i] - -140.3 * (i as f64 + 1.0)).abs() < 0.05,
                    "{scale:?}"
                );
                assert_eq!(zero[i], 10.0 * i as f64);
            }
        }
    }

    #[test]
    fn refusal_forms_are_learned_from_the_answer_to_an_unknown_word() {
        for (line, form) in [
            ("012-COMMAND ERROR.", "NNN-TEXT."),
            (":012-COMMAND ERROR.", ":NNN-TEXT."),
            ("*** UNKNOWN COMMAND ***", "*** TEXT ***"),
            ("012-COMMAND ERROR", "NNN-TEXT"),
        ] {
            assert_eq!(RefusalForm::learn(line).as_deref(), Some(form), "{line}");
            let f = RefusalForm::parse(form).unwrap();
            assert!(f.read(line).is_some(), "{line}");
            assert_eq!(
                f.read(&f.write(58, "ARM POWER IS OFF")).unwrap().1,
                "ARM POWER IS OFF"
            );
        }
        assert_eq!(RefusalForm::learn(""), None);
        // An ordinary output line is no refusal of a form with a number.
        let f = RefusalForm::parse("NNN-TEXT.").unwrap();
        assert_eq!(f.read("LAST ERROR CODE: 012-COMMAND ERROR."), None);
        assert_eq!(f.read("+000.0150 +000.0150."), None);
        assert!(RefusalForm::parse("TEXT").is_err());
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

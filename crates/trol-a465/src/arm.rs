//! The simulated arm: timed motion, gripper, location table and safety checks.
//!
//! The arm takes the time as an argument (`now`, seconds on the simulation's clock) and never
//! reads a clock or sleeps, so that tests drive it through time exactly and the controller
//! can run it faster than real time. Motions are accepted at once and run in the background;
//! a motion accepted while another runs starts when that one ends (the controller's implicit
//! wait between motion commands, manual "TROLFinish").
//!
//! Return values are the simulated BIOS's codes ([`code`]); what the real C500 returns is not
//! public, so these are ours (docs/a465.md).

use std::collections::{HashMap, VecDeque};

use glam::DQuat;

use crate::kinematics::{IkError, Joints, Kinematics, Pose, wrap};
use crate::model::{
    self, READY, counts_to_joints, first_outside_limits, joints_to_counts, max_accels, max_speeds,
};

/// The simulated BIOS's return values (ours; the real ones are in CRS's technical manual,
/// which is not public).
pub mod code {
    /// Done (or: accepted and running).
    pub const OK: i16 = 0;
    /// Finish(FINISH_STATUS): the arm or the gripper still moves.
    pub const MOVING: i16 = 1;
    /// A motion before the arm (or the axis it needs) was homed.
    pub const NOT_HOMED: i16 = -1;
    /// The target or a point of the path is out of the arm's reach.
    pub const OUT_OF_REACH: i16 = -2;
    /// The target or a point of the path lies beyond a joint limit.
    pub const JOINT_LIMIT: i16 = -3;
    /// The tool tip would go below the table plane.
    pub const BELOW_TABLE: i16 = -4;
    /// A straight line that passes a singularity (the wrist centre across the base axis, or
    /// the wrist through J5 = 0 with a half turn of J4): the arm cannot follow it with its
    /// joints moving smoothly.
    pub const SINGULAR_PATH: i16 = -5;
    /// An axis or joint number outside 0..6 (Home) or 1..6 (Joint), or a value that is not
    /// a finite number.
    pub const BAD_ARGUMENT: i16 = -6;
}

/// A location in the controller's table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Stored {
    /// A cartesian location (x y z mm, yaw pitch roll rad).
    Cart([f64; 6]),
    /// A precision point (encoder counts).
    Prec([i32; 6]),
}

/// A target of an absolute motion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target {
    /// A cartesian location of the tool centre point.
    Cart([f64; 6]),
    /// A precision point.
    Prec([f64; 6]),
    /// Joint angles.
    Joints(Joints),
}

/// Which position GetPosition reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Which {
    /// What the controller commands.
    Commanded,
    /// What the encoders read.
    Actual,
}

/// Settings of the simulation.
#[derive(Clone, Debug)]
pub struct ArmSettings {
    /// The table plane: the tool tip may not go below this world z, mm (default 0).
    pub table_z: f64,
    /// The width of an object between the fingers, mm: closing stops there. None: nothing.
    pub object_width: Option<f64>,
    /// Whether the arm counts as homed from the start (default false, as after power-up).
    pub homed: bool,
}

impl Default for ArmSettings {
    fn default() -> Self {
        ArmSettings {
            table_z: 0.0,
            object_width: None,
            homed: false,
        }
    }
}

/// Finger travel, mm: 0..50 (about 2 in; an assumption, manual "TROLGrip").
pub const FINGER_MAX: f64 = 50.0;
/// Finger speed, mm/s (assumption): a full stroke takes 1.25 s, within the 2 s the manual's
/// example waits after TROLClose.
pub const FINGER_SPEED: f64 = 40.0;
/// How far the actual position lags the commanded one, s (a servo loop's lag; assumption).
pub const SERVO_LAG: f64 = 0.01;
/// How long homing an axis takes at least, s (assumption).
pub const HOME_TIME: f64 = 2.0;
/// Points checked along a path for the safety checks and used to follow a straight line.
const PATH_SAMPLES: usize = 64;
/// The largest change of any joint between two neighbouring points of a straight line,
/// radians (30°, while a smooth line of the arm's reach changes far less per 1/64 of it):
/// more means the line crosses a singularity.
const MAX_PATH_STEP: f64 = std::f64::consts::PI / 6.0;

#[derive(Clone, Debug)]
enum Path {
    Joint {
        from: Joints,
        to: Joints,
    },
    Line {
        kin: Box<Kinematics>,
        from: Pose,
        to: Pose,
        q_from: DQuat,
        q_to: DQuat,
        samples: Vec<Joints>,
    },
}

#[derive(Clone, Debug)]
struct Motion {
    start: f64,
    duration: f64,
    accel_time: f64,
    path: Path,
    end: Joints,
}

impl Motion {
    /// Path parameter 0..1 at `t` (trapezoidal velocity profile).
    fn s(&self, t: f64) -> f64 {
        let t = t - self.start;
        let (tt, ta) = (self.duration, self.accel_time);
        if t <= 0.0 || tt <= 0.0 {
            return if t <= 0.0 { 0.0 } else { 1.0 };
        }
        if t >= tt {
            return 1.0;
        }
        let v = 1.0 / (tt - ta);
        if t < ta {
            0.5 * v / ta * t * t
        } else if t <= tt - ta {
            v * (t - ta / 2.0)
        } else {
            1.0 - 0.5 * v / ta * (tt - t) * (tt - t)
        }
    }

    fn joints_at(&self, t: f64) -> Joints {
        let s = self.s(t);
        match &self.path {
            Path::Joint { from, to } => std::array::from_fn(|i| from[i] + (to[i] - from[i]) * s),
            Path::Line {
                kin,
                from,
                to,
                q_from,
                q_to,
                samples,
            } => {
                if s >= 1.0 {
                    return self.end;
                }
                let pose = line_pose(from, to, q_from, q_to, s);
                let idx =
                    ((s * (samples.len() - 1) as f64).round() as usize).min(samples.len() - 1);
                kin.ik_nearest(&pose, &samples[idx]).unwrap_or(samples[idx])
            }
        }
    }
}

fn line_pose(from: &Pose, to: &Pose, q_from: &DQuat, q_to: &DQuat, s: f64) -> Pose {
    Pose {
        pos: from.pos.lerp(to.pos, s),
        rot: glam::DMat3::from_quat(q_from.slerp(*q_to, s)),
    }
}

#[derive(Clone, Copy, Debug)]
struct Fingers {
    from: f64,
    to: f64,
    start: f64,
}

impl Fingers {
    fn at(&self, t: f64) -> f64 {
        let d = self.to - self.from;
        let dt = (t - self.start).max(0.0);
        if d.abs() <= FINGER_SPEED * dt {
            self.to
        } else {
            self.from + d.signum() * FINGER_SPEED * dt
        }
    }

    fn done_at(&self) -> f64 {
        self.start + (self.to - self.from).abs() / FINGER_SPEED
    }
}

/// The simulated A465 with its gripper and the controller's location table.
#[derive(Clone, Debug)]
pub struct Arm {
    settings: ArmSettings,
    kin: Kinematics,
    speed: f64,
    homed: [bool; 6],
    base: Joints,
    motions: VecDeque<Motion>,
    fingers: Fingers,
    locations: HashMap<String, Stored>,
}

impl Arm {
    /// An arm at READY, not homed (unless the settings say so), speed 100 %, fingers open.
    pub fn new(settings: ArmSettings) -> Arm {
        let homed = [settings.homed; 6];
        Arm {
            settings,
            kin: Kinematics::default(),
            speed: 100.0,
            homed,
            base: READY,
            motions: VecDeque::new(),
            fingers: Fingers {
                from: FINGER_MAX,
                to: FINGER_MAX,
                start: 0.0,
            },
            locations: HashMap::new(),
        }
    }

    /// The settings.
    pub fn settings(&self) -> &ArmSettings {
        &self.settings
    }

    /// The settings, to change them.
    pub fn settings_mut(&mut self) -> &mut ArmSettings {
        &mut self.settings
    }

    /// The kinematics with the current tool transform.
    pub fn kinematics(&self) -> &Kinematics {
        &self.kin
    }

    /// The location table.
    pub fn locations(&self) -> &HashMap<String, Stored> {
        &self.locations
    }

    /// Store a location under a name (the RAPL `POINT` / `HERE`).
    pub fn set_location(&mut self, name: &str, loc: Stored) {
        self.locations.insert(name.to_string(), loc);
    }

    /// A stored location.
    pub fn location(&self, name: &str) -> Option<Stored> {
        self.locations.get(name).copied()
    }

    /// Which axes are homed.
    pub fn homed(&self) -> [bool; 6] {
        self.homed
    }

    /// The speed setting, percent.
    pub fn speed(&self) -> f64 {
        self.speed
    }

    fn retire(&mut self, now: f64) {
        while let Some(m) = self.motions.front() {
            if m.start + m.duration <= now {
                self.base = m.end;
                self.motions.pop_front();
            } else {
                break;
            }
        }
    }

    /// Where the arm will be once every accepted motion has ended.
    pub fn planned_end(&self) -> Joints {
        self.motions.back().map(|m| m.end).unwrap_or(self.base)
    }

    fn planned_start_time(&self, now: f64) -> f64 {
        self.motions
            .back()
            .map(|m| (m.start + m.duration).max(now))
            .unwrap_or(now)
    }

    /// The commanded joints at `t`.
    pub fn commanded(&mut self, now: f64) -> Joints {
        self.retire(now);
        self.commanded_at(now)
    }

    fn commanded_at(&self, t: f64) -> Joints {
        let mut pos = self.base;
        for m in &self.motions {
            if t < m.start {
                return pos;
            }
            if t < m.start + m.duration {
                return m.joints_at(t);
            }
            pos = m.end;
        }
        pos
    }

    /// The actual joints at `now`: the commanded ones a servo lag ago, as the encoders read
    /// them (whole counts).
    pub fn actual(&mut self, now: f64) -> Joints {
        self.retire(now - SERVO_LAG);
        let q = self.commanded_at(now - SERVO_LAG);
        let counts = joints_to_counts(&q).map(|c| c as f64);
        counts_to_joints(&counts)
    }

    /// Joints in the form asked for.
    pub fn position(&mut self, now: f64, which: Which) -> Joints {
        match which {
            Which::Commanded => self.commanded(now),
            Which::Actual => self.actual(now),
        }
    }

    /// The finger distance at `now`, mm.
    pub fn fingers(&self, now: f64) -> f64 {
        self.fingers.at(now)
    }

    /// Whether the arm or the gripper moves at `now` (Finish(FINISH_STATUS)).
    pub fn is_moving(&mut self, now: f64) -> bool {
        self.done_at(now) > now
    }

    /// When everything accepted so far will have ended.
    pub fn done_at(&mut self, now: f64) -> f64 {
        self.retire(now);
        let arm = self
            .motions
            .back()
            .map(|m| m.start + m.duration)
            .unwrap_or(now);
        arm.max(self.fingers.done_at()).max(now)
    }

    /// Finish(FINISH_STATUS).
    pub fn finish_status(&mut self, now: f64) -> i16 {
        if self.is_moving(now) {
            code::MOVING
        } else {
            code::OK
        }
    }

    /// Halt: stop arm and fingers where they are now; the commanded position stays there.
    pub fn halt(&mut self, now: f64) -> i16 {
        let here = self.commanded(now);
        self.motions.clear();
        self.base = here;
        let f = self.fingers.at(now);
        self.fingers = Fingers {
            from: f,
            to: f,
            start: now,
        };
        code::OK
    }

    /// Speed: percent of the maximum (1..150) for the motions that follow.
    pub fn set_speed(&mut self, percent: f64) -> i16 {
        self.speed = percent.clamp(1.0, 150.0);
        code::OK
    }

    /// The tool transform for every cartesian computation that follows.
    pub fn set_tool(&mut self, tool: [f64; 6]) -> i16 {
        self.kin = Kinematics::new(tool);
        code::OK
    }

    /// Home one axis (1..6) or all (0). The arm drives the axes to their zero (the home
    /// switches) and counts them as homed.
    pub fn home(&mut self, axis: u8, now: f64) -> i16 {
        if axis > 6 {
            return code::BAD_ARGUMENT;
        }
        let mut to = self.planned_end();
        let axes: Vec<usize> = if axis == 0 {
            (0..6).collect()
        } else {
            vec![axis as usize - 1]
        };
        for &a in &axes {
            to[a] = 0.0;
        }
        let from = self.planned_end();
        let (duration, accel_time) = joint_profile(&from, &to, 20.0);
        let start = self.planned_start_time(now);
        self.motions.push_back(Motion {
            start,
            duration: duration.max(HOME_TIME * axes.len() as f64),
            accel_time,
            path: Path::Joint { from, to },
            end: to,
        });
        for a in axes {
            self.homed[a] = true;
        }
        code::OK
    }

    /// The fingers to `dist` mm (Grip; full force). Closing stops at an object.
    pub fn grip(&mut self, dist: f64, now: f64) -> i16 {
        self.fingers_to(dist.clamp(0.0, FINGER_MAX), now)
    }

    /// Open the gripper.
    pub fn open(&mut self, _force: f64, now: f64) -> i16 {
        self.fingers_to(FINGER_MAX, now)
    }

    /// Close the gripper (on an object, if there is one).
    pub fn close(&mut self, _force: f64, now: f64) -> i16 {
        self.fingers_to(0.0, now)
    }

    fn fingers_to(&mut self, target: f64, now: f64) -> i16 {
        let from = self.fingers.at(now);
        let stop = match self.settings.object_width {
            Some(w) if target < w && from >= w => w,
            _ => target,
        };
        self.fingers = Fingers {
            from,
            to: stop,
            start: now,
        };
        code::OK
    }

    fn need_homed(&self) -> Result<(), i16> {
        if self.homed.iter().all(|h| *h) {
            Ok(())
        } else {
            Err(code::NOT_HOMED)
        }
    }

    /// The TCP pose where the arm will be once it has done what it was told.
    fn planned_pose(&self) -> Pose {
        self.kin.fk(&self.planned_end())
    }

    fn joints_for(&self, target: &Target) -> Result<Joints, i16> {
        let q = match target {
            Target::Joints(q) => *q,
            Target::Prec(c) => counts_to_joints(c),
            Target::Cart(v) => {
                let pose = Pose::from_xyzypr(*v);
                self.kin
                    .ik_nearest(&pose, &self.planned_end())
                    .map_err(ik_code)?
            }
        };
        if first_outside_limits(&q).is_some() {
            return Err(code::JOINT_LIMIT);
        }
        Ok(q)
    }

    /// Accept a motion to joints `to` (joint-interpolated) after the safety checks.
    fn move_joints(&mut self, to: Joints, now: f64) -> i16 {
        if let Err(c) = self.need_homed() {
            return c;
        }
        if to.iter().any(|x| !x.is_finite()) {
            return code::BAD_ARGUMENT;
        }
        if first_outside_limits(&to).is_some() {
            return code::JOINT_LIMIT;
        }
        let from = self.planned_end();
        for k in 0..=PATH_SAMPLES {
            let s = k as f64 / PATH_SAMPLES as f64;
            let q: Joints = std::array::from_fn(|i| from[i] + (to[i] - from[i]) * s);
            if self.kin.fk(&q).pos.z < self.settings.table_z - 1e-9 {
                return code::BELOW_TABLE;
            }
        }
        let (duration, accel_time) = joint_profile(&from, &to, self.speed);
        let start = self.planned_start_time(now);
        self.motions.push_back(Motion {
            start,
            duration,
            accel_time,
            path: Path::Joint { from, to },
            end: to,
        });
        code::OK
    }

    /// Accept a straight-line motion of the tool centre point to `to`, orientation
    /// interpolated, after checking every point of the path.
    fn move_line(&mut self, to: Pose, now: f64) -> i16 {
        if let Err(c) = self.need_homed() {
            return c;
        }
        let q0 = self.planned_end();
        // The target first: out of reach is the clearer answer than whatever fails on the
        // way there.
        if self.kin.ik_all(&to, &q0).is_empty() {
            return code::OUT_OF_REACH;
        }
        let from = self.kin.fk(&q0);
        let (q_from, q_to) = (DQuat::from_mat3(&from.rot), DQuat::from_mat3(&to.rot));
        let mut samples = Vec::with_capacity(PATH_SAMPLES + 1);
        let mut prev = q0;
        for k in 0..=PATH_SAMPLES {
            let s = k as f64 / PATH_SAMPLES as f64;
            let pose = line_pose(&from, &to, &q_from, &q_to, s);
            if pose.pos.z < self.settings.table_z - 1e-9 {
                return code::BELOW_TABLE;
            }
            let q = match self.follow(&pose, &prev) {
                Ok(q) => q,
                Err(c) => return c,
            };
            samples.push(q);
            prev = q;
        }
        // Cruise time: each stretch takes as long as its slowest joint needs.
        let v = max_speeds().map(|v| v * self.speed / 100.0);
        let cruise: f64 = samples
            .windows(2)
            .map(|w| {
                (0..6)
                    .map(|i| wrap(w[1][i] - w[0][i]).abs() / v[i])
                    .fold(0.0, f64::max)
            })
            .sum();
        let f = self.speed / 100.0;
        let a = max_accels().map(|a| a * f * f);
        let accel_time = (v[0] / a[0]).min(cruise.max(1e-3));
        let duration = if cruise > 0.0 {
            cruise + accel_time
        } else {
            0.0
        };
        let end = *samples.last().expect("samples");
        let start = self.planned_start_time(now);
        self.motions.push_back(Motion {
            start,
            duration,
            accel_time: accel_time.min(duration / 2.0),
            path: Path::Line {
                kin: Box::new(self.kin),
                from,
                to,
                q_from,
                q_to,
                samples,
            },
            end,
        });
        code::OK
    }

    /// The next joints along a straight line: the solution nearest the previous point,
    /// whatever its limits, so that the arm keeps its configuration as a real one does. If
    /// that solution is beyond a limit the line leaves the limits (JOINT_LIMIT); if even the
    /// nearest one is far away the line crosses a singularity (SINGULAR_PATH).
    fn follow(&self, pose: &Pose, prev: &Joints) -> Result<Joints, i16> {
        let all = self.kin.ik_all(pose, prev);
        let step = |q: &Joints| -> f64 {
            (0..6)
                .map(|i| wrap(q[i] - prev[i]).abs())
                .fold(0.0, f64::max)
        };
        let next = all
            .as_slice()
            .iter()
            .min_by(|a, b| step(&a.q).total_cmp(&step(&b.q)))
            .ok_or(code::OUT_OF_REACH)?;
        if step(&next.q) > MAX_PATH_STEP {
            return Err(code::SINGULAR_PATH);
        }
        // Continue each joint from the previous one (J4 and J6 may pass ±180° only where
        // their limits allow it, which they do not: ±180° is their limit).
        let q: Joints = std::array::from_fn(|i| prev[i] + wrap(next.q[i] - prev[i]));
        if first_outside_limits(&q).is_some() {
            return Err(code::JOINT_LIMIT);
        }
        Ok(q)
    }

    fn move_pose(&mut self, to: Pose, straight: bool, now: f64) -> i16 {
        if !to.pos.is_finite() || !to.rot.is_finite() {
            return code::BAD_ARGUMENT;
        }
        // A target below the table says so first, whatever else is wrong with it.
        if to.pos.z < self.settings.table_z - 1e-9 {
            return code::BELOW_TABLE;
        }
        if straight {
            self.move_line(to, now)
        } else {
            match self.kin.ik_nearest(&to, &self.planned_end()) {
                Ok(q) => self.move_joints(q, now),
                Err(e) => ik_code(e),
            }
        }
    }

    /// Move (and MoveII): to a target, joint-interpolated or in a straight line.
    pub fn move_to(&mut self, target: Target, straight: bool, now: f64) -> i16 {
        if let Err(c) = self.need_homed() {
            return c;
        }
        if let Target::Cart(v) = target {
            return self.move_pose(Pose::from_xyzypr(v), straight, now);
        }
        if straight {
            let q = match self.joints_for(&target) {
                Ok(q) => q,
                Err(c) => return c,
            };
            self.move_line(self.kin.fk(&q), now)
        } else {
            match self.joints_for(&target) {
                Ok(q) => self.move_joints(q, now),
                Err(c) => c,
            }
        }
    }

    /// Appro (and ApproII): to the target displaced by `disp` in its tool frame.
    pub fn appro(&mut self, target: Target, disp: [f64; 6], straight: bool, now: f64) -> i16 {
        if let Err(c) = self.need_homed() {
            return c;
        }
        let pose = match target {
            Target::Cart(v) => Pose::from_xyzypr(v),
            other => match self.joints_for(&other) {
                Ok(q) => self.kin.fk(&q),
                Err(c) => return c,
            },
        };
        self.move_pose(pose.then(&Pose::from_xyzypr(disp)), straight, now)
    }

    /// Depart: from where the arm is (once its motions end), displaced in the tool frame.
    pub fn depart(&mut self, disp: [f64; 6], straight: bool, now: f64) -> i16 {
        if let Err(c) = self.need_homed() {
            return c;
        }
        let to = self.planned_pose().then(&Pose::from_xyzypr(disp));
        self.move_pose(to, straight, now)
    }

    /// Jog: the tool centre point by dx dy dz in the world frame, orientation kept.
    pub fn jog(&mut self, d: [f64; 3], straight: bool, now: f64) -> i16 {
        if let Err(c) = self.need_homed() {
            return c;
        }
        let mut to = self.planned_pose();
        to.pos += glam::DVec3::from_array(d);
        self.move_pose(to, straight, now)
    }

    /// Joint: one joint (1..6) by an increment in radians.
    pub fn joint(&mut self, joint: u8, radians: f64, now: f64) -> i16 {
        if !(1..=6).contains(&joint) || !radians.is_finite() {
            return code::BAD_ARGUMENT;
        }
        let mut to = self.planned_end();
        to[joint as usize - 1] += radians;
        self.move_joints(to, now)
    }

    /// MA: all joints to absolute angles.
    pub fn ma(&mut self, q: Joints, now: f64) -> i16 {
        self.move_joints(q, now)
    }

    /// MI: all joints by increments.
    pub fn mi(&mut self, dq: Joints, now: f64) -> i16 {
        let from = self.planned_end();
        self.move_joints(std::array::from_fn(|i| from[i] + dq[i]), now)
    }

    /// Ready: to the READY pose.
    pub fn ready(&mut self, now: f64) -> i16 {
        self.move_joints(READY, now)
    }
}

fn ik_code(e: IkError) -> i16 {
    match e {
        IkError::OutOfReach => code::OUT_OF_REACH,
        IkError::JointLimit { .. } => code::JOINT_LIMIT,
    }
}

/// Duration and acceleration time of a joint-interpolated motion: every joint runs the same
/// trapezoidal profile in time, set by the joint that needs longest at `percent` of the
/// maximum speeds (and the square of it of the accelerations, so that half the speed takes
/// twice the time).
pub fn joint_profile(from: &Joints, to: &Joints, percent: f64) -> (f64, f64) {
    let f = percent / 100.0;
    let v = max_speeds().map(|v| v * f);
    // Accelerations scale with the square, so that the speed setting scales time alone.
    let a = max_accels().map(|a| a * f * f);
    let mut best = (0.0, 0.0);
    for i in 0..6 {
        let d = (to[i] - from[i]).abs();
        if d == 0.0 {
            continue;
        }
        let (t, ta) = if d >= v[i] * v[i] / a[i] {
            (d / v[i] + v[i] / a[i], v[i] / a[i])
        } else {
            let ta = (d / a[i]).sqrt();
            (2.0 * ta, ta)
        };
        if t > best.0 {
            best = (t, ta);
        }
    }
    best
}

/// Read a location file: one location per line, `NAME v1 v2 v3 v4 v5 v6` (blanks or commas
/// between). A name starting with `#` is a precision point (six encoder counts); any other
/// is cartesian (x y z in mm, yaw pitch roll in radians). Blank lines and lines starting
/// with `;` are ignored.
pub fn parse_locations(text: &str) -> Result<Vec<(String, Stored)>, String> {
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with(';') {
            continue;
        }
        let mut parts = line
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|s| !s.is_empty());
        let name = parts.next().unwrap_or_default();
        let err = |why: &str| {
            format!(
                "line {}: {why}; expected `NAME v1 v2 v3 v4 v5 v6` (a name of up to 8 \
                 characters, the first a letter or '#', the rest letters, digits or '_')",
                n + 1
            )
        };
        let ok_name = !name.is_empty()
            && name.len() <= 8
            && (name.as_bytes()[0].is_ascii_alphabetic() || name.starts_with('#'))
            && name[1..]
                .bytes()
                .all(|b| b.is_ascii_alphanumeric() || b == b'_');
        if !ok_name {
            return Err(err(&format!("bad name {name:?}")));
        }
        let values: Vec<&str> = parts.collect();
        if values.len() != 6 {
            return Err(err(&format!("{} values", values.len())));
        }
        let loc = if name.starts_with('#') {
            let mut c = [0i32; 6];
            for (i, v) in values.iter().enumerate() {
                c[i] = v
                    .parse()
                    .map_err(|_| err(&format!("{v:?} is not a whole number of counts")))?;
            }
            Stored::Prec(c)
        } else {
            let mut c = [0f64; 6];
            for (i, v) in values.iter().enumerate() {
                c[i] = v
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| err(&format!("{v:?} is not a number")))?;
            }
            Stored::Cart(c)
        };
        out.push((name.to_string(), loc));
    }
    Ok(out)
}

/// The precision-point form of joints (re-exported for the controller).
pub fn counts_of(q: &Joints) -> [i32; 6] {
    model::joints_to_counts(q)
}

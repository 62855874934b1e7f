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
    snap_to_limits,
};
use crate::motion::{Path, Profile, Stretch};

mod files;
mod gripper;
mod line;

pub use files::{parse_locations, parse_objects, read_locations};
pub use gripper::WorldObject;
use gripper::{Fingers, Held};
pub use line::{LINE_MAX_FACTOR, LINE_SLACK, LineOutcome};

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
    /// The motion queue is full ([`super::MOTION_QUEUE`] motions accepted and not yet done):
    /// wait (TROLFinish) and send the motion again.
    pub const QUEUE_FULL: i16 = -7;
    /// Closing the fingers on an object at the tool centre point that is wider than their
    /// opening: they are not around it and cannot pass through it. Nothing moves; open the
    /// gripper wider than the object before moving onto it. (-9 to -16 and -20 to -22 are
    /// the real controllers' backends' own codes.)
    pub const GRIPPER_BLOCKED: i16 = -17;
    /// The arm has no power (an e-stop, a power failure; [`super::Arm::power_off`]): every
    /// motion is refused, and the Finish after a motion the power cut short says so. The
    /// same number on every controller's backend.
    pub const ARM_POWER: i16 = -8;
    /// Here or Define with the location table full (docs/teach.md).
    pub const TABLE_FULL: i16 = -18;
    /// Save without a locations file to write (the simulator started without one).
    pub const NO_FILE: i16 = -19;
    /// Save refused by the system: the locations file (or its folder) may not be written,
    /// or the file is read-only (it is then left as it is).
    pub const FILE_DENIED: i16 = -23;
    /// Save found no room on the disk; the file is left as it was.
    pub const DISK_FULL: i16 = -24;
    /// Save found no folder where the locations file should be.
    pub const NO_FOLDER: i16 = -25;
    /// Save failed for another reason (the controller's log says which); the file is left
    /// as it was.
    pub const SAVE_FAILED: i16 = -26;
    /// A trajectory (TROLTrajectory) whose times ask more speed or acceleration of a joint
    /// than the arm has at the speed setting: nothing moves; give it more time (-27 to -29
    /// are the C500C backend's).
    pub const TOO_FAST: i16 = -30;
}

/// How far a trajectory's waypoint at time 0 may be from where the arm starts it, rad (it
/// is that start; assumption: ten times the f32 rounding of an angle, and well inside what
/// ROS 2's trajectory controllers accept as a start).
pub const TRAJECTORY_START_TOLERANCE: f64 = 1e-3;
/// Points checked along each segment of a trajectory for joint limits and the table.
const TRAJECTORY_SAMPLES: usize = 16;

/// The largest locations file read (bytes): a full table of [`MAX_TABLE`] lines with
/// comments fits many times over; a larger file is refused, not read whole.
pub const MAX_LOCATIONS_FILE: u64 = 4 << 20;

/// How many locations the table holds (the wire's limit, TROLListLocations).
pub const MAX_TABLE: usize = 1000;

/// How many accepted motions (the one under way included) the controller holds before it
/// refuses the next with `QUEUE_FULL` (assumption: the C500's own depth is not public).
pub const MOTION_QUEUE: usize = 16;

/// How close an object's position must be to the tool centre point for the closing fingers
/// to take it, mm (assumption).
pub const GRASP_DISTANCE: f64 = 10.0;

/// A location in the controller's table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Stored {
    /// A cartesian location (x y z mm, yaw pitch roll rad).
    Cart([f64; 6]),
    /// A precision point (encoder counts).
    Prec([i32; 6]),
    /// Joint angles, radians (taught in joint form; a RAPL-II controller has none).
    Joints([f64; 6]),
}

/// The form Here stores a location in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HereForm {
    /// Cartesian: the tool centre point.
    Cart,
    /// Joint angles.
    Joints,
    /// A precision point: encoder counts.
    Prec,
}

/// Six values as a locations file writes them, to the precision the arm has (0.001 mm,
/// 1e-6 rad: `420` where a person wrote 420, not `420.00000000000006`).
fn join_values(tag: trol_proto::application::Tag, v: &[f64; 6]) -> String {
    trol_proto::application::record::format_values(tag, v).join(" ")
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
    /// The width of an object held between the fingers at start, mm (`object = W`): closing
    /// stops there. None: nothing.
    pub object_width: Option<f64>,
    /// Objects in the world at start (on the table, or wherever the file puts them).
    pub objects: Vec<WorldObject>,
    /// Whether the arm counts as homed from the start (default false, as after power-up).
    pub homed: bool,
    /// The joints' top speeds at 100 %, rad/s, where the controller holds the arm below the
    /// published ones (a MARS 8's REGMS; issue 43): each joint at the lower of the two.
    /// None: the published speeds.
    pub joint_speeds: Option<[f64; 6]>,
}

impl Default for ArmSettings {
    fn default() -> Self {
        ArmSettings {
            table_z: 0.0,
            object_width: None,
            objects: Vec::new(),
            homed: false,
            joint_speeds: None,
        }
    }
}

/// Finger travel, mm: 0..50 (about 2 in; an assumption, manual "TROLGrip").
pub const FINGER_MAX: f64 = 50.0;
/// Finger speed, mm/s (assumption): a full stroke takes 1.25 s, within the 2 s the manual's
/// example waits after TROLClose.
pub const FINGER_SPEED: f64 = 40.0;
/// How far the actual position lags the commanded one, s: the following error of a servo
/// loop, which grows with speed (about speed x lag) and acceleration (assumption).
pub const SERVO_LAG: f64 = 0.01;
/// The dither of the actual position around the commanded one, at rest and moving: 1 or 2
/// encoder counts either way on every joint, changing every 5 ms (assumption). So the two are
/// close but never identical, as the manual says ("TROLGetPosition").
pub const DITHER_COUNTS: i32 = 2;
/// How long homing an axis takes at least, s (assumption).
pub const HOME_TIME: f64 = 2.0;
/// The speed setting homing runs at, percent (assumption).
pub const HOME_SPEED: f64 = 20.0;

/// The order Home(0) homes the axes in, group by group (joint indices from 0): joint 2, then
/// joints 1 and 3, then 4, 5 and 6: the order of CTU's hard home of an A465 (B, AC, DEF;
/// shared/reference/a465.md, "CTU home/index sensing", and mars8.md). A group's axes count
/// as homed when its motion ends; a Halt leaves the rest unhomed.
pub const HOME_GROUPS: &[&[usize]] = &[&[1], &[0, 2], &[3, 4, 5]];
/// The tool's maximum speed on a straight line at 100 %, mm/s (assumption: no public figure
/// for the A465; an F3 on a C500C shows 1016 mm/s).
pub const MAX_LINEAR_SPEED: f64 = 1000.0;
/// The tool's maximum acceleration on a straight line at 100 %, mm/s² (assumption: the F3's
/// figure, 2540 mm/s²).
pub const MAX_LINEAR_ACCEL: f64 = 2540.0;
/// Points checked along a joint-interpolated path for the table.
const PATH_SAMPLES: usize = 64;
/// A motion: a path and its profile in time.
#[derive(Clone, Debug)]
struct Motion {
    profile: Profile,
    path: Path,
    /// Axes (0-based) that count as homed once this motion has ended (Home).
    homes: Option<Vec<usize>>,
}

impl Motion {
    fn joints_at(&self, t: f64) -> Joints {
        self.path.at(self.profile.at(t).0)
    }

    fn end(&self) -> Joints {
        self.path.at(self.profile.s_end())
    }
}

/// Below this |J3| (rad) a line's end counts as on the stretched elbow ([`Ease`]).
const STRETCHED_ELBOW: f64 = 0.05;

fn max_step(a: &Joints, b: &Joints) -> f64 {
    (0..6).map(|i| (a[i] - b[i]).abs()).fold(0.0, f64::max)
}

/// The joints' speed and acceleration limits at `percent`: the published maxima scaled by the
/// setting, never beyond them (above 100 % the arm runs at its maxima); accelerations scale
/// like the speeds (assumption).
pub fn joint_limits(percent: f64) -> ([f64; 6], [f64; 6]) {
    let f = percent.clamp(1.0, 100.0) / 100.0;
    (max_speeds().map(|v| v * f), max_accels().map(|a| a * f))
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
    objects: Vec<WorldObject>,
    held: Option<Held>,
    /// Why the last straight line was refused, in words, not yet taken.
    refusal: Option<String>,
    /// What the planner found for the last straight line.
    last_line: Option<LineOutcome>,
    /// Whether the arm has power (an e-stop, a power cut: [`Arm::power_off`]).
    powered: bool,
    /// A motion or homing was under way when the power went: the Finish after it says so
    /// (BIOS_ARM_POWER) until the next motion is accepted.
    cut_short: bool,
    /// Where homing leaves each axis (its home switch), radians: every joint's 0 unless a
    /// controller's twin says otherwise ([`Arm::set_home_pose`]).
    home_pose: Joints,
}

impl Arm {
    /// An arm at READY, not homed (unless the settings say so), speed 100 %, fingers open.
    pub fn new(settings: ArmSettings) -> Arm {
        let homed = [settings.homed; 6];
        let mut arm = Arm {
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
            objects: Vec::new(),
            held: None,
            refusal: None,
            last_line: None,
            powered: true,
            cut_short: false,
            home_pose: [0.0; 6],
        };
        for o in arm.settings.objects.clone() {
            arm.objects.push(o);
        }
        if let Some(w) = arm.settings.object_width {
            // An object already between the fingers: closed on it at start.
            let centre = arm.kin.fk(&READY).pos;
            arm.objects.push(WorldObject {
                name: "object".into(),
                pos: (centre - glam::DVec3::Z * (w / 2.0)).to_array(),
                width: w,
            });
            arm.held = Some(Held {
                index: arm.objects.len() - 1,
                in_tool: glam::DVec3::ZERO,
            });
        }
        arm
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

    /// The table's key of `name` as stored: case does not tell two names apart (RAPL-II
    /// upper-cases what it is typed, docs/teach.md "Names").
    fn stored_name(&self, name: &str) -> Option<String> {
        if self.locations.contains_key(name) {
            return Some(name.to_string());
        }
        self.locations
            .keys()
            .find(|k| k.eq_ignore_ascii_case(name))
            .cloned()
    }

    /// Store a location under a name (the RAPL `POINT` / `HERE`); one of the same name in
    /// another case is replaced, and the name keeps the spelling it had.
    pub fn set_location(&mut self, name: &str, loc: Stored) {
        let key = self.stored_name(name).unwrap_or_else(|| name.to_string());
        self.locations.insert(key, loc);
    }

    /// A stored location (any case of its name).
    pub fn location(&self, name: &str) -> Option<Stored> {
        let key = self.stored_name(name)?;
        self.locations.get(&key).copied()
    }

    /// Forget a location (the RAPL `DLOCN`; any case of its name). Whether there was one
    /// of that name.
    pub fn delete_location(&mut self, name: &str) -> bool {
        match self.stored_name(name) {
            Some(key) => self.locations.remove(&key).is_some(),
            None => false,
        }
    }

    /// Where the arm is commanded to be at `now`, in the form of `like` (HERE): cartesian
    /// (the tool centre point with the tool in force), joint angles, or encoder counts.
    pub fn here(&mut self, form: HereForm, now: f64) -> Stored {
        let q = self.commanded(now);
        match form {
            HereForm::Cart => Stored::Cart(self.kin.fk_xyzypr(&q)),
            HereForm::Joints => Stored::Joints(q),
            HereForm::Prec => Stored::Prec(joints_to_counts(&q)),
        }
    }

    /// The location table as a locations file ([`parse_locations`] reads it back): one line
    /// per location, sorted by name.
    pub fn locations_text(&self) -> String {
        let mut names: Vec<&String> = self.locations.keys().collect();
        names.sort();
        let mut out = String::from(
            "; TROL locations: NAME and six values (x y z mm, yaw pitch roll rad); \
             #NAME: encoder counts; NAME joint: radians\n",
        );
        for name in names {
            let line = match self.locations[name] {
                Stored::Cart(v) => format!(
                    "{name} {}",
                    join_values(trol_proto::application::Tag::Cart, &v)
                ),
                Stored::Joints(v) => format!(
                    "{name} joint {}",
                    join_values(trol_proto::application::Tag::Joint, &v)
                ),
                Stored::Prec(c) => format!(
                    "{name} {}",
                    c.iter()
                        .map(|x| x.to_string())
                        .collect::<Vec<_>>()
                        .join(" ")
                ),
            };
            out.push_str(&line);
            out.push('\n');
        }
        out
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
        // A homing's axes are homed once its commanded motion has ended.
        for m in &self.motions {
            if m.profile.end() > now {
                break;
            }
            for &a in m.homes.iter().flatten() {
                self.homed[a] = true;
            }
        }
        while let Some(m) = self.motions.front() {
            // A motion stays until the actual position (a servo lag behind) has ended it
            // too: retired at its end, the actual position snapped to the end up to a lag
            // early.
            if m.profile.end() > now - SERVO_LAG {
                break;
            }
            let m = self.motions.pop_front().expect("a front motion");
            self.base = m.end();
            for a in m.homes.into_iter().flatten() {
                self.homed[a] = true;
            }
        }
    }

    /// Where the arm will be once every accepted motion has ended.
    pub fn planned_end(&self) -> Joints {
        self.motions.back().map(Motion::end).unwrap_or(self.base)
    }

    fn planned_start_time(&self, now: f64) -> f64 {
        self.motions
            .back()
            .map(|m| m.profile.end().max(now))
            .unwrap_or(now)
    }

    /// Put the arm where it is (a real arm's encoders, read by a backend that plans with this
    /// model): every accepted motion is dropped and the arm stands at `q`.
    pub fn place(&mut self, q: Joints) {
        self.motions.clear();
        self.base = q;
    }

    /// Set which axes count as homed (a real arm's homing, done by its controller).
    pub fn set_homed(&mut self, homed: [bool; 6]) {
        self.homed = homed;
    }

    /// The last accepted motion: its start and end time, and whether every joint moves
    /// linearly in its path parameter (a joint-interpolated motion; a straight line or a
    /// spline is not). A backend that drives a real arm samples it with [`Arm::planned_at`].
    pub fn last_motion(&self) -> Option<(f64, f64, bool)> {
        self.motions.back().map(|m| {
            (
                m.profile.start(),
                m.profile.end(),
                matches!(m.path, Path::Joint { .. }),
            )
        })
    }

    /// The commanded joints at `t` as planned, without retiring anything.
    pub fn planned_at(&self, t: f64) -> Joints {
        self.commanded_at(t)
    }

    /// The commanded joints at `t`.
    pub fn commanded(&mut self, now: f64) -> Joints {
        self.retire(now);
        self.commanded_at(now)
    }

    fn commanded_at(&self, t: f64) -> Joints {
        let mut pos = self.base;
        for m in &self.motions {
            if t < m.profile.start() {
                return pos;
            }
            if t < m.profile.end() {
                return m.joints_at(t);
            }
            pos = m.end();
        }
        pos
    }

    /// The actual joints at `now`, as the encoders read them (whole counts): the commanded
    /// ones a servo lag ago (the following error), with a dither of 1 or 2 counts.
    pub fn actual(&mut self, now: f64) -> Joints {
        self.retire(now - SERVO_LAG);
        let q = self.commanded_at(now - SERVO_LAG);
        let slot = (now * 200.0).floor() as i64;
        let counts: [f64; 6] =
            std::array::from_fn(|i| (joints_to_counts(&q)[i] + dither(slot, i)) as f64);
        counts_to_joints(&counts)
    }

    /// Joints in the form asked for.
    pub fn position(&mut self, now: f64, which: Which) -> Joints {
        match which {
            Which::Commanded => self.commanded(now),
            Which::Actual => self.actual(now),
        }
    }

    /// Whether the arm or the gripper moves at `now` (Finish(FINISH_STATUS)).
    pub fn is_moving(&mut self, now: f64) -> bool {
        self.done_at(now) > now
    }

    /// When everything accepted so far will have ended: the actual position at the last
    /// motion's end (a servo lag after the command's, as a controller's in-position flag
    /// waits for the following error), and the fingers.
    pub fn done_at(&mut self, now: f64) -> f64 {
        self.retire(now);
        let arm = self
            .motions
            .back()
            .map(|m| m.profile.end() + SERVO_LAG)
            .unwrap_or(now);
        arm.max(self.fingers.done_at()).max(now)
    }

    /// Finish(FINISH_STATUS).
    pub fn finish_status(&mut self, now: f64) -> i16 {
        if self.is_moving(now) {
            code::MOVING
        } else if self.cut_short {
            code::ARM_POWER
        } else {
            code::OK
        }
    }

    /// Cut the arm's power at `now` (an e-stop, a power failure): the motion under way stops
    /// where it is (as a Halt, so a homing on its way leaves its axes unhomed), the fingers
    /// stop, and every motion, homing and gripper motion is refused (BIOS_ARM_POWER) until
    /// [`Arm::power_on`]. The Finish after a motion so cut short says BIOS_ARM_POWER.
    pub fn power_off(&mut self, now: f64) {
        if self.is_moving(now) {
            self.cut_short = true;
        }
        self.halt(now);
        self.powered = false;
    }

    /// Where homing leaves each axis, radians (a controller whose home switches are not at
    /// every joint's 0: a twin's switch for an open point, issue 62). Every joint's 0 by
    /// default, as the simulated A465's.
    pub fn set_home_pose(&mut self, q: Joints) {
        self.home_pose = q;
    }

    /// Give the arm its power back: it stands where the power left it.
    pub fn power_on(&mut self) {
        self.powered = true;
    }

    /// Whether the arm has power.
    pub fn has_power(&self) -> bool {
        self.powered
    }

    /// Halt: the motion under way brakes at the limits along its own path (a straight line
    /// stays on its line), queued motions are dropped, and the fingers stop. A homing that is
    /// stopped leaves its axes unhomed.
    pub fn halt(&mut self, now: f64) -> i16 {
        self.retire(now);
        if let Some(m) = self.motions.front_mut() {
            if m.profile.start() <= now {
                m.profile.stop_at(now);
                m.homes = None;
                self.motions.truncate(1);
            } else {
                self.motions.clear();
            }
        }
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

    /// The tool transform for every cartesian computation that follows. A tool that would put
    /// the tool centre point below the table where the arm will stand is refused
    /// (BIOS_BELOW_TABLE) and changes nothing: taken, it left every move but Home refused. A
    /// held object stays where it is in the world.
    pub fn set_tool(&mut self, tool: [f64; 6]) -> i16 {
        let kin = Kinematics::new(tool);
        let q = self.planned_end();
        let end = kin.fk(&q);
        if end.pos.z < self.settings.table_z - 1e-9 {
            return code::BELOW_TABLE;
        }
        let old = self.kin.fk(&q);
        if let Some(h) = self.held.as_mut() {
            let centre = old.pos + old.rot * h.in_tool;
            h.in_tool = end.rot.transpose() * (centre - end.pos);
        }
        self.kin = kin;
        code::OK
    }

    /// Home one axis (1..6) or all (0, in the groups of [`HOME_GROUPS`], one after the
    /// other): the arm drives the axes to their home switches (every joint's 0 unless
    /// [`Arm::set_home_pose`] says otherwise) at the homing speed, at least HOME_TIME per
    /// axis. Its axes are unhomed from the moment it is accepted (it
    /// references them anew) and count as homed when their group's motion ends; a Halt before
    /// then leaves them unhomed, whether or not they were homed before (issue 62: a halted
    /// Home on a homed arm was reported done), so the Finish after it fails.
    pub fn home(&mut self, axis: u8, now: f64) -> i16 {
        if axis > 6 {
            return code::BAD_ARGUMENT;
        }
        if !self.powered {
            return code::ARM_POWER;
        }
        self.retire(now);
        let groups: Vec<Vec<usize>> = if axis == 0 {
            HOME_GROUPS.iter().map(|g| g.to_vec()).collect()
        } else {
            vec![vec![axis as usize - 1]]
        };
        if self.motions.len() + groups.len() > MOTION_QUEUE {
            return code::QUEUE_FULL;
        }
        for &a in groups.iter().flatten() {
            self.homed[a] = false;
        }
        self.cut_short = false;
        for axes in groups {
            let from = self.planned_end();
            let mut to = from;
            for &a in &axes {
                to[a] = self.home_pose[a];
            }
            let path = Path::Joint { from, to };
            let (speeds, accels) = self.joint_limits_at(HOME_SPEED);
            let (v, a) = path.bounds().limits(&speeds, &accels);
            let start = self.planned_start_time(now);
            let profile = Profile::trapezoid(start, v, a, HOME_TIME * axes.len() as f64);
            self.motions.push_back(Motion {
                profile,
                path,
                homes: Some(axes),
            });
        }
        code::OK
    }

    /// The arm powered, and every axis homed or being homed by a homing already accepted (a
    /// motion then queues behind it; a Halt drops both).
    fn need_homed(&mut self, now: f64) -> Result<(), i16> {
        if !self.powered {
            return Err(code::ARM_POWER);
        }
        self.retire(now);
        let mut will_be = self.homed;
        for m in &self.motions {
            for &a in m.homes.iter().flatten() {
                will_be[a] = true;
            }
        }
        if !will_be.iter().all(|h| *h) {
            Err(code::NOT_HOMED)
        } else {
            self.need_room()
        }
    }

    /// Room in the motion queue for one more.
    fn need_room(&self) -> Result<(), i16> {
        if self.motions.len() >= MOTION_QUEUE {
            Err(code::QUEUE_FULL)
        } else {
            Ok(())
        }
    }

    /// The TCP pose where the arm will be once it has done what it was told.
    fn planned_pose(&self) -> Pose {
        self.kin.fk(&self.planned_end())
    }

    fn joints_for(&self, target: &Target) -> Result<Joints, i16> {
        let q = match target {
            Target::Joints(q) => snap_to_limits(q),
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
        if let Err(c) = self.need_homed(now) {
            return c;
        }
        if to.iter().any(|x| !x.is_finite()) {
            return code::BAD_ARGUMENT;
        }
        let to = snap_to_limits(&to);
        if first_outside_limits(&to).is_some() {
            return code::JOINT_LIMIT;
        }
        let from = self.planned_end();
        for k in 0..=PATH_SAMPLES {
            let s = k as f64 / PATH_SAMPLES as f64;
            let q: Joints = std::array::from_fn(|i| from[i] + (to[i] - from[i]) * s);
            if self.lowest_z(&self.kin.fk(&q)) < self.settings.table_z - 1e-9 {
                return code::BELOW_TABLE;
            }
        }
        self.push(Path::Joint { from, to }, now);
        code::OK
    }

    /// Queue a motion along `path`, timed by the joint limits at the speed setting.
    fn push(&mut self, path: Path, now: f64) {
        let (speeds, accels) = self.joint_limits_at(self.speed);
        let (v, a) = path.bounds().limits(&speeds, &accels);
        let start = self.planned_start_time(now);
        let profile = Profile::trapezoid(start, v, a, 0.0);
        self.push_timed(path, profile);
    }

    fn push_timed(&mut self, path: Path, profile: Profile) {
        self.cut_short = false;
        self.motions.push_back(Motion {
            profile,
            path,
            homes: None,
        });
    }

    /// The tool's linear limits at the speed setting: (mm/s, mm/s²).
    /// [`joint_limits`] at `percent` for this arm: each joint's speed at most its
    /// controller's top speed ([`ArmSettings::joint_speeds`]) scaled the same way.
    fn joint_limits_at(&self, percent: f64) -> ([f64; 6], [f64; 6]) {
        let (mut speeds, accels) = joint_limits(percent);
        if let Some(top) = self.settings.joint_speeds {
            let f = percent.clamp(1.0, 100.0) / 100.0;
            for (v, t) in speeds.iter_mut().zip(top) {
                if t.is_finite() && t > 0.0 {
                    *v = v.min(t * f);
                }
            }
        }
        (speeds, accels)
    }

    /// Why the last straight line was refused (which pose, where on the line, what to do),
    /// once: for the controller's log, beside the code.
    pub fn take_refusal(&mut self) -> Option<String> {
        self.refusal.take()
    }

    fn move_pose(&mut self, to: Pose, straight: bool, now: f64) -> i16 {
        if !to.pos.is_finite() || !to.rot.is_finite() {
            return code::BAD_ARGUMENT;
        }
        // A target below the table (the tool's, or a held object's underside) says so
        // first, whatever else is wrong with it.
        if self.lowest_z(&to) < self.settings.table_z - 1e-9 {
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
        if let Err(c) = self.need_homed(now) {
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
        if let Err(c) = self.need_homed(now) {
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
        if let Err(c) = self.need_homed(now) {
            return c;
        }
        let to = self.planned_pose().then(&Pose::from_xyzypr(disp));
        self.move_pose(to, straight, now)
    }

    /// Jog: the tool centre point by dx dy dz in the world frame, orientation kept.
    pub fn jog(&mut self, d: [f64; 3], straight: bool, now: f64) -> i16 {
        if let Err(c) = self.need_homed(now) {
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

    /// Trajectory (TROLTrajectory): one motion through `points` (seconds from its start,
    /// joints), at their times: a C1 cubic spline through the waypoints, at rest at both
    /// ends ([`Path::timed`]), run at one path speed ([`Profile::steady`]), so the commanded
    /// position is at each waypoint at its time. It starts where the arm will be once the
    /// motions before it have ended; a waypoint at time 0 must be there (within
    /// [`TRAJECTORY_START_TOLERANCE`]). Refused before anything moves: a joint beyond its
    /// limit anywhere along it (`JOINT_LIMIT`), the tool below the table (`BELOW_TABLE`),
    /// more speed or acceleration than the joints have at the speed setting (`TOO_FAST`),
    /// times that do not increase or values that are not finite (`BAD_ARGUMENT`).
    pub fn trajectory(&mut self, points: &[(f64, Joints)], now: f64) -> i16 {
        if let Err(c) = self.need_homed(now) {
            return c;
        }
        if points.is_empty()
            || points
                .iter()
                .any(|(t, q)| !t.is_finite() || *t < 0.0 || q.iter().any(|x| !x.is_finite()))
            || points.windows(2).any(|w| w[1].0 <= w[0].0)
        {
            return code::BAD_ARGUMENT;
        }
        let from = self.planned_end();
        let (mut ts, mut qs) = (vec![0.0], vec![from]);
        for (k, (t, q)) in points.iter().enumerate() {
            if k == 0 && *t == 0.0 {
                let off = max_step(q, &from);
                if off > TRAJECTORY_START_TOLERANCE {
                    self.refusal = Some(format!(
                        "the trajectory's waypoint at time 0 is {off:.4} rad from where it \
                         starts: make it the arm's position (or leave it out)"
                    ));
                    return code::BAD_ARGUMENT;
                }
                continue;
            }
            ts.push(*t);
            qs.push(snap_to_limits(q));
        }
        let total = *ts.last().expect("the start");
        if total <= 0.0 {
            // Only the start: nothing to do.
            return code::OK;
        }
        let s: Vec<f64> = ts.iter().map(|t| t / total).collect();
        let path = Path::timed(s.clone(), qs);
        for k in 0..s.len() - 1 {
            for j in 0..=TRAJECTORY_SAMPLES {
                let at = s[k] + (s[k + 1] - s[k]) * j as f64 / TRAJECTORY_SAMPLES as f64;
                let q = path.at(at);
                if let Some(i) = first_outside_limits(&q) {
                    self.refusal = Some(format!(
                        "joint {} would pass its limit at {:.3} s of the trajectory",
                        i + 1,
                        at * total
                    ));
                    return code::JOINT_LIMIT;
                }
                if self.lowest_z(&self.kin.fk(&q)) < self.settings.table_z - 1e-9 {
                    self.refusal = Some(format!(
                        "the tool would go below the table at {:.3} s of the trajectory",
                        at * total
                    ));
                    return code::BELOW_TABLE;
                }
            }
        }
        let (speeds, accels) = self.joint_limits_at(self.speed);
        let b = path.bounds();
        let v = 1.0 / total;
        for i in 0..6 {
            let (speed, accel) = (b.d1[i] * v, b.d2[i] * v * v);
            // A hair over the limit is the limit (the times travel as f32).
            if speed > speeds[i] * (1.0 + 1e-6) || accel > accels[i] * (1.0 + 1e-6) {
                self.refusal = Some(format!(
                    "joint {} would need {:.3} rad/s and {:.3} rad/s² where it has {:.3} and \
                     {:.3} at {}% speed: give the trajectory more time",
                    i + 1,
                    speed,
                    accel,
                    speeds[i],
                    accels[i],
                    self.speed
                ));
                return code::TOO_FAST;
            }
        }
        let (_, brake) = b.limits(&speeds, &accels);
        let start = self.planned_start_time(now);
        self.push_timed(path, Profile::steady(start, total, brake));
        code::OK
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

/// A pseudo-random dither of the encoders: 1 or 2 counts either way, per joint and 5 ms
/// slot (never 0, so actual and commanded never agree exactly).
fn dither(slot: i64, joint: usize) -> i32 {
    let mut x = (slot as u64) ^ ((joint as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15));
    x ^= x >> 33;
    x = x.wrapping_mul(0xFF51_AFD7_ED55_8CCD);
    x ^= x >> 33;
    let magnitude = 1 + (x & 1) as i32;
    let sign = if x & 2 == 0 { 1 } else { -1 };
    (sign * magnitude).clamp(-DITHER_COUNTS, DITHER_COUNTS)
}

/// The precision-point form of joints (re-exported for the controller).
pub fn counts_of(q: &Joints) -> [i32; 6] {
    model::joints_to_counts(q)
}

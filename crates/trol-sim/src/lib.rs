//! The simulated A465: the arm model ([`trol_a465::arm`]) as a robot backend of the PCP server,
//! on a clock that may run faster than real time, and the embedded controller (port `sim`).
//!
//! - [`SimBackend`]: the backend ([`trol_controller::Backend`]);
//! - [`ArmView`] / [`SharedArm`]: a copy of the whole arm for tests and conformance checks
//!   that compare the arm itself with what TROL says (a live view reads the backend's
//!   report, [`trol_controller::Backend::report`], as for every backend);
//! - [`embedded`]: the controller the host's port `sim` talks to, on a thread.

#![forbid(unsafe_code)]
#![warn(missing_docs, missing_debug_implementations)]

use std::time::Instant;

use trol_a465::arm::{self, Arm, ArmSettings, Stored, Which, code};
use trol_a465::backend::{A465_CODES, arm_target};
use trol_a465::model::joints_to_counts;
use trol_controller::{
    ArmReport, Backend, BackendError, BiosResult, Embedded, Pcp, PosMode, ReportedObject, Target,
    embedded_with,
};
use trol_port::memory::MemoryLine;
use trol_proto::application::record::{MM_DECIMALS, format_fixed};
use trol_proto::application::{
    CodeInfo, CodeTable, Gripper, Held, LocName, Location, Tag, Waypoint,
};
use trol_proto::link::LinkConfig;

/// The BIOS codes of the simulated A465 (docs/a465.md, "BIOS codes"): the planner's, and
/// the arm's power.
pub static SIM_CODES: &CodeTable = &{
    const EXTRA: [CodeInfo; 1] = [CodeInfo {
        value: code::ARM_POWER,
        name: "BIOS_ARM_POWER",
        meaning: "the arm has no power (an e-stop): switch it on, then TROLHome",
    }];
    trol_a465::backend::with_a465_codes::<{ A465_CODES.len() + EXTRA.len() }>(&EXTRA)
};

/// Start the embedded controller (port `sim`): the simulated A465 behind the PCP server, in
/// server mode, on a thread, over an in-memory line. Returns the host's end of the line.
pub fn embedded(settings: SimSettings, cfg: LinkConfig) -> (MemoryLine, Embedded) {
    embedded_with(Pcp::new(SimBackend::new(settings)), cfg)
}

/// Settings of the simulated controller.
#[derive(Clone, Debug)]
pub struct SimSettings {
    /// The arm's settings (table height, object between the fingers, homed at start).
    pub arm: ArmSettings,
    /// How much faster than real time the simulation runs (1 = real time).
    pub time_scale: f64,
    /// Locations loaded at start.
    pub locations: Vec<(String, Stored)>,
    /// The locations file they came from, which TROLSaveLocations writes back (none: Save
    /// answers BIOS_NO_FILE).
    pub locations_file: Option<std::path::PathBuf>,
    /// The tool transform at start.
    pub tool: [f64; 6],
}

impl Default for SimSettings {
    fn default() -> Self {
        SimSettings {
            arm: ArmSettings::default(),
            time_scale: 1.0,
            locations: Vec::new(),
            locations_file: None,
            tool: [0.0; 6],
        }
    }
}

/// The simulated A465 as a backend.
pub struct SimBackend {
    arm: Arm,
    epoch: Instant,
    scale: f64,
    view: Option<SharedArm>,
    locations_file: Option<std::path::PathBuf>,
    /// The axes of the last Home accepted, until a Finish has seen it end.
    homing: Option<Vec<usize>>,
    /// The arm's power switch, where a test holds it ([`SimBackend::power_switch`]).
    power: Option<PowerSwitch>,
}

/// The simulated arm's power, switched by a test as an e-stop or a power failure would
/// switch it: the backend applies each change before anything else it does, and when the
/// line is quiet.
#[derive(Clone, Debug, Default)]
pub struct PowerSwitch(std::sync::Arc<std::sync::Mutex<PowerChanges>>);

#[derive(Debug, Default)]
struct PowerChanges {
    pending: Vec<bool>,
    asked: u64,
    applied: u64,
}

impl PowerSwitch {
    /// Switch the power on or off; returns the change's number for [`PowerSwitch::applied`].
    pub fn set(&self, on: bool) -> u64 {
        let mut c = self.0.lock().unwrap_or_else(|e| e.into_inner());
        c.pending.push(on);
        c.asked += 1;
        c.asked
    }

    /// How many changes the arm has taken.
    pub fn applied(&self) -> u64 {
        self.0.lock().unwrap_or_else(|e| e.into_inner()).applied
    }

    fn pending(&self) -> bool {
        !self
            .0
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .pending
            .is_empty()
    }

    fn take(&self) -> Vec<bool> {
        let mut c = self.0.lock().unwrap_or_else(|e| e.into_inner());
        c.applied = c.asked;
        std::mem::take(&mut c.pending)
    }
}

/// A copy of the simulated arm for a view (a browser page): the arm's motions are planned,
/// so where it is at any instant follows from the copy and the simulation's clock.
#[derive(Clone, Debug)]
pub struct ArmView {
    /// The arm as of the last transaction.
    pub arm: Arm,
    /// When the simulation's time was 0.
    pub epoch: Instant,
    /// How much faster than real time the simulation runs.
    pub scale: f64,
}

impl ArmView {
    /// Simulation time now, s.
    pub fn now(&self) -> f64 {
        self.epoch.elapsed().as_secs_f64() * self.scale
    }
}

/// The arm's copy, shared with a view and renewed after every transaction.
pub type SharedArm = std::sync::Arc<std::sync::Mutex<Option<ArmView>>>;

impl SimBackend {
    /// A simulated arm with `settings`.
    pub fn new(settings: SimSettings) -> SimBackend {
        let mut arm = Arm::new(settings.arm);
        arm.set_tool(settings.tool);
        for (name, loc) in settings.locations {
            arm.set_location(&name, loc);
        }
        SimBackend {
            arm,
            epoch: Instant::now(),
            scale: settings.time_scale.max(1e-3),
            view: None,
            locations_file: settings.locations_file,
            homing: None,
            power: None,
        }
    }

    /// The arm's power switch, for a test that plays an e-stop or a power failure.
    pub fn power_switch(&mut self) -> PowerSwitch {
        self.power.get_or_insert_with(PowerSwitch::default).clone()
    }

    /// Simulation time now, after the power changes a test made (each at this instant).
    fn at(&mut self) -> f64 {
        let now = self.now();
        if let Some(p) = &self.power {
            for on in p.take() {
                if on {
                    self.arm.power_on();
                } else {
                    self.arm.power_off(now);
                }
            }
        }
        now
    }

    /// Share a copy of the arm with a test or a conformance check: it is renewed after every
    /// request and watchdog halt ([`Backend::after_request`]), a clone of the whole arm each
    /// time, so a live view reads [`Backend::report`] instead.
    pub fn share(&mut self) -> SharedArm {
        let shared = SharedArm::default();
        self.view = Some(shared.clone());
        self.publish();
        shared
    }

    fn publish(&self) {
        if let Some(v) = &self.view {
            if let Ok(mut slot) = v.lock() {
                *slot = Some(ArmView {
                    arm: self.arm.clone(),
                    epoch: self.epoch,
                    scale: self.scale,
                });
            }
        }
    }

    /// Simulation time now, s.
    pub fn now(&self) -> f64 {
        self.epoch.elapsed().as_secs_f64() * self.scale
    }

    /// The arm.
    pub fn arm(&self) -> &Arm {
        &self.arm
    }

    /// The arm, mutably.
    pub fn arm_mut(&mut self) -> &mut Arm {
        &mut self.arm
    }

    fn target(&self, t: &Target) -> Result<arm::Target, BackendError> {
        arm_target(&self.arm, t)
    }
}

impl Backend for SimBackend {
    fn kind(&self) -> &'static str {
        "simulated A465"
    }
    fn codes(&self) -> &'static CodeTable {
        SIM_CODES
    }
    fn appro(&mut self, target: &Target, disp: [f64; 6], straight: bool) -> BiosResult {
        let t = self.target(target)?;
        let now = self.at();
        Ok(self.arm.appro(t, disp, straight, now))
    }
    fn close(&mut self, force: u8) -> BiosResult {
        let now = self.at();
        Ok(self.arm.close(force as f64, now))
    }
    fn depart(&mut self, disp: [f64; 6], straight: bool) -> BiosResult {
        let now = self.at();
        Ok(self.arm.depart(disp, straight, now))
    }
    fn moving(&mut self) -> Result<bool, BackendError> {
        let now = self.at();
        let status = self.arm.finish_status(now);
        let moving = status == code::MOVING;
        // A motion or a Home the power cut short fails its Finish with the power's code.
        if status == code::ARM_POWER {
            self.homing = None;
            return Err(BackendError::Refused(code::ARM_POWER));
        }
        // A Home that ended with its axes not homed (halted on the way) fails the Finish
        // after it, once (issue 37: a halted Home is a failure, not a success).
        if !moving {
            if let Some(axes) = self.homing.take() {
                let homed = self.arm.homed();
                if !axes.iter().all(|&a| homed[a]) {
                    return Err(BackendError::Refused(code::NOT_HOMED));
                }
            }
        }
        Ok(moving)
    }
    fn stands(&mut self) -> Result<bool, BackendError> {
        let now = self.at();
        Ok(self.arm.finish_status(now) != code::MOVING)
    }
    fn grip(&mut self, dist: u8) -> BiosResult {
        let now = self.at();
        Ok(self.arm.grip(dist as f64, now))
    }
    fn halt(&mut self) -> BiosResult {
        let now = self.at();
        Ok(self.arm.halt(now))
    }
    fn home(&mut self, axis: u8) -> BiosResult {
        let now = self.at();
        let c = self.arm.home(axis, now);
        if c == code::OK {
            self.homing = Some(if axis == 0 {
                (0..6).collect()
            } else {
                vec![axis as usize - 1]
            });
        }
        Ok(c)
    }
    fn jog(&mut self, d: [f64; 3], straight: bool) -> BiosResult {
        let now = self.at();
        Ok(self.arm.jog(d, straight, now))
    }
    fn joint(&mut self, joint: u8, radians: f64) -> BiosResult {
        let now = self.at();
        Ok(self.arm.joint(joint, radians, now))
    }
    fn ma(&mut self, q: [f64; 6]) -> BiosResult {
        let now = self.at();
        Ok(self.arm.ma(q, now))
    }
    fn mi(&mut self, dq: [f64; 6]) -> BiosResult {
        let now = self.at();
        Ok(self.arm.mi(dq, now))
    }
    fn trajectory(&mut self, points: &[Waypoint]) -> BiosResult {
        let now = self.at();
        let points: Vec<(f64, [f64; 6])> = points.iter().map(|p| (p.time, p.joints)).collect();
        Ok(self.arm.trajectory(&points, now))
    }
    fn move_to(&mut self, target: &Target, straight: bool) -> BiosResult {
        let t = self.target(target)?;
        let now = self.at();
        Ok(self.arm.move_to(t, straight, now))
    }
    fn open(&mut self, force: u8) -> BiosResult {
        let now = self.at();
        Ok(self.arm.open(force as f64, now))
    }
    fn ready(&mut self) -> BiosResult {
        let now = self.at();
        Ok(self.arm.ready(now))
    }
    fn set_tool(&mut self, tool: [f64; 6]) -> BiosResult {
        Ok(self.arm.set_tool(tool))
    }
    fn speed(&mut self, percent: u8) -> BiosResult {
        Ok(self.arm.set_speed(percent as f64))
    }
    fn here(&mut self, name: LocName, tag: Tag) -> BiosResult {
        let now = self.at();
        trol_a465::backend::table::here(&mut self.arm, name, tag, now)
    }
    fn define(&mut self, name: LocName, loc: &Location) -> BiosResult {
        trol_a465::backend::table::define(&mut self.arm, name, loc)
    }
    fn delete_location(&mut self, name: LocName) -> BiosResult {
        trol_a465::backend::table::delete(&mut self.arm, name)
    }
    fn locations(&mut self) -> Result<Vec<(LocName, Location)>, BackendError> {
        Ok(trol_a465::backend::table::list(&self.arm))
    }
    fn save_locations(&mut self) -> BiosResult {
        trol_a465::backend::table::save(&self.arm, self.locations_file.as_deref())
    }
    fn after_request(&mut self) {
        self.at();
        self.publish();
    }
    fn idle(&mut self) {
        if self.power.as_ref().is_some_and(PowerSwitch::pending) {
            self.at();
            self.publish();
        }
    }
    fn take_note(&mut self) -> Option<String> {
        self.arm.take_refusal()
    }
    fn world(&mut self) -> Option<String> {
        let now = self.at();
        let held = self.arm.held().map(str::to_string);
        let objects = self.arm.objects(now);
        if objects.is_empty() {
            return None;
        }
        let words: Vec<String> = objects
            .iter()
            .map(|o| {
                let [x, y, z] = o.pos;
                let place = if held.as_deref() == Some(o.name.as_str()) {
                    "in the gripper"
                } else {
                    "resting"
                };
                // To the arm's 0.001 mm, as every surface prints a length (issue 42).
                let mm = |v: f64| format_fixed(v, MM_DECIMALS);
                format!(
                    "{} at x {} y {} z {} mm, {place}",
                    o.name,
                    mm(x),
                    mm(y),
                    mm(z)
                )
            })
            .collect();
        Some(words.join("; "))
    }
    fn report_is_free(&self) -> bool {
        true
    }
    fn report(&mut self) -> Option<ArmReport> {
        // Read from the arm where it is now: no copy of it (issue 39, item 4).
        let now = self.at();
        let arm = &mut self.arm;
        let moving = arm.is_moving(now);
        let held = arm.held().map(str::to_string);
        let objects = arm
            .objects(now)
            .into_iter()
            .map(|o| ReportedObject {
                held: held.as_deref() == Some(o.name.as_str()),
                name: o.name,
                pos: o.pos,
                width: o.width,
            })
            .collect();
        Some(ArmReport {
            joints: arm.position(now, Which::Actual),
            moving,
            target: moving.then(|| arm.planned_end()),
            gripper_mm: Some(arm.fingers(now)),
            tool: arm.kinematics().tool(),
            // The simulation is the arm itself: its joints are known homed or not, and the
            // view shows them as they are.
            homed: None,
            time: Some(now),
            objects,
            table_z: Some(arm.settings().table_z),
            simulated: true,
        })
    }
    fn gripper(&mut self) -> Result<Gripper, BackendError> {
        let now = self.at();
        Ok(Gripper {
            opening_mm: self.arm.fingers(now),
            held: match self.arm.held() {
                Some(name) => Held::Object(name.to_string()),
                None => Held::Nothing,
            },
        })
    }
    fn position(&mut self, tag: Tag, mode: PosMode) -> Result<Location, BackendError> {
        let now = self.at();
        let which = match mode {
            PosMode::Commanded => Which::Commanded,
            PosMode::Actual => Which::Actual,
        };
        let q = self.arm.position(now, which);
        Ok(match tag {
            Tag::Joint => Location::from_array6(Tag::Joint, q),
            Tag::Prec => Location::Prec(joints_to_counts(&q).to_vec()),
            Tag::Cart => Location::from_array6(Tag::Cart, self.arm.kinematics().fk_xyzypr(&q)),
        })
    }
}

impl std::fmt::Debug for SimBackend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SimBackend")
            .field("time_scale", &self.scale)
            .field("now", &self.now())
            .finish_non_exhaustive()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_code_table_names_every_code_the_arm_returns() {
        for v in [
            code::MOVING,
            code::NOT_HOMED,
            code::OUT_OF_REACH,
            code::JOINT_LIMIT,
            code::BELOW_TABLE,
            code::SINGULAR_PATH,
            code::BAD_ARGUMENT,
        ] {
            assert!(SIM_CODES.iter().any(|c| c.value == v), "{v}");
        }
    }
}

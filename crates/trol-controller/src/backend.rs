//! The robot backend contract: what the PCP server asks of the robot's firmware (manual,
//! "Erstellen von Kommando-Handlern"; "PCP\BIOSCALL.C", the C interface to the RAPL-BIOS).
//!
//! The manual's PCP ran on the C500 and called the RAPL-BIOS directly. Here the server runs on
//! a PC, in front of a [`Backend`]: the simulated A465 (`trol_sim::SimBackend`), or a backend
//! that drives a real C500 over its own line. The contract is shaped for both:
//!
//! - every call can fail with a [`BackendError`] (the link to the robot can break), besides
//!   returning a BIOS code (> -32000, 0 = success);
//! - a target is a location name, passed through to a controller that keeps its own table, or
//!   coordinates ([`Target`]);
//! - values are f64 as decoded from the wire, never narrowed again;
//! - the backend publishes the table of the BIOS codes it can return ([`Backend::codes`]),
//!   which the server's log, the trace and the API's error texts use;
//! - nothing blocks: motions start and return; the server waits for an idle arm
//!   (Finish(FINISH_WAIT), Home) by polling [`Backend::moving`], between which it can serve
//!   its line.

use trol_proto::application::code::{
    Code, CodeTable, TROL_ERR_LOCATION, TROL_ERR_ROBOT, TROL_ERR_ROBOT_UNSURE,
};
use trol_proto::application::{Gripper, LocName, Location, Tag, Waypoint};

/// The target of an absolute motion.
#[derive(Clone, Debug, PartialEq)]
pub enum Target {
    /// A location of the controller's own table, by name (TROLMove, TROLAppro).
    Name(LocName),
    /// Coordinates: cartesian or a precision point (TROLMoveII, TROLApproII).
    Location(Location),
}

/// GetPosition's mode.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PosMode {
    /// POS_COMMANDED: where the firmware tells the arm to be.
    Commanded,
    /// POS_ACT: where the encoders say it is.
    Actual,
}

/// The arm as a backend reports it (what its controller says, or the simulated arm itself),
/// for a view of any backend: the live view reads nothing else ([`Backend::report`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ArmReport {
    /// Where the encoders say the arm is, radians.
    pub joints: [f64; 6],
    /// Whether it moves (or a motion of TROL's has not ended).
    pub moving: bool,
    /// Where the motion under way ends, radians, where the backend knows it.
    pub target: Option<[f64; 6]>,
    /// The finger distance, mm, where the backend knows it.
    pub gripper_mm: Option<f64>,
    /// The tool transform in force.
    pub tool: [f64; 6],
    /// Which axes are homed, where the backend knows it: a view shows an axis that is not
    /// as "not homed" rather than a value its counters cannot give yet.
    pub homed: Option<[bool; 6]>,
    /// The controller's own clock, s, where it has one (the simulation's time): a view plots
    /// against it; without it, against when the report was taken.
    pub time: Option<f64>,
    /// The objects of a simulated world; a real controller knows of none.
    pub objects: Vec<ReportedObject>,
    /// The table plane, mm, where the backend knows it.
    pub table_z: Option<f64>,
    /// The report is the simulated arm itself, not what a controller says of a real one.
    pub simulated: bool,
}

/// An object of a simulated world, as a report gives it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReportedObject {
    /// Its name.
    pub name: String,
    /// Where its centre is, mm.
    pub pos: [f64; 3],
    /// Its width, mm.
    pub width: f64,
    /// It is between the fingers.
    pub held: bool,
}

/// The latest report and when it was taken, shared between the controller that renews it and
/// a view that reads it. Reports are renewed only while someone reads them: a reader says so
/// ([`SharedReport::want`]), and the controller renews the report for [`WANT_HOLD`] after
/// that (a backend that asks its controller for each report then keeps its line free while
/// nobody watches).
#[derive(Clone, Debug, Default)]
pub struct SharedReport {
    slot: std::sync::Arc<std::sync::Mutex<Slot>>,
}

#[derive(Debug, Default)]
struct Slot {
    report: Option<(ArmReport, std::time::Instant)>,
    wanted: Option<std::time::Instant>,
}

/// How long one [`SharedReport::want`] keeps the controller renewing the report.
pub const WANT_HOLD: std::time::Duration = std::time::Duration::from_secs(2);

impl SharedReport {
    fn lock(&self) -> std::sync::MutexGuard<'_, Slot> {
        self.slot.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The latest report and when it was taken (`None` before the first).
    pub fn latest(&self) -> Option<(ArmReport, std::time::Instant)> {
        self.lock().report.clone()
    }

    /// Say that a reader wants reports from now on (for [`WANT_HOLD`]); whether one wanted
    /// them already (else the latest report may be as old as the last reader left it).
    pub fn want(&self) -> bool {
        let mut slot = self.lock();
        let warm = slot.wanted.is_some_and(|at| at.elapsed() < WANT_HOLD);
        slot.wanted = Some(std::time::Instant::now());
        warm
    }

    /// Whether a reader wanted reports within the last [`WANT_HOLD`].
    pub fn wanted(&self) -> bool {
        self.lock()
            .wanted
            .is_some_and(|at| at.elapsed() < WANT_HOLD)
    }

    /// Put a new report, taken now.
    pub fn put(&self, report: ArmReport) {
        self.lock().report = Some((report, std::time::Instant::now()));
    }
}

/// A call the backend could not make.
#[derive(Debug, thiserror::Error)]
pub enum BackendError {
    /// The controller's table has no location of this name (TROL_ERR_LOCATION).
    #[error("no location named {0} in the controller's table")]
    UnknownLocation(LocName),
    /// The command did not reach the robot, and did not run (TROL_ERR_ROBOT): the link
    /// failed, the robot's answer to a read before it was not in the form the backend reads,
    /// or the command's line came back damaged and was taken back. The text says which.
    #[error("the command did not reach the robot, and did not run: {0}")]
    Link(String),
    /// The link to the robot failed after the command was sent: it may have run
    /// (TROL_ERR_ROBOT_UNSURE; GetStatus reports the BIOS as called).
    #[error("the link to the robot failed after the command was sent: {0}")]
    Unsure(String),
    /// The backend refused the call with one of its BIOS codes (for calls whose answer is
    /// not a code, such as GetPosition).
    #[error("refused with BIOS code {0}")]
    Refused(i16),
    /// Refused with one of its BIOS codes, and the cause in words for the log (a locations
    /// file that could not be written: which file, and what the system said).
    #[error("refused with BIOS code {0}: {1}")]
    Explained(i16, String),
    /// The controller cannot answer this command at all (TROL_ERR_UNKNOWN): a gripper it
    /// cannot read, for example.
    #[error("this controller cannot {0}")]
    Unsupported(&'static str),
    /// Halt: every stop the controller has was sent, and the arm was not seen standing: it
    /// may still be moving (TROL_ERR_NOT_STOPPED), with what the controller said.
    #[error("the arm was not seen standing after every stop: {0}")]
    NotStopped(String),
}

impl BackendError {
    /// The TROL code the server answers with.
    pub fn code(&self) -> Code {
        match self {
            BackendError::UnknownLocation(_) => TROL_ERR_LOCATION,
            BackendError::Link(_) => TROL_ERR_ROBOT,
            BackendError::Unsure(_) => TROL_ERR_ROBOT_UNSURE,
            BackendError::Refused(v) | BackendError::Explained(v, _) => Code(*v),
            BackendError::Unsupported(_) => trol_proto::application::code::TROL_ERR_UNKNOWN,
            BackendError::NotStopped(_) => trol_proto::application::code::TROL_ERR_NOT_STOPPED,
        }
    }
}

impl From<BackendError> for Code {
    fn from(e: BackendError) -> Code {
        e.code()
    }
}

/// The most waypoints [`untimed_trajectory`] takes: one queued motion each, and the
/// simulated A465's and a C500's motion queues hold 16.
pub const UNTIMED_WAYPOINTS: usize = 16;

/// Whether `kind`, running a trajectory as one joint move per waypoint, takes `n`
/// waypoints: at most [`UNTIMED_WAYPOINTS`], else TROL_ERR_ARG_RANGE with what to do.
pub fn untimed_count(kind: &str, n: usize) -> Result<(), BackendError> {
    if n > UNTIMED_WAYPOINTS {
        return Err(BackendError::Explained(
            trol_proto::application::code::TROL_ERR_ARG_RANGE.0,
            format!(
                "{n} waypoints: {kind} runs a trajectory as one joint move per waypoint, at \
                 most {UNTIMED_WAYPOINTS}: send fewer (every few points of a dense plan)"
            ),
        ));
    }
    Ok(())
}

/// A trajectory on a controller that cannot run a timed path: one MA to each waypoint at
/// the speed setting (queued behind each other), and TRAJECTORY_UNTIMED. More than
/// [`UNTIMED_WAYPOINTS`] is TROL_ERR_ARG_RANGE before anything is sent. A waypoint the
/// controller refuses after others were accepted stops the arm (Halt, seen standing) so
/// that no part of a refused trajectory runs on, and its code is the answer; a link that
/// fails is the answer as it is (unsure: nothing more is sent).
pub fn untimed_trajectory<B: Backend + ?Sized>(b: &mut B, points: &[Waypoint]) -> BiosResult {
    untimed_count(b.kind(), points.len())?;
    for (k, p) in points.iter().enumerate() {
        let c = b.ma(p.joints)?;
        if c != 0 {
            if k > 0 {
                b.halt()?;
            }
            return Ok(c);
        }
    }
    Ok(trol_proto::application::table::TRAJECTORY_UNTIMED)
}

/// A BIOS call's result: its return value, or why it could not be made.
pub type BiosResult = Result<i16, BackendError>;

/// The robot behind the PCP server: one method per RAPL-BIOS call. Coordinates arrive with
/// all six values (the server has set the ones not sent to 0).
pub trait Backend: Send {
    /// What it is, for logs and for the host (`simulated A465`).
    fn kind(&self) -> &'static str;
    /// Name and meaning of every BIOS code it returns.
    fn codes(&self) -> &'static CodeTable;
    /// The longest a call of it takes (but a wait without limit): what the server answers
    /// TROLGetReplyTime, and the host waits for a reply, with a margin. A backend that waits
    /// for a robot controller of its own says how long it waits for it.
    fn reply_time(&self) -> std::time::Duration {
        std::time::Duration::from_millis(500)
    }
    /// Approach `target` displaced by `disp` in its tool frame.
    fn appro(&mut self, target: &Target, disp: [f64; 6], straight: bool) -> BiosResult;
    /// Close the gripper with `force` percent.
    fn close(&mut self, force: u8) -> BiosResult;
    /// Move away from here by `disp` in the tool frame.
    fn depart(&mut self, disp: [f64; 6], straight: bool) -> BiosResult;
    /// Whether the arm or the gripper still moves, or homes (Finish(FINISH_STATUS)).
    fn moving(&mut self) -> Result<bool, BackendError>;
    /// Whether the arm stands, for the answer to a Halt: without deciding how any motion
    /// ended (that is [`Backend::moving`]'s, at the next Finish). A backend whose
    /// [`Backend::halt`] has seen the arm standing answers true.
    fn stands(&mut self) -> Result<bool, BackendError> {
        self.moving().map(|m| !m)
    }
    /// Set the finger distance, mm.
    fn grip(&mut self, dist: u8) -> BiosResult;
    /// Stop all motion, and return success only once the arm is seen standing (issue 37): a
    /// backend that drives a real controller reads the arm after its stop, tries the
    /// controller's other stops where it is not standing, and answers
    /// [`BackendError::NotStopped`] when none was seen to work.
    fn halt(&mut self) -> BiosResult;
    /// Start homing one axis (1..6) or all (0); the server replies once [`Backend::moving`]
    /// says it is done.
    fn home(&mut self, axis: u8) -> BiosResult;
    /// Move the tool by dx dy dz in the world frame.
    fn jog(&mut self, d: [f64; 3], straight: bool) -> BiosResult;
    /// Move one joint (1..6) by an increment, radians.
    fn joint(&mut self, joint: u8, radians: f64) -> BiosResult;
    /// All joints to absolute angles.
    fn ma(&mut self, q: [f64; 6]) -> BiosResult;
    /// All joints by increments.
    fn mi(&mut self, dq: [f64; 6]) -> BiosResult;
    /// Move to `target`.
    fn move_to(&mut self, target: &Target, straight: bool) -> BiosResult;
    /// Open the gripper with `force` percent.
    fn open(&mut self, force: u8) -> BiosResult;
    /// Go to the READY pose.
    fn ready(&mut self) -> BiosResult;
    /// Set the tool transform.
    fn set_tool(&mut self, tool: [f64; 6]) -> BiosResult;
    /// Set the speed, percent.
    fn speed(&mut self, percent: u8) -> BiosResult;
    /// Read the position in the form `tag`, commanded or actual (six values).
    fn position(&mut self, tag: Tag, mode: PosMode) -> Result<Location, BackendError>;
    /// The gripper: the fingers' opening (mm) and what they hold (GetGripper). By default
    /// the controller cannot read it (TROL_ERR_UNKNOWN).
    fn gripper(&mut self) -> Result<Gripper, BackendError> {
        Err(BackendError::Unsupported("read its gripper"))
    }
    /// Here: store where the arm is (commanded) under `name`, in the form `tag` (teaching,
    /// docs/teach.md). A precision point's name starts with `#` (the server checked). By
    /// default: GetPosition's commanded position, stored by [`Backend::define`].
    fn here(&mut self, name: LocName, tag: Tag) -> BiosResult {
        let here = self.position(tag, PosMode::Commanded)?;
        self.define(name, &here)
    }
    /// Define: store `loc` (six values) under `name` (RAPL-II's POINT).
    fn define(&mut self, name: LocName, loc: &Location) -> BiosResult {
        let _ = (name, loc);
        Err(BackendError::Unsupported("store locations"))
    }
    /// Forget the location `name` (RAPL-II's DLOCN); TROL_ERR_LOCATION if there is none.
    fn delete_location(&mut self, name: LocName) -> BiosResult {
        let _ = name;
        Err(BackendError::Unsupported("delete locations"))
    }
    /// The location table: each name with its location (RAPL-II's LISTL), sorted by name.
    fn locations(&mut self) -> Result<Vec<(LocName, Location)>, BackendError> {
        Err(BackendError::Unsupported("list locations"))
    }
    /// Keep the location table across a restart (the simulator writes its locations file; a
    /// controller that keeps its own table answers 0).
    fn save_locations(&mut self) -> BiosResult {
        Err(BackendError::Unsupported("save locations"))
    }
    /// Trajectory: one motion through `points` at their times (TROLTrajectory; the server
    /// checked their number, values and increasing times). 0: it runs as timed. By default,
    /// for a controller that cannot run a timed path, [`untimed_trajectory`]: one MA to each
    /// waypoint at the speed setting, and TRAJECTORY_UNTIMED.
    fn trajectory(&mut self, points: &[Waypoint]) -> BiosResult {
        untimed_trajectory(self, points)
    }
    /// Where the world's objects are, in words, for logs (a simulator knows; a real
    /// controller does not, and says nothing).
    fn world(&mut self) -> Option<String> {
        None
    }
    /// Called after each request the controller ran, before its reply leaves, and after its
    /// watchdog halted the arm: a moment to share the arm's state (the simulator renews the
    /// copy a test compares with, [`SimBackend::share`](../trol_sim/struct.SimBackend.html)),
    /// so that whoever reads the arm after the reply sees what the call did.
    fn after_request(&mut self) {}
    /// Why the last request was refused, in words, where its code alone cannot say it (a
    /// straight line: which singular pose, where on the line, what to do), once: for the
    /// controller's log.
    fn take_note(&mut self) -> Option<String> {
        None
    }
    /// The arm as the controller reports it now, for a view (`None`: nothing to report, or
    /// not now). Called between requests and during long waits, at most as often as the
    /// controller was told ([`crate::Controller::share_reports`]); it may ask the controller,
    /// so it must be as quick as one short read-only command.
    fn report(&mut self) -> Option<ArmReport> {
        None
    }
    /// Whether [`Backend::report`] only reads memory (the simulated arm) and so may be asked
    /// after every request as well: a view then shows the end of a motion as soon as the
    /// call that waited for it returns. A backend that asks its controller says no (the
    /// default), and is asked at most as often as the controller was told.
    fn report_is_free(&self) -> bool {
        false
    }
    /// Called when the line has been quiet for a moment (no request arrived): a backend that
    /// keeps motions of its own for later (the RAPL-II backend's queue behind a motion under
    /// way) starts them here. It must return within the time one short command takes, so a
    /// Halt waits no longer.
    fn idle(&mut self) {}
}

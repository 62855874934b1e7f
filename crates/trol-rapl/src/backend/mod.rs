//! The RAPL-II backend: the PCP server's robot backend ([`trol_controller::Backend`]) on a
//! real C500, over a port (c500-rapl.md §1.4 has the command table this follows).
//!
//! The rule (docs/c500.md, "What TROL assumes"): where the public sources do not settle what a
//! C500 does, take the reading under which TROL never reports success for a failure nor moves
//! the arm unasked; where it cannot tell, say so (TROL_ERR_ROBOT_UNSURE with the controller's
//! text) and send nothing further.
//!
//! - **Success is recognised, not assumed**: a command succeeded only when its reply is the
//!   exact success form (the ACK as this controller gives it, the prompt, and no text where
//!   the command prints none). A line in one of the profile's refusal forms is a refusal with
//!   its text; any other line, or a refusal line followed by ACK, is UNSURE.
//! - **No stale target**: a scratch location is read back (LISTL) after POINT and must hold
//!   what was sent before a MOVE names it; scratch names rotate, so a queued motion never
//!   moves to another's target.
//! - **Before a motion**, STATUS: arm power (LIMP) and HOMED are checked, and a motion while
//!   another runs waits in the backend's queue (so the line stays free for Halt) and starts
//!   once the first has ended.
//! - **Finish tells the truth**: the end of a motion is STATUS's DONE row *and* the arm (W2)
//!   at the motion's target within the profile's tolerance (or, for a target not known
//!   beforehand, seen moving or standing still); arm power lost or HOMED lost during a motion,
//!   and any line the controller prints unasked, end the wait with a named code.
//! - **The safe default gates what it does not know**: cartesian values need `angles` and
//!   units, MA/MI `joint_units`, precision points and joint targets `pulse_scale` (or MA),
//!   a straight Jog `jog_frame`; each is refused before anything is sent, naming the key.
//! - **Halt always gets through**: it is typed through an XOFF, clears the queue, and no
//!   other wait holds the line longer than one short command (motion commands answer at
//!   their start; their end is polled).
//! - Move and Appro by name use the controller's own location table (LISTL first, so an
//!   unknown name is TROL_ERR_LOCATION whatever the controller's error numbers); MoveII,
//!   ApproII, Depart, Jog off the straight line and SetToolTransform are computed on the PC
//!   with the A465 kinematics (trol-a465) and sent as POINT plus MOVE/MOVES or TOOL.
//! - A failure of the line is TROL_ERR_ROBOT when the line was cancelled before its
//!   terminator (the command did not run), TROL_ERR_ROBOT_UNSURE after it.

use std::collections::VecDeque;
use std::io;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use trol_a465::arm::code as sim_code;
use trol_a465::backend::A465_CODES;
use trol_a465::kinematics::{Kinematics, Pose};
use trol_controller::backend::{ArmReport, Backend, BackendError, BiosResult, PosMode, Target};
use trol_controller::real;
use trol_port::Port;
use trol_proto::application::{CodeInfo, CodeTable, LocName, Location, Tag};
use trol_proto::time::Instant;

use crate::aci::{AciError, Master};
use crate::frames::{Frames, Unsettled};
use crate::profile::{
    Ack, Completion, Entry, Halt, JointUnits, MotionAck, Profile, RefusalForm, Units,
};
use crate::session::{ACK, CTRL_Z, Reply, Session, SessionConfig, SessionError};
use crate::text::{self, Listed};

mod bios;
mod completion;
mod halt;
mod line;
mod motion;
mod opening;
mod position;
mod teach;

// The codes every real controller's backend shares (trol_a465::backend::real): the arm has
// no power (LIMP, an e-stop), a call with no RAPL-II form, a motion computed from where the
// arm is while another has not ended, the arm standing short of a motion the controller
// calls done.
pub use trol_a465::backend::real::{ARM_POWER, BUSY, NOT_AT_TARGET, UNSUPPORTED};
/// Cartesian values need the controller's angle order.
pub const NO_ANGLES: i16 = -9;
/// An error line the profile does not map.
pub const RAPL_ERROR: i16 = -10;
/// MA and MI need their units.
pub const NO_JOINT_UNITS: i16 = -12;
/// Cartesian values need the controller's length units.
pub const NO_UNITS: i16 = -13;
/// Precision points and joint targets as pulses need the pulse convention.
pub const NO_PULSES: i16 = -14;
/// A straight Jog needs JOG's frame.
pub const NO_JOG_FRAME: i16 = -15;
/// A call needs a profile key that is not set (the log names it): a Home needs the arm's
/// home pose (`home_joints`). The C500C's BIOS_UNSETTLED, the same number.
pub const UNSETTLED: i16 = -28;

/// The BIOS codes of the RAPL-II backend: the simulator's, and those of a real controller.
pub static RAPL_CODES: &CodeTable = &{
    const EXTRA: [CodeInfo; 11] = [
        CodeInfo {
            value: ARM_POWER,
            name: "BIOS_ARM_POWER",
            meaning: "the arm has no power (LIMP, an emergency stop): restore it at the controller",
        },
        CodeInfo {
            value: NO_ANGLES,
            name: "BIOS_NO_ANGLES",
            meaning: "cartesian commands need the controller's angle order: set `angles` in the \
                      RAPL-II profile (docs/c500.md, section Settle the conventions)",
        },
        CodeInfo {
            value: RAPL_ERROR,
            name: "BIOS_RAPL_ERROR",
            meaning: "the C500 refused with an error line the profile does not map; the log has \
                      its text (map it in the profile's [errors])",
        },
        CodeInfo {
            value: UNSUPPORTED,
            name: "BIOS_UNSUPPORTED",
            meaning: "RAPL-II has no form for this: homing one axis (use TROLHome(0)), a joint \
                      location (use a precision point, #NAME), or Save (the C500 keeps them)",
        },
        CodeInfo {
            value: NO_JOINT_UNITS,
            name: "BIOS_NO_JOINT_UNITS",
            meaning: "MA and MI need their units: set `joint_units` (degrees or radians) in the \
                      RAPL-II profile (docs/c500.md, section Settle the conventions)",
        },
        CodeInfo {
            value: NO_UNITS,
            name: "BIOS_NO_UNITS",
            meaning: "the controller's length units are unknown: set `units` (mm or inch) in the \
                      RAPL-II profile",
        },
        CodeInfo {
            value: NO_PULSES,
            name: "BIOS_NO_PULSES",
            meaning: "precision points need the pulse scale and zero: set pulse_scale and \
                      pulse_zero in the profile (trol rapl probe --poses 4 fits them), or \
                      joint_units",
        },
        CodeInfo {
            value: NO_JOG_FRAME,
            name: "BIOS_NO_JOG_FRAME",
            meaning: "a straight Jog needs JOG's frame: set `jog_frame` (world or tool) in the \
                      RAPL-II profile (docs/c500.md, section Settle the conventions)",
        },
        CodeInfo {
            value: UNSETTLED,
            name: "BIOS_UNSETTLED",
            meaning: "a Home needs the arm's home pose: set `home_joints` in the RAPL-II profile \
                      (`trol rapl probe --measure` reads it after HOME)",
        },
        CodeInfo {
            value: BUSY,
            name: "BIOS_BUSY",
            meaning: "the arm moves, not by TROL (the pendant?), or a tool change while a \
                      motion has not ended: call TROLFinish(FINISH_WAIT) first",
        },
        CodeInfo {
            value: NOT_AT_TARGET,
            name: "BIOS_NOT_AT_TARGET",
            meaning: "the controller says the motion is done, but the arm stands short of its \
                      end (a servo fault, a stop at the controller): check the arm",
        },
    ];
    trol_a465::backend::with_a465_codes::<{ A465_CODES.len() + EXTRA.len() }>(&EXTRA)
};

/// Why a session could not be opened.
#[derive(Debug, thiserror::Error)]
pub enum RaplError {
    /// The line failed.
    #[error("the line to the C500 failed: {0}")]
    Io(#[from] io::Error),
    /// Neither the ACI steps nor Ctrl-C found a controller.
    #[error(
        "no C500 answers on {port}: {aci}; and Ctrl-C brought no prompt. Check the cable, the \
         baud rate ({baud}), and that the teach pendant handed control to the host (docs/c500.md)"
    )]
    NoController {
        /// The port.
        port: String,
        /// What the ACI steps said.
        aci: String,
        /// The baud rate tried.
        baud: u32,
    },
    /// A command of the opening failed.
    #[error("opening the RAPL-II session failed: {0}")]
    Session(#[from] SessionError),
    /// The controller echoes nothing.
    #[error(
        "the C500 answers Ctrl-C with its prompt but echoes nothing typed ({0}): TROL checks \
         every echo, so turn the controller's echo on (RAPL-II CONFIG); nothing was sent"
    )]
    NoEcho(SessionError),
    /// STATUS could not be read.
    #[error("the C500's STATUS could not be read: {0}")]
    Status(String),
}

/// One direction of a transcript entry.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dir {
    /// From the host (gateway) to the controller.
    ToController,
    /// From the controller.
    FromController,
}

/// Every byte of a session with its time (a first contact with a controller, golden files).
#[derive(Clone, Debug, Default)]
pub struct Transcript {
    /// (seconds since the session began, direction, bytes).
    pub entries: Vec<(f64, Dir, Vec<u8>)>,
}

impl Transcript {
    fn add(&mut self, t: f64, dir: Dir, bytes: &[u8]) {
        match self.entries.last_mut() {
            Some((_, d, b)) if *d == dir => b.extend_from_slice(bytes),
            _ => self.entries.push((t, dir, bytes.to_vec())),
        }
    }

    /// As text: one line per run of bytes, `+T.TTTTTT H|C <hex>  <printable>`.
    pub fn to_text(&self) -> String {
        let mut s = String::new();
        for (t, d, b) in &self.entries {
            let hex: Vec<String> = b.iter().map(|x| format!("{x:02x}")).collect();
            let shown: String = b
                .iter()
                .map(|&x| {
                    if (0x20..0x7f).contains(&x) {
                        x as char
                    } else {
                        '.'
                    }
                })
                .collect();
            let who = if *d == Dir::ToController { 'H' } else { 'C' };
            s.push_str(&format!("{t:+.6} {who} {}  {shown}\n", hex.join(" ")));
        }
        s
    }
}

/// Where the backend's log lines go.
pub type LogFn = Box<dyn FnMut(&str) + Send>;

/// A transcript shared with the caller, so that it outlives a session that failed to open
/// (`trol rapl probe` writes it on every exit).
pub type Recorder = Arc<Mutex<Transcript>>;

/// What an error line means.
enum Meaning {
    Code(i16),
    Location,
}

/// What a motion must end at for Finish to call it ended.
#[derive(Clone, Debug, PartialEq)]
enum Expect {
    /// The JOINTS row, degrees.
    Joints([f64; 6]),
    /// The WORLD row, the controller's units and angles.
    World([f64; 6]),
    /// The PULSES row.
    Pulses([i64; 6]),
    /// Not known beforehand (READY): seen moving, or standing still `settle_ms`.
    Unknown,
    /// HOME: HOMED on every axis, and as [`Expect::Unknown`].
    Homed,
}

/// A motion line and what it must end at.
#[derive(Clone, Debug)]
struct Motion {
    line: String,
    expect: Expect,
}

/// A motion computed from where the arm stands (Joint, MI, Depart, Jog): sent while another
/// runs, it waits in the queue and is computed when its turn comes, from where the motion
/// before it ended (the manual's controller queued them so, as RAPL-II does).
type Later = Box<dyn FnOnce(&mut RaplBackend) -> BiosResult + Send>;

/// What waits in the backend's queue.
enum Queued {
    /// A motion whose line and end are known now.
    Motion(Motion),
    /// A motion computed when its turn comes; what the call asked for, for the log.
    Later(String, Later),
}

impl Queued {
    fn line(&self) -> &str {
        match self {
            Queued::Motion(m) => &m.line,
            Queued::Later(what, _) => what,
        }
    }
}

/// A motion the controller accepted whose end has not been seen.
#[derive(Debug)]
struct Outstanding {
    motion: Motion,
    /// Its end, look by look (the shared rule: STATUS's DONE row or FINISH, and W2).
    watch: real::EndWatch,
    /// FINISH was answered for it without settling its end (`completion = "finish"`): its
    /// end is looked for by STATUS.
    finish_tried: bool,
}

impl Outstanding {
    /// `seen_moving`: the controller answered it at its end (it ran); `from`: where W2 last
    /// saw the arm at rest before it (the end of the one before), if it did.
    fn new(motion: Motion, seen_moving: bool, from: Option<[f64; 6]>) -> Outstanding {
        let mut watch = real::EndWatch::new(std::time::Instant::now(), from, [STILL_DEG; 6]);
        if seen_moving {
            watch.saw_moving();
        }
        Outstanding {
            motion,
            watch,
            finish_tried: false,
        }
    }
}

/// How a reply reads.
enum Answer {
    /// The exact success form.
    Done(Reply),
    /// A refusal in one of the profile's forms: number (0 for a form without one), text.
    Refused(u16, String),
}

/// How long one look for FINISH's answer listens (`completion = "finish"`): the end is seen
/// the moment it comes within it; a request of the host waits at most this long.
pub const FINISH_LISTEN: Duration = Duration::from_millis(200);

/// The longest Ctrl-C may take to end a waiting FINISH (its prompt, and the line quiet
/// after it) before the controller counts as one that does not take it.
pub const CTRL_C_ENDS_FINISH_WITHIN: Duration = Duration::from_millis(500);

/// How many motions may wait behind the one under way (the simulated arm's queue).
pub const QUEUE: usize = trol_a465::arm::MOTION_QUEUE;
// The scratch names (T1 to T{QUEUE + 2}) are the ones every backend refuses a program
// (`LocName::reserved`), so that a program behaves alike on each.
const _: () = assert!(
    QUEUE + 2 == trol_proto::application::location::RESERVED_SCRATCH as usize,
    "the scratch names must be the reserved ones"
);

/// How long a stop may take to show on the arm: the A465's longest braking (a straight line
/// at 1000 mm/s and 2540 mm/s^2, 0.4 s; a joint at full speed, 0.25 s) and a margin for the
/// reads.
pub const STOP_WITHIN: Duration = Duration::from_millis(1000);

pub use trol_controller::real::{STILL_DEG, STILL_GAP};

/// The longest a Halt takes, all its stops included: within the reply time the host waits.
pub const HALT_WITHIN: Duration = Duration::from_millis(3300);

/// The RAPL-II backend over a port.
pub struct RaplBackend {
    port: Box<dyn Port>,
    session: Session,
    profile: Profile,
    frames: Frames,
    forms: Vec<RefusalForm>,
    ack: bool,
    joint_units: Option<JointUnits>,
    epoch: std::time::Instant,
    tool: [f64; 6],
    last_poll: Option<(std::time::Instant, bool)>,
    /// An OPEN, CLOSE or GRIP was taken and STATUS has not yet shown everything done: a
    /// motion called meanwhile waits in the queue for the fingers, as one behind a motion
    /// waits for it (issue 62: the manual's TROLClose then TROLDepart got BIOS_BUSY).
    gripping: bool,
    outstanding: Option<Outstanding>,
    /// Where W2 last saw the arm at rest (a motion's confirmed end, a Halt's stop).
    rest: Option<[f64; 6]>,
    queue: real::MotionQueue<Queued>,
    /// The speed setting the next motion is typed at: a trajectory's waypoint's own
    /// ([`RaplBackend::trajectory_paced`]), taken by [`RaplBackend::launch`].
    pacing: Option<u8>,
    /// The controller's SPEED is a waypoint's, not the user's: the next other motion types
    /// the user's back first.
    paced: bool,
    /// The user's speed setting as TROL knows it: set by Speed, else STATUS's while no
    /// waypoint's is in force.
    speed_setting: Option<u8>,
    deferred: Option<BackendError>,
    /// A motion line whose answer comes at the motion's end is being read (`motion_ack =
    /// "end"`): the controller's interpreter is busy until then.
    awaiting: Option<String>,
    /// FINISH was typed and its answer is being read (`completion = "finish"`).
    finishing: bool,
    /// FINISH was refused as a command this controller does not take: not tried again.
    finish_off: bool,
    unasked: String,
    scratch: usize,
    log: VecDeque<String>,
    log_fn: Option<LogFn>,
    transcript: Option<Recorder>,
    status: Option<text::Status>,
    /// What was seen of the arm and may stand in for a read (issue 43).
    seen: Seen,
    closed: bool,
}

/// How long what was seen of the arm stands in for a read before a motion (issue 43; the rule
/// is [`real::Recent`]'s, shared by every real controller). On a C500: a STATUS that showed it
/// idle, and where the motion before ended. Reads are STATUS, W0, W2 and the other lines of
/// [`crate::probe::READ_ONLY`]; any other line, any byte unasked, Ctrl-C or a failure forgets
/// it. A motion sent on it that the controller refuses (arm power lost meanwhile, the pendant
/// holding control) is refused by its own reply, read as every motion's is.
pub use trol_controller::real::SEEN_FOR;

/// What the backend saw of the arm (see [`SEEN_FOR`]).
#[derive(Clone, Debug, Default)]
struct Seen {
    /// A STATUS that showed every axis DONE, powered and homed, with no motion of ours
    /// under way (its end confirmed).
    idle: real::Recent<text::Status>,
    /// Where the last motion ended as commanded (its joints, degrees), its arrival confirmed
    /// by W2: what W0 would read.
    end: real::Recent<[f64; 6]>,
}

const LOG_KEEP: usize = 200;

impl RaplBackend {
    /// Open a session on `port` as `profile` says: the ACI steps (falling back to Ctrl-C if
    /// the port is in terminal mode already), NOHELP, STATUS.
    pub fn connect(port: Box<dyn Port>, profile: Profile) -> Result<RaplBackend, RaplError> {
        RaplBackend::connect_with(port, profile, None, None)
    }

    /// Like [`RaplBackend::connect`], logging each line to `log_fn` and, with `record`,
    /// adding every byte to the transcript (kept by the caller, so it is there even when
    /// the opening fails).
    pub fn connect_with(
        port: Box<dyn Port>,
        profile: Profile,
        log_fn: Option<LogFn>,
        record: Option<Recorder>,
    ) -> Result<RaplBackend, RaplError> {
        let mut b = RaplBackend {
            port,
            session: Session::new(SessionConfig::from(&profile)),
            joint_units: profile.joint_units().ok().flatten(),
            frames: Frames::of(&profile),
            forms: profile.refusal_forms(),
            ack: profile.ack == Ack::Required,
            profile,
            epoch: std::time::Instant::now(),
            tool: [0.0; 6],
            last_poll: None,
            gripping: false,
            outstanding: None,
            rest: None,
            queue: real::MotionQueue::new(QUEUE),
            pacing: None,
            paced: false,
            speed_setting: None,
            deferred: None,
            awaiting: None,
            finishing: false,
            finish_off: false,
            unasked: String::new(),
            scratch: 0,
            log: VecDeque::new(),
            log_fn,
            transcript: record,
            status: None,
            seen: Seen::default(),
            closed: false,
        };
        if let Err(e) = b.open() {
            b.note(format!("opening failed: {e}"));
            b.closed = true;
            return Err(e);
        }
        Ok(b)
    }
}

/// The lines of a reply's text, trimmed, without blank ones (NULs and spaces a controller
/// sends after a number count as blank).
fn lines(text: &str) -> Vec<String> {
    text.split(['\r', '\n'])
        .map(|l| l.trim_matches(|c: char| c.is_whitespace() || c == '\0'))
        .filter(|l| !l.is_empty())
        .map(str::to_string)
        .collect()
}

fn no_echo(e: SessionError) -> RaplError {
    match e {
        e @ SessionError::EchoTimeout { at: 0, .. } => RaplError::NoEcho(e),
        e => RaplError::Session(e),
    }
}

impl Drop for RaplBackend {
    fn drop(&mut self) {
        self.close();
    }
}

/// A failure of a line that cannot move the arm: the motion it prepared was not sent.
fn not_run(e: BackendError) -> BackendError {
    match e {
        BackendError::Unsure(t) => BackendError::Link(t),
        e => e,
    }
}

fn link(e: &io::Error) -> BackendError {
    BackendError::Link(e.to_string())
}

fn code_of(name: &str) -> i16 {
    RAPL_CODES
        .iter()
        .find(|c| c.name == name)
        .map(|c| c.value)
        .unwrap_or(RAPL_ERROR)
}

fn mv(straight: bool) -> &'static str {
    if straight { "MOVES" } else { "MOVE" }
}

fn join(v: &[f64]) -> String {
    v.iter()
        .map(|x| text::num(*x))
        .collect::<Vec<_>>()
        .join(",")
}

fn join_int(v: &[i64]) -> String {
    v.iter()
        .map(|x| x.to_string())
        .collect::<Vec<_>>()
        .join(",")
}

impl std::fmt::Debug for RaplBackend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RaplBackend")
            .field("port", &self.port.name())
            .finish_non_exhaustive()
    }
}

#[cfg(test)]
mod tests;

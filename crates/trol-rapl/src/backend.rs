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

/// The BIOS codes of the RAPL-II backend: the simulator's, and those of a real controller.
pub static RAPL_CODES: &CodeTable = &{
    const EXTRA: [CodeInfo; 10] = [
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
            value: BUSY,
            name: "BIOS_BUSY",
            meaning: "a tool change while a motion has not ended (it would change what a \
                      queued motion's target means): call TROLFinish(FINISH_WAIT) first",
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
    since: std::time::Instant,
    seen_moving: bool,
    still: Option<(std::time::Instant, [f64; 6])>,
    /// Since when W2 has read the arm within [`STILL_DEG`] of one place, and that place.
    standing: Option<(std::time::Instant, [f64; 6])>,
    /// W2 has read the arm in two places since the motion was sent.
    w2_moved: bool,
    /// Where W2 last saw the arm at rest before the motion was sent (the end of the one
    /// before), if it did.
    from: Option<[f64; 6]>,
    /// FINISH was answered for it without settling its end (`completion = "finish"`): its
    /// end is looked for by STATUS.
    finish_tried: bool,
}

impl Outstanding {
    fn new(motion: Motion, seen_moving: bool, from: Option<[f64; 6]>) -> Outstanding {
        Outstanding {
            motion,
            since: std::time::Instant::now(),
            seen_moving,
            still: None,
            standing: None,
            w2_moved: false,
            from,
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

/// How a motion may go now.
enum Gate {
    /// Refused before anything was sent, with this code.
    Refuse(i16),
    /// The arm stands: send it.
    Idle,
    /// A motion runs or waits: queue it.
    Busy,
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

/// One of the C500's stops (docs/c500.md, "Halt").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stop {
    Halt,
    Abort,
    CtrlC,
}

impl Stop {
    fn word(self) -> &'static str {
        match self {
            Stop::Halt => "HALT",
            Stop::Abort => "ABORT",
            Stop::CtrlC => "Ctrl-C",
        }
    }
}

/// The C500's side of the shared Halt ([`trol_controller::real`]): its stops, W2's JOINTS
/// row (degrees) as the reading.
struct Stopper<'a>(&'a mut RaplBackend);

impl real::Stopping for Stopper<'_> {
    type Stop = Stop;
    fn stop_name(&self, stop: Stop) -> String {
        stop.word().into()
    }
    fn send_stop(&mut self, stop: Stop) -> Result<String, String> {
        let b = &mut *self.0;
        match stop {
            Stop::CtrlC => {
                b.awaiting = None;
                b.interrupt()
                    .map(|_| "prompt back".to_string())
                    .map_err(|e| e.to_string())
            }
            Stop::Halt | Stop::Abort => match b.command_as(stop.word(), true) {
                Ok(0) => Ok("acknowledged".into()),
                Ok(c) => Ok(format!("refused, {c}")),
                Err(e) => Err(e.to_string()),
            },
        }
    }
    fn reading(&mut self) -> Result<Option<[f64; 6]>, String> {
        self.0
            .read_position(PosMode::Actual)
            .map(|p| Some(p.joints))
            .map_err(|e| format!("W2: {e}"))
    }
    fn still_within(&self) -> [f64; 6] {
        [real::STILL_DEG; 6]
    }
    fn now(&self) -> std::time::Instant {
        std::time::Instant::now()
    }
    fn pause(&mut self, d: Duration) {
        std::thread::sleep(d);
    }
}

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
    outstanding: Option<Outstanding>,
    /// Where W2 last saw the arm at rest (a motion's confirmed end, a Halt's stop).
    rest: Option<[f64; 6]>,
    queue: VecDeque<Queued>,
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
    /// How long it may ([`SEEN_FOR`]).
    seen_for: Duration,
    closed: bool,
}

/// How long what was seen of the arm stands in for a read before a motion (issue 43): a
/// STATUS that showed it idle, and where the motion before ended. Only while nothing but
/// reads (STATUS, W0, W2, ...) went to the controller since, and nothing came unasked: any
/// other line, any byte unasked, Ctrl-C or a failure forgets it. A motion sent on it that
/// the controller refuses (arm power lost meanwhile, the pendant holding control) is
/// refused by its own reply, read as every motion's is. 250 ms: about as old as a STATUS
/// read before the motion is by the time the motion is typed (its 638 bytes take 166 ms at
/// 38400 Bd), so the arm's state is not trusted for longer than before; a program's next
/// motion after Finish comes within a few milliseconds.
pub const SEEN_FOR: Duration = Duration::from_millis(250);

/// What the backend saw of the arm, each with when (see [`SEEN_FOR`]).
#[derive(Clone, Debug, Default)]
struct Seen {
    /// A STATUS that showed every axis DONE, powered and homed, with no motion of ours
    /// under way (its end confirmed).
    idle: Option<(std::time::Instant, text::Status)>,
    /// Where the last motion ended as commanded (its joints, degrees), its arrival confirmed
    /// by W2: what W0 would read.
    end: Option<(std::time::Instant, [f64; 6])>,
}

impl Seen {
    fn idle(&self, within: Duration) -> Option<&text::Status> {
        self.idle
            .as_ref()
            .filter(|(t, _)| t.elapsed() <= within)
            .map(|(_, s)| s)
    }

    fn end(&self, within: Duration) -> Option<[f64; 6]> {
        self.end
            .filter(|(t, _)| t.elapsed() <= within)
            .map(|(_, q)| q)
    }
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
            outstanding: None,
            rest: None,
            queue: VecDeque::new(),
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
            seen_for: SEEN_FOR,
            closed: false,
        };
        if let Err(e) = b.open() {
            b.note(format!("opening failed: {e}"));
            b.closed = true;
            return Err(e);
        }
        Ok(b)
    }

    /// Forget what was seen of the arm: a line that is not a read went out, something came
    /// unasked, or something failed.
    fn forget(&mut self) {
        self.seen = Seen::default();
    }

    /// Whether `line` only reads (cannot move the arm or change what it does).
    fn only_reads(line: &str) -> bool {
        let word = line.split_whitespace().next().unwrap_or("");
        crate::probe::READ_ONLY
            .iter()
            .any(|k| k.eq_ignore_ascii_case(word))
    }

    fn note(&mut self, line: String) {
        if let Some(f) = self.log_fn.as_mut() {
            f(&line);
        }
        if self.log.len() == LOG_KEEP {
            self.log.pop_front();
        }
        self.log.push_back(line);
    }

    /// The last lines of the log (refusals with the controller's text, resynchronisations).
    pub fn log_lines(&self) -> Vec<String> {
        self.log.iter().cloned().collect()
    }

    /// The transcript so far, when recording.
    pub fn transcript(&self) -> Option<Transcript> {
        self.transcript
            .as_ref()
            .map(|t| t.lock().map(|t| t.clone()).unwrap_or_default())
    }

    /// The profile the session was opened with.
    pub fn profile(&self) -> &Profile {
        &self.profile
    }

    /// Whether this controller answers a successful command with ACK (the profile's `ack`,
    /// or what NOHELP's answer showed with `ack = "auto"`).
    pub fn expects_ack(&self) -> bool {
        self.ack
    }

    /// How long what was seen of the arm stands in for a read before a motion ([`SEEN_FOR`]
    /// by default; zero: a read before every motion). For tests, and for a cautious
    /// application.
    pub fn set_seen_for(&mut self, d: Duration) {
        self.seen_for = d;
    }

    /// Type a line that cannot move the arm (its keyword is one of
    /// [`crate::probe::READ_ONLY`]) and read its reply; any other line is refused unsent.
    pub fn read_only(&mut self, line: &str) -> Result<Reply, BackendError> {
        let word = line.split_whitespace().next().unwrap_or("");
        if !crate::probe::READ_ONLY
            .iter()
            .any(|k| k.eq_ignore_ascii_case(word))
        {
            return Err(BackendError::Link(format!(
                "`{line}` is not one of the commands that cannot move the arm ({}); not sent",
                crate::probe::READ_ONLY.join(", ")
            )));
        }
        let t = self.reply_timeout();
        self.exchange(line, t)
    }

    /// Type any line, as a terminal would (`trol rapl term`), and read its reply within
    /// `timeout`. The line is checked like every other: typed byte by byte, each echo
    /// checked, and cancelled with Ctrl-C before its terminator if an echo differs.
    pub fn type_line(&mut self, line: &str, timeout: Duration) -> Result<Reply, BackendError> {
        self.last_poll = None;
        self.exchange(line, timeout)
    }

    /// Like [`RaplBackend::type_line`], stopped when `stop` is set (Ctrl-C in `trol rapl
    /// term`): the line is cancelled with Ctrl-C and the arm halted as the profile says; the
    /// answer is then UNSURE (the line may have run) with what was done.
    pub fn type_line_unless(
        &mut self,
        line: &str,
        timeout: Duration,
        stop: &std::sync::atomic::AtomicBool,
    ) -> Result<Reply, BackendError> {
        self.last_poll = None;
        self.forget();
        self.settle()?;
        let now = self.now();
        self.session
            .send_line(line, timeout, now)
            .map_err(|e| BackendError::Link(e.to_string()))?;
        match self.pump_unless(Some(stop)) {
            Ok(Some(Ok(r))) => Ok(r),
            Ok(Some(Err(e))) => Err(if e.surely_not_run() {
                BackendError::Link(e.to_string())
            } else {
                BackendError::Unsure(e.to_string())
            }),
            Ok(None) => {
                let cancelled = self.interrupt();
                let halted = self.halt();
                Err(BackendError::Unsure(format!(
                    "`{line}` interrupted: Ctrl-C sent ({}), then the halt ({})",
                    match cancelled {
                        Ok(()) => "prompt back".to_string(),
                        Err(e) => e.to_string(),
                    },
                    match halted {
                        Ok(0) => "done".to_string(),
                        Ok(c) => format!("refused, {c}"),
                        Err(e) => e.to_string(),
                    }
                )))
            }
            Err(e) => Err(BackendError::Unsure(format!("`{line}`: {e}"))),
        }
    }

    /// Ctrl-C, as a terminal's user presses it: the line is cancelled and the controller's
    /// prompt awaited (on a controller whose halt is Ctrl-C, this stops the arm).
    pub fn interrupt(&mut self) -> Result<(), BackendError> {
        self.ctrl_c().map(drop)
    }

    /// Ctrl-C, and what came back up to the prompt.
    fn ctrl_c(&mut self) -> Result<String, BackendError> {
        self.forget();
        let now = self.now();
        self.session.resync(now);
        match self.pump() {
            Ok(Ok(r)) => Ok(r.text),
            Ok(Err(e)) => Err(BackendError::Unsure(e.to_string())),
            Err(e) => Err(BackendError::Unsure(e.to_string())),
        }
    }

    /// The refusal in `reply`, if one of its lines has one of the profile's forms.
    pub fn refusal(&self, reply: &Reply) -> Option<(u16, String)> {
        lines(&reply.text)
            .into_iter()
            .find_map(|l| self.forms.iter().find_map(|f| f.read(&l)))
    }

    /// STATUS as read at the opening.
    pub fn opening_status(&self) -> Option<&text::Status> {
        self.status.as_ref()
    }

    fn now(&self) -> Instant {
        Instant::from_duration(self.epoch.elapsed())
    }

    fn secs(&self) -> f64 {
        self.epoch.elapsed().as_secs_f64()
    }

    fn record(&self, dir: Dir, bytes: &[u8]) {
        if let Some(tr) = self.transcript.as_ref() {
            if let Ok(mut tr) = tr.lock() {
                tr.add(self.secs(), dir, bytes);
            }
        }
    }

    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.record(Dir::ToController, bytes);
        self.port.send(bytes)
    }

    fn recv(&mut self, until: std::time::Instant) -> io::Result<Vec<u8>> {
        let mut buf = [0u8; 512];
        let n = self.port.recv(&mut buf, until)?;
        if n > 0 {
            self.record(Dir::FromController, &buf[..n]);
        }
        Ok(buf[..n].to_vec())
    }

    fn at(&self, t: Instant) -> std::time::Instant {
        self.epoch + t.since_epoch()
    }

    /// Run the session until its next event.
    fn pump(&mut self) -> io::Result<Result<Reply, SessionError>> {
        Ok(self
            .pump_until(None, None)?
            .expect("without a stop flag or a limit, pumping ends in an event"))
    }

    /// Run the session until its next event, or until `stop` is set (None).
    fn pump_unless(
        &mut self,
        stop: Option<&std::sync::atomic::AtomicBool>,
    ) -> io::Result<Option<Result<Reply, SessionError>>> {
        self.pump_until(stop, None)
    }

    /// Run the session until its next event, `stop` is set, or `until` has come while a
    /// reply is being read (None).
    fn pump_until(
        &mut self,
        stop: Option<&std::sync::atomic::AtomicBool>,
        until: Option<std::time::Instant>,
    ) -> io::Result<Option<Result<Reply, SessionError>>> {
        loop {
            if stop.is_some_and(|s| s.load(std::sync::atomic::Ordering::SeqCst)) {
                return Ok(None);
            }
            if until.is_some_and(|u| std::time::Instant::now() >= u) && self.session.is_reading() {
                return Ok(None);
            }
            let now = self.now();
            while let Some(b) = self.session.poll_transmit(now) {
                self.send(&[b])?;
            }
            let expired = self.session.take_xoff_expired();
            if expired > 0 {
                self.note(format!(
                    "the C500 said XOFF and no XON followed within {} ms: typing went on",
                    crate::session::XOFF_LIMIT.as_millis()
                ));
            }
            if let Some(ev) = self.session.poll_event() {
                return Ok(Some(ev));
            }
            let wake = self
                .session
                .next_timeout()
                .map(|t| self.at(t))
                .unwrap_or_else(|| std::time::Instant::now() + Duration::from_millis(50))
                .min(std::time::Instant::now() + Duration::from_millis(50));
            let wake = until.map_or(wake, |u| wake.min(u.max(std::time::Instant::now())));
            let got = self.recv(wake)?;
            let now = self.now();
            if !got.is_empty() {
                self.session.feed(&got, now);
            }
            self.session.handle_timeout(now);
            if self.session.is_lost() {
                if let Some(ev) = self.session.poll_event() {
                    return Ok(Some(ev));
                }
            }
        }
    }

    /// Take in what arrived unasked: a line of text is kept (the next call reports it); any
    /// byte at all, or a lost session, makes the next command resynchronise first.
    fn settle(&mut self) -> Result<(), BackendError> {
        while self.port.available().map_err(|e| link(&e))? > 0 {
            let got = self.recv(std::time::Instant::now()).map_err(|e| link(&e))?;
            let now = self.now();
            self.session.feed(&got, now);
        }
        let stray = self.session.take_stray();
        if !stray.is_empty() || self.session.is_lost() {
            self.forget();
            if !stray.is_empty() {
                let text = String::from_utf8_lossy(&stray).into_owned();
                let said = lines(&text)
                    .into_iter()
                    .filter(|l| !l.ends_with(">>") && !l.ends_with("O>"))
                    .collect::<Vec<_>>()
                    .join(" / ");
                self.note(format!("the C500 sent unasked: {text:?}; resynchronising"));
                if !said.is_empty() {
                    if !self.unasked.is_empty() {
                        self.unasked.push_str(" / ");
                    }
                    self.unasked.push_str(&said);
                }
            }
            let now = self.now();
            self.session.resync(now);
            match self.pump().map_err(|e| link(&e))? {
                Ok(_) => {}
                Err(e) => {
                    self.note(format!("resynchronisation failed: {e}"));
                    return Err(BackendError::Link(e.to_string()));
                }
            }
        }
        Ok(())
    }

    /// Keep the lines that came in a resynchronisation after a surprise (an e-stop's line
    /// can break the echo of the next command), but not the echo of `typed`, nor prompts.
    fn keep_unasked(&mut self, typed: &str) {
        let got = self.session.take_resync_text();
        let text = String::from_utf8_lossy(&got).into_owned();
        let typed = typed.trim();
        let said: Vec<String> = lines(&text)
            .into_iter()
            .map(|l| {
                l.trim_end_matches(">>")
                    .trim_end_matches("O>")
                    .trim()
                    .to_string()
            })
            .filter(|l| {
                !l.is_empty()
                    && l.bytes().any(|b| b.is_ascii_alphanumeric())
                    && !typed.starts_with(l.as_str())
            })
            .collect();
        if !said.is_empty() {
            self.forget();
            self.note(format!(
                "the C500 said, while a line was typed: {}",
                said.join(" / ")
            ));
            if !self.unasked.is_empty() {
                self.unasked.push_str(" / ");
            }
            self.unasked.push_str(&said.join(" / "));
        }
    }

    /// A line the controller printed unasked, reported once: a refusal form the profile maps
    /// gives its code; anything else is UNSURE with the text. A motion of ours that was under
    /// way or queued is given up (the queue is dropped: nothing more is sent after it).
    fn report_unasked(&mut self) -> Result<(), BackendError> {
        self.settle()?;
        if self.unasked.is_empty() {
            return Ok(());
        }
        let text = std::mem::take(&mut self.unasked);
        self.forget();
        self.outstanding = None;
        let dropped = self.queue.len();
        self.queue.clear();
        let known = lines(&text)
            .into_iter()
            .find_map(|l| self.forms.iter().find_map(|f| f.read(&l)));
        let tail = if dropped > 0 {
            format!("; {dropped} queued motion(s) dropped, not sent")
        } else {
            String::new()
        };
        self.note(format!("the C500 said unasked: {text}{tail}"));
        match known {
            Some((n, _)) if n > 0 => match self.meaning(n) {
                Meaning::Code(c) => Err(BackendError::Refused(c)),
                Meaning::Location => Err(BackendError::Refused(RAPL_ERROR)),
            },
            _ => Err(BackendError::Unsure(format!(
                "the C500 said unasked: {text}{tail}"
            ))),
        }
    }

    /// Type a line and read its reply.
    fn exchange(&mut self, line: &str, timeout: Duration) -> Result<Reply, BackendError> {
        self.exchange_as(line, timeout, false)
    }

    fn exchange_as(
        &mut self,
        line: &str,
        timeout: Duration,
        urgent: bool,
    ) -> Result<Reply, BackendError> {
        if self.closed {
            return Err(BackendError::Link(format!(
                "`{line}` not sent: the RAPL-II session is closed"
            )));
        }
        self.release()?;
        if let Some(motion) = &self.awaiting {
            return Err(BackendError::Link(format!(
                "`{line}` not sent: this controller answers `{motion}` only at the motion's end \
                 (motion_ack = \"end\"), and its interpreter takes nothing before: call \
                 TROLFinish(FINISH_WAIT) first"
            )));
        }
        if !Self::only_reads(line) {
            self.forget();
        }
        self.settle()?;
        let now = self.now();
        let started = if urgent {
            self.session.send_urgent(line, timeout, now)
        } else {
            self.session.send_line(line, timeout, now)
        };
        if let Err(e) = started {
            self.forget();
            self.note(format!("`{line}` not sent: {e}"));
            return Err(BackendError::Link(e.to_string()));
        }
        match self.pump() {
            Ok(Ok(r)) => Ok(r),
            Ok(Err(e)) => {
                self.forget();
                self.note(format!("`{line}`: {e}"));
                self.keep_unasked(&format!("{line}\r"));
                Err(if e.surely_not_run() {
                    BackendError::Link(e.to_string())
                } else {
                    BackendError::Unsure(e.to_string())
                })
            }
            Err(e) => {
                self.forget();
                Err(BackendError::Unsure(format!("`{line}`: {e}")))
            }
        }
    }

    /// How the reply to `line` reads. `output`: the command prints text (its parser checks
    /// it); otherwise any text at all is not the success form.
    fn answer(&mut self, line: &str, r: Reply, output: bool) -> Result<Answer, BackendError> {
        let refused = self.refusal(&r);
        let printed = lines(&r.text).join(" / ");
        if refused.is_some() || (self.ack && !r.ack) || (!output && !printed.is_empty()) {
            self.forget();
        }
        if let Some((n, t)) = refused {
            if r.ack {
                let e = format!(
                    "`{line}`: the C500 printed `{printed}` and then ACK: whether it ran is not \
                     known, so nothing further was sent"
                );
                self.note(e.clone());
                return Err(BackendError::Unsure(e));
            }
            self.note(format!("`{line}` refused: {printed}"));
            return Ok(Answer::Refused(n, t));
        }
        if self.ack && !r.ack {
            let e = format!(
                "`{line}`: answered without the ACK this controller gives on success{}; whether \
                 it ran is not known, so nothing further was sent (a controller that sends no \
                 ACK: ack = \"never\" in the profile)",
                if printed.is_empty() {
                    String::new()
                } else {
                    format!(" (it printed `{printed}`)")
                }
            );
            self.note(e.clone());
            return Err(BackendError::Unsure(e));
        }
        if !output && !printed.is_empty() {
            let e = format!(
                "`{line}`: the C500 printed `{printed}`, which is neither its success form nor \
                 one of the profile's refusal forms; whether it ran is not known, so nothing \
                 further was sent (if it is a refusal, add its form to `refusal` in the profile)"
            );
            self.note(e.clone());
            return Err(BackendError::Unsure(e));
        }
        Ok(Answer::Done(r))
    }

    /// A command whose output is parsed (STATUS, W0, W2, LISTL): a refusal is a failure
    /// of the line (these commands change nothing).
    fn output(&mut self, line: &str) -> Result<Reply, BackendError> {
        let t = self.reply_timeout();
        // These lines change nothing: a failure leaves no doubt about the arm.
        let r = self.exchange(line, t).map_err(not_run)?;
        match self.answer(line, r, true)? {
            Answer::Done(r) => Ok(r),
            Answer::Refused(n, t) => Err(BackendError::Link(format!(
                "`{line}` was refused: {n:03}-{t}"
            ))),
        }
    }

    fn reply_timeout(&self) -> Duration {
        Duration::from_millis(self.profile.reply_timeout_ms)
    }

    fn motion_timeout(&self) -> Duration {
        Duration::from_secs(self.profile.motion_timeout_s)
    }

    /// The BIOS code of a refusal numbered `number` (a location the controller does not
    /// know, after LISTL found it, is a bad argument).
    fn code_of_refusal(&self, number: u16) -> i16 {
        match self.meaning(number) {
            Meaning::Code(c) => c,
            Meaning::Location => code_of("BIOS_BAD_ARGUMENT"),
        }
    }

    fn meaning(&self, number: u16) -> Meaning {
        match self.profile.error_target(number) {
            Some("TROL_ERR_LOCATION") => Meaning::Location,
            Some(name) => Meaning::Code(code_of(name)),
            None => Meaning::Code(RAPL_ERROR),
        }
    }

    /// A command whose answer is the success form or a refusal. Its timeout is the short
    /// one: nothing here waits for a motion's end (a name is looked up with LISTL before).
    fn command(&mut self, line: &str) -> BiosResult {
        self.command_as(line, false)
    }

    fn command_as(&mut self, line: &str, urgent: bool) -> BiosResult {
        let t = self.reply_timeout();
        let r = self.exchange_as(line, t, urgent)?;
        match self.answer(line, r, false)? {
            Answer::Done(_) => Ok(0),
            Answer::Refused(n, _) => Ok(self.code_of_refusal(n)),
        }
    }

    fn read_status(&mut self) -> Result<text::Status, BackendError> {
        let r = self.output("STATUS")?;
        let s = text::read_status(&r.text).map_err(BackendError::Link)?;
        self.status = Some(s.clone());
        let idle =
            s.done.iter().all(|d| *d) && s.homed.iter().all(|h| *h) && !s.limp.iter().any(|l| *l);
        self.seen.idle = idle.then(|| (std::time::Instant::now(), s.clone()));
        Ok(s)
    }

    /// Whether a motion may be sent now: power and homing checked, and whether the arm is
    /// busy (a motion of ours not seen to end, a queue, or the DONE row).
    fn gate(&mut self, homing: bool) -> Result<Gate, BackendError> {
        self.release()?;
        // A controller that answers a motion at its end takes nothing before: the next motion
        // waits in the queue for that answer, as the controller itself would, and the call
        // returns at once (a request that waited for the motion's end would outlast the
        // host's reply timeout; Halt and Finish get through meanwhile).
        if self.awaiting.is_some() && self.await_end()? {
            return Ok(Gate::Busy);
        }
        self.report_unasked()?;
        if let Some(e) = self.deferred.take() {
            return Err(e);
        }
        // Idle as seen a moment ago, with nothing but reads since: no read needed (issue 43).
        let seen = (self.outstanding.is_none()
            && self.queue.is_empty()
            && self.awaiting.is_none()
            && !self.finishing)
            .then(|| self.seen.idle(self.seen_for).cloned())
            .flatten();
        let (moving, st) = match seen {
            Some(st) => (false, st),
            None => {
                let moving = self.poll()?;
                let st = self.status.clone().ok_or_else(|| {
                    BackendError::Link("STATUS could not be read before the motion".into())
                })?;
                (moving, st)
            }
        };
        if st.limp.iter().any(|l| *l) {
            self.note(
                "refused before sending: STATUS says the arm has no power (LIMP): restore arm \
                 power at the controller"
                    .into(),
            );
            return Ok(Gate::Refuse(ARM_POWER));
        }
        if !homing && !st.homed.iter().all(|h| *h) {
            self.note(
                "refused before sending: STATUS says the arm is not homed: call TROLHome(0) \
                 (with the arm near its home position)"
                    .into(),
            );
            return Ok(Gate::Refuse(sim_code::NOT_HOMED));
        }
        Ok(if moving || !self.queue.is_empty() {
            Gate::Busy
        } else {
            Gate::Idle
        })
    }

    /// Send a motion now or queue it behind the one under way.
    fn submit(&mut self, m: Motion, busy: bool) -> BiosResult {
        if busy {
            if self.queue.len() >= QUEUE {
                self.note(format!(
                    "`{}` refused: {QUEUE} motions wait already",
                    m.line
                ));
                return Ok(sim_code::QUEUE_FULL);
            }
            self.note(format!(
                "`{}` waits for the motion under way to end",
                m.line
            ));
            self.queue.push_back(Queued::Motion(m));
            return Ok(0);
        }
        self.launch(m)
    }

    /// A motion line whose end is computed from where the arm stands (JOINT, MI, JOG): now,
    /// or when its turn comes ([`RaplBackend::relative`]); `end` gives its end from there.
    fn relative_line(
        &mut self,
        line: String,
        busy: bool,
        end: impl FnOnce(&text::Position) -> Expect + Send + 'static,
    ) -> BiosResult {
        self.relative(
            line.clone(),
            busy,
            Box::new(move |b| {
                let p = match b.standing()? {
                    Ok(p) => p,
                    Err(c) => return Ok(c),
                };
                let expect = end(&p);
                b.submit(Motion { line, expect }, false)
            }),
        )
    }

    /// A joint motion relative to where the arm stands (JOINT, MI): as
    /// [`RaplBackend::relative_line`], from the end of the motion before where that was seen
    /// a moment ago (no W0 read), else from W0; `end` gives its end (joints, degrees).
    fn relative_joints(
        &mut self,
        line: String,
        busy: bool,
        end: impl FnOnce([f64; 6]) -> [f64; 6] + Send + 'static,
    ) -> BiosResult {
        self.relative(
            line.clone(),
            busy,
            Box::new(move |b| {
                let q = match b.standing_joints()? {
                    Ok(q) => q,
                    Err(c) => return Ok(c),
                };
                let expect = Expect::Joints(end(q));
                b.submit(Motion { line, expect }, false)
            }),
        )
    }

    /// A relative motion: now, computed from where the arm stands, when it stands; queued
    /// and computed when its turn comes while another runs. `what` names it in the log.
    fn relative(&mut self, what: String, busy: bool, now: Later) -> BiosResult {
        if !busy {
            return now(self);
        }
        if self.queue.len() >= QUEUE {
            self.note(format!("`{what}` refused: {QUEUE} motions wait already"));
            return Ok(sim_code::QUEUE_FULL);
        }
        self.note(format!(
            "`{what}` waits for the motion under way to end; it is computed from where that \
             one ends"
        ));
        self.queue.push_back(Queued::Later(what, now));
        Ok(0)
    }

    /// Type a motion line; on the success form it is under way.
    fn launch(&mut self, m: Motion) -> BiosResult {
        self.last_poll = None;
        if self.profile.motion_ack == MotionAck::End {
            return self.launch_answered_at_end(m);
        }
        match self.command(&m.line) {
            Ok(0) => {
                self.outstanding = Some(Outstanding::new(m, false, self.rest));
                Ok(0)
            }
            other => {
                if !self.queue.is_empty() {
                    self.note(format!(
                        "{} queued motion(s) dropped after `{}` failed: not sent",
                        self.queue.len(),
                        m.line
                    ));
                    self.queue.clear();
                }
                other
            }
        }
    }

    /// A motion on a controller that answers at the motion's end: typed whole (every echo
    /// checked), then a refusal has the reply window to come; without one the motion runs,
    /// and its answer is read by [`RaplBackend::poll`].
    fn launch_answered_at_end(&mut self, m: Motion) -> BiosResult {
        self.forget();
        self.settle()?;
        let now = self.now();
        self.session
            .send_line(&m.line, self.motion_timeout(), now)
            .map_err(|e| BackendError::Link(e.to_string()))?;
        let window = std::time::Instant::now() + self.reply_timeout().min(Duration::from_secs(1));
        match self.pump_until(None, Some(window)) {
            Ok(Some(Ok(r))) => {
                // Answered within the window: a refusal, or a motion that already ended.
                match self.answer(&m.line, r, false)? {
                    Answer::Refused(n, _) => {
                        self.queue.clear();
                        Ok(self.code_of_refusal(n))
                    }
                    Answer::Done(_) => {
                        self.outstanding = Some(Outstanding::new(m, true, self.rest));
                        Ok(0)
                    }
                }
            }
            Ok(Some(Err(e))) => {
                self.note(format!("`{}`: {e}", m.line));
                self.queue.clear();
                Err(if e.surely_not_run() {
                    BackendError::Link(e.to_string())
                } else {
                    BackendError::Unsure(e.to_string())
                })
            }
            Ok(None) => {
                self.note(format!(
                    "`{}` taken, no refusal within the reply window: under way (its answer \
                     comes at its end)",
                    m.line
                ));
                self.awaiting = Some(m.line.clone());
                self.outstanding = Some(Outstanding::new(m, true, self.rest));
                Ok(0)
            }
            Err(e) => Err(BackendError::Unsure(format!("`{}`: {e}", m.line))),
        }
    }

    /// The answer of a motion that answers at its end: still running (true), ended in its
    /// success form (false), or its refusal or failure.
    fn await_end(&mut self) -> Result<bool, BackendError> {
        let Some(line) = self.awaiting.clone() else {
            return Ok(false);
        };
        let until = std::time::Instant::now() + Duration::from_millis(self.profile.poll_ms);
        let ev = self
            .pump_until(None, Some(until))
            .map_err(|e| BackendError::Unsure(format!("`{line}`: {e}")))?;
        let Some(ev) = ev else {
            if self.past_motion_timeout() {
                self.awaiting = None;
                self.outstanding = None;
                self.queue.clear();
                let _ = self.interrupt();
                return Err(BackendError::Unsure(format!(
                    "`{line}` was not answered within motion_timeout_s ({} s): Ctrl-C sent; \
                     whether it ran to its end is not known",
                    self.profile.motion_timeout_s
                )));
            }
            return Ok(true);
        };
        self.awaiting = None;
        match ev {
            Ok(r) => match self.answer(&line, r, false) {
                Ok(Answer::Done(_)) => Ok(false),
                Ok(Answer::Refused(n, t)) => {
                    self.outstanding = None;
                    self.queue.clear();
                    self.note(format!("`{line}` ended in a refusal: {n:03}-{t}"));
                    Err(BackendError::Refused(match self.meaning(n) {
                        Meaning::Code(c) => c,
                        Meaning::Location => RAPL_ERROR,
                    }))
                }
                Err(e) => {
                    self.outstanding = None;
                    self.queue.clear();
                    Err(e)
                }
            },
            Err(e) => {
                self.outstanding = None;
                self.queue.clear();
                Err(BackendError::Unsure(format!("`{line}`: {e}")))
            }
        }
    }

    /// One look at the arm: STATUS, and W2 when the controller says done while a motion of
    /// ours is under way; starts the next queued motion once the last has ended. Whether
    /// anything still moves.
    fn poll(&mut self) -> Result<bool, BackendError> {
        let r = if self.finishing {
            self.await_finish()
        } else {
            self.poll_status()
        };
        if r.is_err() {
            self.forget();
        }
        r
    }

    /// One look at the arm by STATUS (and W2), as [`RaplBackend::poll`] describes.
    fn poll_status(&mut self) -> Result<bool, BackendError> {
        if self.await_end()? {
            return Ok(true);
        }
        self.report_unasked()?;
        let st = match self.profile.completion {
            Completion::W5 if self.outstanding.is_none() && self.queue.is_empty() => {
                // W5 alone: velocities.
                let r = self.output("W5")?;
                let v = text::row(&r.text, "JOINTS").map_err(BackendError::Link)?;
                let st = self.read_status()?;
                if v.iter().any(|x| x.abs() > 1e-6) {
                    return Ok(true);
                }
                st
            }
            _ => match self.read_status() {
                Ok(st) => st,
                // A read that met a surprise (an unasked line) and resynchronised: what the
                // controller said is told first, then one more look.
                Err(BackendError::Link(e)) => {
                    self.note(format!("STATUS read again after: {e}"));
                    self.report_unasked()?;
                    self.read_status()?
                }
                Err(e) => return Err(e),
            },
        };
        if st.limp.iter().any(|l| *l) {
            let ours = self.outstanding.take();
            let dropped = std::mem::take(&mut self.queue);
            if ours.is_some() || !dropped.is_empty() {
                self.note(format!(
                    "the arm lost power (STATUS's LIMP row says Y){}{}",
                    ours.map(|o| format!(" during `{}`", o.motion.line))
                        .unwrap_or_default(),
                    if dropped.is_empty() {
                        String::new()
                    } else {
                        format!("; {} queued motion(s) dropped, not sent", dropped.len())
                    }
                ));
                return Err(BackendError::Refused(ARM_POWER));
            }
            return Ok(false);
        }
        let done = st.done.iter().all(|d| *d);
        let Some(o) = self.outstanding.as_mut() else {
            if done {
                return self.next_in_queue();
            }
            return Ok(true);
        };
        if o.motion.expect != Expect::Homed && !st.homed.iter().all(|h| *h) {
            let line = o.motion.line.clone();
            self.outstanding = None;
            self.queue.clear();
            self.note(format!(
                "the arm lost its homing during `{line}` (STATUS's HOMED row says N); queue dropped"
            ));
            return Err(BackendError::Refused(sim_code::NOT_HOMED));
        }
        if !done {
            o.seen_moving = true;
            return Ok(true);
        }
        if self.arrived()? {
            self.outstanding = None;
            return self.next_in_queue();
        }
        let o = self.outstanding.as_ref().expect("a motion under way");
        // The motion ran (STATUS said not done, W2 moved, or W2 left where the arm last
        // rested), the controller says done, and the arm has stood still short of the end
        // for `settle_ms`: it stopped short (a servo fault, a stop at the controller) without
        // a word. Known within the motion's own time and settle_ms, not after
        // motion_timeout_s (issue 37, item 7). A motion that never left its start and
        // never showed as running still waits for motion_timeout_s: the DONE row may lag.
        let settle = Duration::from_millis(self.profile.settle_ms);
        let left_rest = match (o.from, o.standing) {
            (Some(a), Some((_, b))) => a.iter().zip(&b).any(|(x, y)| (x - y).abs() > STILL_DEG),
            _ => false,
        };
        if (o.seen_moving || o.w2_moved || left_rest)
            && o.standing.is_some_and(|(t, _)| t.elapsed() >= settle)
        {
            let line = o.motion.line.clone();
            let expect = o.motion.expect.clone();
            let at = o.standing.map(|(_, q)| q).unwrap_or_default();
            self.outstanding = None;
            self.queue.clear();
            self.note(format!(
                "`{line}`: the C500 says done, and the arm (W2 joints {}) has stood still for \
                 {} ms short of the motion's end ({expect:?}): it stopped short; the queue was \
                 dropped",
                join(&at),
                settle.as_millis()
            ));
            return Err(BackendError::Refused(NOT_AT_TARGET));
        }
        if o.since.elapsed() > self.motion_timeout() {
            let line = o.motion.line.clone();
            let expect = o.motion.expect.clone();
            self.outstanding = None;
            self.queue.clear();
            let e = format!(
                "`{line}`: the C500 says done, but after {} s the arm (W2) is not at the \
                 motion's end ({expect:?}); whether it ran as asked is not known, and the queue \
                 was dropped",
                self.profile.motion_timeout_s
            );
            self.note(e.clone());
            return Err(BackendError::Unsure(e));
        }
        Ok(true)
    }

    /// Give up the motion under way and the queue (nothing more of them is sent); its line.
    fn give_up(&mut self) -> String {
        self.queue.clear();
        self.outstanding
            .take()
            .map(|o| o.motion.line)
            .unwrap_or_default()
    }

    /// Whether the motion under way was sent longer ago than `motion_timeout_s`.
    fn past_motion_timeout(&self) -> bool {
        self.outstanding
            .as_ref()
            .is_some_and(|o| o.since.elapsed() > self.motion_timeout())
    }

    /// Whether FINISH should go out now: `completion = "finish"`, a motion of ours under way
    /// whose end FINISH has not yet answered for, and the line free.
    fn finish_due(&self) -> bool {
        self.profile.completion == Completion::Finish
            && !self.finish_off
            && !self.finishing
            && self.awaiting.is_none()
            && self.outstanding.as_ref().is_some_and(|o| !o.finish_tried)
    }

    /// Type FINISH; its answer is read by [`RaplBackend::await_finish`].
    fn type_finish(&mut self) -> Result<(), BackendError> {
        self.forget();
        self.report_unasked()?;
        let now = self.now();
        if let Err(e) = self.session.send_line("FINISH", self.motion_timeout(), now) {
            self.note(format!("`FINISH` not sent: {e}"));
            return Err(BackendError::Link(e.to_string()));
        }
        self.finishing = true;
        Ok(())
    }

    /// Listen for FINISH's answer (at most [`FINISH_LISTEN`]): still moving (true), or the
    /// motion's end, confirmed by W2 unless the profile says FINISH's ACK means arrival.
    /// Where it settles nothing, the end is looked for by STATUS.
    fn await_finish(&mut self) -> Result<bool, BackendError> {
        let until = std::time::Instant::now() + FINISH_LISTEN;
        let ev = match self.pump_until(None, Some(until)) {
            Ok(ev) => ev,
            Err(e) => {
                self.finishing = false;
                return Err(BackendError::Unsure(format!("`FINISH`: {e}")));
            }
        };
        let Some(ev) = ev else {
            if self.past_motion_timeout() {
                let line = self.give_up();
                let _ = self.release();
                return Err(BackendError::Unsure(format!(
                    "`{line}`: FINISH was not answered within motion_timeout_s ({} s): Ctrl-C \
                     sent; whether the motion ran to its end is not known",
                    self.profile.motion_timeout_s
                )));
            }
            return Ok(true);
        };
        self.finishing = false;
        let line = self
            .outstanding
            .as_ref()
            .map(|o| o.motion.line.clone())
            .unwrap_or_default();
        let answer = match ev {
            Ok(r) => self.answer("FINISH", r, false),
            Err(e) => Err(if e.surely_not_run() {
                BackendError::Link(format!("`FINISH`: {e}"))
            } else {
                BackendError::Unsure(format!("`FINISH` after `{line}`: {e}"))
            }),
        };
        match answer {
            Ok(Answer::Done(_)) => {
                if self.profile.finish_ack_means_arrived {
                    if let Some(expect) = self.outstanding.as_ref().map(|o| o.motion.expect.clone())
                    {
                        self.seen_at_end(&expect);
                    }
                }
                if self.profile.finish_ack_means_arrived || self.arrived()? {
                    self.outstanding = None;
                    return self.next_in_queue();
                }
                self.note(format!(
                    "FINISH answered after `{line}`, but W2 does not put the arm at the motion's \
                     end: its end is looked for by STATUS"
                ));
            }
            Ok(Answer::Refused(n, t)) if self.profile.finish_ack_means_arrived => {
                // This controller answers FINISH with an error only when the motion stopped
                // short (the profile says so).
                self.outstanding = None;
                let dropped = std::mem::take(&mut self.queue).len();
                self.note(format!(
                    "`{line}` ended short: FINISH answered {n:03}-{t}{}",
                    if dropped > 0 {
                        format!("; {dropped} queued motion(s) dropped, not sent")
                    } else {
                        String::new()
                    }
                ));
                return Err(BackendError::Refused(self.code_of_refusal(n)));
            }
            Ok(Answer::Refused(n, t)) => {
                if self.code_of_refusal(n) == code_of("BIOS_BAD_ARGUMENT") {
                    self.finish_off = true;
                    self.note(format!(
                        "FINISH refused ({n:03}-{t}): this controller does not take it in \
                         immediate mode; the end of each motion is looked for by STATUS"
                    ));
                } else {
                    self.note(format!(
                        "FINISH after `{line}` answered {n:03}-{t}: its end is looked for by \
                         STATUS"
                    ));
                }
            }
            Err(e) => {
                self.outstanding = None;
                self.queue.clear();
                return Err(e);
            }
        }
        if let Some(o) = self.outstanding.as_mut() {
            o.finish_tried = true;
        }
        self.poll_status()
    }

    /// End a FINISH that waits (Ctrl-C, before anything else is typed): the motion runs on.
    /// A controller that does not answer at once leaves the arm's state unknown: UNSURE,
    /// the motion and the queue given up.
    fn release(&mut self) -> Result<(), BackendError> {
        if !self.finishing {
            return Ok(());
        }
        self.finishing = false;
        let t = std::time::Instant::now();
        let r = self.ctrl_c();
        let took = t.elapsed();
        // An ACK before the prompt is FINISH's own answer: the motion ended by itself, and
        // the Ctrl-C may never have been taken.
        let answered = matches!(&r, Ok(text) if text.contains(char::from(ACK)));
        if r.is_ok() && !answered && took <= CTRL_C_ENDS_FINISH_WITHIN {
            return Ok(());
        }
        let line = self.give_up();
        let e = format!(
            "Ctrl-C did not end the FINISH that waited for `{line}` within {} ms ({}): this \
             controller may not take Ctrl-C while FINISH waits (the profile says \
             ctrl_c_ends_finish = true); the arm may still be moving, and nothing further was \
             sent",
            CTRL_C_ENDS_FINISH_WITHIN.as_millis(),
            match r {
                Ok(_) if answered => "FINISH answered by itself".to_string(),
                Ok(_) => format!("its prompt came after {} ms", took.as_millis()),
                Err(e) => e.to_string(),
            }
        );
        self.note(e.clone());
        Err(BackendError::Unsure(e))
    }

    fn next_in_queue(&mut self) -> Result<bool, BackendError> {
        let Some(q) = self.queue.pop_front() else {
            return Ok(false);
        };
        let line = q.line().to_string();
        let r = match q {
            Queued::Motion(m) => self.launch(m),
            Queued::Later(_, f) => {
                // Computed now, from where the arm stands (the motion before it ended): the
                // rest of the queue waits aside, so that the arm counts as standing.
                let rest = std::mem::take(&mut self.queue);
                let r = f(self);
                if matches!(r, Ok(0)) {
                    self.queue = rest;
                } else if !rest.is_empty() {
                    self.note(format!(
                        "{} queued motion(s) dropped after `{line}` failed: not sent",
                        rest.len()
                    ));
                }
                r
            }
        };
        match r? {
            0 => Ok(true),
            c => {
                self.note(format!("queued `{line}` was refused when its turn came"));
                Err(BackendError::Refused(c))
            }
        }
    }

    /// Whether the arm is where the motion under way ends (the controller said done).
    fn arrived(&mut self) -> Result<bool, BackendError> {
        let expect = match &self.outstanding {
            Some(o) => o.motion.expect.clone(),
            None => return Ok(true),
        };
        let p = self.read_position(PosMode::Actual)?;
        if let Some(o) = self.outstanding.as_mut() {
            match o.standing {
                Some((_, q))
                    if q.iter()
                        .zip(&p.joints)
                        .all(|(a, b)| (a - b).abs() <= STILL_DEG) => {}
                Some(_) => {
                    o.w2_moved = true;
                    o.standing = Some((std::time::Instant::now(), p.joints));
                }
                None => o.standing = Some((std::time::Instant::now(), p.joints)),
            }
        }
        let tol = self.profile.arrive_deg;
        let arrived = match expect {
            Expect::Joints(q) => p.joints.iter().zip(&q).all(|(a, b)| (a - b).abs() <= tol),
            Expect::Pulses(c) => {
                let scale = self
                    .frames
                    .pulses
                    .map(|s| s.map(|(k, _)| k.abs()))
                    .unwrap_or([1.0; 6]);
                p.pulses
                    .iter()
                    .zip(&c)
                    .zip(&scale)
                    .all(|((a, b), k)| ((a - b) as f64).abs() <= tol * k)
            }
            Expect::World(w) => self.world_near(&p.world, &w),
            Expect::Unknown | Expect::Homed => {
                let homed = self
                    .status
                    .as_ref()
                    .is_some_and(|s| s.homed.iter().all(|h| *h));
                let o = self.outstanding.as_mut().expect("a motion under way");
                if expect == Expect::Homed && !homed {
                    false
                } else if o.seen_moving {
                    true
                } else {
                    let settle = Duration::from_millis(self.profile.settle_ms);
                    match o.still {
                        Some((t, q))
                            if q.iter().zip(&p.joints).all(|(a, b)| (a - b).abs() <= tol) =>
                        {
                            t.elapsed() >= settle
                        }
                        _ => {
                            o.still = Some((std::time::Instant::now(), p.joints));
                            false
                        }
                    }
                }
            }
        };
        if arrived {
            self.rest = Some(p.joints);
            self.seen_at_end(&expect);
        }
        Ok(arrived)
    }

    /// A motion seen to end where it was sent (W2 there, or FINISH's ACK where the profile
    /// has it mean arrival): the arm stands at its end, idle, and powered and homed as the
    /// last STATUS said (the motion ran), as of now ([`SEEN_FOR`]).
    fn seen_at_end(&mut self, expect: &Expect) {
        let now = std::time::Instant::now();
        self.seen.end = match expect {
            Expect::Joints(q) => Some((now, *q)),
            _ => None,
        };
        self.seen.idle = self
            .status
            .clone()
            .filter(|s| s.homed.iter().all(|h| *h) && !s.limp.iter().any(|l| *l))
            .map(|s| (now, s));
    }

    /// Whether two WORLD rows are the same pose within the profile's tolerance (the angles
    /// compared as rotations when the profile knows them).
    fn world_near(&self, a: &[f64; 6], b: &[f64; 6]) -> bool {
        let mm = self.frames.mm.unwrap_or(1.0);
        let d = (0..3)
            .map(|i| (a[i] - b[i]) * mm)
            .map(|x| x * x)
            .sum::<f64>();
        if d.sqrt() > self.profile.arrive_mm {
            return false;
        }
        match (self.frames.from_rapl(*a), self.frames.from_rapl(*b)) {
            (Ok(x), Ok(y)) => {
                crate::probe::rotation_distance_deg(&Pose::from_xyzypr(x), &Pose::from_xyzypr(y))
                    <= self.profile.arrive_deg
            }
            _ => true,
        }
    }

    fn open(&mut self) -> Result<(), RaplError> {
        let mut aci_said = String::from("the port was taken to be in terminal mode");
        if self.profile.entry != Entry::Terminal {
            match self.aci_steps()? {
                Ok(()) => {
                    // RW waits 100 ms for the switch.
                    let until = std::time::Instant::now() + Duration::from_millis(100);
                    while std::time::Instant::now() < until {
                        let got = self.recv(until)?;
                        if !got.is_empty() {
                            self.note(format!(
                                "after the ACI steps: {:?}",
                                String::from_utf8_lossy(&got)
                            ));
                        }
                    }
                }
                Err(e) => {
                    aci_said = e.to_string();
                    self.note(format!(
                        "{e}; trying Ctrl-C in case the port is in terminal mode"
                    ));
                }
            }
        }
        let now = self.now();
        self.session.resync(now);
        if self.pump()?.is_err() {
            return Err(RaplError::NoController {
                port: self.port.name(),
                aci: aci_said,
                baud: self.profile.baud,
            });
        }
        // NOHELP the way RW types it: NOH, then whatever completion comes, then CR.
        let now = self.now();
        self.session.send_completing(
            "NOH",
            Duration::from_millis(150),
            self.reply_timeout(),
            now,
        )?;
        let mut r = self.pump()?.map_err(no_echo)?;
        if self.refusal(&r).is_some() {
            let now = self.now();
            self.session
                .send_line("NOHELP", self.reply_timeout(), now)?;
            r = self.pump()?.map_err(no_echo)?;
            if let Some((n, t)) = self.refusal(&r) {
                return Err(RaplError::Status(format!(
                    "NOHELP was refused ({n:03}-{t}); nothing was moved"
                )));
            }
        }
        match self.profile.ack {
            Ack::Required if !r.ack => {
                return Err(RaplError::Status(
                    "NOHELP was answered without ACK, which the profile requires (ack = \
                     \"required\"): set ack = \"auto\" if this controller sends none; nothing \
                     was moved"
                        .into(),
                ));
            }
            Ack::Never if r.ack => {
                return Err(RaplError::Status(
                    "NOHELP was answered with ACK, but the profile says ack = \"never\": set \
                     ack = \"auto\"; nothing was moved"
                        .into(),
                ));
            }
            Ack::Auto => {
                self.ack = r.ack;
                self.note(format!(
                    "this controller answers success {} ACK (learned from NOHELP)",
                    if r.ack { "with" } else { "without" }
                ));
            }
            _ => {}
        }
        let status = self
            .read_status()
            .map_err(|e| RaplError::Status(e.to_string()))?;
        match (self.profile.units, status.metric) {
            (Units::Auto, m) => self.frames.mm = m.map(|m| if m { 1.0 } else { 25.4 }),
            (Units::Mm, Some(false)) | (Units::Inch, Some(true)) => {
                return Err(RaplError::Status(format!(
                    "the profile says units = \"{}\" but STATUS says {}: set units = \"auto\" \
                     or change the controller's setting; nothing was moved",
                    if self.profile.units == Units::Mm {
                        "mm"
                    } else {
                        "inch"
                    },
                    if status.metric == Some(true) {
                        "METRIC UNITS"
                    } else {
                        "ENGLISH UNITS"
                    }
                )));
            }
            _ => {}
        }
        if self.profile.simulated {
            self.check_simulator()?;
        }
        self.note(format!(
            "session open: {}; units {}",
            status.version,
            match self.frames.mm {
                Some(1.0) => "mm",
                Some(_) => "inch",
                None => "unknown (cartesian commands refused)",
            }
        ));
        if status.limp.iter().any(|l| *l) {
            self.note(
                "the arm has no power (STATUS's LIMP row says Y): motions are refused until it \
                 has"
                .into(),
            );
        }
        if !status.homed.iter().all(|h| *h) {
            self.note(
                "the arm is not homed (STATUS's HOMED row says N): call TROLHome(0) with the arm \
                 near its home position; other motions are refused until then"
                    .into(),
            );
        }
        Ok(())
    }

    /// A profile written for the simulated C500 (`simulated = true`) drives only the
    /// simulator: the probe's unknown word must come back refused with the simulator's name
    /// (a real C500 refuses it in its own words, or answers in a form the simulator's profile
    /// does not know). Nothing that moves was sent.
    fn check_simulator(&mut self) -> Result<(), RaplError> {
        let word = crate::probe::PROBE_WORD;
        let said = match self.exchange(word, self.reply_timeout()) {
            Ok(r) => {
                let text = lines(&r.text).join(" / ");
                match self.answer(word, r, false) {
                    Ok(Answer::Refused(_, t)) if t.contains(crate::c500::SIMULATOR_SAYS) => {
                        return Ok(());
                    }
                    _ => text,
                }
            }
            Err(e) => e.to_string(),
        };
        Err(RaplError::Status(format!(
            "this profile was written for TROL's simulated C500 (`simulated = true`, by `trol \
             sim --rapl --print-profile`), and the controller on {} is not it (it answered \
             `{word}` with `{said}`): its readings would move a real arm wrongly. Write this \
             controller's own profile with `trol rapl probe` (docs/c500.md, \"The first hour \
             with a real arm\"), or delete the line `simulated = true` to use the file anyway; \
             nothing was moved",
            self.port.name()
        )))
    }

    fn aci_steps(&mut self) -> io::Result<Result<(), AciError>> {
        let mut m = Master::new(self.profile.entry, self.profile.slave, self.now());
        loop {
            let tx = m.take_transmit();
            if !tx.is_empty() {
                self.send(&tx)?;
            }
            if let Some(r) = m.result() {
                return Ok(r);
            }
            let wake = m
                .next_timeout()
                .map(|t| self.at(t))
                .unwrap_or_else(std::time::Instant::now);
            let got = self.recv(wake)?;
            let now = self.now();
            m.feed(&got, now);
            m.handle_timeout(now);
        }
    }

    /// End the session: HELP back on, then two Ctrl-Z to ACI mode. Once: later calls, and
    /// dropping the backend, send nothing more. Motions still queued are dropped, not sent.
    pub fn close(&mut self) {
        if self.closed {
            return;
        }
        if !self.queue.is_empty() {
            let n = self.queue.len();
            self.queue.clear();
            self.note(format!("{n} queued motion(s) dropped at close, not sent"));
        }
        let t = self.reply_timeout();
        let _ = self.exchange("HELP", t);
        let _ = self.send(&[CTRL_Z, CTRL_Z]);
        self.closed = true;
    }

    fn unsettled(&mut self, u: Unsettled) -> i16 {
        self.note(format!("refused before sending: {u}"));
        match u {
            Unsettled::Units => NO_UNITS,
            Unsettled::Angles => NO_ANGLES,
            Unsettled::Pulses => NO_PULSES,
        }
    }

    /// A scratch name not used by a motion under way or queued.
    /// Why a teaching command cannot go to the C500 (said in the log), before anything is
    /// sent: a joint location (RAPL-II keeps cartesian locations and precision points), or a
    /// scratch location's name.
    fn teach_refusal(&mut self, name: &LocName, tag: Tag) -> Option<i16> {
        if tag == Tag::Joint {
            self.note(
                "refused before sending: RAPL-II keeps cartesian locations and precision \
                 points (#NAME), not joint angles"
                    .into(),
            );
            return Some(UNSUPPORTED);
        }
        if Self::is_scratch(name.as_str()) {
            self.note(format!(
                "refused before sending: {name} is a scratch location of this backend (T1 to \
                 T{}, for MoveII and Appro); choose another name",
                QUEUE + 2
            ));
            return Some(code_of("BIOS_BAD_ARGUMENT"));
        }
        None
    }

    fn scratch_name(&mut self) -> String {
        self.scratch = (self.scratch % (QUEUE + 2)) + 1;
        format!("T{}", self.scratch)
    }

    /// Define a scratch location for a TROL target and read it back; the motion line's
    /// target name and what the motion must end at, or the code that refused it.
    fn point(&mut self, loc: &Location) -> Result<Result<(String, Expect), i16>, BackendError> {
        let name = self.scratch_name();
        self.point_named(name, loc)
    }

    /// Whether `name` (any case) is one of the scratch locations this backend defines for
    /// MoveII and Appro: a program's location of that name would be overwritten.
    fn is_scratch(name: &str) -> bool {
        let upper = name.to_ascii_uppercase();
        upper
            .strip_prefix('T')
            .and_then(|n| n.parse::<usize>().ok())
            .is_some_and(|n| (1..=QUEUE + 2).contains(&n))
    }

    /// POINT `name` (upper case; `#` added for a precision point) with `loc`, read back with
    /// LISTL: the RAPL name and what a motion to it must end at, or the code that refused it.
    fn point_named(
        &mut self,
        name: String,
        loc: &Location,
    ) -> Result<Result<(String, Expect), i16>, BackendError> {
        let name = name.trim_start_matches('#').to_ascii_uppercase();
        let (name, values, expect) = match loc {
            Location::Cart(_) => match self.frames.to_rapl(loc.to_array6()) {
                Ok(v) => (name, v, Expect::World(v)),
                Err(u) => return Ok(Err(self.unsettled(u))),
            },
            Location::Prec(_) => {
                if self.frames.pulses.is_none() {
                    return Ok(Err(self.unsettled(Unsettled::Pulses)));
                }
                let c = loc.to_array6().map(|x| x.round() as i64);
                (format!("#{name}"), c.map(|x| x as f64), Expect::Pulses(c))
            }
            Location::Joint(_) => {
                let deg = loc.to_array6().map(f64::to_degrees);
                match self.frames.joints_to_pulses(deg) {
                    Ok(c) => (format!("#{name}"), c.map(|x| x as f64), Expect::Joints(deg)),
                    Err(u) => return Ok(Err(self.unsettled(u))),
                }
            }
        };
        let line = if name.starts_with('#') {
            format!("POINT {name} {}", join_int(&values.map(|x| x as i64)))
        } else {
            format!("POINT {name} {}", join(&values))
        };
        // POINT changes a scratch location only: whatever happened to it, no motion was sent.
        match self.command(&line).map_err(not_run)? {
            0 => {}
            c => return Ok(Err(c)),
        }
        // Read it back: the motion names it only if it holds what was sent.
        let back = self.output(&format!("LISTL {name}"))?;
        let rows = text::read_listl(&back.text).map_err(BackendError::Link)?;
        let held = rows.into_iter().find(|(n, _)| *n == name).map(|(_, l)| l);
        let same = match (&held, &expect) {
            (Some(Listed::Cart(v)), Expect::World(w)) => {
                v.iter().zip(w).all(|(a, b)| (a - b).abs() <= 0.002)
            }
            (Some(Listed::Prec(p)), _) => p.iter().zip(&values).all(|(a, b)| *a as f64 == *b),
            _ => false,
        };
        if !same {
            let e = format!(
                "`{line}` was answered with success, but LISTL {name} reads {held:?}: the \
                 scratch location does not hold the target, so no motion was sent"
            );
            self.note(e.clone());
            return Err(BackendError::Link(e));
        }
        Ok(Ok((name, expect)))
    }

    fn move_pose(&mut self, pose: &Pose, straight: bool, busy: bool) -> BiosResult {
        let loc = Location::from_array6(Tag::Cart, pose.to_xyzypr());
        match self.point(&loc)? {
            Ok((n, expect)) => self.submit(
                Motion {
                    line: format!("{} {n}", mv(straight)),
                    expect,
                },
                busy,
            ),
            Err(c) => Ok(c),
        }
    }

    /// A location of the controller's table, or None when it has none of the name.
    fn listed(&mut self, name: &LocName) -> Result<Option<Listed>, BackendError> {
        let upper = name.as_str().to_ascii_uppercase();
        let line = format!("LISTL {upper}");
        let t = self.reply_timeout();
        let r = self.exchange(&line, t)?;
        let r = match self.answer(&line, r, true)? {
            Answer::Refused(..) => return Ok(None),
            Answer::Done(r) => r,
        };
        let rows = text::read_listl(&r.text).map_err(BackendError::Link)?;
        Ok(rows.into_iter().find(|(n, _)| *n == upper).map(|(_, l)| l))
    }

    /// The pose of a listed location (a cartesian one needs the profile's conventions, a
    /// precision point its pulses).
    fn pose_of(&mut self, l: Listed) -> Result<Pose, i16> {
        Ok(match l {
            Listed::Cart(v) => match self.frames.from_rapl(v) {
                Ok(t) => Pose::from_xyzypr(t),
                Err(u) => return Err(self.unsettled(u)),
            },
            Listed::Prec(p) => match self.frames.pulses_to_joints(p) {
                Ok(deg) => self.kin().fk(&deg.map(f64::to_radians)),
                Err(u) => return Err(self.unsettled(u)),
            },
        })
    }

    /// One stop (`HALT`, `ABORT` or `Ctrl-C`) on its own, and whether W2 then shows the arm
    /// standing within [`STOP_WITHIN`] (its joints), or why not: for the probe's supervised
    /// step that finds which stop stops a motion. Halt itself tries them all.
    pub fn stop_with(&mut self, stop: &str) -> Result<Result<[f64; 6], String>, BackendError> {
        let stop = match stop {
            "HALT" => Stop::Halt,
            "ABORT" => Stop::Abort,
            "Ctrl-C" => Stop::CtrlC,
            other => {
                return Err(BackendError::Link(format!(
                    "{other} is not one of the C500's stops"
                )));
            }
        };
        match stop {
            Stop::CtrlC => {
                self.awaiting = None;
                self.interrupt()?;
            }
            Stop::Halt | Stop::Abort => match self.command_as(stop.word(), true)? {
                0 => {}
                c => return Ok(Err(format!("{} was refused ({c})", stop.word()))),
            },
        }
        let until = std::time::Instant::now() + STOP_WITHIN;
        real::seen_standing(&mut Stopper(self), until, STOP_WITHIN).map_err(BackendError::Link)
    }

    /// The stops to try, in order: Ctrl-C first where the interpreter is busy with a line
    /// (a motion answered at its end) or where the profile says it is the halt, then the
    /// profile's halt, then the others in the order HALT, ABORT, Ctrl-C.
    fn stop_order(&self) -> Vec<Stop> {
        let mut order = Vec::new();
        if self.awaiting.is_some() || self.profile.halt == Halt::CtrlC {
            order.push(Stop::CtrlC);
        }
        order.push(match self.profile.halt {
            Halt::Halt => Stop::Halt,
            Halt::Abort => Stop::Abort,
            Halt::CtrlC => Stop::CtrlC,
        });
        for s in [Stop::Halt, Stop::Abort, Stop::CtrlC] {
            if !order.contains(&s) {
                order.push(s);
            }
        }
        order
    }

    /// Halt as the arm shows it (issue 37; the rule is the shared one of
    /// [`trol_controller::real::halt`]): each stop of [`RaplBackend::stop_order`] in turn,
    /// until W2 shows the arm standing; success only then. Where none is seen to work within
    /// [`HALT_WITHIN`] of the call, TROL_ERR_NOT_STOPPED with what each stop got. No profile
    /// key makes a stop count that was not seen.
    fn stop_and_see(&mut self) -> BiosResult {
        let order = self.stop_order();
        let times = real::HaltTimes {
            halt_within: HALT_WITHIN,
            stop_within: STOP_WITHIN,
        };
        match real::halt(&mut Stopper(self), &order, times) {
            real::Halted::Standing { at, note } => {
                self.rest = Some(at);
                self.outstanding = None;
                self.awaiting = None;
                if let Some(note) = note {
                    self.note(note);
                }
                Ok(0)
            }
            real::Halted::NotStopped(text) => {
                self.note(format!("Halt: the arm was not seen standing: {text}"));
                Err(BackendError::NotStopped(text))
            }
        }
    }

    fn kin(&self) -> Kinematics {
        Kinematics::new(self.tool)
    }

    fn read_position(&mut self, mode: PosMode) -> Result<text::Position, BackendError> {
        let cmd = match mode {
            PosMode::Commanded => "W0",
            PosMode::Actual => "W2",
        };
        let mut why = String::new();
        for _ in 0..3 {
            let r = self.output(cmd)?;
            match text::read_position(&r.text).and_then(|p| self.consistent(p)) {
                Ok(p) => return Ok(p),
                Err(e) => {
                    self.note(format!("{cmd} read again: {e}: {:?}", r.text));
                    why = e;
                }
            }
        }
        Err(BackendError::Link(format!(
            "the reply to {cmd} could not be read three times: {why}"
        )))
    }

    /// A reading whose PULSES and JOINTS rows agree (within 0.01 degrees) under the
    /// profile's pulse convention, when it has one and asks for the check.
    fn consistent(&self, p: text::Position) -> Result<text::Position, String> {
        if !self.profile.cross_check {
            return Ok(p);
        }
        let Ok(q) = self.frames.pulses_to_joints(p.pulses) else {
            return Ok(p);
        };
        for (i, (from_pulses, read)) in q.iter().zip(&p.joints).enumerate() {
            if (from_pulses - read).abs() > 0.01 {
                return Err(format!(
                    "joint {} reads {read:.4} deg but its pulses say {from_pulses:.4} deg",
                    i + 1,
                ));
            }
        }
        Ok(p)
    }

    /// Where the arm stands (W0), for a motion computed from it; BUSY while a motion of ours
    /// has not ended (its end would be a guess).
    fn standing(&mut self) -> Result<Result<text::Position, i16>, BackendError> {
        if self.outstanding.is_some() || !self.queue.is_empty() {
            self.note(
                "refused: a motion has not ended, and this one is computed from where the arm \
                 is: call TROLFinish(FINISH_WAIT) first"
                    .into(),
            );
            return Ok(Err(BUSY));
        }
        self.read_position(PosMode::Commanded).map(Ok)
    }

    /// Where the arm stands in joints (degrees): the end of the motion before, seen arrived a
    /// moment ago with nothing but reads since ([`SEEN_FOR`]), else W0 as
    /// [`RaplBackend::standing`] reads it.
    fn standing_joints(&mut self) -> Result<Result<[f64; 6], i16>, BackendError> {
        if self.outstanding.is_none() && self.queue.is_empty() {
            if let Some(q) = self.seen.end(self.seen_for) {
                return Ok(Ok(q));
            }
        }
        Ok(self.standing()?.map(|p| p.joints))
    }

    fn here(&mut self) -> Result<Result<Pose, i16>, BackendError> {
        let p = match self.standing()? {
            Ok(p) => p,
            Err(c) => return Ok(Err(c)),
        };
        Ok(match self.frames.from_rapl(p.world) {
            Ok(v) => Ok(Pose::from_xyzypr(v)),
            Err(u) => Err(self.unsettled(u)),
        })
    }

    /// The gate, then `f` with whether the arm is busy.
    fn motion_with(
        &mut self,
        homing: bool,
        f: impl FnOnce(&mut Self, bool) -> BiosResult,
    ) -> BiosResult {
        match self.gate(homing)? {
            Gate::Refuse(c) => Ok(c),
            Gate::Idle => f(self, false),
            Gate::Busy => f(self, true),
        }
    }

    fn joints(&mut self, cmd: &str, q: [f64; 6], relative: bool) -> BiosResult {
        let Some(units) = self.joint_units else {
            self.note(format!(
                "refused {cmd} before sending: its units are not known; set joint_units in the \
                 RAPL-II profile (docs/c500.md, Settle the conventions)"
            ));
            return Ok(NO_JOINT_UNITS);
        };
        if q.iter().any(|x| !x.is_finite()) {
            return Ok(code_of("BIOS_BAD_ARGUMENT"));
        }
        let v = match units {
            JointUnits::Degrees => q.map(f64::to_degrees),
            JointUnits::Radians => q,
        };
        let line = format!("{cmd} {}", join(&v));
        let deg = q.map(f64::to_degrees);
        self.motion_with(false, |b, busy| {
            if !relative {
                let expect = Expect::Joints(deg);
                return b.submit(Motion { line, expect }, busy);
            }
            b.relative_joints(line, busy, move |q| std::array::from_fn(|i| q[i] + deg[i]))
        })
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

impl Backend for RaplBackend {
    fn kind(&self) -> &'static str {
        "C500 over RAPL-II"
    }
    fn codes(&self) -> &'static CodeTable {
        RAPL_CODES
    }
    fn reply_time(&self) -> Duration {
        // One command the C500 does not answer (the profile's reply timeout), after a
        // FINISH that waits was ended with Ctrl-C and listened for once; or a Halt that
        // tries every stop.
        (self.reply_timeout() + CTRL_C_ENDS_FINISH_WITHIN + FINISH_LISTEN)
            .max(HALT_WITHIN + Duration::from_millis(400))
    }
    fn appro(&mut self, target: &Target, disp: [f64; 6], straight: bool) -> BiosResult {
        let target = target.clone();
        self.motion_with(false, |b, busy| {
            let pose = match &target {
                Target::Name(n) => match b.listed(n)? {
                    Some(l) => match b.pose_of(l) {
                        Ok(p) => p,
                        Err(c) => return Ok(c),
                    },
                    None => return Err(BackendError::UnknownLocation(*n)),
                },
                Target::Location(l @ Location::Cart(_)) => Pose::from_xyzypr(l.to_array6()),
                Target::Location(l @ Location::Prec(_)) => {
                    match b
                        .frames
                        .pulses_to_joints(l.to_array6().map(|x| x.round() as i64))
                    {
                        Ok(deg) => b.kin().fk(&deg.map(f64::to_radians)),
                        Err(u) => return Ok(b.unsettled(u)),
                    }
                }
                Target::Location(l @ Location::Joint(_)) => b.kin().fk(&l.to_array6()),
            };
            b.move_pose(&pose.then(&Pose::from_xyzypr(disp)), straight, busy)
        })
    }
    fn close(&mut self, force: u8) -> BiosResult {
        self.report_unasked()?;
        let r = self.command(&format!("CLOSE {force}"))?;
        self.last_poll = None;
        Ok(r)
    }
    fn depart(&mut self, disp: [f64; 6], straight: bool) -> BiosResult {
        let what = format!("Depart {}", join(&disp));
        self.motion_with(false, |b, busy| {
            b.relative(
                what,
                busy,
                Box::new(move |b| match b.here()? {
                    Ok(p) => b.move_pose(&p.then(&Pose::from_xyzypr(disp)), straight, false),
                    Err(c) => Ok(c),
                }),
            )
        })
    }
    fn moving(&mut self) -> Result<bool, BackendError> {
        if let Some(e) = self.deferred.take() {
            return Err(e);
        }
        if self.finish_due() {
            self.type_finish()?;
        } else if let Some((at, m)) = self.last_poll {
            if !self.finishing && at.elapsed() < Duration::from_millis(self.profile.poll_ms) {
                return Ok(m);
            }
        }
        let m = self.poll()?;
        self.last_poll = Some((std::time::Instant::now(), m));
        Ok(m)
    }
    fn stands(&mut self) -> Result<bool, BackendError> {
        // halt() answers success only once it has seen the arm standing.
        Ok(true)
    }
    fn grip(&mut self, dist: u8) -> BiosResult {
        self.report_unasked()?;
        let d = match self.frames.length_to_rapl(f64::from(dist)) {
            Ok(d) => d,
            Err(u) => return Ok(self.unsettled(u)),
        };
        let r = self.command(&format!("GRIP {}", text::num(d)))?;
        self.last_poll = None;
        Ok(r)
    }
    fn halt(&mut self) -> BiosResult {
        // A Home halted on the way leaves the arm not homed: the Finish after it says so.
        let homing = self
            .outstanding
            .as_ref()
            .is_some_and(|o| o.motion.expect == Expect::Homed)
            || self.queue.iter().any(|q| q.line() == "HOME");
        // Nothing queued goes out after a Halt, whatever happens to the Halt itself.
        self.last_poll = None;
        if !self.queue.is_empty() {
            let n = self.queue.len();
            self.queue.clear();
            self.note(format!("Halt: {n} queued motion(s) dropped, not sent"));
        }
        let r = self.stop_and_see();
        if homing && r.is_ok() {
            self.deferred = Some(BackendError::Refused(sim_code::NOT_HOMED));
            self.note("Halt during HOME: the arm is not homed (the next Finish says so)".into());
        }
        r
    }
    fn home(&mut self, axis: u8) -> BiosResult {
        if axis != 0 {
            self.note(format!(
                "refused: RAPL-II has no form for homing axis {axis} alone"
            ));
            return Ok(UNSUPPORTED);
        }
        self.motion_with(true, |b, busy| {
            b.submit(
                Motion {
                    line: "HOME".into(),
                    expect: Expect::Homed,
                },
                busy,
            )
        })
    }
    fn jog(&mut self, d: [f64; 3], straight: bool) -> BiosResult {
        if straight {
            match self.profile.jog_frame() {
                Ok(Some(true)) => {}
                Ok(Some(false)) => {
                    self.note(
                        "refused before sending: this controller's JOG moves in the tool \
                         frame, TROL's Jog in the world frame; use Jog with straight = 0"
                            .into(),
                    );
                    return Ok(UNSUPPORTED);
                }
                _ => {
                    self.note(
                        "refused before sending: JOG's frame is not known; set jog_frame in \
                         the RAPL-II profile (docs/c500.md, Settle the conventions)"
                            .into(),
                    );
                    return Ok(NO_JOG_FRAME);
                }
            }
            let v: Result<Vec<f64>, Unsettled> =
                d.iter().map(|x| self.frames.length_to_rapl(*x)).collect();
            let v = match v {
                Ok(v) => v,
                Err(u) => return Ok(self.unsettled(u)),
            };
            let line = format!("JOG {}", join(&v));
            return self.motion_with(false, |b, busy| {
                b.relative_line(line, busy, move |p| {
                    let mut w = p.world;
                    for i in 0..3 {
                        w[i] += v[i];
                    }
                    Expect::World(w)
                })
            });
        }
        let what = format!("Jog {}", join(&d));
        self.motion_with(false, |b, busy| {
            b.relative(
                what,
                busy,
                Box::new(move |b| match b.here()? {
                    Ok(mut p) => {
                        p.pos.x += d[0];
                        p.pos.y += d[1];
                        p.pos.z += d[2];
                        b.move_pose(&p, false, false)
                    }
                    Err(c) => Ok(c),
                }),
            )
        })
    }
    fn joint(&mut self, joint: u8, radians: f64) -> BiosResult {
        if !(1..=6).contains(&joint) || !radians.is_finite() {
            return Ok(code_of("BIOS_BAD_ARGUMENT"));
        }
        let deg = radians.to_degrees();
        let line = format!("JOINT {joint},{}", text::num(deg));
        self.motion_with(false, |b, busy| {
            b.relative_joints(line, busy, move |mut q| {
                q[usize::from(joint - 1)] += deg;
                q
            })
        })
    }
    fn ma(&mut self, q: [f64; 6]) -> BiosResult {
        self.joints("MA", q, false)
    }
    fn mi(&mut self, dq: [f64; 6]) -> BiosResult {
        self.joints("MI", dq, true)
    }
    fn move_to(&mut self, target: &Target, straight: bool) -> BiosResult {
        let target = target.clone();
        if let Target::Location(l @ Location::Joint(_)) = &target {
            // A joint target goes as MA where its units are known: no pulse convention needed.
            if self.joint_units.is_some() && !straight {
                return self.joints("MA", l.to_array6(), false);
            }
        }
        self.motion_with(false, |b, busy| match &target {
            Target::Name(n) => match b.listed(n)? {
                Some(l) => {
                    let expect = match l {
                        Listed::Cart(v) => Expect::World(v),
                        Listed::Prec(p) => Expect::Pulses(p),
                    };
                    // LISTL found it: a refusal now is the motion's, not the name's.
                    let upper = n.as_str().to_ascii_uppercase();
                    let line = format!("{} {upper}", mv(straight));
                    b.submit(Motion { line, expect }, busy)
                }
                None => Err(BackendError::UnknownLocation(*n)),
            },
            Target::Location(l) => match b.point(l)? {
                Ok((name, expect)) => b.submit(
                    Motion {
                        line: format!("{} {name}", mv(straight)),
                        expect,
                    },
                    busy,
                ),
                Err(c) => Ok(c),
            },
        })
    }
    fn here(&mut self, name: LocName, tag: Tag) -> BiosResult {
        self.report_unasked()?;
        if let Some(c) = self.teach_refusal(&name, tag) {
            return Ok(c);
        }
        let upper = name.as_str().to_ascii_uppercase();
        // HERE moves nothing: whatever happens to it, no motion was sent.
        match self.command(&format!("HERE {upper}")).map_err(not_run)? {
            0 => {}
            c => return Ok(c),
        }
        // Success only once LISTL shows the location.
        match self.listed(&name)? {
            Some(_) => Ok(0),
            None => {
                let e = format!(
                    "`HERE {upper}` was answered with success, but LISTL does not list {upper}"
                );
                self.note(e.clone());
                Err(BackendError::Link(e))
            }
        }
    }
    fn define(&mut self, name: LocName, loc: &Location) -> BiosResult {
        self.report_unasked()?;
        if let Some(c) = self.teach_refusal(&name, loc.tag()) {
            return Ok(c);
        }
        // POINT and its read back, as for a scratch location of MoveII.
        match self.point_named(name.as_str().to_string(), loc)? {
            Ok(_) => Ok(0),
            Err(c) => Ok(c),
        }
    }
    fn delete_location(&mut self, name: LocName) -> BiosResult {
        self.report_unasked()?;
        if let Some(c) = self.teach_refusal(&name, Tag::Cart) {
            return Ok(c);
        }
        if self.listed(&name)?.is_none() {
            return Err(BackendError::UnknownLocation(name));
        }
        let upper = name.as_str().to_ascii_uppercase();
        match self.command(&format!("DLOCN {upper}")).map_err(not_run)? {
            0 => {}
            c => return Ok(c),
        }
        match self.listed(&name)? {
            None => Ok(0),
            Some(_) => {
                let e =
                    format!("`DLOCN {upper}` was answered with success, but LISTL still lists it");
                self.note(e.clone());
                Err(BackendError::Link(e))
            }
        }
    }
    fn locations(&mut self) -> Result<Vec<(LocName, Location)>, BackendError> {
        self.report_unasked()?;
        let r = self.output("LISTL")?;
        let rows = text::read_listl(&r.text).map_err(BackendError::Link)?;
        let mut all = Vec::new();
        for (n, l) in rows {
            if Self::is_scratch(&n) {
                continue;
            }
            let Ok(name) = LocName::new(&n.to_ascii_lowercase()) else {
                self.note(format!("LISTL: {n} is no TROL location name; left out"));
                continue;
            };
            let loc = match l {
                Listed::Cart(v) => match self.frames.from_rapl(v) {
                    Ok(t) => Location::from_array6(Tag::Cart, t),
                    Err(u) => return Err(BackendError::Refused(self.unsettled(u))),
                },
                Listed::Prec(p) => {
                    let counts: Option<Vec<i32>> =
                        p.iter().map(|x| i32::try_from(*x).ok()).collect();
                    match counts {
                        Some(c) => Location::Prec(c),
                        None => {
                            self.note(format!("LISTL: {n}'s pulses do not fit 32 bits; left out"));
                            continue;
                        }
                    }
                }
            };
            all.push((name, loc));
        }
        all.sort_by(|a, b| a.0.as_str().cmp(b.0.as_str()));
        Ok(all)
    }
    fn save_locations(&mut self) -> BiosResult {
        // The C500 keeps its location table itself; no public source says whether that
        // memory outlives a power cycle, nor names a command that makes it. Success would
        // claim what cannot be told.
        self.note(
            "refused: the C500 keeps its locations itself; whether they outlive a power \
             cycle is the controller's, and TROL has no command to make sure (write them \
             down with LISTL)"
                .into(),
        );
        Ok(UNSUPPORTED)
    }
    fn open(&mut self, force: u8) -> BiosResult {
        self.report_unasked()?;
        let r = self.command(&format!("OPEN {force}"))?;
        self.last_poll = None;
        Ok(r)
    }
    fn ready(&mut self) -> BiosResult {
        self.motion_with(false, |b, busy| {
            b.submit(
                Motion {
                    line: "READY".into(),
                    expect: Expect::Unknown,
                },
                busy,
            )
        })
    }
    fn set_tool(&mut self, tool: [f64; 6]) -> BiosResult {
        self.report_unasked()?;
        if self.outstanding.is_some() || !self.queue.is_empty() {
            self.note(
                "refused: the tool changes what a queued motion's target means: call \
                 TROLFinish(FINISH_WAIT) first"
                    .into(),
            );
            return Ok(BUSY);
        }
        let v = match self.frames.to_rapl(tool) {
            Ok(v) => v,
            Err(u) => return Ok(self.unsettled(u)),
        };
        match self.command(&format!("POINT TL {}", join(&v)))? {
            0 => {}
            c => return Ok(c),
        }
        let r = self.command("TOOL TL")?;
        if r == 0 {
            self.tool = tool;
        }
        Ok(r)
    }
    fn speed(&mut self, percent: u8) -> BiosResult {
        if !(1..=100).contains(&percent) {
            return Ok(code_of("BIOS_BAD_ARGUMENT"));
        }
        self.report_unasked()?;
        self.command(&format!("SPEED {percent}"))
    }
    fn position(&mut self, tag: Tag, mode: PosMode) -> Result<Location, BackendError> {
        let p = self.read_position(mode)?;
        Ok(match tag {
            Tag::Joint => Location::from_array6(Tag::Joint, p.joints.map(f64::to_radians)),
            Tag::Prec => Location::Prec(p.pulses.iter().map(|x| *x as i32).collect()),
            Tag::Cart => match self.frames.from_rapl(p.world) {
                Ok(v) => Location::from_array6(Tag::Cart, v),
                Err(u) => return Err(BackendError::Refused(self.unsettled(u))),
            },
        })
    }
    fn report(&mut self) -> Option<ArmReport> {
        // W2 is read-only; not while a motion answered at its end or a FINISH holds the
        // session (the view would end the FINISH at every update), nor once it failed.
        if self.closed || self.awaiting.is_some() || self.finishing || self.deferred.is_some() {
            return None;
        }
        let p = self.read_position(PosMode::Actual).ok()?;
        Some(ArmReport {
            joints: p.joints.map(f64::to_radians),
            moving: self.outstanding.is_some() || !self.queue.is_empty(),
            target: None,
            gripper_mm: None,
            tool: self.tool,
            homed: self.status.as_ref().map(|s| s.homed),
        })
    }
    fn idle(&mut self) {
        // Only a queue waiting for the motion under way to end needs a look; an error
        // already kept is told by the next call.
        if self.closed || self.queue.is_empty() || self.deferred.is_some() {
            return;
        }
        if self
            .last_poll
            .is_some_and(|(at, _)| at.elapsed() < Duration::from_millis(self.profile.poll_ms))
        {
            return;
        }
        match self.poll() {
            Ok(m) => self.last_poll = Some((std::time::Instant::now(), m)),
            // Told by the next call (Finish, or any motion).
            Err(e) => self.deferred = Some(e),
        }
    }
}

impl std::fmt::Debug for RaplBackend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RaplBackend")
            .field("port", &self.port.name())
            .finish_non_exhaustive()
    }
}

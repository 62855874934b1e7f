//! The robot backend for an A465 on a MARS 8 (port `mars:DEVICE`, `trol gateway --controller
//! mars:DEVICE`; docs/mars.md).
//!
//! TROL plans every motion itself, with the simulated A465's planner (its limits, timing,
//! inverse kinematics and straight lines), and sends the plan as coordinated segments
//! (`COORDMVT:<ms>,<irc x6>`): one for a joint-interpolated motion, one per `segment_ms` of a
//! straight line. Nothing is taken on trust:
//!
//! - every batch of commands ends with `STAMP:n`, and only `STAMP=n` says the unit took them;
//!   a line nobody asked for is kept and makes the call TROL_ERR_ROBOT_UNSURE;
//! - before a motion the status word (`ST?`) must show no error, power and no motion stop,
//!   and every point of the plan must lie inside the profile's range;
//! - a motion has ended only when the unit says it stands still and `COORDAP?` puts every
//!   axis at the motion's end within `arrive_irc`; a unit that stops elsewhere fails Finish
//!   with BIOS_NOT_AT_TARGET, and a lost arm power, a motion stop or the error bit each with
//!   their code;
//! - first contact reads only; the regulator set-up is sent before the first Home or motion,
//!   and motions are refused until TROLHome has homed the arm (the unit's counters are
//!   incremental), unless the profile says `assume_homed`.

use std::collections::VecDeque;
use std::io;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use trol_a465::arm::{self, Arm, ArmSettings, Stored, code};
use trol_a465::backend::A465_CODES;
use trol_a465::model::joints_to_counts;
use trol_controller::real;
use trol_controller::{ArmReport, Backend, BackendError, BiosResult, PosMode, Target};
use trol_port::Port;
use trol_proto::application::{CodeInfo, CodeTable, Gripper, Held, LocName, Location, Tag};

use crate::line::{self, Lines, Reply, st};
use crate::profile::Profile;

mod bios;
mod completion;
mod exchange;
mod halt;
mod motion;

// The codes every real controller's backend shares (trol_a465::backend::real): arm power
// off (ST bit 0x10000), no gripper axis in the profile, a call that needs the arm at rest
// while a motion or homing has not ended, the unit stopped short of a motion's end.
pub use trol_a465::backend::real::{ARM_POWER, BUSY, NOT_AT_TARGET, UNSUPPORTED};
/// The unit reports an error (ST bit 0x8).
pub const MARS_ERROR: i16 = -20;
/// The motion stop is active (ST bit 0x20000).
pub const MOTION_STOP: i16 = -21;

/// The BIOS codes of the MARS 8 backend: the simulator's, and those of the unit.
pub static MARS_CODES: &CodeTable = &{
    const EXTRA: [CodeInfo; 6] = [
        CodeInfo {
            value: ARM_POWER,
            name: "BIOS_ARM_POWER",
            meaning: "arm power is off: switch it on, then TROLHome",
        },
        CodeInfo {
            value: UNSUPPORTED,
            name: "BIOS_UNSUPPORTED",
            meaning: "the arm profile names no gripper axis",
        },
        CodeInfo {
            value: BUSY,
            name: "BIOS_BUSY",
            meaning: "a homing or motion has not ended: call TROLFinish(FINISH_WAIT) first",
        },
        CodeInfo {
            value: MARS_ERROR,
            name: "BIOS_MARS_ERROR",
            meaning: "the MARS 8 reports an error (status bit 0x8): TROLHome clears it and homes again",
        },
        CodeInfo {
            value: MOTION_STOP,
            name: "BIOS_MOTION_STOP",
            meaning: "the motion stop is active: release it, then call again",
        },
        CodeInfo {
            value: NOT_AT_TARGET,
            name: "BIOS_NOT_AT_TARGET",
            meaning: "the unit stopped with the arm short of the motion's end",
        },
    ];
    trol_a465::backend::with_a465_codes::<{ A465_CODES.len() + EXTRA.len() }>(&EXTRA)
};

/// How long a reply may take (a command at 19200 baud takes a few ms).
pub const REPLY_LIMIT: Duration = Duration::from_secs(2);
/// The longest one homing group may take to be seen at its home mark (assumption: CTU's
/// whole hard home of an A465 takes about 17 s).
pub const HOMING_GROUP_LIMIT: Duration = Duration::from_secs(30);
/// How long a stop may take to show on the unit: the A465's longest braking (0.4 s) and a
/// margin for the reads.
pub const STOP_WITHIN: Duration = Duration::from_millis(900);
pub use trol_controller::real::{STILL_DEG, STILL_GAP};
/// The longest a Halt takes, both its stops included (within the reply time).
pub const HALT_WITHIN: Duration = Duration::from_millis(2100);
/// The unit's parameter for how smoothly segments join (ctu-crs sends 5).
pub const DISCONT: u32 = 5;

/// Why a session could not be opened.
#[derive(Debug, thiserror::Error)]
pub enum MarsError {
    /// The line failed.
    #[error("the line to the MARS 8 failed: {0}")]
    Io(#[from] io::Error),
    /// Nothing answered STAMP.
    #[error(
        "no MARS 8 answers on {port}: STAMP:{stamp} got no STAMP={stamp} within {limit:?}. \
         Check the cable (RTS/CTS wired), the baud rate ({baud}) and that the unit is on"
    )]
    NoUnit {
        /// The port.
        port: String,
        /// The stamp sent.
        stamp: u16,
        /// The profile's baud rate.
        baud: u32,
        /// The wait.
        limit: Duration,
    },
}

/// Every byte both ways, for a transcript (the shared core's).
pub use trol_controller::real::Transcript;

/// A transcript shared with the caller.
pub type Recorder = Arc<Mutex<Transcript>>;
/// Where the unit's texts go.
pub type LogFn = Box<dyn FnMut(&str) + Send>;

#[derive(Clone, Debug)]
struct Outstanding {
    /// Its end, IRC.
    target: [f64; 6],
    /// Its end, look by look (the shared rule: the moving bit, `COORDAP?`, the planned end).
    watch: real::EndWatch,
    /// From its sending: the plan's time, the settle time and [`END_MARGIN`].
    give_up: Duration,
}

/// How long past its planned end and the settle time a motion whose end is neither seen
/// nor ruled out (the moving bit clear, the arm neither at the end nor standing) is looked
/// for before it is given up as unsure. Assumed: the unit's own speeds govern its motions,
/// and TROL's plan may be several times shorter than the unit's (issue 43, item 5).
pub const END_MARGIN: Duration = Duration::from_secs(20);

#[derive(Clone, Debug)]
struct Homing {
    groups: VecDeque<String>,
    /// The group under way (its axis letters) and when it was sent.
    group: String,
    since: f64,
    /// The last `COORDAP?` that put the group's axes at their home mark.
    at_mark: Option<[f64; 6]>,
    axes: Vec<usize>,
    then_pose: bool,
}

#[derive(Clone, Debug)]
struct GripWait {
    target: f64,
    last: Option<(f64, f64)>,
    release_after: bool,
}

enum Fail {
    Io(io::Error),
    Silent(String),
}

impl Fail {
    fn text(&self) -> String {
        match self {
            Fail::Io(e) => format!("the line failed: {e}"),
            Fail::Silent(what) => format!("no answer to {what} within {REPLY_LIMIT:?}"),
        }
    }
    fn not_run(&self) -> BackendError {
        BackendError::Link(self.text())
    }
    fn unsure(&self) -> BackendError {
        BackendError::Unsure(self.text())
    }
}

/// The MARS 8 backend.
pub struct MarsBackend {
    port: Box<dyn Port>,
    lines: Lines,
    rx: VecDeque<String>,
    profile: Profile,
    planner: Arm,
    epoch: Instant,
    stamp: u16,
    set_up: bool,
    homed: [bool; 6],
    /// A Home was halted on the way: the next Finish fails with BIOS_NOT_HOMED.
    homing_halted: bool,
    unasked: Vec<String>,
    pending: VecDeque<String>,
    motion: Option<Outstanding>,
    homing: Option<Homing>,
    gripper: Option<GripWait>,
    version: String,
    tool: [f64; 6],
    log: Option<LogFn>,
    record: Option<Recorder>,
    /// The locations file TROLSaveLocations writes (docs/teach.md).
    locations_file: Option<std::path::PathBuf>,
    /// The arm seen standing at its last motion's end, which may stand in for the reads
    /// before the next motion ([`SEEN_FOR`]; shorter in tests).
    seen: real::Recent<AtEnd>,
    /// `COORDISCONT:` was sent, and since then only segments and reads: the unit still has
    /// it, and the next motion does not send it again (issue 43). Any other line (a stop,
    /// a purge, a home, the set-up, the gripper) and anything unasked make it go again.
    discont_set: bool,
}

/// How long the arm seen standing at its motion's end stands in for the reads before the
/// next motion (issue 43; the rule is [`real::Recent`]'s, shared by every real controller).
/// On a MARS 8 it stands in for the status word (its moving bit clear, no fault) and
/// COORDAP? (where the planner starts). Only queries and STAMP exchanges are reads: any other
/// line and anything printed unasked forget it. A motion sent on it to a unit that lost power
/// or had its motion stop pressed meanwhile is caught by the `ST?` read right after the
/// motion's lines, as every motion's is: refused with the fault's code, never a success.
pub use trol_controller::real::SEEN_FOR;

/// What was seen at a motion's end ([`SEEN_FOR`]).
#[derive(Clone, Copy, Debug)]
struct AtEnd {
    /// The status word, moving bit clear and no fault.
    status: u32,
    /// COORDAP?: the counters, IRC.
    counters: [f64; 6],
}

impl MarsBackend {
    /// The locations file the table came from, which TROLSaveLocations writes back.
    pub fn set_locations_file(&mut self, file: Option<std::path::PathBuf>) {
        self.locations_file = file;
    }

    /// Open a session on `port`: read what the unit printed at power-up, `ECHO:0`, a STAMP
    /// exchange, `VER?`, `ST?` and `COORDAP?`. Nothing that moves, nothing that sets up.
    pub fn connect(
        port: Box<dyn Port>,
        profile: Profile,
        log: Option<LogFn>,
        record: Option<Recorder>,
        locations: Vec<(String, Stored)>,
    ) -> Result<MarsBackend, MarsError> {
        let name = port.name();
        let homed = [profile.assume_homed; 6];
        // The unit holds each axis to its REGMS: planned at those speeds, a motion's time is
        // the arm's (issue 43). Accelerations stay the model's: REGACC's unit is not settled
        // by the public sources, and the unit (and its twin) accelerate at least as fast.
        let mut planner = Arm::new(ArmSettings {
            homed: profile.assume_homed,
            joint_speeds: Some(profile.top_speeds()),
            ..ArmSettings::default()
        });
        for (n, l) in locations {
            planner.set_location(&n, l);
        }
        let mut b = MarsBackend {
            port,
            lines: Lines::default(),
            rx: VecDeque::new(),
            profile,
            planner,
            epoch: Instant::now(),
            stamp: (std::process::id() & 0x3fff) as u16,
            set_up: false,
            homed,
            homing_halted: false,
            unasked: Vec::new(),
            pending: VecDeque::new(),
            motion: None,
            homing: None,
            gripper: None,
            version: String::new(),
            tool: [0.0; 6],
            log,
            record,
            locations_file: None,
            seen: real::Recent::new(),
            discont_set: false,
        };
        // Power-up noise: read and drop what is there.
        let mut buf = [0u8; 256];
        let until = Instant::now() + Duration::from_millis(50);
        while let Ok(n) = b.port.recv(&mut buf, until) {
            if n == 0 {
                break;
            }
            b.note(false, &buf[..n]);
        }
        b.lines.clear();
        b.send(b"\nECHO:0\n")?;
        match b.sync() {
            Ok(()) => {}
            Err(Fail::Io(e)) => return Err(MarsError::Io(e)),
            Err(Fail::Silent(_)) => {
                return Err(MarsError::NoUnit {
                    port: name,
                    stamp: b.stamp,
                    baud: b.profile.baud,
                    limit: REPLY_LIMIT,
                });
            }
        }
        // Echoes and noise before the stamp are not the unit's answers to anything.
        b.unasked.clear();
        let fail = |f: Fail| match f {
            Fail::Io(e) => MarsError::Io(e),
            Fail::Silent(what) => MarsError::Io(io::Error::new(
                io::ErrorKind::TimedOut,
                format!("no answer to {what}"),
            )),
        };
        b.version = b.query("VER").map_err(fail)?;
        b.status().map_err(fail)?;
        let q = b.actual().map_err(fail)?;
        b.planner.place(q);
        Ok(b)
    }

    /// What `VER?` answered.
    pub fn version(&self) -> &str {
        &self.version
    }

    /// The arm profile.
    pub fn profile(&self) -> &Profile {
        &self.profile
    }
}

impl std::fmt::Debug for MarsBackend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MarsBackend")
            .field("port", &self.port.name())
            .finish_non_exhaustive()
    }
}

#[cfg(test)]
mod tests;

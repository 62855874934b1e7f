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
/// Lines sent between two checks of the queue-full bit.
const CHECK_EVERY: usize = 8;

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

/// Every byte both ways, for a transcript.
#[derive(Debug, Default)]
pub struct Transcript {
    /// `(sent, bytes)` in order.
    pub chunks: Vec<(bool, Vec<u8>)>,
}

impl Transcript {
    /// The transcript as text: `> ` for what TROL sent, `< ` for what it read.
    pub fn text(&self) -> String {
        let mut s = String::new();
        for (sent, b) in &self.chunks {
            s.push_str(if *sent { "> " } else { "< " });
            s.push_str(&line::text(b));
            s.push('\n');
        }
        s
    }
}

/// A transcript shared with the caller.
pub type Recorder = Arc<Mutex<Transcript>>;
/// Where the unit's texts go.
pub type LogFn = Box<dyn FnMut(&str) + Send>;

#[derive(Clone, Debug)]
struct Outstanding {
    target: [f64; 6],
    end: f64,
    /// The unit's moving bit was seen up since the motion was sent.
    seen_moving: bool,
}

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

    fn say(&mut self, text: &str) {
        if let Some(l) = &mut self.log {
            l(text);
        }
    }

    fn note(&mut self, sent: bool, bytes: &[u8]) {
        if let Some(r) = &self.record {
            if let Ok(mut t) = r.lock() {
                t.chunks.push((sent, bytes.to_vec()));
            }
        }
    }

    fn now(&self) -> f64 {
        self.epoch.elapsed().as_secs_f64()
    }

    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.note(true, bytes);
        self.port.send(bytes)
    }

    /// The next line, waiting until `deadline`.
    fn next_line(&mut self, deadline: Instant) -> Result<Option<String>, Fail> {
        loop {
            if let Some(l) = self.rx.pop_front() {
                return Ok(Some(l));
            }
            let mut buf = [0u8; 256];
            let n = self.port.recv(&mut buf, deadline).map_err(Fail::Io)?;
            if n == 0 {
                return Ok(None);
            }
            self.note(false, &buf[..n]);
            let got = self.lines.feed(&buf[..n]);
            self.rx.extend(got);
        }
    }

    /// Read lines until one `want`s; the others are kept as unasked.
    fn await_reply(&mut self, what: &str, want: impl Fn(&Reply) -> bool) -> Result<Reply, Fail> {
        let deadline = Instant::now() + REPLY_LIMIT;
        loop {
            match self.next_line(deadline)? {
                None => return Err(Fail::Silent(what.to_string())),
                Some(l) => {
                    let r = line::parse(&l);
                    if want(&r) {
                        return Ok(r);
                    }
                    self.say(&format!("unasked: {l}"));
                    self.unasked.push(l);
                }
            }
        }
    }

    fn sync(&mut self) -> Result<(), Fail> {
        self.stamp = (self.stamp + 1) & 0x7fff;
        let s = self.stamp.to_string();
        self.send(format!("STAMP:{s}\n").as_bytes())
            .map_err(Fail::Io)?;
        let what = format!("STAMP:{s}");
        self.await_reply(
            &what,
            |r| matches!(r, Reply::Value { name, value } if name == "STAMP" && *value == s),
        )?;
        Ok(())
    }

    fn query(&mut self, q: &str) -> Result<String, Fail> {
        self.send(&line::query(q)).map_err(Fail::Io)?;
        match self.await_reply(
            &format!("{q}?"),
            |r| matches!(r, Reply::Value { name, .. } if name == q),
        )? {
            Reply::Value { value, .. } => Ok(value),
            _ => unreachable!("await_reply returns what it wants"),
        }
    }

    fn status(&mut self) -> Result<u32, Fail> {
        let v = self.query("ST")?;
        v.parse::<u32>()
            .map_err(|_| Fail::Silent(format!("ST? (it answered `ST={v}`, not a number)")))
    }

    fn counters(&mut self) -> Result<[f64; 6], Fail> {
        let v = self.query("COORDAP")?;
        line::coordap(&v).map_err(Fail::Silent)
    }

    fn actual(&mut self) -> Result<[f64; 6], Fail> {
        let c = self.counters()?;
        Ok(self.profile.irc_to_joints(&c))
    }

    /// Lines the unit printed unasked since the last call: TROL cannot tell what they mean
    /// for the arm, so the call is UNSURE and sends nothing.
    fn take_unasked(&mut self) -> Result<(), BackendError> {
        // What has arrived meanwhile.
        let _ = self.drain();
        if self.unasked.is_empty() {
            return Ok(());
        }
        let text = std::mem::take(&mut self.unasked).join(" | ");
        self.pending.clear();
        Err(BackendError::Unsure(format!(
            "the MARS 8 printed what TROL did not ask for: {text}"
        )))
    }

    fn drain(&mut self) -> Result<(), Fail> {
        while let Some(l) = self.next_line(Instant::now())? {
            self.say(&format!("unasked: {l}"));
            self.unasked.push(l);
        }
        Ok(())
    }

    /// The status word's faults as a code.
    fn fault(s: u32) -> Option<i16> {
        if s & st::POWER_OFF != 0 {
            Some(ARM_POWER)
        } else if s & st::MOTION_STOP != 0 {
            Some(MOTION_STOP)
        } else if s & st::ERROR != 0 {
            Some(MARS_ERROR)
        } else {
            None
        }
    }

    fn busy(&self) -> bool {
        self.motion.is_some() || self.homing.is_some() || !self.pending.is_empty()
    }

    fn set_up(&mut self) -> Result<(), BackendError> {
        if self.set_up {
            return Ok(());
        }
        let p = self.profile.clone();
        let r = &p.regulator;
        let mut l = Vec::new();
        for (word, v) in [
            ("REGME", r.me),
            ("REGCFG", r.cfg),
            ("REGP", r.p),
            ("REGI", r.i),
            ("REGD", r.d),
            ("REGMS", p.speed),
            ("REGACC", p.accel),
        ] {
            for (j, value) in v.iter().enumerate() {
                l.push(format!("{word}{}:{value}", p.axis(j)));
            }
        }
        l.push(format!("IDLEREL:{}", r.idlerel));
        if let Some(g) = &p.gripper {
            // ctu-crs's gripper set-up.
            let a = &g.axis;
            for c in [
                format!("ANAXSETUP{a}:10,16"),
                format!("REGS1{a}:16"),
                format!("REGS2{a}:500"),
                format!("REGME{a}:10000"),
                format!("REGMS{a}:500"),
                format!("REGCFG{a}:256"),
                format!("REGP{a}:200"),
                format!("REGI{a}:0"),
                format!("REGD{a}:100"),
            ] {
                l.push(c);
            }
        }
        l.push("SPDTB:0,300".into());
        l.push(format!(
            "COORDGRP:{}",
            p.axes
                .chars()
                .map(String::from)
                .collect::<Vec<_>>()
                .join(",")
        ));
        let mut bytes = Vec::new();
        for c in l {
            bytes.extend(line::command(&c));
        }
        self.send(&bytes)
            .map_err(|e| BackendError::Unsure(e.to_string()))?;
        self.sync().map_err(|f| f.unsure())?;
        self.take_unasked()?;
        self.set_up = true;
        Ok(())
    }

    /// Send queued segment lines while the unit's queue has room (`room`: the status word
    /// was read a moment ago and showed room, so the first lines go without another look).
    fn pump_from(&mut self, room: bool) -> Result<(), Fail> {
        let mut sent = 0;
        while !self.pending.is_empty() {
            if sent % CHECK_EVERY == 0
                && !(room && sent == 0)
                && self.status()? & st::QUEUE_FULL != 0
            {
                break;
            }
            let l = self.pending.pop_front().expect("not empty");
            self.send(&line::command(&l)).map_err(Fail::Io)?;
            sent += 1;
        }
        if sent > 0 {
            self.sync()?;
        }
        Ok(())
    }

    /// [`MarsBackend::pump_from`] with a look at the unit's queue first.
    fn pump(&mut self) -> Result<(), Fail> {
        self.pump_from(false)
    }

    /// Halt as the arm shows it (issue 37; the rule is the shared one of
    /// [`trol_controller::real::halt`]): `STOP:`, and where the arm is not seen standing
    /// within [`STOP_WITHIN`], `PURGE:` (which resets the motors; the arm counts as not
    /// homed after it). Success only once the moving bit is clear and two `COORDAP?` reads
    /// [`STILL_GAP`] apart agree; otherwise TROL_ERR_NOT_STOPPED, and what was under way is
    /// kept, so that Finish goes on reporting the arm as the unit shows it.
    fn stop_and_see(&mut self) -> BiosResult {
        let times = real::HaltTimes {
            halt_within: HALT_WITHIN,
            stop_within: STOP_WITHIN,
        };
        match real::halt(&mut Stopper(self), &["STOP:", "PURGE:"], times) {
            real::Halted::Standing { note, .. } => {
                if let Some(note) = note {
                    self.say(&note);
                }
                self.abandon();
                Ok(code::OK)
            }
            real::Halted::NotStopped(text) => {
                self.say(&format!("Halt: the arm was not seen standing: {text}"));
                Err(BackendError::NotStopped(text))
            }
        }
    }

    /// Forget what was under way (after a fault or Halt) and take the arm as where it is.
    fn abandon(&mut self) {
        self.pending.clear();
        self.motion = None;
        self.homing = None;
        self.gripper = None;
        let now = self.now();
        self.planner.halt(now);
        if let Ok(q) = self.actual() {
            self.planner.place(q);
        }
    }

    /// Gate, plan with the planner, check the plan against the profile, send it, confirm.
    fn motion(&mut self, f: impl FnOnce(&mut Arm, f64) -> i16) -> BiosResult {
        self.take_unasked()?;
        if self.homing.is_some() {
            return Ok(BUSY);
        }
        let s = self.status().map_err(|f| f.not_run())?;
        if let Some(c) = Self::fault(s) {
            return Ok(c);
        }
        self.planner.set_homed(self.homed);
        let now = self.now();
        let busy_before = self.motion.is_some() || !self.pending.is_empty();
        if self.motion.is_none() && self.pending.is_empty() {
            if s & st::MOVING != 0 {
                // Moving, and not by TROL's doing: a pendant, or another program.
                return Ok(BUSY);
            }
            let q = self.actual().map_err(|f| f.not_run())?;
            self.planner.place(q);
        }
        let before = self.planner.clone();
        let c = f(&mut self.planner, now);
        if c != code::OK {
            self.planner = before;
            return Ok(c);
        }
        let Some((t0, t1, joint)) = self.planner.last_motion() else {
            return Ok(code::OK);
        };
        if before.last_motion() == Some((t0, t1, joint)) {
            // Nothing new was planned (a motion of no length).
            return Ok(code::OK);
        }
        let seg = self.profile.segment_ms as f64 / 1000.0;
        let n = if joint {
            1
        } else {
            ((t1 - t0) / seg).ceil().max(1.0) as usize
        };
        let mut lines = vec![format!("COORDISCONT:{DISCONT}")];
        let mut prev = t0;
        let mut last = [0.0; 6];
        for k in 1..=n {
            let t = t0 + (t1 - t0) * k as f64 / n as f64;
            let q = self.planner.planned_at(t);
            let irc = self.profile.joints_to_irc(&q).map(f64::round);
            if let Some(j) = self.profile.outside(&irc) {
                self.planner = before;
                self.say(&format!(
                    "refused: joint {} would leave the profile's range ({} IRC)",
                    j + 1,
                    irc[j]
                ));
                return Ok(code::JOINT_LIMIT);
            }
            let ms = ((t - prev) * 1000.0).round().max(1.0) as i64;
            lines.push(format!(
                "COORDMVT:{ms},{}",
                irc.map(|v| (v as i64).to_string()).join(",")
            ));
            prev = t;
            last = irc;
        }
        if let Err(e) = self.set_up() {
            self.planner = before;
            return Err(e);
        }
        self.pending.extend(lines);
        self.motion = Some(Outstanding {
            target: last,
            end: t1,
            seen_moving: false,
        });
        // The status word read above, before this motion, showed the unit's queue with room
        // and nothing of ours in it: no second look before the first lines (issue 43).
        let room = s & st::QUEUE_FULL == 0 && !busy_before;
        let confirmed = self
            .pump_from(room)
            .map_err(|f| f.unsure())
            .and_then(|()| self.take_unasked())
            .and_then(|()| self.status().map_err(|f| f.unsure()));
        match confirmed {
            Ok(s) => match Self::fault(s) {
                Some(c) => {
                    self.abandon();
                    Ok(c)
                }
                None => Ok(code::OK),
            },
            Err(e) => {
                // Whether the unit took it is not known: TROL keeps nothing of it, sends
                // nothing more of it, and the next motion starts from where the arm is
                // (refused as BUSY while the unit says it moves).
                self.pending.clear();
                self.motion = None;
                Err(e)
            }
        }
    }

    /// One look at a hard home: a group has homed only when the moving bit is clear and
    /// two `COORDAP?` reads in a row put each of its axes at its home mark (0 IRC of the homed
    /// frame, within `arrive_irc`), never on the moving bit alone (issue 37, item 6: a unit
    /// that does not raise the bit while homing had its next group sent while the first
    /// still homed). Then the next group goes; a group not seen home within
    /// [`HOMING_GROUP_LIMIT`] is a failure: `STOP:`, and nothing else is sent.
    fn homing_step(&mut self) -> Result<bool, BackendError> {
        let s = self.status().map_err(|f| f.not_run())?;
        if let Some(c) = Self::fault(s) {
            self.abandon();
            return Err(BackendError::Refused(c));
        }
        let now = self.now();
        let c = if s & st::MOVING == 0 {
            Some(self.counters().map_err(|f| f.not_run())?)
        } else {
            None
        };
        let tol = self.profile.arrive_irc;
        let letters = self.profile.axes.clone();
        let h = self.homing.as_mut().expect("homing");
        let group: Vec<usize> = h.group.chars().filter_map(|a| letters.find(a)).collect();
        let home = c.filter(|c| group.iter().all(|&j| c[j].abs() <= tol));
        match (home, h.at_mark) {
            (Some(c), Some(before)) if group.iter().all(|&j| (c[j] - before[j]).abs() <= tol) => {
                // The group is home and stands.
                h.at_mark = None;
                if let Some(g) = h.groups.pop_front() {
                    h.since = now;
                    h.group = g.clone();
                    self.send_hh(&g).map_err(|f| f.unsure())?;
                    return Ok(true);
                }
            }
            (home, _) => {
                h.at_mark = home;
                if now - h.since <= HOMING_GROUP_LIMIT.as_secs_f64() {
                    return Ok(true);
                }
                let g = h.group.clone();
                let _ = self.send(&line::command("STOP:"));
                self.abandon();
                let text = format!(
                    "homing group {g} was not seen at its home mark within {} s (COORDAP? {}): \
                     STOP: sent, nothing else; the arm is not homed",
                    HOMING_GROUP_LIMIT.as_secs(),
                    match c {
                        Some(c) => format!("{c:?}"),
                        None => "not read: the unit still showed the moving bit".into(),
                    }
                );
                self.say(&text);
                return Err(BackendError::Unsure(text));
            }
        }
        let h = self.homing.take().expect("homing");
        for a in &h.axes {
            self.homed[*a] = true;
        }
        self.planner.set_homed(self.homed);
        let q = self.actual().map_err(|f| f.not_run())?;
        self.planner.place(q);
        if h.then_pose {
            let pose = self.profile.home_pose_deg.map(f64::to_radians);
            match self.motion(|arm, now| arm.ma(pose, now))? {
                code::OK => return Ok(true),
                c => return Err(BackendError::Refused(c)),
            }
        }
        Ok(false)
    }

    fn send_hh(&mut self, group: &str) -> Result<(), Fail> {
        let mut bytes = Vec::new();
        for a in group.chars() {
            bytes.extend(line::command(&format!("HH{a}:")));
        }
        self.send(&bytes).map_err(Fail::Io)?;
        self.sync()
    }

    /// The gripper's axis letter (only called with a gripper in the profile).
    fn gripper_axis(&self) -> String {
        self.profile
            .gripper
            .as_ref()
            .map(|g| g.axis.clone())
            .unwrap_or_default()
    }

    /// The gripper's axis position (`AP<g>?`).
    /// The fingers' opening from the gripper axis' position and the profile's open and
    /// closed positions, mm.
    fn gripper_mm(&mut self, g: &crate::profile::Gripper) -> Result<f64, BackendError> {
        let p = self.read_gripper()?;
        Ok(
            ((p - g.closed) / (g.open - g.closed) * trol_a465::arm::FINGER_MAX)
                .clamp(0.0, trol_a465::arm::FINGER_MAX),
        )
    }

    fn read_gripper(&mut self) -> Result<f64, BackendError> {
        let axis = self.gripper_axis();
        let v = self.query(&format!("AP{axis}")).map_err(|f| f.not_run())?;
        v.parse()
            .map_err(|_| BackendError::Unsure(format!("AP{axis}={v}: not a number")))
    }

    /// Whether the fingers still move; `unit_moving`: the unit's moving bit now. The
    /// fingers have arrived only once they are at their target *and* the unit says nothing
    /// moves (it still drove them for a moment after they came within 10 units, and a
    /// motion sent then was refused BIOS_BUSY); or they stalled on an object.
    fn gripper_step(&mut self, unit_moving: bool) -> Result<bool, BackendError> {
        let Some(w) = self.gripper.clone() else {
            return Ok(false);
        };
        let axis = self.gripper_axis();
        let p = self.read_gripper()?;
        let now = self.now();
        let arrived = (p - w.target).abs() <= 10.0 && !unit_moving;
        let stalled = match w.last {
            Some((lp, lt)) if now - lt >= 0.2 => (p - lp).abs() < 50.0 * (now - lt) / 0.2,
            _ => false,
        };
        if !(arrived || stalled) {
            let g = self.gripper.as_mut().expect("gripper");
            if g.last.is_none_or(|(_, lt)| now - lt >= 0.2) {
                g.last = Some((p, now));
            }
            return Ok(true);
        }
        self.gripper = None;
        if w.release_after {
            // As ctu-crs does once the fingers closed: stop driving the motor.
            self.send(&line::command(&format!("RELEASE{axis}:")))
                .map_err(|e| BackendError::Unsure(e.to_string()))?;
            self.sync().map_err(|f| f.unsure())?;
        }
        Ok(false)
    }

    fn fingers(&mut self, mm: f64, closing: bool) -> BiosResult {
        self.take_unasked()?;
        let Some(pos) = self.profile.gripper_position(mm) else {
            return Ok(UNSUPPORTED);
        };
        let s = self.status().map_err(|f| f.not_run())?;
        if let Some(c) = Self::fault(s) {
            return Ok(c);
        }
        self.set_up()?;
        let axis = self.gripper_axis();
        let mut bytes = line::command(&format!("RELEASE{axis}:"));
        bytes.extend(line::command(&format!("G{axis}:{pos}")));
        self.send(&bytes)
            .map_err(|e| BackendError::Unsure(e.to_string()))?;
        self.sync().map_err(|f| f.unsure())?;
        self.take_unasked()?;
        let now = self.now();
        self.planner.grip(mm, now);
        self.gripper = Some(GripWait {
            target: pos,
            last: None,
            release_after: closing,
        });
        Ok(code::OK)
    }

    fn target(&self, t: &Target) -> Result<arm::Target, BackendError> {
        // A precision point given here is the unit's IRC counts (what GetPosition(POS_PREC)
        // answers); the arm model plans in the A465 controller's.
        if let Target::Location(Location::Prec(irc)) = t {
            let loc = Location::Prec(self.irc_to_a465(irc).to_vec());
            return trol_a465::backend::arm_target(&self.planner, &Target::Location(loc));
        }
        trol_a465::backend::arm_target(&self.planner, t)
    }

    /// The unit's IRC counts (missing ones 0) as the A465 controller's encoder counts, which
    /// the arm model and TROL's location table keep.
    fn irc_to_a465(&self, irc: &[i32]) -> [i32; 6] {
        let c: [f64; 6] = std::array::from_fn(|i| f64::from(irc.get(i).copied().unwrap_or(0)));
        joints_to_counts(&self.profile.irc_to_joints(&c))
    }

    /// The A465 controller's counts as the unit's IRC counts.
    fn a465_to_irc(&self, counts: &[i32]) -> Vec<i32> {
        let c: [f64; 6] = std::array::from_fn(|i| f64::from(counts.get(i).copied().unwrap_or(0)));
        let q = trol_a465::model::counts_to_joints(&c);
        self.profile
            .joints_to_irc(&q)
            .map(|v| v.round() as i32)
            .to_vec()
    }
}

impl Backend for MarsBackend {
    fn kind(&self) -> &'static str {
        "MARS 8"
    }
    fn codes(&self) -> &'static CodeTable {
        MARS_CODES
    }
    fn reply_time(&self) -> Duration {
        // The unit's silence is found out after REPLY_LIMIT; the rest of a call is line time.
        // A Halt that tries both stops takes as long.
        (REPLY_LIMIT + Duration::from_millis(500)).max(HALT_WITHIN + Duration::from_millis(400))
    }
    fn appro(&mut self, target: &Target, disp: [f64; 6], straight: bool) -> BiosResult {
        let t = self.target(target)?;
        self.motion(|a, now| a.appro(t, disp, straight, now))
    }
    fn close(&mut self, _force: u8) -> BiosResult {
        self.fingers(0.0, true)
    }
    fn depart(&mut self, disp: [f64; 6], straight: bool) -> BiosResult {
        self.motion(|a, now| a.depart(disp, straight, now))
    }
    fn moving(&mut self) -> Result<bool, BackendError> {
        if std::mem::take(&mut self.homing_halted) {
            return Err(BackendError::Refused(code::NOT_HOMED));
        }
        self.take_unasked()?;
        self.pump().map_err(|f| f.unsure())?;
        if self.homing.is_some() {
            return self.homing_step();
        }
        let s = self.status().map_err(|f| f.not_run())?;
        if let Some(c) = Self::fault(s) {
            if self.busy() || self.gripper.is_some() {
                self.abandon();
                return Err(BackendError::Refused(c));
            }
            return Ok(false);
        }
        let grip = self.gripper_step(s & st::MOVING != 0)?;
        let Some(m) = self.motion.clone() else {
            return Ok(grip);
        };
        if !self.pending.is_empty() || s & st::MOVING != 0 {
            if let Some(o) = self.motion.as_mut() {
                o.seen_moving |= s & st::MOVING != 0;
            }
            return Ok(true);
        }
        let c = self.counters().map_err(|f| f.not_run())?;
        let tol = self.profile.arrive_irc;
        // At the end within arrive_irc, once the moving bit was seen up and down again, or
        // (a motion too short to show it) not before the planned end: counters within the
        // tolerance before either are an arm still slowing down, and a unit whose moving bit
        // lags then showed it moving at the next call, which was refused BIOS_BUSY.
        if (m.seen_moving || self.now() >= m.end)
            && (0..6).all(|j| (c[j] - m.target[j]).abs() <= tol)
        {
            self.motion = None;
            let q = self.profile.irc_to_joints(&c);
            self.planner.place(q);
            return Ok(grip);
        }
        let settle = self.profile.settle_ms as f64 / 1000.0;
        if self.now() < m.end + settle {
            return Ok(true);
        }
        let far: Vec<String> = (0..6)
            .filter(|&j| (c[j] - m.target[j]).abs() > tol)
            .map(|j| format!("joint {} at {} IRC for {}", j + 1, c[j], m.target[j]))
            .collect();
        self.say(&format!("the unit stopped short: {}", far.join(", ")));
        self.abandon();
        Err(BackendError::Refused(NOT_AT_TARGET))
    }
    fn grip(&mut self, dist: u8) -> BiosResult {
        self.fingers(f64::from(dist), true)
    }
    fn halt(&mut self) -> BiosResult {
        self.pending.clear();
        let homing = self.homing.take();
        let r = self.stop_and_see();
        if let Some(h) = homing {
            if r.is_ok() {
                // A Home halted on the way: its axes are not homed, and the Finish after it
                // fails, once.
                for a in h.axes {
                    self.homed[a] = false;
                }
                self.planner.set_homed(self.homed);
                self.homing_halted = true;
            } else {
                // Not seen to stop: as far as TROL knows the unit still homes, and Finish
                // goes on following it.
                self.homing = Some(h);
            }
        }
        r
    }
    fn stands(&mut self) -> Result<bool, BackendError> {
        // halt() answers success only once it has seen the arm standing.
        Ok(true)
    }
    fn home(&mut self, axis: u8) -> BiosResult {
        self.take_unasked()?;
        if axis > 6 {
            return Ok(code::BAD_ARGUMENT);
        }
        if self.busy() {
            return Ok(BUSY);
        }
        let s = self.status().map_err(|f| f.not_run())?;
        if s & st::POWER_OFF != 0 {
            return Ok(ARM_POWER);
        }
        if s & st::MOTION_STOP != 0 {
            return Ok(MOTION_STOP);
        }
        if s & st::MOVING != 0 {
            return Ok(BUSY);
        }
        // PURGE: clears the unit's errors (ctu-crs's initialize() sends it first).
        self.send(&line::command("PURGE:"))
            .map_err(|e| BackendError::Link(e.to_string()))?;
        self.set_up = false;
        self.set_up()?;
        let mut groups: VecDeque<String> = if axis == 0 {
            self.profile.hh_sequence.iter().cloned().collect()
        } else {
            VecDeque::from([self.profile.axis(axis as usize - 1).to_string()])
        };
        let axes: Vec<usize> = if axis == 0 {
            (0..6).collect()
        } else {
            vec![axis as usize - 1]
        };
        for &a in &axes {
            self.homed[a] = false;
        }
        self.planner.set_homed(self.homed);
        let first = groups.pop_front().expect("a group");
        self.send_hh(&first).map_err(|f| f.unsure())?;
        self.take_unasked()?;
        self.homing = Some(Homing {
            groups,
            group: first,
            since: self.now(),
            at_mark: None,
            axes,
            then_pose: axis == 0,
        });
        Ok(code::OK)
    }
    fn jog(&mut self, d: [f64; 3], straight: bool) -> BiosResult {
        self.motion(|a, now| a.jog(d, straight, now))
    }
    fn joint(&mut self, joint: u8, radians: f64) -> BiosResult {
        self.motion(|a, now| a.joint(joint, radians, now))
    }
    fn ma(&mut self, q: [f64; 6]) -> BiosResult {
        self.motion(|a, now| a.ma(q, now))
    }
    fn mi(&mut self, dq: [f64; 6]) -> BiosResult {
        self.motion(|a, now| a.mi(dq, now))
    }
    fn move_to(&mut self, target: &Target, straight: bool) -> BiosResult {
        let t = self.target(target)?;
        self.motion(|a, now| a.move_to(t, straight, now))
    }
    fn open(&mut self, _force: u8) -> BiosResult {
        self.fingers(arm::FINGER_MAX, false)
    }
    fn ready(&mut self) -> BiosResult {
        self.motion(|a, now| a.ready(now))
    }
    fn set_tool(&mut self, tool: [f64; 6]) -> BiosResult {
        self.tool = tool;
        Ok(self.planner.set_tool(tool))
    }
    fn speed(&mut self, percent: u8) -> BiosResult {
        Ok(self.planner.set_speed(f64::from(percent)))
    }
    fn define(&mut self, name: LocName, loc: &Location) -> BiosResult {
        let loc = match loc {
            Location::Prec(irc) => Location::Prec(self.irc_to_a465(irc).to_vec()),
            other => other.clone(),
        };
        trol_a465::backend::table::define(&mut self.planner, name, &loc)
    }
    fn delete_location(&mut self, name: LocName) -> BiosResult {
        trol_a465::backend::table::delete(&mut self.planner, name)
    }
    fn locations(&mut self) -> Result<Vec<(LocName, Location)>, BackendError> {
        Ok(trol_a465::backend::table::list(&self.planner)
            .into_iter()
            .map(|(n, l)| match l {
                Location::Prec(c) => (n, Location::Prec(self.a465_to_irc(&c))),
                other => (n, other),
            })
            .collect())
    }
    fn save_locations(&mut self) -> BiosResult {
        trol_a465::backend::table::save(&self.planner, self.locations_file.as_deref())
    }
    fn take_note(&mut self) -> Option<String> {
        self.planner.take_refusal()
    }
    fn position(&mut self, tag: Tag, mode: PosMode) -> Result<Location, BackendError> {
        let q = match mode {
            PosMode::Commanded => {
                let now = self.now();
                self.planner.commanded(now)
            }
            PosMode::Actual => self.actual().map_err(|f| f.not_run())?,
        };
        Ok(match tag {
            Tag::Joint => Location::from_array6(Tag::Joint, q),
            // The unit's own counts (the A465 controller's were answered before, which a
            // MARS 8 has none of).
            Tag::Prec => Location::Prec(
                self.profile
                    .joints_to_irc(&q)
                    .map(|v| v.round() as i32)
                    .to_vec(),
            ),
            Tag::Cart => Location::from_array6(Tag::Cart, self.planner.kinematics().fk_xyzypr(&q)),
        })
    }
    fn gripper(&mut self) -> Result<Gripper, BackendError> {
        let Some(g) = self.profile.gripper.clone() else {
            return Err(BackendError::Unsupported(
                "read a gripper: the arm profile names none ([gripper])",
            ));
        };
        // The unit reads the gripper axis' position, not what is between the fingers.
        Ok(Gripper {
            opening_mm: self.gripper_mm(&g)?,
            held: Held::Unknown,
        })
    }
    fn idle(&mut self) {
        if !self.pending.is_empty() {
            let _ = self.pump();
        }
    }
    fn report(&mut self) -> Option<ArmReport> {
        // Read-only: ST?, COORDAP? and the gripper's AP<g>?. A line the unit printed unasked
        // stays kept for the next call.
        let s = self.status().ok()?;
        let c = self.counters().ok()?;
        let gripper_mm = match self.profile.gripper.clone() {
            Some(g) => Some(self.gripper_mm(&g).ok()?),
            None => None,
        };
        Some(ArmReport {
            joints: self.profile.irc_to_joints(&c),
            moving: s & st::MOVING != 0 || self.busy(),
            target: self
                .motion
                .as_ref()
                .map(|m| self.profile.irc_to_joints(&m.target)),
            gripper_mm,
            tool: self.tool,
            // The counters of an axis not homed mean nothing yet: the view says so (issue
            // 38: it showed their values, and the last report while the arm homed again).
            homed: Some(self.homed),
        })
    }
}

impl std::fmt::Debug for MarsBackend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MarsBackend")
            .field("port", &self.port.name())
            .finish_non_exhaustive()
    }
}

/// The MARS 8's side of the shared Halt ([`trol_controller::real`]): `STOP:` and `PURGE:`,
/// each confirmed by `STAMP`; the status word's moving bit and `COORDAP?` (IRC) as the
/// reading.
struct Stopper<'a>(&'a mut MarsBackend);

impl real::Stopping for Stopper<'_> {
    type Stop = &'static str;
    fn stop_name(&self, stop: &'static str) -> String {
        stop.into()
    }
    fn send_stop(&mut self, stop: &'static str) -> Result<String, String> {
        let b = &mut *self.0;
        b.send(&line::command(stop))
            .map_err(|e| format!("not sent: {e}"))?;
        if stop == "PURGE:" {
            // The motors were reset: the regulator set-up goes again, and the arm is homed
            // again before it moves.
            b.set_up = false;
            b.homed = [false; 6];
            b.planner.set_homed(b.homed);
            b.say("Halt: PURGE: sent; the arm must be homed again (TROLHome)");
        }
        b.sync().map(|_| "taken".to_string()).map_err(|f| f.text())
    }
    fn reading(&mut self) -> Result<Option<[f64; 6]>, String> {
        let b = &mut *self.0;
        if b.status().map_err(|f| f.text())? & st::MOVING != 0 {
            return Ok(None);
        }
        b.counters().map(Some).map_err(|f| f.text())
    }
    fn still_within(&self) -> [f64; 6] {
        let p = &self.0.profile;
        std::array::from_fn(|j| (STILL_DEG * p.irc_per_deg(j)).abs().max(2.0))
    }
    fn now(&self) -> Instant {
        Instant::now()
    }
    fn pause(&mut self, d: Duration) {
        std::thread::sleep(d);
    }
}

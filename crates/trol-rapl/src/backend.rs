//! The RAPL-II backend: the PCP server's robot backend ([`trol_controller::Backend`]) on a
//! real C500, over a port (c500-rapl.md §1.4 has the command table this follows).
//!
//! - Move and Appro by name use the controller's own location table (LISTL first, so an
//!   unknown name is TROL_ERR_LOCATION whatever the controller's error numbers);
//! - MoveII, ApproII, Depart, Jog off the straight line and SetToolTransform are computed on
//!   the PC with the A465 kinematics (trol-a465) and sent as POINT plus MOVE/MOVES or TOOL;
//!   a joint target goes as a precision point (pulses), so no angle unit is guessed;
//! - GetPosition reads W0 (commanded) or W2 (actual) in every form;
//! - the end of a motion is polled (STATUS's DONE row by default), so between polls the line
//!   is free for Halt;
//! - error lines map onto BIOS codes through the profile, their raw text logged;
//! - a failure of the line is TROL_ERR_ROBOT when the line was cancelled before its
//!   terminator (the command did not run), TROL_ERR_ROBOT_UNSURE after it.

use std::collections::VecDeque;
use std::io;
use std::time::Duration;

use trol_a465::kinematics::{Kinematics, Pose};
use trol_a465::model::{counts_to_joints, joints_to_counts};
use trol_controller::backend::{Backend, BackendError, BiosResult, PosMode, Target};
use trol_controller::sim::SIM_CODES;
use trol_port::Port;
use trol_proto::application::{CodeInfo, CodeTable, LocName, Location, Tag};
use trol_proto::time::Instant;

use crate::aci::{AciError, Master};
use crate::frames::{Frames, Unsettled};
use crate::profile::{Completion, Entry, Halt, JointUnits, Profile, Units};
use crate::session::{CTRL_Z, Reply, Session, SessionConfig, SessionError};
use crate::text::{self, Listed};

/// The arm has no power (LIMP, an e-stop).
pub const ARM_POWER: i16 = -8;
/// Cartesian values need the controller's angle order.
pub const NO_ANGLES: i16 = -9;
/// An error line the profile does not map.
pub const RAPL_ERROR: i16 = -10;
/// No RAPL-II form for the call.
pub const UNSUPPORTED: i16 = -11;
/// MA and MI need their units.
pub const NO_JOINT_UNITS: i16 = -12;
/// Cartesian values need the controller's length units.
pub const NO_UNITS: i16 = -13;

/// The BIOS codes of the RAPL-II backend: the simulator's, and those of a real controller.
pub static RAPL_CODES: &CodeTable = &{
    const EXTRA: [CodeInfo; 6] = [
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
            meaning: "RAPL-II has no form for this call (homing one axis: use TROLHome(0))",
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
    ];
    let mut all = [EXTRA[0]; 14];
    let mut i = 0;
    while i < 8 {
        all[i] = SIM_CODES[i];
        i += 1;
    }
    while i < 14 {
        all[i] = EXTRA[i - 8];
        i += 1;
    }
    all
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

/// What an error line means.
enum Meaning {
    Code(i16),
    Location,
}

/// The RAPL-II backend over a port.
pub struct RaplBackend {
    port: Box<dyn Port>,
    session: Session,
    profile: Profile,
    frames: Frames,
    joint_units: Option<JointUnits>,
    epoch: std::time::Instant,
    tool: [f64; 6],
    last_poll: Option<(std::time::Instant, bool)>,
    log: VecDeque<String>,
    log_fn: Option<LogFn>,
    transcript: Option<Transcript>,
    status: Option<text::Status>,
    closed: bool,
}

const LOG_KEEP: usize = 200;

impl RaplBackend {
    /// Open a session on `port` as `profile` says: the ACI steps (falling back to Ctrl-C if
    /// the port is in terminal mode already), NOHELP, STATUS.
    pub fn connect(port: Box<dyn Port>, profile: Profile) -> Result<RaplBackend, RaplError> {
        RaplBackend::connect_with(port, profile, None, false)
    }

    /// Like [`RaplBackend::connect`], logging each line to `log_fn` and, with `record`,
    /// keeping a transcript of every byte.
    pub fn connect_with(
        port: Box<dyn Port>,
        profile: Profile,
        log_fn: Option<LogFn>,
        record: bool,
    ) -> Result<RaplBackend, RaplError> {
        let frames = Frames {
            mm: profile.units.mm(),
            angles: profile.angles(),
        };
        let mut b = RaplBackend {
            port,
            session: Session::new(SessionConfig::from(&profile)),
            joint_units: profile.joint_units().ok().flatten(),
            frames,
            profile,
            epoch: std::time::Instant::now(),
            tool: [0.0; 6],
            last_poll: None,
            log: VecDeque::new(),
            log_fn,
            transcript: record.then(Transcript::default),
            status: None,
            closed: false,
        };
        b.open()?;
        Ok(b)
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

    /// The transcript, when recording.
    pub fn transcript(&self) -> Option<&Transcript> {
        self.transcript.as_ref()
    }

    /// The profile the session was opened with.
    pub fn profile(&self) -> &Profile {
        &self.profile
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

    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        let t = self.secs();
        if let Some(tr) = self.transcript.as_mut() {
            tr.add(t, Dir::ToController, bytes);
        }
        self.port.send(bytes)
    }

    fn recv(&mut self, until: std::time::Instant) -> io::Result<Vec<u8>> {
        let mut buf = [0u8; 512];
        let n = self.port.recv(&mut buf, until)?;
        let t = self.secs();
        if n > 0 {
            if let Some(tr) = self.transcript.as_mut() {
                tr.add(t, Dir::FromController, &buf[..n]);
            }
        }
        Ok(buf[..n].to_vec())
    }

    fn at(&self, t: Instant) -> std::time::Instant {
        self.epoch + t.since_epoch()
    }

    /// Run the session until its next event.
    fn pump(&mut self) -> io::Result<Result<Reply, SessionError>> {
        loop {
            let now = self.now();
            while let Some(b) = self.session.poll_transmit(now) {
                self.send(&[b])?;
            }
            if let Some(ev) = self.session.poll_event() {
                return Ok(ev);
            }
            let wake = self
                .session
                .next_timeout()
                .map(|t| self.at(t))
                .unwrap_or_else(|| std::time::Instant::now() + Duration::from_millis(50))
                .min(std::time::Instant::now() + Duration::from_millis(50));
            let got = self.recv(wake)?;
            let now = self.now();
            if !got.is_empty() {
                self.session.feed(&got, now);
            }
            self.session.handle_timeout(now);
            if self.session.is_lost() {
                if let Some(ev) = self.session.poll_event() {
                    return Ok(ev);
                }
            }
        }
    }

    /// Drop what arrived unasked; if anything did, or the session was lost, resynchronise.
    fn settle(&mut self) -> Result<(), BackendError> {
        while self.port.available().map_err(|e| link(&e))? > 0 {
            let got = self.recv(std::time::Instant::now()).map_err(|e| link(&e))?;
            let now = self.now();
            self.session.feed(&got, now);
        }
        let stray = self.session.take_stray();
        if !stray.is_empty() || self.session.is_lost() {
            if !stray.is_empty() {
                self.note(format!(
                    "unasked bytes from the C500 dropped: {:?}; resynchronising",
                    String::from_utf8_lossy(&stray)
                ));
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

    /// Type a line and read its reply.
    fn exchange(&mut self, line: &str, timeout: Duration) -> Result<Reply, BackendError> {
        if self.closed {
            return Err(BackendError::Link(format!(
                "`{line}` not sent: the RAPL-II session is closed"
            )));
        }
        self.settle()?;
        let now = self.now();
        self.session
            .send_line(line, timeout, now)
            .map_err(|e| BackendError::Link(e.to_string()))?;
        match self.pump() {
            Ok(Ok(r)) => Ok(r),
            Ok(Err(e)) => {
                self.note(format!("`{line}`: {e}"));
                Err(if e.surely_not_run() {
                    BackendError::Link(e.to_string())
                } else {
                    BackendError::Unsure(e.to_string())
                })
            }
            Err(e) => Err(BackendError::Unsure(format!("`{line}`: {e}"))),
        }
    }

    fn reply_timeout(&self) -> Duration {
        Duration::from_millis(self.profile.reply_timeout_ms)
    }

    fn motion_timeout(&self) -> Duration {
        Duration::from_secs(self.profile.motion_timeout_s)
    }

    fn meaning(&self, number: u16) -> Meaning {
        match self.profile.error_target(number) {
            Some("TROL_ERR_LOCATION") => Meaning::Location,
            Some(name) => Meaning::Code(
                RAPL_CODES
                    .iter()
                    .find(|c| c.name == name)
                    .map(|c| c.value)
                    .unwrap_or(RAPL_ERROR),
            ),
            None => Meaning::Code(RAPL_ERROR),
        }
    }

    /// A command whose answer is ACK or an error line; `name` is the location it names.
    fn command(&mut self, line: &str, timeout: Duration, name: Option<LocName>) -> BiosResult {
        let r = self.exchange(line, timeout)?;
        match r.error {
            None => Ok(0),
            Some((n, t)) => {
                self.note(format!("`{line}` refused: {n:03}-{t}."));
                match (self.meaning(n), name) {
                    (Meaning::Location, Some(name)) => Err(BackendError::UnknownLocation(name)),
                    (Meaning::Location, None) => Ok(code_of("BIOS_BAD_ARGUMENT")),
                    (Meaning::Code(c), _) => Ok(c),
                }
            }
        }
    }

    fn motion(&mut self, line: &str, name: Option<LocName>) -> BiosResult {
        let timeout = self.motion_timeout();
        let r = self.command(line, timeout, name)?;
        if r == 0 {
            self.last_poll = None;
        }
        Ok(r)
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
        let r = self.pump()??;
        if r.error.is_some() {
            let now = self.now();
            self.session
                .send_line("NOHELP", self.reply_timeout(), now)?;
            self.pump()??;
        }
        let st = self
            .exchange("STATUS", self.reply_timeout())
            .map_err(|e| RaplError::Status(e.to_string()))?;
        let status = text::read_status(&st.text).map_err(RaplError::Status)?;
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
        self.note(format!(
            "session open: {}; units {}",
            status.version,
            match self.frames.mm {
                Some(1.0) => "mm",
                Some(_) => "inch",
                None => "unknown (cartesian commands refused)",
            }
        ));
        self.status = Some(status);
        Ok(())
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
    /// dropping the backend, send nothing more.
    pub fn close(&mut self) {
        if self.closed {
            return;
        }
        let t = self.reply_timeout();
        let _ = self.exchange("HELP", t);
        let _ = self.send(&[CTRL_Z, CTRL_Z]);
        self.closed = true;
    }

    fn unsettled(&mut self, u: Unsettled) -> i16 {
        self.note(format!("refused: {u}"));
        match u {
            Unsettled::Units => NO_UNITS,
            Unsettled::Angles => NO_ANGLES,
        }
    }

    /// Define the scratch location `name` for a TROL target.
    fn point(&mut self, name: &str, loc: &Location) -> Result<Result<String, i16>, BackendError> {
        let line = match loc {
            Location::Cart(_) => match self.frames.to_rapl(loc.to_array6()) {
                Ok(v) => format!("POINT {name} {}", join(&v)),
                Err(u) => return Ok(Err(self.unsettled(u))),
            },
            Location::Prec(_) => {
                let c = loc.to_array6();
                format!("POINT #{name} {}", join_int(&c.map(|x| x.round() as i64)))
            }
            Location::Joint(_) => {
                let c = joints_to_counts(&loc.to_array6());
                format!("POINT #{name} {}", join_int(&c.map(i64::from)))
            }
        };
        let t = self.reply_timeout();
        match self.command(&line, t, None)? {
            0 => Ok(Ok(if matches!(loc, Location::Cart(_)) {
                name.to_string()
            } else {
                format!("#{name}")
            })),
            c => Ok(Err(c)),
        }
    }

    fn move_pose(&mut self, pose: &Pose, straight: bool) -> BiosResult {
        let loc = Location::from_array6(Tag::Cart, pose.to_xyzypr());
        match self.point("T1", &loc)? {
            Ok(n) => self.motion(&format!("{} {n}", mv(straight)), None),
            Err(c) => Ok(c),
        }
    }

    /// A location of the controller's table, or None when it has none of the name.
    fn listed(&mut self, name: &LocName) -> Result<Option<Listed>, BackendError> {
        let upper = name.as_str().to_ascii_uppercase();
        let t = self.reply_timeout();
        let r = self.exchange(&format!("LISTL {upper}"), t)?;
        if r.error.is_some() {
            return Ok(None);
        }
        let rows = text::read_listl(&r.text).map_err(BackendError::Link)?;
        Ok(rows.into_iter().find(|(n, _)| *n == upper).map(|(_, l)| l))
    }

    /// The pose of a listed location (a cartesian one needs the profile's conventions).
    fn pose_of(&mut self, l: Listed) -> Result<Pose, i16> {
        Ok(match l {
            Listed::Cart(v) => match self.frames.from_rapl(v) {
                Ok(t) => Pose::from_xyzypr(t),
                Err(u) => return Err(self.unsettled(u)),
            },
            Listed::Prec(p) => self.kin().fk(&counts_to_joints(&p.map(|x| x as f64))),
        })
    }

    fn kin(&self) -> Kinematics {
        Kinematics::new(self.tool)
    }

    /// Wait until the arm is idle (for a motion computed from where the arm will be).
    fn wait_idle(&mut self) -> Result<(), BackendError> {
        let until = std::time::Instant::now() + self.motion_timeout();
        while self.moving()? {
            if std::time::Instant::now() > until {
                return Err(BackendError::Link(
                    "the previous motion did not end within motion_timeout_s".into(),
                ));
            }
            std::thread::sleep(Duration::from_millis(self.profile.poll_ms));
        }
        Ok(())
    }

    fn read_position(&mut self, mode: PosMode) -> Result<text::Position, BackendError> {
        let cmd = match mode {
            PosMode::Commanded => "W0",
            PosMode::Actual => "W2",
        };
        let t = self.reply_timeout();
        let mut why = String::new();
        for _ in 0..3 {
            let r = self.exchange(cmd, t)?;
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

    /// A reading whose PULSES and JOINTS rows agree (within 0.01 degrees), when the profile
    /// asks for the check.
    fn consistent(&self, p: text::Position) -> Result<text::Position, String> {
        if !self.profile.cross_check {
            return Ok(p);
        }
        let q = counts_to_joints(&p.pulses.map(|x| x as f64));
        for (i, (from_pulses, read)) in q.iter().zip(&p.joints).enumerate() {
            if (from_pulses.to_degrees() - read).abs() > 0.01 {
                return Err(format!(
                    "joint {} reads {read:.4} deg but its pulses say {:.4} deg",
                    i + 1,
                    from_pulses.to_degrees()
                ));
            }
        }
        Ok(p)
    }

    fn here(&mut self) -> Result<Result<Pose, i16>, BackendError> {
        self.wait_idle()?;
        let p = self.read_position(PosMode::Commanded)?;
        Ok(match self.frames.from_rapl(p.world) {
            Ok(v) => Ok(Pose::from_xyzypr(v)),
            Err(u) => Err(self.unsettled(u)),
        })
    }
}

impl Drop for RaplBackend {
    fn drop(&mut self) {
        self.close();
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
    fn appro(&mut self, target: &Target, disp: [f64; 6], straight: bool) -> BiosResult {
        let pose = match target {
            Target::Name(n) => match self.listed(n)? {
                Some(l) => match self.pose_of(l) {
                    Ok(p) => p,
                    Err(c) => return Ok(c),
                },
                None => return Err(BackendError::UnknownLocation(*n)),
            },
            Target::Location(l @ Location::Cart(_)) => Pose::from_xyzypr(l.to_array6()),
            Target::Location(l @ Location::Prec(_)) => {
                self.kin().fk(&counts_to_joints(&l.to_array6()))
            }
            Target::Location(l @ Location::Joint(_)) => self.kin().fk(&l.to_array6()),
        };
        self.move_pose(&pose.then(&Pose::from_xyzypr(disp)), straight)
    }
    fn close(&mut self, force: u8) -> BiosResult {
        let t = self.reply_timeout();
        let r = self.command(&format!("CLOSE {force}"), t, None)?;
        if r == 0 {
            self.last_poll = None;
        }
        Ok(r)
    }
    fn depart(&mut self, disp: [f64; 6], straight: bool) -> BiosResult {
        match self.here()? {
            Ok(p) => self.move_pose(&p.then(&Pose::from_xyzypr(disp)), straight),
            Err(c) => Ok(c),
        }
    }
    fn moving(&mut self) -> Result<bool, BackendError> {
        if let Some((at, m)) = self.last_poll {
            if at.elapsed() < Duration::from_millis(self.profile.poll_ms) {
                return Ok(m);
            }
        }
        let t = self.reply_timeout();
        let m = match self.profile.completion {
            Completion::Status => {
                let r = self.exchange("STATUS", t)?;
                let s = text::read_status(&r.text).map_err(BackendError::Link)?;
                !s.done.iter().all(|d| *d)
            }
            Completion::W5 => {
                let r = self.exchange("W5", t)?;
                let v = text::row(&r.text, "JOINTS").map_err(BackendError::Link)?;
                v.iter().any(|x| x.abs() > 1e-6)
            }
            Completion::Finish => {
                let mt = self.motion_timeout();
                self.exchange("FINISH", mt)?;
                false
            }
        };
        self.last_poll = Some((std::time::Instant::now(), m));
        Ok(m)
    }
    fn grip(&mut self, dist: u8) -> BiosResult {
        let d = match self.frames.length_to_rapl(f64::from(dist)) {
            Ok(d) => d,
            Err(u) => return Ok(self.unsettled(u)),
        };
        let t = self.reply_timeout();
        let r = self.command(&format!("GRIP {}", text::num(d)), t, None)?;
        if r == 0 {
            self.last_poll = None;
        }
        Ok(r)
    }
    fn halt(&mut self) -> BiosResult {
        self.last_poll = None;
        let t = self.reply_timeout();
        match self.profile.halt {
            Halt::Halt => self.command("HALT", t, None),
            Halt::Abort => self.command("ABORT", t, None),
            Halt::CtrlC => {
                self.settle()?;
                let now = self.now();
                self.session.resync(now);
                match self.pump() {
                    Ok(Ok(_)) => Ok(0),
                    Ok(Err(e)) => Err(BackendError::Unsure(e.to_string())),
                    Err(e) => Err(BackendError::Unsure(e.to_string())),
                }
            }
        }
    }
    fn home(&mut self, axis: u8) -> BiosResult {
        if axis != 0 {
            self.note(format!(
                "refused: RAPL-II has no form for homing axis {axis} alone"
            ));
            return Ok(UNSUPPORTED);
        }
        self.motion("HOME", None)
    }
    fn jog(&mut self, d: [f64; 3], straight: bool) -> BiosResult {
        if straight {
            let v: Result<Vec<f64>, Unsettled> =
                d.iter().map(|x| self.frames.length_to_rapl(*x)).collect();
            return match v {
                Ok(v) => self.motion(&format!("JOG {}", join(&v)), None),
                Err(u) => Ok(self.unsettled(u)),
            };
        }
        match self.here()? {
            Ok(mut p) => {
                p.pos.x += d[0];
                p.pos.y += d[1];
                p.pos.z += d[2];
                self.move_pose(&p, false)
            }
            Err(c) => Ok(c),
        }
    }
    fn joint(&mut self, joint: u8, radians: f64) -> BiosResult {
        if !(1..=6).contains(&joint) || !radians.is_finite() {
            return Ok(code_of("BIOS_BAD_ARGUMENT"));
        }
        self.motion(
            &format!("JOINT {joint},{}", text::num(radians.to_degrees())),
            None,
        )
    }
    fn ma(&mut self, q: [f64; 6]) -> BiosResult {
        self.joints("MA", q)
    }
    fn mi(&mut self, dq: [f64; 6]) -> BiosResult {
        self.joints("MI", dq)
    }
    fn move_to(&mut self, target: &Target, straight: bool) -> BiosResult {
        match target {
            Target::Name(n) => match self.listed(n)? {
                Some(_) => {
                    let upper = n.as_str().to_ascii_uppercase();
                    self.motion(&format!("{} {upper}", mv(straight)), Some(*n))
                }
                None => Err(BackendError::UnknownLocation(*n)),
            },
            Target::Location(l) => match self.point("T1", l)? {
                Ok(name) => self.motion(&format!("{} {name}", mv(straight)), None),
                Err(c) => Ok(c),
            },
        }
    }
    fn open(&mut self, force: u8) -> BiosResult {
        let t = self.reply_timeout();
        let r = self.command(&format!("OPEN {force}"), t, None)?;
        if r == 0 {
            self.last_poll = None;
        }
        Ok(r)
    }
    fn ready(&mut self) -> BiosResult {
        self.motion("READY", None)
    }
    fn set_tool(&mut self, tool: [f64; 6]) -> BiosResult {
        match self.point("TL", &Location::from_array6(Tag::Cart, tool))? {
            Ok(_) => {
                let t = self.reply_timeout();
                let r = self.command("TOOL TL", t, None)?;
                if r == 0 {
                    self.tool = tool;
                }
                Ok(r)
            }
            Err(c) => Ok(c),
        }
    }
    fn speed(&mut self, percent: u8) -> BiosResult {
        if !(1..=100).contains(&percent) {
            return Ok(code_of("BIOS_BAD_ARGUMENT"));
        }
        let t = self.reply_timeout();
        self.command(&format!("SPEED {percent}"), t, None)
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
}

impl RaplBackend {
    fn joints(&mut self, cmd: &str, q: [f64; 6]) -> BiosResult {
        let Some(units) = self.joint_units else {
            self.note(format!(
                "refused {cmd}: its units are not known; set joint_units in the RAPL-II profile"
            ));
            return Ok(NO_JOINT_UNITS);
        };
        let v = match units {
            JointUnits::Degrees => q.map(f64::to_degrees),
            JointUnits::Radians => q,
        };
        self.motion(&format!("{cmd} {}", join(&v)), None)
    }
}

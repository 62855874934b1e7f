//! The robot backend for an A465 on a C500C (port `c500c:DEVICE`; docs/c500c.md): TROL's
//! calls as ash commands on the front console, under the rule for real controllers and on
//! the shared core ([`trol_controller::real`]):
//!
//! - success only in ash's exact success form (the echo, no line, the prompt); a known error
//!   text of CRS's tables is a refusal with its code and text; any other line, a question
//!   TROL did not ask, a silence where the prompt was due: TROL_ERR_ROBOT_UNSURE, and
//!   nothing further is sent;
//! - a line nobody asked for (`[test: Lost robot power]`) makes the next call UNSURE;
//! - before a motion, the gate on a fresh `armstat` (power, homed), the point of control
//!   from ash's own refusal; a motion behind one of TROL's waits in the bounded queue;
//! - a motion has ended when ash says so (its prompt, or `finish`'s) *and* `w2` reads the arm
//!   at its end; standing short of it is BIOS_NOT_AT_TARGET; neither within the planned time
//!   and a margin: UNSURE;
//! - Halt is Ctrl-C, and success only once `w2` shows the arm standing;
//! - what the profile has not settled is refused before sending, naming the key: motions
//!   need `motion-return`; cartesian motions need the WORLD row's angle order and MA of
//!   several joints the A465's pulses per degree on a C500C, which no key settles yet.

use std::collections::VecDeque;
use std::io;
use std::time::{Duration, Instant};

use trol_a465::arm::{Arm, ArmSettings, code};
use trol_a465::backend::A465_CODES;
use trol_a465::kinematics::Kinematics;
use trol_controller::real;
use trol_controller::{ArmReport, Backend, BackendError, BiosResult, PosMode, Target};
use trol_port::Port;
use trol_proto::application::{CodeInfo, CodeTable, Location, Tag};

use crate::console::{self, Console, Said};
use crate::profile::{MotionReturn, Profile};
use crate::reports::{self, ArmStat, Homing, Known};

pub use trol_a465::backend::real::{ARM_POWER, BUSY, NOT_AT_TARGET, UNSUPPORTED};
/// The pendant holds the point of control (`Ash doesn't have control`).
pub const NO_CONTROL: i16 = -27;
/// The profile has not settled what this call needs (the log names the key).
pub const UNSETTLED: i16 = -28;
/// An error of CRS's tables with no code of its own (a servo fault, a parse error).
pub const C500C_ERROR: i16 = -29;

/// The BIOS codes of the C500C backend: the simulator's, and those of the controller.
pub static C500C_CODES: &CodeTable = &{
    const EXTRA: [CodeInfo; 7] = [
        CodeInfo {
            value: ARM_POWER,
            name: "BIOS_ARM_POWER",
            meaning: "arm power is off: switch it on at the controller, then TROLHome",
        },
        CodeInfo {
            value: UNSUPPORTED,
            name: "BIOS_UNSUPPORTED",
            meaning: "this call has no ash form TROL knows on a C500C",
        },
        CodeInfo {
            value: BUSY,
            name: "BIOS_BUSY",
            meaning: "a motion has not ended: call TROLFinish(FINISH_WAIT) first",
        },
        CodeInfo {
            value: NOT_AT_TARGET,
            name: "BIOS_NOT_AT_TARGET",
            meaning: "ash said done with the arm short of the motion's end",
        },
        CodeInfo {
            value: NO_CONTROL,
            name: "BIOS_NO_CONTROL",
            meaning: "the pendant holds the point of control: press <SHIFT><ESC> on the \
                      pendant keyboard to give it to the console",
        },
        CodeInfo {
            value: UNSETTLED,
            name: "BIOS_UNSETTLED",
            meaning: "the C500C profile has not settled what this call needs: the log names \
                      the key (docs/c500c.md, The profile)",
        },
        CodeInfo {
            value: C500C_ERROR,
            name: "BIOS_C500C_ERROR",
            meaning: "ash printed an error with no code of its own: the log has its text",
        },
    ];
    trol_a465::backend::with_a465_codes::<{ A465_CODES.len() + EXTRA.len() }>(&EXTRA)
};

/// How long ash may take to give its prompt back after a command that does not move.
pub const REPLY_LIMIT: Duration = Duration::from_secs(3);
/// With `motion-return = "end"`: how long a motion command's refusal may take to show
/// before the motion counts as started (its prompt is then due at its end).
pub const ACCEPT_WITHIN: Duration = Duration::from_millis(400);
/// How long one stop is given to show the arm standing (the A465 brakes within 0.4 s).
pub const STOP_WITHIN: Duration = Duration::from_millis(1500);
/// At connect: how long the console must stay quiet after a prompt before the last one is
/// taken as the shell's (one prompt per CR sent).
pub const CONNECT_QUIET: Duration = Duration::from_millis(500);
/// The longest a Halt takes.
pub const HALT_WITHIN: Duration = Duration::from_millis(2500);
/// How long a reading of where the arm rests serves a motion computed from it.
pub const FRESH_REST: Duration = Duration::from_millis(250);
/// How far (degrees) the arm may stand from a motion's end and be at it.
pub const ARRIVE_DEG: f64 = 0.05;

/// Why a session could not be opened.
#[derive(Debug, thiserror::Error)]
pub enum C500cError {
    /// The line failed.
    #[error("the line to the C500C failed: {0}")]
    Io(#[from] io::Error),
    /// Nothing answered with a prompt.
    #[error(
        "no C500C answers on {port}: Ctrl-E and two CR got no prompt within {limit:?}. Check \
         the cable (the front console), the baud rate ({baud}, 8N1) and that the controller \
         has booted"
    )]
    Silent {
        /// The port.
        port: String,
        /// The baud rate.
        baud: u32,
        /// How long it waited.
        limit: Duration,
    },
    /// Something answered that is not what TROL expects; nothing was moved.
    #[error("{0}")]
    Unexpected(String),
}

/// A log of what the controller said (`-v` in the utilities).
pub type Log = Box<dyn FnMut(&str) + Send>;

/// Why an exchange failed.
enum Fail {
    Io(io::Error),
    /// No prompt in time after the command was sent.
    Silent(String),
    /// A line or question TROL cannot place.
    Unsure(String),
}

impl Fail {
    fn into_backend(self) -> BackendError {
        match self {
            Fail::Io(e) => BackendError::Unsure(format!("the console failed: {e}")),
            Fail::Silent(s) | Fail::Unsure(s) => BackendError::Unsure(s),
        }
    }
}

/// A motion TROL sends, or keeps until the one before has ended.
#[derive(Clone, Debug)]
struct Motion {
    /// The ash line.
    line: String,
    /// What it changes: a joint by degrees, or a home.
    kind: Kind,
}

#[derive(Clone, Copy, Debug)]
enum Kind {
    Joint(u8, f64),
    Home,
}

struct Outstanding {
    motion: Motion,
    /// Where the motion ends, degrees (a home: where the arm is read once homed).
    target: Option<[f64; 6]>,
    watch: real::EndWatch,
    /// The motion's planned time.
    planned: Duration,
    /// ash runs a command whose prompt is still due (the motion with `motion-return =
    /// "end"`, or `finish`).
    prompt_due: bool,
    /// That command, as typed (its echo comes first).
    due: String,
    /// ash has said the motion is done (its prompt came back at its end).
    done: bool,
}

/// The C500C backend.
pub struct C500cBackend {
    port: Box<dyn Port>,
    profile: Profile,
    console: Console,
    rx: VecDeque<Said>,
    log: Option<Log>,
    version: String,
    stat: ArmStat,
    tool: [f64; 6],
    /// Where the arm was last seen at rest, degrees, and when.
    rest: [f64; 6],
    rest_at: Instant,
    speed: u8,
    unasked: Vec<String>,
    broken: Option<String>,
    outstanding: Option<Outstanding>,
    queue: real::MotionQueue<Motion>,
    note: Option<String>,
}

impl std::fmt::Debug for C500cBackend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("C500cBackend")
            .field("version", &self.version)
            .field("profile", &self.profile)
            .finish_non_exhaustive()
    }
}

fn join(q: &[f64; 6]) -> String {
    q.iter()
        .map(|v| format!("{v:.3}"))
        .collect::<Vec<_>>()
        .join(" ")
}

impl C500cBackend {
    /// Open the session: Ctrl-E and two CR, the prompt, `ash <app>` from the system shell
    /// where needed, then only reads (`robotver`, `armstat`, `speed`, `w2`). Nothing moves.
    pub fn connect(
        port: Box<dyn Port>,
        profile: Profile,
        log: Option<Log>,
    ) -> Result<C500cBackend, C500cError> {
        let name = port.name();
        let mut b = C500cBackend {
            port,
            console: Console::default(),
            rx: VecDeque::new(),
            log,
            version: String::new(),
            stat: ArmStat {
                arm: String::new(),
                power: false,
                homing: Homing::NotHomed,
                metric: true,
                online: false,
            },
            tool: [0.0; 6],
            rest: [0.0; 6],
            rest_at: Instant::now(),
            speed: 0,
            unasked: Vec::new(),
            broken: None,
            outstanding: None,
            queue: real::MotionQueue::new(trol_a465::arm::MOTION_QUEUE),
            note: None,
            profile,
        };
        b.send(b"\x05\r\r")?;
        // The last prompt of a quiet console (one per CR).
        let mut shell = None;
        let limit = REPLY_LIMIT;
        let deadline = Instant::now() + limit;
        loop {
            let quiet = if shell.is_some() {
                Instant::now() + CONNECT_QUIET
            } else {
                deadline
            };
            match b.next(quiet.min(deadline).max(Instant::now()))? {
                Some(Said::Prompt(p)) => shell = Some(p),
                Some(Said::Question(q)) => {
                    return Err(C500cError::Unexpected(format!(
                        "the console asks `{q}`: answer it at a terminal, then connect again"
                    )));
                }
                Some(Said::Line(l)) => b.say(&format!("at connect: {l}")),
                None => break,
            }
        }
        let Some(shell) = shell else {
            return Err(C500cError::Silent {
                port: name,
                baud: b.profile.baud,
                limit,
            });
        };
        let app = b.profile.app.clone();
        if shell == "$" {
            // A prompt of the system shell still on its way (one per CR sent) comes before
            // ash's: skipped here, where nothing but ash's can be the answer.
            let cmd = format!("ash {app}");
            b.send(format!("{cmd}\r").as_bytes())?;
            let deadline = Instant::now() + REPLY_LIMIT;
            loop {
                match b.next(deadline)? {
                    Some(Said::Prompt(p)) if p == "$" => continue,
                    Some(Said::Prompt(p)) if p == app => break,
                    Some(Said::Line(l)) if l.trim_end() == cmd || l.trim().is_empty() => {}
                    Some(Said::Line(l)) => b.say(&format!("ash: {l}")),
                    other => {
                        return Err(C500cError::Unexpected(format!(
                            "`{cmd}` did not start ash (the console said {other:?}): start it \
                             at a terminal to see why"
                        )));
                    }
                }
            }
        } else if shell != app {
            return Err(C500cError::Unexpected(format!(
                "the console runs ash with the application `{shell}`, and the profile names \
                 `{app}`: exit it (`exit`, then y) or name it in the profile (`app = \"{shell}\"`)"
            )));
        }
        let read = |b: &mut C500cBackend, cmd: &str| {
            b.exchange(cmd)
                .map_err(|e| C500cError::Unexpected(e.into_backend().to_string()))
        };
        let lines = read(&mut b, "robotver")?;
        b.version = reports::robotver(&lines).map_err(|e| C500cError::Unexpected(e.to_string()))?;
        let lines = read(&mut b, "armstat")?;
        b.stat = reports::armstat(&lines).map_err(|e| C500cError::Unexpected(e.to_string()))?;
        if b.stat.arm != "A465" {
            return Err(C500cError::Unexpected(format!(
                "armstat says the arm is an {}: TROL drives an A465",
                b.stat.arm
            )));
        }
        let lines = read(&mut b, "speed")?;
        b.speed = reports::speed(&lines).map_err(|e| C500cError::Unexpected(e.to_string()))?;
        let lines = read(&mut b, "w2")?;
        b.rest = reports::position(&lines, true)
            .map_err(|e| C500cError::Unexpected(e.to_string()))?
            .joints_deg;
        Ok(b)
    }

    /// What `robotver` said.
    pub fn version(&self) -> &str {
        &self.version
    }

    fn say(&mut self, text: &str) {
        if let Some(l) = &mut self.log {
            l(text);
        }
    }

    fn note(&mut self, text: String) {
        self.say(&text);
        self.note = Some(text);
    }

    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.port.send(bytes)
    }

    /// The next thing the console said, waiting until `deadline`.
    fn next(&mut self, deadline: Instant) -> io::Result<Option<Said>> {
        loop {
            if let Some(s) = self.rx.pop_front() {
                return Ok(Some(s));
            }
            let mut buf = [0u8; 512];
            let n = self.port.recv(&mut buf, deadline)?;
            if n == 0 {
                return Ok(None);
            }
            let said = self.console.feed(&buf[..n]);
            self.rx.extend(said);
        }
    }

    /// Send `cmd` and read to ash's prompt: the lines between (the echo taken off).
    fn exchange(&mut self, cmd: &str) -> Result<Vec<String>, Fail> {
        self.send(format!("{cmd}\r").as_bytes()).map_err(Fail::Io)?;
        self.read_to_prompt(cmd, Instant::now() + REPLY_LIMIT)
            .and_then(|got| {
                got.ok_or_else(|| {
                    Fail::Silent(format!("`{cmd}`: no prompt within {REPLY_LIMIT:?}"))
                })
            })
    }

    /// The lines up to ash's prompt (`None`: no prompt by `deadline`).
    fn read_to_prompt(
        &mut self,
        cmd: &str,
        deadline: Instant,
    ) -> Result<Option<Vec<String>>, Fail> {
        let app = self.profile.app.clone();
        let mut lines = Vec::new();
        let mut echo_seen = false;
        loop {
            match self.next(deadline).map_err(Fail::Io)? {
                None => {
                    self.rx.extend(lines.into_iter().map(Said::Line));
                    return Ok(None);
                }
                Some(Said::Prompt(p)) if p == app => return Ok(Some(lines)),
                Some(Said::Prompt(p)) => {
                    return Err(Fail::Unsure(format!(
                        "after `{cmd}` the console gave the prompt of `{p}`, not ash's: ash \
                         ended"
                    )));
                }
                Some(Said::Question(q)) => {
                    // Never answered unasked: out of it, and the call cannot tell.
                    let _ = self.send(b"\x03");
                    return Err(Fail::Unsure(format!(
                        "after `{cmd}` ash asked `{q}`: not answered (Ctrl-C sent)"
                    )));
                }
                Some(Said::Line(l)) if !echo_seen && l.trim_end() == cmd => echo_seen = true,
                // A bracketed line with an error of CRS's tables is the command's (ash may
                // print a robot error so); any other is unasked.
                Some(Said::Line(l))
                    if console::bracketed(&l).is_some() && reports::known_error(&l).is_none() =>
                {
                    self.say(&format!("unasked: {l}"));
                    self.unasked.push(l);
                }
                Some(Said::Line(l)) => {
                    echo_seen = true;
                    lines.push(l);
                }
            }
        }
    }

    /// Before a call: what came unasked makes it UNSURE, as does an earlier call that could
    /// not tell; nothing is sent then.
    fn clean(&mut self) -> Result<(), BackendError> {
        if !self.console_busy() {
            // What the console printed since the last exchange.
            while let Some(s) = self
                .next(Instant::now())
                .map_err(|e| BackendError::Unsure(format!("the console failed: {e}")))?
            {
                match s {
                    Said::Line(l) if !l.trim().is_empty() => {
                        self.say(&format!("unasked: {l}"));
                        self.unasked.push(l);
                    }
                    Said::Line(_) => {}
                    other => self.unasked.push(format!("{other:?}")),
                }
            }
        }
        if !self.unasked.is_empty() && self.broken.is_none() {
            let lines = std::mem::take(&mut self.unasked).join(" | ");
            self.queue.drop_all();
            self.outstanding = None;
            self.broken = Some(format!(
                "the C500C said, unasked: {lines}; TROL sends nothing further (check the arm, \
                 then reconnect)"
            ));
        }
        match &self.broken {
            Some(why) => Err(BackendError::Unsure(why.clone())),
            None => Ok(()),
        }
    }

    /// Give up: UNSURE with `why`, and nothing further is sent.
    fn unsure(&mut self, why: String) -> BackendError {
        self.queue.drop_all();
        self.outstanding = None;
        self.note(why.clone());
        self.broken = Some(why.clone());
        BackendError::Unsure(why)
    }

    fn read_position(&mut self, actual: bool) -> Result<reports::Position, BackendError> {
        let cmd = if actual { "w2" } else { "w0" };
        let lines = match self.exchange(cmd) {
            Ok(l) => l,
            Err(e) => return Err(self.fail(e)),
        };
        reports::position(&lines, actual).map_err(|e| self.unsure(e.to_string()))
    }

    fn fail(&mut self, e: Fail) -> BackendError {
        match e.into_backend() {
            BackendError::Unsure(why) => self.unsure(why),
            other => other,
        }
    }

    /// A known error text: its code; anything else: UNSURE.
    fn refusal(&mut self, line: &str, lines: &[String]) -> BackendError {
        let Some(known) = lines.iter().find_map(|l| reports::known_error(l)) else {
            return self.unsure(format!(
                "`{line}`: ash printed `{}`, not a form TROL knows: whether it ran is not known",
                lines.join(" | ")
            ));
        };
        let code = match known {
            Known::NoPower => ARM_POWER,
            Known::NotHomed => code::NOT_HOMED,
            Known::JointLimit => code::JOINT_LIMIT,
            Known::OutOfReach => code::OUT_OF_REACH,
            Known::Limp => ARM_POWER,
            Known::NoControl => NO_CONTROL,
            Known::Halted | Known::Parse | Known::Servo => C500C_ERROR,
        };
        self.note(format!("`{line}` refused: {}", lines.join(" | ")));
        BackendError::Refused(code)
    }

    fn unsettled(&mut self, what: &str) -> BiosResult {
        self.note(format!(
            "refused before sending: {what} (docs/c500c.md, The profile)"
        ));
        Ok(UNSETTLED)
    }

    /// The gate and the queue, then the motion.
    fn motion(&mut self, m: Motion) -> BiosResult {
        self.clean()?;
        if self.profile.motion_return.is_none() {
            return self.unsettled(
                "a motion needs to know when ash gives its prompt back: set `motion-return = \
                 \"start\"` or `\"end\"` in the C500C profile (the probe's supervised step \
                 `motion-return` measures it)",
            );
        }
        // While ash runs a motion of TROL's to its end it reads no command: the gate then
        // takes the status read before that motion (a fault meanwhile ends it with a line).
        if !self.console_busy() {
            let lines = match self.exchange("armstat") {
                Ok(l) => l,
                Err(e) => return Err(self.fail(e)),
            };
            self.stat = reports::armstat(&lines).map_err(|e| self.unsure(e.to_string()))?;
        }
        let ours = self.outstanding.is_some() || !self.queue.is_empty();
        if !ours {
            // Where the arm rests now: the pendant or another program may have moved it
            // since TROL last looked, and the motion's end is computed from it.
            self.fresh_rest()?;
        }
        let homing = self
            .outstanding
            .as_ref()
            .is_some_and(|o| matches!(o.motion.kind, Kind::Home))
            || self.queue.iter().any(|q| matches!(q.kind, Kind::Home));
        let snapshot = real::Snapshot {
            powered: self.stat.power,
            homed: self.stat.homing == Homing::Homed,
            in_control: true,
            moving: ours,
            ours,
            homing,
        };
        match real::gate(&snapshot, matches!(m.kind, Kind::Home)) {
            real::Gate::Refuse(r) => {
                self.note(r.text().to_string());
                Ok(match r {
                    real::Refusal::NoPower => ARM_POWER,
                    real::Refusal::NotHomed => code::NOT_HOMED,
                    real::Refusal::NoControl => NO_CONTROL,
                    real::Refusal::Busy => BUSY,
                })
            }
            real::Gate::Queue => match self.queue.push(m) {
                Ok(()) => Ok(code::OK),
                Err(_) => Ok(code::QUEUE_FULL),
            },
            real::Gate::Send => self.send_motion(m),
        }
    }

    /// The motion's planned time from where the arm rests, at the speed set.
    fn planned(&self, kind: Kind) -> Duration {
        let mut arm = Arm::new(ArmSettings {
            homed: true,
            ..ArmSettings::default()
        });
        arm.place(self.rest.map(f64::to_radians));
        arm.set_speed(f64::from(self.speed.max(1)));
        let r = match kind {
            Kind::Joint(n, deg) => arm.joint(n, deg.to_radians(), 0.0),
            Kind::Home => arm.home(0, 0.0),
        };
        if r != code::OK {
            return Duration::from_secs(60);
        }
        Duration::from_secs_f64(arm.done_at(0.0).clamp(0.0, 600.0))
    }

    fn send_motion(&mut self, m: Motion) -> BiosResult {
        let planned = self.planned(m.kind);
        let target = match m.kind {
            Kind::Joint(n, deg) => {
                let mut t = self.rest;
                t[n as usize - 1] += deg;
                Some(t)
            }
            Kind::Home => None,
        };
        if let Err(e) = self.send(format!("{}\r", m.line).as_bytes()) {
            return Err(self.unsure(format!("`{}`: the console failed: {e}", m.line)));
        }
        let sent = Instant::now();
        // ash gives the prompt back as the motion starts (`start`): it is waited for as any
        // reply; or once it ends (`end`): what comes within ACCEPT_WITHIN is a refusal, and
        // silence is the motion running (a refusal printed later is read at its end).
        let wait = match self.profile.motion_return {
            Some(MotionReturn::End) => ACCEPT_WITHIN,
            _ => REPLY_LIMIT,
        };
        let got = match self.read_to_prompt(&m.line, sent + wait) {
            Ok(g) => g,
            Err(e) => return Err(self.fail(e)),
        };
        let prompt_due = match got {
            Some(lines) if lines.is_empty() => false,
            Some(lines) => return Err(self.refusal(&m.line, &lines)),
            None if self.profile.motion_return == Some(MotionReturn::End) && self.rx.is_empty() => {
                true
            }
            None => {
                let seen: Vec<String> = self.rx.drain(..).map(|s| format!("{s:?}")).collect();
                return Err(self.unsure(format!(
                    "`{}`: no prompt within {wait:?} ({}), and the profile says ash gives it \
                     back as a motion starts: whether the motion runs is not known",
                    m.line,
                    if seen.is_empty() {
                        "nothing printed".to_string()
                    } else {
                        seen.join(" ")
                    }
                )));
            }
        };
        let m_line_for_due = m.line.clone();
        let still = [real::STILL_DEG; 6];
        let watch =
            real::EndWatch::new(sent, Some(self.rest), still).planned_to_end(sent + planned);
        self.outstanding = Some(Outstanding {
            motion: m,
            target,
            watch,
            planned,
            prompt_due,
            due: m_line_for_due,
            done: false,
        });
        Ok(code::OK)
    }

    /// The end rule's times for the motion under way: the settle time, and its planned
    /// time with the profile's margin.
    fn end_times(&self) -> real::EndTimes {
        let planned = self
            .outstanding
            .as_ref()
            .map_or(Duration::ZERO, |o| o.planned);
        real::EndTimes {
            settle: Duration::from_millis(self.profile.settle_ms),
            give_up: planned + Duration::from_secs(self.profile.end_margin_s),
        }
    }

    /// One look at the motion under way: `true` while it (or one queued) runs.
    fn look(&mut self) -> Result<bool, BackendError> {
        if self.outstanding.is_none() {
            return Ok(false);
        }
        let give_up = self.end_times().give_up;
        let o = self.outstanding.as_mut().expect("a motion under way");
        if o.prompt_due {
            let line = o.motion.line.clone();
            let due = o.due.clone();
            match self.read_to_prompt(&due, Instant::now() + Duration::from_millis(20)) {
                Ok(Some(lines)) if lines.is_empty() => {
                    let o = self.outstanding.as_mut().expect("a motion under way");
                    o.prompt_due = false;
                    o.done = true;
                }
                Ok(Some(lines)) => {
                    // The motion ended with an error of ash's: nothing more of it, and
                    // nothing that waited behind it, is sent.
                    self.outstanding = None;
                    let n = self.queue.drop_all();
                    if let Some(note) = real::MotionQueue::<Motion>::dropped_note(n, &line) {
                        self.say(&note);
                    }
                    return Err(self.refusal(&line, &lines));
                }
                Ok(None) => {
                    let o = self.outstanding.as_ref().expect("a motion under way");
                    if o.watch.older_than(Instant::now(), give_up) {
                        return Err(self.unsure(format!(
                            "`{line}`: ash has not said done within the motion's time and a \
                             margin: whether it ran as asked is not known"
                        )));
                    }
                    return Ok(true);
                }
                Err(e) => return Err(self.fail(e)),
            }
        } else if !o.done {
            // The motion started with the prompt: ash's `finish` says when it ends.
            if let Err(e) = self.send(b"finish\r") {
                return Err(self.unsure(format!("`finish`: the console failed: {e}")));
            }
            let o = self.outstanding.as_mut().expect("a motion under way");
            o.prompt_due = true;
            o.due = "finish".into();
            return Ok(true);
        }
        // ash says done: the arm must be read at the motion's end.
        let p = self.read_position(true)?;
        let now = Instant::now();
        let homed = if self
            .outstanding
            .as_ref()
            .is_some_and(|o| o.target.is_none())
        {
            let lines = match self.exchange("armstat") {
                Ok(l) => l,
                Err(e) => return Err(self.fail(e)),
            };
            self.stat = reports::armstat(&lines).map_err(|e| self.unsure(e.to_string()))?;
            self.stat.homing == Homing::Homed
        } else {
            true
        };
        let times = self.end_times();
        let o = self.outstanding.as_mut().expect("a motion under way");
        // ash gives no moving flag: the arm read away from where it rested is the motion
        // seen running (once: the readings after it show whether it stands).
        let away = (0..6).any(|j| (p.joints_deg[j] - self.rest[j]).abs() > real::STILL_DEG);
        if away && !o.watch.seen_moving() {
            o.watch.saw_moving();
        }
        let standing_before = o.watch.stood_for(now);
        o.watch.saw_at(now, p.joints_deg);
        if o.target.is_none() && homed && standing_before.is_some() && !o.watch.seen_moving() {
            // A home: ash said done, and armstat says homed: the controller's own word twice.
            o.watch.saw_moving();
            o.watch.saw_at(now, p.joints_deg);
        }
        let at_end = match o.target {
            Some(t) => (0..6).all(|j| (p.joints_deg[j] - t[j]).abs() <= ARRIVE_DEG),
            // A home: homed, and read standing twice.
            None => homed && standing_before.is_some() && o.watch.stood_for(now).is_some(),
        };
        match o.watch.verdict(now, at_end, times) {
            real::End::Arrived => {
                self.rest = p.joints_deg;
                self.rest_at = Instant::now();
                self.outstanding = None;
                match self.queue.pop() {
                    Some(next) => {
                        self.send_motion(next)?;
                        Ok(true)
                    }
                    None => Ok(false),
                }
            }
            real::End::Running => Ok(true),
            real::End::StoppedShort(at) => {
                let line = o.motion.line.clone();
                self.rest = at;
                self.rest_at = Instant::now();
                self.outstanding = None;
                let n = self.queue.drop_all();
                self.note(format!(
                    "`{line}`: ash says done, and the arm (w2 joints {}) has stood short of the \
                     motion's end{}",
                    join(&at),
                    real::MotionQueue::<Motion>::dropped_note(n, &line)
                        .map(|n| format!("; {n}"))
                        .unwrap_or_default()
                ));
                Err(BackendError::Refused(NOT_AT_TARGET))
            }
            real::End::TimedOut => {
                let line = o.motion.line.clone();
                Err(self.unsure(format!(
                    "`{line}`: ash says done, but the arm (w2) is not at the motion's end: \
                     whether it ran as asked is not known"
                )))
            }
        }
    }
}

/// Ctrl-C for [`real::halt`], and `w2` for its readings.
impl real::Stopping for C500cBackend {
    type Stop = ();

    fn stop_name(&self, _: ()) -> String {
        "Ctrl-C".into()
    }

    fn send_stop(&mut self, _: ()) -> Result<String, String> {
        self.send(b"\x03").map_err(|e| e.to_string())?;
        self.console.clear();
        self.rx.clear();
        // ash's prompt after the interrupt; what it printed before is kept for the log.
        let app = self.profile.app.clone();
        let deadline = Instant::now() + REPLY_LIMIT;
        let mut said = Vec::new();
        loop {
            match self.next(deadline).map_err(|e| e.to_string())? {
                Some(Said::Prompt(p)) if p == app => break,
                Some(Said::Line(l)) if l.trim().is_empty() || l.trim() == "^C" => {}
                Some(s) => said.push(format!("{s:?}")),
                None => return Err("no prompt after Ctrl-C".into()),
            }
        }
        if let Some(o) = self.outstanding.as_mut() {
            o.prompt_due = false;
        }
        Ok(if said.is_empty() {
            "the prompt came back".into()
        } else {
            format!("ash printed {}", said.join(" "))
        })
    }

    fn reading(&mut self) -> Result<Option<[f64; 6]>, String> {
        let lines = self.exchange("w2").map_err(|e| match e {
            Fail::Io(e) => e.to_string(),
            Fail::Silent(s) | Fail::Unsure(s) => s,
        })?;
        reports::position(&lines, true)
            .map(|p| Some(p.joints_deg))
            .map_err(|e| e.to_string())
    }

    fn still_within(&self) -> [f64; 6] {
        [real::STILL_DEG; 6]
    }

    fn now(&self) -> Instant {
        Instant::now()
    }

    fn pause(&mut self, d: Duration) {
        std::thread::sleep(d);
    }
}

impl Backend for C500cBackend {
    fn kind(&self) -> &'static str {
        "C500C over ash"
    }
    fn codes(&self) -> &'static CodeTable {
        C500C_CODES
    }
    fn reply_time(&self) -> Duration {
        // A Halt: its stop, and the readings that show the arm standing.
        HALT_WITHIN + REPLY_LIMIT
    }
    fn appro(&mut self, target: &Target, _: [f64; 6], _: bool) -> BiosResult {
        self.named(target)?;
        self.cartesian()
    }
    fn depart(&mut self, _: [f64; 6], _: bool) -> BiosResult {
        self.cartesian()
    }
    fn jog(&mut self, _: [f64; 3], _: bool) -> BiosResult {
        self.cartesian()
    }
    fn move_to(&mut self, target: &Target, _: bool) -> BiosResult {
        self.named(target)?;
        self.cartesian()
    }
    fn close(&mut self, _: u8) -> BiosResult {
        self.no_gripper()
    }
    fn open(&mut self, _: u8) -> BiosResult {
        self.no_gripper()
    }
    fn grip(&mut self, _: u8) -> BiosResult {
        self.no_gripper()
    }
    fn moving(&mut self) -> Result<bool, BackendError> {
        if self.outstanding.is_none() {
            self.clean()?;
            if let Some(next) = self.queue.pop() {
                self.send_motion(next)?;
            } else {
                return Ok(false);
            }
        }
        self.look()
    }
    fn stands(&mut self) -> Result<bool, BackendError> {
        Ok(self.outstanding.is_none() && self.queue.is_empty())
    }
    fn halt(&mut self) -> BiosResult {
        if let Some(why) = &self.broken {
            // A Halt is always tried: it sends nothing that moves.
            self.say(&format!("Halt after an earlier failure: {why}"));
        }
        let times = real::HaltTimes {
            halt_within: HALT_WITHIN,
            stop_within: STOP_WITHIN,
        };
        match real::halt(self, &[()], times) {
            real::Halted::Standing { at, note } => {
                let n = self.queue.drop_all();
                self.outstanding = None;
                self.rest = at;
                self.rest_at = Instant::now();
                if let Some(note) = note {
                    self.note(note);
                } else if n > 0 {
                    self.note(format!("Halt: {n} queued motion(s) dropped unsent"));
                }
                Ok(code::OK)
            }
            real::Halted::NotStopped(why) => {
                self.queue.drop_all();
                self.outstanding = None;
                self.broken = Some(format!("Halt: {why}"));
                Err(BackendError::NotStopped(why))
            }
        }
    }
    fn home(&mut self, axis: u8) -> BiosResult {
        if axis != 0 {
            self.note(format!(
                "refused before sending: Home of axis {axis} alone: ash's `home [axes]` form is \
                 not settled; TROLHome(0) homes every axis"
            ));
            return Ok(UNSUPPORTED);
        }
        self.motion(Motion {
            line: "home".into(),
            kind: Kind::Home,
        })
    }
    fn joint(&mut self, joint: u8, radians: f64) -> BiosResult {
        if !(1..=6).contains(&joint) || !radians.is_finite() {
            return Ok(code::BAD_ARGUMENT);
        }
        let deg = radians.to_degrees();
        self.motion(Motion {
            line: format!("joint {joint},{deg:.3}"),
            kind: Kind::Joint(joint, (deg * 1000.0).round() / 1000.0),
        })
    }
    fn ma(&mut self, q: [f64; 6]) -> BiosResult {
        if q.iter().any(|v| !v.is_finite()) {
            return Ok(code::BAD_ARGUMENT);
        }
        self.clean()?;
        if self.outstanding.is_some() || !self.queue.is_empty() {
            // Computed from where the arm rests: not while a motion runs.
            self.note(
                "refused: a motion has not ended, and MA is sent as a relative joint motion \
                 from where the arm rests: call TROLFinish(FINISH_WAIT) first"
                    .into(),
            );
            return Ok(BUSY);
        }
        // Sent as one relative motion: from where the arm rests now, read, not remembered.
        self.fresh_rest()?;
        let d: [f64; 6] = std::array::from_fn(|j| q[j].to_degrees() - self.rest[j]);
        self.relative(d)
    }
    fn mi(&mut self, dq: [f64; 6]) -> BiosResult {
        if dq.iter().any(|v| !v.is_finite()) {
            return Ok(code::BAD_ARGUMENT);
        }
        self.relative(dq.map(f64::to_degrees))
    }
    /// Untimed, and one waypoint only: MA is sent relative to where the arm rests, so a
    /// second joint move cannot wait behind the first (docs/c500c.md). The waypoint goes at
    /// the speed setting, so one whose time is shorter than the move takes there is
    /// BIOS_TOO_FAST (one at time 0 away from the arm BIOS_BAD_ARGUMENT), before anything
    /// is sent: the arm never goes faster than the user set it to.
    fn trajectory(&mut self, points: &[trol_proto::application::Waypoint]) -> BiosResult {
        if let ([p], false) = (points, self.outstanding.is_some() || !self.queue.is_empty()) {
            self.clean()?;
            if p.joints.iter().all(|v| v.is_finite()) && p.time.is_finite() {
                self.fresh_rest()?;
                let from = self.rest.map(f64::to_radians);
                let top = trol_a465::model::max_speeds();
                if let real::Pace::TooFast(needed) =
                    real::pace(&from, &p.joints, p.time, &top, self.speed)
                {
                    let (c, why) = if p.time <= 0.0 {
                        (
                            code::BAD_ARGUMENT,
                            "at time 0 away from where the arm rests".into(),
                        )
                    } else {
                        (
                            code::TOO_FAST,
                            format!(
                                "needs {needed:.0} % of the joints' top speed in its {} s; the \
                                 speed setting is {} % (TROLSpeed)",
                                p.time, self.speed
                            ),
                        )
                    };
                    self.note(format!(
                        "trajectory refused before sending: its waypoint {why}"
                    ));
                    return Ok(c);
                }
            }
        }
        if points.len() > 1 {
            return Err(BackendError::Explained(
                trol_proto::application::code::TROL_ERR_ARG_RANGE.0,
                format!(
                    "{} waypoints: on a C500C a trajectory has one waypoint (each joint move \
                     is sent from where the arm rests): send them one by one, with \
                     TROLFinish(FINISH_WAIT) between",
                    points.len()
                ),
            ));
        }
        trol_controller::untimed_trajectory(self, points)
    }
    fn ready(&mut self) -> BiosResult {
        self.unsettled(
            "READY's joint values on an A465 with a C500C are not public, so its end could not \
             be checked: use TROLMA with the joints of READY",
        )
    }
    fn set_tool(&mut self, tool: [f64; 6]) -> BiosResult {
        // TROL's own: the cartesian readings are computed with it from the joints.
        self.tool = tool;
        Ok(code::OK)
    }
    fn speed(&mut self, percent: u8) -> BiosResult {
        self.clean()?;
        if !(1..=100).contains(&percent) {
            return Ok(code::BAD_ARGUMENT);
        }
        if self.console_busy() {
            self.note(
                "refused: ash runs a motion to its end and reads no command until then: call                  TROLFinish(FINISH_WAIT) first"
                    .into(),
            );
            return Ok(BUSY);
        }
        let line = format!("speed {percent}");
        let lines = match self.exchange(&line) {
            Ok(l) => l,
            Err(e) => return Err(self.fail(e)),
        };
        if !lines.is_empty() {
            return Err(self.refusal(&line, &lines));
        }
        let lines = match self.exchange("speed") {
            Ok(l) => l,
            Err(e) => return Err(self.fail(e)),
        };
        match reports::speed(&lines) {
            Ok(v) if v == percent => {
                self.speed = v;
                Ok(code::OK)
            }
            Ok(v) => Err(self.unsure(format!("`{line}` taken, and `speed` then says {v}"))),
            Err(e) => Err(self.unsure(e.to_string())),
        }
    }
    fn position(&mut self, tag: Tag, mode: PosMode) -> Result<Location, BackendError> {
        self.clean()?;
        if self.console_busy() {
            // ash runs the motion and reads no command until its end.
            return Err(BackendError::Refused(BUSY));
        }
        let p = self.read_position(mode == PosMode::Actual)?;
        let q = p.joints_deg.map(f64::to_radians);
        Ok(match tag {
            Tag::Joint => Location::from_array6(Tag::Joint, q),
            Tag::Cart => Location::from_array6(Tag::Cart, Kinematics::new(self.tool).fk_xyzypr(&q)),
            Tag::Prec => Location::Prec(p.pulses.iter().map(|&x| x as i32).collect()),
        })
    }
    fn take_note(&mut self) -> Option<String> {
        self.note.take()
    }
    fn report(&mut self) -> Option<ArmReport> {
        if self.broken.is_some() || self.console_busy() {
            return None;
        }
        let p = self.read_position(true).ok()?;
        Some(ArmReport {
            joints: p.joints_deg.map(f64::to_radians),
            moving: self.outstanding.is_some() || !self.queue.is_empty(),
            tool: self.tool,
            homed: Some([self.stat.homing == Homing::Homed; 6]),
            ..ArmReport::default()
        })
    }
}

impl C500cBackend {
    /// ash runs a command of TROL's to its end (a motion with `motion-return = "end"`, or
    /// `finish`) and reads no other until its prompt.
    fn console_busy(&self) -> bool {
        self.outstanding.as_ref().is_some_and(|o| o.prompt_due)
    }

    /// Read where the arm rests (`w2`), unless it was read a moment ago ([`FRESH_REST`]).
    fn fresh_rest(&mut self) -> Result<(), BackendError> {
        if self.rest_at.elapsed() > FRESH_REST {
            self.rest = self.read_position(true)?.joints_deg;
            self.rest_at = Instant::now();
        }
        Ok(())
    }

    /// A location by name: TROL keeps no table of the C500C's yet (its ash variables are
    /// for later), so no name is known.
    fn named(&mut self, target: &Target) -> Result<(), BackendError> {
        match target {
            Target::Name(name) => Err(BackendError::UnknownLocation(*name)),
            Target::Location(_) => Ok(()),
        }
    }

    fn cartesian(&mut self) -> BiosResult {
        self.unsettled(
            "a cartesian motion needs the composition order of the WORLD row's Z-Rot, Y-Rot \
             and X-Rot on a C500C, which no public source settles yet",
        )
    }

    fn no_gripper(&mut self) -> BiosResult {
        self.note(
            "refused before sending: ash's grip commands take a form TROL does not know yet".into(),
        );
        Ok(UNSUPPORTED)
    }

    /// A joint motion by `d` degrees: one `joint n,deg` where one joint changes; several
    /// never go as a series of them.
    fn relative(&mut self, d: [f64; 6]) -> BiosResult {
        // A joint that changes by no more than an arm standing still dithers does not move.
        let moved: Vec<usize> = (0..6).filter(|&j| d[j].abs() > real::STILL_DEG).collect();
        match moved[..] {
            [] => Ok(code::OK),
            [j] => self.joint(j as u8 + 1, d[j].to_radians()),
            _ => self.unsettled(
                "a motion of several joints at once needs a joint-space location on the \
                 C500C, which needs the A465's pulses per degree there (not settled); a series \
                 of `joint` commands would not be one motion",
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_code_is_named_once() {
        for (i, a) in C500C_CODES.iter().enumerate() {
            for b in &C500C_CODES[i + 1..] {
                assert_ne!(a.value, b.value, "{} and {}", a.name, b.name);
            }
        }
    }
}

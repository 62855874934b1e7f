//! The robot backend for an A465 on a C500C (port `c500c:DEVICE`; docs/c500c.md): TROL's
//! calls as ash commands on the front console, under the rule for real controllers and on
//! the shared core ([`trol_controller::real`]):
//!
//! - success only in ash's exact success form (the echo, no line, the prompt); a known error
//!   text of CRS's tables is a refusal with its code and text; any other line, a question
//!   TROL did not ask, a silence where the prompt was due: TROL_ERR_ROBOT_UNSURE, and
//!   nothing further is sent;
//! - a line nobody asked for (`[test: Caught SIGABRT]`) makes the next call UNSURE; ash's
//!   `[test: Lost robot power]` drops the queue and leaves the power's code to the gate and
//!   the motion's end;
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
use trol_proto::application::{CodeInfo, CodeTable, Gripper, Held, LocName, Location, Tag};

use crate::console::{self, Console, Said};
use crate::profile::{MotionReturn, Profile};
use crate::reports::{self, ArmStat, Homing, Known};

mod backup;
mod bios;
pub(crate) mod cartesian;
mod gripper;
mod motion;
mod precision;
mod teach;

pub use backup::{Backup, Restored, Saved};
pub use bios::{HALT_STOPS, HaltStop};
pub use cartesian::{AGREE_DEG, AGREE_MM, ARRIVE_MM, ARRIVE_TURN_DEG, SCRATCH};
pub use gripper::{JAWS_AT_MM, JAWS_STILL_FOR, JAWS_WITHIN};
pub use teach::ARRIVE_PULSES;

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
/// The longest a Halt takes: each of its stops ([`bios::HALT_STOPS`]) with its prompt and the
/// readings that show the arm standing.
pub const HALT_WITHIN: Duration = Duration::from_millis(5500);
/// How long ash's prompt may take after one of Halt's stops before the next is tried.
pub const STOP_PROMPT: Duration = Duration::from_millis(1000);
/// How long a reading of where the arm rests serves a motion computed from it, with nothing
/// but reads ([`crate::probe::READS`]) typed since: the rule of [`real::Recent`], shared by
/// every real controller. Any other line (a motion, `speed p`, `finish`, Ctrl-C) forgets it.
pub use trol_controller::real::SEEN_FOR as FRESH_REST;
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
    /// The echo of a line differed from what was typed, and Ctrl-C took the line back before
    /// its line end: nothing ran.
    Damaged(String),
    /// A line that is not a read, on a console where TROL cannot check a line before it
    /// runs (no echo, or Ctrl-C does not take a typed line back): not sent.
    Unchecked(String),
}

impl Fail {
    fn into_backend(self) -> BackendError {
        match self {
            Fail::Io(e) => BackendError::Unsure(format!("the console failed: {e}")),
            Fail::Silent(s) | Fail::Unsure(s) => BackendError::Unsure(s),
            Fail::Damaged(s) => BackendError::Link(s),
            Fail::Unchecked(_) => BackendError::Refused(UNSUPPORTED),
        }
    }

    fn text(&self) -> String {
        match self {
            Fail::Io(e) => format!("the console failed: {e}"),
            Fail::Silent(s) | Fail::Unsure(s) | Fail::Damaged(s) | Fail::Unchecked(s) => s.clone(),
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
    /// `move var` to a precision point read back at these pulses.
    Named([i64; 6]),
    /// A cartesian motion: where the flange ends, and the motion's planned time, s.
    Pose(trol_a465::kinematics::Pose, f64),
    /// Worked out as it goes ([`C500cBackend::resolve`]): one of the kinds above then.
    Pending(cartesian::Pending),
}

struct Outstanding {
    motion: Motion,
    /// Where the motion ends, degrees (a home: where the arm is read once homed; a
    /// precision point: its pulses, [`Kind::Named`]).
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
    /// Where the arm was last seen at rest, degrees.
    rest: [f64; 6],
    /// The same, while it may stand in for a `w2` before a motion ([`FRESH_REST`]).
    rest_seen: real::Recent<[f64; 6]>,
    /// What `armstat` said, while it may stand in for the gate's `armstat` before a motion:
    /// as read, or as a motion that ash ran to its end and the arm was seen to end found it.
    stat_seen: real::Recent<ArmStat>,
    /// A Home was halted on its way: the next Finish fails with BIOS_NOT_HOMED (issue 62: a
    /// halted Home on a homed arm was reported done).
    homing_halted: bool,
    speed: u8,
    unasked: Vec<String>,
    broken: Option<String>,
    outstanding: Option<Outstanding>,
    queue: real::MotionQueue<Motion>,
    note: Option<String>,
    /// The gripper ash is set up for, once read.
    grip_kind: Option<gripper::GripKind>,
    /// A grip command whose end is still to be seen.
    jaws_wait: Option<gripper::JawsWait>,
    /// The WORLD row was seen, this session, to agree with the profile's `world-angles` at
    /// a pose where the two readings differ.
    angles_seen: bool,
    /// A cartesian location's constant was seen to hold the WORLD row's values in the row's
    /// order ([`C500cBackend::cloc_order`]).
    cloc_order_seen: bool,
    /// Per joint: a `w2` read this session agreed with the profile's pulses with the joint a
    /// degree or more from its zero.
    pulses_seen: [bool; 6],
    /// A `w2` read this session that disagreed with the profile's pulses.
    pulses_wrong: Option<String>,
    /// The console echoes what is typed (seen at connect).
    echo: bool,
    /// Ctrl-C takes a typed line back (seen at connect: `w`, Ctrl-C, and `robotver` printed
    /// the version, not an error of `wrobotver`).
    cancels: bool,
}

impl std::fmt::Debug for C500cBackend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("C500cBackend")
            .field("version", &self.version)
            .field("profile", &self.profile)
            .finish_non_exhaustive()
    }
}

/// The lines ash printed, each trimmed, blank ones left out.
fn said(lines: &[String]) -> Vec<&str> {
    lines
        .iter()
        .map(|l| l.trim())
        .filter(|l| !l.is_empty())
        .collect()
}

/// `got` is as long as the echo of `typed` at least, and differs from it in at most half its
/// bytes: the echo, damaged (a line of the console's own differs from it almost everywhere).
fn alike(got: &[u8], typed: &[u8]) -> bool {
    got.len() >= typed.len()
        && 2 * got.iter().zip(typed).filter(|(a, b)| a != b).count() <= typed.len()
}

/// A value as TROL types it into ash: three decimals, and no `-0.000`.
fn fmt3(x: f64) -> String {
    let x = if x.abs() < 0.0005 { 0.0 } else { x };
    format!("{x:.3}")
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
            rest_seen: real::Recent::new(),
            stat_seen: real::Recent::new(),
            homing_halted: false,
            speed: 0,
            unasked: Vec::new(),
            broken: None,
            outstanding: None,
            queue: real::MotionQueue::new(trol_a465::arm::MOTION_QUEUE),
            note: None,
            grip_kind: None,
            jaws_wait: None,
            angles_seen: false,
            cloc_order_seen: false,
            pulses_seen: [false; 6],
            pulses_wrong: None,
            echo: true,
            cancels: true,
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
                            "`{cmd}` did not start ash (the console said {}): start it at a \
                             terminal to see why",
                            console::heard(&other)
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
        b.line_checks()?;
        let mut lines = read(&mut b, "robotver")?;
        if reports::robotver(&lines).is_err() && b.cancels {
            // The `w` that Ctrl-C should have taken back ran with `robotver` as one line.
            b.cancels = false;
            b.say(&format!(
                "Ctrl-C did not take back a typed `w`: `robotver` after it printed `{}`; TROL \
                 sends only reads (a damaged line could not be taken back)",
                lines.join(" | ")
            ));
            lines = read(&mut b, "robotver")?;
        }
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
        let rest = reports::position(&lines, true)
            .map_err(|e| C500cError::Unexpected(e.to_string()))?
            .joints_deg;
        b.rests_at(rest);
        Ok(b)
    }

    /// How long where the arm was seen to rest stands in for a `w2` before a motion
    /// ([`FRESH_REST`] by default; zero: a `w2` before every motion). For tests, and for a
    /// cautious application.
    pub fn set_seen_for(&mut self, d: Duration) {
        self.rest_seen.set_window(d);
        self.stat_seen.set_window(d);
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
        // Anything but a read (or the line end of one) may change what the arm does: where it
        // was seen to rest no longer stands in for a `w2`.
        let line = std::str::from_utf8(bytes).unwrap_or("").trim_end();
        if !line.is_empty() && !crate::probe::READS.contains(&line) {
            self.rest_seen.forget();
            self.stat_seen.forget();
        }
        self.port.send(bytes)
    }

    /// The arm seen at rest at `at` (degrees), now.
    fn rests_at(&mut self, at: [f64; 6]) {
        self.rest = at;
        self.rest_seen.saw(Instant::now(), Some(at));
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

    /// At connect, at ash's prompt: whether the console echoes what is typed, and whether
    /// Ctrl-C takes a typed line back (the public sources settle neither). `w` is typed, then
    /// Ctrl-C; the `robotver` that follows shows whether `w` was kept.
    fn line_checks(&mut self) -> Result<(), C500cError> {
        self.send(b"w")?;
        let deadline = Instant::now() + REPLY_LIMIT;
        let before = self.rx.len();
        while self.console.echo().is_empty() && self.rx.len() == before {
            let mut buf = [0u8; 64];
            let n = self.port.recv(&mut buf, deadline)?;
            if n == 0 {
                break;
            }
            let said = self.console.feed(&buf[..n]);
            self.rx.extend(said);
        }
        let echo = self.console.echo().to_vec();
        match echo.as_slice() {
            b"w" => self.echo = true,
            b"" if self.rx.len() == before => {
                self.echo = false;
                self.say(
                    "the console echoes nothing typed: TROL cannot see a line whole before ash \
                     runs it, and sends only reads (docs/c500c.md, The line)",
                );
            }
            other => {
                let _ = self.send(b"\x03");
                return Err(C500cError::Unexpected(format!(
                    "`w` typed at ash's prompt came back as `{}`: a noisy line? Check the \
                     cable, then connect again",
                    console::text(other)
                )));
            }
        }
        self.send(b"\x03")?;
        self.back_to_prompt()
            .map_err(|e| C500cError::Unexpected(e.text()))
    }

    /// After a Ctrl-C at ash's prompt: its prompt again, with nothing before it but blank
    /// lines, `^C` and the echo of what was typed. A line of another form: UNSURE.
    fn back_to_prompt(&mut self) -> Result<(), Fail> {
        let app = self.profile.app.clone();
        let deadline = Instant::now() + REPLY_LIMIT;
        loop {
            match self.next(deadline).map_err(Fail::Io)? {
                Some(Said::Prompt(p)) if p == app => return Ok(()),
                Some(Said::Line(l))
                    if console::bracketed(&l).is_some() && reports::known_error(&l).is_none() =>
                {
                    self.unasked_line(l);
                }
                Some(Said::Line(l)) if reports::known_error(&l).is_none() && !l.contains(':') => {}
                Some(other) => {
                    return Err(Fail::Unsure(format!(
                        "after Ctrl-C the console said {}, not only ash's prompt",
                        other
                    )));
                }
                None => {
                    return Err(Fail::Unsure(format!(
                        "Ctrl-C got no prompt of ash's back within {REPLY_LIMIT:?}"
                    )));
                }
            }
        }
    }

    /// Type `cmd` and commit it with its line end only once its echo is seen whole and equal
    /// (issue 62: ash's console has no check sum; the echo is the only check there is). An
    /// echo that differs, or none, and the line is taken back with Ctrl-C before its line
    /// end: nothing ran. On a console where a line cannot be checked so, only reads are
    /// typed.
    fn type_line(&mut self, cmd: &str) -> Result<(), Fail> {
        let read = crate::probe::READS.contains(&cmd);
        let checked = self.echo && self.cancels;
        if !read && !checked {
            return Err(Fail::Unchecked(format!(
                "refused before sending `{cmd}`: {} so TROL cannot make sure a line runs as \
                 typed (ash's console has no check sum) and sends only reads (docs/c500c.md, \
                 The line)",
                if self.echo {
                    "Ctrl-C did not take back a typed line at connect,"
                } else {
                    "the console does not echo what is typed,"
                }
            )));
        }
        self.send(cmd.as_bytes()).map_err(Fail::Io)?;
        if self.echo {
            self.see_echo(cmd)?;
        }
        self.send(b"\r").map_err(Fail::Io)
    }

    /// Read until the echo of `cmd` is whole; one that differs, or none: take the line back.
    /// A line the console prints of its own before the echo (unasked, or a motion's end) is
    /// kept for the reply's reading: what is not the start of the echo is waited on to its
    /// line end, unless it is as long as the echo and alike (a damaged echo). A line end
    /// within the echo is damage.
    fn see_echo(&mut self, cmd: &str) -> Result<(), Fail> {
        let cmd_bytes = cmd.as_bytes();
        let deadline = Instant::now() + REPLY_LIMIT;
        loop {
            let got = self.console.echo();
            if got == cmd_bytes {
                return Ok(());
            }
            if !cmd_bytes.starts_with(got) && alike(got, cmd_bytes) {
                let what = format!("`{}`", console::text(got));
                return Err(self.take_back(cmd, what, false));
            }
            let mut buf = [0u8; 512];
            let n = self.port.recv(&mut buf, deadline).map_err(Fail::Io)?;
            if n == 0 {
                let what = format!(
                    "`{}` and no more within {REPLY_LIMIT:?}",
                    console::text(got)
                );
                return Err(self.take_back(cmd, what, false));
            }
            let mut within = Vec::new();
            for &byte in &buf[..n] {
                let echoing = {
                    let e = self.console.echo();
                    !e.is_empty() && cmd_bytes.starts_with(e)
                };
                let said = self.console.feed(&[byte]);
                if echoing {
                    within.extend(said.iter().map(Said::to_string));
                }
                self.rx.extend(said);
            }
            if !within.is_empty() {
                within.push(format!("`{}`", console::text(self.console.echo())));
                return Err(self.take_back(cmd, within.join(", then "), true));
            }
        }
    }

    /// The echo of `cmd` came back as `what`: Ctrl-C before its line end, and ash's prompt.
    /// `ended`: a line end or a prompt came within the echo (a byte damaged into a line end
    /// may have run part of the line): UNSURE. A motion under way is stopped by the Ctrl-C:
    /// UNSURE too.
    fn take_back(&mut self, cmd: &str, what: String, ended: bool) -> Fail {
        let moving = self.outstanding.is_some() || self.jaws_wait.is_some();
        if let Err(e) = self.send(b"\x03") {
            return Fail::Io(e);
        }
        if ended {
            // What the console said within the echo is not read again as an answer.
            self.rx.clear();
        }
        if let Err(e) = self.back_to_prompt() {
            return Fail::Unsure(format!(
                "`{cmd}` came back from the console as {what}; TROL typed Ctrl-C before its \
                 line end, and {}: whether the line is gone is not known",
                e.text()
            ));
        }
        if ended {
            return Fail::Unsure(format!(
                "`{cmd}` came back from the console as {what}: a line end within the echo may \
                 have run part of the line; Ctrl-C sent, and TROL sends nothing further (check \
                 the arm and the cable, then reconnect)"
            ));
        }
        if moving {
            return Fail::Unsure(format!(
                "`{cmd}`, typed while a motion or the gripper ran, came back from the console \
                 as {what}: TROL took it back with Ctrl-C, which stops the motion; check the \
                 arm, then reconnect"
            ));
        }
        Fail::Damaged(format!(
            "`{cmd}` came back from the console as {what}: TROL took the line back with Ctrl-C \
             before its line end, so nothing ran; call again (more of this: check the cable)"
        ))
    }

    /// Send `cmd` and read to ash's prompt: the lines between (the echo taken off).
    fn exchange(&mut self, cmd: &str) -> Result<Vec<String>, Fail> {
        self.type_line(cmd)?;
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
                Some(Said::Line(l)) if !echo_seen && l.trim() == cmd => echo_seen = true,
                // A bracketed line with an error of CRS's tables is the command's (ash may
                // print a robot error so); any other is unasked.
                Some(Said::Line(l))
                    if console::bracketed(&l).is_some() && reports::known_error(&l).is_none() =>
                {
                    self.unasked_line(l);
                }
                Some(Said::Line(l)) => {
                    echo_seen = true;
                    lines.push(l);
                }
            }
        }
    }

    /// A line ash printed of its own. `[<app>: Lost robot power]` (ash's, public) says what
    /// happened: the arm stands without power. Motions queued behind one under way are
    /// dropped unsent, the last `armstat` is forgotten (the next motion's gate reads it
    /// again: BIOS_ARM_POWER until the power is back), and a motion under way ends in the
    /// power's code when its end is looked for; nothing is UNSURE for it. Any other line
    /// makes the next call UNSURE.
    fn unasked_line(&mut self, l: String) {
        let lost = console::bracketed(&l)
            .is_some_and(|b| b.trim() == format!("{}: Lost robot power", self.profile.app));
        if lost {
            self.say(&format!("the arm lost its power: {l}"));
            if !self.queue.is_empty() {
                let n = self.queue.len();
                self.queue.drop_all();
                self.note(format!(
                    "{n} queued motion(s) dropped, not sent: the arm lost its power"
                ));
            }
            self.stat_seen.forget();
            return;
        }
        self.say(&format!("unasked: {l}"));
        self.unasked.push(l);
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
                    Said::Line(l) if !l.trim().is_empty() => self.unasked_line(l),
                    Said::Line(_) => {}
                    other => self.unasked.push(other.to_string()),
                }
            }
        }
        if !self.unasked.is_empty() && self.broken.is_none() {
            let lines = std::mem::take(&mut self.unasked).join(" | ");
            self.queue.drop_all();
            self.outstanding = None;
            self.jaws_wait = None;
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
        self.jaws_wait = None;
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
        let p = reports::position(&lines, actual).map_err(|e| self.unsure(e.to_string()))?;
        // Held against the profile's pulses only with no motion of TROL's under way (a moving
        // arm's two rows need not be one instant's); a motion's end is noted where Finish
        // sees it arrive.
        if actual && self.outstanding.is_none() {
            self.note_pulses(&p);
        }
        Ok(p)
    }

    fn fail(&mut self, e: Fail) -> BackendError {
        if let Fail::Damaged(why) | Fail::Unchecked(why) = &e {
            self.note(why.clone());
        }
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

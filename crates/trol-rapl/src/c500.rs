//! The simulated C500 in RAPL-II mode: the host port as a real controller's would look, backed
//! by the simulated A465 (c500-rapl.md §1.8). Sans-IO: bytes in with the simulation time,
//! bytes out; `trol sim --rapl` paces them at the baud rate over a real port.
//!
//! - ACI mode at start ([`crate::aci::Slave`]: both entry variants of the 0x48 transfer),
//!   two Ctrl-Z back to it (or terminal mode at start: `entry = "terminal"`);
//! - terminal mode: echo (upper-cased), Ctrl-C cancels the line and prompts, backspace,
//!   HELP mode on at start with keyword completion (the rest of the word and two blanks,
//!   an assumption fitting RW's five-byte read after `NOH`) until NOHELP, the profile's
//!   `extra_after_digit` bytes (`[twin] extra_byte`, spaces by default) after the first
//!   character of a number (assumption: RW read 4 bytes it never explained), ACK (unless
//!   `ack = "never"`) and the prompt;
//! - every point the public sources leave open is a switch ([`crate::profile::Twin`] and the
//!   profile's conventions), and [`VARIANTS`] names the matrix the backend's tests run across;
//! - a finite type-ahead buffer: while a command waits (FINISH, or a motion behind another,
//!   which waits for the first to end), input queues and XOFF goes out when it fills, XON
//!   when it drains; the host's XOFF stops the output;
//! - the commands of c500-rapl.md's table, their refusals as error lines (the numbers of
//!   [`SIM_ERRORS`]), and the reply layouts of [`crate::text`].

use std::collections::{BTreeMap, VecDeque};

use trol_a465::arm::{self, Arm, Stored, Which, code};
use trol_a465::model::{counts_to_joints, joints_to_counts};

use crate::aci::Slave;
use crate::frames::Frames;
use crate::profile::{
    Ack, Entry, Halt, JointUnits, Profile, RefusalForm, SIM_ERRORS, TwinFinish, Units,
};
use crate::session::{ACK, CTRL_C, CTRL_Z, XOFF, XON};
use crate::text::{self, Listed, Position, Status};

/// Type-ahead capacity, bytes (assumption).
pub const TYPEAHEAD: usize = 64;
/// XOFF goes out when this many bytes wait.
pub const XOFF_AT: usize = 48;
/// XON goes out when no more than this many wait.
pub const XON_AT: usize = 16;

/// The keywords the simulated C500 knows.
pub const KEYWORDS: &[&str] = &[
    "ABORT", "ACTUAL", "APPRO", "ARM", "CLOSE", "DELAY", "DEPART", "DLOC", "DLOCN", "ENABLE",
    "FINISH", "GRIP", "HALT", "HELP", "HERE", "HOME", "JOG", "JOINT", "LIMP", "LISTL", "LLOC",
    "MA", "MI", "MOVE", "MOVES", "NOHELP", "NOLIMP", "OPEN", "POINT", "READY", "SERIAL", "SET",
    "SPEED", "STATUS", "TOOL", "W0", "W2", "W5",
];

#[derive(Debug)]
enum Mode {
    Aci(Slave),
    Terminal,
}

#[derive(Debug)]
enum Waiting {
    /// A motion answered at its end (`motion_ack = "end"`): ACK once the arm is idle.
    Finish,
    /// The FINISH command: ACK once the arm is idle (or the `finish_stopped` error when the
    /// motion stopped short).
    FinishCommand,
    /// A motion behind another: run it once the arm is idle.
    Motion(String),
}

/// The controllers the public sources allow, one per open point (docs/c500.md, "What TROL
/// assumes"): a name, what it changes, and the profile that makes the simulated C500 play
/// it. `trol sim --rapl --variant NAME` serves one; the backend's tests run across all.
pub const VARIANTS: &[(&str, &str)] = &[
    (
        "default",
        "the simulator's own readings of every open point",
    ),
    (
        "colon-refusal",
        "refusals as `:NNN-TEXT.` (the form of the only public program error)",
    ),
    (
        "stars-refusal",
        "refusals as `*** TEXT ***`, without a number",
    ),
    ("no-period", "refusals as `NNN-TEXT`, without the period"),
    (
        "ack-at-end",
        "a motion's ACK and prompt come at its end; Ctrl-C halts",
    ),
    (
        "done-lag",
        "the DONE row still says done for 0.3 s after a motion's ACK",
    ),
    (
        "estop-line",
        "an emergency stop prints `*** EMERGENCY STOP ***` unasked",
    ),
    (
        "warning-then-ack",
        "a numbered warning line before the ACK of every motion",
    ),
    (
        "no-ack",
        "no ACK on success (the G3000 driver never looks for one)",
    ),
    ("ma-radians", "MA and MI take radians (R2JSON, RobWork)"),
    ("inch", "lengths in inches (RobWork's controller)"),
    (
        "world-offset",
        "WORLD angles of a model with identity orientation at all joints zero",
    ),
    (
        "pulses-g3000",
        "one pulse per encoder line and a negative sign (the G3000 driver's table)",
    ),
    (
        "nul-after-digit",
        "four NUL bytes after a number's first character",
    ),
    ("no-echo", "echo off (RAPL-II's CONFIG ECHO)"),
    ("not-homed", "the arm is not homed at power-up"),
    (
        "finish",
        "completion = \"finish\": FINISH waits in immediate mode, Ctrl-C ends it",
    ),
    (
        "finish-trusted",
        "as finish, and FINISH after a motion stopped short answers 037, never ACK \
         (finish_ack_means_arrived)",
    ),
    (
        "finish-at-once",
        "as finish, but FINISH answers at once while the arm still moves",
    ),
    (
        "finish-refused",
        "as finish, but FINISH is refused in immediate mode (program mode only, as R2JSON lists it)",
    ),
    (
        "jog-tool",
        "JOG moves along the tool's axes, not the world's (jog_frame = \"tool\")",
    ),
    (
        "halt-ignored",
        "HALT is acknowledged but does not stop a motion (ABORT does)",
    ),
    (
        "ctrl-c-cancels-line",
        "as ack-at-end, but Ctrl-C only cancels the line (RobWork's reading); HALT stops",
    ),
    (
        "unstoppable",
        "no stop stops a motion (HALT and ABORT acknowledged, Ctrl-C cancels the line): a \
         fault, for the rule that Halt never says done unseen",
    ),
    (
        "finish-deaf",
        "as finish, but Ctrl-C is ignored while FINISH waits (the profile's \
         ctrl_c_ends_finish is wrong)",
    ),
];

/// The profile of variant `name` (see [`VARIANTS`]), and whether its arm starts homed.
pub fn variant(name: &str) -> Option<(Profile, bool)> {
    let base = Profile::simulator();
    let twin = base.twin.clone();
    let p = match name {
        "default" | "not-homed" => base,
        "colon-refusal" => Profile {
            twin: crate::profile::Twin {
                refusal: ":NNN-TEXT.".into(),
                ..twin
            },
            ..base
        },
        "stars-refusal" => Profile {
            twin: crate::profile::Twin {
                refusal: "*** TEXT ***".into(),
                ..twin
            },
            ..base
        },
        "no-period" => Profile {
            twin: crate::profile::Twin {
                refusal: "NNN-TEXT".into(),
                ..twin
            },
            ..base
        },
        "ack-at-end" => Profile {
            motion_ack: crate::profile::MotionAck::End,
            halt: Halt::CtrlC,
            ..base
        },
        "done-lag" => Profile {
            twin: crate::profile::Twin {
                done_lag_ms: 3000,
                ..twin
            },
            ..base
        },
        "estop-line" => Profile {
            twin: crate::profile::Twin {
                estop_line: "*** EMERGENCY STOP ***".into(),
                ..twin
            },
            ..base
        },
        "warning-then-ack" => Profile {
            twin: crate::profile::Twin {
                motion_warning: "101-NEAR JOINT LIMIT.".into(),
                ..twin
            },
            ..base
        },
        "no-ack" => Profile {
            ack: Ack::Never,
            twin: crate::profile::Twin {
                refusal: "*** TEXT ***".into(),
                ..twin
            },
            ..base
        },
        "ma-radians" => Profile {
            joint_units: "radians".into(),
            ..base
        },
        "inch" => Profile {
            units: Units::Inch,
            ..base
        },
        "world-offset" => Profile {
            tool_rotation: [0.0, 90.0, 0.0],
            ..base
        },
        "pulses-g3000" => Profile {
            pulse_scale: trol_a465::model::ENCODER_LINES
                .iter()
                .zip(trol_a465::model::GEAR_RATIOS)
                .map(|(l, g)| -l * g / 360.0)
                .collect(),
            pulse_zero: vec![120.0, -40.0, 7.0, 0.0, 2.0, -9.0],
            ..base
        },
        "nul-after-digit" => Profile {
            twin: crate::profile::Twin {
                extra_byte: 0,
                ..twin
            },
            ..base
        },
        "no-echo" => Profile {
            twin: crate::profile::Twin {
                echo: false,
                ..twin
            },
            ..base
        },
        "jog-tool" => Profile {
            jog_frame: "tool".into(),
            twin: crate::profile::Twin {
                jog_tool: true,
                ..twin
            },
            ..base
        },
        "halt-ignored" => Profile {
            twin: crate::profile::Twin {
                halt_stops: false,
                ..twin
            },
            ..base
        },
        "ctrl-c-cancels-line" => Profile {
            motion_ack: crate::profile::MotionAck::End,
            halt: Halt::CtrlC,
            twin: crate::profile::Twin {
                ctrl_c_stops: Some(false),
                ..twin
            },
            ..base
        },
        "unstoppable" => Profile {
            twin: crate::profile::Twin {
                halt_stops: false,
                abort_stops: false,
                ctrl_c_stops: Some(false),
                ..twin
            },
            ..base
        },
        "finish" | "finish-trusted" | "finish-at-once" | "finish-refused" | "finish-deaf" => {
            let twin = crate::profile::Twin {
                finish: match name {
                    "finish-at-once" => TwinFinish::AtOnce,
                    "finish-refused" => TwinFinish::Refused,
                    _ => TwinFinish::Waits,
                },
                finish_ctrl_c: name != "finish-deaf",
                finish_stopped: if name == "finish-trusted" { 37 } else { 0 },
                ..twin
            };
            Profile {
                completion: crate::profile::Completion::Finish,
                ctrl_c_ends_finish: true,
                finish_ack_means_arrived: name == "finish-trusted",
                twin,
                ..base
            }
        }
        _ => return None,
    };
    Some((p, name != "not-homed"))
}

/// The text of the simulated C500's refusal of the probe's word, which tells it from a real
/// controller.
pub const SIMULATOR_SAYS: &str = "COMMAND ERROR, TROL SIMULATED C500";

/// The simulated C500.
pub struct C500 {
    profile: Profile,
    refusal: RefusalForm,
    acked_at: f64,
    frames: Frames,
    joint_units: JointUnits,
    arm: Arm,
    mode: Mode,
    help: bool,
    line: Vec<u8>,
    in_number: bool,
    swallow: VecDeque<u8>,
    out: VecDeque<u8>,
    host_xoff: bool,
    typeahead: VecDeque<u8>,
    xoff_sent: bool,
    waiting: Option<Waiting>,
    last_error: String,
    ctrl_z: u8,
    limp: bool,
    /// The last motion stopped short of its end (an emergency stop, a halt).
    stopped_short: bool,
    locations: BTreeMap<String, Stored>,
    log: Vec<String>,
}

fn is_numeric(b: u8) -> bool {
    b.is_ascii_digit() || b == b'.' || b == b'-'
}

impl C500 {
    /// A C500 as `profile` describes it, with `arm`, and the locations (names upper-cased).
    pub fn new(profile: Profile, arm: Arm, locations: Vec<(String, Stored)>) -> C500 {
        let mut frames = Frames::of(&profile);
        frames.mm = frames.mm.or(Some(1.0));
        frames.angles = frames
            .angles
            .or(crate::profile::parse_angles("yaw pitch roll")
                .ok()
                .flatten());
        let model = Frames::of(&Profile::simulator());
        frames.pulses = frames.pulses.or(model.pulses);
        let joint_units = profile
            .joint_units()
            .ok()
            .flatten()
            .unwrap_or(JointUnits::Degrees);
        let mode = if profile.entry == Entry::Terminal {
            Mode::Terminal
        } else {
            Mode::Aci(Slave::new(profile.slave))
        };
        let refusal = RefusalForm::parse(&profile.twin.refusal)
            .or_else(|_| RefusalForm::parse("NNN-TEXT."))
            .expect("the default form parses");
        // Precision points of a location file are the A465 model's counts: as this
        // controller's pulses.
        let locations = locations
            .into_iter()
            .map(|(n, l)| {
                let l = match l {
                    Stored::Prec(c) => {
                        let deg = counts_to_joints(&c.map(f64::from)).map(f64::to_degrees);
                        Stored::Prec(
                            frames
                                .joints_to_pulses(deg)
                                .unwrap_or_default()
                                .map(|p| p as i32),
                        )
                    }
                    other => other,
                };
                (n.to_ascii_uppercase(), l)
            })
            .collect();
        C500 {
            refusal,
            acked_at: f64::NEG_INFINITY,
            help: profile.help_at_start,
            frames,
            joint_units,
            arm,
            mode,
            line: Vec::new(),
            in_number: false,
            swallow: VecDeque::new(),
            out: VecDeque::new(),
            host_xoff: false,
            typeahead: VecDeque::new(),
            xoff_sent: false,
            waiting: None,
            last_error: "000-NO ERROR.".into(),
            ctrl_z: 0,
            limp: false,
            stopped_short: false,
            locations,
            log: Vec::new(),
            profile,
        }
    }

    /// The profile that describes this controller (`--print-profile`): its settings, with
    /// the units and conventions it uses filled in.
    pub fn describe(&self) -> Profile {
        let mut p = self.profile.clone();
        p.simulated = true;
        // The simulator is a process on a PC that may be busy: each echo gets the reply
        // timeout's 3 s, not a C500's 0.5 s (an opening failed so under two busy loops).
        p.echo_timeout_ms = p.echo_timeout_ms.max(3000);
        if p.angles().is_none() {
            p.angles = "yaw pitch roll".into();
        }
        if p.joint_units.is_empty() {
            p.joint_units = "degrees".into();
        }
        if p.pulse_scale.is_empty() {
            p.pulse_scale = Profile::simulator().pulse_scale;
        }
        if p.jog_frame.is_empty() {
            p.jog_frame = "world".into();
        }
        if !p.refusal.contains(&p.twin.refusal) {
            p.refusal = vec![p.twin.refusal.clone()];
        }
        if p.units == Units::Auto {
            p.units = Units::Mm;
        }
        p
    }

    /// The arm.
    pub fn arm_mut(&mut self) -> &mut Arm {
        &mut self.arm
    }

    /// Whether the port is in terminal mode.
    pub fn in_terminal_mode(&self) -> bool {
        matches!(self.mode, Mode::Terminal)
    }

    /// The command lines run since the last call, for the log.
    pub fn take_log(&mut self) -> Vec<String> {
        std::mem::take(&mut self.log)
    }

    /// Take bytes from the line at simulation time `now` (s).
    pub fn feed(&mut self, input: &[u8], now: f64) {
        for &b in input {
            if let Mode::Aci(slave) = &mut self.mode {
                let mut out = Vec::new();
                let switched = slave.feed(b, &mut out);
                self.out.extend(out);
                if switched {
                    self.mode = Mode::Terminal;
                    self.line.clear();
                    self.help = self.profile.help_at_start;
                }
                continue;
            }
            match b {
                XOFF => self.host_xoff = true,
                XON => self.host_xoff = false,
                CTRL_C
                    if matches!(self.waiting, Some(Waiting::FinishCommand))
                        && !self.profile.twin.finish_ctrl_c => {}
                CTRL_C => {
                    // At once, even while a command waits.
                    self.typeahead.clear();
                    // A waiting command is cancelled; the motion stops only where Ctrl-C is
                    // how this controller halts.
                    self.waiting = None;
                    let stops = self
                        .profile
                        .twin
                        .ctrl_c_stops
                        .unwrap_or(self.profile.halt == Halt::CtrlC);
                    if stops && self.arm.is_moving(now) {
                        self.stopped_short = true;
                        self.arm.halt(now);
                    }
                    self.line.clear();
                    self.swallow.clear();
                    self.in_number = false;
                    self.prompt();
                }
                _ => {
                    if self.typeahead.len() < TYPEAHEAD {
                        self.typeahead.push_back(b);
                    }
                }
            }
        }
        self.run(now);
    }

    /// Let time pass: a waiting command goes on once the arm is idle.
    pub fn tick(&mut self, now: f64) {
        if self.waiting.is_some() && !self.arm.is_moving(now) {
            match self.waiting.take() {
                Some(Waiting::Finish) => self.ok(""),
                Some(Waiting::FinishCommand) => match self.profile.twin.finish_stopped {
                    n if n > 0 && self.stopped_short => self.refuse(n),
                    _ => self.ok(""),
                },
                Some(Waiting::Motion(line)) => self.execute(&line, now),
                None => {}
            }
        }
        self.run(now);
    }

    /// Up to `max` bytes to put on the line (none while the host said XOFF, except XON and
    /// XOFF themselves).
    pub fn take_output(&mut self, max: usize) -> Vec<u8> {
        if self.host_xoff {
            return Vec::new();
        }
        let n = max.min(self.out.len());
        self.out.drain(..n).collect()
    }

    /// Whether output waits.
    pub fn has_output(&self) -> bool {
        !self.out.is_empty() && !self.host_xoff
    }

    fn run(&mut self, now: f64) {
        while self.waiting.is_none() {
            let Some(b) = self.typeahead.pop_front() else {
                break;
            };
            self.byte(b, now);
        }
        let waiting = self.typeahead.len();
        if !self.xoff_sent && waiting >= XOFF_AT {
            self.out.push_front(XOFF);
            self.xoff_sent = true;
        } else if self.xoff_sent && waiting <= XON_AT {
            self.out.push_front(XON);
            self.xoff_sent = false;
        }
    }

    fn prompt(&mut self) {
        self.out.extend(b"\r\n");
        self.out.extend(self.profile.prompt.bytes());
    }

    fn ok(&mut self, body: &str) {
        self.out.extend(body.bytes());
        self.ack_prompt();
    }

    fn ack_prompt(&mut self) {
        if self.profile.ack != Ack::Never {
            self.out.push_back(ACK);
        }
        self.prompt();
    }

    fn refuse(&mut self, number: u16) {
        let text = SIM_ERRORS
            .iter()
            .find(|e| e.0 == number)
            .map(|e| e.1)
            .unwrap_or("COMMAND ERROR");
        let line = self.refusal.write(number, text);
        self.out.extend(b"\n");
        self.out.extend(line.bytes());
        self.last_error = line;
        self.prompt();
    }

    fn byte(&mut self, b: u8, now: f64) {
        if b == CTRL_Z {
            self.ctrl_z += 1;
            if self.ctrl_z == 2 {
                self.ctrl_z = 0;
                self.mode = Mode::Aci(Slave::new(self.profile.slave));
                self.typeahead.clear();
                self.line.clear();
            }
            return;
        }
        self.ctrl_z = 0;
        let terminator = self.profile.terminator.byte();
        match b {
            _ if b == terminator => {
                if self.profile.twin.echo {
                    self.out.push_back(b);
                }
                let line = String::from_utf8_lossy(&self.line).trim().to_string();
                self.line.clear();
                self.swallow.clear();
                self.in_number = false;
                if line.is_empty() {
                    self.prompt();
                } else {
                    self.execute(&line, now);
                }
            }
            0x08 | 0x7F if self.line.pop().is_some() => self.out.extend(b"\x08 \x08"),
            0x20..=0x7E => {
                let c = b.to_ascii_uppercase();
                if self.swallow.front() == Some(&c) {
                    self.swallow.pop_front();
                    return;
                }
                self.swallow.clear();
                if self.line.len() >= 80 {
                    return;
                }
                self.line.push(c);
                let numeric = is_numeric(c);
                if self.profile.twin.echo {
                    self.out.push_back(c);
                    if numeric && !self.in_number {
                        for _ in 0..self.profile.extra_after_digit {
                            self.out.push_back(self.profile.twin.extra_byte);
                        }
                    }
                }
                self.in_number = numeric;
                if self.help {
                    self.complete();
                }
            }
            _ => {}
        }
    }

    /// HELP mode: a unique prefix of a keyword (not itself one) is completed.
    fn complete(&mut self) {
        if self.line.len() < 2 || self.line.contains(&b' ') {
            return;
        }
        let typed = String::from_utf8_lossy(&self.line).to_string();
        if KEYWORDS.contains(&typed.as_str()) {
            return;
        }
        let mut matches = KEYWORDS.iter().filter(|k| k.starts_with(&typed));
        if let (Some(k), None) = (matches.next(), matches.next()) {
            let rest = &k[typed.len()..];
            self.out.extend(rest.bytes());
            self.out.extend(b"  ");
            self.line = format!("{k} ").into_bytes();
            self.swallow = format!("{rest} ").bytes().collect();
        }
    }

    fn code_error(c: i16) -> u16 {
        match c {
            code::NOT_HOMED => 30,
            code::OUT_OF_REACH => 31,
            code::JOINT_LIMIT => 32,
            code::BELOW_TABLE => 33,
            code::SINGULAR_PATH => 34,
            code::QUEUE_FULL => 36,
            code::GRIPPER_BLOCKED => 38,
            _ => 12,
        }
    }

    fn answer(&mut self, c: i16) {
        if c == code::OK {
            self.ok("");
        } else {
            self.refuse(Self::code_error(c));
        }
    }

    /// A motion's answer: a refusal at once; an acceptance with the warning line (if any) and
    /// the ACK now, or once the motion ends (`ack_at_end`).
    fn motion_answer(&mut self, c: i16, now: f64) {
        if c != code::OK {
            return self.refuse(Self::code_error(c));
        }
        self.acked_at = now;
        self.stopped_short = false;
        if !self.profile.twin.motion_warning.is_empty() {
            let w = format!("\r\n{}\r\n", self.profile.twin.motion_warning);
            self.out.extend(w.bytes());
        }
        if self.profile.motion_ack == crate::profile::MotionAck::End && self.arm.is_moving(now) {
            self.waiting = Some(Waiting::Finish);
        } else {
            self.ack_prompt();
        }
    }

    /// This controller's pulses as the A465 model's counts.
    fn model_counts(&self, p: [i32; 6]) -> [f64; 6] {
        let deg = self
            .frames
            .pulses_to_joints(p.map(i64::from))
            .unwrap_or_default();
        joints_to_counts(&deg.map(f64::to_radians)).map(f64::from)
    }

    fn pulses_of(&self, q: &[f64; 6]) -> [i64; 6] {
        self.frames
            .joints_to_pulses(q.map(f64::to_degrees))
            .unwrap_or_default()
    }

    fn target(&self, name: &str) -> Option<arm::Target> {
        Some(match self.locations.get(name)? {
            Stored::Cart(v) => arm::Target::Cart(*v),
            Stored::Prec(c) => arm::Target::Prec(self.model_counts(*c)),
            // (RAPL-II has no joint locations: this controller never stores one.)
            Stored::Joints(q) => arm::Target::Joints(*q),
        })
    }

    fn position(&mut self, now: f64, which: Which) -> Position {
        let q = self.arm.position(now, which);
        let trol = self.arm.kinematics().fk_xyzypr(&q);
        Position {
            pulses: self.pulses_of(&q),
            joints: q.map(f64::to_degrees),
            world: self.frames.to_rapl(trol).unwrap_or([0.0; 6]),
        }
    }

    fn execute(&mut self, line: &str, now: f64) {
        self.log.push(line.to_string());
        let (word, rest) = match line.split_once(' ') {
            Some((w, r)) => (w.trim(), r.trim()),
            None => (line, ""),
        };
        let args: Vec<&str> = rest
            .split([',', ' '])
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .collect();
        let nums: Option<Vec<f64>> = args
            .iter()
            .map(|a| a.parse::<f64>().ok().filter(|v| v.is_finite()))
            .collect();
        let motion = matches!(
            word,
            "MOVE"
                | "MOVES"
                | "APPRO"
                | "DEPART"
                | "JOINT"
                | "MA"
                | "MI"
                | "JOG"
                | "READY"
                | "HOME"
        );
        if motion && self.limp {
            return self.refuse(37);
        }
        if motion && self.arm.is_moving(now) {
            // A second motion waits for the first to end (RW's reading, c500-rapl.md §1.1.7).
            self.waiting = Some(Waiting::Motion(line.to_string()));
            return;
        }
        let mm = self.frames.mm.unwrap_or(1.0);
        match (word, nums.as_deref()) {
            ("NOHELP", _) => {
                self.help = false;
                self.ok("")
            }
            ("HELP", _) => {
                self.help = true;
                self.ok("")
            }
            ("SPEED", Some([p])) if (1.0..=100.0).contains(p) => {
                self.arm.set_speed(*p);
                self.ok("")
            }
            ("READY", _) => {
                let c = self.arm.ready(now);
                self.motion_answer(c, now)
            }
            ("HOME", _) => {
                let c = self.arm.home(0, now);
                self.motion_answer(c, now)
            }
            ("MOVE" | "MOVES", _) if args.len() == 1 => match self.target(args[0]) {
                Some(t) => {
                    let c = self.arm.move_to(t, word == "MOVES", now);
                    self.motion_answer(c, now)
                }
                None => self.refuse(35),
            },
            ("APPRO", _) if args.len() >= 2 => {
                let (Some(t), Ok(d)) = (self.target(args[0]), args[1].parse::<f64>()) else {
                    return self.refuse(35);
                };
                let straight = args.get(2) == Some(&"S");
                let c = self
                    .arm
                    .appro(t, [-d * mm, 0.0, 0.0, 0.0, 0.0, 0.0], straight, now);
                self.motion_answer(c, now)
            }
            ("DEPART", _) if !args.is_empty() => {
                let Ok(d) = args[0].parse::<f64>() else {
                    return self.refuse(12);
                };
                let straight = args.get(1) == Some(&"S");
                let c = self
                    .arm
                    .depart([-d * mm, 0.0, 0.0, 0.0, 0.0, 0.0], straight, now);
                self.motion_answer(c, now)
            }
            ("JOINT", Some([j, deg])) if j.fract() == 0.0 && (1.0..=6.0).contains(j) => {
                let c = self.arm.joint(*j as u8, deg.to_radians(), now);
                self.motion_answer(c, now)
            }
            ("MA" | "MI", Some(q)) if q.len() == 6 => {
                let f = match self.joint_units {
                    JointUnits::Degrees => 1f64.to_radians(),
                    JointUnits::Radians => 1.0,
                };
                let v: [f64; 6] = std::array::from_fn(|i| q[i] * f);
                let c = if word == "MA" {
                    self.arm.ma(v, now)
                } else {
                    self.arm.mi(v, now)
                };
                self.motion_answer(c, now)
            }
            ("JOG", Some([x, y, z])) => {
                let mut d = [x * mm, y * mm, z * mm];
                if self.profile.twin.jog_tool {
                    // Along the tool's axes where the arm will be: the controller's tool
                    // frame is TROL's turned by the profile's tool_rotation.
                    let q = self.arm.planned_end();
                    let p = self.arm.kinematics().fk(&q);
                    let [ty, tp, tr] = self.profile.tool_rotation.map(f64::to_radians);
                    let off = trol_a465::kinematics::Pose::from_xyzypr([0.0, 0.0, 0.0, ty, tp, tr]);
                    let r = p.rot * off.rot;
                    let v = r.x_axis * d[0] + r.y_axis * d[1] + r.z_axis * d[2];
                    d = [v.x, v.y, v.z];
                }
                let c = self.arm.jog(d, true, now);
                self.motion_answer(c, now)
            }
            ("HALT" | "ABORT", _) => {
                let stops = if word == "HALT" {
                    self.profile.twin.halt_stops
                } else {
                    self.profile.twin.abort_stops
                };
                if stops {
                    if self.arm.is_moving(now) {
                        self.stopped_short = true;
                    }
                    self.arm.halt(now);
                }
                self.ok("")
            }
            ("FINISH", _) => match self.profile.twin.finish {
                TwinFinish::Refused => self.refuse(12),
                TwinFinish::Waits if self.arm.is_moving(now) => {
                    self.waiting = Some(Waiting::FinishCommand);
                }
                _ => match self.profile.twin.finish_stopped {
                    n if n > 0 && self.stopped_short => self.refuse(n),
                    _ => self.ok(""),
                },
            },
            ("GRIP", Some([d])) => {
                let c = self.arm.grip(d * mm, now);
                self.answer(c)
            }
            ("OPEN", Some(f)) if f.len() <= 1 => {
                let c = self.arm.open(f.first().copied().unwrap_or(50.0), now);
                self.answer(c)
            }
            ("CLOSE", Some(f)) if f.len() <= 1 => {
                let c = self.arm.close(f.first().copied().unwrap_or(50.0), now);
                self.answer(c)
            }
            ("POINT", _) if args.len() == 7 => {
                let name = args[0].to_string();
                let vals: Option<Vec<f64>> = args[1..]
                    .iter()
                    .map(|a| a.parse::<f64>().ok().filter(|v| v.is_finite()))
                    .collect();
                let Some(v) = vals else {
                    return self.refuse(12);
                };
                let v: [f64; 6] = std::array::from_fn(|i| v[i]);
                let stored = if name.starts_with('#') {
                    if v.iter().any(|p| p.fract() != 0.0 || p.abs() > 1e9) {
                        return self.refuse(12);
                    }
                    Stored::Prec(v.map(|p| p as i32))
                    // (this controller's pulses; MOVE converts them)
                } else {
                    match self.frames.from_rapl(v) {
                        Ok(t) => Stored::Cart(t),
                        Err(_) => return self.refuse(12),
                    }
                };
                self.locations.insert(name, stored);
                self.ok("")
            }
            ("TOOL", _) if args.len() == 1 => match self.locations.get(args[0]) {
                Some(Stored::Cart(v)) => {
                    let v = *v;
                    let c = self.arm.set_tool(v);
                    self.answer(c)
                }
                _ => self.refuse(35),
            },
            ("HERE" | "ACTUAL", _) if args.len() == 1 => {
                let which = if word == "HERE" {
                    Which::Commanded
                } else {
                    Which::Actual
                };
                let q = self.arm.position(now, which);
                let stored = if args[0].starts_with('#') {
                    Stored::Prec(self.pulses_of(&q).map(|p| p as i32))
                } else {
                    Stored::Cart(self.arm.kinematics().fk_xyzypr(&q))
                };
                self.locations.insert(args[0].to_string(), stored);
                self.ok("")
            }
            ("SET", _) => match rest.split_once('=') {
                Some((to, from)) => match self.locations.get(from.trim()).copied() {
                    Some(l) => {
                        self.locations.insert(to.trim().to_string(), l);
                        self.ok("")
                    }
                    None => self.refuse(35),
                },
                None => self.refuse(12),
            },
            ("DLOC" | "DLOCN", _) if !args.is_empty() => {
                for a in &args {
                    self.locations.remove(*a);
                }
                self.ok("")
            }
            ("LISTL" | "LLOC", _) => {
                let rows: Vec<(String, Listed)> = self
                    .locations
                    .iter()
                    .filter(|(n, _)| args.is_empty() || args.contains(&n.as_str()))
                    .map(|(n, l)| {
                        let listed = match l {
                            Stored::Cart(v) => {
                                Listed::Cart(self.frames.to_rapl(*v).unwrap_or([0.0; 6]))
                            }
                            Stored::Prec(p) => Listed::Prec(p.map(i64::from)),
                            Stored::Joints(q) => Listed::Prec(self.pulses_of(q)),
                        };
                        (n.clone(), listed)
                    })
                    .collect();
                if rows.is_empty() && !args.is_empty() {
                    return self.refuse(35);
                }
                let body = text::write_listl(&rows);
                self.ok(&body)
            }
            ("W0" | "W2", _) => {
                let which = if word == "W0" {
                    Which::Commanded
                } else {
                    Which::Actual
                };
                let p = self.position(now, which);
                let body = text::write_position(word == "W0", &p);
                self.ok(&body)
            }
            ("W5", _) => {
                let dt = 0.01;
                let a = self.arm.position((now - dt).max(0.0), Which::Commanded);
                let b = self.arm.position(now, Which::Commanded);
                let v: [f64; 6] = std::array::from_fn(|i| {
                    if self.arm.is_moving(now) {
                        ((b[i] - a[i]) / dt).to_degrees()
                    } else {
                        0.0
                    }
                });
                let body = text::write_velocity(&v);
                self.ok(&body)
            }
            ("STATUS", _) => {
                let lagging = now - self.acked_at < self.profile.twin.done_lag_ms as f64 / 1000.0;
                let moving = self.arm.is_moving(now) && !lagging;
                let s = Status {
                    version: "RAPL-II Version 2.60     A465 Robot (simulated)".into(),
                    last_error: self.last_error.clone(),
                    speed: self.arm.speed(),
                    lock: [false; 6],
                    done: [!moving; 6],
                    limp: [self.limp; 6],
                    homed: self.arm.homed(),
                    metric: match self.profile.units {
                        crate::profile::Units::Inch => Some(false),
                        _ => Some(true),
                    },
                };
                let tool = self.frames.to_rapl(self.arm.kinematics().tool());
                let body = text::write_status(&s, &tool.unwrap_or([0.0; 6]));
                self.ok(&body)
            }
            ("SERIAL", _) => {
                let body = format!(
                    "\n\r\nDEVICE 0: {} BAUD, NO PARITY, 8 DATA, 1 STOP, {}\r\n",
                    self.profile.baud,
                    if self.profile.flow == crate::profile::Flow::Xonxoff {
                        "XON/XOFF"
                    } else {
                        "NO HANDSHAKE"
                    }
                );
                self.ok(&body)
            }
            ("LIMP", _) => {
                self.limp = true;
                self.arm.halt(now);
                self.ok("")
            }
            ("NOLIMP" | "ENABLE", _) | ("ARM", _) if !rest.contains("OFF") => {
                self.limp = false;
                self.ok("")
            }
            ("DELAY", Some([_])) => self.ok(""),
            // The probe's unknown word: refused as any, with the simulator's name in the text,
            // so that a session with a simulator's profile knows it talks to the simulator.
            (crate::probe::PROBE_WORD, _) if self.profile.twin.names_itself => {
                let line = self.refusal.write(12, SIMULATOR_SAYS);
                self.out.extend(b"\n");
                self.out.extend(line.bytes());
                self.last_error = line;
                self.prompt();
            }
            _ => self.refuse(12),
        }
    }

    /// The teach pendant: move the arm to `joints` (radians) as an operator would by hand,
    /// whatever the host port is doing. Returns the arm's code (0, or why it refused).
    pub fn pendant(&mut self, joints: [f64; 6], now: f64) -> i16 {
        self.arm.ma(joints, now)
    }

    /// Whether a command waits for the arm (FINISH, or a motion behind another).
    pub fn is_waiting(&self) -> bool {
        self.waiting.is_some()
    }

    /// Whether the arm moves at `now`.
    pub fn arm_moving(&mut self, now: f64) -> bool {
        self.arm.is_moving(now)
    }

    /// Stop the arm where it is now without a word (a fault: a servo that gives up, a stop at
    /// the controller's panel): the DONE row says done, nothing is printed, power stays on.
    pub fn stall(&mut self, now: f64) {
        if self.arm.is_moving(now) {
            self.stopped_short = true;
        }
        self.arm.halt(now);
    }

    /// Cut the arm's power now (a fault: an e-stop), as LIMP does; a controller with an
    /// `estop_line` prints it unasked.
    pub fn power_off(&mut self, now: f64) {
        self.limp = true;
        if self.arm.is_moving(now) {
            self.stopped_short = true;
        }
        self.arm.halt(now);
        if !self.profile.twin.estop_line.is_empty() {
            let l = format!("\r\n{}\r\n", self.profile.twin.estop_line);
            self.out.extend(l.bytes());
            self.prompt();
        }
    }

    /// Whether the arm has power.
    pub fn has_power(&self) -> bool {
        !self.limp
    }

    /// Where the arm will be once every accepted motion has ended (radians), for tests that
    /// check that nothing moved unasked.
    pub fn planned_end(&self) -> [f64; 6] {
        self.arm.planned_end()
    }
}

/// Serve the simulated C500 on `port` until `stop` is set or the line fails: input is fed at
/// the simulation time (wall time × `time_scale`), output goes out paced at the profile's
/// baud rate (10 bits a byte). `log` gets each command line the controller ran.
pub fn serve(
    port: &mut dyn trol_port::Port,
    c: &mut C500,
    time_scale: f64,
    stop: &std::sync::atomic::AtomicBool,
    log: &mut dyn FnMut(&str),
) -> std::io::Result<()> {
    serve_with(port, c, time_scale, stop, log, &mut |_, _| {})
}

/// Like [`serve`], calling `each` with the controller and the simulation time on every turn
/// of the loop (at least every 2 ms): the teach pendant of `trol sim --rapl --pendant`, and
/// measurements that watch the arm.
pub fn serve_with(
    port: &mut dyn trol_port::Port,
    c: &mut C500,
    time_scale: f64,
    stop: &std::sync::atomic::AtomicBool,
    log: &mut dyn FnMut(&str),
    each: &mut dyn FnMut(&mut C500, f64),
) -> std::io::Result<()> {
    use std::time::{Duration, Instant};
    let epoch = Instant::now();
    let scale = time_scale.max(1e-3);
    let char_time = c.profile.char_time();
    let mut next_free = Instant::now();
    let mut buf = [0u8; 256];
    while !stop.load(std::sync::atomic::Ordering::Relaxed) {
        let wait = if c.has_output() {
            next_free.saturating_duration_since(Instant::now())
        } else {
            Duration::from_millis(2)
        };
        let n = port.recv(&mut buf, Instant::now() + wait)?;
        let now = epoch.elapsed().as_secs_f64() * scale;
        if n > 0 {
            c.feed(&buf[..n], now);
        }
        c.tick(now);
        each(c, now);
        for line in c.take_log() {
            log(&line);
        }
        let t = Instant::now();
        if next_free < t {
            next_free = t;
        }
        if c.has_output() && next_free <= t + char_time {
            // As many bytes as the line carries in a millisecond, at least one.
            let burst =
                (Duration::from_millis(1).as_nanos() / char_time.as_nanos().max(1)).max(1) as usize;
            let out = c.take_output(burst);
            port.send(&out)?;
            next_free += char_time * out.len() as u32;
        }
    }
    Ok(())
}

impl std::fmt::Debug for C500 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("C500").finish_non_exhaustive()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use trol_a465::arm::ArmSettings;

    fn c500(profile: Profile) -> C500 {
        C500::new(
            profile,
            Arm::new(ArmSettings {
                homed: true,
                ..Default::default()
            }),
            vec![(
                "test_001".into(),
                Stored::Cart([400.0, 0.0, 150.0, 0.0, std::f64::consts::FRAC_PI_2, 0.0]),
            )],
        )
    }

    fn out(c: &mut C500) -> Vec<u8> {
        c.take_output(100_000)
    }

    #[test]
    fn help_mode_completes_and_swallows_what_follows() {
        let mut c = c500(Profile {
            entry: Entry::Terminal,
            ..Profile::simulator()
        });
        c.feed(b"NOH", 0.0);
        assert_eq!(out(&mut c), b"NOHELP  ");
        // G3K types the whole word: the rest is swallowed.
        c.feed(b"ELP\r", 0.0);
        assert_eq!(out(&mut c), b"\r\x06\r\n>>");
        c.feed(b"SPEED 50\r", 0.0);
        assert_eq!(out(&mut c), b"SPEED 5    0\r\x06\r\n>>");
    }

    #[test]
    fn aci_to_terminal_and_back() {
        let mut c = c500(Profile::simulator());
        // Terminal-mode text is ignored in ACI mode.
        c.feed(b"W2\r", 0.0);
        assert!(out(&mut c).is_empty());
        c.feed(b"R!\x05", 0.0);
        assert_eq!(out(&mut c), b"R!\x06");
        c.feed(&crate::aci::header(Entry::Aci, 1), 0.0);
        assert_eq!(out(&mut c), b"\x06\x02\x00\x03\x00");
        c.feed(b"\x06", 0.0);
        assert_eq!(out(&mut c), b"\x04");
        c.feed(b"\x04", 0.0);
        assert!(c.in_terminal_mode());
        c.feed(b"\x1a\x1a", 0.0);
        assert!(!c.in_terminal_mode());
    }

    #[test]
    fn a_second_motion_waits_and_input_queues_behind_it_with_xoff() {
        let mut c = c500(Profile {
            entry: Entry::Terminal,
            help_at_start: false,
            extra_after_digit: 0,
            ..Profile::simulator()
        });
        c.feed(b"JOINT 1,90\r", 0.0);
        assert!(out(&mut c).ends_with(b"\x06\r\n>>"));
        c.feed(b"JOINT 1,-90\r", 0.01);
        let o = out(&mut c);
        assert!(
            o.ends_with(b"\r"),
            "no answer while the first motion runs: {o:?}"
        );
        c.feed(&[b'W'; 50], 0.02);
        assert_eq!(out(&mut c), vec![XOFF]);
        c.tick(100.0);
        let o = out(&mut c);
        assert!(o.starts_with(&[XON]) || o.contains(&XON), "{o:?}");
        assert!(o.windows(5).any(|w| w == b"\x06\r\n>>"));
    }

    #[test]
    fn unknown_lines_and_locations_are_refused() {
        let mut c = c500(Profile {
            entry: Entry::Terminal,
            help_at_start: false,
            ..Profile::simulator()
        });
        c.feed(b"FLY\r", 0.0);
        assert_eq!(out(&mut c), b"FLY\r\n012-COMMAND ERROR.\r\n>>");
        c.feed(b"MOVE NOWHERE\r", 0.0);
        assert!(String::from_utf8_lossy(&out(&mut c)).contains("035-LOCATION NOT DEFINED."));
        c.feed(b"LISTL TEST_001\r", 0.0);
        let o = String::from_utf8_lossy(&out(&mut c)).to_string();
        let body = &o[o.find('\r').unwrap() + 1..];
        let rows = text::read_listl(body.trim_end_matches("\x06\r\n>>")).unwrap();
        assert_eq!(rows[0].0, "TEST_001");
    }
}

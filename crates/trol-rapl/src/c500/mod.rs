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

mod commands;
mod serve;
mod variants;

pub use serve::{serve, serve_with};
pub use variants::{VARIANTS, variant};

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
    pub fn new(profile: Profile, mut arm: Arm, locations: Vec<(String, Stored)>) -> C500 {
        arm.set_home_pose(profile.twin.home_deg.map(f64::to_radians));
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
        // Where HOME puts this arm (the JOINTS row, degrees), whatever the profile it was
        // made from said.
        p.home_joints = Some(p.twin.home_deg);
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

    /// Give the arm its power back (the panel's button; NOLIMP on the line).
    pub fn power_on(&mut self) {
        self.limp = false;
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

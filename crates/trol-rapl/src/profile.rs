//! The profile: everything the public sources leave open about a C500's RAPL-II host port
//! (../shared/reference/c500-rapl.md, "What is unknown"), one TOML file per controller.
//!
//! The gateway reads it to talk to a real controller; the simulated C500 (`trol sim --rapl`)
//! reads the same format to decide how it behaves, so each variant can be tested, and
//! `trol sim --rapl --print-profile` prints the one that matches it.
//!
//! The default is safe: the two settings whose wrong guess turns into a large or wrong
//! motion, the order and signs of POINT's angles and the units of MA and MI, are empty, and
//! every command that needs them is refused with a message saying what to set
//! (docs/c500.md, "Settle the conventions", fits them from readings of a pendant-moved arm).

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Duration;

use serde::{Deserialize, Serialize};

/// Software flow control on the host port.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Flow {
    /// None.
    None,
    /// XON/XOFF (both public drivers; the default).
    Xonxoff,
}

/// How a session is entered.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Entry {
    /// The ACI transfer 0x48 reading one data byte, source id 0xFF (CRS's sample code, RW).
    Aci,
    /// The ACI transfer 0x48 with no data, source id 0x21 (the G3000 driver).
    AciEmpty,
    /// The port is in terminal mode already: Ctrl-C and the prompt.
    Terminal,
}

/// The line terminator.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Terminator {
    /// CR, 0x0D (RW, G3K).
    Cr,
    /// LF, 0x0A (XARM).
    Lf,
}

impl Terminator {
    /// The byte.
    pub fn byte(self) -> u8 {
        match self {
            Terminator::Cr => b'\r',
            Terminator::Lf => b'\n',
        }
    }
}

/// Whether a successful command is answered with ACK (0x06).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Ack {
    /// Accept a reply with or without it (the default).
    Auto,
    /// A reply without ACK or error line is a failure (RW's controller).
    Required,
    /// The controller sends none (the simulated C500 then sends none).
    Never,
}

/// Length units of cartesian values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Units {
    /// As STATUS says (`METRIC UNITS.`); cartesian commands are refused when it says nothing.
    Auto,
    /// Millimetres.
    Mm,
    /// Inches (RW's controller).
    Inch,
}

impl Units {
    /// Millimetres per unit (None for `auto`).
    pub fn mm(self) -> Option<f64> {
        match self {
            Units::Auto => None,
            Units::Mm => Some(1.0),
            Units::Inch => Some(25.4),
        }
    }
}

/// Units of MA and MI.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum JointUnits {
    /// Degrees.
    Degrees,
    /// Radians (the RAPL-II manual's transcription for MA).
    Radians,
}

/// How the end of a motion is found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Completion {
    /// Poll STATUS: the DONE row all Y (the default; the line stays free for a halt).
    Status,
    /// Poll W5: all joint velocities 0.
    W5,
    /// Send FINISH while the host waits for the motion and listen for its answer: the end is
    /// known as soon as the controller says so (FINISH holds the interpreter, so a Halt goes
    /// as Ctrl-C first). Needs `ctrl_c_ends_finish = true`, checked on the arm. The arm's
    /// position (W2) confirms the end unless `finish_ack_means_arrived`; where it does not,
    /// the end is looked for by STATUS as with `status`.
    Finish,
}

/// When a motion's ACK and prompt come.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MotionAck {
    /// At its start (RobWork's reading; the default): the motion call returns then.
    Start,
    /// At its end (the G3000 driver's reading): the call returns once the line was taken
    /// and no refusal came within the reply window; Finish waits for the late ACK, and
    /// Halt goes as Ctrl-C (the interpreter is busy), so `halt = "ctrl-c"` is required.
    End,
}

/// How a motion is stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Halt {
    /// The HALT command.
    Halt,
    /// Ctrl-C.
    CtrlC,
    /// The ABORT command.
    Abort,
}

/// One of POINT's three angles: which of TROL's yaw, pitch, roll it is, and its sign.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Angle {
    /// 0 yaw, 1 pitch, 2 roll.
    pub which: usize,
    /// +1 or -1.
    pub sign: f64,
}

const ANGLE_NAMES: [&str; 3] = ["yaw", "pitch", "roll"];

/// Parse `angles`: three of `yaw`, `pitch`, `roll`, each once, each optionally with `-`, in
/// the order the controller writes them after x y z; empty: None (cartesian commands are
/// refused).
pub fn parse_angles(s: &str) -> Result<Option<[Angle; 3]>, String> {
    let words: Vec<&str> = s
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|w| !w.is_empty())
        .collect();
    if words.is_empty() {
        return Ok(None);
    }
    let bad = || {
        format!(
            "`angles = \"{s}\"`: expected the three angles in the controller's order, each of \
             yaw, pitch, roll once, with - for an opposite sign (\"yaw pitch roll\", \
             \"roll -pitch yaw\"), or \"\" to refuse cartesian commands"
        )
    };
    if words.len() != 3 {
        return Err(bad());
    }
    let mut out = [Angle {
        which: 0,
        sign: 1.0,
    }; 3];
    let mut seen = [false; 3];
    for (i, w) in words.iter().enumerate() {
        let (sign, name) = match w.strip_prefix('-') {
            Some(n) => (-1.0, n),
            None => (1.0, w.strip_prefix('+').unwrap_or(w)),
        };
        let which = ANGLE_NAMES
            .iter()
            .position(|n| n.eq_ignore_ascii_case(name))
            .ok_or_else(bad)?;
        if seen[which] {
            return Err(bad());
        }
        seen[which] = true;
        out[i] = Angle { which, sign };
    }
    Ok(Some(out))
}

/// The names of the BIOS codes an error line may map to (docs/c500.md, "Errors").
pub const ERROR_TARGETS: &[&str] = &[
    "BIOS_NOT_HOMED",
    "BIOS_OUT_OF_REACH",
    "BIOS_JOINT_LIMIT",
    "BIOS_BELOW_TABLE",
    "BIOS_SINGULAR_PATH",
    "BIOS_BAD_ARGUMENT",
    "BIOS_QUEUE_FULL",
    "BIOS_GRIPPER_BLOCKED",
    "BIOS_ARM_POWER",
    "BIOS_RAPL_ERROR",
    "TROL_ERR_LOCATION",
];

/// The error lines of the simulated C500 and what they mean. Only 012 is seen in public
/// sources (G3K); the other numbers are the simulator's own (assumption) until a real
/// controller's list is known; a profile maps a real controller's numbers in `[errors]`.
pub const SIM_ERRORS: &[(u16, &str, &str)] = &[
    (12, "COMMAND ERROR", "BIOS_BAD_ARGUMENT"),
    (30, "ROBOT NOT HOMED", "BIOS_NOT_HOMED"),
    (31, "LOCATION OUT OF REACH", "BIOS_OUT_OF_REACH"),
    (32, "JOINT LIMIT", "BIOS_JOINT_LIMIT"),
    (33, "BELOW WORK SURFACE", "BIOS_BELOW_TABLE"),
    (34, "PATH THROUGH SINGULARITY", "BIOS_SINGULAR_PATH"),
    (35, "LOCATION NOT DEFINED", "TROL_ERR_LOCATION"),
    (36, "MOTION QUEUE FULL", "BIOS_QUEUE_FULL"),
    (37, "ARM POWER OFF", "BIOS_ARM_POWER"),
    (38, "GRIPPER BLOCKED", "BIOS_GRIPPER_BLOCKED"),
];

/// A profile (the keys of the TOML file; docs/c500.md, "The profile").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Profile {
    /// Baud rate of the host port.
    pub baud: u32,
    /// Software flow control.
    pub flow: Flow,
    /// How the session is entered.
    pub entry: Entry,
    /// The controller's ACI slave number, 1..127.
    pub slave: u8,
    /// The line terminator.
    pub terminator: Terminator,
    /// Bytes the controller sends after echoing the first character of a number (0..4;
    /// RW's controller sent 4). The reader tolerates up to this many.
    pub extra_after_digit: u8,
    /// Whether a successful command is answered with ACK.
    pub ack: Ack,
    /// Length units of cartesian values.
    pub units: Units,
    /// The order and signs of the three angles after x y z in POINT, W0/W2's WORLD row and
    /// LISTL: a permutation of `yaw pitch roll` with optional `-` (TROL's convention:
    /// R = Rz(yaw)·Ry(pitch)·Rx(roll)). Empty: cartesian commands are refused.
    pub angles: String,
    /// Units of MA and MI: `degrees` or `radians`. Empty: MA and MI are refused.
    pub joint_units: String,
    /// How the end of a motion is found.
    pub completion: Completion,
    /// How a motion is stopped.
    pub halt: Halt,
    /// Ctrl-C ends a FINISH that waits at once, with the prompt, and leaves the motion
    /// running (no public source says; check it on the arm, docs/c500.md "Settle the
    /// conventions"). `completion = "finish"` needs it, so that a Halt always gets through.
    pub ctrl_c_ends_finish: bool,
    /// FINISH's ACK alone means the motion arrived: this controller answers a FINISH whose
    /// motion stopped short (an emergency stop, a fault) with an error line, never ACK (no
    /// public source says; check it on the arm). Without it, W2 confirms each end (about
    /// 0.1 s more at 38400 baud).
    pub finish_ack_means_arrived: bool,
    /// When a motion's ACK comes: at its `start` or its `end` (`trol rapl probe` cannot
    /// tell without a motion; docs/c500.md has the supervised step).
    pub motion_ack: MotionAck,
    /// The prompt the controller writes after each command (`>>`; G3K also saw `O>`). The
    /// reader accepts both.
    pub prompt: String,
    /// HELP mode (keyword completion) on at the start of a session (the simulated C500's
    /// power-up state).
    pub help_at_start: bool,
    /// How long the echo of one byte may take, ms (2000 by default: a C500 echoes within a
    /// character time, but the host that reads it may be held back on a busy machine; a
    /// line that echoes nothing is still given up within seconds).
    pub echo_timeout_ms: u64,
    /// How long the answer to a command that does not move may take, ms.
    pub reply_timeout_ms: u64,
    /// The longest a motion may take before its end is given up for lost, s.
    pub motion_timeout_s: u64,
    /// How often the end of a motion is polled, ms.
    pub poll_ms: u64,
    /// Check each W0/W2 reading against itself (PULSES against JOINTS through the A465's
    /// counts per radian) and read again when they disagree, so a damaged digit is never
    /// reported as the position. Turn off if a controller's pulses do not follow the model.
    pub cross_check: bool,
    /// The forms a refusal takes on this controller, as templates: `NNN` stands for the
    /// three-digit error number, `TEXT` for the message, everything else is literal
    /// (`"NNN-TEXT."`, `":NNN-TEXT."`, `"*** TEXT ***"`). A reply line in one of these forms is
    /// a refusal; any other line where a command prints nothing is not understood, and the
    /// call ends in TROL_ERR_ROBOT_UNSURE with the line (`trol rapl probe` records the
    /// controller's form).
    pub refusal: Vec<String>,
    /// Pulses per degree of each joint's JOINTS row, signed (the G3000 driver's table had one
    /// pulse per encoder line and a negative sign; TROL's model counts four). Empty: not
    /// established, and precision points are refused (`trol rapl probe --poses` fits it).
    pub pulse_scale: Vec<f64>,
    /// The PULSES reading at each joint's zero of the JOINTS row (with `pulse_scale`; empty:
    /// zero).
    pub pulse_zero: Vec<f64>,
    /// The frame of JOG's dx dy dz: `world` or `tool`. Empty: not established, and a straight
    /// Jog is refused (docs/c500.md, "Settle the conventions").
    pub jog_frame: String,
    /// A fixed rotation between TROL's tool frame and the controller's, yaw pitch roll in
    /// degrees (R_controller = R_TROL * R(tool_rotation)): public kinematic models of the
    /// A465 have an identity orientation at all joints zero, TROL's model pitch -90 degrees.
    pub tool_rotation: [f64; 3],
    /// Finish: how far (mm) the arm (W2) may be from the motion's target when the controller
    /// says done.
    pub arrive_mm: f64,
    /// Finish: how far (degrees) the arm's joints and orientation may be from the target.
    pub arrive_deg: f64,
    /// Finish, for a motion whose end pose is not known beforehand (READY, HOME) and that was
    /// never seen moving: how long W2 must stay still before the motion counts as ended, ms.
    pub settle_ms: u64,
    /// Where HOME leaves the arm, the JOINTS row in the profile's joint units (RAPL-II puts
    /// the calibrated home position in the command registers when it gets there; the A465's
    /// values are not public). With it, a HOME is done only with W2 reading each joint
    /// within `arrive_deg` of it (issue 62: a Home is a home, seen on the arm); without it,
    /// only STATUS's HOMED row and the arm seen standing say so. `trol rapl probe` records
    /// the row once the person at the arm confirms it stands at its home marks.
    pub home_joints: Option<[f64; 6]>,
    /// Error numbers (three digits) and the code each means (one of [`ERROR_TARGETS`]);
    /// numbers not listed give BIOS_RAPL_ERROR, and their text is logged.
    pub errors: BTreeMap<String, String>,
    /// This profile describes TROL's simulated C500 (`trol sim --rapl --print-profile` writes
    /// it): a session refuses it unless the controller answers as the simulator does, so a
    /// simulator's readings never drive a real arm (issue 37). Delete the line to use the
    /// file on a real controller anyway.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub simulated: bool,
    /// How the simulated C500 plays the points the public sources leave open (read only by
    /// `trol sim --rapl`; a real controller's profile needs none of it).
    #[serde(skip_serializing_if = "Twin::is_default")]
    pub twin: Twin,
}

/// The simulated C500's answers to what no public source settles (each a switch, so the
/// backend's tests run across all of them: [`crate::c500::VARIANTS`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Twin {
    /// How it writes a refusal (a template as in [`Profile::refusal`]).
    pub refusal: String,
    /// The byte it sends `extra_after_digit` times after a number's first character (RW read
    /// four bytes it never looked at; the G3000 driver reads replies as C strings, so NULs
    /// would cut them: spaces satisfy both).
    pub extra_byte: u8,
    /// Whether it echoes what is typed (RAPL-II's CONFIG has an ECHO setting).
    pub echo: bool,
    /// How long after a motion's ACK its DONE row still says done, ms of the controller's
    /// time (`trol sim --time-scale` shortens it like every other time of the arm).
    pub done_lag_ms: u64,
    /// A line it prints unasked when the arm loses power ("": none).
    pub estop_line: String,
    /// A numbered line it prints before the ACK of every motion ("": none).
    pub motion_warning: String,
    /// How it takes FINISH in immediate mode (R2JSON lists FINISH for program mode only).
    pub finish: TwinFinish,
    /// Whether Ctrl-C ends a FINISH that waits (else it is ignored until the motion ends).
    pub finish_ctrl_c: bool,
    /// The error number it answers FINISH with when the last motion stopped short (an
    /// emergency stop: 037), whether FINISH waited for it or came after; 0: ACK, as for an
    /// arrival.
    pub finish_stopped: u16,
    /// Whether HALT stops a motion (else it is acknowledged and the motion runs on).
    pub halt_stops: bool,
    /// Whether ABORT stops a motion.
    pub abort_stops: bool,
    /// Whether Ctrl-C stops a motion, besides cancelling the line; unset: exactly when the
    /// profile's `halt` is "ctrl-c".
    pub ctrl_c_stops: Option<bool>,
    /// Whether JOG moves along the tool's axes (the flange frame, as TOOL sets it) instead
    /// of the world's.
    pub jog_tool: bool,
    /// Whether it names itself in its refusal of the probe's word (false: it plays a real
    /// C500, for the test that a simulator's profile is refused there).
    pub names_itself: bool,
    /// Where HOME leaves each joint, degrees (the JOINTS row there). Not public for an A465:
    /// every joint's 0 by default, [0, 0, 90, 0, 90, 0] on the variant `home-elsewhere` (an
    /// assumed figure: a profile that takes the default's pose must fail there).
    pub home_deg: [f64; 6],
}

/// How the simulated C500 takes FINISH typed in immediate mode.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TwinFinish {
    /// It waits for the motion's end, then answers.
    Waits,
    /// It answers at once, moving or not.
    AtOnce,
    /// It refuses it (012-COMMAND ERROR.).
    Refused,
}

impl Default for Twin {
    fn default() -> Self {
        Twin {
            refusal: "NNN-TEXT.".into(),
            extra_byte: b' ',
            echo: true,
            done_lag_ms: 0,
            estop_line: String::new(),
            motion_warning: String::new(),
            finish: TwinFinish::Waits,
            finish_ctrl_c: true,
            finish_stopped: 0,
            halt_stops: true,
            abort_stops: true,
            ctrl_c_stops: None,
            names_itself: true,
            jog_tool: false,
            home_deg: [0.0; 6],
        }
    }
}

impl Twin {
    fn is_default(&self) -> bool {
        *self == Twin::default()
    }
}

/// A refusal's form: literal text around the error number (`NNN`) and the message (`TEXT`).
#[derive(Clone, Debug, PartialEq)]
pub struct RefusalForm {
    before: String,
    number: bool,
    between: String,
    after: String,
}

impl RefusalForm {
    /// Parse a template; it needs `TEXT` once, at most one `NNN` before it, and something
    /// literal or a number so that an ordinary line of output cannot match.
    pub fn parse(template: &str) -> Result<RefusalForm, String> {
        let bad = |why: &str| {
            format!(
                "refusal form \"{template}\": {why} (forms look like \"NNN-TEXT.\", \":NNN-TEXT.\", \"*** TEXT ***\")"
            )
        };
        let (head, after) = template
            .split_once("TEXT")
            .ok_or_else(|| bad("it needs TEXT where the message stands"))?;
        if after.contains("TEXT") || after.contains("NNN") {
            return Err(bad("TEXT must come once, after NNN"));
        }
        let (before, number, between) = match head.split_once("NNN") {
            Some((b, m)) if !m.contains("NNN") => (b, true, m),
            Some(_) => return Err(bad("NNN must come once")),
            None => (head, false, ""),
        };
        if !number && before.trim().is_empty() && after.trim().is_empty() {
            return Err(bad("without NNN it needs literal text around TEXT"));
        }
        Ok(RefusalForm {
            before: before.to_string(),
            number,
            between: between.to_string(),
            after: after.to_string(),
        })
    }

    /// The error number (0 when the form has none) and message of `line` (trimmed), if it
    /// has this form.
    pub fn read(&self, line: &str) -> Option<(u16, String)> {
        let l = line.trim();
        let rest = l.strip_prefix(self.before.as_str())?;
        let (number, rest) = if self.number {
            let digits = rest.get(..3)?;
            if !digits.bytes().all(|b| b.is_ascii_digit()) {
                return None;
            }
            (digits.parse().ok()?, &rest[3..])
        } else {
            (0, rest)
        };
        let rest = rest.strip_prefix(self.between.as_str())?;
        let text = rest.strip_suffix(self.after.as_str())?;
        let text = text.trim();
        if text.is_empty() || !text.bytes().any(|b| b.is_ascii_alphabetic()) {
            return None;
        }
        Some((number, text.to_string()))
    }

    /// A refusal in this form.
    pub fn write(&self, number: u16, text: &str) -> String {
        let n = if self.number {
            format!("{number:03}")
        } else {
            String::new()
        };
        format!("{}{n}{}{text}{}", self.before, self.between, self.after)
    }

    /// The template that describes `line` (what `trol rapl probe` records from the answer to
    /// an unknown word): the first three-digit number is NNN, the run of words after it is
    /// TEXT, the rest literal.
    pub fn learn(line: &str) -> Option<String> {
        let l = line.trim();
        let b = l.as_bytes();
        let num = (0..b.len().saturating_sub(2)).find(|&i| {
            b[i..i + 3].iter().all(u8::is_ascii_digit)
                && (i == 0 || !b[i - 1].is_ascii_digit())
                && b.get(i + 3).is_none_or(|c| !c.is_ascii_digit())
        });
        let from = num.map(|i| i + 3).unwrap_or(0);
        let start = from + l[from..].find(|c: char| c.is_ascii_alphabetic())?;
        let end = l.rfind(|c: char| c.is_ascii_alphanumeric())? + 1;
        if end <= start {
            return None;
        }
        let t = match num {
            Some(i) => format!("{}NNN{}TEXT{}", &l[..i], &l[i + 3..start], &l[end..]),
            None => format!("{}TEXT{}", &l[..start], &l[end..]),
        };
        RefusalForm::parse(&t).ok()?.read(l).map(|_| t)
    }
}

impl Default for Profile {
    fn default() -> Self {
        Profile {
            baud: 38400,
            flow: Flow::Xonxoff,
            entry: Entry::Aci,
            slave: 1,
            terminator: Terminator::Cr,
            extra_after_digit: 4,
            ack: Ack::Auto,
            units: Units::Auto,
            angles: String::new(),
            joint_units: String::new(),
            completion: Completion::Status,
            halt: Halt::Halt,
            ctrl_c_ends_finish: false,
            finish_ack_means_arrived: false,
            motion_ack: MotionAck::Start,
            prompt: ">>".into(),
            help_at_start: true,
            echo_timeout_ms: 2000,
            reply_timeout_ms: 3000,
            motion_timeout_s: 120,
            poll_ms: 50,
            cross_check: true,
            refusal: vec!["NNN-TEXT.".into(), ":NNN-TEXT.".into()],
            pulse_scale: Vec::new(),
            pulse_zero: Vec::new(),
            jog_frame: String::new(),
            tool_rotation: [0.0; 3],
            arrive_mm: 1.0,
            arrive_deg: 0.2,
            settle_ms: 1000,
            home_joints: None,
            errors: SIM_ERRORS
                .iter()
                .map(|(n, _, to)| (format!("{n:03}"), to.to_string()))
                .collect(),
            simulated: false,
            twin: Twin::default(),
        }
    }
}

/// A profile file that cannot be used.
#[derive(Debug, thiserror::Error)]
#[error("RAPL-II profile {file}: {message}")]
pub struct ProfileError {
    /// The file (or `<text>`).
    pub file: String,
    /// What is wrong, and what is expected.
    pub message: String,
}

impl Profile {
    /// The profile of the simulated C500 as it starts by default: every open point decided
    /// (mm, `yaw pitch roll`, MA/MI in degrees; assumptions of the simulator, not facts
    /// about a real controller).
    pub fn simulator() -> Profile {
        Profile {
            units: Units::Mm,
            angles: "yaw pitch roll".into(),
            joint_units: "degrees".into(),
            pulse_scale: trol_a465::model::counts_per_radian()
                .map(|c| c * std::f64::consts::PI / 180.0)
                .to_vec(),
            jog_frame: "world".into(),
            home_joints: Some([0.0; 6]),
            ..Profile::default()
        }
    }

    /// Read a profile file.
    pub fn from_file(path: &Path) -> Result<Profile, ProfileError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| ProfileError {
            file: file.clone(),
            message: format!(
                "cannot read it ({e}); `trol sim --rapl --print-profile` prints one to start from"
            ),
        })?;
        Profile::parse(&text).map_err(|message| ProfileError { file, message })
    }

    /// Parse a profile's text; keys not given keep their defaults.
    pub fn parse(text: &str) -> Result<Profile, String> {
        let p: Profile = toml::from_str(text).map_err(|e| e.to_string().trim().to_string())?;
        p.check()?;
        Ok(p)
    }

    /// Check the values the types cannot.
    pub fn check(&self) -> Result<(), String> {
        if !(300..=4_000_000).contains(&self.baud) {
            return Err(format!("`baud = {}`: expected 300 to 4000000", self.baud));
        }
        if !(1..=127).contains(&self.slave) {
            return Err(format!("`slave = {}`: expected 1 to 127", self.slave));
        }
        if self.extra_after_digit > 4 {
            return Err(format!(
                "`extra_after_digit = {}`: expected 0 to 4",
                self.extra_after_digit
            ));
        }
        parse_angles(&self.angles)?;
        self.joint_units()?;
        if self.prompt.len() != 2 || !self.prompt.is_ascii() {
            return Err(format!(
                "`prompt = \"{}\"`: expected two characters, \">>\" or \"O>\"",
                self.prompt
            ));
        }
        if self.echo_timeout_ms == 0 || self.reply_timeout_ms == 0 || self.poll_ms == 0 {
            return Err("timeouts and `poll_ms` must be above 0".into());
        }
        if !(1..=3600).contains(&self.motion_timeout_s) {
            return Err(format!(
                "`motion_timeout_s = {}`: expected 1 to 3600",
                self.motion_timeout_s
            ));
        }
        if self.refusal.is_empty() {
            return Err("`refusal = []`: name at least one form (\"NNN-TEXT.\")".into());
        }
        for t in self.refusal.iter().chain([&self.twin.refusal]) {
            RefusalForm::parse(t)?;
        }
        self.pulses()?;
        self.jog_frame()?;
        if self
            .tool_rotation
            .iter()
            .any(|a| !a.is_finite() || a.abs() > 360.0)
        {
            return Err("`tool_rotation`: three angles in degrees, -360 to 360".into());
        }
        if !((0.0..=50.0).contains(&self.arrive_mm)
            && self.arrive_mm > 0.0
            && (0.0..=10.0).contains(&self.arrive_deg)
            && self.arrive_deg > 0.0)
        {
            return Err("`arrive_mm` (0 to 50) and `arrive_deg` (0 to 10) must be above 0".into());
        }
        if self
            .home_joints
            .is_some_and(|h| h.iter().any(|a| !a.is_finite() || a.abs() > 400.0))
        {
            return Err("`home_joints`: six joint values, each -400 to 400".into());
        }
        if !(1..=60_000).contains(&self.settle_ms) {
            return Err(format!(
                "`settle_ms = {}`: expected 1 to 60000",
                self.settle_ms
            ));
        }
        if self.motion_ack == MotionAck::End && self.halt != Halt::CtrlC {
            return Err(
                "`motion_ack = \"end\"` needs `halt = \"ctrl-c\"`: while a motion runs the \
                 controller's interpreter is busy, and only Ctrl-C reaches it"
                    .into(),
            );
        }
        if self.completion == Completion::Finish {
            if !self.ctrl_c_ends_finish {
                return Err(
                    "`completion = \"finish\"` holds the controller's interpreter while a motion \
                     runs, so a Halt must end the FINISH with Ctrl-C first: set \
                     `ctrl_c_ends_finish = true` once the arm showed that Ctrl-C answers at once \
                     while FINISH waits (docs/c500.md, \"Settle the conventions\"), or use \
                     \"status\""
                        .into(),
                );
            }
            if self.motion_ack == MotionAck::End || self.halt == Halt::CtrlC {
                return Err(
                    "`completion = \"finish\"` needs `motion_ack = \"start\"` and a halt other than \
                     \"ctrl-c\" (Ctrl-C ends the FINISH, the halt then stops the arm); a \
                     controller that answers a motion at its end needs no FINISH"
                        .into(),
                );
            }
        }
        if self.finish_ack_means_arrived && self.completion != Completion::Finish {
            return Err(
                "`finish_ack_means_arrived = true` is about FINISH: it needs `completion = \
                 \"finish\"`"
                    .into(),
            );
        }
        for (k, v) in &self.errors {
            if k.len() != 3 || !k.bytes().all(|b| b.is_ascii_digit()) {
                return Err(format!(
                    "[errors] key \"{k}\": expected a three-digit error number (\"012\")"
                ));
            }
            if !ERROR_TARGETS.contains(&v.as_str()) {
                return Err(format!(
                    "[errors] \"{k}\" = \"{v}\": expected one of {}",
                    ERROR_TARGETS.join(", ")
                ));
            }
        }
        Ok(())
    }

    /// The refusal forms.
    pub fn refusal_forms(&self) -> Vec<RefusalForm> {
        self.refusal
            .iter()
            .filter_map(|t| RefusalForm::parse(t).ok())
            .collect()
    }

    /// The pulse convention, when established: per joint (pulses per degree, pulses at 0).
    pub fn pulses(&self) -> Result<Option<[(f64, f64); 6]>, String> {
        if self.pulse_scale.is_empty() {
            return Ok(None);
        }
        let zero = if self.pulse_zero.is_empty() {
            vec![0.0; 6]
        } else {
            self.pulse_zero.clone()
        };
        if self.pulse_scale.len() != 6 || zero.len() != 6 {
            return Err(
                "`pulse_scale` and `pulse_zero`: six numbers each (pulses per degree, pulses at 0)"
                    .into(),
            );
        }
        if self
            .pulse_scale
            .iter()
            .any(|s| !s.is_finite() || s.abs() < 1.0 || s.abs() > 1e5)
            || zero.iter().any(|z| !z.is_finite())
        {
            return Err("`pulse_scale`: each 1 to 100000 pulses per degree, either sign".into());
        }
        Ok(Some(std::array::from_fn(|i| {
            (self.pulse_scale[i], zero[i])
        })))
    }

    /// JOG's frame, when established: Some(true) world, Some(false) tool.
    pub fn jog_frame(&self) -> Result<Option<bool>, String> {
        match self.jog_frame.trim().to_ascii_lowercase().as_str() {
            "" => Ok(None),
            "world" => Ok(Some(true)),
            "tool" => Ok(Some(false)),
            other => Err(format!(
                "`jog_frame = \"{other}\"`: expected \"world\", \"tool\", or \"\" to refuse JOG"
            )),
        }
    }

    /// The angles, when set.
    pub fn angles(&self) -> Option<[Angle; 3]> {
        parse_angles(&self.angles).ok().flatten()
    }

    /// The units of MA and MI, when set.
    pub fn joint_units(&self) -> Result<Option<JointUnits>, String> {
        match self.joint_units.trim().to_ascii_lowercase().as_str() {
            "" => Ok(None),
            "degrees" | "deg" => Ok(Some(JointUnits::Degrees)),
            "radians" | "rad" => Ok(Some(JointUnits::Radians)),
            other => Err(format!(
                "`joint_units = \"{other}\"`: expected \"degrees\", \"radians\", or \"\" to refuse MA and MI"
            )),
        }
    }

    /// The TOML text of this profile, with a line of explanation per key.
    pub fn to_toml(&self) -> String {
        let body = toml::to_string(self).unwrap_or_default();
        let mut out = String::from(
            "# A RAPL-II profile for TROL (docs/c500.md, \"The profile\").\n\
             # Keys left out keep their defaults; angles = \"\" refuses cartesian commands,\n\
             # joint_units = \"\" refuses MA and MI.\n",
        );
        if self.simulated {
            out.push_str(
                "# Written for TROL's SIMULATED C500 (`simulated = true`): a real C500's session\n\
                 # refuses it. Write your controller's own with `trol rapl probe` (docs/c500.md,\n\
                 # \"The first hour with a real arm\").\n",
            );
        }
        out.push_str(&body);
        out
    }

    /// One byte's time on the line (10 bits: 8N1).
    pub fn char_time(&self) -> Duration {
        Duration::from_nanos(10_000_000_000 / u64::from(self.baud.max(1)))
    }

    /// The error number's meaning, by name, if the profile maps it.
    pub fn error_target(&self, number: u16) -> Option<&str> {
        self.errors.get(&format!("{number:03}")).map(String::as_str)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_is_safe_and_round_trips() {
        let p = Profile::default();
        assert_eq!(p.angles(), None);
        assert_eq!(p.joint_units(), Ok(None));
        let again = Profile::parse(&p.to_toml()).unwrap();
        assert_eq!(again, p);
        let s = Profile::simulator();
        assert_eq!(Profile::parse(&s.to_toml()).unwrap(), s);
    }

    #[test]
    fn finish_needs_the_statements_that_keep_halt_and_success_true() {
        let e = Profile::parse("completion = \"finish\"").unwrap_err();
        assert!(e.contains("ctrl_c_ends_finish = true"), "{e}");
        let p = Profile::parse("completion = \"finish\"\nctrl_c_ends_finish = true").unwrap();
        assert!(!p.finish_ack_means_arrived);
        let e =
            Profile::parse("completion = \"finish\"\nctrl_c_ends_finish = true\nhalt = \"ctrl-c\"")
                .unwrap_err();
        assert!(e.contains("motion_ack = \"start\""), "{e}");
        let e = Profile::parse("finish_ack_means_arrived = true").unwrap_err();
        assert!(e.contains("needs `completion = \"finish\"`"), "{e}");
    }

    #[test]
    fn bad_values_say_what_is_expected() {
        let e = Profile::parse("angles = \"yaw yaw roll\"").unwrap_err();
        assert!(e.contains("each of yaw, pitch, roll once"), "{e}");
        let e = Profile::parse("joint_units = \"grad\"").unwrap_err();
        assert!(e.contains("\"degrees\", \"radians\""), "{e}");
        let e = Profile::parse("units = \"furlong\"").unwrap_err();
        assert!(e.contains("units"), "{e}");
        let e = Profile::parse("slave = 200").unwrap_err();
        assert!(e.contains("1 to 127"), "{e}");
        let e = Profile::parse("speed = 3").unwrap_err();
        assert!(e.contains("speed"), "{e}");
        let e = Profile::parse("[errors]\n\"12\" = \"BIOS_NOT_HOMED\"").unwrap_err();
        assert!(e.contains("three-digit"), "{e}");
    }

    #[test]
    fn angles_parse_with_signs() {
        let a = parse_angles("roll -pitch yaw").unwrap().unwrap();
        assert_eq!(a[0].which, 2);
        assert_eq!(a[1].which, 1);
        assert_eq!(a[1].sign, -1.0);
        assert_eq!(a[2].which, 0);
        assert_eq!(parse_angles("").unwrap(), None);
    }
}

//! A simulated C500C with an A465 (`trol sim --c500c`, the backend's tests): the front
//! console as the public sources show it (shared/reference/c500c.md), the CROS system shell
//! (`$ `) and the application shell `ash test` (`test> `), over the simulated A465's planner
//! and clock.
//!
//! Where the public sources leave a point open it is a switch ([`Switches`], named in
//! [`VARIANTS`]); the backend's tests run across every one, with a profile that agrees and
//! one that does not. What is assumed here and nowhere settled is marked so.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use std::collections::BTreeMap;

use trol_a465::arm::{Arm, ArmSettings, Target, Which, code};
use trol_port::Port;

use crate::pulses::Pulses;
use crate::reports::{self, ArmStat, Homing, Position};
use crate::world::{self, Angles};

mod gripper;
mod variables;

use variables::Var;

/// When ash gives its prompt back after a motion command: an open point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Return {
    /// As soon as the motion has started.
    AtStart,
    /// Once the motion has ended.
    AtEnd,
}

/// How ash prints a robot error on the console: an open point (the system shell's tools
/// print `{program}: {message}`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorForm {
    /// The message alone: `Joint 2 limit exceeded`.
    Bare,
    /// After the application's name: `test: Joint 2 limit exceeded`.
    Prefixed,
    /// In brackets, as ash's asynchronous lines: `[test: Joint 2 limit exceeded]`.
    Bracketed,
}

/// How `print` shows a precision point (a `ploc` variable): an open point (ash's print
/// formats for locations are not among its public strings).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LocPrint {
    /// Its pulses as `w2`'s PULSES row prints them, without the label (assumed; TROL's
    /// reading).
    Row,
    /// `name = {p1, p2, p3, p4, p5, p6}`.
    Braced,
}

/// The gripper ash is set up for (`griptype_set`): an open point of each controller.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GripType {
    /// A servo gripper, whose jaws `wgrip` reads.
    Servo,
    /// An air gripper: a valve, nothing to read.
    Air,
    /// None set.
    None,
}

/// The controller's behaviour where the public sources are silent.
#[derive(Clone, Debug, PartialEq)]
pub struct Switches {
    /// When the prompt returns after a motion command.
    pub motion_return: Return,
    /// How a robot error is printed.
    pub error_form: ErrorForm,
    /// Typed characters are echoed (the public sources say they are).
    pub echo: bool,
    /// Lines end in LF alone instead of CR LF.
    pub lf_only: bool,
    /// The pendant holds the point of control at power-on (the factory startup script
    /// starts it).
    pub pendant_holds: bool,
    /// Ctrl-C stops a motion under way (assumed: ash's own way to stop is not public); off,
    /// no stop of the console stops the arm (`armpower off` neither: a drive fault).
    pub ctrl_c_stops: bool,
    /// Ctrl-C during a motion gives ash's prompt back (not public; off, only `^C` is
    /// printed, and Ctrl-E brings the prompt).
    pub ctrl_c_prompt: bool,
    /// Ctrl-C keeps a partly typed line (its prompt printed again all the same), so what is
    /// typed next is added to it (not public: whether ash's line editor drops the line).
    pub ctrl_c_keeps_line: bool,
    /// A power loss prints `[test: Lost robot power]`.
    pub power_loss_line: bool,
    /// A homing the power cut short leaves armstat's word as it was before the Home: an arm
    /// homed before still says `Robot is calibrated and homed` (not public: whether ash
    /// clears the word when a homing starts; an independent reading of ash does not).
    pub cut_home_keeps_homed: bool,
    /// How `print` shows a precision point.
    pub loc_print: LocPrint,
    /// The gripper set up.
    pub grip_type: GripType,
    /// When ash gives its prompt back after a grip command.
    pub grip_return: Return,
    /// How the WORLD row's and a cartesian location's three angles compose.
    pub world_angles: Angles,
    /// The frame those angles turn: TROL's tool frame turned by these right angles (yaw
    /// pitch roll, degrees; [`crate::world::Reading`]). Not public: [0, 0, 0] by default,
    /// [0, 90, 0] on the variant `world-flange` (the public A465 models' flange frame).
    pub world_frame: [f64; 3],
    /// How the PULSES row relates to the JOINTS row (the A465 model's counts by default).
    pub pulses: Pulses,
    /// How long (s of the controller's time) before the JOINTS and WORLD rows of `w0` and
    /// `w2` ash samples their PULSES row. Whether the rows are one instant's is not public:
    /// 0 by default (one instant), 40 ms on the variant `rows-apart` (assumed), where a
    /// moving arm's rows disagree and only an arm at rest shows how they relate.
    pub rows_apart: f64,
    /// Where ash's `home` leaves each joint, degrees. Not public for an A465 on a C500C:
    /// every joint's 0 by default, [0, 0, 90, 0, 90, 0] on the variant `home-elsewhere`
    /// (an assumed figure: a profile that takes the default's pose must fail there).
    pub home_deg: [f64; 6],
    /// A cartesian location's constant holds the angles in the reverse order of the WORLD
    /// row's (`{x, y, z, X-Rot, Y-Rot, Z-Rot}`). Not public which: false by default, true on
    /// the variant `cloc-reversed`.
    pub cloc_reversed: bool,
    /// `setvalid` warns and asks before it sets the flag (ash's strings have the question;
    /// whether it always asks is not public): true by default, false on the variant
    /// `setvalid-silent`, which sets it at once and says nothing.
    pub setvalid_asks: bool,
}

impl Switches {
    /// How this controller prints the WORLD row's angles.
    pub fn reading(&self) -> world::Reading {
        world::Reading {
            angles: self.world_angles,
            frame: self.world_frame,
        }
    }
}

impl Default for Switches {
    fn default() -> Switches {
        Switches {
            motion_return: Return::AtStart,
            error_form: ErrorForm::Bare,
            echo: true,
            lf_only: false,
            pendant_holds: false,
            ctrl_c_stops: true,
            ctrl_c_prompt: true,
            ctrl_c_keeps_line: false,
            power_loss_line: true,
            cut_home_keeps_homed: false,
            loc_print: LocPrint::Row,
            grip_type: GripType::Servo,
            grip_return: Return::AtStart,
            world_angles: Angles::Zyx,
            world_frame: [0.0; 3],
            pulses: Pulses::a465_model(),
            rows_apart: 0.0,
            home_deg: [0.0; 6],
            cloc_reversed: false,
            setvalid_asks: true,
        }
    }
}

/// The profile that agrees with a controller of these switches (`trol sim --c500c
/// --print-profile`).
pub fn matching_profile(sw: &Switches) -> crate::Profile {
    crate::Profile {
        motion_return: Some(match sw.motion_return {
            Return::AtStart => crate::profile::MotionReturn::Start,
            Return::AtEnd => crate::profile::MotionReturn::End,
        }),
        world_angles: Some(sw.world_angles),
        tool_rotation: Some(sw.world_frame),
        cloc_world_order: !sw.cloc_reversed,
        pulses_per_degree: Some(sw.pulses.per_degree),
        pulses_at_zero: Some(sw.pulses.at_zero),
        // Where this controller homes the arm (what `trol c500c step home-pose` reads).
        home_joints: Some(sw.home_deg),
        ..crate::Profile::default()
    }
}

/// The named variants: each sets one switch away from the default.
pub const VARIANTS: &[(&str, &str)] = &[
    (
        "default",
        "the prompt returns as a motion starts, errors bare, echo on, CR LF",
    ),
    (
        "return-at-end",
        "the prompt returns once a motion has ended",
    ),
    (
        "error-prefixed",
        "a robot error is printed after the application's name (`test: ...`)",
    ),
    (
        "error-bracketed",
        "a robot error is printed in brackets (`[test: ...]`)",
    ),
    ("echo-off", "typed characters are not echoed"),
    ("lf-only", "lines end in LF alone"),
    (
        "pendant-holds",
        "the pendant holds the point of control at power-on",
    ),
    (
        "unstoppable",
        "no stop of the console stops a motion (Ctrl-C, `armpower off`): a fault, for the rule \
         that Halt never says done unseen",
    ),
    (
        "ctrl-c-no-prompt",
        "Ctrl-C stops a motion but gives no prompt back (Ctrl-E does)",
    ),
    (
        "ctrl-c-keeps-line",
        "Ctrl-C keeps a partly typed line: what is typed next is added to it",
    ),
    (
        "power-loss-silent",
        "a power loss mid-motion prints nothing, and one during a Home leaves armstat saying \
         homed where the arm was homed before",
    ),
    (
        "print-braced",
        "`print` shows a location as `name = {v1, ...}`, not as a row of values",
    ),
    ("gripper-air", "an air gripper: its jaws cannot be read"),
    ("gripper-none", "no gripper type set"),
    (
        "grip-return-at-end",
        "the prompt returns once the gripper's jaws stand",
    ),
    (
        "world-xyz",
        "the WORLD row's angles compose as Rx(c)·Ry(b)·Rz(a), not Rz(a)·Ry(b)·Rx(c)",
    ),
    (
        "cloc-reversed",
        "a cartesian location's constant holds the angles in the reverse order of the WORLD \
         row's",
    ),
    (
        "setvalid-silent",
        "`setvalid` sets the flag at once, without its warning and question",
    ),
    (
        "home-elsewhere",
        "ash's `home` leaves joints 3 and 5 at 90 degrees, not every joint at 0",
    ),
    (
        "world-flange",
        "the WORLD row's angles turn the flange frame of public A465 models (its axes the \
         world's with every joint at 0), not TROL's tool frame",
    ),
    (
        "pulses-offset",
        "each axis counts its pulses from elsewhere than joint zero, and joint 3 the other way",
    ),
    (
        "rows-apart",
        "w0's and w2's PULSES row is read 40 ms before their JOINTS row: a moving arm's disagree",
    ),
];

/// The pulses of the variant `pulses-offset`: each axis counts from elsewhere than joint
/// zero, and joint 3 the other way.
pub fn offset_pulses() -> Pulses {
    let mut p = Pulses::a465_model();
    p.per_degree[2] = -p.per_degree[2];
    p.at_zero = [12_000, -8_000, 4_000, -20_000, 5_000, 3_000];
    p
}

/// The switches of a named variant.
pub fn variant(name: &str) -> Option<Switches> {
    let d = Switches::default();
    Some(match name {
        "default" => d,
        "return-at-end" => Switches {
            motion_return: Return::AtEnd,
            ..d
        },
        "error-prefixed" => Switches {
            error_form: ErrorForm::Prefixed,
            ..d
        },
        "error-bracketed" => Switches {
            error_form: ErrorForm::Bracketed,
            ..d
        },
        "echo-off" => Switches { echo: false, ..d },
        "lf-only" => Switches { lf_only: true, ..d },
        "pendant-holds" => Switches {
            pendant_holds: true,
            ..d
        },
        "unstoppable" => Switches {
            ctrl_c_stops: false,
            ..d
        },
        "ctrl-c-no-prompt" => Switches {
            ctrl_c_prompt: false,
            ..d
        },
        "ctrl-c-keeps-line" => Switches {
            ctrl_c_keeps_line: true,
            ..d
        },
        "power-loss-silent" => Switches {
            power_loss_line: false,
            cut_home_keeps_homed: true,
            ..d
        },
        "print-braced" => Switches {
            loc_print: LocPrint::Braced,
            ..d
        },
        "gripper-air" => Switches {
            grip_type: GripType::Air,
            ..d
        },
        "gripper-none" => Switches {
            grip_type: GripType::None,
            ..d
        },
        "grip-return-at-end" => Switches {
            grip_return: Return::AtEnd,
            ..d
        },
        "world-xyz" => Switches {
            world_angles: Angles::Xyz,
            ..d
        },
        "cloc-reversed" => Switches {
            cloc_reversed: true,
            ..d
        },
        "setvalid-silent" => Switches {
            setvalid_asks: false,
            ..d
        },
        "home-elsewhere" => Switches {
            home_deg: [0.0, 0.0, 90.0, 0.0, 90.0, 0.0],
            ..d
        },
        "world-flange" => Switches {
            world_frame: [0.0, 90.0, 0.0],
            ..d
        },
        "pulses-offset" => Switches {
            pulses: offset_pulses(),
            ..d
        },
        "rows-apart" => Switches {
            rows_apart: 0.040,
            ..d
        },
        _ => return None,
    })
}

/// The factory application (`/app/test`).
pub const APP: &str = "test";
/// What `robotver` says (assumed: the text of a real A465's C500C is not public).
pub const ROBOT_VERSION: &str = "A465 simulated by TROL 1.0";
/// What `crosver` says (the form PA's notes show).
pub const CROS_VERSION: &str = "System type: 'CROS-104 on a C500C'";

/// Rows `list` prints before its pager asks (assumed: a 24-line terminal).
pub const PAGE_ROWS: usize = 20;

/// What a question of ash's waits for.
#[derive(Clone, Debug, PartialEq)]
enum Ask {
    /// `Are you sure you want to exit?`
    Exit,
    /// `Erase variable 'NAME' and its value?`
    Erase(String),
    /// `Variable 'NAME' not found.  -- create it?` (`here` of a name ash does not have).
    Create(String),
    /// `Set the valid flag anyway (y/n) ?`
    Valid(String),
    /// `list`'s pager: the rows still to print.
    Page(Vec<String>),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Shell {
    System,
    Ash,
}

/// The simulated controller and its arm.
pub struct C500c {
    sw: Switches,
    arm: Arm,
    scale: f64,
    epoch: Instant,
    shell: Shell,
    power: bool,
    /// The Home under way (or the last) started on a homed arm.
    home_from_homed: bool,
    /// armstat says homed though the axes are not ([`Switches::cut_home_keeps_homed`]).
    stale_homed: bool,
    pendant: bool,
    online: bool,
    grip_type: GripType,
    /// A command whose prompt waits for the arm to stand (`finish`, or a motion with
    /// [`Return::AtEnd`]).
    busy: bool,
    /// A question waits for its answer.
    asking: Option<Ask>,
    /// The application's variables (its `.v3` file), by name.
    vars: BTreeMap<String, Var>,
    /// What `save` last wrote (the `.v3` file).
    saved: BTreeMap<String, Var>,
    typed: Vec<u8>,
    /// Lines typed while a command runs: the shell reads them once it prompts again.
    held: Vec<String>,
    out: Vec<u8>,
    received: Vec<String>,
}

impl C500c {
    /// A controller just switched on, in the system shell, the arm at READY with its power on;
    /// `homed` starts it homed and calibrated.
    pub fn new(sw: Switches, homed: bool, time_scale: f64) -> C500c {
        let mut arm = Arm::new(ArmSettings {
            homed,
            ..ArmSettings::default()
        });
        arm.set_home_pose(sw.home_deg.map(f64::to_radians));
        let mut c = C500c {
            pendant: sw.pendant_holds,
            grip_type: sw.grip_type,
            sw,
            arm,
            scale: time_scale.max(1e-3),
            epoch: Instant::now(),
            shell: Shell::System,
            power: true,
            home_from_homed: false,
            stale_homed: false,
            online: false,
            busy: false,
            asking: None,
            vars: BTreeMap::new(),
            saved: BTreeMap::new(),
            typed: Vec::new(),
            held: Vec::new(),
            out: Vec::new(),
            received: Vec::new(),
        };
        c.prompt();
        c
    }

    /// The controller's time, s.
    pub fn now(&self) -> f64 {
        self.epoch.elapsed().as_secs_f64() * self.scale
    }

    /// Every command line received, in order.
    pub fn received(&self) -> &[String] {
        &self.received
    }

    /// Where the arm is, TROL's joints (radians).
    pub fn joints(&mut self) -> [f64; 6] {
        let t = self.now();
        self.arm.position(t, Which::Actual)
    }

    /// Whether the arm moves.
    pub fn is_moving(&mut self) -> bool {
        let t = self.now();
        self.arm.is_moving(t)
    }

    /// Whether the gripper's jaws move.
    pub fn jaws_moving(&mut self) -> bool {
        let t = self.now();
        self.grip_type == GripType::Servo
            && (self.arm.fingers(t) - self.arm.fingers(t + 1e-3)).abs() > 0.0
    }

    /// The jaws' opening, mm.
    pub fn jaws(&mut self) -> f64 {
        let t = self.now();
        self.arm.fingers(t)
    }

    /// Give the point of control to the host (`<SHIFT><ESC>` on the pendant), or take it.
    pub fn set_pendant(&mut self, holds: bool) {
        self.pendant = holds;
    }

    /// Cut the arm's power: the axes stop where they are (brakes); with the switch, ash says
    /// so on the console.
    pub fn set_power_off(&mut self) {
        let t = self.now();
        if self.sw.cut_home_keeps_homed && self.home_from_homed && self.arm.is_moving(t) {
            self.stale_homed = true;
        }
        self.arm.halt(t);
        self.power = false;
        if self.sw.power_loss_line {
            self.line(&format!("[{APP}: Lost robot power]"));
        }
    }

    /// Put the arm at `q` (radians) as an operator would with the pendant, whatever TROL
    /// does.
    pub fn move_by_hand(&mut self, q: [f64; 6]) {
        self.arm.place(q);
    }

    /// A collision on `axis`: the arm stops where it is, and ash prints CRS's error (in the
    /// variant's form) before the prompt of the command that waited.
    pub fn collide(&mut self, axis: u8) {
        let t = self.now();
        self.arm.halt(t);
        self.error(&format!("Collision error on axis {axis}"));
    }

    /// The switches this controller runs with.
    pub fn switches(&self) -> &Switches {
        &self.sw
    }

    /// Give the arm its power back (as `armpower on` or the panel's button).
    pub fn set_power_on(&mut self) {
        self.power = true;
    }

    /// Print a line unasked (a fault the tests play).
    pub fn say(&mut self, text: &str) {
        self.line(text);
    }

    /// Whether output waits for the serving thread to send it ([`serve`]).
    pub fn has_unsent(&self) -> bool {
        !self.out.is_empty()
    }

    fn eol(&self) -> &'static [u8] {
        if self.sw.lf_only { b"\n" } else { b"\r\n" }
    }

    fn line(&mut self, text: &str) {
        self.out.extend_from_slice(text.as_bytes());
        let eol = self.eol();
        self.out.extend_from_slice(eol);
    }

    fn prompt(&mut self) {
        let p = match self.shell {
            Shell::System => "$ ".to_string(),
            Shell::Ash => format!("{APP}> "),
        };
        self.out.extend_from_slice(p.as_bytes());
    }

    fn error(&mut self, message: &str) {
        let text = match self.sw.error_form {
            ErrorForm::Bare => message.to_string(),
            ErrorForm::Prefixed => format!("{APP}: {message}"),
            ErrorForm::Bracketed => format!("[{APP}: {message}]"),
        };
        self.line(&text);
    }

    /// Feed bytes from the host; returns what the console prints.
    pub fn feed(&mut self, bytes: &[u8]) -> Vec<u8> {
        for &b in bytes {
            if let Some(Ask::Page(_)) = &self.asking {
                // The pager reads one key, with no line end.
                match b {
                    0x03 | 0x05 => self.interrupt(b),
                    b' ' => self.page(),
                    b'q' => {
                        self.asking = None;
                        let eol = self.eol();
                        self.out.extend_from_slice(eol);
                        self.prompt();
                    }
                    _ => {}
                }
                continue;
            }
            match b {
                0x03 | 0x05 => self.interrupt(b),
                b'\r' | b'\n' => {
                    if self.sw.echo {
                        let eol = self.eol();
                        self.out.extend_from_slice(eol);
                    }
                    let line = String::from_utf8_lossy(&self.typed).into_owned();
                    self.typed.clear();
                    if self.busy {
                        self.held.push(line);
                    } else {
                        self.command(&line);
                    }
                }
                0x08 | 0x7f => {
                    if self.typed.pop().is_some() && self.sw.echo {
                        self.out.extend_from_slice(b"\x08 \x08");
                    }
                }
                _ => {
                    if self.typed.len() < 256 {
                        self.typed.push(b);
                        if self.sw.echo {
                            self.out.push(b);
                        }
                    }
                }
            }
        }
        self.tick()
    }

    /// Let time pass: a command that waits for the arm gives its prompt back once it stands.
    pub fn tick(&mut self) -> Vec<u8> {
        if self.busy && !self.is_moving() && !self.jaws_moving() {
            self.busy = false;
            self.prompt();
            for line in std::mem::take(&mut self.held) {
                if self.busy {
                    self.held.push(line);
                } else {
                    self.command(&line);
                }
            }
        }
        std::mem::take(&mut self.out)
    }

    fn interrupt(&mut self, b: u8) {
        if !(b == 0x03 && self.sw.ctrl_c_keeps_line) {
            self.typed.clear();
        }
        self.held.clear();
        if self.sw.echo {
            self.out
                .extend_from_slice(if b == 0x03 { b"^C" } else { b"^E" });
        }
        let eol = self.eol();
        self.out.extend_from_slice(eol);
        let moving = self.busy || self.is_moving();
        if b == 0x03 && self.sw.ctrl_c_stops {
            let t = self.now();
            self.arm.halt(t);
        }
        self.asking = None;
        self.busy = false;
        if !(b == 0x03 && moving && !self.sw.ctrl_c_prompt) {
            self.prompt();
        }
    }

    /// The next page of `list`'s rows, and the pager's question if rows remain.
    fn page(&mut self) {
        let Some(Ask::Page(rows)) = self.asking.take() else {
            return;
        };
        // The question's line is overwritten by the next row.
        self.out.extend_from_slice(b"\r");
        let n = rows.len().min(PAGE_ROWS);
        for r in &rows[..n] {
            self.line(r);
        }
        if rows.len() > n {
            self.out.extend_from_slice(b"Hit <space> or <q>");
            self.asking = Some(Ask::Page(rows[n..].to_vec()));
        } else {
            self.prompt();
        }
    }

    fn command(&mut self, line: &str) {
        let line = line.trim();
        self.received.push(line.to_string());
        if let Some(ask) = self.asking.take() {
            match (line, ask) {
                ("y" | "yes", Ask::Exit) => self.shell = Shell::System,
                ("y" | "yes", Ask::Erase(name)) => {
                    self.vars.remove(&name);
                }
                ("y" | "yes", Ask::Valid(name)) => {
                    if let Some(Var::Cloc(v, _)) = self.vars.get(&name).cloned() {
                        self.vars.insert(name, Var::Cloc(v, true));
                    }
                }
                ("y" | "yes", Ask::Create(name)) => {
                    // Assumed: created as a cartesian location, taught where the arm is.
                    self.vars.insert(name.clone(), Var::Cloc(None, true));
                    self.here(&name);
                }
                ("n" | "no", _) => {}
                (_, ask) => {
                    self.out.extend_from_slice(b"Please answer 'yes' or 'no': ");
                    self.asking = Some(ask);
                    return;
                }
            }
            self.prompt();
            return;
        }
        if line.is_empty() {
            self.prompt();
            return;
        }
        let (word, args) = match line.split_once(char::is_whitespace) {
            Some((w, a)) => (w, a.trim()),
            None => (line, ""),
        };
        match (self.shell, word) {
            (_, "crosver") => {
                self.line(CROS_VERSION);
                self.line("CROS version 3.1.1 (simulated)");
            }
            (Shell::System, "ash") => {
                let app = args.split_whitespace().next().unwrap_or("");
                if app != APP {
                    self.line(&format!("ash: no application '{app}'"));
                } else {
                    self.shell = Shell::Ash;
                    if self.pendant {
                        self.line(&format!(
                            "Please shut down the pendant so {APP} can initialize..."
                        ));
                    }
                }
            }
            (Shell::System, _) => self.line(&format!("{word}: not found")),
            (Shell::Ash, "exit") => {
                self.out
                    .extend_from_slice(b"Are you sure you want to exit? ");
                self.asking = Some(Ask::Exit);
                return;
            }
            (Shell::Ash, "new") => self.new_var(args),
            (Shell::Ash, "here") if args.is_empty() => self.position(true),
            (Shell::Ash, "here") => {
                if self.here(args) {
                    return;
                }
            }
            (Shell::Ash, "print" | "?") => self.print_var(args),
            (Shell::Ash, "erase") => {
                if self.erase(args) {
                    return;
                }
            }
            (Shell::Ash, "list") => {
                if self.list(args) {
                    return;
                }
            }
            (Shell::Ash, "save") if args.is_empty() => {
                self.saved = self.vars.clone();
                self.line(&format!("Saving '{APP}.v3'...done."));
            }
            (Shell::Ash, "robotver") => self.line(&format!("Version string: '{ROBOT_VERSION}'")),
            (Shell::Ash, "armstat") => {
                for l in reports::print_armstat(&self.armstat()) {
                    self.line(&l);
                }
            }
            (Shell::Ash, "w0") => self.position(false),
            (Shell::Ash, "w2") => self.position(true),
            (Shell::Ash, "speed") if args.is_empty() => {
                let s = self.arm.speed().round() as u8;
                self.line(&format!("Current speed is {s}"));
            }
            (Shell::Ash, "speed") => match args.parse::<u8>() {
                Ok(v) if (1..=100).contains(&v) => {
                    self.arm.set_speed(f64::from(v));
                }
                _ => self.line("error: bad speed."),
            },
            (Shell::Ash, "armpower") => match args {
                "on" => self.power = true,
                "off" => {
                    if self.sw.ctrl_c_stops {
                        let t = self.now();
                        self.arm.halt(t);
                    }
                    self.power = false;
                }
                _ => self.line("error: missing argument."),
            },
            (Shell::Ash, "online") => match args {
                "on" => self.online = true,
                "off" => self.online = false,
                _ => self.line("error: missing argument."),
            },
            (Shell::Ash, "finish") => {
                if self.is_moving() {
                    self.busy = true;
                    return;
                }
            }
            (Shell::Ash, "griptype_set" | "gtype") => self.grip_type_set(args),
            (Shell::Ash, "wgrip") => {
                if self.grip_type == GripType::Servo {
                    let d = self.jaws();
                    self.line(&format!("Gripper distance = {d:.3}"));
                } else {
                    // Assumed: what ash says without a servo gripper is not public.
                    self.line("Gripper type must be 2(servo)");
                }
            }
            (
                Shell::Ash,
                "grip_open" | "gopen" | "go" | "grip_close" | "gclose" | "gc" | "grip"
                | "gripdist_set",
            ) => {
                if self.gripper(word, args) {
                    return;
                }
            }
            (Shell::Ash, "set" | "!") => self.set_var(args),
            (Shell::Ash, "setvalid") => {
                if self.set_valid(args) {
                    return;
                }
            }
            (Shell::Ash, "joint" | "home" | "ready" | "move" | "moves") => {
                if self.motion(word, args) {
                    return;
                }
            }
            (Shell::Ash, _) => self.line("Unrecognized command."),
        }
        self.prompt();
    }

    fn armstat(&self) -> ArmStat {
        let homed = self.stale_homed || self.arm.homed().iter().all(|&h| h);
        ArmStat {
            arm: "A465".into(),
            power: self.power,
            homing: if homed {
                Homing::Homed
            } else {
                Homing::NotHomed
            },
            metric: true,
            online: self.online,
        }
    }

    fn position(&mut self, actual: bool) {
        let t = self.now();
        let which = if actual {
            Which::Actual
        } else {
            Which::Commanded
        };
        // The PULSES row sampled first, `rows_apart` before the others (an open point).
        let at_pulses = self.arm.position(t - self.sw.rows_apart, which);
        let q = self.arm.position(t, which);
        let world = self.world(&q);
        let p = Position {
            // The pulses per degree of an A465 on a C500C, and where its axes count from,
            // are an open point: the switch's (the A465 model's counts by default).
            pulses: self.sw.pulses.pulses(&at_pulses.map(f64::to_degrees)),
            joints_deg: q.map(f64::to_degrees),
            world,
        };
        for l in reports::print_position(&p, actual, true) {
            self.line(&l);
        }
    }

    /// A motion command; true when its prompt waits for the arm.
    fn motion(&mut self, word: &str, args: &str) -> bool {
        if self.pendant {
            self.error(
                "Ash doesn't have control. Transfer control back by pressing <SHIFT><ESC> on \
                 the pendant keyboard.",
            );
            return false;
        }
        if !self.power {
            self.error("Arm power is OFF");
            return false;
        }
        let t = self.now();
        let homed = self.arm.homed().iter().all(|&h| h);
        let result = match word {
            "home" => {
                if !args.is_empty() {
                    self.line("error: too many arguments.");
                    return false;
                }
                self.home_from_homed = homed;
                self.stale_homed = false;
                self.arm.home(0, t)
            }
            _ if !homed => {
                self.error("Not homed or not calibrated");
                return false;
            }
            "ready" => {
                if !args.is_empty() {
                    self.line("error: too many arguments.");
                    return false;
                }
                self.arm.ready(t)
            }
            "move" | "moves" => {
                let Some(name) = self.var(args) else {
                    return false;
                };
                let straight = word == "moves";
                match self.vars[&name] {
                    Var::Ploc(Some(p)) => {
                        let q = self.sw.pulses.degrees(&p).map(f64::to_radians);
                        self.arm.move_to(Target::Joints(q), straight, t)
                    }
                    Var::Cloc(Some(w), true) => {
                        let pose = world::from_ash(&self.world_of_cloc(w), self.sw.reading());
                        self.arm
                            .move_to(Target::Cart(pose.to_xyzypr()), straight, t)
                    }
                    Var::Cloc(Some(_), false) => {
                        self.line("Invalid location flags");
                        return false;
                    }
                    Var::Ploc(None) | Var::Cloc(None, _) => {
                        self.error("Location has not been taught");
                        return false;
                    }
                    _ => {
                        self.line("Not a location variable.");
                        return false;
                    }
                }
            }
            _ => {
                let Some((n, deg)) = args.split_once(',') else {
                    self.line("error: missing comma.");
                    return false;
                };
                let (Ok(n), Ok(deg)) = (n.trim().parse::<u8>(), deg.trim().parse::<f64>()) else {
                    self.line("error: missing number.");
                    return false;
                };
                if !(1..=6).contains(&n) {
                    self.line("error: bad axis.");
                    return false;
                }
                let r = self.arm.joint(n, deg.to_radians(), t);
                if r == code::JOINT_LIMIT {
                    self.error(&format!("Joint {n} limit exceeded"));
                    return false;
                }
                r
            }
        };
        match result {
            code::OK => {}
            code::JOINT_LIMIT => {
                self.error("Joint 1 limit exceeded");
                return false;
            }
            code::OUT_OF_REACH => {
                self.error("Location out of reach");
                return false;
            }
            _ => {
                self.error("Invalid argument");
                return false;
            }
        }
        if self.sw.motion_return == Return::AtEnd && self.is_moving() {
            self.busy = true;
            return true;
        }
        false
    }
}

impl std::fmt::Debug for C500c {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("C500c")
            .field("switches", &self.sw)
            .field("time_scale", &self.scale)
            .finish_non_exhaustive()
    }
}

/// A controller shared between its serving thread and a test or the CLI.
pub type Shared = Arc<Mutex<C500c>>;

/// Serve the controller on `port` until `stop` is set or the port fails.
pub fn serve(mut port: Box<dyn Port>, unit: Shared, stop: Arc<AtomicBool>) -> std::io::Result<()> {
    let mut buf = [0u8; 512];
    while !stop.load(Ordering::Relaxed) {
        let n = port.recv(&mut buf, Instant::now() + Duration::from_millis(5))?;
        // Sent under the lock: once [`C500c::has_unsent`] is false, the bytes are on the line.
        let mut u = unit.lock().unwrap_or_else(|e| e.into_inner());
        let out = u.feed(&buf[..n]);
        if !out.is_empty() {
            port.send(&out)?;
        }
        drop(u);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::console::{Console, Said};

    fn said(c: &mut C500c, typed: &str) -> Vec<Said> {
        Console::default().feed(&c.feed(typed.as_bytes()))
    }

    #[test]
    fn the_factory_application_answers_as_the_public_sources_print() {
        let mut c = C500c::new(Switches::default(), true, 100.0);
        assert_eq!(c.tick(), b"$ ");
        let s = said(&mut c, "ash test\r");
        assert_eq!(
            s,
            vec![Said::Line("ash test".into()), Said::Prompt("test".into())]
        );
        // robotver as A255ROS cuts it: the version from byte 27 to the quote.
        let out = String::from_utf8(c.feed(b"robotver\r")).unwrap();
        assert_eq!(&out[10..27], "Version string: '");
        assert!(out[27..].starts_with(ROBOT_VERSION));
        let w2 = String::from_utf8(c.feed(b"w2\r")).unwrap();
        assert_eq!(&w2[98..106], "PULSES  ");
        let s = said(&mut c, "exit\r");
        assert_eq!(
            s.last(),
            Some(&Said::Question("Are you sure you want to exit?".into()))
        );
        let s = said(&mut c, "y\r");
        assert_eq!(s.last(), Some(&Said::Prompt("$".into())));
    }

    /// `w2` as the backend reads it: the lines between the echo and the prompt.
    fn w2(c: &mut C500c) -> crate::reports::Position {
        let lines: Vec<String> = said(c, "w2\r")
            .into_iter()
            .filter_map(|s| match s {
                Said::Line(l) if l != "w2" => Some(l),
                _ => None,
            })
            .collect();
        crate::reports::position(&lines, true).unwrap()
    }

    /// On `rows-apart` a moving arm's PULSES row lags its JOINTS row by the arm's speed times
    /// 40 ms, far beyond the tolerance TROL holds the pulses to; at rest, and on `default`
    /// always, the rows agree within the encoders' dither.
    #[test]
    fn a_moving_arms_rows_disagree_only_where_they_are_read_apart() {
        for (name, apart) in [("default", false), ("rows-apart", true)] {
            let sw = variant(name).unwrap();
            let mut c = C500c::new(sw.clone(), true, 1.0);
            c.feed(b"ash test\r");
            // At 20 %, a motion of seconds: read many times even on a busy machine.
            c.feed(b"speed 20\r");
            c.feed(b"joint 1,60\r");
            let mut widest: f64 = 0.0;
            let mut reads = 0;
            while c.is_moving() {
                let p = w2(&mut c);
                widest = widest.max((sw.pulses.degrees(&p.pulses)[0] - p.joints_deg[0]).abs());
                reads += 1;
            }
            assert!(reads > 3, "{name}: {reads} readings mid-motion");
            // 25 pulses, TROL's tolerance, are well under a tenth of a degree on joint 1.
            assert_eq!(widest > 0.2, apart, "{name}: rows {widest} degrees apart");
            let p = w2(&mut c);
            let rest = (sw.pulses.degrees(&p.pulses)[0] - p.joints_deg[0]).abs();
            assert!(rest < 0.01, "{name}: at rest, rows {rest} degrees apart");
        }
    }

    #[test]
    fn motions_refuse_as_crs_words_it() {
        let mut c = C500c::new(Switches::default(), false, 100.0);
        c.feed(b"ash test\r");
        let s = said(&mut c, "joint 1,10\r");
        assert!(
            s.contains(&Said::Line("Not homed or not calibrated".into())),
            "{s:?}"
        );
        c.feed(b"home\r");
        assert!(c.is_moving());
        let mut c = C500c::new(Switches::default(), true, 100.0);
        c.feed(b"ash test\r");
        let s = said(&mut c, "joint 2,170\r");
        assert!(
            s.contains(&Said::Line("Joint 2 limit exceeded".into())),
            "{s:?}"
        );
        assert!(!c.is_moving());
        let s = said(&mut c, "joint 2 10\r");
        assert!(
            s.contains(&Said::Line("error: missing comma.".into())),
            "{s:?}"
        );
    }
}

//! First contact with a C500C that only reads (`trol c500c probe`; docs/c500c.md): Ctrl-E and
//! two CR, `crosver` at the system shell, `ash <app>` where it does not run yet, then
//! `robotver`, `armstat`, `w0`, `w2` and `speed`, and `exit` (answered `y`) only where the
//! probe started ash itself, so the controller is left as it was found. Nothing that moves the
//! arm or changes a setting is sent, and every byte both ways is recorded.

use std::time::{Duration, Instant};

use trol_port::Port;

use crate::console::{self, Console, Said};
use crate::profile::MotionReturn;
use crate::reports;

/// Every byte both ways, in order (the shared core's).
pub use trol_controller::real::Transcript;

/// What first contact found.
#[derive(Debug, Default)]
pub struct Contact {
    /// Per command: the lines it printed before the prompt, or why there are none.
    pub steps: Vec<(String, Result<Vec<String>, String>)>,
    /// Every byte both ways.
    pub transcript: Transcript,
    /// What the answers say, read exactly (each a line for the person at the console).
    pub findings: Vec<String>,
}

/// The reads first contact makes in ash, in order.
pub const READS: [&str; 5] = ["robotver", "armstat", "w0", "w2", "speed"];

struct Probe<'a> {
    port: &'a mut dyn Port,
    console: Console,
    contact: Contact,
    wait: Duration,
}

impl Probe<'_> {
    fn send(&mut self, bytes: &[u8]) -> Result<(), String> {
        self.contact.transcript.chunks.push((true, bytes.to_vec()));
        self.port
            .send(bytes)
            .map_err(|e| format!("the line failed: {e}"))
    }

    /// What the console says until a prompt (or a question), or `wait` passes.
    fn read(&mut self, quiet_after_prompt: bool) -> Result<(Vec<String>, Option<Said>), String> {
        let deadline = Instant::now() + self.wait;
        let mut lines = Vec::new();
        let mut last = None;
        let mut buf = [0u8; 512];
        loop {
            let until = match &last {
                // A quiet console after its prompt: one per CR sent.
                Some(_) if quiet_after_prompt => Instant::now() + crate::backend::CONNECT_QUIET,
                Some(_) => return Ok((lines, last)),
                None => deadline,
            };
            let n = self
                .port
                .recv(&mut buf, until.min(deadline.max(Instant::now())))
                .map_err(|e| format!("the line failed: {e}"))?;
            if n == 0 {
                return Ok((lines, last));
            }
            self.contact
                .transcript
                .chunks
                .push((false, buf[..n].to_vec()));
            for s in self.console.feed(&buf[..n]) {
                match s {
                    Said::Line(l) => lines.push(l),
                    other => last = Some(other),
                }
            }
        }
    }

    /// Type `cmd` and read to ash's (or the shell's) prompt; the echo taken off.
    fn step(&mut self, cmd: &str) -> Result<(Vec<String>, Option<Said>), String> {
        self.send(format!("{cmd}\r").as_bytes())?;
        let (mut lines, end) = self.read(false)?;
        if lines.first().is_some_and(|l| l.trim_end() == cmd) {
            lines.remove(0);
        }
        Ok((lines, end))
    }

    fn record(&mut self, cmd: &str, r: Result<Vec<String>, String>) {
        self.contact.steps.push((cmd.to_string(), r));
    }

    /// Ctrl-E (ends a continuous report) and two CR, then the prompt: the shell the console
    /// runs (`$`, or ash's application).
    fn attach(&mut self) -> Result<String, String> {
        let wait = self.wait;
        self.send(b"\x05\r\r")?;
        let (before, end) = self.read(true)?;
        Ok(match end {
            Some(Said::Prompt(s)) => s,
            Some(Said::Question(q)) => {
                return Err(format!(
                    "the console waits for an answer to `{q}`: answer it at a terminal first"
                ));
            }
            _ => {
                return Err(format!(
                    "no prompt within {wait:?} after Ctrl-E and two CR: check the cable (the \
                     front console), the baud rate (57600, 8N1) and that the controller has \
                     booted{}",
                    if before.is_empty() {
                        String::new()
                    } else {
                        format!("; it printed {:?}", before)
                    }
                ));
            }
        })
    }

    /// Leave ash with `exit`, answering its question `y` (only where this started it).
    fn leave_ash(&mut self) -> Result<(), String> {
        let (lines, end) = self.step("exit")?;
        match end {
            Some(Said::Question(q)) if q.contains("exit") => {
                let (more, _) = self.step("y")?;
                self.record("exit", Ok([lines, vec![q], more].concat()));
            }
            other => self.record(
                "exit",
                Err(format!(
                    "no question after exit: {}",
                    console::heard(&other)
                )),
            ),
        }
        Ok(())
    }

    /// Where the console runs the system shell (`shell` is its prompt), start ash with `app`
    /// (noting a pendant that holds control); where ash runs `app` already, nothing. Whether
    /// this started ash (and should leave it again with `exit`).
    fn enter_ash(&mut self, shell: &str, app: &str) -> Result<bool, String> {
        if shell == "$" {
            let (lines, _) = self.step("crosver")?;
            self.record("crosver", Ok(lines.clone()));
            if let Some(l) = lines.iter().find(|l| l.starts_with("System type:")) {
                self.contact.findings.push(l.clone());
            }
            let cmd = format!("ash {app}");
            let (mut lines, mut end) = self.step(&cmd)?;
            // A system shell's prompt still on its way (one per CR sent) comes before ash's.
            while end == Some(Said::Prompt("$".into())) {
                let (more, next) = self.read(false)?;
                lines.extend(more);
                end = next;
            }
            self.record(&cmd, Ok(lines.clone()));
            if lines.iter().any(|l| l.contains("shut down the pendant")) {
                self.contact.findings.push(
                    "the pendant holds the point of control: press <SHIFT><ESC> on the pendant \
                     keyboard before the first motion"
                        .into(),
                );
            }
            match end {
                Some(Said::Prompt(a)) if a == app => return Ok(true),
                other => {
                    return Err(format!(
                        "`{cmd}` did not give ash's prompt: {}",
                        console::heard(&other)
                    ));
                }
            }
        } else if shell != app {
            return Err(format!(
                "ash runs the application `{shell}`, not `{app}`: give --app {shell}"
            ));
        }
        Ok(false)
    }
}

/// First contact: read the controller, move nothing, change nothing. `app` is the ash
/// application to read through (`test`, the factory one); `wait` bounds each answer.
pub fn first_contact(port: &mut dyn Port, app: &str, wait: Duration) -> Contact {
    let mut p = Probe {
        port,
        console: Console::default(),
        contact: Contact::default(),
        wait,
    };
    let found = (|| -> Result<(), String> {
        let shell = p.attach()?;
        p.contact
            .findings
            .push(format!("at first contact the console runs `{shell}`"));
        let started = p.enter_ash(&shell, app)?;
        for cmd in READS {
            let r = p.step(cmd).and_then(|(lines, end)| match end {
                Some(Said::Prompt(a)) if a == app => Ok(lines),
                other => Err(format!(
                    "no prompt after `{cmd}`: {} (before it {})",
                    console::heard(&other),
                    console::lines_said(&lines)
                )),
            });
            if let Ok(lines) = &r {
                let finding = match cmd {
                    "robotver" => reports::robotver(lines).map(|v| format!("robot version {v}")),
                    "armstat" => reports::armstat(lines).map(|s| {
                        format!(
                            "an {} arm, power {}, {:?}, units {}, online {}",
                            s.arm,
                            if s.power { "on" } else { "off" },
                            s.homing,
                            if s.metric { "metric" } else { "imperial" },
                            if s.online { "on" } else { "off" }
                        )
                    }),
                    "w2" => reports::position(lines, true)
                        .map(|p| format!("the arm stands at joints {:?} degrees", p.joints_deg)),
                    "w0" => reports::position(lines, false)
                        .map(|p| format!("commanded joints {:?} degrees", p.joints_deg)),
                    _ => reports::speed(lines).map(|s| format!("speed {s} %")),
                };
                p.contact.findings.push(match finding {
                    Ok(f) => f,
                    Err(e) => format!("{e}: tell TROL's maintainers (the transcript has it)"),
                });
            }
            let failed = r.is_err();
            p.record(cmd, r);
            if failed {
                break;
            }
        }
        if started {
            // Leave the controller as it was found: back to the system shell.
            p.leave_ash()?;
        }
        Ok(())
    })();
    if let Err(e) = found {
        p.contact.findings.push(format!("stopped: {e}"));
    }
    p.contact
}

/// What the supervised step `motion-return` saw (`trol c500c step motion-return`).
#[derive(Debug, Default)]
pub struct Supervised {
    /// The commands, the transcript and the findings, as first contact's.
    pub contact: Contact,
    /// When ash gave its prompt back after a motion command, where the step could tell.
    pub motion_return: Option<MotionReturn>,
}

/// The supervised step's speed setting, percent.
pub const STEP_SPEED: u8 = 5;
/// The joint it moves (the wrist's last, the least in anyone's way).
pub const STEP_JOINT: usize = 6;
/// How far, degrees (and back).
pub const STEP_DEG: f64 = 3.0;
/// How close to where it was sent the arm must end, degrees.
const STEP_TOL_DEG: f64 = 0.05;

/// The supervised step `motion-return`: after the person at the arm has confirmed it is
/// clear, with the arm powered and homed (armstat), joint 6 goes by +3 degrees at 5 % speed
/// (`speed 5`, `joint 6,3`), and back; the speed setting is typed back as it was found.
/// When ash's prompt came back after `joint` is told by where `w2` puts the arm right then:
/// short of the end, the prompt came as the motion started; at the end, after at least the
/// motion's least time, once it had ended. Anything else (a refusal, the arm not ending
/// where sent, a prompt too soon with the arm already there) settles nothing: the step
/// says what it saw and writes nothing; where the arm did not end where it was sent, or a
/// reading after the motion failed, nothing further moves it. The caller has the
/// confirmation; this sends.
pub fn motion_return_step(port: &mut dyn Port, app: &str, wait: Duration) -> Supervised {
    let (contact, settled) = in_ash(port, app, wait, |p| supervised_motion(p, app));
    Supervised {
        contact,
        motion_return: settled.flatten(),
    }
}

/// A step's frame: attach, `ash APP` where the system shell runs, `step`, and `exit` again
/// where it started ash, so the controller is left as found; what `step` returned, or the
/// reason it stopped among the findings.
fn in_ash<T>(
    port: &mut dyn Port,
    app: &str,
    wait: Duration,
    step: impl FnOnce(&mut Probe) -> Result<T, String>,
) -> (Contact, Option<T>) {
    let mut p = Probe {
        port,
        console: Console::default(),
        contact: Contact::default(),
        wait,
    };
    let r = (|| -> Result<T, String> {
        let shell = p.attach()?;
        let started = p.enter_ash(&shell, app)?;
        let r = step(&mut p);
        if started {
            p.leave_ash()?;
        }
        r
    })();
    let out = match r {
        Ok(v) => Some(v),
        Err(e) => {
            p.contact.findings.push(format!("stopped: {e}"));
            None
        }
    };
    (p.contact, out)
}

/// What the step `world-angles` saw (`trol c500c step world-angles`).
#[derive(Debug, Default)]
pub struct AnglesRead {
    /// The commands, the transcript and the findings, as first contact's.
    pub contact: Contact,
    /// The reading of the WORLD row (the angles' order and the frame they turn) that puts
    /// the flange where TROL's kinematics put it from the JOINTS row, where exactly one does.
    pub reading: Option<crate::world::Reading>,
    /// Whether a cartesian location's constant holds the WORLD row's values in its order,
    /// where the step could tell (`here trolgo`, `print trolgo`, the WORLD row's first and
    /// last angles apart).
    pub cloc_world_order: Option<bool>,
}

/// How far a reading's rotation may be from a right-angle turn of TROL's tool frame and be
/// that turn, degrees (the rows' three decimals).
const FRAME_FITS_DEG: f64 = 0.1;
/// How far the other order must be from any right-angle turn for the pose to tell the
/// orders apart, degrees.
const FRAME_APART_DEG: f64 = 1.0;

/// The step `world-angles`, which only reads: `w2` where the arm stands, and which reading
/// of the WORLD row's Z-Rot, Y-Rot and X-Rot (their order, and the frame they turn: TROL's
/// tool frame, or it turned by right angles, as public A465 models' flange frame is) puts
/// the flange where TROL's A465 kinematics put it from the JOINTS row (within 0.5 mm and 0.1
/// degrees), where the other order fits no such frame within a degree. Where both fit (the
/// arm stands where the orders coincide, as at READY) or neither does (a tool or base
/// transform set in ash), it settles nothing and says so.
pub fn world_angles_step(port: &mut dyn Port, app: &str, wait: Duration) -> AnglesRead {
    use crate::world::{self, Angles, Reading};
    let (mut contact, read) = in_ash(port, app, wait, |p| {
        let lines = read_at(p, app, "w2")?;
        let pos = reports::position(&lines, true).map_err(|e| e.to_string())?;
        // How a location holds its angles: TROL's own `trolgo` set where the arm stands,
        // printed, against the WORLD row, where its first and last angles tell.
        let order = if crate::backend::cartesian::cloc_order_tells(&pos.world) {
            cloc_order_at(p, app, &pos.world)?
        } else {
            None
        };
        Ok((pos, order))
    });
    let Some((pos, cloc_world_order)) = read else {
        return AnglesRead {
            contact,
            reading: None,
            cloc_world_order: None,
        };
    };
    match cloc_world_order {
        Some(true) => contact.findings.push(
            "`here trolgo`, then `print trolgo`, reads the WORLD row in its order: \
             cloc-world-order = true"
                .into(),
        ),
        Some(false) => contact.findings.push(
            "`here trolgo`, then `print trolgo`, does not read the WORLD row in its order: \
             ash's cartesian locations hold their values otherwise, and TROL writes and reads \
             none there"
                .into(),
        ),
        None => {}
    }
    let flange =
        trol_a465::kinematics::Kinematics::new([0.0; 6]).fk(&pos.joints_deg.map(f64::to_radians));
    // For each order: the right-angle frame nearest to what the row turns, and how far off.
    let fits: Vec<(Angles, f64, Option<world::Fit>)> = Angles::ALL
        .iter()
        .map(|&a| {
            let printed = world::from_ash(&pos.world, a);
            let mm = (printed.pos - flange.pos).length();
            let turn = flange.rot.transpose() * printed.rot;
            (a, mm, world::nearest_right_angles(&turn))
        })
        .collect();
    for (a, mm, fit) in &fits {
        contact.findings.push(match fit {
            Some((frame, deg)) => format!(
                "read as `{}`, the WORLD row is {mm:.2} mm from TROL's flange, and its frame \
                 is TROL's tool frame turned by [{}, {}, {}] degrees to {deg:.2} degrees",
                a.word(),
                frame[0],
                frame[1],
                frame[2]
            ),
            None => format!(
                "read as `{}`, the WORLD row is {mm:.2} mm from TROL's flange, and its frame \
                 is no right-angle turn of TROL's tool frame",
                a.word()
            ),
        });
    }
    let agree: Vec<Reading> = fits
        .iter()
        .filter_map(|(a, mm, fit)| match fit {
            Some((frame, deg)) if *mm <= 0.5 && *deg <= FRAME_FITS_DEG => Some(Reading {
                angles: *a,
                frame: *frame,
            }),
            _ => None,
        })
        .collect();
    let apart = fits.iter().any(|(_, _, fit)| match fit {
        Some((_, deg)) => *deg > FRAME_APART_DEG,
        None => true,
    });
    let reading = match agree[..] {
        [r] if apart => {
            contact.findings.push(format!("{} (settled)", r.words()));
            Some(r)
        }
        [_, _] | [_] => {
            contact.findings.push(format!(
                "{} where the arm stands: turn joint 4 and joint 5 by 20 degrees or more \
                 (the pendant, or TROLJoint), then run the step again",
                if agree.len() == 2 {
                    "both orders fit"
                } else {
                    "the orders are less than a degree apart"
                }
            ));
            None
        }
        _ => {
            contact.findings.push(
                "no reading puts the flange where TROL's kinematics do: ash has a tool or \
                 base transform set (`tool`, `base`), or its units are not millimetres"
                    .into(),
            );
            None
        }
    };
    AnglesRead {
        contact,
        reading,
        cloc_world_order,
    }
}

/// `here trolgo` (made with `new _trolgo` where it does not exist: TROL's own location,
/// nothing moves) and `print trolgo`: whether it reads the WORLD row `world` in its order.
fn cloc_order_at(p: &mut Probe, app: &str, world: &[f64; 6]) -> Result<Option<bool>, String> {
    use crate::backend::cartesian::{Cloc, SCRATCH, read_cloc};
    let print = format!("print {SCRATCH}");
    if read_cloc(&read_at(p, app, &print)?) == Some(Cloc::Missing) {
        quiet(p, app, &format!("new _{SCRATCH}"))?;
    }
    quiet(p, app, &format!("here {SCRATCH}"))?;
    Ok(match read_cloc(&read_at(p, app, &print)?) {
        Some(Cloc::At(got)) => Some(crate::backend::cartesian::same_values(&got, world)),
        _ => None,
    })
}

/// What the supervised step `home-pose` saw (`trol c500c step home-pose`).
#[derive(Debug, Default)]
pub struct HomeRead {
    /// The commands, the transcript and the findings, as first contact's.
    pub contact: Contact,
    /// Where the arm stood once homed, joints in degrees, read twice alike (the caller
    /// writes it as `home-joints` once the person at the arm has seen it at its home marks).
    pub joints: Option<[f64; 6]>,
}

/// How long a Home may take before the step gives up on it (assumed: six axes, each
/// searching its switch at the homing speed).
pub const HOME_WAIT: Duration = Duration::from_secs(180);
/// How far two readings of the homed arm may differ and be one pose, degrees (the rows' last
/// decimal and the encoders' dither).
const HOME_STILL_DEG: f64 = 0.01;

/// The supervised step `home-pose`: after the person at the arm has confirmed it is clear,
/// with the arm powered (armstat), `home` and `finish` (waited for up to [`HOME_WAIT`]);
/// then `armstat` must say `Robot is calibrated and homed` and two `w2` a quarter second
/// apart must put every joint within 0.01 degrees of each other: that pose is where ash
/// homes this arm. Anything else settles nothing and says why. Whether the arm stands at its
/// home marks only the person at it can see: the caller asks before writing. The caller has
/// the confirmation to move; this sends.
pub fn home_pose_step(port: &mut dyn Port, app: &str, wait: Duration) -> HomeRead {
    let (mut contact, joints) = in_ash(port, app, wait, |p| {
        let stat = reports::armstat(&read_at(p, app, "armstat")?).map_err(|e| e.to_string())?;
        if !stat.power {
            return Err(
                "arm power is off: switch it on at the controller, then run the step again".into(),
            );
        }
        let short = p.wait;
        p.wait = p.wait.max(HOME_WAIT);
        let homed = (|| {
            quiet(p, app, "home")?;
            read_at(p, app, "finish").map(|_| ())
        })();
        p.wait = short;
        homed.map_err(|e| format!("{e} (the arm may stand part way home; check it)"))?;
        let stat = reports::armstat(&read_at(p, app, "armstat")?).map_err(|e| e.to_string())?;
        if !stat.power || stat.homing != reports::Homing::Homed {
            return Err(format!(
                "after `home` and `finish`, armstat says power {} and {:?}: not homed, nothing \
                 settled",
                if stat.power { "on" } else { "off" },
                stat.homing
            ));
        }
        let a = w2(p, app)?;
        std::thread::sleep(Duration::from_millis(250));
        let b = w2(p, app)?;
        if (0..6).any(|j| (a[j] - b[j]).abs() > HOME_STILL_DEG) {
            return Err(format!(
                "the homed arm read {a:?} then {b:?} degrees a quarter second later: it does \
                 not stand; nothing settled"
            ));
        }
        Ok(b)
    });
    if let Some(q) = joints {
        contact.findings.push(format!(
            "ash homed the arm to joints {} degrees (home-joints, once you have seen it stand \
             at its home marks)",
            q.iter()
                .map(|v| format!("{v:.3}"))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    HomeRead { contact, joints }
}

/// What the step `pulses` saw (`trol c500c step pulses`).
#[derive(Debug, Default)]
pub struct PulsesRead {
    /// The commands, the transcript and the findings, as first contact's.
    pub contact: Contact,
    /// How the PULSES row relates to the JOINTS row, where every joint told it.
    pub pulses: Option<crate::pulses::Pulses>,
}

/// How far the two legs of a joint's step may disagree on its pulses per degree (a share of
/// it) and still tell it: the rounding of the rows over 3 degrees is about 0.03 %.
const LEGS_AGREE: f64 = 0.002;

/// The supervised step `pulses`: after the person at the arm has confirmed it is clear, with
/// the arm powered and homed, each joint in turn goes by 3 degrees at 5 % speed and back
/// (away from its nearer limit), with `finish` and `w2` after each. A joint's pulses per
/// degree is what its PULSES moved over what its JOINTS moved, on both legs, which must
/// agree; where it counts from follows. Every other joint's pulses must stay put while one
/// moves (an axis whose pulses follow another's is not one ratio per joint: nothing is
/// settled). The arm not ending where sent stops the step, with nothing further sent to
/// move it. The caller has the confirmation; this sends.
pub fn pulses_step(port: &mut dyn Port, app: &str, wait: Duration) -> PulsesRead {
    let (mut contact, read) = in_ash(port, app, wait, |p| {
        at_step_speed(p, app, |p| {
            let mut per_degree = [0.0; 6];
            let mut at_zero = [0; 6];
            for j in 0..6 {
                let (k, zero) = one_joint(p, app, j)?;
                per_degree[j] = k;
                at_zero[j] = zero;
            }
            Ok(crate::pulses::Pulses {
                per_degree,
                at_zero,
            })
        })
    });
    if let Some(rel) = &read {
        if let Err(e) = rel.check() {
            contact.findings.push(format!("{e}: nothing settled"));
            return PulsesRead {
                contact,
                pulses: None,
            };
        }
        contact.findings.push(format!(
            "pulses-per-degree = [{}], pulses-at-zero = [{}] (settled)",
            rel.per_degree
                .iter()
                .map(|k| format!("{k:.4}"))
                .collect::<Vec<_>>()
                .join(", "),
            rel.at_zero
                .iter()
                .map(|v| v.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    PulsesRead {
        contact,
        pulses: read,
    }
}

/// `w2`'s PULSES and JOINTS rows.
fn w2_rows(p: &mut Probe, app: &str) -> Result<reports::Position, String> {
    let lines = read_at(p, app, "w2")?;
    reports::position(&lines, true).map_err(|e| e.to_string())
}

/// Joint `j` (0-based) by 3 degrees and back: its pulses per degree and its pulses at zero.
fn one_joint(p: &mut Probe, app: &str, j: usize) -> Result<(f64, i64), String> {
    let n = j + 1;
    let a = w2_rows(p, app)?;
    let lim = trol_a465::model::LIMITS_DEG[j];
    let deg = if a.joints_deg[j] + STEP_DEG <= lim - 1.0 {
        STEP_DEG
    } else {
        -STEP_DEG
    };
    let moved = |e: String| {
        format!(
            "{e} (joint {n} may stand up to {STEP_DEG} degrees from where it started; nothing \
             further was sent to move it)"
        )
    };
    let leg = |p: &mut Probe, from: &reports::Position, by: f64| {
        let cmd = format!("joint {n},{by}");
        quiet(p, app, &cmd)?;
        read_at(p, app, "finish")?;
        let to = w2_rows(p, app)?;
        let want = from.joints_deg[j] + by;
        let arrived = (to.joints_deg[j] - want).abs() <= STEP_TOL_DEG
            && (0..6)
                .all(|k| k == j || (to.joints_deg[k] - from.joints_deg[k]).abs() <= STEP_TOL_DEG);
        if !arrived {
            return Err(format!(
                "after `{cmd}` and `finish` the arm is at {:?} degrees, not at joint {n} \
                 {want:.3}: nothing settled, and nothing further was sent (check the arm)",
                to.joints_deg
            ));
        }
        if let Some(k) = (0..6).find(|&k| {
            k != j && (to.pulses[k] - from.pulses[k]).abs() as f64 > crate::pulses::tolerance(0.0)
        }) {
            return Err(format!(
                "as joint {n} moved, joint {}'s pulses went from {} to {} with its angle \
                 unchanged: its pulses follow another axis, not one ratio per joint; nothing \
                 settled",
                k + 1,
                from.pulses[k],
                to.pulses[k]
            ));
        }
        let k = (to.pulses[j] - from.pulses[j]) as f64 / (to.joints_deg[j] - from.joints_deg[j]);
        Ok((to, k))
    };
    let (b, k1) = leg(p, &a, deg).map_err(moved)?;
    let (c, k2) = leg(p, &b, -deg).map_err(moved)?;
    if (k1 - k2).abs() > LEGS_AGREE * k1.abs().max(k2.abs()) {
        return Err(format!(
            "joint {n}: {k1:.4} pulses per degree going, {k2:.4} coming back: not one ratio; \
             nothing settled"
        ));
    }
    let k = (k1 + k2) / 2.0;
    // Where it counts from, by the first reading, and checked on all three.
    let zero = |r: &reports::Position| r.pulses[j] as f64 - k * r.joints_deg[j];
    let z = zero(&a).round() as i64;
    let rel = crate::pulses::Pulses {
        per_degree: [k; 6],
        at_zero: [z; 6],
    };
    for r in [&a, &b, &c] {
        let mut deg = [0.0; 6];
        let mut pulses = [z; 6];
        deg[j] = r.joints_deg[j];
        pulses[j] = r.pulses[j];
        if !rel.agrees(&deg, &pulses)[j] {
            return Err(format!(
                "joint {n}: {k:.4} pulses per degree from {z} does not give the {} pulses read \
                 at {:.3} degrees; nothing settled",
                r.pulses[j], r.joints_deg[j]
            ));
        }
    }
    p.contact.findings.push(format!(
        "joint {n}: {k:.4} pulses per degree ({k1:.4} going, {k2:.4} back), {z} pulses at zero"
    ));
    Ok((k, z))
}

/// A command at ash's prompt that must print nothing (a setting, a motion): its lines, or
/// the refusal.
fn quiet(p: &mut Probe, app: &str, cmd: &str) -> Result<(), String> {
    let (lines, end) = p.step(cmd)?;
    p.record(cmd, Ok(lines.clone()));
    match end {
        Some(Said::Prompt(a)) if a == app && lines.iter().all(|l| l.trim().is_empty()) => Ok(()),
        Some(Said::Question(q)) => {
            // A question nobody meant to answer: Ctrl-C, never `y`.
            p.send(b"\x03")?;
            Err(format!(
                "`{cmd}` asked `{q}`: answered with Ctrl-C; nothing settled"
            ))
        }
        other => Err(format!(
            "`{cmd}` printed {}, then {}: nothing settled",
            console::lines_said(&lines),
            console::heard(&other)
        )),
    }
}

fn read_at(p: &mut Probe, app: &str, cmd: &str) -> Result<Vec<String>, String> {
    let (lines, end) = p.step(cmd)?;
    p.record(cmd, Ok(lines.clone()));
    match end {
        Some(Said::Prompt(a)) if a == app => Ok(lines),
        other => Err(format!(
            "no prompt after `{cmd}`: {} (before it {})",
            console::heard(&other),
            console::lines_said(&lines)
        )),
    }
}

fn w2(p: &mut Probe, app: &str) -> Result<[f64; 6], String> {
    let lines = read_at(p, app, "w2")?;
    reports::position(&lines, true)
        .map(|x| x.joints_deg)
        .map_err(|e| e.to_string())
}

/// A supervised step's frame: with the arm powered and homed (armstat), the speed setting
/// read, set to [`STEP_SPEED`] and read back, `body` run, and the speed typed back as it was
/// found whatever happened once it was changed.
fn at_step_speed<T>(
    p: &mut Probe,
    app: &str,
    body: impl FnOnce(&mut Probe) -> Result<T, String>,
) -> Result<T, String> {
    let stat = reports::armstat(&read_at(p, app, "armstat")?).map_err(|e| e.to_string())?;
    if !stat.power {
        return Err(
            "arm power is off: switch it on at the controller, then run the step again".into(),
        );
    }
    if stat.homing != reports::Homing::Homed {
        return Err(format!(
            "the arm is not homed ({:?}): home it first (at the pendant, or `home` in ash)",
            stat.homing
        ));
    }
    let speed = reports::speed(&read_at(p, app, "speed")?).map_err(|e| e.to_string())?;
    quiet(p, app, &format!("speed {STEP_SPEED}"))?;
    let r = (|| {
        let now = reports::speed(&read_at(p, app, "speed")?).map_err(|e| e.to_string())?;
        if now != STEP_SPEED {
            return Err(format!(
                "`speed {STEP_SPEED}` taken, and `speed` then says {now}: nothing moved"
            ));
        }
        body(p)
    })();
    let restored = quiet(p, app, &format!("speed {speed}"));
    if let Err(e) = &restored {
        p.contact.findings.push(format!(
            "the speed setting ({speed} %) could not be typed back: {e}"
        ));
    }
    let found = r?;
    restored?;
    Ok(found)
}

/// The motion of the supervised step `motion-return` and what it tells.
fn supervised_motion(p: &mut Probe, app: &str) -> Result<Option<MotionReturn>, String> {
    let found = at_step_speed(p, app, |p| {
        let q0 = w2(p, app)?;
        let j = STEP_JOINT - 1;
        let cmd = format!("joint {STEP_JOINT},{STEP_DEG}");
        let sent = Instant::now();
        quiet(p, app, &cmd)?;
        let prompt_after = sent.elapsed();
        // From here on the arm may stand off where it started: a failure says so, and
        // nothing further moves it.
        let moved = |e: String| {
            format!(
                "{e} (after `{cmd}`: joint {STEP_JOINT} may stand up to {STEP_DEG} degrees from \
                 where it started; nothing further was sent to move it)"
            )
        };
        let at = w2(p, app).map_err(moved)?;
        read_at(p, app, "finish").map_err(moved)?;
        let end = w2(p, app).map_err(moved)?;
        let target = q0[j] + STEP_DEG;
        let arrived = (end[j] - target).abs() <= STEP_TOL_DEG
            && (0..6).all(|k| k == j || (end[k] - q0[k]).abs() <= STEP_TOL_DEG);
        if !arrived {
            // Not where it was sent: what a move back would do is not known either.
            return Err(format!(
                "after `{cmd}` and `finish` the arm is at {end:?} degrees, not at joint \
                 {STEP_JOINT} {target:.3}: nothing settled, and nothing further was sent \
                 (check the arm)"
            ));
        }
        // Back where it was.
        let back_cmd = format!("joint {STEP_JOINT},{}", -STEP_DEG);
        quiet(p, app, &back_cmd).map_err(moved)?;
        read_at(p, app, "finish").map_err(moved)?;
        let back = w2(p, app).map_err(moved)?;
        if (back[j] - q0[j]).abs() > STEP_TOL_DEG {
            p.contact.findings.push(format!(
                "the arm did not come back: joint {STEP_JOINT} at {:.3} degrees, it started at \
                 {:.3}",
                back[j], q0[j]
            ));
        }
        // The least time of the motion: the joint's top speed at the step's setting (the
        // ramps make it longer).
        let top = trol_a465::model::MAX_SPEED_DEG[j] * f64::from(STEP_SPEED) / 100.0;
        let least = Duration::from_secs_f64(STEP_DEG / top);
        let short = target - at[j] > STEP_TOL_DEG;
        p.contact.findings.push(format!(
            "`{cmd}` at {STEP_SPEED} %: the prompt came back after {} ms (the motion takes at \
             least {} ms); w2 right then put joint {STEP_JOINT} {:.3} degrees short of its end",
            prompt_after.as_millis(),
            least.as_millis(),
            (target - at[j]).max(0.0)
        ));
        Ok(if short {
            Some(MotionReturn::Start)
        } else if prompt_after >= least {
            Some(MotionReturn::End)
        } else {
            p.contact.findings.push(
                "the prompt came sooner than the motion can take, and the arm was already at \
                 its end: this cannot be told apart; nothing settled (tell TROL's maintainers; \
                 the transcript has it)"
                    .into(),
            );
            None
        })
    })?;
    if let Some(m) = found {
        p.contact.findings.push(format!(
            "motion-return = \"{}\": ash gives its prompt back {}",
            match m {
                MotionReturn::Start => "start",
                MotionReturn::End => "end",
            },
            match m {
                MotionReturn::Start => "as a motion starts",
                MotionReturn::End => "once a motion has ended",
            }
        ));
    }
    Ok(found)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::c500c::{C500c, Switches, serve};
    use std::sync::atomic::AtomicBool;
    use std::sync::{Arc, Mutex};

    /// `step` on the host's end of a line whose other end serves `unit` (in a thread of its
    /// own, stopped after).
    fn served<T>(unit: &Arc<Mutex<C500c>>, step: impl FnOnce(&mut dyn Port) -> T) -> T {
        let (mut host, ctl) = trol_port::memory::pair(None);
        let stop = Arc::new(AtomicBool::new(false));
        let t = {
            let (unit, stop) = (unit.clone(), stop.clone());
            std::thread::spawn(move || serve(Box::new(ctl), unit, stop))
        };
        let out = step(&mut host);
        stop.store(true, std::sync::atomic::Ordering::Relaxed);
        let _ = t.join();
        out
    }

    #[test]
    fn it_reads_and_leaves_the_controller_in_the_system_shell() {
        let unit = Arc::new(Mutex::new(C500c::new(Switches::default(), false, 10.0)));
        let c = served(&unit, |host| {
            first_contact(host, "test", Duration::from_secs(3))
        });
        let typed = unit.lock().unwrap().received().to_vec();
        let moving = [
            "joint", "home", "ready", "move", "speed ", "armpower", "limp",
        ];
        assert!(
            !typed
                .iter()
                .any(|l| moving.iter().any(|m| l.starts_with(m))),
            "{typed:?}"
        );
        assert_eq!(typed.last().map(String::as_str), Some("y"), "{typed:?}");
        let f = c.findings.join("\n");
        assert!(f.contains("an A465 arm, power on, NotHomed"), "{f}");
        assert!(f.contains("System type: 'CROS-104 on a C500C'"), "{f}");
        assert!(
            c.transcript.text().contains("> w2\\x0d"),
            "{}",
            c.transcript.text()
        );
        assert!(!f.contains("stopped"), "{f}");
    }

    /// The step `world-angles` on a simulated C500C of each reading (both orders, TROL's tool
    /// frame and the public models' flange frame), the arm at `q`: it reads only, settles the
    /// twin's reading where the arm stands where the orders differ, and nothing where they
    /// coincide.
    #[test]
    fn the_world_angles_step_reads_only_and_settles_only_where_it_can_tell() {
        use crate::world::{Angles, Reading};
        let turned = [0.3, -0.2, 0.4, 0.5, -0.6, 0.2];
        let flange = [0.0, 90.0, 0.0];
        for (angles, frame, q, settles) in [
            (Angles::Zyx, [0.0; 3], turned, true),
            (Angles::Xyz, [0.0; 3], turned, true),
            (Angles::Zyx, flange, turned, true),
            (Angles::Xyz, flange, turned, true),
            (Angles::Zyx, [0.0; 3], [0.0; 6], false),
        ] {
            let sw = Switches {
                world_angles: angles,
                world_frame: frame,
                ..Switches::default()
            };
            let mut twin = C500c::new(sw, true, 10.0);
            twin.move_by_hand(q);
            let unit = Arc::new(Mutex::new(twin));
            let s = served(&unit, |host| {
                world_angles_step(host, "test", Duration::from_secs(3))
            });
            let want = settles.then_some(Reading { angles, frame });
            assert_eq!(
                s.reading, want,
                "{angles:?} {frame:?} at {q:?}: {:?}",
                s.contact.findings
            );
            // Nothing that moves: reads, and TROL's own location set where the arm stands.
            let typed = unit.lock().unwrap().received().to_vec();
            let reads = [
                "",
                "crosver",
                "ash test",
                "w2",
                "exit",
                "y",
                "print trolgo",
                "new _trolgo",
                "here trolgo",
            ];
            assert!(
                typed.iter().all(|l| reads.contains(&l.as_str())),
                "{typed:?}"
            );
            if settles {
                assert_eq!(s.cloc_world_order, Some(true), "{:?}", s.contact.findings);
            }
        }
        // A controller whose locations hold the angles reversed: seen, and said.
        let sw = crate::c500c::variant("cloc-reversed").unwrap();
        let mut twin = C500c::new(sw, true, 10.0);
        twin.move_by_hand(turned);
        let unit = Arc::new(Mutex::new(twin));
        let s = served(&unit, |host| {
            world_angles_step(host, "test", Duration::from_secs(3))
        });
        assert_eq!(s.cloc_world_order, Some(false), "{:?}", s.contact.findings);
    }

    /// The step `home-pose` on a simulated C500C away from home, not homed and homed: it
    /// homes the arm and reads where ash homed it (every joint 0 on the twin); with the
    /// power off it sends nothing that moves, and settles nothing.
    #[test]
    fn the_home_pose_step_homes_and_reads_where_the_arm_stands() {
        for (name, homed) in [
            ("default", false),
            ("default", true),
            ("home-elsewhere", false),
        ] {
            let sw = crate::c500c::variant(name).unwrap();
            let want = sw.home_deg;
            let mut twin = C500c::new(sw, homed, 20.0);
            twin.move_by_hand([0.3, -0.2, 0.4, 0.5, -0.6, 0.2]);
            let unit = Arc::new(Mutex::new(twin));
            let s = served(&unit, |host| {
                home_pose_step(host, "test", Duration::from_secs(3))
            });
            let q = s
                .joints
                .unwrap_or_else(|| panic!("{name}, homed {homed}: {:?}", s.contact.findings));
            assert!(
                (0..6).all(|j| (q[j] - want[j]).abs() < 0.01),
                "{name}, homed {homed}: {q:?}"
            );
            let at = unit.lock().unwrap().joints();
            assert!(
                (0..6).all(|j| (at[j] - want[j].to_radians()).abs() < 1e-3),
                "{at:?}"
            );
        }
        let mut twin = C500c::new(Switches::default(), true, 20.0);
        twin.set_power_off();
        let unit = Arc::new(Mutex::new(twin));
        let s = served(&unit, |host| {
            home_pose_step(host, "test", Duration::from_secs(3))
        });
        assert_eq!(s.joints, None);
        let typed = unit.lock().unwrap().received().to_vec();
        assert!(!typed.iter().any(|l| l == "home"), "{typed:?}");
    }

    /// The simulated C500C of `sw` in real time (the step compares the prompt's time with
    /// the motion's), its arm homed or not, and the step run on it.
    fn step_on(sw: Switches, homed: bool) -> (Supervised, Vec<String>, [f64; 6], [f64; 6]) {
        let unit = Arc::new(Mutex::new(C500c::new(sw, homed, 1.0)));
        let before = unit.lock().unwrap().joints();
        let s = served(&unit, |host| {
            motion_return_step(host, "test", Duration::from_secs(10))
        });
        let mut u = unit.lock().unwrap();
        let after = u.joints();
        (s, u.received().to_vec(), before, after)
    }

    #[test]
    fn the_motion_return_step_measures_each_variant_and_leaves_things_as_found() {
        for (name, want) in [
            ("default", MotionReturn::Start),
            ("return-at-end", MotionReturn::End),
        ] {
            let sw = crate::c500c::variant(name).unwrap();
            let (s, typed, before, after) = step_on(sw, true);
            let f = s.contact.findings.join("\n");
            assert_eq!(s.motion_return, Some(want), "{name}: {f}");
            // The arm back where it was, the speed setting typed back (the twin's was 100),
            // ash left with `exit` as found.
            for k in 0..6 {
                assert!(
                    (after[k] - before[k]).abs() < 1e-3,
                    "{name}: {before:?} -> {after:?}"
                );
            }
            let joints: Vec<&String> = typed.iter().filter(|l| l.starts_with("joint")).collect();
            assert_eq!(joints, ["joint 6,3", "joint 6,-3"], "{name}");
            let speeds: Vec<&String> = typed.iter().filter(|l| l.starts_with("speed ")).collect();
            assert_eq!(speeds, ["speed 5", "speed 100"], "{name}");
            assert_eq!(
                typed.last().map(String::as_str),
                Some("y"),
                "{name}: {typed:?}"
            );
            assert!(
                s.contact.transcript.text().contains("> joint 6,3"),
                "{name}"
            );
        }
    }

    #[test]
    fn the_pulses_step_measures_each_joint_and_leaves_the_arm_where_it_was() {
        for name in ["default", "pulses-offset"] {
            let sw = crate::c500c::variant(name).unwrap();
            let want = sw.pulses;
            let unit = Arc::new(Mutex::new(C500c::new(sw, true, 20.0)));
            // Away from READY, joint 5 near its limit: that one goes the other way.
            unit.lock()
                .unwrap()
                .move_by_hand([0.3, -0.2, 0.5, 0.1, 104.0f64.to_radians(), -0.4]);
            let before = unit.lock().unwrap().joints();
            let s = served(&unit, |host| {
                pulses_step(host, "test", Duration::from_secs(10))
            });
            let f = s.contact.findings.join("\n");
            let got = s.pulses.unwrap_or_else(|| panic!("{name}: {f}"));
            for j in 0..6 {
                let k = want.per_degree[j];
                assert!(
                    (got.per_degree[j] - k).abs() <= 0.001 * k.abs(),
                    "{name}: joint {}: {} for {k}\n{f}",
                    j + 1,
                    got.per_degree[j]
                );
                assert!(
                    (got.at_zero[j] - want.at_zero[j]).abs() as f64
                        <= crate::pulses::tolerance(k * 180.0),
                    "{name}: joint {}: {} for {}\n{f}",
                    j + 1,
                    got.at_zero[j],
                    want.at_zero[j]
                );
            }
            let mut u = unit.lock().unwrap();
            let after = u.joints();
            for k in 0..6 {
                assert!(
                    (after[k] - before[k]).abs() < 1e-3,
                    "{name}: {before:?} -> {after:?}"
                );
            }
            let joints: Vec<&str> = u
                .received()
                .iter()
                .filter(|l| l.starts_with("joint"))
                .map(String::as_str)
                .collect();
            assert_eq!(
                joints,
                [
                    "joint 1,3",
                    "joint 1,-3",
                    "joint 2,3",
                    "joint 2,-3",
                    "joint 3,3",
                    "joint 3,-3",
                    "joint 4,3",
                    "joint 4,-3",
                    "joint 5,-3",
                    "joint 5,3",
                    "joint 6,3",
                    "joint 6,-3"
                ],
                "{name}"
            );
            let speeds: Vec<&String> = u
                .received()
                .iter()
                .filter(|l| l.starts_with("speed "))
                .collect();
            assert_eq!(speeds, ["speed 5", "speed 100"], "{name}");
        }
    }

    #[test]
    fn the_motion_return_step_moves_nothing_on_an_arm_not_homed() {
        let (s, typed, before, after) = step_on(Switches::default(), false);
        assert_eq!(s.motion_return, None);
        let f = s.contact.findings.join("\n");
        assert!(f.contains("not homed"), "{f}");
        assert!(
            !typed
                .iter()
                .any(|l| l.starts_with("joint") || l.starts_with("speed "))
        );
        // (The encoders dither by a few microradians.)
        assert!(
            (0..6).all(|k| (after[k] - before[k]).abs() < 1e-3),
            "{before:?} -> {after:?}"
        );
    }

    #[test]
    fn a_silent_line_is_said_with_what_to_check_and_recorded() {
        let (mut host, _ctl) = trol_port::memory::pair(None);
        let c = first_contact(&mut host, "test", Duration::from_millis(300));
        assert!(
            c.findings.last().unwrap().contains("check the cable"),
            "{:?}",
            c.findings
        );
        assert!(c.transcript.text().starts_with("> \\x05\\x0d\\x0d"));
    }
}

//! A simulated MARS 8 with an A465 on its axes (`trol sim --mars`): the unit as its public
//! client, ctu-mars-control-unit, expects it byte for byte, so that client and TROL's `mars:`
//! backend can both be tested against it.
//!
//! What the client does not show is a switch ([`Switches`], named [`VARIANTS`]); the
//! backend's tests run across every one. The arm: IRC counters per axis (incremental: they
//! read 0 at power-up until HH homes the axis), coordinated segments from a queue, each
//! taking at least its COORDMVT time and as long as the slowest axis needs at its REGMS, a
//! hard stop at each end of the profile's range, and a gripper on an analog axis.

use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use trol_port::Port;

use crate::line::{Lines, st};
use crate::profile::Profile;

/// What the unit does with a command it does not take (unknown, malformed, or a motion it
/// cannot run): not shown by the public client.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Refusal {
    /// Nothing is printed; the command is dropped.
    Silent,
    /// A line `ERR:<command>` is printed.
    Line,
    /// The status word's error bit is set.
    ErrorBit,
}

/// The unit's behaviour where the public sources are silent.
#[derive(Clone, Debug, PartialEq)]
pub struct Switches {
    /// Echo every line until `ECHO:0`.
    pub echo: bool,
    /// Bytes of noise at power-up (the client says the unit "can send some nonsense").
    pub noise: bool,
    /// The moving bit rises this long after a motion command, ms.
    pub moving_lag_ms: u64,
    /// What a refused command does.
    pub refusal: Refusal,
    /// STOP: while an axis moves leaves the error bit set until PURGE: or RELEASE: (on an
    /// idle arm it does not: ctu-crs's initialize() sends STOP: and then requires no error).
    pub stop_latches: bool,
    /// Replies end in `\n` instead of `\r\n`.
    pub lf_only: bool,
    /// R: holds every later command until it is answered.
    pub r_blocks: bool,
    /// The moving bit is up while the gripper axis moves too (the public sources do not say
    /// whether `ST?`'s moving bit covers it).
    pub gripper_moving: bool,
    /// `STOP:` stops the axes (else it is taken and the motion runs on).
    pub stop_stops: bool,
    /// `PURGE:` stops the axes.
    pub purge_stops: bool,
    /// The moving bit is up while an axis hard-homes (HH).
    pub homing_moving: bool,
}

impl Default for Switches {
    fn default() -> Switches {
        Switches {
            echo: false,
            noise: false,
            moving_lag_ms: 0,
            refusal: Refusal::Silent,
            stop_latches: false,
            lf_only: false,
            r_blocks: false,
            gripper_moving: false,
            stop_stops: true,
            purge_stops: true,
            homing_moving: true,
        }
    }
}

/// The named variants: each sets one switch away from the default.
pub const VARIANTS: &[(&str, &str)] = &[
    (
        "default",
        "no echo, refusals silent, the moving bit at once",
    ),
    ("echo", "echoes every line until ECHO:0"),
    ("noise", "prints noise at power-up"),
    (
        "moving-lag",
        "the moving bit rises 300 ms after a motion command",
    ),
    ("refusal-line", "a refused command prints ERR:<command>"),
    ("refusal-error-bit", "a refused command sets the error bit"),
    (
        "stop-latches",
        "STOP: while the arm moves leaves the error bit set until PURGE:",
    ),
    ("lf-only", "replies end in LF alone"),
    (
        "r-blocks",
        "R: holds every later command until it is answered",
    ),
    (
        "gripper-moving",
        "the moving bit is up while the gripper moves too",
    ),
    (
        "stop-ignored",
        "STOP: is taken but does not stop a motion (PURGE: does)",
    ),
    (
        "homing-silent",
        "the moving bit stays down while an axis hard-homes",
    ),
    (
        "unstoppable",
        "neither STOP: nor PURGE: stops a motion: a fault, for the rule that Halt never says \
         done unseen",
    ),
];

/// The switches of a named variant.
pub fn variant(name: &str) -> Option<Switches> {
    let d = Switches::default();
    Some(match name {
        "default" => d,
        "echo" => Switches { echo: true, ..d },
        "noise" => Switches { noise: true, ..d },
        "moving-lag" => Switches {
            moving_lag_ms: 300,
            ..d
        },
        "refusal-line" => Switches {
            refusal: Refusal::Line,
            ..d
        },
        "refusal-error-bit" => Switches {
            refusal: Refusal::ErrorBit,
            ..d
        },
        "stop-latches" => Switches {
            stop_latches: true,
            ..d
        },
        "lf-only" => Switches { lf_only: true, ..d },
        "r-blocks" => Switches {
            r_blocks: true,
            ..d
        },
        "gripper-moving" => Switches {
            gripper_moving: true,
            ..d
        },
        "stop-ignored" => Switches {
            stop_stops: false,
            ..d
        },
        "homing-silent" => Switches {
            homing_moving: false,
            ..d
        },
        "unstoppable" => Switches {
            stop_stops: false,
            purge_stops: false,
            ..d
        },
        _ => return None,
    })
}

/// Coordinated segments the unit keeps (assumption: the public client checks the queue-full
/// bit every 20 moves).
pub const QUEUE: usize = 32;
/// The gripper axis's speed, positions per second (assumption).
pub const GRIPPER_SPEED: f64 = 800.0;

#[derive(Clone, Copy, Debug)]
struct Move {
    from: f64,
    to: f64,
    start: f64,
    dur: f64,
}

impl Move {
    fn at(&self, t: f64) -> f64 {
        if self.dur <= 0.0 || t >= self.start + self.dur {
            return self.to;
        }
        let u = ((t - self.start) / self.dur).clamp(0.0, 1.0);
        // Smooth start and stop (assumption: the unit's own profile is not known).
        let s = u * u * (3.0 - 2.0 * u);
        self.from + (self.to - self.from) * s
    }
    fn done(&self, t: f64) -> bool {
        t >= self.start + self.dur
    }
}

/// The simulated unit and its arm.
pub struct Mars8 {
    profile: Profile,
    sw: Switches,
    scale: f64,
    epoch: Instant,
    /// Per joint axis: where the axis is (IRC of the homed frame) and where it goes.
    pos: [f64; 6],
    moves: [Option<Move>; 6],
    /// Counter = position - offset (an axis not homed counts from its power-up pose).
    offset: [f64; 6],
    /// The axes whose move under way is a hard home (HH).
    homing: [bool; 6],
    /// Each HH that came while an axis of an earlier batch still homed (CTU's client waits
    /// for each group with R:; a host that does not may start a group too early).
    overlaps: Vec<String>,
    queue: VecDeque<([f64; 6], f64)>,
    coord_group: bool,
    regms: [f64; 6],
    last_motion_cmd: f64,
    error: bool,
    power_off: bool,
    motion_stop: bool,
    silent: bool,
    echo: bool,
    gripper: Move,
    object: Option<f64>,
    waiters: VecDeque<String>,
    lines: Lines,
    held: VecDeque<String>,
    out: Vec<u8>,
    received: Vec<String>,
}

impl Mars8 {
    /// A unit just powered up with the arm at the profile's home pose; `homed` starts it with
    /// every axis homed.
    pub fn new(profile: Profile, sw: Switches, homed: bool, time_scale: f64) -> Mars8 {
        let pos = profile.joints_to_irc(&profile.home_pose_deg.map(f64::to_radians));
        let offset = if homed { [0.0; 6] } else { pos.map(f64::round) };
        let open = profile.gripper.as_ref().map(|g| g.open).unwrap_or(0.0);
        let mut m = Mars8 {
            regms: profile.speed.map(|v| v as f64),
            profile,
            echo: sw.echo,
            sw,
            scale: time_scale.max(1e-3),
            epoch: Instant::now(),
            pos,
            moves: [None; 6],
            offset,
            homing: [false; 6],
            overlaps: Vec::new(),
            queue: VecDeque::new(),
            coord_group: false,
            last_motion_cmd: f64::NEG_INFINITY,
            error: false,
            power_off: false,
            motion_stop: false,
            silent: false,
            gripper: Move {
                from: open,
                to: open,
                start: 0.0,
                dur: 0.0,
            },
            object: None,
            waiters: VecDeque::new(),
            lines: Lines::default(),
            held: VecDeque::new(),
            out: Vec::new(),
            received: Vec::new(),
        };
        if m.sw.noise {
            m.out.extend_from_slice(b"\x00\xfe\x13#?MARS boot\r\n\xff");
        }
        m
    }

    /// The unit's time, s.
    pub fn now(&self) -> f64 {
        self.epoch.elapsed().as_secs_f64() * self.scale
    }

    /// Each hard home that came while an axis of an earlier batch still homed.
    pub fn overlaps(&self) -> &[String] {
        &self.overlaps
    }

    /// Every command line received, in order.
    pub fn received(&self) -> &[String] {
        &self.received
    }

    /// Where the arm is, TROL's joints (radians), whatever the counters say.
    pub fn joints(&mut self) -> [f64; 6] {
        let t = self.now();
        self.advance(t);
        let p: [f64; 6] = std::array::from_fn(|j| self.axis_pos(j, t));
        self.profile.irc_to_joints(&p)
    }

    /// Whether an axis or the gripper moves.
    pub fn is_moving(&mut self) -> bool {
        let t = self.now();
        self.advance(t);
        self.busy(t)
    }

    /// Cut the arm's power: the axes stop where they are (brakes), the queue is dropped.
    pub fn set_power_off(&mut self, off: bool) {
        let t = self.now();
        if off {
            self.stop_all(t);
        }
        self.power_off = off;
    }

    /// Press (or release) the motion stop.
    pub fn set_motion_stop(&mut self, on: bool) {
        let t = self.now();
        if on {
            self.stop_all(t);
        }
        self.motion_stop = on;
    }

    /// A unit that no longer answers (hung, or its cable cut at the unit's end).
    pub fn set_silent(&mut self, silent: bool) {
        self.silent = silent;
    }

    /// An object between the fingers: closing stops at this gripper position.
    pub fn set_object(&mut self, at: Option<f64>) {
        self.object = at;
    }

    /// Print a line unasked (a fault the client did not cause).
    pub fn say(&mut self, text: &str) {
        self.reply(text);
    }

    fn axis_pos(&self, j: usize, t: f64) -> f64 {
        match &self.moves[j] {
            Some(m) => m.at(t),
            None => self.pos[j],
        }
    }

    fn counter(&self, j: usize, t: f64) -> f64 {
        (self.axis_pos(j, t) - self.offset[j]).round()
    }

    fn axes_moving(&self, t: f64) -> bool {
        self.moves.iter().flatten().any(|m| !m.done(t)) || !self.queue.is_empty()
    }

    fn busy(&self, t: f64) -> bool {
        self.axes_moving(t) || !self.gripper.done(t)
    }

    fn stop_all(&mut self, t: f64) {
        for j in 0..6 {
            self.pos[j] = self.axis_pos(j, t);
            self.moves[j] = None;
        }
        self.queue.clear();
        let g = self.gripper.at(t);
        self.gripper = Move {
            from: g,
            to: g,
            start: t,
            dur: 0.0,
        };
    }

    /// Retire finished moves, start queued segments, hit the hard stops.
    fn advance(&mut self, t: f64) {
        for j in 0..6 {
            if let Some(m) = self.moves[j] {
                let (lo, hi) = self.profile.range_irc(j);
                // A homed axis that leaves its range hits the stop (a homing axis runs to
                // its switch, inside).
                let p = m.at(t);
                let margin = 2000.0;
                if p < lo as f64 - margin || p > hi as f64 + margin {
                    self.pos[j] = p.clamp(lo as f64 - margin, hi as f64 + margin);
                    self.error = true;
                    self.stop_all(t);
                    return;
                }
                if m.done(t) {
                    self.pos[j] = m.to;
                    self.moves[j] = None;
                }
            }
        }
        while !self.axes_moving_now(t) {
            let Some((target, min_time)) = self.queue.pop_front() else {
                break;
            };
            let to: [f64; 6] = std::array::from_fn(|j| target[j] + self.offset[j]);
            let mut dur = min_time;
            for (j, to) in to.iter().enumerate() {
                let v = (self.regms[j] / 256.0 * 1000.0).max(1.0);
                dur = dur.max((to - self.pos[j]).abs() / v);
            }
            for (j, to) in to.into_iter().enumerate() {
                self.homing[j] = false;
                self.moves[j] = Some(Move {
                    from: self.pos[j],
                    to,
                    start: t,
                    dur,
                });
            }
        }
    }

    fn axes_moving_now(&self, t: f64) -> bool {
        self.moves.iter().flatten().any(|m| !m.done(t))
    }

    fn reply(&mut self, text: &str) {
        self.out.extend_from_slice(text.as_bytes());
        self.out
            .extend_from_slice(if self.sw.lf_only { b"\n" } else { b"\r\n" });
    }

    fn refuse(&mut self, cmd: &str) {
        match self.sw.refusal {
            Refusal::Silent => {}
            Refusal::Line => self.reply(&format!("ERR:{cmd}")),
            Refusal::ErrorBit => self.error = true,
        }
    }

    fn status(&self, t: f64) -> u32 {
        let mut s = 0;
        if self.error {
            s |= st::ERROR;
        }
        let lagging = (t - self.last_motion_cmd) * 1000.0 / self.scale.max(1e-9)
            < self.sw.moving_lag_ms as f64;
        let shown = (0..6).any(|j| {
            self.moves[j]
                .as_ref()
                .is_some_and(|m| !m.done(t) && (self.sw.homing_moving || !self.homing[j]))
        }) || !self.queue.is_empty();
        if shown && !lagging {
            s |= st::MOVING;
        }
        if self.sw.gripper_moving && !self.gripper.done(t) {
            s |= st::MOVING;
        }
        if self.queue.len() >= QUEUE {
            s |= st::QUEUE_FULL;
        }
        if self.power_off {
            s |= st::POWER_OFF;
        }
        if self.motion_stop {
            s |= st::MOTION_STOP;
        }
        s
    }

    fn axis_index(&self, c: &str) -> Option<usize> {
        if c.len() != 1 {
            return None;
        }
        self.profile.axes.find(c)
    }

    fn gripper_axis(&self, c: &str) -> bool {
        self.profile.gripper.as_ref().is_some_and(|g| g.axis == c)
    }

    fn can_move(&self) -> bool {
        !(self.power_off || self.motion_stop || self.error)
    }

    /// Feed bytes from the line; returns what the unit prints.
    pub fn feed(&mut self, bytes: &[u8]) -> Vec<u8> {
        if !self.silent {
            for l in self.lines.feed(bytes) {
                self.held.push_back(l);
            }
        }
        self.tick()
    }

    /// Let time pass; returns what the unit prints.
    pub fn tick(&mut self) -> Vec<u8> {
        let t = self.now();
        self.advance(t);
        self.answer_waiters(t);
        while !self.sw.r_blocks || self.waiters.is_empty() {
            let Some(l) = self.held.pop_front() else {
                break;
            };
            self.received.push(l.clone());
            if self.echo {
                self.reply(&l);
            }
            self.execute(l.trim(), t);
            self.answer_waiters(t);
        }
        if self.silent {
            self.out.clear();
        }
        std::mem::take(&mut self.out)
    }

    fn answer_waiters(&mut self, t: f64) {
        // Answer waiters (R:, R<axis>:) that are ready.
        while let Some(w) = self.waiters.front().cloned() {
            let failed = self.power_off || self.motion_stop || self.error;
            let ready = if w.is_empty() {
                !self.axes_moving(t)
            } else if self.gripper_axis(&w) {
                self.gripper.done(t)
            } else {
                self.axis_index(&w)
                    .map(|j| self.moves[j].is_none_or(|m| m.done(t)) && self.queue.is_empty())
                    .unwrap_or(true)
            };
            if failed {
                self.waiters.pop_front();
                self.reply("FAIL!");
            } else if ready {
                self.waiters.pop_front();
                self.reply(&format!("R{w}!"));
            } else {
                break;
            }
        }
    }

    fn execute(&mut self, cmd: &str, t: f64) {
        if cmd.is_empty() {
            return;
        }
        if let Some(name) = cmd.strip_suffix('?') {
            return self.query(name, t);
        }
        let Some((word, args)) = cmd.split_once(':') else {
            return self.refuse(cmd);
        };
        if word == "COORDGRP" {
            let all = args.split(',').map(str::trim).collect::<Vec<_>>().join("");
            if all.is_empty() || !all.chars().all(|c| self.profile.axes.contains(c)) {
                return self.refuse(cmd);
            }
            // A group other than the arm's six: coordinated moves of six axes are refused.
            self.coord_group = all == self.profile.axes;
            return;
        }
        let nums: Vec<Option<f64>> = if args.trim().is_empty() {
            Vec::new()
        } else {
            args.split(',')
                .map(|a| a.trim().parse::<f64>().ok().filter(|v| v.is_finite()))
                .collect()
        };
        let ints: Option<Vec<f64>> = nums.iter().copied().collect();
        let Some(ints) = ints else {
            return self.refuse(cmd);
        };
        match word {
            "ECHO" if ints.len() == 1 => self.echo = ints[0] != 0.0,
            "STAMP" if ints.len() == 1 => self.reply(&format!("STAMP={}", ints[0] as i64)),
            "PURGE" | "RELEASE" if ints.is_empty() => {
                self.error = false;
                if word == "PURGE" && self.sw.purge_stops {
                    self.stop_all(t);
                }
            }
            "STOP" if ints.is_empty() => {
                if self.sw.stop_stops {
                    if self.sw.stop_latches && self.axes_moving(t) {
                        self.error = true;
                    }
                    self.stop_all(t);
                }
            }
            "R" if ints.is_empty() => self.waiters.push_back(String::new()),
            "IDLEREL" | "SPDTB" | "COORDISCONT" => {}
            "COORDMV" | "COORDMVT" => {
                let (min_ms, axes) = if word == "COORDMVT" && ints.len() == 7 {
                    (ints[0], &ints[1..])
                } else if word == "COORDMV" && ints.len() == 6 {
                    (0.0, &ints[..])
                } else {
                    return self.refuse(cmd);
                };
                if !self.coord_group || !self.can_move() || min_ms < 0.0 {
                    return self.refuse(cmd);
                }
                if self.queue.len() >= QUEUE {
                    return self.refuse(cmd);
                }
                let target: [f64; 6] = std::array::from_fn(|j| axes[j]);
                self.queue.push_back((target, min_ms / 1000.0));
                self.last_motion_cmd = t;
                self.advance(t);
            }
            w if w.starts_with("HH") => match self.axis_index(&w[2..]) {
                Some(j) if ints.is_empty() && self.can_move() => {
                    let still: Vec<char> = (0..6)
                        .filter(|&k| {
                            k != j
                                && self.homing[k]
                                && self.moves[k]
                                    .as_ref()
                                    .is_some_and(|m| !m.done(t) && t - m.start > 0.1)
                        })
                        .map(|k| self.profile.axis(k))
                        .collect();
                    if !still.is_empty() {
                        self.overlaps.push(format!(
                            "{w} while {} still homed",
                            still.iter().collect::<String>()
                        ));
                    }
                    // To the home switch (the homed frame's 0) at the axis's REGMS.
                    let from = self.axis_pos(j, t);
                    let v = (self.regms[j] / 256.0 * 1000.0).max(1.0);
                    self.offset[j] = 0.0;
                    self.homing[j] = true;
                    self.moves[j] = Some(Move {
                        from,
                        to: 0.0,
                        start: t,
                        dur: (from.abs() / v).max(0.5),
                    });
                    self.last_motion_cmd = t;
                }
                _ => self.refuse(cmd),
            },
            w if w.starts_with('R') && w.len() == 2 && ints.is_empty() => {
                let a = &w[1..];
                if self.axis_index(a).is_some() || self.gripper_axis(a) {
                    self.waiters.push_back(a.to_string());
                } else {
                    self.refuse(cmd)
                }
            }
            w if w.starts_with("RELEASE") && ints.is_empty() => {
                if !(self.axis_index(&w[7..]).is_some() || self.gripper_axis(&w[7..])) {
                    self.refuse(cmd)
                }
            }
            w if w.starts_with('G') && w.len() == 2 && ints.len() == 1 => {
                if !self.gripper_axis(&w[1..]) || !self.can_move() {
                    return self.refuse(cmd);
                }
                let from = self.gripper.at(t);
                let mut to = ints[0];
                if let (Some(o), Some(g)) = (self.object, &self.profile.gripper) {
                    // Closing stops at the object.
                    let closing = (g.closed - g.open).signum();
                    if (to - o) * closing > 0.0 && (from - o) * closing <= 0.0 {
                        to = o;
                    }
                }
                self.gripper = Move {
                    from,
                    to,
                    start: t,
                    dur: (to - from).abs() / GRIPPER_SPEED,
                };
            }
            w if [
                "REGMS",
                "REGACC",
                "REGME",
                "REGCFG",
                "REGP",
                "REGI",
                "REGD",
                "REGS1",
                "REGS2",
                "ANAXSETUP",
            ]
            .iter()
            .any(|p| w.starts_with(p) && w.len() == p.len() + 1) =>
            {
                let a = &w[w.len() - 1..];
                let j = self.axis_index(a);
                if j.is_none() && !self.gripper_axis(a) || ints.is_empty() {
                    return self.refuse(cmd);
                }
                if let (Some(j), true) = (j, w.starts_with("REGMS")) {
                    if ints[0] > 0.0 {
                        self.regms[j] = ints[0];
                    }
                }
            }
            _ => self.refuse(cmd),
        }
    }

    fn query(&mut self, name: &str, t: f64) {
        match name {
            "VER" => self.reply("VER=TROL simulated MARS 8 1.0"),
            "ST" => {
                let s = self.status(t);
                self.reply(&format!("ST={s}"));
            }
            "COORDAP" => {
                let mut v: Vec<String> = Vec::new();
                v.push(format!("{}", (t * 1000.0) as i64 & 0x7fff_ffff));
                // Three numbers before the axes: ctu-crs reads the axes from index 3 on,
                // pyrocon as the last six. What the two after the time are is not known.
                v.push("0".into());
                v.push("0".into());
                for j in 0..6 {
                    v.push(format!("{}", self.counter(j, t) as i64));
                }
                self.reply(&format!("COORDAP={}", v.join(",")));
            }
            n if n.starts_with("AP") && n.len() == 3 => {
                let a = &n[2..];
                if let Some(j) = self.axis_index(a) {
                    let c = self.counter(j, t) as i64;
                    self.reply(&format!("AP{a}={c}"));
                } else if self.gripper_axis(a) {
                    let g = self.gripper.at(t).round() as i64;
                    self.reply(&format!("AP{a}={g}"));
                } else {
                    self.refuse(&format!("{name}?"))
                }
            }
            _ => self.refuse(&format!("{name}?")),
        }
    }
}

/// A unit shared between its serving thread and a test or the CLI.
pub type Shared = Arc<Mutex<Mars8>>;

/// Serve the unit on `port` until `stop` is set or the port fails.
pub fn serve(mut port: Box<dyn Port>, unit: Shared, stop: Arc<AtomicBool>) -> std::io::Result<()> {
    let mut buf = [0u8; 512];
    while !stop.load(Ordering::Relaxed) {
        let n = port.recv(&mut buf, Instant::now() + Duration::from_millis(5))?;
        let out = {
            let mut u = unit.lock().unwrap_or_else(|e| e.into_inner());
            u.feed(&buf[..n])
        };
        if !out.is_empty() {
            port.send(&out)?;
        }
    }
    Ok(())
}

impl std::fmt::Debug for Mars8 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Mars8")
            .field("time_scale", &self.scale)
            .finish_non_exhaustive()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> Mars8 {
        Mars8::new(Profile::crs93(), Switches::default(), true, 100.0)
    }

    fn text(b: Vec<u8>) -> String {
        String::from_utf8(b).unwrap()
    }

    #[test]
    fn it_answers_as_the_public_client_reads_it() {
        let mut u = unit();
        assert_eq!(text(u.feed(b"\nECHO:0\nSTAMP:17\n")), "STAMP=17\r\n");
        assert_eq!(
            text(u.feed(b"\nVER?\n")),
            "VER=TROL simulated MARS 8 1.0\r\n"
        );
        assert_eq!(text(u.feed(b"\nST?\n")), "ST=0\r\n");
        let ap = text(u.feed(b"\nCOORDAP?\n"));
        let v: Vec<&str> = ap
            .trim()
            .strip_prefix("COORDAP=")
            .unwrap()
            .split(',')
            .collect();
        assert_eq!(v.len(), 9);
        assert_eq!(text(u.feed(b"\nR:\n")), "R!\r\n");
        // A move without COORDGRP is refused (silently, by default), and nothing moves.
        assert_eq!(text(u.feed(b"COORDMV:0,0,0,0,0,0\n")), "");
        assert!(!u.is_moving());
    }

    #[test]
    fn a_coordinated_move_runs_and_r_answers_when_it_ends() {
        let mut u = unit();
        u.feed(b"COORDGRP:A,B,C,D,E,F\n");
        let p = Profile::crs93();
        let target = p
            .joints_to_irc(&[0.1, 0.0, 0.5, 0.0, 0.5, 0.0])
            .map(f64::round);
        let cmd = format!(
            "COORDMVT:500,{}\nR:\n",
            target.map(|v| (v as i64).to_string()).join(",")
        );
        assert_eq!(text(u.feed(cmd.as_bytes())), "");
        assert!(u.is_moving());
        assert!(text(u.feed(b"\nST?\n")).contains(&format!("ST={}", st::MOVING)));
        let deadline = Instant::now() + Duration::from_secs(10);
        let mut got = String::new();
        while !got.contains("R!") && Instant::now() < deadline {
            got += &text(u.tick());
            std::thread::sleep(Duration::from_millis(2));
        }
        assert_eq!(got, "R!\r\n");
        let q = u.joints();
        assert!((q[0] - 0.1).abs() < 1e-3, "{q:?}");
    }

    #[test]
    fn counters_read_from_the_power_up_pose_until_homed() {
        let mut u = Mars8::new(Profile::crs93(), Switches::default(), false, 100.0);
        let ap = text(u.feed(b"\nCOORDAP?\n"));
        assert!(ap.ends_with(",0,0,0,0,0,0\r\n"), "{ap}");
        u.feed(b"HHB:\n");
        assert!(u.is_moving());
    }
}

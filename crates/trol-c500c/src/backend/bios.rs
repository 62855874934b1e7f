//! The calls of the controller's contract ([`trol_controller::Backend`]) on a C500C, and
//! Halt's stop and readings for [`real::halt`].

use super::*;

/// Six values of a location, or BIOS_BAD_ARGUMENT.
fn array6(v: &[f64]) -> Result<[f64; 6], BackendError> {
    match <[f64; 6]>::try_from(v) {
        Ok(a) if a.iter().all(|x| x.is_finite()) => Ok(a),
        _ => Err(BackendError::Refused(code::BAD_ARGUMENT)),
    }
}

/// The ways TROL stops the arm from ash's console, in the order a Halt tries them (issue
/// 62, item 4): the next is tried where one gets no prompt of ash's back within
/// [`STOP_PROMPT`] (the arm's readings need it) or the arm is not seen standing.
pub const HALT_STOPS: [HaltStop; 3] = [HaltStop::CtrlC, HaltStop::CtrlE, HaltStop::PowerOff];

/// One of [`HALT_STOPS`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HaltStop {
    /// Ctrl-C: ash's interrupt (assumed to stop a motion: ash's own way is not public).
    CtrlC,
    /// Ctrl-E, which ends ash's continuous reports (`w1`, `w3`) and brings its prompt back
    /// (the public scripts send it first).
    CtrlE,
    /// `armpower off`: the arm's power cut (it must then be switched on, and homed where
    /// the controller asks).
    PowerOff,
}

/// Ctrl-C, Ctrl-E and `armpower off` for [`real::halt`], and `w2` for its readings.
impl real::Stopping for C500cBackend {
    type Stop = HaltStop;

    fn stop_name(&self, stop: HaltStop) -> String {
        match stop {
            HaltStop::CtrlC => "Ctrl-C",
            HaltStop::CtrlE => "Ctrl-E",
            HaltStop::PowerOff => "`armpower off`",
        }
        .into()
    }

    fn send_stop(&mut self, stop: HaltStop) -> Result<String, String> {
        match stop {
            HaltStop::CtrlC | HaltStop::CtrlE => {
                let key: &[u8] = if stop == HaltStop::CtrlC {
                    b"\x03"
                } else {
                    b"\x05"
                };
                self.send(key).map_err(|e| e.to_string())?;
                self.console.clear();
                self.rx.clear();
            }
            HaltStop::PowerOff => {
                self.type_line("armpower off").map_err(|e| e.text())?;
            }
        }
        // ash's prompt after it; what it printed before is kept for the log.
        let app = self.profile.app.clone();
        let deadline = Instant::now() + STOP_PROMPT;
        let mut said = Vec::new();
        loop {
            match self.next(deadline).map_err(|e| e.to_string())? {
                Some(Said::Prompt(p)) if p == app => break,
                Some(Said::Line(l))
                    if l.trim().is_empty() || ["^C", "^E", "armpower off"].contains(&l.trim()) => {}
                Some(s) => said.push(s.to_string()),
                None => {
                    return Err(format!(
                        "no prompt of ash's within {STOP_PROMPT:?}{}",
                        if said.is_empty() {
                            String::new()
                        } else {
                            format!(" (it printed {})", said.join(", "))
                        }
                    ));
                }
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
        let lines = self.exchange("w2").map_err(|e| e.text())?;
        // Halt's readings: the arm may still move, and the two rows of a moving arm need not
        // be one instant's, so they are not held against the profile's pulses.
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
    fn appro(&mut self, target: &Target, disp: [f64; 6], straight: bool) -> BiosResult {
        match target {
            Target::Name(name) => self.named_motion(*name, Some(disp), straight),
            Target::Location(Location::Cart(v)) => {
                let v = array6(v)?;
                self.cart_motion(cartesian::CartCall::Appro(v, disp), straight)
            }
            Target::Location(_) => self.no_ploc_values(),
        }
    }
    fn depart(&mut self, disp: [f64; 6], straight: bool) -> BiosResult {
        self.cart_motion(cartesian::CartCall::Depart(disp), straight)
    }
    fn jog(&mut self, d: [f64; 3], straight: bool) -> BiosResult {
        self.cart_motion(cartesian::CartCall::Jog(d), straight)
    }
    fn move_to(&mut self, target: &Target, straight: bool) -> BiosResult {
        match target {
            Target::Name(name) => self.move_named(*name, straight),
            Target::Location(Location::Cart(v)) => {
                let v = array6(v)?;
                self.cart_motion(cartesian::CartCall::Move(v), straight)
            }
            Target::Location(_) => self.no_ploc_values(),
        }
    }
    fn here(&mut self, name: LocName, tag: Tag) -> BiosResult {
        self.teach_here(name, tag)
    }
    fn define(&mut self, name: LocName, _: &Location) -> BiosResult {
        self.teach_define(name)
    }
    fn delete_location(&mut self, name: LocName) -> BiosResult {
        self.teach_delete(name)
    }
    fn locations(&mut self) -> Result<Vec<(LocName, Location)>, BackendError> {
        self.teach_list()
    }
    fn save_locations(&mut self) -> BiosResult {
        self.teach_save()
    }
    fn close(&mut self, force: u8) -> BiosResult {
        self.grip_command(gripper::GripCall::Close(force))
    }
    fn open(&mut self, force: u8) -> BiosResult {
        self.grip_command(gripper::GripCall::Open(force))
    }
    fn grip(&mut self, dist: u8) -> BiosResult {
        self.grip_command(gripper::GripCall::Grip(dist))
    }
    fn gripper(&mut self) -> Result<Gripper, BackendError> {
        self.read_gripper()
    }
    fn moving(&mut self) -> Result<bool, BackendError> {
        if std::mem::take(&mut self.homing_halted) {
            self.note(
                "Home was halted before ash said done: the arm is not homed as asked, wherever \
                 armstat says; call TROLHome again"
                    .into(),
            );
            return Err(BackendError::Refused(code::NOT_HOMED));
        }
        if self.jaws_wait.is_some() {
            self.clean()?;
            if self.look_jaws()? {
                return Ok(true);
            }
            // The jaws stand: a motion queued behind them goes now.
        }
        if self.outstanding.is_none() {
            self.clean()?;
            match self.queue.pop() {
                Some(next) => {
                    self.send_next(next)?;
                }
                None => return Ok(false),
            }
        }
        self.look()
    }
    fn stands(&mut self) -> Result<bool, BackendError> {
        Ok(self.outstanding.is_none() && self.queue.is_empty() && self.jaws_wait.is_none())
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
        let homing = self
            .outstanding
            .as_ref()
            .is_some_and(|o| matches!(o.motion.kind, Kind::Home))
            || self.queue.iter().any(|q| matches!(q.kind, Kind::Home));
        match real::halt(self, &HALT_STOPS, times) {
            real::Halted::Standing { at, note } => {
                self.homing_halted |= homing;
                let n = self.queue.drop_all();
                self.outstanding = None;
                self.jaws_wait = None;
                self.rests_at(at);
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
                self.jaws_wait = None;
                self.broken = Some(format!("Halt: {why}"));
                self.note(format!("Halt: {why}"));
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

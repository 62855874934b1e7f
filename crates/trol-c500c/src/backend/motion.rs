//! A motion: the gate and the queue, typing it, and its end seen on the arm (Finish's look);
//! relative motions from where the arm was seen to rest.

use super::*;

impl C500cBackend {
    /// The gate and the queue, then the motion.
    pub(super) fn motion(&mut self, m: Motion) -> BiosResult {
        self.clean()?;
        if self.profile.motion_return.is_none() {
            return self.unsettled(
                "a motion needs to know when ash gives its prompt back: set `motion-return = \
                 \"start\"` or `\"end\"` in the C500C profile (the probe's supervised step \
                 `motion-return` measures it)",
            );
        }
        if matches!(m.kind, Kind::Home) && self.profile.home_joints.is_none() {
            // A Home is done only with the arm seen at its home pose (issue 62): without it
            // in the profile TROL could only take ash's word.
            return self.unsettled(
                "a Home is done only with the arm seen at its home pose, which is not public \
                 for an A465 on a C500C: set `home-joints` in the C500C profile (`trol c500c \
                 step home-pose` homes the arm under supervision and reads it)",
            );
        }
        // While ash runs a motion of TROL's to its end it reads no command: the gate then
        // takes the status read before that motion (a fault meanwhile ends it with a line).
        // Else `armstat`, unless it was read, or a motion of TROL's was seen to end, a moment
        // ago with nothing but reads typed since ([`real::SEEN_FOR`]): ash refuses a motion
        // itself where the arm lost power meanwhile (`Arm power is OFF`), which is then the
        // refusal with its code.
        if !self.console_busy() {
            // A reading of a moment ago stands for the arm only where it lets the motion
            // go: one that would refuse it (no power, not homed) is read again, so that an
            // arm whose power came back is not refused on a stale word.
            let fresh = self
                .stat_seen
                .get(Instant::now())
                .filter(|s| s.power && s.homing == Homing::Homed)
                .cloned();
            match fresh {
                Some(stat) => self.stat = stat,
                None => {
                    let lines = match self.exchange("armstat") {
                        Ok(l) => l,
                        Err(e) => return Err(self.fail(e)),
                    };
                    self.stat = reports::armstat(&lines).map_err(|e| self.unsure(e.to_string()))?;
                    self.stat_seen.saw(Instant::now(), Some(self.stat.clone()));
                }
            }
        }
        // The arm does not move while the gripper's jaws do: a motion behind a grip command
        // of TROL's waits in the queue until they stand, as behind a motion (the manual's
        // TROLClose then TROLDepart runs both; issue 62: it was BIOS_BUSY).
        let ours = self.outstanding.is_some() || !self.queue.is_empty() || self.jaws_wait.is_some();
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
    pub(super) fn planned(&self, kind: Kind) -> Duration {
        let mut arm = Arm::new(ArmSettings {
            homed: true,
            ..ArmSettings::default()
        });
        arm.place(self.rest.map(f64::to_radians));
        arm.set_speed(f64::from(self.speed.max(1)));
        let r = match kind {
            Kind::Joint(n, deg) => arm.joint(n, deg.to_radians(), 0.0),
            Kind::Home => arm.home(0, 0.0),
            Kind::Pose(_, secs) => return Duration::from_secs_f64(secs),
            // Worked out before it is sent.
            Kind::Pending(_) => return Duration::from_secs(60),
            // Where a precision point is in degrees, by the profile's pulses where the arm
            // has shown them ([`Self::ploc_degrees`]); else the time bound is that of the
            // longest motion from here, each joint to its farther limit.
            Kind::Named(p) => {
                let end = self.ploc_degrees(&p).unwrap_or_else(|| {
                    std::array::from_fn(|j| {
                        let lim = trol_a465::model::LIMITS_DEG[j];
                        if self.rest[j] >= 0.0 { -lim } else { lim }
                    })
                });
                arm.ma(end.map(f64::to_radians), 0.0)
            }
        };
        if r != code::OK {
            return Duration::from_secs(60);
        }
        Duration::from_secs_f64(arm.done_at(0.0).clamp(0.0, 600.0))
    }

    pub(super) fn send_motion(&mut self, m: Motion) -> BiosResult {
        let m = match m.kind {
            Kind::Pending(p) => self.resolve(p)?,
            _ => m,
        };
        let planned = self.planned(m.kind);
        let target = match m.kind {
            Kind::Joint(n, deg) => {
                let mut t = self.rest;
                t[n as usize - 1] += deg;
                Some(t)
            }
            Kind::Home | Kind::Named(_) | Kind::Pose(..) | Kind::Pending(_) => None,
        };
        if let Err(e) = self.type_line(&m.line) {
            return Err(self.fail(e));
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
                let seen: Vec<String> = self.rx.drain(..).map(|s| s.to_string()).collect();
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
    pub(super) fn end_times(&self) -> real::EndTimes {
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
    pub(super) fn look(&mut self) -> Result<bool, BackendError> {
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
            if let Err(e) = self.type_line("finish") {
                return Err(self.fail(e));
            }
            let o = self.outstanding.as_mut().expect("a motion under way");
            o.prompt_due = true;
            o.due = "finish".into();
            return Ok(true);
        }
        // ash says done: the arm must be read at the motion's end.
        let p = self.read_position(true)?;
        let now = Instant::now();
        let homing = self
            .outstanding
            .as_ref()
            .is_some_and(|o| matches!(o.motion.kind, Kind::Home));
        let homed = if homing {
            let lines = match self.exchange("armstat") {
                Ok(l) => l,
                Err(e) => return Err(self.fail(e)),
            };
            self.stat = reports::armstat(&lines).map_err(|e| self.unsure(e.to_string()))?;
            if !self.stat.power {
                // ash said done, and the arm has no power: the homing stopped where the
                // power left it, whatever armstat says of the axes (issue 62: a silent power
                // loss during Home was reported a success).
                self.outstanding = None;
                let n = self.queue.drop_all();
                self.note(format!(
                    "`home`: ash says done, and armstat says `Arm power is OFF`: the homing \
                     stopped where the power left the arm{}; switch the arm power on and call \
                     TROLHome again",
                    real::MotionQueue::<Motion>::dropped_note(n, "home")
                        .map(|n| format!("; {n}"))
                        .unwrap_or_default()
                ));
                return Err(BackendError::Refused(ARM_POWER));
            }
            self.stat.homing == Homing::Homed
        } else {
            true
        };
        // A home's pose (issue 62: a Home is done only with the arm seen there): each joint
        // within `home-within-deg` of `home-joints`; without them (a Home is refused before
        // it is sent then) never.
        let at_home = self.profile.home_joints.is_some_and(|h| {
            (0..6).all(|j| (p.joints_deg[j] - h[j]).abs() <= self.profile.home_within_deg)
        });
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
        if homing && homed && standing_before.is_some() && !o.watch.seen_moving() {
            // A home: ash said done, and armstat says homed: the controller's own word twice.
            o.watch.saw_moving();
            o.watch.saw_at(now, p.joints_deg);
        }
        let at_end = match (o.target, o.motion.kind) {
            (Some(t), _) => (0..6).all(|j| (p.joints_deg[j] - t[j]).abs() <= ARRIVE_DEG),
            (None, Kind::Named(at)) => (0..6).all(|j| (p.pulses[j] - at[j]).abs() <= ARRIVE_PULSES),
            (None, Kind::Pose(end, _)) => cartesian::at_pose(&p.joints_deg, &end),
            // A home: homed, read standing twice, and at the profile's home pose.
            (None, _) => {
                homed && at_home && standing_before.is_some() && o.watch.stood_for(now).is_some()
            }
        };
        match o.watch.verdict(now, at_end, times) {
            real::End::Arrived => {
                self.rests_at(p.joints_deg);
                self.note_pulses(&p);
                // ash ran it to its end, and the arm was seen there: powered and homed as the
                // gate found it, for the motion that follows at once.
                if self.stat.power && self.stat.homing == Homing::Homed {
                    self.stat_seen.saw(now, Some(self.stat.clone()));
                }
                self.outstanding = None;
                match self.queue.pop() {
                    Some(next) => self.send_next(next),
                    None => Ok(false),
                }
            }
            real::End::Running => Ok(true),
            real::End::StoppedShort(at) => {
                let line = o.motion.line.clone();
                self.rests_at(at);
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
                // Why it stopped, where ash can say: a power loss that printed nothing is a
                // power code, not "short of the target" (issue 62).
                let lines = match self.exchange("armstat") {
                    Ok(l) => l,
                    Err(e) => return Err(self.fail(e)),
                };
                self.stat = reports::armstat(&lines).map_err(|e| self.unsure(e.to_string()))?;
                if !self.stat.power {
                    self.note(format!(
                        "`{line}` stopped short: armstat says `Arm power is OFF` (switch it on, \
                         then TROLHome where the controller asks)"
                    ));
                    return Err(BackendError::Refused(ARM_POWER));
                }
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

    /// Send a motion that waited in the queue: `true` once it runs. A refusal ends Finish
    /// with it, and what waited behind it is dropped unsent.
    pub(super) fn send_next(&mut self, next: Motion) -> Result<bool, BackendError> {
        let line = next.line.clone();
        let r = match self.send_motion(next) {
            Ok(c) if c == code::OK => return Ok(true),
            Ok(c) => Err(BackendError::Refused(c)),
            Err(e) => Err(e),
        };
        let n = self.queue.drop_all();
        if let Some(note) = real::MotionQueue::<Motion>::dropped_note(n, &line) {
            self.say(&note);
        }
        r
    }

    /// ash runs a command of TROL's to its end (a motion with `motion-return = "end"`, or
    /// `finish`) and reads no other until its prompt.
    pub(super) fn console_busy(&self) -> bool {
        self.outstanding.as_ref().is_some_and(|o| o.prompt_due)
            || self.jaws_wait.as_ref().is_some_and(|w| w.prompt_due)
    }

    /// Read where the arm rests (`w2`), unless it was seen a moment ago ([`FRESH_REST`]).
    pub(super) fn fresh_rest(&mut self) -> Result<(), BackendError> {
        if self.rest_seen.get(Instant::now()).is_none() {
            let at = self.read_position(true)?.joints_deg;
            self.rests_at(at);
        }
        Ok(())
    }

    /// MoveII or ApproII to a precision point's (or joints') values: ash sets a precision
    /// point only with `here`.
    pub(super) fn no_ploc_values(&mut self) -> BiosResult {
        self.note(
            "refused before sending: a motion to a precision point's values: ash sets a \
             precision point only with `here` (its `set` takes cartesian constants only); teach \
             it and move to it by name, or give a cartesian location"
                .into(),
        );
        Ok(UNSUPPORTED)
    }

    /// A joint motion by `d` degrees: one `joint n,deg` where one joint changes; several
    /// never go as a series of them.
    pub(super) fn relative(&mut self, d: [f64; 6]) -> BiosResult {
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

//! Before and at a motion: the gate (power, homing, busy), the queue, relative motions
//! computed from where the last one ends, and typing the motion line.

use super::*;

impl RaplBackend {
    /// Whether a motion may be sent now, wait in the queue, or is refused: the shared gate
    /// ([`real::gate`]) on STATUS (read now, or seen a moment ago with nothing since).
    /// `homing`: the motion is a Home.
    pub(super) fn gate(&mut self, homing: bool) -> Result<real::Gate, BackendError> {
        self.release()?;
        // A controller that answers a motion at its end takes nothing before: the next motion
        // waits in the queue for that answer, as the controller itself would, and the call
        // returns at once (a request that waited for the motion's end would outlast the
        // host's reply timeout; Halt and Finish get through meanwhile).
        if self.awaiting.is_some() && self.await_end()? {
            return Ok(real::Gate::Queue);
        }
        self.report_unasked()?;
        if let Some(e) = self.deferred.take() {
            return Err(e);
        }
        // Idle as seen a moment ago, with nothing but reads since: no read needed (issue 43).
        let seen = (self.outstanding.is_none()
            && self.queue.is_empty()
            && self.awaiting.is_none()
            && !self.finishing)
            .then(|| self.seen.idle.get(std::time::Instant::now()).cloned())
            .flatten();
        let (moving, st) = match seen {
            Some(st) => (false, st),
            None => {
                let moving = self.poll()?;
                let st = self.status.clone().ok_or_else(|| {
                    BackendError::Link("STATUS could not be read before the motion".into())
                })?;
                (moving, st)
            }
        };
        let home = |m: &Motion| m.expect == Expect::Homed;
        let snapshot = real::Snapshot {
            powered: !st.limp.iter().any(|l| *l),
            homed: st.homed.iter().all(|h| *h),
            in_control: true,
            moving,
            // The fingers of a grip command of TROL's count as its own motion: what comes
            // next waits for them in the queue.
            ours: self.outstanding.is_some() || !self.queue.is_empty() || (moving && self.gripping),
            homing: self.outstanding.as_ref().is_some_and(|o| home(&o.motion))
                || self
                    .queue
                    .iter()
                    .any(|q| matches!(q, Queued::Motion(m) if home(m))),
        };
        let gate = real::gate(&snapshot, homing);
        if let real::Gate::Refuse(why) = gate {
            self.note(format!("{} (STATUS)", why.text()));
        }
        Ok(gate)
    }

    /// The code of a refusal by the gate.
    pub(super) fn refusal_code(why: real::Refusal) -> i16 {
        match why {
            real::Refusal::NoPower => ARM_POWER,
            real::Refusal::NotHomed => sim_code::NOT_HOMED,
            real::Refusal::NoControl | real::Refusal::Busy => BUSY,
        }
    }

    /// Send a motion now or queue it behind the one under way.
    pub(super) fn submit(&mut self, m: Motion, busy: bool) -> BiosResult {
        if busy {
            let line = m.line.clone();
            if self.queue.push(Queued::Motion(m)).is_err() {
                self.note(format!("`{line}` refused: {QUEUE} motions wait already"));
                return Ok(sim_code::QUEUE_FULL);
            }
            self.note(format!("`{line}` waits for the motion under way to end"));
            return Ok(0);
        }
        self.launch(m)
    }

    /// A motion line whose end is computed from where the arm stands (JOINT, MI, JOG): now,
    /// or when its turn comes ([`RaplBackend::relative`]); `end` gives its end from there.
    pub(super) fn relative_line(
        &mut self,
        line: String,
        busy: bool,
        end: impl FnOnce(&text::Position) -> Expect + Send + 'static,
    ) -> BiosResult {
        self.relative(
            line.clone(),
            busy,
            Box::new(move |b| {
                let p = match b.standing()? {
                    Ok(p) => p,
                    Err(c) => return Ok(c),
                };
                let expect = end(&p);
                b.submit(Motion { line, expect }, false)
            }),
        )
    }

    /// A joint motion relative to where the arm stands (JOINT, MI): as
    /// [`RaplBackend::relative_line`], from the end of the motion before where that was seen
    /// a moment ago (no W0 read), else from W0; `end` gives its end (joints, degrees).
    pub(super) fn relative_joints(
        &mut self,
        line: String,
        busy: bool,
        end: impl FnOnce([f64; 6]) -> [f64; 6] + Send + 'static,
    ) -> BiosResult {
        self.relative(
            line.clone(),
            busy,
            Box::new(move |b| {
                let q = match b.standing_joints()? {
                    Ok(q) => q,
                    Err(c) => return Ok(c),
                };
                let expect = Expect::Joints(end(q));
                b.submit(Motion { line, expect }, false)
            }),
        )
    }

    /// A relative motion: now, computed from where the arm stands, when it stands; queued
    /// and computed when its turn comes while another runs. `what` names it in the log.
    pub(super) fn relative(&mut self, what: String, busy: bool, now: Later) -> BiosResult {
        if !busy {
            return now(self);
        }
        if self.queue.push(Queued::Later(what.clone(), now)).is_err() {
            self.note(format!("`{what}` refused: {QUEUE} motions wait already"));
            return Ok(sim_code::QUEUE_FULL);
        }
        self.note(format!(
            "`{what}` waits for the motion under way to end; it is computed from where that \
             one ends"
        ));
        Ok(0)
    }

    /// Type a motion line; on the success form it is under way.
    pub(super) fn launch(&mut self, m: Motion) -> BiosResult {
        self.last_poll = None;
        match self.pace_for(&m.line)? {
            0 => {}
            c => return Ok(c),
        }
        if self.profile.motion_ack == MotionAck::End {
            return self.launch_answered_at_end(m);
        }
        match self.command(&m.line) {
            Ok(0) => {
                self.outstanding = Some(Outstanding::new(m, false, self.rest));
                Ok(0)
            }
            other => {
                self.drop_queue(&format!("`{}` failed", m.line));
                other
            }
        }
    }

    /// A motion on a controller that answers at the motion's end: typed whole (every echo
    /// checked), then a refusal has the reply window to come; without one the motion runs,
    /// and its answer is read by [`RaplBackend::poll`].
    pub(super) fn launch_answered_at_end(&mut self, m: Motion) -> BiosResult {
        self.forget();
        self.settle()?;
        let now = self.now();
        self.session
            .send_line(&m.line, self.motion_timeout(), now)
            .map_err(|e| BackendError::Link(e.to_string()))?;
        let window = std::time::Instant::now() + self.reply_timeout().min(Duration::from_secs(1));
        match self.pump_until(None, Some(window)) {
            Ok(Some(Ok(r))) => {
                // Answered within the window: a refusal, or a motion that already ended.
                match self.answer(&m.line, r, false)? {
                    Answer::Refused(n, _) => {
                        self.queue.drop_all();
                        Ok(self.code_of_refusal(n))
                    }
                    Answer::Done(_) => {
                        self.outstanding = Some(Outstanding::new(m, true, self.rest));
                        Ok(0)
                    }
                }
            }
            Ok(Some(Err(e))) => {
                self.note(format!("`{}`: {e}", m.line));
                self.queue.drop_all();
                Err(if e.surely_not_run() {
                    BackendError::Link(e.to_string())
                } else {
                    BackendError::Unsure(e.to_string())
                })
            }
            Ok(None) => {
                self.note(format!(
                    "`{}` taken, no refusal within the reply window: under way (its answer \
                     comes at its end)",
                    m.line
                ));
                self.awaiting = Some(m.line.clone());
                self.outstanding = Some(Outstanding::new(m, true, self.rest));
                Ok(0)
            }
            Err(e) => Err(BackendError::Unsure(format!("`{}`: {e}", m.line))),
        }
    }

    /// The answer of a motion that answers at its end: still running (true), ended in its
    /// success form (false), or its refusal or failure.
    pub(super) fn await_end(&mut self) -> Result<bool, BackendError> {
        let Some(line) = self.awaiting.clone() else {
            return Ok(false);
        };
        let until = std::time::Instant::now() + Duration::from_millis(self.profile.poll_ms);
        let ev = self
            .pump_until(None, Some(until))
            .map_err(|e| BackendError::Unsure(format!("`{line}`: {e}")))?;
        let Some(ev) = ev else {
            if self.past_motion_timeout() {
                self.awaiting = None;
                self.outstanding = None;
                self.queue.drop_all();
                let _ = self.interrupt();
                return Err(BackendError::Unsure(format!(
                    "`{line}` was not answered within motion_timeout_s ({} s): Ctrl-C sent; \
                     whether it ran to its end is not known",
                    self.profile.motion_timeout_s
                )));
            }
            return Ok(true);
        };
        self.awaiting = None;
        match ev {
            Ok(r) => match self.answer(&line, r, false) {
                Ok(Answer::Done(_)) => Ok(false),
                Ok(Answer::Refused(n, t)) => {
                    self.outstanding = None;
                    self.queue.drop_all();
                    self.note(format!("`{line}` ended in a refusal: {n:03}-{t}"));
                    Err(BackendError::Refused(match self.meaning(n) {
                        Meaning::Code(c) => c,
                        Meaning::Location => RAPL_ERROR,
                    }))
                }
                Err(e) => {
                    self.outstanding = None;
                    self.queue.drop_all();
                    Err(e)
                }
            },
            Err(e) => {
                self.outstanding = None;
                self.queue.drop_all();
                Err(BackendError::Unsure(format!("`{line}`: {e}")))
            }
        }
    }

    /// The speed setting for the motion about to be typed (the arm stands: nothing of
    /// TROL's is under way): a waypoint's own ([`RaplBackend::pacing`]), else the user's
    /// typed back after a waypoint's. A refused or failed SPEED drops the queue.
    fn pace_for(&mut self, line: &str) -> BiosResult {
        let want = match self.pacing.take() {
            Some(p) => Some(p),
            None if self.paced => self.speed_setting,
            None => return Ok(0),
        };
        let Some(p) = want else {
            self.paced = false;
            return Ok(0);
        };
        match self.command(&format!("SPEED {p}")) {
            Ok(0) => {
                self.paced = want != self.speed_setting;
                Ok(0)
            }
            other => {
                self.drop_queue(&format!("`SPEED {p}` before `{line}` failed"));
                other
            }
        }
    }

    /// TROLTrajectory on a C500 (issue 41). RAPL-II has no timed path: each waypoint is an
    /// MA, queued behind the one before and typed once that has ended, at the speed setting
    /// its time implies ([`real::pace`]: the move from the waypoint before, at the joints'
    /// top speeds scaled so, never above the user's setting; the first from where the arm
    /// stands when its turn comes). SPEED is typed only to a standing arm, so whether a C500
    /// applies it to a motion under way does not matter; the user's setting is typed back
    /// before the next motion that is not a waypoint. A waypoint too fast for the user's
    /// setting is BIOS_TOO_FAST, and a first waypoint at time 0 away from the arm
    /// BIOS_BAD_ARGUMENT, before anything of the trajectory is typed.
    pub(super) fn trajectory_paced(
        &mut self,
        points: &[trol_proto::application::Waypoint],
    ) -> BiosResult {
        trol_controller::untimed_count(self.kind(), points.len())?;
        if points.is_empty() {
            return Ok(code_of("BIOS_BAD_ARGUMENT"));
        }
        let mut lines = Vec::with_capacity(points.len());
        for p in points {
            match self.ma_line(p.joints) {
                Ok(l) => lines.push(l),
                Err(c) => return Ok(c),
            }
        }
        let top = trol_a465::model::max_speeds();
        let points = points.to_vec();
        self.motion_with(false, move |b, busy| {
            if !b.paced {
                if let Some(s) = b.status.as_ref().map(|s| s.speed.round()) {
                    if (1.0..=100.0).contains(&s) {
                        b.speed_setting = Some(s as u8);
                    }
                }
            }
            let Some(ceiling) = b.speed_setting else {
                b.note(
                    "STATUS shows no speed setting: the trajectory's waypoints go at the \
                     controller's speed setting, not at the speeds their times imply"
                        .into(),
                );
                return trol_controller::untimed_trajectory(b, &points);
            };
            let free = b.queue.cap() - b.queue.len();
            if free + usize::from(!busy) < points.len() {
                b.note(format!(
                    "a trajectory of {} waypoints refused: {} motion(s) wait already",
                    points.len(),
                    b.queue.len()
                ));
                return Ok(sim_code::QUEUE_FULL);
            }
            let mut paces = vec![None; points.len()];
            for k in 1..points.len() {
                let (a, z) = (&points[k - 1], &points[k]);
                match real::pace(&a.joints, &z.joints, z.time - a.time, &top, ceiling) {
                    real::Pace::Still => {}
                    real::Pace::Percent(p) => paces[k] = Some(p),
                    real::Pace::TooFast(needed) => {
                        b.note(too_fast(k + 1, needed, ceiling));
                        return Ok(code_of("BIOS_TOO_FAST"));
                    }
                }
            }
            let (t0, q0) = (points[0].time, points[0].joints);
            for (k, line) in lines.into_iter().enumerate() {
                let deg = points[k].joints.map(f64::to_degrees);
                let pace = paces[k];
                let what = format!("trajectory waypoint {}: `{line}`", k + 1);
                let r = b.relative(
                    what,
                    busy || k > 0,
                    Box::new(move |b| {
                        let pace = if k > 0 {
                            pace
                        } else {
                            let q = match b.standing_joints()? {
                                Ok(q) => q.map(f64::to_radians),
                                Err(c) => return Ok(c),
                            };
                            let off = (0..6).map(|j| (q[j] - q0[j]).abs()).fold(0.0, f64::max);
                            match real::pace(&q, &q0, t0, &top, ceiling) {
                                // At time 0 where the arm stands, as the simulated A465
                                // takes it (its readings travel as f32).
                                _ if t0 == 0.0
                                    && off <= trol_a465::arm::TRAJECTORY_START_TOLERANCE =>
                                {
                                    None
                                }
                                real::Pace::Still => None,
                                real::Pace::Percent(p) => Some(p),
                                real::Pace::TooFast(_) if t0 == 0.0 => {
                                    b.note(
                                        "the trajectory's waypoint at time 0 is not where the \
                                         arm stands: make it the arm's position (or leave it \
                                         out)"
                                            .into(),
                                    );
                                    return Ok(code_of("BIOS_BAD_ARGUMENT"));
                                }
                                real::Pace::TooFast(needed) => {
                                    b.note(too_fast(1, needed, ceiling));
                                    return Ok(code_of("BIOS_TOO_FAST"));
                                }
                            }
                        };
                        b.pacing = pace;
                        b.submit(
                            Motion {
                                line,
                                expect: Expect::Joints(deg),
                            },
                            false,
                        )
                    }),
                )?;
                if r != 0 {
                    if k > 0 {
                        b.halt()?;
                    }
                    return Ok(r);
                }
            }
            Ok(trol_proto::application::table::TRAJECTORY_UNTIMED)
        })
    }

    /// The gate, then `f` with whether the arm is busy.
    pub(super) fn motion_with(
        &mut self,
        homing: bool,
        f: impl FnOnce(&mut Self, bool) -> BiosResult,
    ) -> BiosResult {
        match self.gate(homing)? {
            real::Gate::Refuse(why) => Ok(Self::refusal_code(why)),
            real::Gate::Send => f(self, false),
            real::Gate::Queue => f(self, true),
        }
    }

    pub(super) fn joints(&mut self, cmd: &str, q: [f64; 6], relative: bool) -> BiosResult {
        let Some(units) = self.joint_units else {
            self.note(format!(
                "refused {cmd} before sending: its units are not known; set joint_units in the \
                 RAPL-II profile (docs/c500.md, Settle the conventions)"
            ));
            return Ok(NO_JOINT_UNITS);
        };
        if q.iter().any(|x| !x.is_finite()) {
            return Ok(code_of("BIOS_BAD_ARGUMENT"));
        }
        let line = format!("{cmd} {}", join(&Self::in_units(units, q)));
        let deg = q.map(f64::to_degrees);
        self.motion_with(false, |b, busy| {
            if !relative {
                let expect = Expect::Joints(deg);
                return b.submit(Motion { line, expect }, busy);
            }
            b.relative_joints(line, busy, move |q| std::array::from_fn(|i| q[i] + deg[i]))
        })
    }

    fn in_units(units: JointUnits, q: [f64; 6]) -> [f64; 6] {
        match units {
            JointUnits::Degrees => q.map(f64::to_degrees),
            JointUnits::Radians => q,
        }
    }

    /// An MA line to joints `q` (radians), or why it cannot be typed.
    fn ma_line(&mut self, q: [f64; 6]) -> Result<String, i16> {
        let Some(units) = self.joint_units else {
            self.note(
                "refused a trajectory before sending: its units are not known; set \
                 joint_units in the RAPL-II profile (docs/c500.md, Settle the conventions)"
                    .into(),
            );
            return Err(NO_JOINT_UNITS);
        };
        if q.iter().any(|x| !x.is_finite()) {
            return Err(code_of("BIOS_BAD_ARGUMENT"));
        }
        Ok(format!("MA {}", join(&Self::in_units(units, q))))
    }
}

/// The log's words for a waypoint too fast for the user's speed setting.
fn too_fast(waypoint: usize, needed: f64, ceiling: u8) -> String {
    format!(
        "the trajectory's waypoint {waypoint} would need {needed:.0}% speed where the speed \
         setting is {ceiling}%: give the trajectory more time (or raise the speed setting)"
    )
}

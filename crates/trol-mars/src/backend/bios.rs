//! The calls of the controller's contract ([`trol_controller::Backend`]) on a MARS 8.

use super::*;

impl Backend for MarsBackend {
    fn kind(&self) -> &'static str {
        "MARS 8"
    }
    fn codes(&self) -> &'static CodeTable {
        MARS_CODES
    }
    fn reply_time(&self) -> Duration {
        // The unit's silence is found out after REPLY_LIMIT; the rest of a call is line time.
        // A Halt that tries both stops takes as long.
        (REPLY_LIMIT + Duration::from_millis(500)).max(HALT_WITHIN + Duration::from_millis(400))
    }
    fn appro(&mut self, target: &Target, disp: [f64; 6], straight: bool) -> BiosResult {
        let t = self.target(target)?;
        self.motion(|a, now| a.appro(t, disp, straight, now))
    }
    fn close(&mut self, _force: u8) -> BiosResult {
        self.fingers(0.0, true)
    }
    fn depart(&mut self, disp: [f64; 6], straight: bool) -> BiosResult {
        self.motion(|a, now| a.depart(disp, straight, now))
    }
    fn moving(&mut self) -> Result<bool, BackendError> {
        if std::mem::take(&mut self.homing_halted) {
            return Err(BackendError::Refused(code::NOT_HOMED));
        }
        self.take_unasked()?;
        self.pump().map_err(|f| f.unsure())?;
        if self.homing.is_some() {
            return self.homing_step();
        }
        let s = self.status().map_err(|f| f.not_run())?;
        if let Some(c) = Self::fault(s) {
            if self.busy() || self.gripper.is_some() {
                self.abandon();
                return Err(BackendError::Refused(c));
            }
            return Ok(false);
        }
        let grip = self.gripper_step(s & st::MOVING != 0)?;
        let Some(m) = self.motion.as_mut() else {
            return Ok(grip);
        };
        if s & st::MOVING != 0 {
            m.watch.saw_moving();
            return Ok(true);
        }
        if !self.pending.is_empty() {
            return Ok(true);
        }
        let c = self.counters().map_err(|f| f.not_run())?;
        let tol = self.profile.arrive_irc;
        let times = real::EndTimes {
            settle: Duration::from_millis(self.profile.settle_ms),
            give_up: Duration::ZERO,
        };
        let m = self.motion.as_mut().expect("a motion under way");
        let now = Instant::now();
        m.watch.saw_at(now, c);
        let at_end = (0..6).all(|j| (c[j] - m.target[j]).abs() <= tol);
        // The shared end rule (real::EndWatch): at the end within arrive_irc once the
        // moving bit was seen up and down again, or (a motion too short to show it) not
        // before the planned end: counters within the tolerance before either are an arm
        // still slowing down, and a unit whose moving bit lags then showed it moving at the
        // next call, which was refused BIOS_BUSY. Short of the end, standing, after the
        // planned end and the settle time: a stop short.
        let target = m.target;
        match m.watch.verdict(
            now,
            at_end,
            real::EndTimes {
                give_up: m.give_up,
                ..times
            },
        ) {
            real::End::Arrived => {
                self.motion = None;
                let q = self.profile.irc_to_joints(&c);
                self.planner.place(q);
                // Standing at its end, the unit idle and without fault: what the next
                // motion's reads would show, for SEEN_FOR.
                self.seen.saw(
                    now,
                    (Self::fault(s).is_none() && self.gripper.is_none()).then_some(AtEnd {
                        status: s,
                        counters: c,
                    }),
                );
                Ok(grip)
            }
            real::End::Running => Ok(true),
            real::End::StoppedShort(_) => {
                let far: Vec<String> = (0..6)
                    .filter(|&j| (c[j] - target[j]).abs() > tol)
                    .map(|j| format!("joint {} at {} IRC for {}", j + 1, c[j], target[j]))
                    .collect();
                self.say(&format!("the unit stopped short: {}", far.join(", ")));
                self.abandon();
                Err(BackendError::Refused(NOT_AT_TARGET))
            }
            real::End::TimedOut => {
                let text = format!(
                    "the unit's moving bit is clear, but the arm is neither at the motion's end \
                     nor standing (COORDAP? {c:?} for {target:?}) past the planned end and {} \
                     s: whether the motion runs as asked is not known; nothing further was sent",
                    END_MARGIN.as_secs()
                );
                self.say(&text);
                self.abandon();
                Err(BackendError::Unsure(text))
            }
        }
    }
    fn grip(&mut self, dist: u8) -> BiosResult {
        self.fingers(f64::from(dist), true)
    }
    fn halt(&mut self) -> BiosResult {
        self.pending.clear();
        let homing = self.homing.take();
        let r = self.stop_and_see();
        if let Some(h) = homing {
            if r.is_ok() {
                // A Home halted on the way: its axes are not homed, and the Finish after it
                // fails, once.
                for a in h.axes {
                    self.homed[a] = false;
                }
                self.planner.set_homed(self.homed);
                self.homing_halted = true;
            } else {
                // Not seen to stop: as far as TROL knows the unit still homes, and Finish
                // goes on following it.
                self.homing = Some(h);
            }
        }
        r
    }
    fn stands(&mut self) -> Result<bool, BackendError> {
        // halt() answers success only once it has seen the arm standing.
        Ok(true)
    }
    fn home(&mut self, axis: u8) -> BiosResult {
        self.take_unasked()?;
        if axis > 6 {
            return Ok(code::BAD_ARGUMENT);
        }
        if self.busy() {
            return Ok(BUSY);
        }
        let s = self.status().map_err(|f| f.not_run())?;
        if s & st::POWER_OFF != 0 {
            return Ok(ARM_POWER);
        }
        if s & st::MOTION_STOP != 0 {
            return Ok(MOTION_STOP);
        }
        if s & st::MOVING != 0 {
            return Ok(BUSY);
        }
        // PURGE: clears the unit's errors (ctu-crs's initialize() sends it first).
        self.send(&line::command("PURGE:"))
            .map_err(|e| BackendError::Link(e.to_string()))?;
        self.set_up = false;
        self.set_up()?;
        let mut groups: VecDeque<String> = if axis == 0 {
            self.profile.hh_sequence.iter().cloned().collect()
        } else {
            VecDeque::from([self.profile.axis(axis as usize - 1).to_string()])
        };
        let axes: Vec<usize> = if axis == 0 {
            (0..6).collect()
        } else {
            vec![axis as usize - 1]
        };
        for &a in &axes {
            self.homed[a] = false;
        }
        self.planner.set_homed(self.homed);
        let first = groups.pop_front().expect("a group");
        self.send_hh(&first).map_err(|f| f.unsure())?;
        self.take_unasked()?;
        self.homing = Some(Homing {
            groups,
            group: first,
            since: self.now(),
            at_mark: None,
            axes,
            then_pose: axis == 0,
        });
        Ok(code::OK)
    }
    fn jog(&mut self, d: [f64; 3], straight: bool) -> BiosResult {
        self.motion(|a, now| a.jog(d, straight, now))
    }
    fn joint(&mut self, joint: u8, radians: f64) -> BiosResult {
        self.motion(|a, now| a.joint(joint, radians, now))
    }
    fn ma(&mut self, q: [f64; 6]) -> BiosResult {
        self.motion(|a, now| a.ma(q, now))
    }
    fn mi(&mut self, dq: [f64; 6]) -> BiosResult {
        self.motion(|a, now| a.mi(dq, now))
    }
    /// Timed: the A465 model's spline through the waypoints, sent as coordinated segments
    /// (COORDMVT) of the profile's segment time, as every planned path is.
    fn trajectory(&mut self, points: &[trol_proto::application::Waypoint]) -> BiosResult {
        let points: Vec<(f64, [f64; 6])> = points.iter().map(|p| (p.time, p.joints)).collect();
        self.motion(|a, now| a.trajectory(&points, now))
    }
    fn move_to(&mut self, target: &Target, straight: bool) -> BiosResult {
        let t = self.target(target)?;
        self.motion(|a, now| a.move_to(t, straight, now))
    }
    fn open(&mut self, _force: u8) -> BiosResult {
        self.fingers(arm::FINGER_MAX, false)
    }
    fn ready(&mut self) -> BiosResult {
        self.motion(|a, now| a.ready(now))
    }
    fn set_tool(&mut self, tool: [f64; 6]) -> BiosResult {
        self.tool = tool;
        Ok(self.planner.set_tool(tool))
    }
    fn speed(&mut self, percent: u8) -> BiosResult {
        Ok(self.planner.set_speed(f64::from(percent)))
    }
    fn define(&mut self, name: LocName, loc: &Location) -> BiosResult {
        let loc = match loc {
            Location::Prec(irc) => Location::Prec(self.irc_to_a465(irc).to_vec()),
            other => other.clone(),
        };
        trol_a465::backend::table::define(&mut self.planner, name, &loc)
    }
    fn delete_location(&mut self, name: LocName) -> BiosResult {
        trol_a465::backend::table::delete(&mut self.planner, name)
    }
    fn locations(&mut self) -> Result<Vec<(LocName, Location)>, BackendError> {
        Ok(trol_a465::backend::table::list(&self.planner)
            .into_iter()
            .map(|(n, l)| match l {
                Location::Prec(c) => (n, Location::Prec(self.a465_to_irc(&c))),
                other => (n, other),
            })
            .collect())
    }
    fn save_locations(&mut self) -> BiosResult {
        trol_a465::backend::table::save(&self.planner, self.locations_file.as_deref())
    }
    fn take_note(&mut self) -> Option<String> {
        self.planner.take_refusal()
    }
    fn position(&mut self, tag: Tag, mode: PosMode) -> Result<Location, BackendError> {
        let q = match mode {
            PosMode::Commanded => {
                let now = self.now();
                self.planner.commanded(now)
            }
            PosMode::Actual => self.actual().map_err(|f| f.not_run())?,
        };
        Ok(match tag {
            Tag::Joint => Location::from_array6(Tag::Joint, q),
            // The unit's own counts (the A465 controller's were answered before, which a
            // MARS 8 has none of).
            Tag::Prec => Location::Prec(
                self.profile
                    .joints_to_irc(&q)
                    .map(|v| v.round() as i32)
                    .to_vec(),
            ),
            Tag::Cart => Location::from_array6(Tag::Cart, self.planner.kinematics().fk_xyzypr(&q)),
        })
    }
    fn gripper(&mut self) -> Result<Gripper, BackendError> {
        let Some(g) = self.profile.gripper.clone() else {
            return Err(BackendError::Unsupported(
                "read a gripper: the arm profile names none ([gripper])",
            ));
        };
        // The unit reads the gripper axis' position, not what is between the fingers.
        Ok(Gripper {
            opening_mm: self.gripper_mm(&g)?,
            held: Held::Unknown,
        })
    }
    fn idle(&mut self) {
        if !self.pending.is_empty() {
            let _ = self.pump();
        }
    }
    fn report(&mut self) -> Option<ArmReport> {
        // Read-only: ST?, COORDAP? and the gripper's AP<g>?. A line the unit printed unasked
        // stays kept for the next call.
        let s = self.status().ok()?;
        let c = self.counters().ok()?;
        let gripper_mm = match self.profile.gripper.clone() {
            Some(g) => Some(self.gripper_mm(&g).ok()?),
            None => None,
        };
        Some(ArmReport {
            joints: self.profile.irc_to_joints(&c),
            moving: s & st::MOVING != 0 || self.busy(),
            target: self
                .motion
                .as_ref()
                .map(|m| self.profile.irc_to_joints(&m.target)),
            gripper_mm,
            tool: self.tool,
            // The counters of an axis not homed mean nothing yet: the view says so (issue
            // 38: it showed their values, and the last report while the arm homed again).
            homed: Some(self.homed),
            ..ArmReport::default()
        })
    }
}

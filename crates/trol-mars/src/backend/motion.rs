//! A motion: the gate, the plan from the A465 model at the unit's own speeds, its check
//! against the profile's range, and the segments sent.

use super::*;

impl MarsBackend {
    /// Gate, plan with the planner, check the plan against the profile, send it, confirm.
    pub(super) fn motion(&mut self, f: impl FnOnce(&mut Arm, f64) -> i16) -> BiosResult {
        self.take_unasked()?;
        let busy_before = self.motion.is_some() || !self.pending.is_empty();
        // The arm seen standing at the last motion's end, a moment ago, with nothing but
        // reads since: it stands in for ST? and COORDAP? (SEEN_FOR).
        let seen = self
            .seen
            .take(Instant::now())
            .filter(|_| !busy_before && self.gripper.is_none());
        let s = match seen {
            Some(x) => x.status,
            None => self.status().map_err(|f| f.not_run())?,
        };
        let powered = s & st::POWER_OFF == 0;
        if powered {
            // The unit's own faults, which the shared gate has no word for: the motion stop,
            // the error bit.
            if let Some(c) = Self::fault(s) {
                return Ok(c);
            }
        }
        let snapshot = real::Snapshot {
            powered,
            homed: self.homed.iter().all(|h| *h),
            in_control: true,
            moving: s & st::MOVING != 0,
            ours: busy_before,
            homing: self.homing.is_some(),
        };
        match real::gate(&snapshot, false) {
            real::Gate::Refuse(why) => {
                self.say(why.text());
                return Ok(match why {
                    real::Refusal::NoPower => ARM_POWER,
                    real::Refusal::NotHomed => code::NOT_HOMED,
                    real::Refusal::NoControl | real::Refusal::Busy => BUSY,
                });
            }
            // A MARS 8's hard homing runs group by group under TROL: nothing waits behind
            // it (where the simulated A465 and a C500 queue a motion behind a Home).
            real::Gate::Queue if self.homing.is_some() => return Ok(BUSY),
            real::Gate::Queue | real::Gate::Send => {}
        }
        self.planner.set_homed(self.homed);
        let now = self.now();
        if !busy_before {
            let q = match seen {
                Some(x) => self.profile.irc_to_joints(&x.counters),
                None => self.actual().map_err(|f| f.not_run())?,
            };
            self.planner.place(q);
        }
        let before = self.planner.clone();
        let c = f(&mut self.planner, now);
        if c != code::OK {
            self.planner = before;
            return Ok(c);
        }
        let Some((t0, t1, joint)) = self.planner.last_motion() else {
            return Ok(code::OK);
        };
        if before.last_motion() == Some((t0, t1, joint)) {
            // Nothing new was planned (a motion of no length).
            return Ok(code::OK);
        }
        let seg = self.profile.segment_ms as f64 / 1000.0;
        let n = if joint {
            1
        } else {
            ((t1 - t0) / seg).ceil().max(1.0) as usize
        };
        // The discontinuity once per run of segments: the unit keeps it (CTU's client sends
        // it before every segment; 14 bytes, 7 ms at 19200 Bd, before the arm can start).
        let mut lines = if self.discont_set {
            Vec::new()
        } else {
            vec![format!("COORDISCONT:{DISCONT}")]
        };
        let mut prev = t0;
        let mut last = [0.0; 6];
        for k in 1..=n {
            let t = t0 + (t1 - t0) * k as f64 / n as f64;
            let q = self.planner.planned_at(t);
            let irc = self.profile.joints_to_irc(&q).map(f64::round);
            if let Some(j) = self.profile.outside(&irc) {
                self.planner = before;
                self.say(&format!(
                    "refused: joint {} would leave the profile's range ({} IRC)",
                    j + 1,
                    irc[j]
                ));
                return Ok(code::JOINT_LIMIT);
            }
            let ms = ((t - prev) * 1000.0).round().max(1.0) as i64;
            lines.push(format!(
                "COORDMVT:{ms},{}",
                irc.map(|v| (v as i64).to_string()).join(",")
            ));
            prev = t;
            last = irc;
        }
        if let Err(e) = self.set_up() {
            self.planner = before;
            return Err(e);
        }
        self.pending.extend(lines);
        let sent = Instant::now();
        let planned = self.epoch + Duration::from_secs_f64(t1.max(0.0));
        let from = if busy_before {
            None
        } else {
            Some(self.profile.joints_to_irc(&self.planner.planned_at(t0)))
        };
        self.motion = Some(Outstanding {
            target: last,
            watch: real::EndWatch::new(sent, from, self.still_irc()).planned_to_end(planned),
            give_up: planned.saturating_duration_since(sent)
                + Duration::from_millis(self.profile.settle_ms)
                + END_MARGIN,
        });
        // The status word read above, before this motion, showed the unit's queue with room
        // and nothing of ours in it: no second look before the first lines (issue 43).
        let room = s & st::QUEUE_FULL == 0 && !busy_before;
        let confirmed = self
            .pump_from(room)
            .map_err(|f| f.unsure())
            .and_then(|()| self.take_unasked())
            .and_then(|()| self.status().map_err(|f| f.unsure()));
        match confirmed {
            Ok(s) => match Self::fault(s) {
                Some(c) => {
                    self.abandon();
                    Ok(c)
                }
                None => Ok(code::OK),
            },
            Err(e) => {
                // Whether the unit took it is not known: TROL keeps nothing of it, sends
                // nothing more of it, and the next motion starts from where the arm is
                // (refused as BUSY while the unit says it moves).
                self.pending.clear();
                self.motion = None;
                Err(e)
            }
        }
    }

    pub(super) fn target(&self, t: &Target) -> Result<arm::Target, BackendError> {
        // A precision point given here is the unit's IRC counts (what GetPosition(POS_PREC)
        // answers); the arm model plans in the A465 controller's.
        if let Target::Location(Location::Prec(irc)) = t {
            let loc = Location::Prec(self.irc_to_a465(irc).to_vec());
            return trol_a465::backend::arm_target(&self.planner, &Target::Location(loc));
        }
        trol_a465::backend::arm_target(&self.planner, t)
    }

    /// The unit's IRC counts (missing ones 0) as the A465 controller's encoder counts, which
    /// the arm model and TROL's location table keep.
    pub(super) fn irc_to_a465(&self, irc: &[i32]) -> [i32; 6] {
        let c: [f64; 6] = std::array::from_fn(|i| f64::from(irc.get(i).copied().unwrap_or(0)));
        joints_to_counts(&self.profile.irc_to_joints(&c))
    }

    /// The A465 controller's counts as the unit's IRC counts.
    pub(super) fn a465_to_irc(&self, counts: &[i32]) -> Vec<i32> {
        let c: [f64; 6] = std::array::from_fn(|i| f64::from(counts.get(i).copied().unwrap_or(0)));
        let q = trol_a465::model::counts_to_joints(&c);
        self.profile
            .joints_to_irc(&q)
            .map(|v| v.round() as i32)
            .to_vec()
    }
}

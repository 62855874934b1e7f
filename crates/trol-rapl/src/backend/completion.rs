//! The end of a motion (Finish): STATUS's DONE row or FINISH, the arm at the motion's end
//! (W2), stopped short, timed out; the queue's next motion.

use super::*;

impl RaplBackend {
    /// One look at the arm: STATUS, and W2 when the controller says done while a motion of
    /// ours is under way; starts the next queued motion once the last has ended. Whether
    /// anything still moves.
    pub(super) fn poll(&mut self) -> Result<bool, BackendError> {
        let r = if self.finishing {
            self.await_finish()
        } else {
            self.poll_status()
        };
        if r.is_err() {
            self.forget();
        }
        r
    }

    /// One look at the arm by STATUS (and W2), as [`RaplBackend::poll`] describes.
    pub(super) fn poll_status(&mut self) -> Result<bool, BackendError> {
        if self.await_end()? {
            return Ok(true);
        }
        self.report_unasked()?;
        let st = match self.profile.completion {
            Completion::W5 if self.outstanding.is_none() && self.queue.is_empty() => {
                // W5 alone: velocities.
                let r = self.output("W5")?;
                let v = text::row(&r.text, "JOINTS").map_err(BackendError::Link)?;
                let st = self.read_status()?;
                if v.iter().any(|x| x.abs() > 1e-6) {
                    return Ok(true);
                }
                st
            }
            _ => match self.read_status() {
                Ok(st) => st,
                // A read that met a surprise (an unasked line) and resynchronised: what the
                // controller said is told first, then one more look.
                Err(BackendError::Link(e)) => {
                    self.note(format!("STATUS read again after: {e}"));
                    self.report_unasked()?;
                    self.read_status()?
                }
                Err(e) => return Err(e),
            },
        };
        if st.limp.iter().any(|l| *l) {
            let ours = self.outstanding.take();
            let dropped = std::mem::take(&mut self.queue);
            if ours.is_some() || !dropped.is_empty() {
                self.note(format!(
                    "the arm lost power (STATUS's LIMP row says Y){}{}",
                    ours.map(|o| format!(" during `{}`", o.motion.line))
                        .unwrap_or_default(),
                    if dropped.is_empty() {
                        String::new()
                    } else {
                        format!("; {} queued motion(s) dropped, not sent", dropped.len())
                    }
                ));
                return Err(BackendError::Refused(ARM_POWER));
            }
            return Ok(false);
        }
        let done = st.done.iter().all(|d| *d);
        let Some(o) = self.outstanding.as_mut() else {
            if done {
                return self.next_in_queue();
            }
            return Ok(true);
        };
        if o.motion.expect != Expect::Homed && !st.homed.iter().all(|h| *h) {
            let line = o.motion.line.clone();
            self.outstanding = None;
            self.queue.clear();
            self.note(format!(
                "the arm lost its homing during `{line}` (STATUS's HOMED row says N); queue dropped"
            ));
            return Err(BackendError::Refused(sim_code::NOT_HOMED));
        }
        if !done {
            o.seen_moving = true;
            return Ok(true);
        }
        if self.arrived()? {
            self.outstanding = None;
            return self.next_in_queue();
        }
        let o = self.outstanding.as_ref().expect("a motion under way");
        // The motion ran (STATUS said not done, W2 moved, or W2 left where the arm last
        // rested), the controller says done, and the arm has stood still short of the end
        // for `settle_ms`: it stopped short (a servo fault, a stop at the controller) without
        // a word. Known within the motion's own time and settle_ms, not after
        // motion_timeout_s (issue 37, item 7). A motion that never left its start and
        // never showed as running still waits for motion_timeout_s: the DONE row may lag.
        let settle = Duration::from_millis(self.profile.settle_ms);
        let left_rest = match (o.from, o.standing) {
            (Some(a), Some((_, b))) => a.iter().zip(&b).any(|(x, y)| (x - y).abs() > STILL_DEG),
            _ => false,
        };
        if (o.seen_moving || o.w2_moved || left_rest)
            && o.standing.is_some_and(|(t, _)| t.elapsed() >= settle)
        {
            let line = o.motion.line.clone();
            let expect = o.motion.expect.clone();
            let at = o.standing.map(|(_, q)| q).unwrap_or_default();
            self.outstanding = None;
            self.queue.clear();
            self.note(format!(
                "`{line}`: the C500 says done, and the arm (W2 joints {}) has stood still for \
                 {} ms short of the motion's end ({expect:?}): it stopped short; the queue was \
                 dropped",
                join(&at),
                settle.as_millis()
            ));
            return Err(BackendError::Refused(NOT_AT_TARGET));
        }
        if o.since.elapsed() > self.motion_timeout() {
            let line = o.motion.line.clone();
            let expect = o.motion.expect.clone();
            self.outstanding = None;
            self.queue.clear();
            let e = format!(
                "`{line}`: the C500 says done, but after {} s the arm (W2) is not at the \
                 motion's end ({expect:?}); whether it ran as asked is not known, and the queue \
                 was dropped",
                self.profile.motion_timeout_s
            );
            self.note(e.clone());
            return Err(BackendError::Unsure(e));
        }
        Ok(true)
    }

    /// Give up the motion under way and the queue (nothing more of them is sent); its line.
    pub(super) fn give_up(&mut self) -> String {
        self.queue.clear();
        self.outstanding
            .take()
            .map(|o| o.motion.line)
            .unwrap_or_default()
    }

    /// Whether the motion under way was sent longer ago than `motion_timeout_s`.
    pub(super) fn past_motion_timeout(&self) -> bool {
        self.outstanding
            .as_ref()
            .is_some_and(|o| o.since.elapsed() > self.motion_timeout())
    }

    /// Whether FINISH should go out now: `completion = "finish"`, a motion of ours under way
    /// whose end FINISH has not yet answered for, and the line free.
    pub(super) fn finish_due(&self) -> bool {
        self.profile.completion == Completion::Finish
            && !self.finish_off
            && !self.finishing
            && self.awaiting.is_none()
            && self.outstanding.as_ref().is_some_and(|o| !o.finish_tried)
    }

    /// Type FINISH; its answer is read by [`RaplBackend::await_finish`].
    pub(super) fn type_finish(&mut self) -> Result<(), BackendError> {
        self.forget();
        self.report_unasked()?;
        let now = self.now();
        if let Err(e) = self.session.send_line("FINISH", self.motion_timeout(), now) {
            self.note(format!("`FINISH` not sent: {e}"));
            return Err(BackendError::Link(e.to_string()));
        }
        self.finishing = true;
        Ok(())
    }

    /// Listen for FINISH's answer (at most [`FINISH_LISTEN`]): still moving (true), or the
    /// motion's end, confirmed by W2 unless the profile says FINISH's ACK means arrival.
    /// Where it settles nothing, the end is looked for by STATUS.
    pub(super) fn await_finish(&mut self) -> Result<bool, BackendError> {
        let until = std::time::Instant::now() + FINISH_LISTEN;
        let ev = match self.pump_until(None, Some(until)) {
            Ok(ev) => ev,
            Err(e) => {
                self.finishing = false;
                return Err(BackendError::Unsure(format!("`FINISH`: {e}")));
            }
        };
        let Some(ev) = ev else {
            if self.past_motion_timeout() {
                let line = self.give_up();
                let _ = self.release();
                return Err(BackendError::Unsure(format!(
                    "`{line}`: FINISH was not answered within motion_timeout_s ({} s): Ctrl-C \
                     sent; whether the motion ran to its end is not known",
                    self.profile.motion_timeout_s
                )));
            }
            return Ok(true);
        };
        self.finishing = false;
        let line = self
            .outstanding
            .as_ref()
            .map(|o| o.motion.line.clone())
            .unwrap_or_default();
        let answer = match ev {
            Ok(r) => self.answer("FINISH", r, false),
            Err(e) => Err(if e.surely_not_run() {
                BackendError::Link(format!("`FINISH`: {e}"))
            } else {
                BackendError::Unsure(format!("`FINISH` after `{line}`: {e}"))
            }),
        };
        match answer {
            Ok(Answer::Done(_)) => {
                if self.profile.finish_ack_means_arrived {
                    if let Some(expect) = self.outstanding.as_ref().map(|o| o.motion.expect.clone())
                    {
                        self.seen_at_end(&expect);
                    }
                }
                if self.profile.finish_ack_means_arrived || self.arrived()? {
                    self.outstanding = None;
                    return self.next_in_queue();
                }
                self.note(format!(
                    "FINISH answered after `{line}`, but W2 does not put the arm at the motion's \
                     end: its end is looked for by STATUS"
                ));
            }
            Ok(Answer::Refused(n, t)) if self.profile.finish_ack_means_arrived => {
                // This controller answers FINISH with an error only when the motion stopped
                // short (the profile says so).
                self.outstanding = None;
                let dropped = std::mem::take(&mut self.queue).len();
                self.note(format!(
                    "`{line}` ended short: FINISH answered {n:03}-{t}{}",
                    if dropped > 0 {
                        format!("; {dropped} queued motion(s) dropped, not sent")
                    } else {
                        String::new()
                    }
                ));
                return Err(BackendError::Refused(self.code_of_refusal(n)));
            }
            Ok(Answer::Refused(n, t)) => {
                if self.code_of_refusal(n) == code_of("BIOS_BAD_ARGUMENT") {
                    self.finish_off = true;
                    self.note(format!(
                        "FINISH refused ({n:03}-{t}): this controller does not take it in \
                         immediate mode; the end of each motion is looked for by STATUS"
                    ));
                } else {
                    self.note(format!(
                        "FINISH after `{line}` answered {n:03}-{t}: its end is looked for by \
                         STATUS"
                    ));
                }
            }
            Err(e) => {
                self.outstanding = None;
                self.queue.clear();
                return Err(e);
            }
        }
        if let Some(o) = self.outstanding.as_mut() {
            o.finish_tried = true;
        }
        self.poll_status()
    }

    /// End a FINISH that waits (Ctrl-C, before anything else is typed): the motion runs on.
    /// A controller that does not answer at once leaves the arm's state unknown: UNSURE,
    /// the motion and the queue given up.
    pub(super) fn release(&mut self) -> Result<(), BackendError> {
        if !self.finishing {
            return Ok(());
        }
        self.finishing = false;
        let t = std::time::Instant::now();
        let r = self.ctrl_c();
        let took = t.elapsed();
        // An ACK before the prompt is FINISH's own answer: the motion ended by itself, and
        // the Ctrl-C may never have been taken.
        let answered = matches!(&r, Ok(text) if text.contains(char::from(ACK)));
        if r.is_ok() && !answered && took <= CTRL_C_ENDS_FINISH_WITHIN {
            return Ok(());
        }
        let line = self.give_up();
        let e = format!(
            "Ctrl-C did not end the FINISH that waited for `{line}` within {} ms ({}): this \
             controller may not take Ctrl-C while FINISH waits (the profile says \
             ctrl_c_ends_finish = true); the arm may still be moving, and nothing further was \
             sent",
            CTRL_C_ENDS_FINISH_WITHIN.as_millis(),
            match r {
                Ok(_) if answered => "FINISH answered by itself".to_string(),
                Ok(_) => format!("its prompt came after {} ms", took.as_millis()),
                Err(e) => e.to_string(),
            }
        );
        self.note(e.clone());
        Err(BackendError::Unsure(e))
    }

    pub(super) fn next_in_queue(&mut self) -> Result<bool, BackendError> {
        let Some(q) = self.queue.pop_front() else {
            return Ok(false);
        };
        let line = q.line().to_string();
        let r = match q {
            Queued::Motion(m) => self.launch(m),
            Queued::Later(_, f) => {
                // Computed now, from where the arm stands (the motion before it ended): the
                // rest of the queue waits aside, so that the arm counts as standing.
                let rest = std::mem::take(&mut self.queue);
                let r = f(self);
                if matches!(r, Ok(0)) {
                    self.queue = rest;
                } else if !rest.is_empty() {
                    self.note(format!(
                        "{} queued motion(s) dropped after `{line}` failed: not sent",
                        rest.len()
                    ));
                }
                r
            }
        };
        match r? {
            0 => Ok(true),
            c => {
                self.note(format!("queued `{line}` was refused when its turn came"));
                Err(BackendError::Refused(c))
            }
        }
    }

    /// Whether the arm is where the motion under way ends (the controller said done).
    pub(super) fn arrived(&mut self) -> Result<bool, BackendError> {
        let expect = match &self.outstanding {
            Some(o) => o.motion.expect.clone(),
            None => return Ok(true),
        };
        let p = self.read_position(PosMode::Actual)?;
        if let Some(o) = self.outstanding.as_mut() {
            match o.standing {
                Some((_, q))
                    if q.iter()
                        .zip(&p.joints)
                        .all(|(a, b)| (a - b).abs() <= STILL_DEG) => {}
                Some(_) => {
                    o.w2_moved = true;
                    o.standing = Some((std::time::Instant::now(), p.joints));
                }
                None => o.standing = Some((std::time::Instant::now(), p.joints)),
            }
        }
        let tol = self.profile.arrive_deg;
        let arrived = match expect {
            Expect::Joints(q) => p.joints.iter().zip(&q).all(|(a, b)| (a - b).abs() <= tol),
            Expect::Pulses(c) => {
                let scale = self
                    .frames
                    .pulses
                    .map(|s| s.map(|(k, _)| k.abs()))
                    .unwrap_or([1.0; 6]);
                p.pulses
                    .iter()
                    .zip(&c)
                    .zip(&scale)
                    .all(|((a, b), k)| ((a - b) as f64).abs() <= tol * k)
            }
            Expect::World(w) => self.world_near(&p.world, &w),
            Expect::Unknown | Expect::Homed => {
                let homed = self
                    .status
                    .as_ref()
                    .is_some_and(|s| s.homed.iter().all(|h| *h));
                let o = self.outstanding.as_mut().expect("a motion under way");
                if expect == Expect::Homed && !homed {
                    false
                } else if o.seen_moving {
                    true
                } else {
                    let settle = Duration::from_millis(self.profile.settle_ms);
                    match o.still {
                        Some((t, q))
                            if q.iter().zip(&p.joints).all(|(a, b)| (a - b).abs() <= tol) =>
                        {
                            t.elapsed() >= settle
                        }
                        _ => {
                            o.still = Some((std::time::Instant::now(), p.joints));
                            false
                        }
                    }
                }
            }
        };
        if arrived {
            self.rest = Some(p.joints);
            self.seen_at_end(&expect);
        }
        Ok(arrived)
    }

    /// A motion seen to end where it was sent (W2 there, or FINISH's ACK where the profile
    /// has it mean arrival): the arm stands at its end, idle, and powered and homed as the
    /// last STATUS said (the motion ran), as of now ([`SEEN_FOR`]).
    pub(super) fn seen_at_end(&mut self, expect: &Expect) {
        let now = std::time::Instant::now();
        self.seen.end = match expect {
            Expect::Joints(q) => Some((now, *q)),
            _ => None,
        };
        self.seen.idle = self
            .status
            .clone()
            .filter(|s| s.homed.iter().all(|h| *h) && !s.limp.iter().any(|l| *l))
            .map(|s| (now, s));
    }

    /// Whether two WORLD rows are the same pose within the profile's tolerance (the angles
    /// compared as rotations when the profile knows them).
    pub(super) fn world_near(&self, a: &[f64; 6], b: &[f64; 6]) -> bool {
        let mm = self.frames.mm.unwrap_or(1.0);
        let d = (0..3)
            .map(|i| (a[i] - b[i]) * mm)
            .map(|x| x * x)
            .sum::<f64>();
        if d.sqrt() > self.profile.arrive_mm {
            return false;
        }
        match (self.frames.from_rapl(*a), self.frames.from_rapl(*b)) {
            (Ok(x), Ok(y)) => {
                crate::probe::rotation_distance_deg(&Pose::from_xyzypr(x), &Pose::from_xyzypr(y))
                    <= self.profile.arrive_deg
            }
            _ => true,
        }
    }
}

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
            let dropped = self.queue.drop_all();
            if ours.is_some() || dropped > 0 {
                self.note(format!(
                    "the arm lost power (STATUS's LIMP row says Y){}{}",
                    ours.map(|o| format!(" during `{}`", o.motion.line))
                        .unwrap_or_default(),
                    if dropped == 0 {
                        String::new()
                    } else {
                        format!("; {dropped} queued motion(s) dropped, not sent")
                    }
                ));
                return Err(BackendError::Refused(ARM_POWER));
            }
            return Ok(false);
        }
        let done = st.done.iter().all(|d| *d);
        if done && self.outstanding.is_none() {
            self.gripping = false;
        }
        let Some(o) = self.outstanding.as_mut() else {
            if done {
                return self.next_in_queue();
            }
            return Ok(true);
        };
        if o.motion.expect != Expect::Homed && !st.homed.iter().all(|h| *h) {
            let line = o.motion.line.clone();
            self.outstanding = None;
            self.queue.drop_all();
            self.note(format!(
                "the arm lost its homing during `{line}` (STATUS's HOMED row says N); queue dropped"
            ));
            return Err(BackendError::Refused(sim_code::NOT_HOMED));
        }
        if !done {
            o.watch.saw_moving();
            return Ok(true);
        }
        // The shared end rule (real::EndWatch): W2 at the motion's end is arrival; W2
        // standing short of it for settle_ms after the motion ran (STATUS said not done, W2
        // moved, or W2 left where the arm last rested) is a stop short, known within the
        // motion's own time and settle_ms (issue 37, item 7); a motion never seen running
        // waits for motion_timeout_s (the DONE row may lag), then is unsure.
        match self.look_at_end()? {
            real::End::Arrived => {
                self.outstanding = None;
                self.next_in_queue()
            }
            real::End::Running => Ok(true),
            real::End::StoppedShort(at) => {
                let (line, expect) = self.end_of_outstanding();
                self.queue.drop_all();
                self.note(format!(
                    "`{line}`: the C500 says done, and the arm (W2 joints {}) has stood still for \
                     {} ms short of the motion's end ({expect:?}): it stopped short; the queue \
                     was dropped",
                    join(&at),
                    self.profile.settle_ms
                ));
                Err(BackendError::Refused(NOT_AT_TARGET))
            }
            real::End::TimedOut => {
                let (line, expect) = self.end_of_outstanding();
                self.queue.drop_all();
                let e = format!(
                    "`{line}`: the C500 says done, but after {} s the arm (W2) is not at the \
                     motion's end ({expect:?}); whether it ran as asked is not known, and the \
                     queue was dropped",
                    self.profile.motion_timeout_s
                );
                self.note(e.clone());
                Err(BackendError::Unsure(e))
            }
        }
    }

    /// Give up the motion under way: its line and end, for the message.
    fn end_of_outstanding(&mut self) -> (String, Expect) {
        self.outstanding
            .take()
            .map(|o| (o.motion.line, o.motion.expect))
            .unwrap_or((String::new(), Expect::Unknown))
    }

    /// Drop what waits in the queue, unsent, and say so (`after`: what failed).
    pub(super) fn drop_queue(&mut self, after: &str) {
        let n = self.queue.drop_all();
        if let Some(note) = real::MotionQueue::<Queued>::dropped_note(n, after) {
            self.note(note);
        }
    }

    /// The times of the shared end rule: the profile's settle time, and motion_timeout_s.
    fn end_times(&self) -> real::EndTimes {
        real::EndTimes {
            settle: Duration::from_millis(self.profile.settle_ms),
            give_up: self.motion_timeout(),
        }
    }

    /// Give up the motion under way and the queue (nothing more of them is sent); its line.
    pub(super) fn give_up(&mut self) -> String {
        self.queue.drop_all();
        self.outstanding
            .take()
            .map(|o| o.motion.line)
            .unwrap_or_default()
    }

    /// Whether the motion under way was sent longer ago than `motion_timeout_s`.
    pub(super) fn past_motion_timeout(&self) -> bool {
        self.outstanding.as_ref().is_some_and(|o| {
            o.watch
                .older_than(std::time::Instant::now(), self.motion_timeout())
        })
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
                if self.profile.finish_ack_means_arrived
                    || self.look_at_end()? == real::End::Arrived
                {
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
                let dropped = self.queue.drop_all();
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
                self.queue.drop_all();
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
        let Some(q) = self.queue.pop() else {
            return Ok(false);
        };
        let line = q.line().to_string();
        let r = match q {
            Queued::Motion(m) => self.launch(m),
            Queued::Later(_, f) => {
                // Computed now, from where the arm stands (the motion before it ended): the
                // rest of the queue waits aside, so that the arm counts as standing.
                let rest = self.queue.set_aside();
                let r = f(self);
                self.queue.restore(rest);
                if !matches!(r, Ok(0)) {
                    self.drop_queue(&format!("`{line}` failed"));
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

    /// One look at the end of the motion under way, the controller having said done: W2
    /// read, fed to the shared end rule with whether it puts the arm at the motion's end
    /// (within `arrive_deg`, `arrive_mm`). On arrival the arm is at rest there.
    pub(super) fn look_at_end(&mut self) -> Result<real::End, BackendError> {
        let expect = match &self.outstanding {
            Some(o) => o.motion.expect.clone(),
            None => return Ok(real::End::Arrived),
        };
        let p = self.read_position(PosMode::Actual)?;
        let now = std::time::Instant::now();
        let times = self.end_times();
        let tol = self.profile.arrive_deg;
        let o = self.outstanding.as_mut().expect("a motion under way");
        o.watch.saw_at(now, p.joints);
        let at_end = match &expect {
            Expect::Joints(q) => p.joints.iter().zip(q).all(|(a, b)| (a - b).abs() <= tol),
            Expect::Pulses(c) => {
                let scale = self
                    .frames
                    .pulses
                    .map(|s| s.map(|(k, _)| k.abs()))
                    .unwrap_or([1.0; 6]);
                p.pulses
                    .iter()
                    .zip(c)
                    .zip(&scale)
                    .all(|((a, b), k)| ((a - b) as f64).abs() <= tol * k)
            }
            Expect::World(w) => self.world_near(&p.world, w),
            Expect::Unknown | Expect::Homed => {
                let homed = self
                    .status
                    .as_ref()
                    .is_some_and(|s| s.homed.iter().all(|h| *h));
                // A HOME ends at the profile's home pose, never without one (issue 62; a HOME
                // is refused before it is typed then).
                let at_home = expect != Expect::Homed
                    || self.profile.home_joints.is_some_and(|h| {
                        p.joints.iter().zip(&h).all(|(a, b)| (a - b).abs() <= tol)
                    });
                // No end to compare with: it ran (the controller said it moves), or it has
                // stood for settle_ms where it is.
                let o = self.outstanding.as_ref().expect("a motion under way");
                (expect != Expect::Homed || homed)
                    && at_home
                    && (o.watch.seen_moving()
                        || o.watch.stood_for(now).is_some_and(|d| d >= times.settle))
            }
        };
        let o = self.outstanding.as_ref().expect("a motion under way");
        let end = o.watch.verdict(now, at_end, times);
        if end == real::End::Arrived {
            self.rest = Some(p.joints);
            self.seen_at_end(&expect);
        }
        Ok(end)
    }

    /// A motion seen to end where it was sent (W2 there, or FINISH's ACK where the profile
    /// has it mean arrival): the arm stands at its end, idle, and powered and homed as the
    /// last STATUS said (the motion ran), as of now ([`SEEN_FOR`]).
    pub(super) fn seen_at_end(&mut self, expect: &Expect) {
        let now = std::time::Instant::now();
        self.seen.end.saw(
            now,
            match expect {
                Expect::Joints(q) => Some(*q),
                _ => None,
            },
        );
        self.seen.idle.saw(
            now,
            self.status
                .clone()
                .filter(|s| s.homed.iter().all(|h| *h) && !s.limp.iter().any(|l| *l)),
        );
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

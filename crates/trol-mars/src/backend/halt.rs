//! Halt on a MARS 8: `STOP:`, then `PURGE:`, each confirmed by the arm through the shared
//! rule ([`trol_controller::real::halt`]).

use super::*;

/// The MARS 8's side of the shared Halt ([`trol_controller::real`]): `STOP:` and `PURGE:`,
/// each confirmed by `STAMP`; the status word's moving bit and `COORDAP?` (IRC) as the
/// reading.
pub(super) struct Stopper<'a>(&'a mut MarsBackend);

impl real::Stopping for Stopper<'_> {
    type Stop = &'static str;
    fn stop_name(&self, stop: &'static str) -> String {
        stop.into()
    }
    fn send_stop(&mut self, stop: &'static str) -> Result<String, String> {
        let b = &mut *self.0;
        b.send(&line::command(stop))
            .map_err(|e| format!("not sent: {e}"))?;
        if stop == "PURGE:" {
            // The motors were reset: the regulator set-up goes again, and the arm is homed
            // again before it moves.
            b.set_up = false;
            b.homed = [false; 6];
            b.planner.set_homed(b.homed);
            b.say("Halt: PURGE: sent; the arm must be homed again (TROLHome)");
        }
        b.sync().map(|_| "taken".to_string()).map_err(|f| f.text())
    }
    fn reading(&mut self) -> Result<Option<[f64; 6]>, String> {
        let b = &mut *self.0;
        if b.status().map_err(|f| f.text())? & st::MOVING != 0 {
            return Ok(None);
        }
        b.counters().map(Some).map_err(|f| f.text())
    }
    fn still_within(&self) -> [f64; 6] {
        self.0.still_irc()
    }
    fn now(&self) -> Instant {
        Instant::now()
    }
    fn pause(&mut self, d: Duration) {
        std::thread::sleep(d);
    }
}

impl MarsBackend {
    /// Halt as the arm shows it (issue 37; the rule is the shared one of
    /// [`trol_controller::real::halt`]): `STOP:`, and where the arm is not seen standing
    /// within [`STOP_WITHIN`], `PURGE:` (which resets the motors; the arm counts as not
    /// homed after it). Success only once the moving bit is clear and two `COORDAP?` reads
    /// [`STILL_GAP`] apart agree; otherwise TROL_ERR_NOT_STOPPED, and what was under way is
    /// kept, so that Finish goes on reporting the arm as the unit shows it.
    pub(super) fn stop_and_see(&mut self) -> BiosResult {
        let times = real::HaltTimes {
            halt_within: HALT_WITHIN,
            stop_within: STOP_WITHIN,
        };
        match real::halt(&mut Stopper(self), &["STOP:", "PURGE:"], times) {
            real::Halted::Standing { note, .. } => {
                if let Some(note) = note {
                    self.say(&note);
                }
                self.abandon();
                Ok(code::OK)
            }
            real::Halted::NotStopped(text) => {
                self.say(&format!("Halt: the arm was not seen standing: {text}"));
                Err(BackendError::NotStopped(text))
            }
        }
    }

    /// How far two `COORDAP?` reads of a standing arm may differ, IRC: [`STILL_DEG`], and
    /// at least 2 counts of encoder dither.
    pub(super) fn still_irc(&self) -> [f64; 6] {
        let p = &self.profile;
        std::array::from_fn(|j| (STILL_DEG * p.irc_per_deg(j)).abs().max(2.0))
    }

    /// Forget what was under way (after a fault or Halt) and take the arm as where it is.
    pub(super) fn abandon(&mut self) {
        self.pending.clear();
        self.motion = None;
        self.homing = None;
        self.gripper = None;
        let now = self.now();
        self.planner.halt(now);
        if let Ok(q) = self.actual() {
            self.planner.place(q);
        }
    }
}

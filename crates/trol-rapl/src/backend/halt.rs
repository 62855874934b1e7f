//! Halt on a C500: its stops (HALT, ABORT, Ctrl-C) in the profile's order, confirmed by W2
//! through the shared rule ([`trol_controller::real::halt`]).

use super::*;

/// One of the C500's stops (docs/c500.md, "Halt").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Stop {
    Halt,
    Abort,
    CtrlC,
}

impl Stop {
    fn word(self) -> &'static str {
        match self {
            Stop::Halt => "HALT",
            Stop::Abort => "ABORT",
            Stop::CtrlC => "Ctrl-C",
        }
    }
}

/// The C500's side of the shared Halt ([`trol_controller::real`]): its stops, W2's JOINTS
/// row (degrees) as the reading.
struct Stopper<'a>(&'a mut RaplBackend);

impl real::Stopping for Stopper<'_> {
    type Stop = Stop;
    fn stop_name(&self, stop: Stop) -> String {
        stop.word().into()
    }
    fn send_stop(&mut self, stop: Stop) -> Result<String, String> {
        let b = &mut *self.0;
        match stop {
            Stop::CtrlC => {
                b.awaiting = None;
                b.interrupt()
                    .map(|_| "prompt back".to_string())
                    .map_err(|e| e.to_string())
            }
            Stop::Halt | Stop::Abort => match b.command_as(stop.word(), true) {
                Ok(0) => Ok("acknowledged".into()),
                Ok(c) => Ok(format!("refused, {c}")),
                Err(e) => Err(e.to_string()),
            },
        }
    }
    fn reading(&mut self) -> Result<Option<[f64; 6]>, String> {
        self.0
            .read_position(PosMode::Actual)
            .map(|p| Some(p.joints))
            .map_err(|e| format!("W2: {e}"))
    }
    fn still_within(&self) -> [f64; 6] {
        [real::STILL_DEG; 6]
    }
    fn now(&self) -> std::time::Instant {
        std::time::Instant::now()
    }
    fn pause(&mut self, d: Duration) {
        std::thread::sleep(d);
    }
}

impl RaplBackend {
    /// One stop (`HALT`, `ABORT` or `Ctrl-C`) on its own, and whether W2 then shows the arm
    /// standing within [`STOP_WITHIN`] (its joints), or why not: for the probe's supervised
    /// step that finds which stop stops a motion. Halt itself tries them all.
    pub fn stop_with(&mut self, stop: &str) -> Result<Result<[f64; 6], String>, BackendError> {
        let stop = match stop {
            "HALT" => Stop::Halt,
            "ABORT" => Stop::Abort,
            "Ctrl-C" => Stop::CtrlC,
            other => {
                return Err(BackendError::Link(format!(
                    "{other} is not one of the C500's stops"
                )));
            }
        };
        match stop {
            Stop::CtrlC => {
                self.awaiting = None;
                self.interrupt()?;
            }
            Stop::Halt | Stop::Abort => match self.command_as(stop.word(), true)? {
                0 => {}
                c => return Ok(Err(format!("{} was refused ({c})", stop.word()))),
            },
        }
        let until = std::time::Instant::now() + STOP_WITHIN;
        real::seen_standing(&mut Stopper(self), until, STOP_WITHIN).map_err(BackendError::Link)
    }

    /// The stops to try, in order: Ctrl-C first where the interpreter is busy with a line
    /// (a motion answered at its end) or where the profile says it is the halt, then the
    /// profile's halt, then the others in the order HALT, ABORT, Ctrl-C.
    pub(super) fn stop_order(&self) -> Vec<Stop> {
        let mut order = Vec::new();
        if self.awaiting.is_some() || self.profile.halt == Halt::CtrlC {
            order.push(Stop::CtrlC);
        }
        let own = match self.profile.halt {
            Halt::Halt => Stop::Halt,
            Halt::Abort => Stop::Abort,
            Halt::CtrlC => Stop::CtrlC,
        };
        // Each stop once: a second Ctrl-C would only spend the Halt's time.
        if !order.contains(&own) {
            order.push(own);
        }
        for s in [Stop::Halt, Stop::Abort, Stop::CtrlC] {
            if !order.contains(&s) {
                order.push(s);
            }
        }
        order
    }

    /// Halt as the arm shows it (issue 37; the rule is the shared one of
    /// [`trol_controller::real::halt`]): each stop of [`RaplBackend::stop_order`] in turn,
    /// until W2 shows the arm standing; success only then. Where none is seen to work within
    /// [`HALT_WITHIN`] of the call, TROL_ERR_NOT_STOPPED with what each stop got. No profile
    /// key makes a stop count that was not seen.
    pub(super) fn stop_and_see(&mut self) -> BiosResult {
        let order = self.stop_order();
        let times = real::HaltTimes {
            halt_within: HALT_WITHIN,
            stop_within: STOP_WITHIN,
        };
        match real::halt(&mut Stopper(self), &order, times) {
            real::Halted::Standing { at, note } => {
                self.rest = Some(at);
                self.outstanding = None;
                self.awaiting = None;
                if let Some(note) = note {
                    self.note(note);
                }
                Ok(0)
            }
            real::Halted::NotStopped(text) => {
                self.note(format!("Halt: the arm was not seen standing: {text}"));
                Err(BackendError::NotStopped(text))
            }
        }
    }
}

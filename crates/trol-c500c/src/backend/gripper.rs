//! The gripper through ash's grip commands (docs/c500c.md, "The gripper"): `grip_open
//! <% force>`, `grip_close <% force>`, `grip <distance>`, and `wgrip`, which reads how far
//! the jaws stand apart.
//!
//! As the manual has it (TROLClose, TROLOpen, TROLGrip), a grip call returns once ash took
//! the command, and TROLFinish(FINISH_WAIT) waits for the jaws. On a servo gripper their
//! end is seen: `wgrip` reads the same twice over [`JAWS_STILL_FOR`]; for Grip, within
//! [`JAWS_AT_MM`] of the distance asked (else BIOS_NOT_AT_TARGET). An air gripper is a
//! valve: its command is taken at ash's word, and GetGripper cannot read it. Which gripper
//! is set up, ash says (`griptype_set`, read once per session); none set: refused.

use super::*;

/// How long the jaws must read the same to stand (assumed: a servo gripper starts within
/// milliseconds of its command).
pub const JAWS_STILL_FOR: Duration = Duration::from_millis(300);
/// How far apart two readings of standing jaws may be, mm.
pub const JAWS_STILL_MM: f64 = 0.1;
/// How far from the distance asked the jaws may stand after Grip, mm (assumed).
pub const JAWS_AT_MM: f64 = 1.0;
/// The longest the jaws may take (assumed: 50 mm at the A465 servo gripper's pace takes
/// about 1.3 s).
pub const JAWS_WITHIN: Duration = Duration::from_secs(5);
/// The jaws' widest opening, mm (the manual's TROLGrip: 0 .. 50 mm).
pub const JAWS_MAX_MM: f64 = 50.0;

/// The gripper ash is set up for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum GripKind {
    Servo,
    Air,
    None,
}

/// A grip command of TROL's whose end is still to be seen.
#[derive(Clone, Debug)]
pub(super) struct JawsWait {
    /// The command, as typed.
    line: String,
    /// Grip's distance, mm (Open and Close: wherever the jaws stop).
    to: Option<f64>,
    /// The prompt is still due (ash gives it back once the jaws stand).
    pub(super) prompt_due: bool,
    /// When the command was taken.
    since: Instant,
    /// The last reading, and since when it has not changed.
    still: Option<(f64, Instant)>,
    /// A servo gripper, whose jaws are read (an air gripper's end is ash's prompt alone).
    servo: bool,
}

/// `griptype_set`'s line: `Gripper type set to 2--SERVO`, `... set to 1--AIR`, `... not
/// set.`
pub(super) fn read_grip_type(lines: &[String]) -> Option<GripKind> {
    let said = said(lines);
    match said[..] {
        ["Gripper type set to 2--SERVO"] => Some(GripKind::Servo),
        ["Gripper type set to 1--AIR"] => Some(GripKind::Air),
        ["Gripper type not set."] => Some(GripKind::None),
        _ => None,
    }
}

/// `wgrip`'s line: `Gripper distance = 12.5`.
pub(super) fn read_jaws(lines: &[String]) -> Option<f64> {
    let said = said(lines);
    match said[..] {
        [l] => l
            .strip_prefix("Gripper distance = ")?
            .trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite()),
        _ => None,
    }
}

impl C500cBackend {
    /// Which gripper ash is set up for, read once.
    fn grip_kind(&mut self) -> Result<GripKind, BackendError> {
        if let Some(k) = self.grip_kind {
            return Ok(k);
        }
        let lines = match self.exchange("griptype_set") {
            Ok(l) => l,
            Err(e) => return Err(self.fail(e)),
        };
        match read_grip_type(&lines) {
            Some(k) => {
                self.grip_kind = Some(k);
                Ok(k)
            }
            None => Err(self.unsure(format!(
                "`griptype_set`: ash printed `{}`, not a gripper type TROL reads",
                lines.join(" | ")
            ))),
        }
    }

    /// Where the jaws stand apart, mm (`wgrip`).
    fn jaws(&mut self) -> Result<f64, BackendError> {
        let lines = match self.exchange("wgrip") {
            Ok(l) => l,
            Err(e) => return Err(self.fail(e)),
        };
        read_jaws(&lines).ok_or_else(|| {
            self.unsure(format!(
                "`wgrip`: ash printed `{}`, not the form TROL reads",
                lines.join(" | ")
            ))
        })
    }

    /// Open (`grip_open force`), Close (`grip_close force`) or Grip (`grip mm`): the gate
    /// (nothing of TROL's moving or queued, the gripper set up), the command, taken on its
    /// exact success form.
    pub(super) fn grip_command(&mut self, what: GripCall) -> BiosResult {
        self.clean()?;
        if self.outstanding.is_some() || !self.queue.is_empty() || self.jaws_wait.is_some() {
            self.note(
                "refused: a motion or the gripper has not ended: call TROLFinish(FINISH_WAIT) \
                 first (the manual: the arm at its place before the gripper moves)"
                    .into(),
            );
            return Ok(BUSY);
        }
        let (line, to) = match what {
            GripCall::Open(f) | GripCall::Close(f) if !(1..=100).contains(&f) => {
                return Ok(code::BAD_ARGUMENT);
            }
            GripCall::Grip(d) if f64::from(d) > JAWS_MAX_MM => return Ok(code::BAD_ARGUMENT),
            GripCall::Open(f) => (format!("grip_open {f}"), None),
            GripCall::Close(f) => (format!("grip_close {f}"), None),
            GripCall::Grip(d) => (format!("grip {d}"), Some(f64::from(d))),
        };
        let kind = self.grip_kind()?;
        match (kind, to) {
            (GripKind::None, _) => {
                self.note(
                    "refused before sending: ash says no gripper type is set: set it at the \
                     controller (`griptype_set servo` or `griptype_set air`), then reconnect"
                        .into(),
                );
                return Ok(UNSUPPORTED);
            }
            (GripKind::Air, Some(_)) => {
                self.note(
                    "refused before sending: Grip sets a distance, and an air gripper has none: \
                     use TROLOpen and TROLClose"
                        .into(),
                );
                return Ok(UNSUPPORTED);
            }
            _ => {}
        }
        if let Err(e) = self.type_line(&line) {
            return Err(self.fail(e));
        }
        let since = Instant::now();
        // ash may give the prompt back at once, or once the jaws stand: a refusal comes
        // within ACCEPT_WITHIN, and silence after it is the jaws moving.
        let got = match self.read_to_prompt(&line, since + ACCEPT_WITHIN) {
            Ok(g) => g,
            Err(e) => return Err(self.fail(e)),
        };
        let prompt_due = match got {
            Some(lines) if lines.is_empty() => false,
            Some(lines) => return Err(self.refusal(&line, &lines)),
            None if self.rx.is_empty() => true,
            None => {
                let seen: Vec<String> = self.rx.drain(..).map(|s| s.to_string()).collect();
                return Err(self.unsure(format!(
                    "`{line}`: ash printed {} and no prompt: whether the gripper moves is not \
                     known",
                    seen.join(" ")
                )));
            }
        };
        if kind == GripKind::Air && !prompt_due {
            // A valve: nothing to see. Taken at ash's word.
            self.note(format!(
                "`{line}`: an air gripper's jaws cannot be read; ash took the command"
            ));
            return Ok(code::OK);
        }
        self.jaws_wait = Some(JawsWait {
            line,
            to,
            prompt_due,
            since,
            still: None,
            servo: kind == GripKind::Servo,
        });
        Ok(code::OK)
    }

    /// One look at the jaws of a grip command under way: `true` while they move.
    pub(super) fn look_jaws(&mut self) -> Result<bool, BackendError> {
        let Some(w) = self.jaws_wait.clone() else {
            return Ok(false);
        };
        let now = Instant::now();
        if w.prompt_due {
            match self.read_to_prompt(&w.line, now + Duration::from_millis(20)) {
                Ok(Some(lines)) if lines.is_empty() => {
                    if !w.servo {
                        self.jaws_wait = None;
                        return Ok(false);
                    }
                    if let Some(j) = self.jaws_wait.as_mut() {
                        j.prompt_due = false;
                    }
                    return Ok(true);
                }
                Ok(Some(lines)) => {
                    self.jaws_wait = None;
                    return Err(self.refusal(&w.line, &lines));
                }
                Ok(None) if now.duration_since(w.since) > JAWS_WITHIN => {
                    return Err(self.unsure(format!(
                        "`{}`: ash has not given its prompt back within {JAWS_WITHIN:?}",
                        w.line
                    )));
                }
                Ok(None) => return Ok(true),
                Err(e) => return Err(self.fail(e)),
            }
        }
        let d = self.jaws()?;
        let now = Instant::now();
        let still = match w.still {
            Some((at, since)) if (d - at).abs() <= JAWS_STILL_MM => (at, since),
            _ => (d, now),
        };
        if now.duration_since(still.1) >= JAWS_STILL_FOR {
            self.jaws_wait = None;
            return match w.to {
                Some(to) if (d - to).abs() > JAWS_AT_MM => {
                    self.note(format!(
                        "`{}`: the jaws stand {d:.1} mm apart, not {to:.0} mm (an object between \
                         them?)",
                        w.line
                    ));
                    Err(BackendError::Refused(NOT_AT_TARGET))
                }
                _ => Ok(false),
            };
        }
        if now.duration_since(w.since) > JAWS_WITHIN {
            self.jaws_wait = None;
            return Err(self.unsure(format!(
                "`{}`: the jaws (wgrip) have not stood still within {JAWS_WITHIN:?}",
                w.line
            )));
        }
        if let Some(j) = self.jaws_wait.as_mut() {
            j.still = Some(still);
        }
        Ok(true)
    }

    /// GetGripper: `wgrip` on a servo gripper; what they hold is not known.
    pub(super) fn read_gripper(&mut self) -> Result<Gripper, BackendError> {
        self.clean()?;
        if self.console_busy() || self.jaws_wait.as_ref().is_some_and(|w| w.prompt_due) {
            return Err(BackendError::Refused(BUSY));
        }
        match self.grip_kind()? {
            GripKind::Servo => Ok(Gripper {
                opening_mm: self.jaws()?,
                held: Held::Unknown,
            }),
            GripKind::Air => Err(BackendError::Unsupported("read an air gripper's jaws")),
            GripKind::None => Err(BackendError::Unsupported("read a gripper (none is set)")),
        }
    }
}

/// A grip call of TROL's.
#[derive(Clone, Copy, Debug)]
pub(super) enum GripCall {
    /// TROLOpen(percent of the force).
    Open(u8),
    /// TROLClose(percent of the force).
    Close(u8),
    /// TROLGrip(mm).
    Grip(u8),
}

#[cfg(test)]
mod tests {
    use super::*;

    fn l(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn replies_are_read_exactly() {
        assert_eq!(
            read_grip_type(&l(&["Gripper type set to 2--SERVO"])),
            Some(GripKind::Servo)
        );
        assert_eq!(
            read_grip_type(&l(&["Gripper type set to 1--AIR"])),
            Some(GripKind::Air)
        );
        assert_eq!(
            read_grip_type(&l(&["Gripper type not set."])),
            Some(GripKind::None)
        );
        assert_eq!(read_grip_type(&l(&["Gripper type set to 3"])), None);
        assert_eq!(read_jaws(&l(&["Gripper distance = 12.500"])), Some(12.5));
        assert_eq!(read_jaws(&l(&["Gripper distance = nan"])), None);
        assert_eq!(read_jaws(&l(&["Gripper distance: 12"])), None);
        assert_eq!(read_jaws(&l(&["Gripper distance = 1", "x"])), None);
    }
}

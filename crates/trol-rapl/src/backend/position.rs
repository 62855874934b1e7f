//! Where the arm is: W0/W2, read and cross-checked with the A465 kinematics.

use super::*;

impl RaplBackend {
    pub(super) fn kin(&self) -> Kinematics {
        Kinematics::new(self.tool)
    }

    pub(super) fn read_position(&mut self, mode: PosMode) -> Result<text::Position, BackendError> {
        let cmd = match mode {
            PosMode::Commanded => "W0",
            PosMode::Actual => "W2",
        };
        let mut why = String::new();
        for _ in 0..3 {
            let r = self.output(cmd)?;
            match text::read_position(&r.text).and_then(|p| self.consistent(p)) {
                Ok(p) => return Ok(p),
                Err(e) => {
                    self.note(format!("{cmd} read again: {e}: {:?}", r.text));
                    why = e;
                }
            }
        }
        Err(BackendError::Link(format!(
            "the reply to {cmd} could not be read three times: {why}"
        )))
    }

    /// A reading whose PULSES and JOINTS rows agree (within 0.01 degrees) under the
    /// profile's pulse convention, when it has one and asks for the check.
    pub(super) fn consistent(&self, p: text::Position) -> Result<text::Position, String> {
        if !self.profile.cross_check {
            return Ok(p);
        }
        let Ok(q) = self.frames.pulses_to_joints(p.pulses) else {
            return Ok(p);
        };
        for (i, (from_pulses, read)) in q.iter().zip(&p.joints).enumerate() {
            if (from_pulses - read).abs() > 0.01 {
                return Err(format!(
                    "joint {} reads {read:.4} deg but its pulses say {from_pulses:.4} deg",
                    i + 1,
                ));
            }
        }
        Ok(p)
    }

    /// Where the arm stands (W0), for a motion computed from it; BUSY while a motion of ours
    /// has not ended (its end would be a guess).
    pub(super) fn standing(&mut self) -> Result<Result<text::Position, i16>, BackendError> {
        if self.outstanding.is_some() || !self.queue.is_empty() {
            self.note(
                "refused: a motion has not ended, and this one is computed from where the arm \
                 is: call TROLFinish(FINISH_WAIT) first"
                    .into(),
            );
            return Ok(Err(BUSY));
        }
        self.read_position(PosMode::Commanded).map(Ok)
    }

    /// Where the arm stands in joints (degrees): the end of the motion before, seen arrived a
    /// moment ago with nothing but reads since ([`SEEN_FOR`]), else W0 as
    /// [`RaplBackend::standing`] reads it.
    pub(super) fn standing_joints(&mut self) -> Result<Result<[f64; 6], i16>, BackendError> {
        if self.outstanding.is_none() && self.queue.is_empty() {
            if let Some(q) = self.seen.end.get(std::time::Instant::now()) {
                return Ok(Ok(*q));
            }
        }
        Ok(self.standing()?.map(|p| p.joints))
    }

    pub(super) fn here(&mut self) -> Result<Result<Pose, i16>, BackendError> {
        let p = match self.standing()? {
            Ok(p) => p,
            Err(c) => return Ok(Err(c)),
        };
        Ok(match self.frames.from_rapl(p.world) {
            Ok(v) => Ok(Pose::from_xyzypr(v)),
            Err(u) => Err(self.unsettled(u)),
        })
    }
}

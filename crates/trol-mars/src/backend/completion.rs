//! Hard homing group by group, and the gripper: each seen done on the unit.

use super::*;

impl MarsBackend {
    /// One look at a hard home: a group has homed only when the moving bit is clear and
    /// two `COORDAP?` reads in a row put each of its axes at its home mark (0 IRC of the homed
    /// frame, within `arrive_irc`), never on the moving bit alone (issue 37, item 6: a unit
    /// that does not raise the bit while homing had its next group sent while the first
    /// still homed). Then the next group goes; a group not seen home within
    /// [`HOMING_GROUP_LIMIT`] is a failure: `STOP:`, and nothing else is sent.
    pub(super) fn homing_step(&mut self) -> Result<bool, BackendError> {
        let s = self.status().map_err(|f| f.not_run())?;
        if let Some(c) = Self::fault(s) {
            self.abandon();
            return Err(BackendError::Refused(c));
        }
        let now = self.now();
        let c = if s & st::MOVING == 0 {
            Some(self.counters().map_err(|f| f.not_run())?)
        } else {
            None
        };
        let tol = self.profile.arrive_irc;
        let letters = self.profile.axes.clone();
        let h = self.homing.as_mut().expect("homing");
        let group: Vec<usize> = h.group.chars().filter_map(|a| letters.find(a)).collect();
        let home = c.filter(|c| group.iter().all(|&j| c[j].abs() <= tol));
        match (home, h.at_mark) {
            (Some(c), Some(before)) if group.iter().all(|&j| (c[j] - before[j]).abs() <= tol) => {
                // The group is home and stands.
                h.at_mark = None;
                if let Some(g) = h.groups.pop_front() {
                    h.since = now;
                    h.group = g.clone();
                    self.send_hh(&g).map_err(|f| f.unsure())?;
                    return Ok(true);
                }
            }
            (home, _) => {
                h.at_mark = home;
                if now - h.since <= HOMING_GROUP_LIMIT.as_secs_f64() {
                    return Ok(true);
                }
                let g = h.group.clone();
                let _ = self.send(&line::command("STOP:"));
                self.abandon();
                let text = format!(
                    "homing group {g} was not seen at its home mark within {} s (COORDAP? {}): \
                     STOP: sent, nothing else; the arm is not homed",
                    HOMING_GROUP_LIMIT.as_secs(),
                    match c {
                        Some(c) => format!("{c:?}"),
                        None => "not read: the unit still showed the moving bit".into(),
                    }
                );
                self.say(&text);
                return Err(BackendError::Unsure(text));
            }
        }
        let h = self.homing.take().expect("homing");
        for a in &h.axes {
            self.homed[*a] = true;
        }
        self.planner.set_homed(self.homed);
        let q = self.actual().map_err(|f| f.not_run())?;
        self.planner.place(q);
        if h.then_pose {
            let pose = self.profile.home_pose_deg.map(f64::to_radians);
            match self.motion(|arm, now| arm.ma(pose, now))? {
                code::OK => return Ok(true),
                c => return Err(BackendError::Refused(c)),
            }
        }
        Ok(false)
    }

    pub(super) fn send_hh(&mut self, group: &str) -> Result<(), Fail> {
        let mut bytes = Vec::new();
        for a in group.chars() {
            bytes.extend(line::command(&format!("HH{a}:")));
        }
        self.send(&bytes).map_err(Fail::Io)?;
        self.sync()
    }

    /// The gripper's axis letter (only called with a gripper in the profile).
    pub(super) fn gripper_axis(&self) -> String {
        self.profile
            .gripper
            .as_ref()
            .map(|g| g.axis.clone())
            .unwrap_or_default()
    }

    /// The gripper's axis position (`AP<g>?`).
    /// The fingers' opening from the gripper axis' position and the profile's open and
    /// closed positions, mm.
    pub(super) fn gripper_mm(&mut self, g: &crate::profile::Gripper) -> Result<f64, BackendError> {
        let p = self.read_gripper()?;
        Ok(
            ((p - g.closed) / (g.open - g.closed) * trol_a465::arm::FINGER_MAX)
                .clamp(0.0, trol_a465::arm::FINGER_MAX),
        )
    }

    pub(super) fn read_gripper(&mut self) -> Result<f64, BackendError> {
        let axis = self.gripper_axis();
        let v = self.query(&format!("AP{axis}")).map_err(|f| f.not_run())?;
        v.parse()
            .map_err(|_| BackendError::Unsure(format!("AP{axis}={v}: not a number")))
    }

    /// Whether the fingers still move; `unit_moving`: the unit's moving bit now. The
    /// fingers have arrived only once they are at their target *and* the unit says nothing
    /// moves (it still drove them for a moment after they came within 10 units, and a
    /// motion sent then was refused BIOS_BUSY); or they stalled on an object.
    pub(super) fn gripper_step(&mut self, unit_moving: bool) -> Result<bool, BackendError> {
        let Some(w) = self.gripper.clone() else {
            return Ok(false);
        };
        let axis = self.gripper_axis();
        let p = self.read_gripper()?;
        let now = self.now();
        let arrived = (p - w.target).abs() <= 10.0 && !unit_moving;
        let stalled = match w.last {
            Some((lp, lt)) if now - lt >= 0.2 => (p - lp).abs() < 50.0 * (now - lt) / 0.2,
            _ => false,
        };
        if !(arrived || stalled) {
            let g = self.gripper.as_mut().expect("gripper");
            if g.last.is_none_or(|(_, lt)| now - lt >= 0.2) {
                g.last = Some((p, now));
            }
            return Ok(true);
        }
        self.gripper = None;
        if w.release_after {
            // As ctu-crs does once the fingers closed: stop driving the motor.
            self.send(&line::command(&format!("RELEASE{axis}:")))
                .map_err(|e| BackendError::Unsure(e.to_string()))?;
            self.sync().map_err(|f| f.unsure())?;
        }
        Ok(false)
    }

    pub(super) fn fingers(&mut self, mm: f64, closing: bool) -> BiosResult {
        self.take_unasked()?;
        let Some(pos) = self.profile.gripper_position(mm) else {
            return Ok(UNSUPPORTED);
        };
        let s = self.status().map_err(|f| f.not_run())?;
        if let Some(c) = Self::fault(s) {
            return Ok(c);
        }
        self.set_up()?;
        let axis = self.gripper_axis();
        let mut bytes = line::command(&format!("RELEASE{axis}:"));
        bytes.extend(line::command(&format!("G{axis}:{pos}")));
        self.send(&bytes)
            .map_err(|e| BackendError::Unsure(e.to_string()))?;
        self.sync().map_err(|f| f.unsure())?;
        self.take_unasked()?;
        let now = self.now();
        self.planner.grip(mm, now);
        self.gripper = Some(GripWait {
            target: pos,
            last: None,
            release_after: closing,
        });
        Ok(code::OK)
    }
}

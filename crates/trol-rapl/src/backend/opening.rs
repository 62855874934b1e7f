//! Opening and closing the session: the ACI steps, NOHELP, STATUS, the simulator check.

use super::*;

impl RaplBackend {
    pub(super) fn open(&mut self) -> Result<(), RaplError> {
        let mut aci_said = String::from("the port was taken to be in terminal mode");
        if self.profile.entry != Entry::Terminal {
            match self.aci_steps()? {
                Ok(()) => {
                    // RW waits 100 ms for the switch.
                    let until = std::time::Instant::now() + Duration::from_millis(100);
                    while std::time::Instant::now() < until {
                        let got = self.recv(until)?;
                        if !got.is_empty() {
                            self.note(format!(
                                "after the ACI steps: {:?}",
                                String::from_utf8_lossy(&got)
                            ));
                        }
                    }
                }
                Err(e) => {
                    aci_said = e.to_string();
                    self.note(format!(
                        "{e}; trying Ctrl-C in case the port is in terminal mode"
                    ));
                }
            }
        }
        let now = self.now();
        self.session.resync(now);
        if self.pump()?.is_err() {
            return Err(RaplError::NoController {
                port: self.port.name(),
                aci: aci_said,
                baud: self.profile.baud,
            });
        }
        // NOHELP the way RW types it: NOH, then whatever completion comes, then CR.
        let now = self.now();
        self.session.send_completing(
            "NOH",
            Duration::from_millis(150),
            self.reply_timeout(),
            now,
        )?;
        let mut r = self.pump()?.map_err(no_echo)?;
        if self.refusal(&r).is_some() {
            let now = self.now();
            self.session
                .send_line("NOHELP", self.reply_timeout(), now)?;
            r = self.pump()?.map_err(no_echo)?;
            if let Some((n, t)) = self.refusal(&r) {
                return Err(RaplError::Status(format!(
                    "NOHELP was refused ({n:03}-{t}); nothing was moved"
                )));
            }
        }
        match self.profile.ack {
            Ack::Required if !r.ack => {
                return Err(RaplError::Status(
                    "NOHELP was answered without ACK, which the profile requires (ack = \
                     \"required\"): set ack = \"auto\" if this controller sends none; nothing \
                     was moved"
                        .into(),
                ));
            }
            Ack::Never if r.ack => {
                return Err(RaplError::Status(
                    "NOHELP was answered with ACK, but the profile says ack = \"never\": set \
                     ack = \"auto\"; nothing was moved"
                        .into(),
                ));
            }
            Ack::Auto => {
                self.ack = r.ack;
                self.note(format!(
                    "this controller answers success {} ACK (learned from NOHELP)",
                    if r.ack { "with" } else { "without" }
                ));
            }
            _ => {}
        }
        let status = self
            .read_status()
            .map_err(|e| RaplError::Status(e.to_string()))?;
        match (self.profile.units, status.metric) {
            (Units::Auto, m) => self.frames.mm = m.map(|m| if m { 1.0 } else { 25.4 }),
            (Units::Mm, Some(false)) | (Units::Inch, Some(true)) => {
                return Err(RaplError::Status(format!(
                    "the profile says units = \"{}\" but STATUS says {}: set units = \"auto\" \
                     or change the controller's setting; nothing was moved",
                    if self.profile.units == Units::Mm {
                        "mm"
                    } else {
                        "inch"
                    },
                    if status.metric == Some(true) {
                        "METRIC UNITS"
                    } else {
                        "ENGLISH UNITS"
                    }
                )));
            }
            _ => {}
        }
        if self.profile.simulated {
            self.check_simulator()?;
        }
        self.note(format!(
            "session open: {}; units {}",
            status.version,
            match self.frames.mm {
                Some(1.0) => "mm",
                Some(_) => "inch",
                None => "unknown (cartesian commands refused)",
            }
        ));
        if status.limp.iter().any(|l| *l) {
            self.note(
                "the arm has no power (STATUS's LIMP row says Y): motions are refused until it \
                 has"
                .into(),
            );
        }
        if !status.homed.iter().all(|h| *h) {
            self.note(
                "the arm is not homed (STATUS's HOMED row says N): call TROLHome(0) with the arm \
                 near its home position; other motions are refused until then"
                    .into(),
            );
        }
        Ok(())
    }

    /// A profile written for the simulated C500 (`simulated = true`) drives only the
    /// simulator: the probe's unknown word must come back refused with the simulator's name
    /// (a real C500 refuses it in its own words, or answers in a form the simulator's profile
    /// does not know). Nothing that moves was sent.
    pub(super) fn check_simulator(&mut self) -> Result<(), RaplError> {
        let word = crate::probe::PROBE_WORD;
        let said = match self.exchange(word, self.reply_timeout()) {
            Ok(r) => {
                let text = lines(&r.text).join(" / ");
                match self.answer(word, r, false) {
                    Ok(Answer::Refused(_, t)) if t.contains(crate::c500::SIMULATOR_SAYS) => {
                        return Ok(());
                    }
                    _ => text,
                }
            }
            Err(e) => e.to_string(),
        };
        Err(RaplError::Status(format!(
            "this profile was written for TROL's simulated C500 (`simulated = true`, by `trol \
             sim --rapl --print-profile`), and the controller on {} is not it (it answered \
             `{word}` with `{said}`): its readings would move a real arm wrongly. Write this \
             controller's own profile with `trol rapl probe` (docs/c500.md, \"The first hour \
             with a real arm\"), or delete the line `simulated = true` to use the file anyway; \
             nothing was moved",
            self.port.name()
        )))
    }

    pub(super) fn aci_steps(&mut self) -> io::Result<Result<(), AciError>> {
        let mut m = Master::new(self.profile.entry, self.profile.slave, self.now());
        loop {
            let tx = m.take_transmit();
            if !tx.is_empty() {
                self.send(&tx)?;
            }
            if let Some(r) = m.result() {
                return Ok(r);
            }
            let wake = m
                .next_timeout()
                .map(|t| self.at(t))
                .unwrap_or_else(std::time::Instant::now);
            let got = self.recv(wake)?;
            let now = self.now();
            m.feed(&got, now);
            m.handle_timeout(now);
        }
    }

    /// End the session: HELP back on, then two Ctrl-Z to ACI mode. Once: later calls, and
    /// dropping the backend, send nothing more. Motions still queued are dropped, not sent.
    pub fn close(&mut self) {
        if self.closed {
            return;
        }
        if !self.queue.is_empty() {
            let n = self.queue.len();
            self.queue.drop_all();
            self.note(format!("{n} queued motion(s) dropped at close, not sent"));
        }
        let t = self.reply_timeout();
        let _ = self.exchange("HELP", t);
        let _ = self.send(&[CTRL_Z, CTRL_Z]);
        self.closed = true;
    }
}

//! The C500's line as the backend uses it: typing a line and reading its reply, the
//! success form and the refusal forms, what the controller says unasked, the log and the
//! transcript.

use super::*;

impl RaplBackend {
    /// Forget what was seen of the arm: a line that is not a read went out, something came
    /// unasked, or something failed.
    pub(super) fn forget(&mut self) {
        self.seen.idle.forget();
        self.seen.end.forget();
    }

    /// Whether `line` only reads (cannot move the arm or change what it does).
    pub(super) fn only_reads(line: &str) -> bool {
        let word = line.split_whitespace().next().unwrap_or("");
        crate::probe::READ_ONLY
            .iter()
            .any(|k| k.eq_ignore_ascii_case(word))
    }

    pub(super) fn note(&mut self, line: String) {
        if let Some(f) = self.log_fn.as_mut() {
            f(&line);
        }
        if self.log.len() == LOG_KEEP {
            self.log.pop_front();
        }
        self.log.push_back(line);
    }

    /// The last lines of the log (refusals with the controller's text, resynchronisations).
    pub fn log_lines(&self) -> Vec<String> {
        self.log.iter().cloned().collect()
    }

    /// The transcript so far, when recording.
    pub fn transcript(&self) -> Option<Transcript> {
        self.transcript
            .as_ref()
            .map(|t| t.lock().map(|t| t.clone()).unwrap_or_default())
    }

    /// The profile the session was opened with.
    pub fn profile(&self) -> &Profile {
        &self.profile
    }

    /// Whether this controller answers a successful command with ACK (the profile's `ack`,
    /// or what NOHELP's answer showed with `ack = "auto"`).
    pub fn expects_ack(&self) -> bool {
        self.ack
    }

    /// How long what was seen of the arm stands in for a read before a motion ([`SEEN_FOR`]
    /// by default; zero: a read before every motion). For tests, and for a cautious
    /// application.
    pub fn set_seen_for(&mut self, d: Duration) {
        self.seen.idle.set_window(d);
        self.seen.end.set_window(d);
    }

    /// Type a line that cannot move the arm (its keyword is one of
    /// [`crate::probe::READ_ONLY`]) and read its reply; any other line is refused unsent.
    pub fn read_only(&mut self, line: &str) -> Result<Reply, BackendError> {
        let word = line.split_whitespace().next().unwrap_or("");
        if !crate::probe::READ_ONLY
            .iter()
            .any(|k| k.eq_ignore_ascii_case(word))
        {
            return Err(BackendError::Link(format!(
                "`{line}` is not one of the commands that cannot move the arm ({}); not sent",
                crate::probe::READ_ONLY.join(", ")
            )));
        }
        let t = self.reply_timeout();
        self.exchange(line, t)
    }

    /// Type any line, as a terminal would (`trol rapl term`), and read its reply within
    /// `timeout`. The line is checked like every other: typed byte by byte, each echo
    /// checked, and cancelled with Ctrl-C before its terminator if an echo differs.
    pub fn type_line(&mut self, line: &str, timeout: Duration) -> Result<Reply, BackendError> {
        self.last_poll = None;
        self.exchange(line, timeout)
    }

    /// Like [`RaplBackend::type_line`], stopped when `stop` is set (Ctrl-C in `trol rapl
    /// term`): the line is cancelled with Ctrl-C and the arm halted as the profile says; the
    /// answer is then UNSURE (the line may have run) with what was done.
    pub fn type_line_unless(
        &mut self,
        line: &str,
        timeout: Duration,
        stop: &std::sync::atomic::AtomicBool,
    ) -> Result<Reply, BackendError> {
        self.last_poll = None;
        self.forget();
        self.settle()?;
        let now = self.now();
        self.session
            .send_line(line, timeout, now)
            .map_err(|e| BackendError::Link(e.to_string()))?;
        match self.pump_unless(Some(stop)) {
            Ok(Some(Ok(r))) => Ok(r),
            Ok(Some(Err(e))) => Err(if e.surely_not_run() {
                BackendError::Link(e.to_string())
            } else {
                BackendError::Unsure(e.to_string())
            }),
            Ok(None) => {
                let cancelled = self.interrupt();
                let halted = self.halt();
                Err(BackendError::Unsure(format!(
                    "`{line}` interrupted: Ctrl-C sent ({}), then the halt ({})",
                    match cancelled {
                        Ok(()) => "prompt back".to_string(),
                        Err(e) => e.to_string(),
                    },
                    match halted {
                        Ok(0) => "done".to_string(),
                        Ok(c) => format!("refused, {c}"),
                        Err(e) => e.to_string(),
                    }
                )))
            }
            Err(e) => Err(BackendError::Unsure(format!("`{line}`: {e}"))),
        }
    }

    /// Ctrl-C, as a terminal's user presses it: the line is cancelled and the controller's
    /// prompt awaited (on a controller whose halt is Ctrl-C, this stops the arm).
    pub fn interrupt(&mut self) -> Result<(), BackendError> {
        self.ctrl_c().map(drop)
    }

    /// Ctrl-C, and what came back up to the prompt.
    pub(super) fn ctrl_c(&mut self) -> Result<String, BackendError> {
        self.forget();
        let now = self.now();
        self.session.resync(now);
        match self.pump() {
            Ok(Ok(r)) => Ok(r.text),
            Ok(Err(e)) => Err(BackendError::Unsure(e.to_string())),
            Err(e) => Err(BackendError::Unsure(e.to_string())),
        }
    }

    /// The refusal in `reply`, if one of its lines has one of the profile's forms.
    pub fn refusal(&self, reply: &Reply) -> Option<(u16, String)> {
        lines(&reply.text)
            .into_iter()
            .find_map(|l| self.forms.iter().find_map(|f| f.read(&l)))
    }

    /// STATUS as read at the opening.
    pub fn opening_status(&self) -> Option<&text::Status> {
        self.status.as_ref()
    }

    pub(super) fn now(&self) -> Instant {
        Instant::from_duration(self.epoch.elapsed())
    }

    pub(super) fn secs(&self) -> f64 {
        self.epoch.elapsed().as_secs_f64()
    }

    pub(super) fn record(&self, dir: Dir, bytes: &[u8]) {
        if let Some(tr) = self.transcript.as_ref() {
            if let Ok(mut tr) = tr.lock() {
                tr.add(self.secs(), dir, bytes);
            }
        }
    }

    pub(super) fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.record(Dir::ToController, bytes);
        self.port.send(bytes)
    }

    pub(super) fn recv(&mut self, until: std::time::Instant) -> io::Result<Vec<u8>> {
        let mut buf = [0u8; 512];
        let n = self.port.recv(&mut buf, until)?;
        if n > 0 {
            self.record(Dir::FromController, &buf[..n]);
        }
        Ok(buf[..n].to_vec())
    }

    pub(super) fn at(&self, t: Instant) -> std::time::Instant {
        self.epoch + t.since_epoch()
    }

    /// Run the session until its next event.
    pub(super) fn pump(&mut self) -> io::Result<Result<Reply, SessionError>> {
        Ok(self
            .pump_until(None, None)?
            .expect("without a stop flag or a limit, pumping ends in an event"))
    }

    /// Run the session until its next event, or until `stop` is set (None).
    pub(super) fn pump_unless(
        &mut self,
        stop: Option<&std::sync::atomic::AtomicBool>,
    ) -> io::Result<Option<Result<Reply, SessionError>>> {
        self.pump_until(stop, None)
    }

    /// Run the session until its next event, `stop` is set, or `until` has come while a
    /// reply is being read (None).
    pub(super) fn pump_until(
        &mut self,
        stop: Option<&std::sync::atomic::AtomicBool>,
        until: Option<std::time::Instant>,
    ) -> io::Result<Option<Result<Reply, SessionError>>> {
        loop {
            if stop.is_some_and(|s| s.load(std::sync::atomic::Ordering::SeqCst)) {
                return Ok(None);
            }
            if until.is_some_and(|u| std::time::Instant::now() >= u) && self.session.is_reading() {
                return Ok(None);
            }
            let now = self.now();
            while let Some(b) = self.session.poll_transmit(now) {
                self.send(&[b])?;
            }
            let expired = self.session.take_xoff_expired();
            if expired > 0 {
                self.note(format!(
                    "the C500 said XOFF and no XON followed within {} ms: typing went on",
                    crate::session::XOFF_LIMIT.as_millis()
                ));
            }
            if let Some(ev) = self.session.poll_event() {
                return Ok(Some(ev));
            }
            let wake = self
                .session
                .next_timeout()
                .map(|t| self.at(t))
                .unwrap_or_else(|| std::time::Instant::now() + Duration::from_millis(50))
                .min(std::time::Instant::now() + Duration::from_millis(50));
            let wake = until.map_or(wake, |u| wake.min(u.max(std::time::Instant::now())));
            let got = self.recv(wake)?;
            let now = self.now();
            if !got.is_empty() {
                self.session.feed(&got, now);
            }
            self.session.handle_timeout(now);
            if self.session.is_lost() {
                if let Some(ev) = self.session.poll_event() {
                    return Ok(Some(ev));
                }
            }
        }
    }

    /// Take in what arrived unasked: a line of text is kept (the next call reports it); any
    /// byte at all, or a lost session, makes the next command resynchronise first.
    pub(super) fn settle(&mut self) -> Result<(), BackendError> {
        while self.port.available().map_err(|e| link(&e))? > 0 {
            let got = self.recv(std::time::Instant::now()).map_err(|e| link(&e))?;
            let now = self.now();
            self.session.feed(&got, now);
        }
        let stray = self.session.take_stray();
        if !stray.is_empty() || self.session.is_lost() {
            self.forget();
            if !stray.is_empty() {
                let text = String::from_utf8_lossy(&stray).into_owned();
                let said = lines(&text)
                    .into_iter()
                    .filter(|l| !l.ends_with(">>") && !l.ends_with("O>"))
                    .collect::<Vec<_>>()
                    .join(" / ");
                self.note(format!("the C500 sent unasked: {text:?}; resynchronising"));
                if !said.is_empty() {
                    if !self.unasked.is_empty() {
                        self.unasked.push_str(" / ");
                    }
                    self.unasked.push_str(&said);
                }
            }
            let now = self.now();
            self.session.resync(now);
            match self.pump().map_err(|e| link(&e))? {
                Ok(_) => {}
                Err(e) => {
                    self.note(format!("resynchronisation failed: {e}"));
                    return Err(BackendError::Link(e.to_string()));
                }
            }
        }
        Ok(())
    }

    /// Keep the lines that came in a resynchronisation after a surprise (an e-stop's line
    /// can break the echo of the next command), but not the echo of `typed`, nor prompts.
    pub(super) fn keep_unasked(&mut self, typed: &str) {
        let got = self.session.take_resync_text();
        let text = String::from_utf8_lossy(&got).into_owned();
        let typed = typed.trim();
        let said: Vec<String> = lines(&text)
            .into_iter()
            .map(|l| {
                l.trim_end_matches(">>")
                    .trim_end_matches("O>")
                    .trim()
                    .to_string()
            })
            .filter(|l| {
                !l.is_empty()
                    && l.bytes().any(|b| b.is_ascii_alphanumeric())
                    && !typed.starts_with(l.as_str())
            })
            .collect();
        if !said.is_empty() {
            self.forget();
            self.note(format!(
                "the C500 said, while a line was typed: {}",
                said.join(" / ")
            ));
            if !self.unasked.is_empty() {
                self.unasked.push_str(" / ");
            }
            self.unasked.push_str(&said.join(" / "));
        }
    }

    /// A line the controller printed unasked, reported once: a refusal form the profile maps
    /// gives its code; anything else is UNSURE with the text. A motion of ours that was under
    /// way or queued is given up (the queue is dropped: nothing more is sent after it).
    pub(super) fn report_unasked(&mut self) -> Result<(), BackendError> {
        self.settle()?;
        if self.unasked.is_empty() {
            return Ok(());
        }
        let text = std::mem::take(&mut self.unasked);
        self.forget();
        self.outstanding = None;
        let dropped = self.queue.len();
        self.queue.drop_all();
        let known = lines(&text)
            .into_iter()
            .find_map(|l| self.forms.iter().find_map(|f| f.read(&l)));
        let tail = if dropped > 0 {
            format!("; {dropped} queued motion(s) dropped, not sent")
        } else {
            String::new()
        };
        self.note(format!("the C500 said unasked: {text}{tail}"));
        match known {
            Some((n, _)) if n > 0 => match self.meaning(n) {
                Meaning::Code(c) => Err(BackendError::Refused(c)),
                Meaning::Location => Err(BackendError::Refused(RAPL_ERROR)),
            },
            _ => Err(BackendError::Unsure(format!(
                "the C500 said unasked: {text}{tail}"
            ))),
        }
    }

    /// Type a line and read its reply.
    pub(super) fn exchange(
        &mut self,
        line: &str,
        timeout: Duration,
    ) -> Result<Reply, BackendError> {
        self.exchange_as(line, timeout, false)
    }

    pub(super) fn exchange_as(
        &mut self,
        line: &str,
        timeout: Duration,
        urgent: bool,
    ) -> Result<Reply, BackendError> {
        if self.closed {
            return Err(BackendError::Link(format!(
                "`{line}` not sent: the RAPL-II session is closed"
            )));
        }
        self.release()?;
        if let Some(motion) = &self.awaiting {
            return Err(BackendError::Link(format!(
                "`{line}` not sent: this controller answers `{motion}` only at the motion's end \
                 (motion_ack = \"end\"), and its interpreter takes nothing before: call \
                 TROLFinish(FINISH_WAIT) first"
            )));
        }
        if !Self::only_reads(line) {
            self.forget();
        }
        self.settle()?;
        let now = self.now();
        let started = if urgent {
            self.session.send_urgent(line, timeout, now)
        } else {
            self.session.send_line(line, timeout, now)
        };
        if let Err(e) = started {
            self.forget();
            self.note(format!("`{line}` not sent: {e}"));
            return Err(BackendError::Link(e.to_string()));
        }
        match self.pump() {
            Ok(Ok(r)) => Ok(r),
            Ok(Err(e)) => {
                self.forget();
                self.note(format!("`{line}`: {e}"));
                self.keep_unasked(&format!("{line}\r"));
                Err(if e.surely_not_run() {
                    BackendError::Link(e.to_string())
                } else {
                    BackendError::Unsure(e.to_string())
                })
            }
            Err(e) => {
                self.forget();
                Err(BackendError::Unsure(format!("`{line}`: {e}")))
            }
        }
    }

    /// How the reply to `line` reads. `output`: the command prints text (its parser checks
    /// it); otherwise any text at all is not the success form.
    pub(super) fn answer(
        &mut self,
        line: &str,
        r: Reply,
        output: bool,
    ) -> Result<Answer, BackendError> {
        let refused = self.refusal(&r);
        let printed = lines(&r.text).join(" / ");
        if refused.is_some() || (self.ack && !r.ack) || (!output && !printed.is_empty()) {
            self.forget();
        }
        if let Some((n, t)) = refused {
            if r.ack {
                let e = format!(
                    "`{line}`: the C500 printed `{printed}` and then ACK: whether it ran is not \
                     known, so nothing further was sent"
                );
                self.note(e.clone());
                return Err(BackendError::Unsure(e));
            }
            self.note(format!("`{line}` refused: {printed}"));
            return Ok(Answer::Refused(n, t));
        }
        if self.ack && !r.ack {
            let e = format!(
                "`{line}`: answered without the ACK this controller gives on success{}; whether \
                 it ran is not known, so nothing further was sent (a controller that sends no \
                 ACK: ack = \"never\" in the profile)",
                if printed.is_empty() {
                    String::new()
                } else {
                    format!(" (it printed `{printed}`)")
                }
            );
            self.note(e.clone());
            return Err(BackendError::Unsure(e));
        }
        if !output && !printed.is_empty() {
            let e = format!(
                "`{line}`: the C500 printed `{printed}`, which is neither its success form nor \
                 one of the profile's refusal forms; whether it ran is not known, so nothing \
                 further was sent (if it is a refusal, add its form to `refusal` in the profile)"
            );
            self.note(e.clone());
            return Err(BackendError::Unsure(e));
        }
        Ok(Answer::Done(r))
    }

    /// A command whose output is parsed (STATUS, W0, W2, LISTL): a refusal is a failure
    /// of the line (these commands change nothing).
    pub(super) fn output(&mut self, line: &str) -> Result<Reply, BackendError> {
        let t = self.reply_timeout();
        // These lines change nothing: a failure leaves no doubt about the arm.
        let r = self.exchange(line, t).map_err(not_run)?;
        match self.answer(line, r, true)? {
            Answer::Done(r) => Ok(r),
            Answer::Refused(n, t) => Err(BackendError::Link(format!(
                "`{line}` was refused: {n:03}-{t}"
            ))),
        }
    }

    pub(super) fn reply_timeout(&self) -> Duration {
        Duration::from_millis(self.profile.reply_timeout_ms)
    }

    pub(super) fn motion_timeout(&self) -> Duration {
        Duration::from_secs(self.profile.motion_timeout_s)
    }

    /// The BIOS code of a refusal numbered `number` (a location the controller does not
    /// know, after LISTL found it, is a bad argument).
    pub(super) fn code_of_refusal(&self, number: u16) -> i16 {
        match self.meaning(number) {
            Meaning::Code(c) => c,
            Meaning::Location => code_of("BIOS_BAD_ARGUMENT"),
        }
    }

    pub(super) fn meaning(&self, number: u16) -> Meaning {
        match self.profile.error_target(number) {
            Some("TROL_ERR_LOCATION") => Meaning::Location,
            Some(name) => Meaning::Code(code_of(name)),
            None => Meaning::Code(RAPL_ERROR),
        }
    }

    /// A command whose answer is the success form or a refusal. Its timeout is the short
    /// one: nothing here waits for a motion's end (a name is looked up with LISTL before).
    pub(super) fn command(&mut self, line: &str) -> BiosResult {
        self.command_as(line, false)
    }

    pub(super) fn command_as(&mut self, line: &str, urgent: bool) -> BiosResult {
        let t = self.reply_timeout();
        let r = self.exchange_as(line, t, urgent)?;
        match self.answer(line, r, false)? {
            Answer::Done(_) => Ok(0),
            Answer::Refused(n, _) => Ok(self.code_of_refusal(n)),
        }
    }

    pub(super) fn read_status(&mut self) -> Result<text::Status, BackendError> {
        let r = self.output("STATUS")?;
        let s = text::read_status(&r.text).map_err(BackendError::Link)?;
        self.status = Some(s.clone());
        let idle =
            s.done.iter().all(|d| *d) && s.homed.iter().all(|h| *h) && !s.limp.iter().any(|l| *l);
        self.seen
            .idle
            .saw(std::time::Instant::now(), idle.then(|| s.clone()));
        Ok(s)
    }
}

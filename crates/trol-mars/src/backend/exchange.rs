//! The MARS 8's line as the backend uses it: sending, each batch confirmed by `STAMP`,
//! the queries (`ST?`, `COORDAP?`), what the unit says unasked, and the regulator set-up.

use super::*;

impl MarsBackend {
    pub(super) fn say(&mut self, text: &str) {
        if let Some(l) = &mut self.log {
            l(text);
        }
    }

    pub(super) fn note(&mut self, sent: bool, bytes: &[u8]) {
        if let Some(r) = &self.record {
            if let Ok(mut t) = r.lock() {
                t.chunks.push((sent, bytes.to_vec()));
            }
        }
    }

    pub(super) fn now(&self) -> f64 {
        self.epoch.elapsed().as_secs_f64()
    }

    pub(super) fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        // Anything but a read (a query, a STAMP exchange) may change what the arm does:
        // what was seen of it no longer stands in for a read.
        let read = bytes.ends_with(b"?\n") || bytes.starts_with(b"STAMP:");
        if !read {
            self.seen.forget();
        }
        if bytes.starts_with(b"COORDISCONT:") {
            self.discont_set = true;
        } else if !(read || bytes.starts_with(b"COORDMV")) {
            self.discont_set = false;
        }
        self.note(true, bytes);
        self.port.send(bytes)
    }

    /// The next line, waiting until `deadline`.
    pub(super) fn next_line(&mut self, deadline: Instant) -> Result<Option<String>, Fail> {
        loop {
            if let Some(l) = self.rx.pop_front() {
                return Ok(Some(l));
            }
            let mut buf = [0u8; 256];
            let n = self.port.recv(&mut buf, deadline).map_err(Fail::Io)?;
            if n == 0 {
                return Ok(None);
            }
            self.note(false, &buf[..n]);
            let got = self.lines.feed(&buf[..n]);
            self.rx.extend(got);
        }
    }

    /// Read lines until one `want`s; the others are kept as unasked.
    pub(super) fn await_reply(
        &mut self,
        what: &str,
        want: impl Fn(&Reply) -> bool,
    ) -> Result<Reply, Fail> {
        let deadline = Instant::now() + REPLY_LIMIT;
        loop {
            match self.next_line(deadline)? {
                None => return Err(Fail::Silent(what.to_string())),
                Some(l) => {
                    let r = line::parse(&l);
                    if want(&r) {
                        return Ok(r);
                    }
                    self.say(&format!("unasked: {l}"));
                    self.unasked.push(l);
                }
            }
        }
    }

    pub(super) fn sync(&mut self) -> Result<(), Fail> {
        self.stamp = (self.stamp + 1) & 0x7fff;
        let s = self.stamp.to_string();
        self.send(format!("STAMP:{s}\n").as_bytes())
            .map_err(Fail::Io)?;
        let what = format!("STAMP:{s}");
        self.await_reply(
            &what,
            |r| matches!(r, Reply::Value { name, value } if name == "STAMP" && *value == s),
        )?;
        Ok(())
    }

    pub(super) fn query(&mut self, q: &str) -> Result<String, Fail> {
        let r = self.send(&line::query(q)).map_err(Fail::Io).and_then(|()| {
            self.await_reply(
                &format!("{q}?"),
                |r| matches!(r, Reply::Value { name, .. } if name == q),
            )
        });
        match r {
            Ok(Reply::Value { value, .. }) => Ok(value),
            Ok(_) => unreachable!("await_reply returns what it wants"),
            Err(e) => {
                // A unit that did not answer a read as asked: what was seen of it a moment
                // ago no longer stands in for the next motion's reads.
                self.seen.forget();
                Err(e)
            }
        }
    }

    pub(super) fn status(&mut self) -> Result<u32, Fail> {
        let v = self.query("ST")?;
        v.parse::<u32>()
            .map_err(|_| Fail::Silent(format!("ST? (it answered `ST={v}`, not a number)")))
    }

    pub(super) fn counters(&mut self) -> Result<[f64; 6], Fail> {
        let v = self.query("COORDAP")?;
        line::coordap(&v).map_err(Fail::Silent)
    }

    pub(super) fn actual(&mut self) -> Result<[f64; 6], Fail> {
        let c = self.counters()?;
        Ok(self.profile.irc_to_joints(&c))
    }

    /// Lines the unit printed unasked since the last call: TROL cannot tell what they mean
    /// for the arm, so the call is UNSURE and sends nothing.
    pub(super) fn take_unasked(&mut self) -> Result<(), BackendError> {
        // What has arrived meanwhile.
        let _ = self.drain();
        if self.unasked.is_empty() {
            return Ok(());
        }
        self.seen.forget();
        self.discont_set = false;
        let text = std::mem::take(&mut self.unasked).join(" | ");
        self.pending.clear();
        Err(BackendError::Unsure(format!(
            "the MARS 8 printed what TROL did not ask for: {text}"
        )))
    }

    pub(super) fn drain(&mut self) -> Result<(), Fail> {
        while let Some(l) = self.next_line(Instant::now())? {
            self.say(&format!("unasked: {l}"));
            self.unasked.push(l);
        }
        Ok(())
    }

    /// The status word's faults as a code.
    pub(super) fn fault(s: u32) -> Option<i16> {
        if s & st::POWER_OFF != 0 {
            Some(ARM_POWER)
        } else if s & st::MOTION_STOP != 0 {
            Some(MOTION_STOP)
        } else if s & st::ERROR != 0 {
            Some(MARS_ERROR)
        } else {
            None
        }
    }

    pub(super) fn busy(&self) -> bool {
        self.motion.is_some() || self.homing.is_some() || !self.pending.is_empty()
    }

    pub(super) fn set_up(&mut self) -> Result<(), BackendError> {
        if self.set_up {
            return Ok(());
        }
        let p = self.profile.clone();
        let r = &p.regulator;
        let mut l = Vec::new();
        for (word, v) in [
            ("REGME", r.me),
            ("REGCFG", r.cfg),
            ("REGP", r.p),
            ("REGI", r.i),
            ("REGD", r.d),
            ("REGMS", p.speed),
            ("REGACC", p.accel),
        ] {
            for (j, value) in v.iter().enumerate() {
                l.push(format!("{word}{}:{value}", p.axis(j)));
            }
        }
        l.push(format!("IDLEREL:{}", r.idlerel));
        if let Some(g) = &p.gripper {
            // ctu-crs's gripper set-up.
            let a = &g.axis;
            for c in [
                format!("ANAXSETUP{a}:10,16"),
                format!("REGS1{a}:16"),
                format!("REGS2{a}:500"),
                format!("REGME{a}:10000"),
                format!("REGMS{a}:500"),
                format!("REGCFG{a}:256"),
                format!("REGP{a}:200"),
                format!("REGI{a}:0"),
                format!("REGD{a}:100"),
            ] {
                l.push(c);
            }
        }
        l.push("SPDTB:0,300".into());
        l.push(format!(
            "COORDGRP:{}",
            p.axes
                .chars()
                .map(String::from)
                .collect::<Vec<_>>()
                .join(",")
        ));
        let mut bytes = Vec::new();
        for c in l {
            bytes.extend(line::command(&c));
        }
        self.send(&bytes)
            .map_err(|e| BackendError::Unsure(e.to_string()))?;
        self.sync().map_err(|f| f.unsure())?;
        self.take_unasked()?;
        self.set_up = true;
        Ok(())
    }

    /// Send queued lines while the unit's queue has room, with a look at its queue-full bit
    /// before every segment (`room`: the status word was read a moment ago and showed room
    /// with nothing of TROL's queued, so the first segment goes without another look). The
    /// bit says only "full", not how much room is left: a batch sent on one look overflowed
    /// a queue with less room than the batch (the unit refuses what does not fit), and a
    /// path longer than the queue ended short of its end (a trajectory of 60 segments; issue
    /// 41). `COORDISCONT:` is a setting, not a segment (CTU's client sends it before every
    /// segment and looks at the bit once in 20 segments), so no look goes before it, nor
    /// between it and the first segment (issue 43: that look delayed every motion's start).
    pub(super) fn pump_from(&mut self, room: bool) -> Result<(), Fail> {
        let mut sent = 0;
        let mut segments = 0;
        while let Some(next) = self.pending.front() {
            let segment = next.starts_with("COORDMV");
            if segment && !(room && segments == 0) && self.status()? & st::QUEUE_FULL != 0 {
                break;
            }
            let l = self.pending.pop_front().expect("not empty");
            self.send(&line::command(&l)).map_err(Fail::Io)?;
            sent += 1;
            if segment {
                segments += 1;
            }
        }
        if sent > 0 {
            self.sync()?;
        }
        Ok(())
    }

    /// [`MarsBackend::pump_from`] with a look at the unit's queue first.
    pub(super) fn pump(&mut self) -> Result<(), Fail> {
        self.pump_from(false)
    }
}

//! The calls of the controller's contract ([`trol_controller::Backend`]) on a C500.

use super::*;

impl Backend for RaplBackend {
    fn kind(&self) -> &'static str {
        "C500 over RAPL-II"
    }
    fn codes(&self) -> &'static CodeTable {
        RAPL_CODES
    }
    fn reply_time(&self) -> Duration {
        // One command the C500 does not answer (the profile's reply timeout), after a
        // FINISH that waits was ended with Ctrl-C and listened for once; or a Halt that
        // tries every stop.
        (self.reply_timeout() + CTRL_C_ENDS_FINISH_WITHIN + FINISH_LISTEN)
            .max(HALT_WITHIN + Duration::from_millis(400))
    }
    fn appro(&mut self, target: &Target, disp: [f64; 6], straight: bool) -> BiosResult {
        let target = target.clone();
        self.motion_with(false, |b, busy| {
            let pose = match &target {
                Target::Name(n) => match b.listed(n)? {
                    Some(l) => match b.pose_of(l) {
                        Ok(p) => p,
                        Err(c) => return Ok(c),
                    },
                    None => return Err(BackendError::UnknownLocation(*n)),
                },
                Target::Location(l @ Location::Cart(_)) => Pose::from_xyzypr(l.to_array6()),
                Target::Location(l @ Location::Prec(_)) => {
                    match b
                        .frames
                        .pulses_to_joints(l.to_array6().map(|x| x.round() as i64))
                    {
                        Ok(deg) => b.kin().fk(&deg.map(f64::to_radians)),
                        Err(u) => return Ok(b.unsettled(u)),
                    }
                }
                Target::Location(l @ Location::Joint(_)) => b.kin().fk(&l.to_array6()),
            };
            b.move_pose(&pose.then(&Pose::from_xyzypr(disp)), straight, busy)
        })
    }
    fn close(&mut self, force: u8) -> BiosResult {
        self.report_unasked()?;
        let r = self.command(&format!("CLOSE {force}"))?;
        self.last_poll = None;
        self.gripping |= r == 0;
        Ok(r)
    }
    fn depart(&mut self, disp: [f64; 6], straight: bool) -> BiosResult {
        let what = format!("Depart {}", join(&disp));
        self.motion_with(false, |b, busy| {
            b.relative(
                what,
                busy,
                Box::new(move |b| match b.here()? {
                    Ok(p) => b.move_pose(&p.then(&Pose::from_xyzypr(disp)), straight, false),
                    Err(c) => Ok(c),
                }),
            )
        })
    }
    fn moving(&mut self) -> Result<bool, BackendError> {
        if let Some(e) = self.deferred.take() {
            return Err(e);
        }
        if self.finish_due() {
            self.type_finish()?;
        } else if let Some((at, m)) = self.last_poll {
            if !self.finishing && at.elapsed() < Duration::from_millis(self.profile.poll_ms) {
                return Ok(m);
            }
        }
        let m = self.poll()?;
        self.last_poll = Some((std::time::Instant::now(), m));
        Ok(m)
    }
    fn stands(&mut self) -> Result<bool, BackendError> {
        // halt() answers success only once it has seen the arm standing.
        Ok(true)
    }
    fn grip(&mut self, dist: u8) -> BiosResult {
        self.report_unasked()?;
        let d = match self.frames.length_to_rapl(f64::from(dist)) {
            Ok(d) => d,
            Err(u) => return Ok(self.unsettled(u)),
        };
        let r = self.command(&format!("GRIP {}", text::num(d)))?;
        self.last_poll = None;
        self.gripping |= r == 0;
        Ok(r)
    }
    fn halt(&mut self) -> BiosResult {
        // A Home halted on the way leaves the arm not homed: the Finish after it says so.
        let homing = self
            .outstanding
            .as_ref()
            .is_some_and(|o| o.motion.expect == Expect::Homed)
            || self.queue.iter().any(|q| q.line() == "HOME");
        // Nothing queued goes out after a Halt, whatever happens to the Halt itself.
        self.last_poll = None;
        if !self.queue.is_empty() {
            let n = self.queue.len();
            self.queue.drop_all();
            self.note(format!("Halt: {n} queued motion(s) dropped, not sent"));
        }
        let r = self.stop_and_see();
        if homing && r.is_ok() {
            self.deferred = Some(BackendError::Refused(sim_code::NOT_HOMED));
            self.note("Halt during HOME: the arm is not homed (the next Finish says so)".into());
        }
        r
    }
    fn home(&mut self, axis: u8) -> BiosResult {
        if axis != 0 {
            self.note(format!(
                "refused: RAPL-II has no form for homing axis {axis} alone"
            ));
            return Ok(UNSUPPORTED);
        }
        if self.profile.home_joints.is_none() {
            // A Home is done only with the arm seen at its home pose (issue 62): without it
            // in the profile TROL could only take STATUS's word.
            self.note(
                "refused before sending: a Home is done only with the arm seen at its home \
                 pose, which is not public for an A465: set `home_joints` in the RAPL-II \
                 profile (`trol rapl probe --measure` reads it once HOME has run; docs/c500.md)"
                    .into(),
            );
            return Ok(UNSETTLED);
        }
        self.motion_with(true, |b, busy| {
            b.submit(
                Motion {
                    line: "HOME".into(),
                    expect: Expect::Homed,
                },
                busy,
            )
        })
    }
    fn jog(&mut self, d: [f64; 3], straight: bool) -> BiosResult {
        if straight {
            match self.profile.jog_frame() {
                Ok(Some(true)) => {}
                Ok(Some(false)) => {
                    self.note(
                        "refused before sending: this controller's JOG moves in the tool \
                         frame, TROL's Jog in the world frame; use Jog with straight = 0"
                            .into(),
                    );
                    return Ok(UNSUPPORTED);
                }
                _ => {
                    self.note(
                        "refused before sending: JOG's frame is not known; set jog_frame in \
                         the RAPL-II profile (docs/c500.md, Settle the conventions)"
                            .into(),
                    );
                    return Ok(NO_JOG_FRAME);
                }
            }
            let v: Result<Vec<f64>, Unsettled> =
                d.iter().map(|x| self.frames.length_to_rapl(*x)).collect();
            let v = match v {
                Ok(v) => v,
                Err(u) => return Ok(self.unsettled(u)),
            };
            let line = format!("JOG {}", join(&v));
            return self.motion_with(false, |b, busy| {
                b.relative_line(line, busy, move |p| {
                    let mut w = p.world;
                    for i in 0..3 {
                        w[i] += v[i];
                    }
                    Expect::World(w)
                })
            });
        }
        let what = format!("Jog {}", join(&d));
        self.motion_with(false, |b, busy| {
            b.relative(
                what,
                busy,
                Box::new(move |b| match b.here()? {
                    Ok(mut p) => {
                        p.pos.x += d[0];
                        p.pos.y += d[1];
                        p.pos.z += d[2];
                        b.move_pose(&p, false, false)
                    }
                    Err(c) => Ok(c),
                }),
            )
        })
    }
    fn joint(&mut self, joint: u8, radians: f64) -> BiosResult {
        if !(1..=6).contains(&joint) || !radians.is_finite() {
            return Ok(code_of("BIOS_BAD_ARGUMENT"));
        }
        let deg = radians.to_degrees();
        let line = format!("JOINT {joint},{}", text::num(deg));
        self.motion_with(false, |b, busy| {
            b.relative_joints(line, busy, move |mut q| {
                q[usize::from(joint - 1)] += deg;
                q
            })
        })
    }
    fn ma(&mut self, q: [f64; 6]) -> BiosResult {
        self.joints("MA", q, false)
    }
    fn mi(&mut self, dq: [f64; 6]) -> BiosResult {
        self.joints("MI", dq, true)
    }
    fn move_to(&mut self, target: &Target, straight: bool) -> BiosResult {
        let target = target.clone();
        if let Target::Location(l @ Location::Joint(_)) = &target {
            // A joint target goes as MA where its units are known: no pulse convention needed.
            if self.joint_units.is_some() && !straight {
                return self.joints("MA", l.to_array6(), false);
            }
        }
        self.motion_with(false, |b, busy| match &target {
            Target::Name(n) => match b.listed(n)? {
                Some(l) => {
                    let expect = match l {
                        Listed::Cart(v) => Expect::World(v),
                        Listed::Prec(p) => Expect::Pulses(p),
                    };
                    // LISTL found it: a refusal now is the motion's, not the name's.
                    let upper = n.as_str().to_ascii_uppercase();
                    let line = format!("{} {upper}", mv(straight));
                    b.submit(Motion { line, expect }, busy)
                }
                None => Err(BackendError::UnknownLocation(*n)),
            },
            Target::Location(l) => match b.point(l)? {
                Ok((name, expect)) => b.submit(
                    Motion {
                        line: format!("{} {name}", mv(straight)),
                        expect,
                    },
                    busy,
                ),
                Err(c) => Ok(c),
            },
        })
    }
    fn here(&mut self, name: LocName, tag: Tag) -> BiosResult {
        self.report_unasked()?;
        if let Some(c) = self.teach_refusal(&name, tag) {
            return Ok(c);
        }
        let upper = name.as_str().to_ascii_uppercase();
        // HERE moves nothing: whatever happens to it, no motion was sent.
        match self.command(&format!("HERE {upper}")).map_err(not_run)? {
            0 => {}
            c => return Ok(c),
        }
        // Success only once LISTL shows the location.
        match self.listed(&name)? {
            Some(_) => Ok(0),
            None => {
                let e = format!(
                    "`HERE {upper}` was answered with success, but LISTL does not list {upper}"
                );
                self.note(e.clone());
                Err(BackendError::Link(e))
            }
        }
    }
    fn define(&mut self, name: LocName, loc: &Location) -> BiosResult {
        self.report_unasked()?;
        if let Some(c) = self.teach_refusal(&name, loc.tag()) {
            return Ok(c);
        }
        // POINT and its read back, as for a scratch location of MoveII.
        match self.point_named(name.as_str().to_string(), loc)? {
            Ok(_) => Ok(0),
            Err(c) => Ok(c),
        }
    }
    fn delete_location(&mut self, name: LocName) -> BiosResult {
        self.report_unasked()?;
        if let Some(c) = self.teach_refusal(&name, Tag::Cart) {
            return Ok(c);
        }
        if self.listed(&name)?.is_none() {
            return Err(BackendError::UnknownLocation(name));
        }
        let upper = name.as_str().to_ascii_uppercase();
        match self.command(&format!("DLOCN {upper}")).map_err(not_run)? {
            0 => {}
            c => return Ok(c),
        }
        match self.listed(&name)? {
            None => Ok(0),
            Some(_) => {
                let e =
                    format!("`DLOCN {upper}` was answered with success, but LISTL still lists it");
                self.note(e.clone());
                Err(BackendError::Link(e))
            }
        }
    }
    fn locations(&mut self) -> Result<Vec<(LocName, Location)>, BackendError> {
        self.report_unasked()?;
        let r = self.output("LISTL")?;
        let rows = text::read_listl(&r.text).map_err(BackendError::Link)?;
        let mut all = Vec::new();
        for (n, l) in rows {
            if Self::is_scratch(&n) {
                continue;
            }
            let Ok(name) = LocName::new(&n.to_ascii_lowercase()) else {
                self.note(format!("LISTL: {n} is no TROL location name; left out"));
                continue;
            };
            let loc = match l {
                Listed::Cart(v) => match self.frames.from_rapl(v) {
                    Ok(t) => Location::from_array6(Tag::Cart, t),
                    Err(u) => return Err(BackendError::Refused(self.unsettled(u))),
                },
                Listed::Prec(p) => {
                    let counts: Option<Vec<i32>> =
                        p.iter().map(|x| i32::try_from(*x).ok()).collect();
                    match counts {
                        Some(c) => Location::Prec(c),
                        None => {
                            self.note(format!("LISTL: {n}'s pulses do not fit 32 bits; left out"));
                            continue;
                        }
                    }
                }
            };
            all.push((name, loc));
        }
        all.sort_by(|a, b| a.0.as_str().cmp(b.0.as_str()));
        Ok(all)
    }
    fn save_locations(&mut self) -> BiosResult {
        // The C500 keeps its location table itself; no public source says whether that
        // memory outlives a power cycle, nor names a command that makes it. Success would
        // claim what cannot be told.
        self.note(
            "refused: the C500 keeps its locations itself; whether they outlive a power \
             cycle is the controller's, and TROL has no command to make sure (write them \
             down with LISTL)"
                .into(),
        );
        Ok(UNSUPPORTED)
    }
    fn open(&mut self, force: u8) -> BiosResult {
        self.report_unasked()?;
        let r = self.command(&format!("OPEN {force}"))?;
        self.last_poll = None;
        self.gripping |= r == 0;
        Ok(r)
    }
    fn ready(&mut self) -> BiosResult {
        self.motion_with(false, |b, busy| {
            b.submit(
                Motion {
                    line: "READY".into(),
                    expect: Expect::Unknown,
                },
                busy,
            )
        })
    }
    fn set_tool(&mut self, tool: [f64; 6]) -> BiosResult {
        self.report_unasked()?;
        if self.outstanding.is_some() || !self.queue.is_empty() {
            self.note(
                "refused: the tool changes what a queued motion's target means: call \
                 TROLFinish(FINISH_WAIT) first"
                    .into(),
            );
            return Ok(BUSY);
        }
        let v = match self.frames.to_rapl(tool) {
            Ok(v) => v,
            Err(u) => return Ok(self.unsettled(u)),
        };
        match self.command(&format!("POINT TL {}", join(&v)))? {
            0 => {}
            c => return Ok(c),
        }
        let r = self.command("TOOL TL")?;
        if r == 0 {
            self.tool = tool;
        }
        Ok(r)
    }
    fn speed(&mut self, percent: u8) -> BiosResult {
        if !(1..=100).contains(&percent) {
            return Ok(code_of("BIOS_BAD_ARGUMENT"));
        }
        self.report_unasked()?;
        let r = self.command(&format!("SPEED {percent}"))?;
        if r == 0 {
            self.speed_setting = Some(percent);
            self.paced = false;
        }
        Ok(r)
    }
    fn trajectory(&mut self, points: &[trol_proto::application::Waypoint]) -> BiosResult {
        self.trajectory_paced(points)
    }
    fn position(&mut self, tag: Tag, mode: PosMode) -> Result<Location, BackendError> {
        let p = self.read_position(mode)?;
        Ok(match tag {
            Tag::Joint => Location::from_array6(Tag::Joint, p.joints.map(f64::to_radians)),
            Tag::Prec => Location::Prec(p.pulses.iter().map(|x| *x as i32).collect()),
            Tag::Cart => match self.frames.from_rapl(p.world) {
                Ok(v) => Location::from_array6(Tag::Cart, v),
                Err(u) => return Err(BackendError::Refused(self.unsettled(u))),
            },
        })
    }
    fn report(&mut self) -> Option<ArmReport> {
        // W2 is read-only; not while a motion answered at its end or a FINISH holds the
        // session (the view would end the FINISH at every update), nor once it failed.
        if self.closed || self.awaiting.is_some() || self.finishing || self.deferred.is_some() {
            return None;
        }
        let p = self.read_position(PosMode::Actual).ok()?;
        Some(ArmReport {
            joints: p.joints.map(f64::to_radians),
            moving: self.outstanding.is_some() || !self.queue.is_empty(),
            target: None,
            gripper_mm: None,
            tool: self.tool,
            homed: self.status.as_ref().map(|s| s.homed),
            ..ArmReport::default()
        })
    }
    fn idle(&mut self) {
        // Only a queue waiting for the motion under way to end needs a look; an error
        // already kept is told by the next call.
        if self.closed || self.queue.is_empty() || self.deferred.is_some() {
            return;
        }
        if self
            .last_poll
            .is_some_and(|(at, _)| at.elapsed() < Duration::from_millis(self.profile.poll_ms))
        {
            return;
        }
        match self.poll() {
            Ok(m) => self.last_poll = Some((std::time::Instant::now(), m)),
            // Told by the next call (Finish, or any motion).
            Err(e) => self.deferred = Some(e),
        }
    }
}

//! The manual's calls (TROLAppro ... TROLGetStatus) and the added ones (version, codes,
//! reply time, watchdog), each a thin skin over its description in the command table.

use super::*;

/// With the manual's LRC, which lets damage through that a CRC finds: a reply to a request
/// of `def` is plausible when its PCI's reserved bits are clear and it decodes in the form
/// the command has, a return value being one the command counts as success or one the
/// controller's code table knows. Layer 2 asks again for one that is not (the same bytes
/// twice are taken), so a damaged reply is not taken for another answer.
pub(super) fn reply_check(
    def: &CommandDef,
    codes: &'static CodeTable,
) -> trol_proto::link::Plausible {
    let def = *def;
    trol_proto::link::Plausible::new(move |pci, bytes| {
        if pci & 0xFE00 != 0 {
            return false;
        }
        let known = |v: Code| def.is_success(v.0) || v.info(codes).is_some();
        match Reply::decode(&def, bytes) {
            Ok(Reply::Code(v)) => known(v),
            Ok(Reply::Reals { value, .. }) => known(value),
            Ok(Reply::Status { last, .. }) => last.is_success() || last.info(codes).is_some(),
            Ok(_) => true,
            Err(_) => false,
        }
    })
}

pub(super) fn cart(v: &[f64]) -> Value {
    Value::Loc(Location::Cart(v.to_vec()))
}

/// A small whole number for the byte the table gives it; its range is checked by the table.
pub(super) fn small(def: &CommandDef, v: u16) -> Result<Value> {
    u8::try_from(v).map(Value::Int).map_err(|_| {
        Error::Argument(RequestError::Range {
            command: def.name,
            arg: def.args.first().map_or("(argument)", |a| a.name),
            what: format!("{v} out of range"),
        })
    })
}

/// A precision point's name starts with `#`, and only a precision point's (RAPL-II's rule).
pub(super) fn precision_name(def: &CommandDef, name: &str, tag: Tag) -> Result<()> {
    if name.starts_with('#') == (tag == Tag::Prec) {
        return Ok(());
    }
    Err(Error::Argument(RequestError::Range {
        command: def.name,
        arg: "locName",
        what: if tag == Tag::Prec {
            format!("{name:?}: a precision point's name starts with '#'")
        } else {
            format!("{name:?}: a name starting with '#' is a precision point's (use the prec form)")
        },
    }))
}

pub(super) fn loc_name(def: &CommandDef, name: &str) -> Result<Value> {
    LocName::new(name).map(Value::Name).map_err(|e| {
        Error::Argument(RequestError::Range {
            command: def.name,
            arg: "locName",
            what: e.to_string(),
        })
    })
}

impl Robot {
    /// TROLAppro: approach the named location, displaced by `disp` (x y z yaw pitch roll,
    /// 1..6 values) in its tool frame.
    pub fn appro(&mut self, name: &str, disp: &[f64], straight: bool) -> Result<()> {
        let args = [
            loc_name(&table::APPRO, name)?,
            cart(disp),
            Value::Flag(straight),
        ];
        self.cat1(&table::APPRO, &args).map(drop)
    }

    /// TROLApproII: approach a given location (cartesian or precision point).
    pub fn appro_ii(&mut self, target: &Location, disp: &[f64], straight: bool) -> Result<()> {
        let args = [
            Value::Loc(target.clone()),
            cart(disp),
            Value::Flag(straight),
        ];
        self.cat1(&table::APPRO_II, &args).map(drop)
    }

    /// TROLClose: close the gripper with `force` percent (1..100).
    pub fn close_gripper(&mut self, force: u16) -> Result<()> {
        let args = [small(&table::CLOSE, force)?];
        self.cat1(&table::CLOSE, &args).map(drop)
    }

    /// TROLClose under its old name, which read as closing the connection (as Python's
    /// `Robot.close()` does).
    #[deprecated(note = "use close_gripper: close reads as closing the connection")]
    pub fn close(&mut self, force: u16) -> Result<()> {
        self.close_gripper(force)
    }

    /// TROLDepart: move by `disp` in the tool frame from where the arm is.
    pub fn depart(&mut self, disp: &[f64], straight: bool) -> Result<()> {
        self.cat1(&table::DEPART, &[cart(disp), Value::Flag(straight)])
            .map(drop)
    }

    /// TROLFinish(FINISH_WAIT): wait until the arm and the gripper are done. The wait polls
    /// FINISH_STATUS every 20 ms instead of holding the line, so a controller that dies is
    /// noticed within a link timeout (about a second), not minutes later.
    pub fn finish(&mut self) -> Result<()> {
        let mut wait = self.finish_wait();
        while self.is_moving()? {
            wait.check(self)?;
            std::thread::sleep(POLL);
        }
        Ok(())
    }

    /// The bound of a polled Finish(FINISH_WAIT), as the manual's one long request had:
    /// after the reply timeout (SetL3_TO_Intervall) ErrAppTimeOut decides, and again each
    /// time the wait it granted runs out. The default handler grants Finish(FINISH_WAIT) no
    /// limit (the manual's default); an application's may end the wait.
    pub fn finish_wait(&self) -> FinishWait {
        FinishWait {
            started: std::time::Instant::now(),
            limit: self.transactor.reply_timeout(),
        }
    }

    /// [`Robot::finish`] that gives up when `cancel` becomes true (set from a Ctrl-C handler or
    /// another thread): it then sends Halt, waits for the arm to brake to a stop, and returns
    /// [`Waited::Halted`]. `cancel` is left as it is; the caller resets it.
    pub fn finish_unless(&mut self, cancel: &AtomicBool) -> Result<Waited> {
        let mut wait = self.finish_wait();
        loop {
            if cancel.load(Ordering::SeqCst) {
                self.halt()?;
                loop {
                    match self.is_moving() {
                        Ok(true) => std::thread::sleep(POLL),
                        Ok(false) => return Ok(Waited::Halted),
                        // The controller answered the Halt once the arm stood; a Finish that
                        // then reports a halted Home (BIOS_NOT_HOMED: the axes not yet homed
                        // stay so) reports an arm that stands: the wait was cancelled. Any
                        // other failure (the controller unsure, say) is the caller's to see.
                        Err(Error::Refused { code, .. })
                            if self
                                .codes
                                .iter()
                                .any(|c| c.value == code.0 && c.name == "BIOS_NOT_HOMED") =>
                        {
                            return Ok(Waited::Halted);
                        }
                        Err(e) => return Err(e),
                    }
                }
            }
            if !self.is_moving()? {
                return Ok(Waited::Idle);
            }
            wait.check(self)?;
            std::thread::sleep(POLL);
        }
    }

    /// One poll of a wait for the arm: whether it still moves. A program that shares the
    /// robot between threads (a `Mutex<Robot>`) waits with [`wait_idle`], which takes the lock
    /// only for each poll, so another thread's `halt()` gets through.
    pub fn poll_idle(&mut self) -> Result<bool> {
        self.is_moving().map(|moving| !moving)
    }

    /// TROLFinish(FINISH_WAIT) as one request on the line: the controller answers when the arm
    /// is done, and the line is busy until then (the manual's way; [`Robot::finish`] polls).
    pub fn finish_on_controller(&mut self) -> Result<()> {
        self.cat1(&table::FINISH, &[Value::Int(FINISH_WAIT)])
            .map(drop)
    }

    /// TROLFinish(FINISH_STATUS): whether the arm or the gripper still moves.
    pub fn is_moving(&mut self) -> Result<bool> {
        self.cat1(&table::FINISH, &[Value::Int(FINISH_STATUS)])
            .map(|v| v == 1)
    }

    /// TROLGrip: the fingers to `dist` mm (0..50).
    pub fn grip(&mut self, dist: u16) -> Result<()> {
        let args = [small(&table::GRIP, dist)?];
        self.cat1(&table::GRIP, &args).map(drop)
    }

    /// TROLHalt: stop all motion.
    pub fn halt(&mut self) -> Result<()> {
        self.cat1(&table::HALT, &[]).map(drop)
    }

    /// TROLHome: home one axis (1..6) or all (0); returns when homing is done (waiting as
    /// [`Robot::finish`] does).
    pub fn home(&mut self, axis: u16) -> Result<()> {
        let args = [small(&table::HOME, axis)?];
        self.cat1(&table::HOME, &args)?;
        self.finish()
    }

    /// TROLJog: move the tool by dx, dy, dz (1..3 values) in the world frame, orientation kept.
    pub fn jog(&mut self, d: &[f64], straight: bool) -> Result<()> {
        self.cat1(&table::JOG, &[cart(d), Value::Flag(straight)])
            .map(drop)
    }

    /// TROLJoint: move joint `joint` (1..6) by `radians`.
    pub fn joint(&mut self, joint: u16, radians: f64) -> Result<()> {
        let args = [small(&table::JOINT, joint)?, Value::Real(radians)];
        self.cat1(&table::JOINT, &args).map(drop)
    }

    /// TROLMA: all joints to absolute angles (1..6 values, the rest 0).
    pub fn ma(&mut self, joints: &[f64]) -> Result<()> {
        let args = [Value::Loc(Location::Joint(joints.to_vec()))];
        self.cat1(&table::MA, &args).map(drop)
    }

    /// TROLTrajectory: one motion through `points` (each a time in seconds from the start
    /// and six joint angles), as a planner's trajectory runs (docs/protocol.md
    /// "Trajectory"). Returns how the controller runs it: [`Timing::Timed`] (the simulated
    /// A465, a MARS 8: at the given times, or refused with BIOS_TOO_FAST before anything
    /// moves where they ask more than the arm's limits at the speed setting), or
    /// [`Timing::Untimed`] (one joint move to each waypoint at the speed setting). Wait
    /// for its end with [`Robot::finish`]. No points, more than [`crate::MAX_WAYPOINTS`], or
    /// times that do not increase are TROL_ERR_ARG_RANGE, and nothing is sent.
    pub fn trajectory(&mut self, points: &[Waypoint]) -> Result<Timing> {
        let args = [Value::Path(points.to_vec())];
        match self.cat1(&table::TRAJECTORY, &args)? {
            table::TRAJECTORY_UNTIMED => Ok(Timing::Untimed),
            _ => Ok(Timing::Timed),
        }
    }

    /// TROLMI: all joints by increments.
    pub fn mi(&mut self, joints: &[f64]) -> Result<()> {
        let args = [Value::Loc(Location::Joint(joints.to_vec()))];
        self.cat1(&table::MI, &args).map(drop)
    }

    /// TROLMove: to the named location.
    pub fn move_to(&mut self, name: &str, straight: bool) -> Result<()> {
        let args = [loc_name(&table::MOVE, name)?, Value::Flag(straight)];
        self.cat1(&table::MOVE, &args).map(drop)
    }

    /// TROLMoveII: to a given location (cartesian or precision point).
    pub fn move_ii(&mut self, target: &Location, straight: bool) -> Result<()> {
        let args = [Value::Loc(target.clone()), Value::Flag(straight)];
        self.cat1(&table::MOVE_II, &args).map(drop)
    }

    /// TROLOpen: open the gripper with `force` percent (1..100).
    pub fn open_gripper(&mut self, force: u16) -> Result<()> {
        let args = [small(&table::OPEN, force)?];
        self.cat1(&table::OPEN, &args).map(drop)
    }

    /// TROLReady: to the READY pose.
    pub fn ready(&mut self) -> Result<()> {
        self.cat1(&table::READY, &[]).map(drop)
    }

    /// TROLSetToolTransform: x y z yaw pitch roll of the tool tip in the tool frame.
    pub fn set_tool_transform(&mut self, tool: &[f64]) -> Result<()> {
        self.cat1(&table::SET_TOOL_TRANSFORM, &[cart(tool)])
            .map(drop)
    }

    /// TROLSpeed: percent of the maximum speed (1..150).
    pub fn speed(&mut self, percent: u16) -> Result<()> {
        let args = [small(&table::SPEED, percent)?];
        self.cat1(&table::SPEED, &args).map(drop)
    }

    /// TROLGetPosition: the position in the form `tag`, commanded or actual. A reply in
    /// another form than the one asked for is TROL_ERR_BAD_RSIZE.
    pub fn position(&mut self, tag: Tag, mode: PosMode) -> Result<Location> {
        let mode = match mode {
            PosMode::Commanded => table::POS_COMMANDED,
            PosMode::Actual => table::POS_ACT,
        };
        let def = &table::GET_POSITION;
        match self.call(def, &[Value::Int(tag as u8), Value::Int(mode)])? {
            Reply::Position(loc) if loc.tag() == tag => Ok(loc),
            other => Err(Error::BadReply {
                command: def.name,
                len: other.encode().len(),
            }),
        }
    }

    /// TROLTerminatePCP: end server mode.
    pub fn terminate_pcp(&mut self) -> Result<()> {
        self.cat1(&table::TERMINATE_PCP, &[]).map(drop)
    }

    /// TROLGetStatus: whether the last CAT1/CAT2 command called the BIOS, and the BIOS's
    /// value or the TROL code that kept it from being called.
    pub fn status(&mut self) -> Result<(bool, Code)> {
        self.status_record().map(|s| (s.bios_called, s.last))
    }

    /// TROLGetStatus in full: also which transaction the status belongs to (compare with
    /// [`Robot::last_transaction`] after a failed call) and the controller's epoch (it changes
    /// when the controller restarts).
    ///
    /// After a CAT1/CAT2 call whose outcome never came back, the status is that call's,
    /// never an older one's (issue 67; docs/reliability.md, "Exactly once"): where the
    /// controller's status belongs to another transaction, TROL answers for the call from
    /// what the controller's status shows. The controller kept its memory (the same epoch),
    /// so the call never ran there: not called, TROL_ERR_COMM. The controller restarted
    /// since (another epoch) and cannot place it: called, TROL_ERR_ROBOT_UNSURE (it may
    /// have run before the restart; look at the arm before sending it again). Either way
    /// the record names the call's transaction. A controller of 1998 (epoch 0) says only
    /// what the manual's GetStatus says.
    pub fn status_record(&mut self) -> Result<StatusRecord> {
        let def = &table::GET_STATUS;
        match self.call(def, &[])? {
            Reply::Status {
                bios_called,
                last,
                transaction,
                epoch,
            } => {
                let reported = StatusRecord {
                    bios_called,
                    last,
                    transaction,
                    epoch,
                };
                let record = match self.doubt {
                    Some(d) if epoch != 0 && transaction != d.transaction => {
                        let kept = d.epoch == Some(epoch);
                        tracing::info!(
                            "GetStatus speaks of transaction {transaction}, not of the call \
                             in doubt ({}); the controller {}",
                            d.transaction,
                            if kept {
                                "kept its memory, so that call never ran there"
                            } else {
                                "restarted since, so that call may have run"
                            }
                        );
                        StatusRecord {
                            bios_called: !kept,
                            last: if kept {
                                TROL_ERR_COMM
                            } else {
                                TROL_ERR_ROBOT_UNSURE
                            },
                            transaction: d.transaction,
                            epoch,
                        }
                    }
                    _ => reported,
                };
                self.epoch = Some(epoch);
                Ok(record)
            }
            other => Err(Error::BadReply {
                command: def.name,
                len: other.encode().len(),
            }),
        }
    }

    /// TROLGetVersion: the protocol version the controller speaks and what drives its arm.
    /// [`crate::check_server`] (InitTROL, `trol init`) checks it with
    /// [`Robot::check_version`].
    pub fn version(&mut self) -> Result<ControllerVersion> {
        let def = &table::GET_VERSION;
        match self.call(def, &[])? {
            Reply::Version { protocol, kind } => Ok(ControllerVersion { protocol, kind }),
            other => Err(Error::BadReply {
                command: def.name,
                len: other.encode().len(),
            }),
        }
    }

    /// TROLGetGripper: the fingers' opening (mm) and what they hold, to check a grasp (a
    /// close that found no object leaves [`Held::Nothing`](trol_proto::application::Held)).
    /// A controller that cannot read its gripper refuses with TROL_ERR_UNKNOWN.
    pub fn gripper(&mut self) -> Result<Gripper> {
        let def = &table::GET_GRIPPER;
        match self.call(def, &[])? {
            Reply::Gripper(g) => Ok(g),
            other => Err(Error::BadReply {
                command: def.name,
                len: other.encode().len(),
            }),
        }
    }

    /// TROLHere: store where the arm is (commanded) under `name`, in the form `tag`
    /// (cartesian, joint angles, or a precision point, whose name starts with `#`). On the
    /// simulator and a MARS 8 the table is TROL's (kept across a restart by
    /// [`Robot::save_locations`]); on a C500 it is the controller's own (docs/teach.md).
    pub fn here(&mut self, name: &str, tag: Tag) -> Result<()> {
        let def = &table::HERE;
        let args = [loc_name(def, name)?, Value::Int(tag as u8)];
        precision_name(def, name, tag)?;
        self.cat1(def, &args).map(drop)
    }

    /// TROLDefine: store `loc` (six values: cartesian, joint angles or encoder counts) under
    /// `name` (a precision point's name starts with `#`).
    pub fn define(&mut self, name: &str, loc: &Location) -> Result<()> {
        let def = &table::DEFINE;
        let args = [loc_name(def, name)?, Value::Loc(loc.clone())];
        precision_name(def, name, loc.tag())?;
        self.cat1(def, &args).map(drop)
    }

    /// TROLDeleteLocation: forget the location `name` (TROL_ERR_LOCATION if there is none).
    pub fn delete_location(&mut self, name: &str) -> Result<()> {
        let def = &table::DELETE_LOCATION;
        let args = [loc_name(def, name)?];
        self.cat1(def, &args).map(drop)
    }

    /// TROLSaveLocations: keep the location table across a restart (the simulator writes its
    /// locations file; without one it answers BIOS_NO_FILE).
    pub fn save_locations(&mut self) -> Result<()> {
        self.cat1(&table::SAVE_LOCATIONS, &[]).map(drop)
    }

    /// TROLListLocations: the controller's table, each name with its location, sorted by
    /// name.
    pub fn locations(&mut self) -> Result<Vec<(String, Location)>> {
        let def = &table::LIST_LOCATIONS;
        match self.call(def, &[])? {
            Reply::Locations(all) => Ok(all
                .into_iter()
                .map(|(n, l)| (n.as_str().to_string(), l))
                .collect()),
            other => Err(Error::BadReply {
                command: def.name,
                len: other.encode().len(),
            }),
        }
    }

    /// TROLGetCodes: the controller's BIOS codes, each with its name and meaning.
    pub fn get_codes(&mut self) -> Result<Vec<CodeEntry>> {
        let def = &table::GET_CODES;
        match self.call(def, &[])? {
            Reply::Codes(codes) => Ok(codes),
            other => Err(Error::BadReply {
                command: def.name,
                len: other.encode().len(),
            }),
        }
    }

    /// Ask the controller its version and refuse one that speaks another protocol than this
    /// library, with what to do; then ask its BIOS codes (TROLGetCodes) and name them from
    /// then on as that controller does ([`Robot::codes`]). A controller that does not know
    /// TROLGetCodes keeps the table the connection had.
    pub fn check_version(&mut self) -> Result<ControllerVersion> {
        let v = match self.version() {
            Ok(v) => v,
            Err(e) if e.code() == trol_proto::application::code::TROL_ERR_UNKNOWN => {
                return Err(SetupError::Incompatible {
                    ours: table::PROTOCOL_VERSION,
                    theirs: None,
                    kind: None,
                }
                .into());
            }
            Err(e) => return Err(e),
        };
        if v.protocol != table::PROTOCOL_VERSION {
            return Err(SetupError::Incompatible {
                ours: table::PROTOCOL_VERSION,
                theirs: Some(v.protocol),
                kind: Some(v.kind),
            }
            .into());
        }
        // This protocol's controller remembers its last request: a request whose
        // transaction failed goes again, unless the application chose otherwise.
        if !self.repeats_set {
            self.transactor.set_repeats(trol_comm::DEFAULT_REPEATS);
        }
        match self.get_codes() {
            Ok(codes) => self.codes = crate::codes::intern(&codes),
            // Link failures are the connection's; a controller that does not know the
            // command, or answers it in a form this end does not take, keeps the default.
            Err(e @ Error::Link { .. }) => return Err(e),
            Err(e) => tracing::warn!(
                "the controller's BIOS codes (TROLGetCodes): {e}; its codes are named by number"
            ),
        }
        // How long it takes to answer: each call waits that and a margin for its reply; and
        // whether it says "still working" meanwhile: then a silence ends the wait sooner.
        match self.reply_times() {
            Ok((t, keepalive)) => {
                self.set_reply_time(t);
                self.set_keepalive(keepalive);
            }
            Err(e @ Error::Link { .. }) => return Err(e),
            other => {
                self.set_keepalive(None);
                tracing::debug!(
                    "TROLGetReplyTime: {other:?}; calls wait the manual's reply timeout"
                )
            }
        }
        Ok(v)
    }

    /// TROLGetReplyTime: the longest the controller takes to answer a request (the version
    /// check asks it, and each call then waits that and a margin for its reply).
    pub fn reply_time(&mut self) -> Result<Duration> {
        self.reply_times().map(|(t, _)| t)
    }

    /// TROLGetReplyTime in full: the longest answer, and how often the controller says
    /// "still working" while it executes (`None`: it does not, or is older than that).
    pub(super) fn reply_times(&mut self) -> Result<(Duration, Option<Duration>)> {
        let secs = |v: f64| Duration::from_secs_f64(v.min(600.0));
        match self.call(&table::GET_REPLY_TIME, &[])? {
            Reply::Reals { values, .. }
                if values.iter().all(|t| t.is_finite() && *t >= 0.0) && !values.is_empty() =>
            {
                let keepalive = values.get(1).filter(|k| **k > 0.0).map(|k| secs(*k));
                Ok((secs(values[0]), keepalive))
            }
            _ => Err(Error::BadReply {
                command: table::GET_REPLY_TIME.name,
                len: 0,
            }),
        }
    }

    /// TROLSetWatchdog: the controller halts the arm when no call arrives for `limit` (in
    /// tenths of a second, at most 25 s; zero turns it off), as ur_rtde's setWatchdog. Every
    /// call feeds it, and so do the polls of a wait ([`Robot::finish`]): it catches an
    /// application that hangs or dies, or a line that is cut. The arm is halted once, and
    /// the next call works as usual.
    pub fn set_watchdog(&mut self, limit: Duration) -> Result<()> {
        let def = &table::SET_WATCHDOG;
        let tenths = limit.as_millis().div_ceil(100);
        let tenths = u16::try_from(tenths).unwrap_or(u16::MAX);
        let args = [small(def, tenths)?];
        self.cat1(def, &args).map(drop)
    }

    /// The transaction number of the last request sent (the PCI's low byte; GetStatus's
    /// [`StatusRecord::transaction`] names the one its status belongs to). Take it at once
    /// after the call that failed: every request takes a number, GetStatus's too.
    pub fn last_transaction(&self) -> u8 {
        self.transactor.transaction_number()
    }
}

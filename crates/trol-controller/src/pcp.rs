//! The PCP server's layer 4 (manual, "Erstellen von Kommando-Handlern", "PCP\PCPTROL.C"):
//! one dispatch table per transaction class, indexed by `code - 64·class`, and the
//! bookkeeping of BIOSCalled and lastErrorCode for GetStatus.
//!
//! Each entry holds a command's description and its handler. The server decodes a request
//! from the description (size, then ranges, with the manual's codes) before the handler runs,
//! so a handler gets checked, typed arguments. It is sans-IO: [`Pcp::handle`] takes a
//! request's bytes and returns the reply's bytes (the manual's MsgReceived), or says that the
//! reply waits until the arm is idle; [`Pcp::poll`] then asks the backend and gives the reply
//! when it is due. [`crate::Controller`] runs it behind layer 3.

use trol_proto::application::code::{
    Code, TROL_ERR_ARG_RANGE, TROL_ERR_HALTED, TROL_ERR_ROBOT_UNSURE, TROL_RETVAL_RANGE,
};
use trol_proto::application::record::Value;
use trol_proto::application::table;
use trol_proto::application::{
    Catalog, CatalogError, Class, CommandDef, LocName, Location, Reply, Tag, Waypoint,
};

use crate::backend::{Backend, PosMode, Target};

/// What GetStatus reports: whether the last CAT1/CAT2 command called the BIOS, and the
/// BIOS's value or the TROL code that kept it from being called.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Status {
    /// BIOSCalled.
    pub bios_called: bool,
    /// lastErrorCode.
    pub last_error_code: Code,
    /// The transaction number of the request this status belongs to.
    pub transaction: u8,
    /// The transaction number of the request being handled.
    pub current: u8,
}

impl Status {
    /// Record a BIOS call's value; returns what the reply carries (TROL_RETVAL_RANGE for a
    /// value in TROL's range, as CAT2 handlers must do themselves).
    pub fn record_bios(&mut self, value: i16) -> Code {
        self.transaction = self.current;
        self.bios_called = true;
        self.last_error_code = Code(value);
        if Code(value).is_trol() {
            TROL_RETVAL_RANGE
        } else {
            Code(value)
        }
    }

    /// Record that the BIOS was not called, and why. TROL_ERR_ROBOT_UNSURE says the call
    /// went out before the link failed: it counts as called.
    pub fn record_refusal(&mut self, code: Code) {
        self.transaction = self.current;
        self.bios_called = code == TROL_ERR_ROBOT_UNSURE;
        self.last_error_code = code;
    }
}

/// What a CAT1 handler did: called the BIOS, which returned this value, and whether the
/// reply is due now or once the arm is idle (Finish(FINISH_WAIT), Home).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Executed {
    /// Reply now.
    Now(i16),
    /// Reply once the backend no longer moves (or with this value at once if it failed).
    WhenIdle(i16),
}

/// A CAT1 handler: gets the decoded, checked arguments, calls the BIOS once. `Err(code)`: the
/// BIOS was not called, for this TROL code. The server builds the reply (manual: CAT1
/// handlers build no reply themselves) and keeps GetStatus's record.
pub type Cat1Handler<B> = fn(&mut B, &Call<'_>) -> Result<Executed, Code>;

/// What CAT2..CAT4 handlers work with.
pub struct Context<'a, B> {
    /// The backend.
    pub backend: &'a mut B,
    /// BIOSCalled / lastErrorCode (CAT2 handlers must keep it).
    pub status: &'a mut Status,
    /// Set to end server mode once the reply is sent (TerminatePCP).
    pub terminate: &'a mut bool,
    /// The server's epoch; 0 when GetStatus answers in the manual's 4 bytes (a host or a
    /// server that speaks only the manual's protocol).
    pub epoch: u16,
    /// The watchdog's limit: the arm is halted when no transaction arrives for this long
    /// (SetWatchdog; `None`: off).
    pub watchdog: &'a mut Option<std::time::Duration>,
    /// How often the server says "still working" while this host's requests execute, if it
    /// does (TROLGetReplyTime tells the host; docs/protocol.md, "Keep-alive").
    pub keepalive: Option<std::time::Duration>,
    /// Why the request was refused, in words, for the controller's log (a file that could
    /// not be written: which, and what the system said).
    pub note: &'a mut Option<String>,
}

/// A handler of CAT2..CAT4: gets the decoded arguments and builds its reply itself.
pub type OtherHandler<B> = fn(&mut Context<'_, B>, &Call<'_>) -> Reply;

/// A dispatch-table entry's handler.
pub enum Handler<B> {
    /// A CAT1 command.
    Cat1(Cat1Handler<B>),
    /// A CAT2, CAT3 or CAT4 command.
    Other(OtherHandler<B>),
}

impl<B> Clone for Handler<B> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<B> Copy for Handler<B> {}

/// Why a command could not be added.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum RegisterError {
    /// The code is not the next one of its class (the manual's tables have no gaps).
    #[error("code {code} leaves a gap or repeats one: the next {class} code is {next}")]
    Gap {
        /// The code.
        code: u8,
        /// Its class.
        class: Class,
        /// The next free code of the class.
        next: usize,
    },
    /// A CAT1 code with a handler of another class, or the reverse.
    #[error("code {code} is {class}; CAT1 codes take a CAT1 handler and the others not")]
    WrongHandler {
        /// The code.
        code: u8,
        /// Its class.
        class: Class,
    },
    /// The name (or code) is taken.
    #[error("{0}")]
    Taken(#[from] CatalogError),
}

/// The longest a Halt from the pendant waits for the arm to stand before it answers
/// TROL_ERR_NOT_STOPPED (the A465 brakes within 0.4 s).
const HALT_ASIDE_LIMIT: std::time::Duration = std::time::Duration::from_secs(2);

/// The reply a long call waits to send.
#[derive(Clone, Copy, Debug)]
struct Pending {
    value: Code,
    /// The command whose reply waits (Finish(FINISH_WAIT), Halt).
    code: u8,
}

/// The PCP server's layer 4 over a backend.
pub struct Pcp<B> {
    backend: B,
    tables: [Vec<Handler<B>>; 4],
    catalog: Catalog,
    status: Status,
    terminate: bool,
    pending: Option<Pending>,
    epoch: u16,
    watchdog: Option<std::time::Duration>,
    /// The host speaks only the manual's protocol (it activated with the bare line): GetStatus
    /// in the manual's 4 bytes.
    manual_host: bool,
    /// This server speaks only the manual's protocol (a 1998 controller, simulated): the
    /// added commands are unknown, GetStatus has the manual's 4 bytes.
    manual_only: bool,
    /// Requests run so far ([`Pcp::handle`] calls).
    handled: u64,
    /// The request being handled came another way than the TROL line ([`Pcp::handle_aside`]).
    aside: bool,
    /// The host on the line started a motion that no Finish of its own has seen end.
    open_motion: bool,
    /// That motion was halted by someone else (the pendant, the watchdog): the host's next
    /// Finish that finds the arm standing answers TROL_ERR_HALTED, once.
    halted_aside: bool,
    /// The keep-alive the server gives the host on the line ([`Pcp::set_keepalive`]).
    keepalive: Option<std::time::Duration>,
    /// Why the last request was refused, in words, not yet taken ([`Pcp::take_note`]).
    note: Option<String>,
}

/// What [`Pcp::handle`] did with a request.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Handled {
    /// Send this reply.
    Reply(Vec<u8>),
    /// The reply waits until the backend is idle: call [`Pcp::poll`].
    Pending,
}

impl<B: Backend> Pcp<B> {
    /// A server with every built-in command in its table (the manual's `entrypoint()`).
    pub fn new(backend: B) -> Pcp<B> {
        let mut pcp = Pcp {
            backend,
            tables: [Vec::new(), Vec::new(), Vec::new(), Vec::new()],
            catalog: Catalog::builtin(),
            status: Status::default(),
            terminate: false,
            pending: None,
            epoch: new_epoch(),
            watchdog: None,
            manual_host: false,
            manual_only: false,
            handled: 0,
            aside: false,
            open_motion: false,
            keepalive: None,
            note: None,
            halted_aside: false,
        };
        for def in table::BUILTIN {
            let handler = match def.class() {
                Class::Cat1 => Handler::Cat1(builtin_cat1::<B> as Cat1Handler<B>),
                _ => Handler::Other(builtin_other::<B> as OtherHandler<B>),
            };
            pcp.enter(def, handler)
                .expect("the built-in codes have no gaps");
        }
        pcp
    }

    /// Add a command (manual, "Modifikation der betroffenen Source-Dateien", step 3:
    /// `dispatchTableX[code - X*64] = handler`). Its code must be the next one of its class,
    /// so that the table has no gaps; a CAT1 code needs a [`Handler::Cat1`]; its name must be
    /// new. From then on the server decodes, checks, dispatches and logs it by `def`.
    pub fn register(&mut self, def: CommandDef, handler: Handler<B>) -> Result<(), RegisterError> {
        self.catalog.add(def)?;
        self.enter(&def, handler)
    }

    fn enter(&mut self, def: &CommandDef, handler: Handler<B>) -> Result<(), RegisterError> {
        let class = def.class();
        let table = &self.tables[class.index()];
        let next = class.base() as usize + table.len();
        if def.code as usize != next {
            return Err(RegisterError::Gap {
                code: def.code,
                class,
                next,
            });
        }
        if matches!(handler, Handler::Cat1(_)) != (class == Class::Cat1) {
            return Err(RegisterError::WrongHandler {
                code: def.code,
                class,
            });
        }
        self.tables[class.index()].push(handler);
        Ok(())
    }

    /// The largest code of a class (LAST_CATx_CODE), one below the base if it is empty.
    pub fn last_code(&self, class: Class) -> i32 {
        class.base() as i32 + self.tables[class.index()].len() as i32 - 1
    }

    /// The commands this server knows: the built-in ones and the registered ones.
    pub fn catalog(&self) -> &Catalog {
        &self.catalog
    }

    /// The backend.
    pub fn backend(&self) -> &B {
        &self.backend
    }

    /// The backend, mutably.
    pub fn backend_mut(&mut self) -> &mut B {
        &mut self.backend
    }

    /// BIOSCalled and lastErrorCode.
    pub fn status(&self) -> Status {
        self.status
    }

    /// The number the server drew when it started (GetStatus reports it, so a host notices a
    /// restart).
    pub fn epoch(&self) -> u16 {
        self.epoch
    }

    /// Go on from what a controller before this one knew (its journal,
    /// [`crate::journal::Restored`]): its epoch and GetStatus's record.
    pub fn restore(&mut self, epoch: u16, status: Status) {
        self.epoch = epoch;
        self.status = status;
    }

    /// The watchdog's limit (SetWatchdog), if it is on: the controller loop halts the arm when
    /// no transaction arrives for this long.
    pub fn watchdog(&self) -> Option<std::time::Duration> {
        self.watchdog
    }

    /// The transaction number of the request about to be handled (the PCI's low byte), for
    /// GetStatus's record.
    pub fn set_transaction(&mut self, number: u8) {
        self.status.current = number;
    }

    /// Why the last request was refused, in words, once (for the controller's log).
    pub fn take_note(&mut self) -> Option<String> {
        self.note.take().or_else(|| self.backend.take_note())
    }

    /// Say how often the server says "still working" while the host's requests execute
    /// (`None`: it does not), for TROLGetReplyTime's answer.
    pub fn set_keepalive(&mut self, keepalive: Option<std::time::Duration>) {
        self.keepalive = keepalive;
    }

    /// Whether the host speaks only the manual's protocol (it activated with the bare `PCP
    /// TROL`): GetStatus answers in the manual's 4 bytes, without transaction and epoch.
    pub fn set_manual_host(&mut self, manual: bool) {
        self.manual_host = manual;
    }

    /// Speak only the manual's protocol, as the 1998 PCP server did: the commands this
    /// successor added ([`table::ADDED`]) are unknown, GetStatus has the manual's 4 bytes.
    pub fn set_manual_only(&mut self, manual: bool) {
        self.manual_only = manual;
    }

    /// Whether GetStatus answers in the manual's 4 bytes (a 1998 host, or a server that
    /// speaks only the manual's protocol).
    pub fn speaks_manual(&self) -> bool {
        self.manual_host || self.manual_only
    }

    /// Whether TerminatePCP asked to end server mode (reading clears it).
    pub fn take_terminate(&mut self) -> bool {
        std::mem::take(&mut self.terminate)
    }

    /// How many requests this server has run ([`Pcp::handle`] calls, refused ones included):
    /// what a log that counts every execution must add up to.
    pub fn handled(&self) -> u64 {
        self.handled
    }

    /// Whether a reply waits for the arm to be idle.
    pub fn is_pending(&self) -> bool {
        self.pending.is_some()
    }

    /// Execute a request that came another way than the TROL line (the browser's pendant,
    /// [`crate::Pendant`]): as [`Pcp::handle`], but what GetStatus tells the host about its
    /// own last call is kept, and a reply that would wait (Finish(FINISH_WAIT)) is refused
    /// (TROL_ERR_UNKNOWN; the pendant asks FINISH_STATUS instead).
    pub fn handle_aside(&mut self, request: &[u8]) -> Vec<u8> {
        let kept = self.status;
        let pending = self.pending;
        self.aside = true;
        let mut handled = self.handle(request);
        if handled == Handled::Pending && request.first() == Some(&table::HALT.code) {
            // A Halt answers once the arm stands (the simulator's brakes for at most
            // 0.4 s; a real controller's backend has seen it standing already).
            let until = std::time::Instant::now() + HALT_ASIDE_LIMIT;
            handled = loop {
                if let Some(r) = self.poll() {
                    break Handled::Reply(r);
                }
                if std::time::Instant::now() >= until {
                    self.pending = None;
                    break Handled::Reply(
                        Reply::Code(trol_proto::application::code::TROL_ERR_NOT_STOPPED).encode(),
                    );
                }
                std::thread::sleep(std::time::Duration::from_millis(5));
            };
        }
        self.aside = false;
        if request.first() == Some(&table::HALT.code) {
            self.halted_by_someone_else();
        }
        let reply = match handled {
            Handled::Reply(r) => r,
            Handled::Pending => {
                Reply::Code(trol_proto::application::code::TROL_ERR_UNKNOWN).encode()
            }
        };
        self.status = kept;
        self.pending = pending;
        reply
    }

    /// The arm was halted by someone else than the host on the line (the pendant, the
    /// watchdog): if the host has a motion under way, its next Finish that finds the arm
    /// standing answers TROL_ERR_HALTED (issue 37: a Halt from anywhere is seen everywhere).
    pub fn halted_by_someone_else(&mut self) {
        if self.open_motion && !self.manual_only {
            self.halted_aside = true;
        }
    }

    /// Keep track of the host's motions: a motion opens, the host's own Halt or a Finish
    /// that saw the arm standing closes. A Finish's success `reply` becomes TROL_ERR_HALTED
    /// when someone else halted the motion (GetStatus says so too).
    fn follow_motions(&mut self, code: u8, reply: Code) -> Code {
        if self.aside || self.manual_only {
            return reply;
        }
        if code == table::FINISH.code {
            // Anything but "still moving" ends the wait: a failure was told as it is.
            if reply != Code(1) {
                self.open_motion = false;
                let halted = std::mem::take(&mut self.halted_aside);
                if halted && reply == Code(0) {
                    self.status.transaction = self.status.current;
                    self.status.bios_called = true;
                    self.status.last_error_code = TROL_ERR_HALTED;
                    return TROL_ERR_HALTED;
                }
            }
        } else if code == table::HALT.code {
            self.open_motion = false;
            self.halted_aside = false;
        } else if code != table::SPEED.code
            && code != table::SET_TOOL_TRANSFORM.code
            && reply == Code(0)
        {
            self.open_motion = true;
            self.halted_aside = false;
        }
        reply
    }

    /// MsgReceived: execute a request; its reply, or [`Handled::Pending`].
    pub fn handle(&mut self, request: &[u8]) -> Handled {
        self.handled += 1;
        let code = request.first().copied();
        let class = code.map(Class::of);
        let (def, values) = match self.catalog.decode(request) {
            Ok((def, values)) => (*def, values),
            Err(e) => {
                // A refused CAT1/CAT2 request did not call the BIOS; GetStatus says so.
                if matches!(class, None | Some(Class::Cat1 | Class::Cat2)) {
                    self.status.record_refusal(e.code());
                }
                return Handled::Reply(Reply::Code(e.code()).encode());
            }
        };
        if self.manual_only && table::ADDED.contains(&def.code) {
            return Handled::Reply(
                Reply::Code(trol_proto::application::code::TROL_ERR_UNKNOWN).encode(),
            );
        }
        let index = (def.code - def.class().base()) as usize;
        let handler = self.tables[def.class().index()][index];
        let call = Call {
            def: &def,
            args: &values,
        };
        match handler {
            Handler::Cat1(h) => match h(&mut self.backend, &call) {
                Ok(Executed::Now(v)) => {
                    let value = self.status.record_bios(v);
                    let value = self.follow_motions(def.code, value);
                    Handled::Reply(Reply::Code(value).encode())
                }
                Ok(Executed::WhenIdle(v)) => {
                    let value = self.status.record_bios(v);
                    if !value.is_success() {
                        return Handled::Reply(Reply::Code(value).encode());
                    }
                    self.pending = Some(Pending {
                        value,
                        code: def.code,
                    });
                    match self.poll() {
                        Some(reply) => Handled::Reply(reply),
                        None => Handled::Pending,
                    }
                }
                Err(code) => {
                    self.status.record_refusal(code);
                    let code = self.follow_motions(def.code, code);
                    Handled::Reply(Reply::Code(code).encode())
                }
            },
            Handler::Other(h) => {
                let mut ctx = Context {
                    backend: &mut self.backend,
                    status: &mut self.status,
                    terminate: &mut self.terminate,
                    // The manual's GetStatus has no epoch (nor transaction).
                    epoch: if self.manual_host || self.manual_only {
                        0
                    } else {
                        self.epoch
                    },
                    watchdog: &mut self.watchdog,
                    keepalive: self.keepalive,
                    note: &mut self.note,
                };
                Handled::Reply(h(&mut ctx, &call).encode())
            }
        }
    }

    /// The pending reply, once the backend is idle (or its link failed: TROL_ERR_ROBOT).
    pub fn poll(&mut self) -> Option<Vec<u8>> {
        let pending = self.pending?;
        let idle = if pending.code == table::HALT.code {
            self.backend.stands()
        } else {
            self.backend.moving().map(|m| !m)
        };
        let value = match idle.map(|i| !i) {
            Ok(true) => return None,
            Ok(false) => self.follow_motions(pending.code, pending.value),
            Err(e) => {
                self.status.record_refusal(e.code());
                self.follow_motions(pending.code, e.code())
            }
        };
        self.pending = None;
        Some(Reply::Code(value).encode())
    }
}

/// A decoded request as a handler gets it: the command's description and its checked
/// arguments, with typed accessors. An accessor of the wrong kind answers TROL_ERR_ARG_RANGE
/// (it cannot happen for arguments the description declares).
#[derive(Clone, Copy, Debug)]
pub struct Call<'a> {
    /// The command.
    pub def: &'a CommandDef,
    /// Its arguments, in the description's order.
    pub args: &'a [Value],
}

impl Call<'_> {
    /// A whole number or a choice's wire value.
    pub fn int(&self, i: usize) -> Result<u8, Code> {
        match self.args.get(i) {
            Some(Value::Int(b)) => Ok(*b),
            _ => Err(TROL_ERR_ARG_RANGE),
        }
    }

    /// The straight flag.
    pub fn flag(&self, i: usize) -> Result<bool, Code> {
        match self.args.get(i) {
            Some(Value::Flag(b)) => Ok(*b),
            _ => Err(TROL_ERR_ARG_RANGE),
        }
    }

    /// A real number.
    pub fn real(&self, i: usize) -> Result<f64, Code> {
        match self.args.get(i) {
            Some(Value::Real(x)) => Ok(*x),
            _ => Err(TROL_ERR_ARG_RANGE),
        }
    }

    /// A location.
    pub fn loc(&self, i: usize) -> Result<&Location, Code> {
        match self.args.get(i) {
            Some(Value::Loc(l)) => Ok(l),
            _ => Err(TROL_ERR_ARG_RANGE),
        }
    }

    /// A location's six values, those not sent 0.
    pub fn six(&self, i: usize) -> Result<[f64; 6], Code> {
        self.loc(i).map(Location::to_array6)
    }

    /// Argument `i` as a trajectory's waypoints.
    pub fn path(&self, i: usize) -> Result<&[Waypoint], Code> {
        match self.args.get(i) {
            Some(Value::Path(p)) => Ok(p),
            _ => Err(TROL_ERR_ARG_RANGE),
        }
    }

    /// Argument `i` as a location name.
    pub fn name(&self, i: usize) -> Result<LocName, Code> {
        match self.args.get(i) {
            Some(Value::Name(n)) => Ok(*n),
            _ => Err(TROL_ERR_ARG_RANGE),
        }
    }

    /// Argument `i` as a target: a name or a location.
    pub fn target(&self, i: usize) -> Result<Target, Code> {
        match self.args.get(i) {
            Some(Value::Name(n)) => Ok(Target::Name(*n)),
            Some(Value::Loc(l)) => Ok(Target::Location(l.clone())),
            _ => Err(TROL_ERR_ARG_RANGE),
        }
    }
}

/// A precision point's name starts with `#`, and only a precision point's (RAPL-II's rule,
/// which the simulator's locations file follows): TROL_ERR_ARG_RANGE otherwise.
fn precision_name_matches(name: LocName, tag: Tag) -> Result<(), Code> {
    if name.is_precision() == (tag == Tag::Prec) {
        Ok(())
    } else {
        Err(TROL_ERR_ARG_RANGE)
    }
}

/// Here, Define, DeleteLocation and SaveLocations (CAT3, docs/teach.md), and Trajectory:
/// the backend's value, or the code that kept the call from being made.
fn teach<B: Backend>(b: &mut B, c: &Call<'_>) -> Result<crate::BiosResult, Code> {
    use table::*;
    Ok(match c.def.code {
        TROL_HERE => {
            let (name, tag) = (
                c.name(0)?,
                Tag::from_u8(c.int(1)?).ok_or(TROL_ERR_ARG_RANGE)?,
            );
            precision_name_matches(name, tag)?;
            b.here(name, tag)
        }
        TROL_DEFINE => {
            let (name, loc) = (c.name(0)?, c.loc(1)?);
            precision_name_matches(name, loc.tag())?;
            if !loc.is_finite() {
                return Err(TROL_ERR_ARG_RANGE);
            }
            b.define(name, loc)
        }
        TROL_DELETE_LOCATION => b.delete_location(c.name(0)?),
        TROL_TRAJECTORY => b.trajectory(c.path(0)?),
        _ => b.save_locations(),
    })
}

/// The handler of every built-in CAT1 command: one BIOS call each, arguments as the table
/// describes them.
fn builtin_cat1<B: Backend>(b: &mut B, c: &Call<'_>) -> Result<Executed, Code> {
    use table::*;
    let now = |r: Result<i16, crate::BackendError>| r.map(Executed::Now).map_err(Code::from);
    match c.def.code {
        TROL_APPRO => now(b.appro(&c.target(0)?, c.six(1)?, c.flag(2)?)),
        TROL_APPRO_II => now(b.appro(&c.target(0)?, c.six(1)?, c.flag(2)?)),
        TROL_CLOSE => now(b.close(c.int(0)?)),
        TROL_DEPART => now(b.depart(c.six(0)?, c.flag(1)?)),
        TROL_FINISH if c.int(0)? == FINISH_WAIT => Ok(Executed::WhenIdle(0)),
        TROL_FINISH => b
            .moving()
            .map(|m| Executed::Now(i16::from(m)))
            .map_err(Code::from),
        TROL_GRIP => now(b.grip(c.int(0)?)),
        // Answered once the arm stands: a backend of a real controller has seen it standing
        // (issue 37), the simulator's arm brakes along its path first.
        TROL_HALT => b.halt().map(Executed::WhenIdle).map_err(Code::from),
        // Answered at once: the host waits by polling FINISH_STATUS (as for a motion), so a
        // Halt from another thread gets through while the arm homes.
        TROL_HOME => now(b.home(c.int(0)?)),
        TROL_JOG => {
            let d = c.six(0)?;
            now(b.jog([d[0], d[1], d[2]], c.flag(1)?))
        }
        TROL_JOINT => now(b.joint(c.int(0)?, c.real(1)?)),
        TROL_MA => now(b.ma(c.six(0)?)),
        TROL_MI => now(b.mi(c.six(0)?)),
        TROL_MOVE => now(b.move_to(&c.target(0)?, c.flag(1)?)),
        TROL_MOVE_II => now(b.move_to(&c.target(0)?, c.flag(1)?)),
        TROL_OPEN => now(b.open(c.int(0)?)),
        TROL_READY => now(b.ready()),
        TROL_SET_TOOL_TRANSFORM => now(b.set_tool(tool_in_reach(c.six(0)?)?)),
        TROL_SPEED => now(b.speed(c.int(0)?)),
        _ => Err(trol_proto::application::code::TROL_ERR_UNKNOWN),
    }
}

/// The handler of the built-in CAT3 and CAT4 commands.
fn builtin_other<B: Backend>(ctx: &mut Context<'_, B>, c: &Call<'_>) -> Reply {
    use table::*;
    match c.def.code {
        TROL_GET_POSITION => {
            let (Ok(t), Ok(m)) = (c.int(0), c.int(1)) else {
                return Reply::Code(TROL_ERR_ARG_RANGE);
            };
            let tag = Tag::from_u8(t).unwrap_or(Tag::Cart);
            let mode = if m == POS_ACT {
                PosMode::Actual
            } else {
                PosMode::Commanded
            };
            match ctx.backend.position(tag, mode) {
                Ok(loc) => Reply::Position(loc),
                Err(e) => Reply::Code(e.code()),
            }
        }
        TROL_TERMINATE_PCP => {
            *ctx.terminate = true;
            Reply::Code(Code(0))
        }
        TROL_GET_STATUS => Reply::Status {
            bios_called: ctx.status.bios_called,
            last: ctx.status.last_error_code,
            transaction: if ctx.epoch == 0 {
                0
            } else {
                ctx.status.transaction
            },
            epoch: ctx.epoch,
        },
        TROL_GET_VERSION => Reply::Version {
            protocol: PROTOCOL_VERSION,
            kind: ctx.backend.kind().into(),
        },
        TROL_HERE | TROL_DEFINE | TROL_DELETE_LOCATION | TROL_SAVE_LOCATIONS | TROL_TRAJECTORY => {
            match teach(ctx.backend, c) {
                Ok(Ok(v)) => Reply::Code(Code(v)),
                Ok(Err(e)) => {
                    if let crate::BackendError::Explained(_, why) = &e {
                        *ctx.note = Some(why.clone());
                    }
                    Reply::Code(e.code())
                }
                Err(code) => Reply::Code(code),
            }
        }
        TROL_LIST_LOCATIONS => match ctx.backend.locations() {
            Ok(mut all) => {
                all.truncate(MAX_LOCATIONS);
                Reply::Locations(all)
            }
            Err(e) => Reply::Code(e.code()),
        },
        TROL_GET_GRIPPER => match ctx.backend.gripper() {
            Ok(g) => Reply::Gripper(g),
            Err(e) => Reply::Code(e.code()),
        },
        TROL_GET_CODES => Reply::Codes(
            ctx.backend
                .codes()
                .iter()
                .filter(|c| !Code(c.value).is_trol() && !Code(c.value).is_success())
                .map(Into::into)
                .collect(),
        ),
        // The longest answer, and how often the server says "still working" meanwhile
        // (0: it does not); a host that knows only the first value reads only it.
        TROL_GET_REPLY_TIME => Reply::Reals {
            value: Code(0),
            values: vec![
                ctx.backend.reply_time().as_secs_f64(),
                ctx.keepalive.map_or(0.0, |k| k.as_secs_f64()),
            ],
        },
        TROL_SET_WATCHDOG => match c.int(0) {
            Ok(0) => {
                *ctx.watchdog = None;
                Reply::Code(Code(0))
            }
            Ok(tenths) => {
                *ctx.watchdog = Some(std::time::Duration::from_millis(100 * u64::from(tenths)));
                Reply::Code(Code(0))
            }
            Err(code) => Reply::Code(code),
        },
        _ => Reply::Code(trol_proto::application::code::TROL_ERR_UNKNOWN),
    }
}

/// A number for this server's start: from the clock's nanoseconds, never 0.
fn new_epoch() -> u16 {
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.subsec_nanos() ^ (d.as_secs() as u32))
        .unwrap_or(1);
    ((nanos ^ (nanos >> 16)) as u16).max(1)
}

pub use trol_proto::application::table::MAX_TOOL_MM;

/// A tool transform the arm can carry: a finite offset of at most [`MAX_TOOL_MM`], finite
/// angles.
pub fn tool_in_reach(tool: [f64; 6]) -> Result<[f64; 6], Code> {
    let len = (tool[0] * tool[0] + tool[1] * tool[1] + tool[2] * tool[2]).sqrt();
    if tool.iter().all(|v| v.is_finite()) && len <= MAX_TOOL_MM {
        Ok(tool)
    } else {
        Err(TROL_ERR_ARG_RANGE)
    }
}

impl<B: Backend> std::fmt::Debug for Context<'_, B> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Context")
            .field("backend", &self.backend.kind())
            .finish_non_exhaustive()
    }
}

impl<B> std::fmt::Debug for Handler<B> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Handler::Cat1(_) => "Handler::Cat1",
            Handler::Other(_) => "Handler::Other",
        })
    }
}

impl<B: Backend> std::fmt::Debug for Pcp<B> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Pcp")
            .field("backend", &self.backend.kind())
            .field("commands", &self.catalog.iter().count())
            .finish_non_exhaustive()
    }
}

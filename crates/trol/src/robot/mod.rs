//! The Rust API: a connection to the controller and one method per TROL API function, each
//! a thin skin over [`Robot::call`], which works from the command's description.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use trol_comm::{DefaultHandlers, ErrorHandlers, TransError, Transactor};
use trol_controller::Embedded;
use trol_port::{Port, PortSettings};
use trol_proto::application::code::{
    Code, CodeTable, TROL_ERR_ARG_RANGE, TROL_ERR_BAD_RSIZE, TROL_ERR_COMM, TROL_ERR_ROBOT_UNSURE,
};
use trol_proto::application::record::{self, RequestError, Value};
use trol_proto::application::table::{self, FINISH_STATUS, FINISH_WAIT};
use trol_proto::application::{
    Catalog, CatalogError, CodeEntry, CommandDef, Gripper, LocName, Location, Reply, ReplyError,
    Tag, Waypoint,
};
use trol_proto::link::{BlockCheck, LinkConfig, LinkError};
#[cfg(feature = "sim")]
use trol_sim::SimSettings;

use crate::config::Config;

mod connect;
mod open;

pub use connect::Connect;

use calls::reply_check;
mod calls;

/// The ErrAppTimeOut policy of a catalog's commands (the manual's default handler's).
pub use trol_comm::{prompt_policy, timeout_policy};
/// GetPosition's mode.
pub use trol_controller::PosMode;

/// Why an API call did not succeed. "The controller said no" ([`Error::Refused`]) is kept
/// apart from "the link failed" ([`Error::Link`]); [`Error::code`] gives the manual's code.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The controller answered with a value that is not success for the command: a BIOS
    /// code (> -32000), or a TROL code the controller detected (TROL_ERR_UNKNOWN,
    /// TROL_ERR_BAD_CSIZE, TROL_ERR_LOCATION, TROL_RETVAL_RANGE, TROL_ERR_ARG_RANGE,
    /// TROL_ERR_ROBOT).
    #[error("{command} returned {}{}", .code.0, refusal_text(.name, .meaning))]
    Refused {
        /// The command's name.
        command: &'static str,
        /// The value.
        code: Code,
        /// The value's name, from TROL's codes or the backend's.
        name: Option<&'static str>,
        /// The value's meaning, from TROL's codes or the backend's.
        meaning: Option<&'static str>,
    },
    /// An argument is out of range; nothing was sent (TROL_ERR_ARG_RANGE).
    #[error("{0}")]
    Argument(#[from] RequestError),
    /// The transaction failed and the error handler could not mend it (TROL_ERR_COMM).
    #[error("TROL_ERR_COMM: {command}: {error}")]
    Link {
        /// The command's name.
        command: &'static str,
        /// What failed.
        error: TransError,
    },
    /// The reply did not fit the command (TROL_ERR_BAD_RSIZE).
    #[error("TROL_ERR_BAD_RSIZE: a reply of {len} bytes does not fit {command}")]
    BadReply {
        /// The command's name.
        command: &'static str,
        /// The reply's length.
        len: usize,
    },
    /// The port could not be opened, or the configuration is wrong.
    #[error("{0}")]
    Setup(#[from] SetupError),
}

/// Why a connection could not be set up.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SetupError {
    /// The port could not be opened.
    #[error("{0}")]
    Port(#[from] trol_port::OpenError),
    /// The configuration is wrong (trol.cfg, a location file).
    #[error("{0}")]
    Config(String),
    /// The controller's server does not answer, or cannot be activated.
    #[error("{0}")]
    NoServer(String),
    /// A command description could not be added.
    #[error("{0}")]
    Command(#[from] CatalogError),
    /// The controller speaks another protocol version than this library (GetVersion).
    #[error("{}", incompatible_text(*ours, *theirs, kind))]
    Incompatible {
        /// This library's protocol version.
        ours: u16,
        /// The controller's, or `None` when it does not know TROLGetVersion (older than
        /// version 1 of the handshake).
        theirs: Option<u16>,
        /// What drives its arm, as it says.
        kind: Option<String>,
    },
}

fn incompatible_text(ours: u16, theirs: Option<u16>, kind: &Option<String>) -> String {
    match theirs {
        None => format!(
            "the controller does not know TROLGetVersion, so it speaks an older TROL protocol \
             than version {ours} of this library: run the same TROL release on both sides"
        ),
        Some(theirs) => format!(
            "the controller ({}) speaks TROL protocol version {theirs}, this library version \
             {ours}: run the same TROL release on both sides (`trol --version`)",
            kind.as_deref().unwrap_or("of an unknown kind")
        ),
    }
}

/// What TROLGetVersion says of the controller.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ControllerVersion {
    /// The protocol version it speaks ([`table::PROTOCOL_VERSION`] for this library).
    pub protocol: u16,
    /// What drives its arm: `simulated A465`, `C500 over RAPL-II`, or a controller
    /// program's own word.
    pub kind: String,
}

fn refusal_text(name: &Option<&str>, meaning: &Option<&str>) -> String {
    let name = name.map(|n| format!(" ({n})")).unwrap_or_default();
    let meaning = meaning.map(|m| format!(": {m}")).unwrap_or_default();
    format!("{name}{meaning}")
}

impl Error {
    /// The manual's return code of this error.
    pub fn code(&self) -> Code {
        match self {
            Error::Refused { code, .. } => *code,
            Error::Argument(_) => TROL_ERR_ARG_RANGE,
            Error::Link { .. } | Error::Setup(_) => TROL_ERR_COMM,
            Error::BadReply { .. } => TROL_ERR_BAD_RSIZE,
        }
    }

    /// Whether the controller answered (as opposed to the link failing or nothing sent).
    pub fn is_refusal(&self) -> bool {
        matches!(self, Error::Refused { .. })
    }
}

impl From<ReplyError> for Error {
    fn from(e: ReplyError) -> Self {
        Error::BadReply {
            command: e.command,
            len: e.len,
        }
    }
}

/// The longest reply timeout SetL3_TO_Intervall takes, tenths of a second (10 min).
pub const MAX_REPLY_TENTHS: u16 = 6000;

/// The longest pause SetDelay takes between two bytes, ms.
pub const MAX_DELAY_MS: u64 = 50;

/// How [`Robot::finish_unless`] ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Waited {
    /// The arm and the gripper came to rest.
    Idle,
    /// The wait was cancelled: Halt was sent and the arm has stopped.
    Halted,
}

/// How a controller runs a trajectory ([`Robot::trajectory`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Timing {
    /// At the waypoints' times (the simulated A465, a MARS 8).
    Timed,
    /// Through the waypoints, one joint move to each at the speed setting, without their
    /// times (a controller that cannot run a timed path: a C500, a C500C).
    Untimed,
}

/// Results of the API.
pub type Result<T> = std::result::Result<T, Error>;

/// How often a wait for the arm asks whether it still moves.
pub const POLL: Duration = Duration::from_millis(20);

/// The reply timeout of one poll of a wait (TROLFinish(FINISH_STATUS)): the controller
/// answers it at once (a C500 gateway after one STATUS, 0.7 s at 9600 Bd), so a controller
/// that dies during a wait is noticed within about 3 s (this, then one unanswered ENQ),
/// whatever the reply timeout of other calls. An in-process controller is given
/// [`IN_PROCESS_SLACK`] more: its poll reads a real controller's line on a thread a busy
/// machine may hold back (issue 44: a C500's STATUS poll on `rapl:` missed 2 s under load).
pub const POLL_REPLY_TIMEOUT: Duration = Duration::from_secs(2);

/// What a call waits for its reply beyond the time the controller says it takes at most
/// (TROLGetReplyTime): the line's time and a loaded machine's scheduling.
pub const REPLY_MARGIN: Duration = Duration::from_millis(500);

/// What the simulator's backend answers TROLGetReplyTime (the default of
/// `Backend::reply_time`).
#[cfg(feature = "sim")]
const SIM_REPLY_TIME: Duration = Duration::from_millis(500);

/// The longest silence taken from a controller that says "still working" every `interval`
/// while it executes ([`Robot::set_keepalive`]): six of its intervals, at least 1.5 s (a
/// loaded machine may hold its keep-alive thread back), so that with one unanswered ENQ of
/// the repeat after it a dead controller is noticed within 2.5 s.
pub fn keepalive_silence(interval: Duration) -> Duration {
    (interval * 6).max(KEEPALIVE_SILENCE)
}

/// The shortest silence [`keepalive_silence`] takes.
pub const KEEPALIVE_SILENCE: Duration = Duration::from_millis(1500);

/// What an in-process line (the embedded controller's, port `sim`, `rapl:`, `mars:`) waits
/// beyond the timeouts of a line to another process: its controller cannot die apart from
/// the program, only be held back by a busy machine, and must not time out for that (issue
/// 42: one TROL_ERR_COMM in 1,100 Defines under heavy load). Its reply time and the silence
/// its keep-alive allows grow by as much, also when the version check learns them again
/// (issue 44: InitTROL(1) had put them back to 3.7 s and 1.5 s, and a 1998 program's first
/// TROLHome on `rapl:` came back TROL_ERR_COMM under load).
pub const IN_PROCESS_SLACK: Duration = Duration::from_secs(5);

/// The shortest reply timeout a controller's reply time gives a call.
pub const MIN_PROMPT_REPLY_TIMEOUT: Duration = Duration::from_millis(1500);

/// The reply timeout of every call but a wait without limit (Finish(FINISH_WAIT)) to a
/// controller that said how long it takes to answer (TROLGetReplyTime, asked by the version
/// check; an in-process controller's backend says it directly), unless the application set
/// one (SetL3_TO_Intervall): that time and [`REPLY_MARGIN`], at least
/// [`MIN_PROMPT_REPLY_TIMEOUT`]. So a controller that died, froze or whose line went silent
/// is noticed within seconds (this, then one unanswered ENQ: 2.5 s for the simulator)
/// instead of the manual's 15 s and more. A 1998 controller keeps the manual's.
pub fn prompt_reply_timeout(reply_time: Duration) -> Duration {
    (reply_time + REPLY_MARGIN).max(MIN_PROMPT_REPLY_TIMEOUT)
}

/// Wait until the arm is done, for a robot shared between threads: the lock is taken for each
/// poll only, so another thread's `halt()` gets through between two polls.
pub fn wait_idle(robot: &std::sync::Mutex<Robot>) -> Result<()> {
    let lock = || robot.lock().unwrap_or_else(|p| p.into_inner());
    let mut wait = lock().finish_wait();
    loop {
        let mut r = lock();
        if r.poll_idle()? {
            return Ok(());
        }
        wait.check(&mut r)?;
        drop(r);
        std::thread::sleep(POLL);
    }
}

/// A polled Finish(FINISH_WAIT) under way, bounded as the manual's one long request was
/// ([`Robot::finish_wait`]).
#[derive(Clone, Copy, Debug)]
pub struct FinishWait {
    started: std::time::Instant,
    limit: Duration,
}

impl FinishWait {
    /// Call after each poll that found the arm moving: once the wait passes its limit, the
    /// connection's ErrAppTimeOut decides; giving up is TRANS_TIMEOUT (TROL_ERR_COMM), as a
    /// late reply is.
    pub fn check(&mut self, robot: &mut Robot) -> Result<()> {
        let waited = self.started.elapsed();
        if waited < self.limit {
            return Ok(());
        }
        let request = [table::TROL_FINISH, FINISH_WAIT];
        match robot.transactor.app_timeout(&request, waited) {
            trol_comm::TimeoutAction::WaitMore(more) => {
                self.limit = waited + more.max(POLL);
                Ok(())
            }
            trol_comm::TimeoutAction::Fail => Err(Error::Link {
                command: table::FINISH.name,
                error: TransError::Failed {
                    code: trol_proto::transaction::TransCode::Timeout,
                    last_comm: None,
                },
            }),
        }
    }
}

/// What GetStatus reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StatusRecord {
    /// Whether the last CAT1/CAT2 command called the BIOS.
    pub bios_called: bool,
    /// Its BIOS value, or the TROL code that kept it from being called.
    pub last: Code,
    /// The transaction number of that command.
    pub transaction: u8,
    /// The controller's epoch.
    pub epoch: u16,
}

/// A CAT1/CAT2 call whose request went out and whose outcome never came back (the call
/// failed on the link, or a repeat of it was answered TROL_ERR_ROBOT_UNSURE): GetStatus must
/// not speak of an older call as if it were this one (issue 67).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Doubt {
    /// Its transaction number.
    transaction: u8,
    /// The controller's epoch as known before it was sent.
    epoch: Option<u16>,
}

/// A connection to a TROL controller.
pub struct Robot {
    transactor: Transactor<Box<dyn Port>>,
    catalog: Catalog,
    /// The application installed its own error handlers ([`Robot::set_handlers`]): adding a
    /// command keeps them.
    own_handlers: bool,
    codes: &'static CodeTable,
    _embedded: Option<Embedded>,
    /// Where the port came from, to open it again after it failed.
    origin: Option<(String, PortSettings)>,
    /// The port failed: open it again before the next call.
    broken: bool,
    /// Activate a controller found in terminal mode on reconnecting, with this tool.
    reactivate: Option<[f64; 6]>,
    /// The controller's epoch when last seen (GetStatus).
    epoch: Option<u16>,
    /// The last CAT1/CAT2 call whose fate this end does not know ([`Doubt`]).
    doubt: Option<Doubt>,
    /// The live view of an embedded simulator, served while the connection lives.
    #[cfg(feature = "view")]
    view: Option<trol_view::ViewServer>,
    /// What lives as long as the connection ([`Robot::keep`]).
    kept: Vec<Box<dyn std::any::Any + Send>>,
    /// No block check was named: CRC-16 may fall back to the manual's LRC at first contact.
    check_auto: bool,
    /// A transaction went through with the block check in use.
    check_settled: bool,
    /// A request was tried with the manual's LRC after CRC-16's blocks were refused.
    lrc_tried: bool,
    /// The application chose the repeats ([`Robot::set_repeats`]): the handshake keeps them.
    repeats_set: bool,
    /// The controller speaks only the manual's protocol (its GetStatus is the manual's).
    manual_peer: bool,
    /// The reply timeout of a call to a controller that said how long it takes to answer
    /// ([`prompt_reply_timeout`]); `None`: the manual's reply timeout.
    prompt: Option<Duration>,
    /// The application set the reply timeout (SetL3_TO_Intervall): every call keeps it.
    reply_timeout_set: bool,
    /// What the user should hear once about this connection ([`Robot::take_notice`]).
    notice: Option<String>,
    /// What an embedded real controller's backend logged (its reasons), for
    /// [`Robot::take_controller_said`].
    said: Option<ControllerSaid>,
}

/// The lines an embedded controller's backend logs (why it refused, what its controller
/// said), kept for the application: the last 32 ([`Robot::take_controller_said`]). Each also
/// goes to the log (target `trol::<backend>`), and to stderr where `TROL_VERBOSE` is set to
/// anything but `0` (issue 62: a C program could not learn why a call got BIOS_UNSETTLED).
#[derive(Clone, Debug, Default)]
pub(crate) struct ControllerSaid(
    std::sync::Arc<std::sync::Mutex<std::collections::VecDeque<String>>>,
);

impl ControllerSaid {
    /// Keep `line` (the backend's, as `who` prints it: `c500c: ...`).
    #[cfg(any(feature = "rapl", feature = "mars", feature = "c500c"))]
    pub(crate) fn keep(&self, line: &str) {
        static VERBOSE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
        let verbose = *VERBOSE
            .get_or_init(|| std::env::var("TROL_VERBOSE").is_ok_and(|v| !v.is_empty() && v != "0"));
        if verbose {
            eprintln!("TROL: {line}");
        }
        let mut q = self.0.lock().unwrap_or_else(|p| p.into_inner());
        if q.len() >= 32 {
            q.pop_front();
        }
        q.push_back(line.to_string());
    }

    fn take(&self) -> Vec<String> {
        self.0
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .drain(..)
            .collect()
    }
}

/// What a connection says once when the controller speaks only the manual's protocol.
pub const MANUAL_PEER_NOTICE: &str = "the controller speaks only the manual's protocol (a \
    1998 TROL server): the manual's LRC block check, which misses damage CRC-16 finds \
    (docs/reliability.md); no exactly-once repeats, so after a failed call TROLGetStatus tells \
    whether it ran; no version check; and TROL's added commands (GetVersion, GetCodes, \
    GetGripper, SetWatchdog) are unknown to it";

/// The port prefix that embeds the controller with the RAPL-II backend (`rapl:/dev/ttyUSB0`).
pub const RAPL_PREFIX: &str = "rapl:";
/// The port prefix that embeds the controller with the MARS 8 backend (`mars:/dev/ttyUSB0`).
pub const MARS_PREFIX: &str = "mars:";
/// The port prefix that embeds the controller with the C500C backend (`c500c:/dev/ttyUSB0`).
pub const C500C_PREFIX: &str = "c500c:";

impl Robot {
    /// The default ErrAppTimeOut's policy for this connection: the commands' descriptions
    /// (90 s more for Home), or, for a controller that said how long it takes to answer
    /// ([`Robot::set_reply_time`]), only where a description asks for no limit. For handler
    /// sets of the application's that fall back on the default (the C library's).
    pub fn timeout_policy(&self) -> trol_comm::TimeoutPolicy {
        if self.prompt.is_some() {
            prompt_policy(self.catalog.clone())
        } else {
            timeout_policy(self.catalog.clone())
        }
    }

    /// The manual's default handlers, unless the application installed its own: their
    /// ErrAppTimeOut waits as the commands' descriptions say (90 s more for Home), or, for a
    /// controller that answers at once, only where a description asks for no limit.
    fn default_handlers(&mut self) {
        if self.own_handlers {
            return;
        }
        let policy = self.timeout_policy();
        self.transactor
            .set_handlers(Box::new(DefaultHandlers::with_policy(policy)));
    }

    /// Say how long the controller takes at most to answer a request (what
    /// TROLGetReplyTime answers; an in-process controller's backend says it): every call
    /// but a wait without limit then waits [`prompt_reply_timeout`] for its reply, unless
    /// the application set the reply timeout, and the default ErrAppTimeOut grants Home no
    /// 90 s more (that was for a 1998 server, which answered Home at its end). An
    /// in-process controller is given [`IN_PROCESS_SLACK`] more.
    pub fn set_reply_time(&mut self, reply_time: Duration) {
        self.prompt = Some(prompt_reply_timeout(reply_time + self.in_process_slack()));
        self.default_handlers();
    }

    /// Whether the controller speaks only the manual's protocol (a 1998 TROL server: found by
    /// its 4-byte GetStatus when the connection was checked). It then has no memory of the
    /// last request, so nothing is sent again on its own ([`Robot::set_repeats`]).
    pub fn speaks_manual_only(&self) -> bool {
        self.manual_peer
    }

    /// What the user should hear once about this connection, taken: that the controller
    /// speaks only the manual's protocol, or that the block check fell back to the manual's
    /// LRC. The utilities, C's InitTROL and Python print it.
    pub fn take_notice(&mut self) -> Option<String> {
        self.notice.take()
    }

    fn add_notice(&mut self, text: &str) {
        self.notice = Some(match self.notice.take() {
            Some(n) => format!("{n}; {text}"),
            None => text.to_string(),
        });
    }

    /// After the first GetStatus of a check: a reply in the manual's 4 bytes is a controller
    /// that speaks only the manual's protocol. Returns whether it is one.
    pub(crate) fn note_status_form(&mut self, status: &StatusRecord) -> bool {
        if status.epoch != 0 {
            return false;
        }
        if !self.manual_peer {
            self.manual_peer = true;
            self.prompt = None;
            self.set_keepalive(None);
            self.default_handlers();
            self.epoch = None;
            if !self.repeats_set {
                self.transactor.set_repeats(0);
            }
            // It says all there is: the LRC fallback's notice is part of it.
            self.notice = Some(MANUAL_PEER_NOTICE.to_string());
        }
        true
    }

    /// Keep `thing` alive as long as the connection: a live view served next to an embedded
    /// controller, a log, anything whose life is the connection's.
    pub fn keep(&mut self, thing: impl std::any::Any + Send) {
        self.kept.push(Box::new(thing));
    }

    /// On reconnecting after a port failure, activate a controller found in terminal mode
    /// (as `trol init` does) with this tool transform; `None` (the default) leaves that to
    /// the user.
    pub fn set_reactivate(&mut self, tool: Option<[f64; 6]>) {
        self.reactivate = tool;
    }

    /// The controller's epoch as last seen by GetStatus: it changes when the controller
    /// restarts (its exactly-once memory is then gone).
    pub fn controller_epoch(&self) -> Option<u16> {
        self.epoch
    }

    /// Before a call: a failed port is opened again.
    fn mend(&mut self) -> Result<()> {
        if self.broken {
            self.reconnect()
        } else {
            Ok(())
        }
    }

    /// TransSR with the reconnection bookkeeping: a port failure marks the connection broken.
    fn trans(&mut self, command: &'static str, request: &[u8]) -> Result<Vec<u8>> {
        self.mend()?;
        let mut result = self.transactor.trans_sr(request);
        if let Err(error) = &result {
            if self.may_fall_back(error) {
                result = self.fall_back_to_lrc(request);
            }
        }
        if request.first().is_some_and(|c| *c < 128) {
            // A CAT1/CAT2 call: GetStatus speaks of it from now on. Its fate is known when
            // its reply came, unless the reply says the controller cannot place it.
            let unsure = TROL_ERR_ROBOT_UNSURE.0.to_le_bytes();
            let known = matches!(&result, Ok(reply) if reply.as_slice() != unsure);
            self.doubt = (!known).then_some(Doubt {
                transaction: self.transactor.transaction_number(),
                epoch: self.epoch,
            });
        }
        match result {
            Ok(reply) => {
                self.check_settled = true;
                Ok(reply)
            }
            Err(error) => {
                if matches!(error, TransError::Io(_)) && self.origin.is_some() {
                    self.broken = true;
                }
                Err(Error::Link { command, error })
            }
        }
    }

    /// Whether `error` is the controller refusing every CRC-16 block as damaged at first
    /// contact, with no block check named: it may check blocks as the manual does.
    fn may_fall_back(&self, error: &TransError) -> bool {
        self.check_auto
            && !self.check_settled
            && self.link_config().check == BlockCheck::Crc16
            && crate::refused_every_block(error)
    }

    /// Send `request` again with the manual's LRC (it never arrived: every block was refused),
    /// and keep LRC if the controller takes it; else go back to CRC-16 and fail as the LRC
    /// attempt did.
    fn fall_back_to_lrc(&mut self, request: &[u8]) -> std::result::Result<Vec<u8>, TransError> {
        let crc = self.link_config();
        // The controller refused the last block and waits for it again; it gives up after its
        // block timeout and is then deaf for a reset period (docs/protocol.md, "The reset
        // after a failure"). An ENQ before that would go unanswered.
        let t = crc.timeouts;
        std::thread::sleep(t.start + t.reset + t.reset / 2);
        self.lrc_tried = true;
        self.set_check(BlockCheck::Lrc);
        let _ = self.transactor.driver_mut().port_mut().flush_input();
        let result = self.transactor.trans_sr(request);
        match &result {
            Ok(_) => self.add_notice(
                "the controller refused CRC-16 blocks and takes the manual's LRC: this \
                 connection checks blocks with the LRC (`check = lrc` in trol.cfg says so and \
                 skips the trial)",
            ),
            Err(_) => self.set_check(crc.check),
        }
        result
    }

    /// Whether no block check was named, so CRC-16 may fall back to the manual's LRC.
    pub(crate) fn check_is_auto(&self) -> bool {
        self.check_auto
    }

    /// Whether a request was tried with the manual's LRC after CRC-16's were refused.
    pub(crate) fn tried_lrc(&self) -> bool {
        self.lrc_tried
    }

    pub(crate) fn set_check(&mut self, check: BlockCheck) {
        let link = self.transactor.initiator_mut().link_mut();
        let cfg = LinkConfig {
            check,
            ..*link.config()
        };
        link.set_config(cfg);
    }

    /// Know a command an application added (docs/extending.md): [`Robot::call`] takes it,
    /// and the default ErrAppTimeOut waits for its reply as its description says. Handlers
    /// the application installed ([`Robot::set_handlers`]) stay as they are.
    pub fn add_command(&mut self, def: CommandDef) -> Result<()> {
        self.catalog.add(def).map_err(SetupError::from)?;
        self.default_handlers();
        Ok(())
    }

    /// The commands this connection knows: the built-in ones and those added.
    pub fn catalog(&self) -> &Catalog {
        &self.catalog
    }

    /// Where the simulated world's objects are (after the last call), for a robot on the
    /// embedded simulator; `None` for other controllers.
    pub fn world(&self) -> Option<String> {
        self._embedded.as_ref().and_then(Embedded::world)
    }

    /// The BIOS codes of the controller's backend, with their names (for messages).
    pub fn codes(&self) -> &'static CodeTable {
        self.codes
    }

    /// Say which BIOS code table the controller's backend uses (the simulated A465's by
    /// default).
    pub fn set_codes(&mut self, codes: &'static CodeTable) {
        self.codes = codes;
    }

    /// Replace the layer-3 error handlers (ErrOnSend, ErrOnReceive, ErrAppTimeOut).
    pub fn set_handlers(&mut self, handlers: Box<dyn ErrorHandlers>) {
        self.own_handlers = true;
        self.transactor.set_handlers(handlers);
    }

    /// SetL3_TO_Intervall: the reply timeout in tenths of a second (default 150; 1..=
    /// [`MAX_REPLY_TENTHS`], else TROL_ERR_ARG_RANGE and the timeout stays).
    pub fn set_reply_timeout_tenths(&mut self, tenths: u16) -> Result<()> {
        if !(1..=MAX_REPLY_TENTHS).contains(&tenths) {
            return Err(Error::Argument(RequestError::Range {
                command: "SetL3_TO_Intervall",
                arg: "TO_Intervall",
                what: format!(
                    "{tenths} tenths of a second: the reply timeout must be 1..{MAX_REPLY_TENTHS} \
                     (0.1 s to 10 min)"
                ),
            }));
        }
        self.transactor.set_reply_timeout_tenths(tenths);
        self.reply_timeout_set = true;
        // The application's reply timeout is the bound of every wait, as the manual's.
        self.transactor.initiator_mut().set_silence(None);
        Ok(())
    }

    /// SetDelay: a pause between two bytes sent (0..=[`MAX_DELAY_MS`] ms). Every timeout
    /// that runs while bytes travel grows with it (docs/protocol.md, "Inter-character
    /// delay").
    pub fn set_delay(&mut self, delay: Duration) -> Result<()> {
        if delay > Duration::from_millis(MAX_DELAY_MS) {
            return Err(Error::Argument(RequestError::Range {
                command: "SetDelay",
                arg: "delay",
                what: format!(
                    "{} ms: at most {MAX_DELAY_MS} ms between two bytes (the manual used 5)",
                    delay.as_millis()
                ),
            }));
        }
        let old = self.transactor.driver().delay();
        let link = self.transactor.initiator_mut().link_mut();
        let cfg = LinkConfig {
            char_time: link.config().char_time.saturating_sub(old) + delay,
            ..*link.config()
        };
        link.set_config(cfg);
        self.transactor.driver_mut().set_delay(delay);
        Ok(())
    }

    /// GetLastCommErr: the layer-2 failure of the last call, `None` if it had none (a call
    /// refused before it reached the line included: no code is left from an earlier call).
    pub fn last_comm_error(&self) -> Option<LinkError> {
        self.transactor.last_comm_error()
    }

    /// A call begins: GetLastCommErr speaks of it from now on.
    fn forget_comm_error(&mut self) {
        self.transactor
            .initiator_mut()
            .link_mut()
            .clear_last_error();
    }

    /// The layer-3 machinery (port, driver, link settings): the crate's own; the public
    /// surface is the methods below.
    pub(crate) fn transactor_mut(&mut self) -> &mut Transactor<Box<dyn Port>> {
        &mut self.transactor
    }

    /// How often a request whose transaction failed is sent again (TROLSetRepeats; 0: the
    /// first failure is the call's).
    ///
    /// Without this call, a connection repeats only to a controller that announced its memory
    /// of the last request ([`Robot::over`]).
    pub fn set_repeats(&mut self, repeats: u8) {
        self.repeats_set = true;
        self.transactor.set_repeats(repeats);
    }

    /// How often a failed request is sent again ([`Robot::set_repeats`]).
    pub fn repeats(&self) -> u8 {
        self.transactor.repeats()
    }

    /// The link's settings in use: the block check, timeouts, the time a character takes
    /// (with [`Robot::set_delay`]).
    pub fn link_config(&self) -> LinkConfig {
        *self.transactor.initiator().link().config()
    }

    /// Drop what waits in the port's input (FlushBuffer).
    pub fn flush_input(&mut self) -> std::io::Result<()> {
        self.transactor.driver_mut().port_mut().flush_input()
    }

    /// Layers 1-2 of this connection for the manual's error handlers (SendData,
    /// ReceiveData, BufferEmpty, FlushBuffer), with the link's settings and reply timeout.
    pub fn channel(&mut self) -> trol_comm::LineChannel<'_, Box<dyn Port>> {
        self.transactor.channel()
    }

    /// Give the port back, ending the connection (`trol link` activates the controller, then
    /// relays over the same port). An embedded controller stops.
    pub fn into_port(self) -> Box<dyn Port> {
        self.transactor.into_port()
    }

    fn name_of(&self, request: &[u8]) -> &'static str {
        request
            .first()
            .and_then(|c| self.catalog.get(*c))
            .map(|d| d.name)
            .unwrap_or("TransSR")
    }

    /// TransSR (layer 3): send any request's bytes and return the reply's bytes, unchecked.
    pub fn transact_raw(&mut self, request: &[u8]) -> Result<Vec<u8>> {
        self.forget_comm_error();
        let command = self.name_of(request);
        self.trans(command, request)
    }

    /// The manual's Cat1Transaction: send a CAT1 request's bytes; its one-word reply is
    /// returned if its command's description counts it as success (0 for a command this
    /// connection has no description of), else [`Error::Refused`].
    pub fn cat1_transaction(&mut self, request: &[u8]) -> Result<i16> {
        let command = self.name_of(request);
        let def = request.first().and_then(|c| self.catalog.get(*c)).copied();
        let reply = self.transact_raw(request)?;
        let value = match reply.as_slice() {
            [a, b] => Code(i16::from_le_bytes([*a, *b])),
            _ => {
                return Err(Error::BadReply {
                    command,
                    len: reply.len(),
                });
            }
        };
        if def.map_or(value.is_success(), |d| d.is_success(value.0)) {
            Ok(value.0)
        } else {
            Err(self.refused(command, value))
        }
    }

    /// Call any described command: check the arguments against `def` (nothing is sent if one
    /// is out of range), send, and decode the reply in the form `def` gives. A return value
    /// that `def` does not count as success is [`Error::Refused`].
    pub fn call(&mut self, def: &CommandDef, args: &[Value]) -> Result<Reply> {
        self.forget_comm_error();
        let request = record::encode(def, args)?;
        tracing::debug!(
            transaction = self
                .transactor
                .transaction_number()
                .checked_add(1)
                .unwrap_or(1),
            "request {}",
            self.catalog.request_text(&request)
        );
        // A poll of a wait: a short reply timeout (POLL_REPLY_TIMEOUT); any call but a wait
        // without limit to a controller that answers at once: PROMPT_REPLY_TIMEOUT, unless
        // the application set the reply timeout.
        let poll = def.code == table::FINISH.code
            && matches!(args.first(), Some(Value::Int(v)) if *v == FINISH_STATUS);
        let prompt = self
            .prompt
            .filter(|_| !self.reply_timeout_set && def.extra_wait(&request).is_some());
        let short = if poll {
            Some(self.poll_reply_timeout())
        } else {
            prompt
        };
        let usual = self.transactor.initiator().reply_timeout();
        let shortened = short.filter(|s| *s < usual);
        if let Some(t) = shortened {
            self.transactor.initiator_mut().set_reply_timeout(t);
        }
        // With the manual's LRC: the reply is taken only in a form this request can have.
        let lrc = self.transactor.initiator().link().config().check == BlockCheck::Lrc;
        if lrc {
            self.transactor
                .initiator_mut()
                .link_mut()
                .set_plausible(Some(reply_check(def, self.codes)));
        }
        let sent = self.trans(def.name, &request);
        if lrc {
            self.transactor
                .initiator_mut()
                .link_mut()
                .set_plausible(None);
        }
        if shortened.is_some() {
            self.transactor.initiator_mut().set_reply_timeout(usual);
        }
        let bytes = sent.inspect_err(|e| {
            tracing::info!("{}: {e}", def.name);
        })?;
        let reply = Reply::decode(def, &bytes)?;
        tracing::debug!("reply {}", reply.text(self.codes));
        match reply {
            // A position in another form than the one asked for is no answer to this request,
            // for every caller (the interpreter and the trace too).
            Reply::Position(loc)
                if def.code == table::GET_POSITION.code
                    && !matches!(args.first(), Some(Value::Int(t)) if *t == loc.tag() as u8) =>
            {
                Err(Error::BadReply {
                    command: def.name,
                    len: bytes.len(),
                })
            }
            // These carry data, not a return value: a refusal comes as a bare code.
            Reply::Status { .. } | Reply::Position(_) => Ok(reply),
            _ if def.is_success(reply.value().0) => Ok(reply),
            _ => Err(self.refused(def.name, reply.value())),
        }
    }

    /// What an embedded real controller's backend logged since this was last asked (the
    /// reasons of its refusals: which profile key a BIOS_UNSETTLED needs, what the controller
    /// printed), oldest first; empty for a controller in another process (its log has them).
    pub fn take_controller_said(&mut self) -> Vec<String> {
        self.said
            .as_ref()
            .map(ControllerSaid::take)
            .unwrap_or_default()
    }

    fn refused(&self, command: &'static str, code: Code) -> Error {
        Error::Refused {
            command,
            code,
            name: code.name(self.codes),
            meaning: code.meaning(self.codes),
        }
    }

    /// A CAT1 call: the return value (0, or another value the description counts as success).
    fn cat1(&mut self, def: &CommandDef, args: &[Value]) -> Result<i16> {
        match self.call(def, args)? {
            Reply::Code(v) => Ok(v.0),
            other => Err(Error::BadReply {
                command: def.name,
                len: other.encode().len(),
            }),
        }
    }

    /// The reply timeout (SetL3_TO_Intervall).
    pub fn reply_timeout(&self) -> Duration {
        self.transactor.reply_timeout()
    }

    /// How long one poll of a wait (TROLFinish(FINISH_STATUS)) waits for its reply:
    /// [`POLL_REPLY_TIMEOUT`] (more for an in-process controller), at most what other
    /// calls wait; the application's reply timeout where it set one.
    pub fn poll_reply_timeout(&self) -> Duration {
        let bound = POLL_REPLY_TIMEOUT + self.in_process_slack();
        self.call_reply_timeout()
            .map_or(bound, |p| p.min(bound))
            .min(self.transactor.initiator().reply_timeout())
    }

    /// How long a call (but a wait without limit) waits for its reply: the controller's
    /// reply time and a margin ([`Robot::set_reply_time`]); `None` where the controller
    /// did not say it, or the application set the reply timeout: then the manual's
    /// [`Robot::reply_timeout`].
    pub fn call_reply_timeout(&self) -> Option<Duration> {
        self.prompt.filter(|_| !self.reply_timeout_set)
    }

    /// The controller says "still working" every `interval` while it executes a request
    /// (docs/protocol.md, "Keep-alive"): a reply is then given up once the line has been
    /// silent for [`keepalive_silence`], however long the controller may take, so a
    /// controller that died is noticed within seconds even where a call may take long (a
    /// C500 behind the gateway stopping its arm). `None`: the reply timeout alone.
    /// A reply timeout the application set (SetL3_TO_Intervall) stays its own: no silence
    /// shortens it.
    pub fn set_keepalive(&mut self, interval: Option<Duration>) {
        let slack = self.in_process_slack();
        let silence = interval
            .filter(|_| !self.reply_timeout_set)
            .map(|i| keepalive_silence(i) + slack);
        self.transactor.initiator_mut().set_silence(silence);
    }

    /// What an in-process controller is given beyond a controller in another process
    /// ([`IN_PROCESS_SLACK`]): it cannot die apart from this program, only be held back.
    fn in_process_slack(&self) -> Duration {
        if self._embedded.is_some() {
            IN_PROCESS_SLACK
        } else {
            Duration::ZERO
        }
    }

    /// The longest silence a reply is waited through, where the controller keeps the line
    /// alive ([`Robot::set_keepalive`]; the version check learns it).
    pub fn keepalive_silence(&self) -> Option<Duration> {
        self.transactor.initiator().silence()
    }
}

impl std::fmt::Debug for Robot {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Robot")
            .field("transactor", &self.transactor)
            .field("embedded", &self._embedded.is_some())
            .field("broken", &self.broken)
            .finish_non_exhaustive()
    }
}

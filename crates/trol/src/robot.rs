//! The Rust API: a connection to the controller and one method per TROL API function, each
//! a thin skin over [`Robot::call`], which works from the command's description.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use trol_comm::{DefaultHandlers, ErrorHandlers, TransError, Transactor};
use trol_controller::Embedded;
use trol_port::{Port, PortSettings};
use trol_proto::application::code::{
    Code, CodeTable, TROL_ERR_ARG_RANGE, TROL_ERR_BAD_RSIZE, TROL_ERR_COMM,
};
use trol_proto::application::record::{self, RequestError, Value};
use trol_proto::application::table::{self, FINISH_STATUS, FINISH_WAIT};
use trol_proto::application::{
    Catalog, CatalogError, CodeEntry, CommandDef, Gripper, LocName, Location, Reply, ReplyError,
    Tag,
};
use trol_proto::link::{BlockCheck, LinkConfig, LinkError};
#[cfg(feature = "sim")]
use trol_sim::SimSettings;

use crate::config::Config;

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

/// Results of the API.
pub type Result<T> = std::result::Result<T, Error>;

/// How often a wait for the arm asks whether it still moves.
pub const POLL: Duration = Duration::from_millis(20);

/// The reply timeout of one poll of a wait (TROLFinish(FINISH_STATUS)): the controller
/// answers it at once (a C500 gateway after one STATUS, 0.7 s at 9600 Bd), so a controller
/// that dies during a wait is noticed within about 3 s (this, then one unanswered ENQ),
/// whatever the reply timeout of other calls.
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

/// The link settings of an in-process line: `cfg`'s block check, every timeout at least
/// [`IN_PROCESS_SLACK`].
#[cfg(any(feature = "sim", feature = "rapl", feature = "mars"))]
fn in_process(cfg: LinkConfig) -> LinkConfig {
    let t = cfg.timeouts;
    let at_least = |d: Duration| d.max(IN_PROCESS_SLACK);
    LinkConfig {
        timeouts: trol_proto::link::Timeouts {
            enq: at_least(t.enq),
            ack: at_least(t.ack),
            nak_code: at_least(t.nak_code),
            start: at_least(t.start),
            termc: at_least(t.termc),
            eot: at_least(t.eot),
            reset: t.reset,
        },
        ..cfg
    }
}

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

/// The error for a port this build cannot serve: the cargo feature it needs.
#[allow(dead_code)]
fn not_built(port: &str, feature: &str, what: &str) -> Error {
    SetupError::Config(format!(
        "port {port}: {what} needs TROL built with the cargo feature `{feature}` (this build \
         has no {what}: add `features = [\"{feature}\"]` to the trol dependency)"
    ))
    .into()
}

impl Robot {
    /// Connect over a port name as layer 1 accepts it (`/dev/ttyUSB0`, `COM1`,
    /// `socket://host:port`, `listen://host:port`), or `sim` for the embedded controller
    /// with default settings, and check the controller as every surface does: the same as
    /// [`Robot::connect`] (it skipped the check once, so that a program that opened a
    /// connection this way never learnt the controller's version, codes or reply time).
    pub fn open(port: &str, baud: u32) -> Result<Robot> {
        Robot::connect(port, baud)
    }

    /// Open the port and send nothing: for a tool that activates a controller in terminal
    /// mode first ([`crate::activate`]: InitTROL(0), `trol init`) or relays its bytes. The
    /// connection learns nothing of its controller until [`crate::check_server`] runs:
    /// without it, no repeats and the manual's reply timeout.
    pub fn open_unchecked(port: &str, baud: u32) -> Result<Robot> {
        Robot::open_checked(port, baud, None)
    }

    /// Connect and check the controller, as every surface does (the utilities, C's
    /// InitTROL(1) and trol_connect, Python's `Robot.open`): [`Robot::open`], then
    /// [`crate::check_server`]: GetStatus, the protocol version (GetVersion, refused with
    /// [`SetupError::Incompatible`]) and the controller's BIOS codes (GetCodes, for
    /// [`Robot::codes`]).
    pub fn connect(port: &str, baud: u32) -> Result<Robot> {
        let mut robot = Robot::open_unchecked(port, baud)?;
        crate::check_server(&mut robot)?;
        Ok(robot)
    }

    /// [`Robot::connect`] as trol.cfg says ([`Robot::from_config`], then the same check).
    pub fn connect_config(cfg: &Config) -> Result<Robot> {
        let mut robot = Robot::from_config(cfg)?;
        crate::check_server(&mut robot)?;
        Ok(robot)
    }

    /// Like [`Robot::open_unchecked`], with the link's block check (`check` in trol.cfg): no
    /// fallback to the manual's LRC.
    pub fn open_with(port: &str, baud: u32, check: BlockCheck) -> Result<Robot> {
        Robot::open_checked(port, baud, Some(check))
    }

    /// [`Robot::open_unchecked`] with the block check trol.cfg names, if any: without one, CRC-16,
    /// and the manual's LRC if the controller refuses every CRC-16 block at first contact
    /// and takes LRC ones (a controller that speaks only the manual's protocol).
    pub fn open_checked(port: &str, baud: u32, check: Option<BlockCheck>) -> Result<Robot> {
        let cfg = LinkConfig {
            check: check.unwrap_or_default(),
            ..LinkConfig::for_line(baud, Duration::ZERO)
        };
        if port == "sim" {
            #[cfg(feature = "sim")]
            return Ok(Robot::embedded_on(SimSettings::default(), cfg));
            #[cfg(not(feature = "sim"))]
            return Err(not_built(port, "sim", "the embedded simulator"));
        }
        if let Some(device) = port.strip_prefix(RAPL_PREFIX) {
            #[cfg(feature = "rapl")]
            return Robot::rapl(device, trol_rapl::Profile::default(), cfg);
            #[cfg(not(feature = "rapl"))]
            return Err(not_built(device, "rapl", "the RAPL-II backend"));
        }
        if port.starts_with(MARS_PREFIX) {
            return Err(SetupError::Config(format!(
                "{port}: an A465 on a MARS 8 needs its arm profile: name it in trol.cfg \
                 (`mars-profile = FILE`; crates/trol-mars/profiles/crs93.toml is CTU's CRS93) or call \
                 Robot::mars"
            ))
            .into());
        }
        let settings = PortSettings {
            baud,
            ..PortSettings::default()
        };
        let p = trol_port::open(port, &settings).map_err(SetupError::Port)?;
        let mut robot = Robot::over(p, cfg, None);
        robot.origin = Some((port.to_string(), settings));
        robot.check_auto = check.is_none();
        Ok(robot)
    }

    /// Connect as trol.cfg says (the embedded controller gets the file's `sim` settings;
    /// `rapl:DEVICE` embeds the controller with the RAPL-II backend on DEVICE, configured by
    /// `rapl-profile`).
    pub fn from_config(cfg: &Config) -> Result<Robot> {
        let mut robot = Robot::from_config_as_is(cfg)?;
        // A locations file that is not there yet is an empty table (docs/teach.md): said
        // once, so that a misspelt name is not a silent empty table.
        if let Some(file) = cfg.locations.as_ref().filter(|f| !f.exists()) {
            robot.add_notice(&format!(
                "{} does not exist yet: the location table starts empty, and \
                 TROLSaveLocations creates the file",
                file.display()
            ));
        }
        Ok(robot)
    }

    fn from_config_as_is(cfg: &Config) -> Result<Robot> {
        #[cfg(not(feature = "mars"))]
        if cfg.port.starts_with(MARS_PREFIX) {
            return Err(not_built(&cfg.port, "mars", "the MARS 8 backend"));
        }
        #[cfg(feature = "mars")]
        if let Some(device) = cfg.port.strip_prefix(MARS_PREFIX) {
            let profile = match &cfg.mars_profile {
                Some(path) => trol_mars::Profile::from_file(path)
                    .map_err(|e| SetupError::Config(e.to_string()))?,
                None => {
                    return Err(SetupError::Config(format!(
                        "port {}: an A465 on a MARS 8 needs its arm profile: add \
                         `mars-profile = FILE` to trol.cfg (crates/trol-mars/profiles/crs93.toml is CTU's \
                         CRS93; docs/mars.md)",
                        cfg.port
                    ))
                    .into());
                }
            };
            let link = LinkConfig {
                check: cfg.block_check(),
                ..LinkConfig::default()
            };
            let locations = crate::config_locations(cfg)?;
            // TROLSaveLocations writes trol.cfg's locations file back (docs/teach.md).
            return Robot::mars(device, profile, (locations, cfg.locations.clone()), link);
        }
        #[cfg(feature = "rapl")]
        if let Some(device) = cfg.port.strip_prefix(RAPL_PREFIX) {
            let profile = match &cfg.rapl_profile {
                Some(path) => trol_rapl::Profile::from_file(path)
                    .map_err(|e| SetupError::Config(e.to_string()))?,
                None => trol_rapl::Profile::default(),
            };
            let link = LinkConfig {
                check: cfg.block_check(),
                ..LinkConfig::default()
            };
            return Robot::rapl(device, profile, link);
        }
        #[cfg(feature = "sim")]
        if cfg.port == "sim" {
            let link = LinkConfig {
                check: cfg.block_check(),
                ..LinkConfig::default()
            };
            let settings = crate::sim_settings(cfg)?;
            return match &cfg.view {
                #[cfg(not(feature = "view"))]
                Some(_) => Err(SetupError::Config(
                    "trol.cfg asks for the live view (`view =`), and this build of TROL has \
                     none (the C library leaves it out): run `trol sim --view ADDR --port \
                     listen://127.0.0.1:PORT` and name `socket://127.0.0.1:PORT` as the port"
                        .into(),
                )
                .into()),
                #[cfg(feature = "view")]
                Some(addr) => {
                    let robot = Robot::embedded_viewed(settings, link, addr)?;
                    // trol.cfg asked for it: say where it is (port 0 picks one).
                    if let Some(view) = &robot.view {
                        eprintln!("trol: the view of the simulated arm: {}", view.url());
                        if let Some(w) = view.exposure() {
                            eprintln!("trol: warning: {w}");
                        }
                    }
                    Ok(robot)
                }
                None => Ok(Robot::embedded_on(settings, link)),
            };
        }
        Robot::open_checked(&cfg.port, cfg.baud, cfg.check)
    }

    /// Connect as ./trol.cfg (or $TROL_CONFIG) says.
    pub fn from_default_config() -> Result<Robot> {
        let cfg = Config::load().map_err(|e| SetupError::Config(e.to_string()))?;
        Robot::from_config(&cfg)
    }

    #[cfg(feature = "rapl")]
    /// Embed the controller with the RAPL-II backend: open DEVICE (a serial device, or
    /// `socket://HOST:PORT`) at the profile's baud rate, open the RAPL-II session, and serve
    /// TROL to this process over an in-memory line (docs/c500.md).
    pub fn rapl(device: &str, profile: trol_rapl::Profile, link: LinkConfig) -> Result<Robot> {
        let settings = PortSettings {
            baud: profile.baud,
            ..PortSettings::default()
        };
        let port = trol_port::open(device, &settings).map_err(SetupError::Port)?;
        // The controller's texts (refusals, what it says unasked, resynchronisations) go to the
        // log as the gateway prints them: `-v` in the utilities, RUST_LOG=trol=info elsewhere.
        let backend = trol_rapl::RaplBackend::connect_with(
            port,
            profile,
            Some(Box::new(
                |line: &str| tracing::info!(target: "trol::rapl", "c500: {line}"),
            )),
            None,
        )
        .map_err(|e| SetupError::NoServer(e.to_string()))?;
        let reply_time = trol_controller::Backend::reply_time(&backend);
        let link = in_process(link);
        let (line, handle) =
            trol_controller::embedded_with(trol_controller::Pcp::new(backend), link);
        let mut robot = Robot::over(Box::new(line), link, Some(handle));
        robot.set_reply_time(reply_time);
        robot.codes = trol_rapl::RAPL_CODES;
        Ok(robot)
    }

    #[cfg(feature = "mars")]
    /// Embed the controller with the MARS 8 backend: open DEVICE (a serial device with
    /// RTS/CTS, or `socket://HOST:PORT`) at the profile's baud rate, read the unit's state
    /// (nothing moves), and serve TROL to this process over an in-memory line
    /// (docs/mars.md). TROL's own location table starts with `locations`: the locations and
    /// the file they came from, which TROLSaveLocations writes back (docs/teach.md).
    pub fn mars(
        device: &str,
        profile: trol_mars::Profile,
        locations: (
            Vec<(String, trol_a465::arm::Stored)>,
            Option<std::path::PathBuf>,
        ),
        link: LinkConfig,
    ) -> Result<Robot> {
        let (locations, file) = locations;
        let settings = PortSettings {
            baud: profile.baud,
            rts_cts: true,
            ..PortSettings::default()
        };
        let port = trol_port::open(device, &settings).map_err(SetupError::Port)?;
        let backend = trol_mars::MarsBackend::connect(
            port,
            profile,
            Some(Box::new(
                |line: &str| tracing::info!(target: "trol::mars", "mars: {line}"),
            )),
            None,
            locations,
        )
        .map_err(|e| SetupError::NoServer(e.to_string()))?;
        let mut backend = backend;
        backend.set_locations_file(file);
        let reply_time = trol_controller::Backend::reply_time(&backend);
        let link = in_process(link);
        let (line, handle) =
            trol_controller::embedded_with(trol_controller::Pcp::new(backend), link);
        let mut robot = Robot::over(Box::new(line), link, Some(handle));
        robot.set_reply_time(reply_time);
        robot.codes = trol_mars::MARS_CODES;
        Ok(robot)
    }

    /// Start an embedded controller (simulated A465) and connect to it.
    #[cfg(feature = "sim")]
    pub fn embedded(settings: SimSettings) -> Robot {
        Robot::embedded_on(settings, LinkConfig::default())
    }

    /// Start an embedded controller (simulated A465) whose live 3D view is served at `addr`
    /// (`host:port`; docs: crates/trol-view), and connect to it. The view lives as long as the
    /// connection; [`Robot::view_url`] says where it is.
    #[cfg(feature = "view")]
    pub fn embedded_viewed(settings: SimSettings, cfg: LinkConfig, addr: &str) -> Result<Robot> {
        let mut backend = trol_sim::SimBackend::new(settings);
        let shared = backend.share();
        let view = trol_view::serve(addr, shared)
            .map_err(|e| SetupError::Config(format!("cannot serve the view at {addr}: {e}")))?;
        let cfg = in_process(cfg);
        let (line, handle) =
            trol_controller::embedded_with(trol_controller::Pcp::new(backend), cfg);
        let mut robot = Robot::over(Box::new(line), cfg, Some(handle));
        robot.set_reply_time(SIM_REPLY_TIME);
        robot.view = Some(view);
        Ok(robot)
    }

    /// Where the live view of an embedded simulator is served, if it is.
    pub fn view_url(&self) -> Option<String> {
        #[cfg(feature = "view")]
        return self.view.as_ref().map(|v| v.url());
        #[cfg(not(feature = "view"))]
        None
    }

    /// A warning when the live view is open to other machines (see
    /// [`trol_view::ViewServer::exposure`]).
    pub fn view_exposure(&self) -> Option<String> {
        #[cfg(feature = "view")]
        return self.view.as_ref().and_then(|v| v.exposure());
        #[cfg(not(feature = "view"))]
        None
    }

    #[cfg(feature = "sim")]
    fn embedded_on(settings: SimSettings, cfg: LinkConfig) -> Robot {
        let cfg = in_process(cfg);
        let (line, handle) = trol_sim::embedded(settings, cfg);
        let mut robot = Robot::over(Box::new(line), cfg, Some(handle));
        robot.set_reply_time(SIM_REPLY_TIME);
        robot
    }

    /// Connect over a port that is already open (for tests, relays, and controllers of the
    /// application's own). `embedded` keeps an in-process controller alive as long as the
    /// connection.
    ///
    /// A request whose transaction failed is sent again (exactly once, docs/protocol.md) only
    /// to a controller that announced its memory of the last request: an in-process one, or
    /// one whose version check ([`Robot::check_version`], part of [`Robot::connect`]) found
    /// this protocol. Until then, and for a controller that speaks only the manual's
    /// protocol, the first failure is the call's, as in the manual ([`Robot::set_repeats`]
    /// chooses otherwise).
    pub fn over(port: Box<dyn Port>, cfg: LinkConfig, embedded: Option<Embedded>) -> Robot {
        let catalog = Catalog::builtin();
        let mut transactor = Transactor::new(port, cfg);
        if embedded.is_none() {
            transactor.set_repeats(0);
        }
        let mut robot = Robot {
            transactor,
            catalog,
            own_handlers: false,
            codes: crate::default_codes(),
            _embedded: embedded,
            origin: None,
            broken: false,
            reactivate: None,
            epoch: None,
            #[cfg(feature = "view")]
            view: None,
            kept: Vec::new(),
            check_auto: false,
            check_settled: false,
            lrc_tried: false,
            repeats_set: false,
            manual_peer: false,
            prompt: None,
            reply_timeout_set: false,
            notice: None,
        };
        robot.default_handlers();
        robot
    }

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

    /// Open the port again now (after a failure, or when the controller restarted), check the
    /// server with GetStatus, and activate it if it is in terminal mode and
    /// [`Robot::set_reactivate`] allows.
    pub fn reconnect(&mut self) -> Result<()> {
        let Some((name, settings)) = self.origin.clone() else {
            return Err(SetupError::NoServer(
                "this connection was not opened by a port name, so it cannot be opened again"
                    .into(),
            )
            .into());
        };
        let port = trol_port::open(&name, &settings).map_err(SetupError::Port)?;
        self.transactor.replace_port(port);
        self.broken = false;
        // A probe: one attempt, so that a controller in terminal mode is found out quickly.
        let repeats = self.transactor.repeats();
        self.transactor.set_repeats(0);
        let probe = self.status_record();
        self.transactor.set_repeats(repeats);
        match probe {
            Ok(status) if self.note_status_form(&status) => Ok(()),
            Ok(_) => self.check_version().map(drop),
            Err(e) => match self.reactivate {
                Some(tool) => crate::activate(self, &tool),
                None => Err(e),
            },
        }
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
        let short = match (poll, prompt) {
            (true, Some(p)) => Some(p.min(POLL_REPLY_TIMEOUT)),
            (true, None) => Some(POLL_REPLY_TIMEOUT),
            (false, p) => p,
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

    /// The reply timeout (SetL3_TO_Intervall).
    pub fn reply_timeout(&self) -> Duration {
        self.transactor.reply_timeout()
    }

    /// How long a call (but a wait without limit) waits for its reply: the controller's
    /// reply time and a margin ([`Robot::set_reply_time`]); `None` where the controller
    /// did not say it, or the application set the reply timeout: then the manual's
    /// [`Robot::reply_timeout`].
    pub fn call_reply_timeout(&self) -> Option<Duration> {
        self.prompt.filter(|_| !self.reply_timeout_set)
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
    pub fn status_record(&mut self) -> Result<StatusRecord> {
        let def = &table::GET_STATUS;
        match self.call(def, &[])? {
            Reply::Status {
                bios_called,
                last,
                transaction,
                epoch,
            } => {
                self.epoch = Some(epoch);
                Ok(StatusRecord {
                    bios_called,
                    last,
                    transaction,
                    epoch,
                })
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
    fn reply_times(&mut self) -> Result<(Duration, Option<Duration>)> {
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
    /// [`StatusRecord::transaction`] names the one its status belongs to).
    pub fn last_transaction(&self) -> u8 {
        self.transactor.transaction_number()
    }
}

/// With the manual's LRC, which lets damage through that a CRC finds: a reply to a request
/// of `def` is plausible when its PCI's reserved bits are clear and it decodes in the form
/// the command has, a return value being one the command counts as success or one the
/// controller's code table knows. Layer 2 asks again for one that is not (the same bytes
/// twice are taken), so a damaged reply is not taken for another answer.
fn reply_check(def: &CommandDef, codes: &'static CodeTable) -> trol_proto::link::Plausible {
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

fn cart(v: &[f64]) -> Value {
    Value::Loc(Location::Cart(v.to_vec()))
}

/// A small whole number for the byte the table gives it; its range is checked by the table.
fn small(def: &CommandDef, v: u16) -> Result<Value> {
    u8::try_from(v).map(Value::Int).map_err(|_| {
        Error::Argument(RequestError::Range {
            command: def.name,
            arg: def.args.first().map_or("(argument)", |a| a.name),
            what: format!("{v} out of range"),
        })
    })
}

/// A precision point's name starts with `#`, and only a precision point's (RAPL-II's rule).
fn precision_name(def: &CommandDef, name: &str, tag: Tag) -> Result<()> {
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

fn loc_name(def: &CommandDef, name: &str) -> Result<Value> {
    LocName::new(name).map(Value::Name).map_err(|e| {
        Error::Argument(RequestError::Range {
            command: def.name,
            arg: "locName",
            what: e.to_string(),
        })
    })
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

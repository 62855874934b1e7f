//! The Rust API: a connection to the controller and one method per TROL API function.

use std::time::Duration;

use trol_comm::{DefaultHandlers, ErrorHandlers, ExtraWait, TransError, Transactor};
use trol_controller::{Embedded, SimSettings};
use trol_port::{Port, PortSettings};
use trol_proto::application::codes::Command;
use trol_proto::application::errors::{TROL_ERR_ARG_RANGE, TROL_ERR_BAD_RSIZE, TROL_ERR_COMM};
use trol_proto::application::request::long_wait;
use trol_proto::application::{
    FinishMode, LocName, Location, PosMode, Reply, ReplyError, Request, RequestError, Tag,
};
use trol_proto::link::{LinkConfig, LinkError};

use crate::config::Config;

/// Why an API call did not succeed. "The controller said no" ([`Error::Refused`]) is kept
/// apart from "the link failed" ([`Error::Link`]); [`Error::code`] gives the manual's code.
#[derive(Debug)]
pub enum Error {
    /// The controller answered with a non-zero value: a BIOS code (> -32000), or a TROL code
    /// the controller detected (TROL_ERR_UNKNOWN, TROL_ERR_BAD_CSIZE, TROL_ERR_LOCATION,
    /// TROL_RETVAL_RANGE, TROL_ERR_ARG_RANGE).
    Refused {
        /// The command's code (a built-in one, or one an application added).
        command: u8,
        /// The value.
        code: i16,
    },
    /// An argument is out of range; nothing was sent (TROL_ERR_ARG_RANGE).
    Argument(RequestError),
    /// The transaction failed and the error handler could not mend it (TROL_ERR_COMM).
    Link {
        /// The command.
        command: Option<Command>,
        /// What failed.
        error: TransError,
    },
    /// The reply did not fit the command (TROL_ERR_BAD_RSIZE).
    BadReply {
        /// The command's code.
        command: u8,
        /// The reply's length.
        len: usize,
    },
    /// The port could not be opened, or the configuration is wrong.
    Setup(String),
}

impl Error {
    /// The manual's return code of this error.
    pub fn code(&self) -> i16 {
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

impl std::fmt::Display for Error {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Error::Refused { command, code } => {
                write!(
                    f,
                    "{} returned {}",
                    command_name(*command),
                    crate::describe(*code)
                )
            }
            Error::Argument(e) => write!(f, "{e}"),
            Error::Link { command, error } => match command {
                Some(c) => write!(f, "TROL_ERR_COMM: {c}: {error}"),
                None => write!(f, "TROL_ERR_COMM: {error}"),
            },
            Error::BadReply { command, len } => write!(
                f,
                "TROL_ERR_BAD_RSIZE: a reply of {len} bytes does not fit {}",
                command_name(*command)
            ),
            Error::Setup(why) => write!(f, "{why}"),
        }
    }
}

impl std::error::Error for Error {}

fn command_name(code: u8) -> String {
    match Command::from_code(code) {
        Some(c) => c.to_string(),
        None => format!("command {code}"),
    }
}

impl From<ReplyError> for Error {
    fn from(e: ReplyError) -> Self {
        Error::BadReply {
            command: e.command.code(),
            len: e.len,
        }
    }
}

/// Results of the API.
pub type Result<T> = std::result::Result<T, Error>;

/// The manual's default ErrAppTimeOut policy: 90 s more for Home, no limit for
/// Finish(FINISH_WAIT).
pub fn timeout_policy(request: &[u8]) -> Option<ExtraWait> {
    long_wait(request).map(|w| match w {
        Some(d) => ExtraWait::Up(d),
        None => ExtraWait::Unlimited,
    })
}

/// A connection to a TROL controller.
pub struct Robot {
    transactor: Transactor<Box<dyn Port>>,
    _embedded: Option<Embedded>,
}

impl Robot {
    /// Connect over a port name as layer 1 accepts it (`/dev/ttyUSB0`, `COM1`,
    /// `socket://host:port`, `listen://host:port`), or `sim` for the embedded controller
    /// with default settings.
    pub fn open(port: &str, baud: u32) -> Result<Robot> {
        if port == "sim" {
            return Ok(Robot::embedded(SimSettings::default()));
        }
        let settings = PortSettings {
            baud,
            ..PortSettings::default()
        };
        let p = trol_port::open(port, &settings)
            .map_err(|e| Error::Setup(format!("cannot open port {port}: {e}")))?;
        Ok(Robot::over(
            p,
            LinkConfig::for_line(baud, Duration::ZERO),
            None,
        ))
    }

    /// Connect as trol.cfg says (the embedded controller gets the file's `sim` settings).
    pub fn from_config(cfg: &Config) -> Result<Robot> {
        if cfg.port == "sim" {
            return Ok(Robot::embedded(crate::sim_settings(cfg)?));
        }
        Robot::open(&cfg.port, cfg.baud)
    }

    /// Connect as ./trol.cfg (or $TROL_CONFIG) says.
    pub fn from_default_config() -> Result<Robot> {
        let cfg = Config::load().map_err(|e| Error::Setup(e.to_string()))?;
        Robot::from_config(&cfg)
    }

    /// Start an embedded controller (simulated A465) and connect to it.
    pub fn embedded(settings: SimSettings) -> Robot {
        let cfg = LinkConfig::default();
        let (line, handle) = trol_controller::embedded(settings, cfg);
        Robot::over(Box::new(line), cfg, Some(handle))
    }

    /// Connect over a port that is already open (for tests and relays). `embedded` keeps an
    /// in-process controller alive as long as the connection.
    pub fn over(port: Box<dyn Port>, cfg: LinkConfig, embedded: Option<Embedded>) -> Robot {
        let mut transactor = Transactor::new(port, cfg);
        transactor.set_handlers(Box::new(DefaultHandlers::with_policy(timeout_policy)));
        Robot {
            transactor,
            _embedded: embedded,
        }
    }

    /// Replace the layer-3 error handlers (ErrOnSend, ErrOnReceive, ErrAppTimeOut).
    pub fn set_handlers(&mut self, handlers: Box<dyn ErrorHandlers>) {
        self.transactor.set_handlers(handlers);
    }

    /// SetL3_TO_Intervall: the reply timeout in tenths of a second (default 150).
    pub fn set_reply_timeout_tenths(&mut self, tenths: u16) {
        self.transactor.set_reply_timeout_tenths(tenths);
    }

    /// SetDelay: a pause between two bytes sent.
    pub fn set_delay(&mut self, delay: Duration) {
        self.transactor.driver_mut().set_delay(delay);
    }

    /// GetLastCommErr: the last layer-2 failure.
    pub fn last_comm_error(&self) -> Option<LinkError> {
        self.transactor.last_comm_error()
    }

    /// The layer-3 machinery (port, driver, link settings).
    pub fn transactor_mut(&mut self) -> &mut Transactor<Box<dyn Port>> {
        &mut self.transactor
    }

    /// Send raw request bytes and return the raw reply (for added commands).
    pub fn transact_raw(&mut self, request: &[u8]) -> Result<Vec<u8>> {
        self.transactor
            .trans_sr(request)
            .map_err(|error| Error::Link {
                command: request.first().and_then(|c| Command::from_code(*c)),
                error,
            })
    }

    /// The manual's Cat1Transaction: send a CAT1 request; its one-word reply is returned
    /// (0 as `Ok`, anything else as [`Error::Refused`] unless `ok_values` lists it).
    pub fn cat1_transaction(&mut self, request: &[u8], ok_values: &[i16]) -> Result<i16> {
        let command = request.first().copied().unwrap_or_default();
        let reply = self.transact_raw(request)?;
        let value = match reply.as_slice() {
            [a, b] => i16::from_le_bytes([*a, *b]),
            _ => {
                return Err(Error::BadReply {
                    command,
                    len: reply.len(),
                });
            }
        };
        if value == 0 || ok_values.contains(&value) {
            Ok(value)
        } else {
            Err(Error::Refused {
                command,
                code: value,
            })
        }
    }

    /// Give the port back, ending the connection (`trol link` activates the controller, then
    /// relays over the same port). An embedded controller stops.
    pub fn into_port(self) -> Box<dyn Port> {
        self.transactor.into_port()
    }

    /// Check, send and decode a built-in request.
    pub fn request(&mut self, req: &Request) -> Result<Reply> {
        req.validate().map_err(Error::Argument)?;
        let command = req.command();
        let bytes = self
            .transactor
            .trans_sr(&req.encode())
            .map_err(|error| Error::Link {
                command: Some(command),
                error,
            })?;
        Ok(Reply::decode(command, &bytes)?)
    }

    fn cat1(&mut self, req: Request, ok: &[i16]) -> Result<i16> {
        let command = req.command();
        match self.request(&req)? {
            Reply::Code(v) if v == 0 || ok.contains(&v) => Ok(v),
            Reply::Code(code) => Err(Error::Refused {
                command: command.code(),
                code,
            }),
            other => Err(Error::BadReply {
                command: command.code(),
                len: other.encode().len(),
            }),
        }
    }

    fn cart6(v: &[f64], command: Command, max: usize) -> Result<Vec<f32>> {
        if v.is_empty() || v.len() > max {
            return Err(Error::Argument(RequestError::Range {
                command,
                what: format!("{} values given, allowed 1..{max}", v.len()),
            }));
        }
        Ok(v.iter().map(|x| *x as f32).collect())
    }

    /// TROLAppro: approach the named location, displaced by `disp` (x y z yaw pitch roll,
    /// 1..6 values) in its tool frame.
    pub fn appro(&mut self, name: &str, disp: &[f64], straight: bool) -> Result<()> {
        let name = loc_name(name, Command::Appro)?;
        let disp = Robot::cart6(disp, Command::Appro, 6)?;
        self.cat1(
            Request::Appro {
                name,
                disp,
                straight,
            },
            &[],
        )
        .map(drop)
    }

    /// TROLApproII: approach a given location (cartesian or precision point).
    pub fn appro_ii(&mut self, target: &Location, disp: &[f64], straight: bool) -> Result<()> {
        let disp = Robot::cart6(disp, Command::ApproII, 6)?;
        let req = Request::ApproII {
            target: target.clone(),
            disp,
            straight,
        };
        self.cat1(req, &[]).map(drop)
    }

    /// TROLClose: close the gripper with `force` percent (1..100).
    pub fn close(&mut self, force: u16) -> Result<()> {
        let force = small(force, Command::Close)?;
        self.cat1(Request::Close { force }, &[]).map(drop)
    }

    /// TROLDepart: move by `disp` in the tool frame from where the arm is.
    pub fn depart(&mut self, disp: &[f64], straight: bool) -> Result<()> {
        let disp = Robot::cart6(disp, Command::Depart, 6)?;
        self.cat1(Request::Depart { disp, straight }, &[]).map(drop)
    }

    /// TROLFinish(FINISH_WAIT): wait until the arm and the gripper are done.
    pub fn finish(&mut self) -> Result<()> {
        let mode = FinishMode::Wait;
        self.cat1(Request::Finish { mode }, &[]).map(drop)
    }

    /// TROLFinish(FINISH_STATUS): whether the arm or the gripper still moves.
    pub fn is_moving(&mut self) -> Result<bool> {
        let mode = FinishMode::Status;
        self.cat1(Request::Finish { mode }, &[1]).map(|v| v == 1)
    }

    /// TROLGrip: the fingers to `dist` mm (0..50).
    pub fn grip(&mut self, dist: u16) -> Result<()> {
        let dist = small(dist, Command::Grip)?;
        self.cat1(Request::Grip { dist }, &[]).map(drop)
    }

    /// TROLHalt: stop all motion.
    pub fn halt(&mut self) -> Result<()> {
        self.cat1(Request::Halt, &[]).map(drop)
    }

    /// TROLHome: home one axis (1..6) or all (0).
    pub fn home(&mut self, axis: u16) -> Result<()> {
        let axis = small(axis, Command::Home)?;
        self.cat1(Request::Home { axis }, &[]).map(drop)
    }

    /// TROLJog: move the tool by dx [dy [dz]] in the world frame, orientation kept.
    pub fn jog(&mut self, d: &[f64], straight: bool) -> Result<()> {
        let disp = Robot::cart6(d, Command::Jog, 3)?;
        self.cat1(Request::Jog { disp, straight }, &[]).map(drop)
    }

    /// TROLJoint: move joint `joint` (1..6) by `radians`.
    pub fn joint(&mut self, joint: u16, radians: f64) -> Result<()> {
        let joint = small(joint, Command::Joint)?;
        let radians = radians as f32;
        self.cat1(Request::Joint { joint, radians }, &[]).map(drop)
    }

    /// TROLMA: all joints to absolute angles (1..6 values, the rest 0).
    pub fn ma(&mut self, joints: &[f64]) -> Result<()> {
        let joints = Robot::cart6(joints, Command::Ma, 6)?;
        self.cat1(Request::Ma { joints }, &[]).map(drop)
    }

    /// TROLMI: all joints by increments.
    pub fn mi(&mut self, joints: &[f64]) -> Result<()> {
        let joints = Robot::cart6(joints, Command::Mi, 6)?;
        self.cat1(Request::Mi { joints }, &[]).map(drop)
    }

    /// TROLMove: to the named location.
    pub fn move_to(&mut self, name: &str, straight: bool) -> Result<()> {
        let name = loc_name(name, Command::Move)?;
        self.cat1(Request::Move { name, straight }, &[]).map(drop)
    }

    /// TROLMoveII: to a given location (cartesian or precision point).
    pub fn move_ii(&mut self, target: &Location, straight: bool) -> Result<()> {
        let req = Request::MoveII {
            target: target.clone(),
            straight,
        };
        self.cat1(req, &[]).map(drop)
    }

    /// TROLOpen: open the gripper with `force` percent (1..100).
    pub fn open_gripper(&mut self, force: u16) -> Result<()> {
        let force = small(force, Command::Open)?;
        self.cat1(Request::Open { force }, &[]).map(drop)
    }

    /// TROLReady: to the READY pose.
    pub fn ready(&mut self) -> Result<()> {
        self.cat1(Request::Ready, &[]).map(drop)
    }

    /// TROLSetToolTransform: x y z yaw pitch roll of the tool tip in the tool frame.
    pub fn set_tool_transform(&mut self, tool: &[f64]) -> Result<()> {
        let tool = Robot::cart6(tool, Command::SetToolTransform, 6)?;
        self.cat1(Request::SetToolTransform { tool }, &[]).map(drop)
    }

    /// TROLSpeed: percent of the maximum speed (1..150).
    pub fn speed(&mut self, percent: u16) -> Result<()> {
        let percent = small(percent, Command::Speed)?;
        self.cat1(Request::Speed { percent }, &[]).map(drop)
    }

    /// TROLGetPosition: the position in the form `tag`, commanded or actual.
    pub fn position(&mut self, tag: Tag, mode: PosMode) -> Result<Location> {
        match self.request(&Request::GetPosition { tag, mode })? {
            Reply::Position(loc) if loc.tag() == tag => Ok(loc),
            Reply::Code(code) => Err(Error::Refused {
                command: Command::GetPosition.code(),
                code,
            }),
            other => Err(Error::BadReply {
                command: Command::GetPosition.code(),
                len: other.encode().len(),
            }),
        }
    }

    /// TROLTerminatePCP: end server mode.
    pub fn terminate_pcp(&mut self) -> Result<()> {
        self.cat1(Request::TerminatePcp, &[]).map(drop)
    }

    /// TROLGetStatus: whether the last CAT1/CAT2 command called the BIOS, and the BIOS's
    /// value or the TROL code that kept it from being called.
    pub fn status(&mut self) -> Result<(bool, i16)> {
        match self.request(&Request::GetStatus)? {
            Reply::Status { bios_called, last } => Ok((bios_called, last)),
            Reply::Code(code) => Err(Error::Refused {
                command: Command::GetStatus.code(),
                code,
            }),
            other => Err(Error::BadReply {
                command: Command::GetStatus.code(),
                len: other.encode().len(),
            }),
        }
    }
}

fn small(v: u16, command: Command) -> Result<u8> {
    u8::try_from(v).map_err(|_| {
        Error::Argument(RequestError::Range {
            command,
            what: format!("{v} out of range"),
        })
    })
}

fn loc_name(name: &str, command: Command) -> Result<LocName> {
    LocName::new(name).map_err(|e| {
        Error::Argument(RequestError::Range {
            command,
            what: e.to_string(),
        })
    })
}

//! TROL: drive a CRS A465 arm through its C500 controller.
//!
//! The Rust API is [`Robot`]: connect it to a port (or `sim`, the embedded simulated
//! controller) with [`Robot::connect`] or the builder [`Connect`], which always checks the
//! controller's protocol version, then call one method per TROL API function. Errors keep "the controller said
//! no" ([`Error::Refused`]) apart from "the link failed" ([`Error::Link`]), and
//! [`Error::code`] gives the manual's return code.
//!
//! ```
//! use trol::{Connect, SimSettings, Tag, PosMode};
//! let mut robot = Connect::sim(SimSettings { time_scale: 100.0, ..SimSettings::default() })
//!     .connect()?;
//! robot.home(0)?;
//! robot.joint(1, 0.5)?;
//! robot.finish()?;
//! let joints = robot.position(Tag::Joint, PosMode::Commanded)?;
//! assert!((joints.to_array6()[0] - 0.5).abs() < 1e-6);
//! // Every command is also reachable through its description, built-in or added:
//! let reply = robot.call(&trol::table::GET_STATUS, &[])?;
//! assert!(reply.text(robot.codes()).starts_with("BIOSCalled 1, lastErrorCode 0 (success)"));
//! # Ok::<(), trol::Error>(())
//! ```
//!
//! # Cargo features
//!
//! The client itself needs only the protocol core, the ports and the link. Each backend an
//! in-process controller can have is a feature:
//!
//! | feature | default | what it adds |
//! |---|---|---|
//! | `sim` | yes | the embedded simulated A465: port `sim`, [`Connect::sim`] |
//! | `rapl` | yes | a real C500 in RAPL-II: port `rapl:DEVICE`, `Connect::rapl_profile` |
//! | `mars` | yes | an A465 on a MARS 8: port `mars:DEVICE`, `Connect::mars_profile` |
//! | `c500c` | yes | an A465 on its C500C, through ash: port `c500c:DEVICE`, `Connect::c500c_profile` |
//! | `view` | no | the live 3D view of the embedded simulator (`view =` in trol.cfg) |
//!
//! The manual's C API (`include/trol.h`, `libtrol.so`, `libtrol.a`) is the crate `trol-c`
//! over this one.

#![warn(missing_docs, missing_debug_implementations)]

pub mod codes;
pub mod config;
pub mod described;
mod robot;

pub use config::{Config, ConfigError};
pub use robot::{
    C500C_PREFIX, Connect, ControllerVersion, Error, FinishWait, IN_PROCESS_SLACK,
    KEEPALIVE_SILENCE, MARS_PREFIX, MAX_DELAY_MS, MAX_REPLY_TENTHS, POLL, POLL_REPLY_TIMEOUT,
    PosMode, Result, Robot, SetupError, StatusRecord, Timing, Waited, prompt_policy,
    prompt_reply_timeout, timeout_policy, wait_idle,
};
pub use trol_proto::application::code::{self, Code, CodeInfo, CodeTable};
pub use trol_proto::application::record::Value;
pub use trol_proto::application::table;
pub use trol_proto::application::{
    Arg, ArgKind, Catalog, Choice, CodeEntry, CommandDef, Gripper, Held, LocName, Location,
    MAX_WAYPOINTS, Reply, ReplyKind, Tag, Wait, Waypoint,
};
use trol_proto::link::BlockCheck;
#[cfg(feature = "sim")]
pub use trol_sim::SimSettings;

#[cfg(feature = "sim")]
use trol_a465::arm::{ArmSettings, parse_objects};

#[cfg(feature = "sim")]
fn read_config_file(path: &std::path::Path) -> Result<String> {
    std::fs::read_to_string(path)
        .map_err(|e| SetupError::Config(format!("{}: {e}", path.display())).into())
}

/// The locations trol.cfg's `locations =` file holds (none without one). A file that does
/// not exist yet, in a folder that does, starts an empty table: TROLSaveLocations creates it
/// (docs/teach.md); a missing folder, a file beyond the table's 1000 locations or a
/// reserved name is refused here, before anything is sent.
#[cfg(any(feature = "sim", feature = "mars"))]
pub fn config_locations(cfg: &Config) -> Result<Vec<(String, trol_a465::arm::Stored)>> {
    match &cfg.locations {
        Some(path) => {
            trol_a465::backend::table::load(path).map_err(|e| SetupError::Config(e).into())
        }
        None => Ok(Vec::new()),
    }
}

/// The settings of the embedded controller from trol.cfg.
#[cfg(feature = "sim")]
pub fn sim_settings(cfg: &Config) -> Result<SimSettings> {
    let objects = match &cfg.objects {
        Some(path) => parse_objects(&read_config_file(path)?)
            .map_err(|e| SetupError::Config(format!("{}: {e}", path.display())))?,
        None => Vec::new(),
    };
    Ok(SimSettings {
        arm: ArmSettings {
            table_z: cfg.table_z,
            object_width: cfg.object,
            objects,
            homed: cfg.homed,
            ..ArmSettings::default()
        },
        time_scale: cfg.time_scale,
        locations: config_locations(cfg)?,
        locations_file: cfg.locations.clone(),
        tool: cfg.tool,
    })
}

/// A return value with its name, BIOS codes named as the simulated A465 names them:
/// `0 (success)`, `-32102 (TROL_ERR_LOCATION)`, `-1 (BIOS_NOT_HOMED)`. A [`Robot`] names
/// them from its controller's table ([`Robot::codes`]).
pub fn describe(value: i16) -> String {
    Code(value).describe(default_codes())
}

/// The BIOS codes a connection names before its controller has told its own: the simulated
/// A465's (with the feature `sim`; otherwise none, and BIOS codes go by number).
pub fn default_codes() -> &'static CodeTable {
    #[cfg(feature = "sim")]
    return trol_sim::SIM_CODES;
    #[cfg(not(feature = "sim"))]
    &[]
}

/// Whether a transaction failed because the controller refused every block this end sent as
/// damaged: the two ends check blocks differently (or the line is very noisy). Nothing
/// arrived, so nothing ran.
pub(crate) fn refused_every_block(error: &trol_comm::TransError) -> bool {
    matches!(
        error,
        trol_comm::TransError::Failed {
            last_comm: Some(trol_proto::link::LinkError::Send(
                trol_proto::link::codes::SendError::LimitExceeded
            )),
            ..
        }
    )
}

/// Check that the server answers (InitTROL(1)): one GetStatus transaction, then its protocol
/// version ([`Robot::check_version`]). A controller whose GetStatus has the manual's 4 bytes
/// speaks only the manual's protocol (a 1998 TROL server): it has no version to check, and
/// the connection says so once ([`Robot::take_notice`]).
pub fn check_server(robot: &mut Robot) -> Result<()> {
    // A probe: one attempt, so that a controller in terminal mode is found out quickly.
    let repeats = robot.transactor_mut().repeats();
    robot.transactor_mut().set_repeats(0);
    let status = robot.status_record();
    robot.transactor_mut().set_repeats(repeats);
    let checked = status.and_then(|s| {
        if robot.note_status_form(&s) {
            Ok(())
        } else {
            robot.check_version().map(drop)
        }
    });
    let e = match checked {
        Ok(_) => return Ok(()),
        Err(e @ Error::Setup(SetupError::Incompatible { .. })) => return Err(e),
        Err(e) => e,
    };
    let busy = matches!(
        &e,
        Error::Link { error: trol_comm::TransError::Io(io), .. }
            if io.kind() == std::io::ErrorKind::ConnectionRefused
    );
    if busy {
        return Err(Error::Setup(SetupError::NoServer(format!(
            "{e}; only one application at a time can drive the controller"
        ))));
    }
    // Every block refused as damaged: the two ends check blocks differently, as a 1998
    // controller (LRC) and TROL's default (CRC-16) do; a noisy line or another baud rate can
    // do the same.
    let damaged = matches!(&e, Error::Link { error, .. } if refused_every_block(error));
    if damaged && robot.tried_lrc() {
        return Err(Error::Setup(SetupError::NoServer(format!(
            "the controller refused every block this end sent as damaged ({e}), checked with \
             CRC-16 and with the manual's LRC: the line is noisy, or the baud rate differs"
        ))));
    }
    if damaged {
        let check = robot.transactor_mut().initiator().link().config().check;
        let other = match check {
            trol_proto::link::BlockCheck::Crc16 => "lrc",
            trol_proto::link::BlockCheck::Lrc => "crc16",
        };
        return Err(Error::Setup(SetupError::NoServer(format!(
            "the controller refused every block this end sent as damaged ({e}): it checks \
             blocks another way (a 1998 TROL controller uses the manual's LRC: add `check = \
             {other}` to trol.cfg), or the line is noisy, or the baud rate differs"
        ))));
    }
    Err(Error::Setup(SetupError::NoServer(
        match shared_port(robot) {
            Some(shared) => format!("the controller's TROL server does not answer ({e}); {shared}"),
            None => format!(
                "the controller's TROL server does not answer ({e}); check the cable and the \
             port, that the baud rate in trol.cfg matches the controller, and that `trol \
             init` has activated the server"
            ),
        },
    )))
}

/// When another program has the robot's device open too (it takes the controller's
/// answers): what to say.
fn shared_port(robot: &mut Robot) -> Option<String> {
    let port = robot.transactor_mut().driver_mut().port_mut().name();
    let others = trol_port::holders(&port);
    (!others.is_empty()).then(|| {
        format!(
            "the port {port} is also open in {}: only one program can use a port at a time, \
             so end that one",
            trol_port::held_by(&others).trim_start_matches(" by ")
        )
    })
}

/// Bring the controller into server mode and apply the tool transform (InitTROL(0), `trol
/// init`): the activation sequence of docs/protocol.md, then GetStatus, then
/// SetToolTransform. A controller that answers the line with the block check's word as an
/// unknown line speaks only the manual's protocol: unless trol.cfg names `check = crc16`, it
/// gets the manual's bare `PCP TROL` and the link the manual's LRC.
pub fn activate(robot: &mut Robot, tool: &[f64; 6]) -> Result<()> {
    if check_server(robot).is_err() {
        // The block check this end uses: the activation line makes the controller use it too.
        let check = robot.link_config().check;
        let line = trol_proto::activation::activation_line(check);
        let answer = trol_proto::activation::activated_line(check);
        let io = |e: std::io::Error| Error::Setup(SetupError::NoServer(format!("port error: {e}")));
        {
            let port = robot.transactor_mut().driver_mut().port_mut();
            port.send(b"\x03\r").map_err(io)?;
            std::thread::sleep(std::time::Duration::from_millis(100));
            port.flush_input().map_err(io)?;
        }
        match type_line(robot, &line, &answer)? {
            Typed::Active => {}
            Typed::Unknown if check == BlockCheck::Crc16 && !robot.check_is_auto() => {
                return Err(Error::Setup(SetupError::NoServer(format!(
                    "the controller does not know `{line}`: it speaks only the manual's \
                     protocol (a 1998 TROL server), which checks blocks with the manual's LRC; \
                     trol.cfg asks for `check = crc16`: remove that line (or write `check = \
                     lrc`)"
                ))));
            }
            Typed::Unknown => {
                // A 1998 controller: the manual's bare line, the manual's LRC.
                let bare = trol_proto::activation::ACTIVATE;
                match type_line(robot, bare, trol_proto::activation::ACTIVATED)? {
                    Typed::Active => robot.set_check(BlockCheck::Lrc),
                    Typed::Unknown => {
                        return Err(Error::Setup(SetupError::NoServer(format!(
                            "the controller knows neither `{line}` nor the manual's `{bare}`: \
                             it answers both as unknown commands, so its TROL server (PCP) is \
                             not installed; load it as its manual says"
                        ))));
                    }
                }
            }
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
        check_activated(robot)?;
    }
    robot.set_tool_transform(tool)
}

/// How long a controller may take to start its server after it answered the activation
/// line. The manual gives no figure; a 1998 PCP server that is loaded and started by the
/// line may miss the first ENQ (issue 67: 0 of 4 activations with a 50 ms start), so the
/// check is tried again, each try one ENQ, until this has passed.
pub const ACTIVATION_WINDOW: std::time::Duration = std::time::Duration::from_secs(3);

/// The check after the activation line: GetStatus, tried again while nothing at all answers
/// its ENQ and the server may still be starting ([`ACTIVATION_WINDOW`]). A controller that
/// answers and refuses (another version, damaged blocks) is not asked again.
fn check_activated(robot: &mut Robot) -> Result<()> {
    let started = std::time::Instant::now();
    let io = |e: std::io::Error| Error::Setup(SetupError::NoServer(format!("port error: {e}")));
    loop {
        // Each try starts afresh. Before the first: the probe that found the controller in
        // terminal mode failed, so this end's link is resetting, deaf for two periods as the
        // manual has a sender do after a failed transfer (layer 2, "Rückgabewerte"), so that
        // neither end takes a byte of that transfer into the next. But the controller has
        // just answered the activation line: its link starts now, idle. Before a later try:
        // nothing answered the last, so no byte of it is on its way back. Either way the
        // input is dropped and there is nothing to wait out (it was 2 s of every `trol
        // init` of a controller in terminal mode).
        robot
            .transactor_mut()
            .driver_mut()
            .port_mut()
            .flush_input()
            .map_err(io)?;
        robot.transactor_mut().initiator_mut().abort();
        let e = match check_server(robot) {
            Ok(()) => return Ok(()),
            Err(e) => e,
        };
        let silent = robot
            .transactor_mut()
            .initiator()
            .link()
            .last_error()
            .is_some_and(|l| {
                l == trol_proto::link::LinkError::Send(
                    trol_proto::link::codes::SendError::TimeoutEnq,
                )
            });
        if !silent || started.elapsed() >= ACTIVATION_WINDOW {
            return Err(e);
        }
    }
}

/// How a controller in terminal mode took an activation line.
enum Typed {
    /// It answered the activation.
    Active,
    /// It answered `COMMAND ERROR` and its prompt: it does not know the line.
    Unknown,
}

/// Type `line` and CR at the controller's terminal and read until it answers `answer`, or
/// says it does not know the line; at most 3 s.
fn type_line(robot: &mut Robot, line: &str, answer: &str) -> Result<Typed> {
    let io = |e: std::io::Error| Error::Setup(SetupError::NoServer(format!("port error: {e}")));
    let port = robot.transactor_mut().driver_mut().port_mut();
    port.send(line.as_bytes()).map_err(io)?;
    port.send(b"\r").map_err(io)?;
    let mut seen = Vec::new();
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(3);
    let mut buf = [0u8; 256];
    loop {
        let text = String::from_utf8_lossy(&seen);
        if text.contains(answer) {
            return Ok(Typed::Active);
        }
        let error = trol_proto::activation::COMMAND_ERROR;
        if text.find(error).is_some_and(|at| text[at..].contains(">>")) {
            return Ok(Typed::Unknown);
        }
        let port = robot.transactor_mut().driver_mut().port_mut();
        let n = port.recv(&mut buf, deadline).map_err(io)?;
        if n == 0 {
            let said = text.into_owned();
            let what = format!(
                "the controller did not answer the activation line `{line}` with `{answer}` (it \
                 answered {said:?})"
            );
            return Err(Error::Setup(SetupError::NoServer(
                match shared_port(robot) {
                    Some(shared) => format!("{what}; {shared}"),
                    None => {
                        format!("{what}; check the cable, the port and the baud rate in trol.cfg")
                    }
                },
            )));
        }
        seen.extend_from_slice(&buf[..n]);
    }
}

/// Whether a program should print the connection's notice `notice` for `port` now: once per
/// program (`surface`, e.g. `InitTROL`) and port on this machine, so that a 1998 program
/// that starts many times a day is told what its controller costs it the first time, not at
/// every start; always with `TROL_VERBOSE` set (to anything but 0) or where no cache folder
/// can keep the mark ($XDG_CACHE_HOME/trol or ~/.cache/trol, a file per notice).
pub fn notice_due(surface: &str, port: &str, notice: &str) -> bool {
    if std::env::var("TROL_VERBOSE").is_ok_and(|v| !v.is_empty() && v != "0") {
        return true;
    }
    let Some(dir) = std::env::var_os("XDG_CACHE_HOME")
        .map(std::path::PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| std::path::Path::new(&h).join(".cache")))
        .map(|d| d.join("trol").join("notices"))
    else {
        return true;
    };
    // FNV-1a of what is noted: the same notice on the same port by the same program.
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in surface
        .bytes()
        .chain([0])
        .chain(port.bytes())
        .chain([0])
        .chain(notice.bytes())
    {
        h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
    }
    let mark = dir.join(format!("{h:016x}"));
    if mark.exists() {
        return false;
    }
    // A mark that cannot be written: say it (and again next time).
    let _ = std::fs::create_dir_all(&dir)
        .and_then(|_| std::fs::write(&mark, format!("{surface}\n{port}\n{notice}\n")));
    true
}

//! `trol init` and `trol cleanup` (the manual's inittrol and cluptrol, "Initialisierung"):
//! activate the controller's TROL server with the tool transform of trol.cfg, and end it.

use trol::Connect;

use crate::common::Conn;

const CHECK: &str = "check that the controller is on and connected to this port, that the \
                     port is the right one (`trol ports` lists them), and that the baud rate \
                     matches the controller's";

/// Why the port did not open, with what to check; a port another program holds, or one
/// whose error says what to do already, needs no cable hint.
fn open_failed(e: trol::Error) -> String {
    match e {
        trol::Error::Setup(trol::SetupError::Port(trol_port::OpenError::Busy { .. })) => {
            e.to_string()
        }
        // The port's own hint already says what to do (a name that is not there, a
        // refusal, a socket nobody listens on).
        trol::Error::Setup(trol::SetupError::Port(trol_port::OpenError::Io {
            ref hint, ..
        })) if !hint.is_empty() => e.to_string(),
        // The controller answered (it refused a step of the activation, or speaks another
        // version): the line is fine, and the message says what to do.
        trol::Error::Refused { .. }
        | trol::Error::Argument(_)
        | trol::Error::Setup(trol::SetupError::Incompatible { .. }) => e.to_string(),
        e => format!("{e}; {CHECK}"),
    }
}

pub fn init(conn: &Conn) -> Result<(), String> {
    let cfg = conn.config()?;
    if cfg.port == "sim" {
        say!(
            "port sim: the embedded simulator runs inside each program and starts active; \
             there is nothing to activate. Give --port (or set it in trol.cfg) to activate a \
             controller on a line."
        );
        return Ok(());
    }
    let mut robot = Connect::config(&cfg)
        .activate()
        .connect()
        .map_err(open_failed)?;
    if let Some(notice) = robot.take_notice() {
        say!("note: {notice}");
    }
    say!(
        "the TROL server on {} is active (baud {}, tool transform {:?})",
        cfg.port,
        cfg.baud,
        cfg.tool
    );
    Ok(())
}

pub fn cleanup(conn: &Conn) -> Result<(), String> {
    let cfg = conn.config()?;
    if cfg.port == "sim" {
        say!("port sim: the embedded simulator ends with each program; nothing to end.");
        return Ok(());
    }
    let mut robot = Connect::config(&cfg).connect().map_err(open_failed)?;
    robot.terminate_pcp().map_err(|e| {
        format!(
            "the controller did not take TerminatePCP: {e}. Is its TROL server active (`trol \
             init`)? Also {CHECK}"
        )
    })?;
    say!(
        "the TROL server on {} has ended; the controller is back in terminal mode",
        cfg.port
    );
    Ok(())
}

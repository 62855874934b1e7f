//! `trol link A B`: the manual's link utility ("Konfiguration"). It activates the controller
//! on A (unless told not to), then relays every byte between A and B, both ways, unchanged,
//! so that an application on B cannot tell it from a direct connection. A listening B
//! accepts the next client when one leaves.

use std::time::{Duration, Instant};

use clap::Args;
use trol::Robot;
use trol_port::Port;
use trol_proto::link::LinkConfig;

#[derive(Args, Debug)]
#[command(after_help = "\
Examples:
  # a serial controller; applications on this machine over TCP:
  trol link /dev/ttyS0 listen://7000
  # ... and from other machines (no authentication!):
  trol link /dev/ttyS0 listen://0.0.0.0:7000
  trol link /dev/ttyUSB0 /dev/ttyUSB1  # serial to serial
  trol link /dev/pts/3 pty             # to a new pty (its path is printed)

The application then opens B's other end (socket://HOST:7000, the pty's path, ...).")]
pub struct LinkArgs {
    /// The controller's port: a serial device, a pty, or socket://HOST:PORT.
    controller: String,
    /// The application's side: a serial device, `pty` (a new pseudo-terminal), or
    /// listen://HOST:PORT.
    application: String,
    /// The configuration file (default: $TROL_CONFIG, else ./trol.cfg, else the defaults):
    /// its baud rate, tool transform and block check apply unless given here.
    #[arg(long, value_name = "FILE")]
    config: Option<std::path::PathBuf>,
    /// Baud rate of serial devices (default: trol.cfg's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(300..=4_000_000))]
    baud: Option<u32>,
    /// Do not activate the controller's TROL server first (it already is, or will be).
    #[arg(long)]
    no_init: bool,
    /// With activation: the tool transform to set (x y z yaw pitch roll; default:
    /// trol.cfg's).
    #[arg(long, num_args = 6, value_name = "V", allow_negative_numbers = true)]
    tool: Option<Vec<f64>>,
}

/// Which end of the relay a port is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    Controller,
    Application,
}

/// An opened end.
pub struct Opened {
    pub port: Box<dyn Port>,
    /// What to tell the other party: the pty path, or socket:// address.
    pub name: String,
    /// The other end of a new pty, kept open so that clients may come and go.
    _keep: Option<Box<dyn Port>>,
}

/// Open one end: `pty` makes a new pseudo-terminal; `listen://HOST:PORT` waits for clients.
/// How to activate a controller served on `asked` (the --port given) that clients reach at
/// `name`: a new pty or a listening socket is reached where it says; a device is one end of
/// a line, and `trol init` belongs at the other end.
pub fn activation_hint(asked: &str, name: &str) -> String {
    if asked == "pty" || asked.starts_with("listen://") {
        format!("activate it with: trol init --port {name}")
    } else {
        format!(
            "{name} is this end of the line: applications and `trol init` use its other end \
             (the device at the far side of the cable, or the other pty of a socat pair): \
             trol init --port OTHER_END"
        )
    }
}

pub fn open_side(name: &str, baud: u32, side: Side) -> Result<Opened, String> {
    if name == "pty" {
        if side == Side::Controller {
            return Err("the controller's side cannot be a new pty; give its path".into());
        }
        #[cfg(unix)]
        {
            let (master, slave, path) = trol_port::serial::SerialLine::pty_pair()
                .map_err(|e| format!("cannot create a pty: {e}"))?;
            return Ok(Opened {
                port: Box::new(master),
                name: path,
                _keep: Some(Box::new(slave)),
            });
        }
        #[cfg(not(unix))]
        return Err("pseudo-terminals need a Unix system; use listen://HOST:PORT".into());
    }
    if let Some(addr) = name.strip_prefix("listen://") {
        let line = trol_port::tcp::TcpLine::listen(addr, Duration::from_secs(10))
            .map_err(|e| format!("cannot listen on {addr}: {e}"))?;
        let at = line
            .local_addr()
            .map(|a| format!("socket://{a}"))
            .unwrap_or_else(|| name.to_string());
        return Ok(Opened {
            port: Box::new(line),
            name: at,
            _keep: None,
        });
    }
    let settings = trol_port::PortSettings {
        baud,
        ..Default::default()
    };
    Ok(Opened {
        port: trol_port::open(name, &settings).map_err(|e| e.to_string())?,
        name: name.to_string(),
        _keep: None,
    })
}

/// Relay bytes both ways until a port fails; `seen(from_application, bytes)` sees each
/// chunk before it is passed on.
pub fn relay(
    ctl: &mut Box<dyn Port>,
    app: &mut Box<dyn Port>,
    seen: &mut dyn FnMut(bool, &[u8]),
) -> Result<(), String> {
    let mut buf = [0u8; 4096];
    let slice = Duration::from_millis(1);
    loop {
        let n = app
            .recv(&mut buf, Instant::now() + slice)
            .map_err(|e| format!("{}: {e}", app.name()))?;
        if n > 0 {
            seen(true, &buf[..n]);
            ctl.send(&buf[..n])
                .map_err(|e| format!("{}: {e}", ctl.name()))?;
        }
        let n = ctl
            .recv(&mut buf, Instant::now() + slice)
            .map_err(|e| format!("{}: {e}", ctl.name()))?;
        if n > 0 {
            seen(false, &buf[..n]);
            app.send(&buf[..n])
                .map_err(|e| format!("{}: {e}", app.name()))?;
        }
    }
}

pub fn run(a: LinkArgs) -> Result<(), String> {
    let cfg = crate::common::Conn {
        config: a.config.clone(),
        ..Default::default()
    }
    .config()?;
    let baud = a.baud.unwrap_or(cfg.baud);
    let mut ctl = open_side(&a.controller, baud, Side::Controller)?;
    if !a.no_init {
        let tool: [f64; 6] = match &a.tool {
            Some(v) => [v[0], v[1], v[2], v[3], v[4], v[5]],
            None => cfg.tool,
        };
        let link = LinkConfig {
            check: cfg.block_check(),
            ..LinkConfig::for_line(baud, Duration::ZERO)
        };
        let mut robot = Robot::over(ctl.port, link, None);
        trol::activate(&mut robot, &tool).map_err(|e| format!("activating the controller: {e}"))?;
        say!("trol link: the TROL server on {} is active", a.controller);
        ctl.port = robot.into_port();
    }
    let mut app = open_side(&a.application, baud, Side::Application)?;
    say!(
        "trol link: relaying {} <-> {} (applications use {})",
        a.controller,
        a.application,
        app.name
    );
    relay(&mut ctl.port, &mut app.port, &mut |from_app, chunk| {
        tracing::debug!(
            from = if from_app {
                "application"
            } else {
                "controller"
            },
            len = chunk.len(),
            "relayed"
        );
    })
}

//! `trol gateway`: TROL's controller side on this PC, driving a real C500 in RAPL-II
//! (docs/c500.md) or an A465 on a MARS 8 (`--controller mars:DEVICE`, docs/mars.md) over a
//! second line. A program that speaks TROL's wire protocol (a 1998 TROL
//! application, or a second PC) uses it as it would a PCP server; `trol init` and
//! `trol cleanup` work against it as against `trol sim`.

use std::path::PathBuf;
use std::time::Duration;

use clap::Args;
use trol_controller::{Controller, Mode, Pcp};
use trol_proto::link::{BlockCheck, LinkConfig};

use crate::link::{Side, open_side};

#[derive(Args, Debug)]
#[command(after_help = "\
Examples:
  # TROL on a new pty (or on a socket), driving a C500:
  trol gateway --controller /dev/ttyUSB0 --profile c500.toml
  trol gateway --controller /dev/ttyUSB0 --port listen://127.0.0.1:7000
  # a simulated C500, and TROL in front of it:
  trol sim --rapl &
  trol gateway --controller /dev/pts/4 \\
    --profile <(trol sim --rapl --print-profile)
  # an A465 on a MARS 8; one on its C500C (docs/c500c.md):
  trol gateway --controller mars:/dev/ttyUSB0 \\
    --profile crates/trol-mars/profiles/crs93.toml
  trol gateway --controller c500c:/dev/ttyUSB0 --profile c500c.toml
  # each motion runs exactly once across restarts of the gateway:
  trol gateway --controller /dev/ttyUSB0 --profile c500.toml \\
    --journal c500.journal

The first line of output names where TROL clients connect: `trol gateway: serving on NAME`.
Activate the server there with `trol init --port NAME`.")]
pub struct GatewayArgs {
    /// The C500's host port: a serial device (or socket://HOST:PORT to a networked one;
    /// `rapl:DEVICE` as in trol.cfg is the same), opened at the profile's baud rate; or
    /// mars:DEVICE for an A465 on a MARS 8; or
    /// c500c:DEVICE for an A465 on its C500C (the front console).
    #[arg(long, value_name = "DEVICE")]
    controller: String,
    /// Where to serve TROL: `pty` (a new pseudo-terminal), a serial device, or
    /// listen://HOST:PORT.
    #[arg(long, default_value = "pty")]
    port: String,
    /// Baud rate of the TROL side, when it is a serial device.
    #[arg(long, default_value_t = 9600)]
    baud: u32,
    /// The C500's RAPL-II profile (docs/c500.md); default: the safe one, which refuses
    /// cartesian commands and MA/MI until their conventions are set. With mars:DEVICE: the
    /// arm profile (docs/mars.md), which it needs. With c500c:DEVICE: the C500C profile
    /// (docs/c500c.md); default: nothing settled, every motion refused naming the key.
    #[arg(long, value_name = "FILE")]
    profile: Option<PathBuf>,
    /// The block check until an activation line names one: crc16 (TROL's) or lrc.
    #[arg(long, default_value = "crc16", value_parser = parse_check)]
    check: BlockCheck,
    /// Start in server mode, as if `trol init` had run.
    #[arg(long)]
    server: bool,
    /// Serve the live 3D view of the arm at ADDR (default 127.0.0.1:8465, this machine only),
    /// as the controller reports it: the joints it reads (W2 on a C500, COORDAP on a MARS 8)
    /// about ten times a second, between requests and during waits.
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = trol_view::DEFAULT_ADDR)]
    view: Option<String>,
    /// With --view: the page is also a pendant that drives the arm through this gateway
    /// (jog, speed, store a location, move to one, delete, Halt; docs/teach.md), from this
    /// machine only, with the token printed at start. Every request goes through the same
    /// fail-safe rules as the host's.
    #[arg(long, requires = "view")]
    control: bool,
    /// With --control: an address besides this machine's that may drive the arm.
    #[arg(long, value_name = "IP", requires = "control")]
    control_from: Vec<std::net::IpAddr>,
    /// Keep the last call in FILE, so that a gateway killed and started again with the same
    /// FILE still knows whether that call ran: GetStatus and a repeat answer for it, and no
    /// recovery sends a move again that ran (docs/reliability.md, "Exactly once"). One
    /// FILE per arm; made if missing.
    #[arg(long, value_name = "FILE")]
    journal: Option<PathBuf>,
}

fn parse_check(s: &str) -> Result<BlockCheck, String> {
    BlockCheck::from_word(s).ok_or_else(|| format!("`{s}` is no block check: crc16 or lrc"))
}

/// Open the C500's session, then serve TROL until the line fails.
pub fn run(a: GatewayArgs) -> Result<(), String> {
    // Serving must never wait for a reader of the log (docs/reliability.md).
    crate::common::log_in_background();
    if let Some(device) = a.controller.strip_prefix(trol_mars::PREFIX) {
        return run_mars(&a, device);
    }
    if let Some(device) = a.controller.strip_prefix(trol_c500c::PREFIX) {
        return run_c500c(&a, device);
    }
    let profile = match &a.profile {
        Some(p) => trol_rapl::Profile::from_file(p).map_err(|e| e.to_string())?,
        None => trol_rapl::Profile::default(),
    };
    let settings = trol_port::PortSettings {
        baud: profile.baud,
        ..Default::default()
    };
    // `rapl:DEVICE`, as trol.cfg names a C500, is the same device.
    let device = a.controller.strip_prefix("rapl:").unwrap_or(&a.controller);
    let port = trol_port::open(device, &settings).map_err(|e| e.to_string())?;
    let backend = trol_rapl::RaplBackend::connect_with(
        port,
        profile,
        Some(Box::new(|line: &str| say!("  c500: {line}"))),
        None,
    )
    .map_err(|e| e.to_string())?;
    serve_backend(&a, backend, "the C500", trol_rapl::RAPL_CODES)
}

/// `--controller c500c:DEVICE`: an A465 on its C500C, through ash.
fn run_c500c(a: &GatewayArgs, device: &str) -> Result<(), String> {
    let profile = match &a.profile {
        Some(p) => trol_c500c::Profile::from_file(p).map_err(|e| e.to_string())?,
        // Nothing settled: every motion is refused, naming the key (docs/c500c.md).
        None => trol_c500c::Profile::default(),
    };
    let settings = trol_port::PortSettings {
        baud: profile.baud,
        ..trol_port::PortSettings::default()
    };
    let port = trol_port::open(device, &settings)
        .map_err(|e| format!("cannot open the C500C's console {device}: {e}"))?;
    let backend = trol_c500c::C500cBackend::connect(
        port,
        profile,
        Some(Box::new(|line: &str| say!("  c500c: {line}"))),
    )
    .map_err(|e| e.to_string())?;
    let what = format!("the C500C ({})", backend.version());
    serve_backend(a, backend, &what, trol_c500c::C500C_CODES)
}

/// `--controller mars:DEVICE`: an A465 on a MARS 8.
fn run_mars(a: &GatewayArgs, device: &str) -> Result<(), String> {
    let profile = match &a.profile {
        Some(p) => trol_mars::Profile::from_file(p).map_err(|e| e.to_string())?,
        None => {
            return Err(format!(
                "--controller {}: an A465 on a MARS 8 needs its arm profile: --profile FILE \
                 (crates/trol-mars/profiles/crs93.toml is CTU's CRS93; docs/mars.md)",
                a.controller
            ));
        }
    };
    let settings = trol_port::PortSettings {
        baud: profile.baud,
        rts_cts: true,
        ..Default::default()
    };
    let port = trol_port::open(device, &settings).map_err(|e| e.to_string())?;
    let backend = trol_mars::MarsBackend::connect(
        port,
        profile,
        Some(Box::new(|line: &str| say!("  mars: {line}"))),
        None,
        Vec::new(),
    )
    .map_err(|e| e.to_string())?;
    let what = format!("the MARS 8 ({})", backend.version());
    serve_backend(a, backend, &what, trol_mars::MARS_CODES)
}

fn serve_backend<B: trol_controller::Backend>(
    a: &GatewayArgs,
    backend: B,
    what: &str,
    codes: &'static trol_proto::application::CodeTable,
) -> Result<(), String> {
    // The view first: an address in use ends the start before anything is served. It reads
    // what the backend reports, and lives as long as the gateway serves.
    let (pendant, inbox) = trol_controller::Pendant::channel();
    let control = a.control.then(|| trol_view::Control {
        from: a.control_from.clone(),
        ..trol_view::Control::new(pendant, codes)
    });
    let token = control.as_ref().map(|c| c.token.clone());
    let view = match &a.view {
        Some(addr) => {
            let slot = trol_controller::SharedReport::default();
            let view = trol_view::serve_controlled(addr, slot.clone(), control)
                .map_err(|e| format!("cannot serve the view at {addr}: {e}"))?;
            Some((slot, view))
        }
        None => None,
    };
    let opened = open_side(&a.port, a.baud, Side::Application)?;
    let name = opened.name.clone();
    say!("trol gateway: serving on {name}");
    if let Some((_, v)) = &view {
        say!("  the view: {}", v.url());
        if let Some(t) = &token {
            say!(
                "  the pendant (it drives the arm; keep the address to yourself): {}#token={t}",
                v.url()
            );
        }
        if let Some(w) = v.exposure() {
            tracing::warn!("{w}");
        }
    }
    say!(
        "  driving {what} on {}; {} mode",
        a.controller,
        if a.server { "server" } else { "terminal" }
    );
    if !a.server {
        say!("  {}", crate::link::activation_hint(&a.port, &name));
    }
    let cfg = LinkConfig {
        check: a.check,
        ..LinkConfig::for_line(a.baud, Duration::ZERO)
    };
    let mode = if a.server {
        Mode::Server
    } else {
        Mode::Terminal
    };
    let mut controller = Controller::new(opened.port, cfg, Pcp::new(backend), mode);
    if let Some(path) = &a.journal {
        match controller
            .set_journal(path)
            .map_err(|e| format!("cannot use the journal {}: {e}", path.display()))?
        {
            Some(restored) => say!("  journal {}: {restored}", path.display()),
            None => say!("  journal {}: nothing to go on from", path.display()),
        }
    }
    if a.control {
        controller.set_pendant(inbox);
    }
    if let Some((slot, _)) = &view {
        controller.report_into(slot.clone(), Duration::from_millis(100));
    }
    crate::sim::serve(
        controller,
        trol_proto::application::Catalog::builtin(),
        codes,
    )
}

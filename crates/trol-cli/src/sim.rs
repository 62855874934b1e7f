//! `trol sim`: the simulated controller as its own process, on a serial device, a new pty,
//! or TCP. It starts in terminal mode, as a C500 does, until `trol init` activates it.

use std::path::PathBuf;
use std::time::Duration;

use clap::Args;
use trol_a465::arm::{ArmSettings, parse_objects};
use trol_comm::ServerEvent;
use trol_controller::{Controller, Mode, Pcp};
use trol_proto::link::{BlockCheck, LinkConfig};
use trol_proto::transaction::ManualLayer3;
use trol_sim::{SimBackend, SimSettings};

use crate::common::positive;
use crate::link::{Side, open_side};

#[derive(Args, Debug)]
#[command(after_help = "\
Examples:
  trol sim                                 # on a new pty; prints its path
  trol sim --port listen://127.0.0.1:7000  # clients: socket://127.0.0.1:7000
  trol sim --port /dev/ttyUSB1 --baud 38400 --locations examples/locations.txt
  trol sim --time-scale 20 --table-z -10 --homed

The first line of output names where clients connect: `trol sim: serving on NAME`.")]
pub struct SimArgs {
    /// Where to serve: `pty` (a new pseudo-terminal), a serial device, or
    /// listen://HOST:PORT (port 0 picks a free one).
    #[arg(long, default_value = "pty")]
    port: String,
    /// The configuration file whose simulator settings apply unless given here (baud,
    /// check, time_scale, locations, objects, table_z, homed, object; default:
    /// $TROL_CONFIG, else ./trol.cfg, else none). Its port is the application's, not this.
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// Baud rate of a serial device [default: trol.cfg's, else 9600].
    #[arg(long)]
    baud: Option<u32>,
    /// The location table to load (docs/a465.md, "Locations"); with --c500c, the
    /// application's variables (docs/c500c.md, "Locations").
    #[arg(long, value_name = "FILE")]
    locations: Option<PathBuf>,
    /// Run the simulation this many times faster than real time [default: trol.cfg's, else
    /// 1].
    #[arg(long, value_parser = positive)]
    time_scale: Option<f64>,
    /// The table plane (world z, mm): the tool tip may not go below it [default: trol.cfg's,
    /// else 0].
    #[arg(long, allow_negative_numbers = true)]
    table_z: Option<f64>,
    /// Start homed (a real arm must be homed after power-up).
    #[arg(long)]
    homed: bool,
    /// Width of an object held between the fingers at start, mm: closing stops there.
    #[arg(long, value_name = "MM")]
    object: Option<f64>,
    /// Objects in the world, one per line `NAME x y z width` (mm): closing the gripper on
    /// one at the tool centre point picks it up, opening drops it onto the table; the log
    /// says where each one is.
    #[arg(long, value_name = "FILE")]
    objects: Option<PathBuf>,
    /// Start in server mode, as if `trol init` had run.
    #[arg(long)]
    server: bool,
    /// The block check in server mode until an activation line names one: crc16 (TROL's) or
    /// lrc (the manual's) [default: trol.cfg's, else crc16].
    #[arg(long, value_parser = parse_check)]
    check: Option<BlockCheck>,
    /// Be a controller with the 1998 PCP server, which speaks only the manual's protocol: only
    /// the bare `PCP TROL` activates it, the manual's LRC, GetStatus in 4 bytes, the commands
    /// TROL added unknown, no memory of the last request (a repeat runs again). PCI says what
    /// its replies carry in the PCI, which the manual leaves open: `zero` (default) or `echo`
    /// (the request's). --check does not apply. For trying a host against an old controller.
    #[arg(long, value_name = "PCI", num_args = 0..=1, default_missing_value = "zero", value_parser = parse_manual_pci, conflicts_with_all = ["rapl", "mars", "c500c"])]
    manual: Option<ManualLayer3>,
    /// Take MS milliseconds to start the server after answering the activation line, losing
    /// what arrives meanwhile, as a 1998 controller whose PCP takes a moment to come up may
    /// (the host tries its check again: docs/protocol.md, "The controller's modes").
    #[arg(long, value_name = "MS", default_value_t = 0, value_parser = clap::value_parser!(u64).range(0..=60_000))]
    start_pause: u64,
    /// Commands an application added, described in FILE (docs/extending.md): the log shows
    /// them by name. `trol sim` has no handlers for them and answers TROL_ERR_UNKNOWN; a
    /// controller program of the application's own serves them.
    #[arg(long, value_name = "FILE")]
    commands: Option<PathBuf>,
    /// Be a C500 in RAPL-II mode instead (what `trol gateway` and `rapl:DEVICE` drive): ACI
    /// mode at start, terminal mode after the 0x48 transfer, RAPL-II commands (docs/c500.md).
    /// The line runs at the profile's baud rate; --baud, --server and --check do not apply.
    #[arg(long)]
    rapl: bool,
    /// Be a PiKRON MARS 8 with an A465 on its axes instead (what `mars:DEVICE` and
    /// `trol gateway --controller mars:DEVICE` drive, and CTU's ctu-crs client): the unit's
    /// line at the profile's baud rate (docs/mars.md); --baud, --server and --check do not
    /// apply.
    #[arg(long, conflicts_with = "rapl")]
    mars: bool,
    /// Be a CRS C500C with an A465 instead (what `c500c:DEVICE` and `trol gateway
    /// --controller c500c:DEVICE` drive): its front console at 57600 Bd, the CROS system
    /// shell and ash (docs/c500c.md); --baud, --server and --check do not apply.
    #[arg(long, conflicts_with_all = ["rapl", "mars"])]
    c500c: bool,
    /// With --rapl: how the simulated C500 behaves on each open point (a RAPL-II profile,
    /// docs/c500.md); default: the simulator's (mm, angles yaw pitch roll, MA/MI in degrees).
    /// With --mars: the arm profile (docs/mars.md); default: CTU's CRS93
    /// (crates/trol-mars/profiles/crs93.toml).
    #[arg(long, value_name = "FILE")]
    profile: Option<PathBuf>,
    /// Play one of the controllers the public sources allow, by name (`--help` lists them)
    #[arg(long, value_name = "NAME", long_help = variant_help())]
    variant: Option<String>,
    /// With --rapl, --mars or --c500c: print the profile that describes this simulated
    /// controller (give it to `trol gateway --profile` or trol.cfg's rapl-profile /
    /// mars-profile / c500c-profile) and exit.
    #[arg(long)]
    print_profile: bool,
    /// Serve the live 3D view of the arm at ADDR (default 127.0.0.1:8465, this machine only;
    /// name an address to serve others): open it in a browser. Not with --rapl.
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = trol_view::DEFAULT_ADDR, conflicts_with_all = ["rapl", "mars", "c500c"])]
    view: Option<String>,
    /// With --view: the page is also a pendant that drives the arm (jog, speed, store a
    /// location, move to one, delete, Halt; docs/teach.md). It takes requests from this
    /// machine only, with the token printed at start (open the printed address).
    #[arg(long, requires = "view")]
    control: bool,
    /// With --control: an address besides this machine's that may drive the arm (repeat for
    /// more). The view's address must be one that machine reaches.
    #[arg(long, value_name = "IP", requires = "control")]
    control_from: Vec<std::net::IpAddr>,
    /// With --mars: faults on standard input, one per line, to try a program's handling:
    /// `power off`, `power on`, `stop on` (the motion stop), `stop off`, `silent on` (the unit
    /// stops answering), `silent off`, `say TEXT` (a line the unit prints unasked),
    /// `object POS` (closing the gripper stops at axis position POS), `object none`. With
    /// --c500c: `power off` (mid-motion: the brakes, and ash's line where the variant prints
    /// it), `power on`, `pendant on|off` (who holds the point of control), `say TEXT`.
    #[arg(long)]
    console: bool,
    /// With --rapl: a teach pendant on standard input. Each line `J1 J2 J3 J4 J5 J6`
    /// (degrees) moves the arm there as an operator would by hand, whatever the host port
    /// does; the log says `pendant: at ...` once it stands (for `trol rapl probe --poses`).
    #[arg(long, requires = "rapl")]
    pendant: bool,
    /// The settings in force: the flags, else trol.cfg's, else the defaults ([`resolve`]).
    #[arg(skip)]
    r: Resolved,
}

/// What `trol sim` runs with, each from its flag, else from trol.cfg, else its default.
#[derive(Debug, Default)]
struct Resolved {
    baud: u32,
    time_scale: f64,
    table_z: f64,
    check: BlockCheck,
    homed: bool,
    /// The configuration file read, if there was one.
    from: Option<String>,
}

/// Fill in what the flags left open from the configuration (`--config`, $TROL_CONFIG or
/// ./trol.cfg; none: the defaults), as every subcommand reads it. Relative files in trol.cfg
/// are its folder's.
fn resolve(mut a: SimArgs) -> Result<SimArgs, String> {
    let (cfg, source) = crate::common::config_file(a.config.clone())?;
    let from =
        (!matches!(source, trol::config::ConfigSource::Defaults)).then(|| source.to_string());
    a.r = Resolved {
        from,
        baud: a.baud.unwrap_or(cfg.baud),
        time_scale: a.time_scale.unwrap_or(cfg.time_scale),
        table_z: a.table_z.unwrap_or(cfg.table_z),
        check: a.check.unwrap_or(cfg.block_check()),
        homed: a.homed || cfg.homed,
    };
    a.locations = a.locations.take().or(cfg.locations);
    a.objects = a.objects.take().or(cfg.objects);
    a.object = a.object.or(cfg.object);
    Ok(a)
}

/// `--variant`'s long help, with the names of every variant from the simulated controllers'
/// own tables, so that it cannot miss one.
fn variant_help() -> String {
    let names = |all: &[(&str, &str)]| all.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ");
    format!(
        "Play one of the controllers the public sources allow, by name (the backend's tests \
         run across all of them). With --rapl (docs/c500.md, \"What TROL assumes\"): {}. With \
         --mars (docs/mars.md): {}. With --c500c (docs/c500c.md): {}.",
        names(trol_rapl::c500::VARIANTS),
        names(trol_mars::mars8::VARIANTS),
        names(trol_c500c::c500c::VARIANTS)
    )
}

fn check_variant(a: &SimArgs) -> Result<(), String> {
    let Some(v) = &a.variant else {
        return Ok(());
    };
    let names: Vec<&str> = if a.rapl {
        trol_rapl::c500::VARIANTS.iter().map(|(n, _)| *n).collect()
    } else if a.mars {
        trol_mars::mars8::VARIANTS.iter().map(|(n, _)| *n).collect()
    } else if a.c500c {
        trol_c500c::c500c::VARIANTS
            .iter()
            .map(|(n, _)| *n)
            .collect()
    } else {
        return Err("--variant needs --rapl, --mars or --c500c".into());
    };
    if a.profile.is_some() && a.rapl {
        return Err("--variant and --profile: give one".into());
    }
    if names.contains(&v.as_str()) {
        Ok(())
    } else {
        Err(format!("no variant `{v}`: one of {}", names.join(", ")))
    }
}

/// Serve until the process is stopped (Ctrl-C) or the line fails.
pub fn run(a: SimArgs) -> Result<(), String> {
    // Serving must never wait for a reader of the log (docs/reliability.md).
    crate::common::log_in_background();
    check_variant(&a)?;
    let a = resolve(a)?;
    if a.profile.is_some() && a.c500c {
        return Err(
            "--profile does not apply to --c500c: its behaviour is the variant's (--variant);              --print-profile prints the profile that matches it"
                .into(),
        );
    }
    if (a.profile.is_some() || a.print_profile) && !(a.rapl || a.mars || a.c500c) {
        return Err("--profile and --print-profile need --rapl, --mars or --c500c".into());
    }
    if a.pendant && !a.rapl {
        return Err("--pendant needs --rapl".into());
    }
    if a.console && !(a.mars || a.c500c) {
        return Err("--console needs --mars or --c500c".into());
    }
    if a.mars {
        return run_mars(&a);
    }
    if a.c500c {
        return run_c500c(&a);
    }
    // A locations file that does not exist yet (its folder does) starts an empty table,
    // which TROLSaveLocations writes there (docs/teach.md).
    let new_file = a.locations.as_ref().is_some_and(|p| !p.exists());
    let locations = match &a.locations {
        Some(p) => trol_a465::backend::table::load(p)?,
        None => Vec::new(),
    };
    let n_locations = locations.len();
    let objects = match &a.objects {
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .map_err(|e| format!("cannot read {}: {e}", p.display()))?;
            parse_objects(&text).map_err(|e| format!("{}: {e}", p.display()))?
        }
        None => Vec::new(),
    };
    let settings = SimSettings {
        arm: ArmSettings {
            table_z: a.r.table_z,
            object_width: a.object,
            objects,
            homed: a.r.homed,
            ..ArmSettings::default()
        },
        time_scale: a.r.time_scale,
        locations,
        locations_file: a.locations.clone(),
        tool: [0.0; 6],
    };
    if a.rapl {
        return run_rapl(&a, settings);
    }
    // The view first: an address in use ends the start before anything is served.
    let backend = SimBackend::new(settings);
    let (pendant, inbox) = trol_controller::Pendant::channel();
    let control = a.control.then(|| trol_view::Control {
        from: a.control_from.clone(),
        ..trol_view::Control::new(pendant, trol_sim::SIM_CODES)
    });
    let token = control.as_ref().map(|c| c.token.clone());
    // The view reads what the simulator reports, as for every backend.
    let view = match &a.view {
        Some(addr) => {
            let slot = trol_controller::SharedReport::default();
            let view = trol_view::serve_controlled(addr, slot.clone(), control)
                .map_err(|e| format!("cannot serve the view at {addr}: {e}"))?;
            Some((slot, view))
        }
        None => None,
    };
    // A new pty or a listening socket, like the application's side of a relay.
    let opened = open_side(&a.port, a.r.baud, Side::Application)?;
    let name = opened.name.clone();
    say!("trol sim: serving on {name}");
    say!(
        "  {} mode, time scale {}, table at z = {} mm, {} location(s), {}",
        if a.server { "server" } else { "terminal" },
        a.r.time_scale,
        a.r.table_z,
        n_locations,
        if a.r.homed { "homed" } else { "not homed" }
    );
    if let Some(file) = &a.r.from {
        say!("  settings not given as flags: from {file}");
    }
    match &a.locations {
        Some(p) if new_file => say!(
            "  locations: {} does not exist yet; TROLSaveLocations (interp: savelocations) \
             creates it",
            p.display()
        ),
        Some(p) => say!(
            "  locations: {} (TROLSaveLocations writes them back)",
            p.display()
        ),
        None => {}
    }
    if !a.server {
        say!("  {}", crate::link::activation_hint(&a.port, &name));
    }
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
    let cfg = LinkConfig {
        // A 1998 controller knows only the manual's LRC.
        check: if a.manual.is_some() {
            BlockCheck::Lrc
        } else {
            a.r.check
        },
        ..LinkConfig::for_line(a.r.baud, Duration::ZERO)
    };
    let pcp = Pcp::new(backend);
    let described = trol::described::catalog(a.commands.as_deref())?;
    let mode = if a.server {
        Mode::Server
    } else {
        Mode::Terminal
    };
    let mut controller = Controller::new(opened.port, cfg, pcp, mode);
    if a.control {
        controller.set_pendant(inbox);
    }
    if let Some((slot, _)) = &view {
        controller.report_into(slot.clone(), trol_view::REPORT_INTERVAL);
    }
    if let Some(pci) = a.manual {
        say!(
            "  speaking only the manual's protocol (a 1998 PCP server): LRC, no memory of the \
             last request, replies with PCI {}",
            match pci {
                ManualLayer3::ZeroPci => "0",
                ManualLayer3::EchoPci => "as the request's",
            }
        );
        controller.speak_manual_only(pci);
    }
    controller.set_start_pause(std::time::Duration::from_millis(a.start_pause));
    serve(controller, described, trol_sim::SIM_CODES)
}

/// Serve TROL with `controller` until the line fails, logging each transaction (names of
/// described commands from `described`, BIOS codes from `codes`).
pub fn serve<P: trol_port::Port, B: trol_controller::Backend>(
    mut controller: Controller<P, B>,
    described: trol_proto::application::Catalog,
    codes: &'static trol_proto::application::CodeTable,
) -> Result<(), String> {
    // The server's own catalog knows what it serves; the described commands name the rest.
    let mut last_world = None;
    controller.set_log(Box::new(move |e| {
        let catalog = match e.request.first() {
            Some(c) if e.catalog.get(*c).is_none() => &described,
            _ => e.catalog,
        };
        let (req, reply) = (
            catalog.request_text(e.request),
            catalog.reply_text(e.request, e.reply, codes),
        );
        match e.event {
            ServerEvent::Executed if e.from_pendant => say!("pendant: {req} -> {reply}"),
            ServerEvent::Executed => say!("{req} -> {reply}"),
            ServerEvent::Repeated => {
                say!("{req} -> {reply} (a repeat: answered from memory, not run again)")
            }
            ServerEvent::RepeatReplyFailed(err) => say!(
                "{req} -> {reply} (a repeat, answered from memory, not run again; the reply \
                 was lost again: {err})"
            ),
            ServerEvent::ReplyFailed(err) => {
                say!("{req} -> {reply} (the reply was lost: {err})")
            }
            ServerEvent::ReplyTooLong { len } => {
                say!("{req} -> a reply of {len} bytes, too long to send")
            }
            ServerEvent::ReceiveFailed(err) if e.executed => {
                say!("{req} -> {reply} (ran; then a request could not be received: {err})")
            }
            ServerEvent::ReceiveFailed(err) => {
                say!("a request could not be received: {err}")
            }
            ServerEvent::SuspectDuplicate => say!(
                "{req} -> {reply} (the last request's number again without the REPEAT bit: \
                 with the LRC, that request repeated with its bit damaged; not run again)"
            ),
            ServerEvent::UnknownRepeat => say!(
                "{req} -> {reply} (a repeat of a request sent before this controller started: \
                 whether it ran before cannot be told, so it was not run)"
            ),
            ServerEvent::Idle | ServerEvent::Pending => {}
        }
        if let Some(why) = &e.note {
            say!("  {why}");
        }
        // Where the world's objects are, whenever that changed.
        if e.world.is_some() && e.world != last_world {
            if let Some(w) = &e.world {
                say!("  world: {w}");
            }
            last_world = e.world.clone();
        }
    }));
    let mut last_mode = controller.mode();
    let slice = controller.slice();
    loop {
        controller
            .step(slice)
            .map_err(|e| format!("the line failed: {e}"))?;
        if let Some(trip) = controller.take_watchdog_trip() {
            say!(
                "watchdog: no call for {:.1} s: the arm was halted ({})",
                trip.after.as_secs_f64(),
                match trip.halt {
                    Ok(v) => trol_proto::application::Code(v).describe(codes),
                    Err(e) => format!("the halt failed: {e}"),
                }
            );
        }
        if controller.mode() != last_mode {
            last_mode = controller.mode();
            match last_mode {
                Mode::Server => say!(
                    "activated: serving TROL ({} block check{})",
                    controller.check().word(),
                    if controller.pcp_mut().speaks_manual() {
                        ", the manual's record sizes"
                    } else {
                        ""
                    }
                ),
                Mode::Terminal => say!("TerminatePCP: back in terminal mode"),
            }
        }
    }
}

/// `trol sim --mars`: the simulated MARS 8 with an A465.
fn run_mars(a: &SimArgs) -> Result<(), String> {
    let profile = match &a.profile {
        Some(p) => trol_mars::Profile::from_file(p).map_err(|e| e.to_string())?,
        None => trol_mars::Profile::crs93(),
    };
    if a.print_profile {
        say!("{}", profile.to_toml().trim_end());
        return Ok(());
    }
    let variant = a.variant.as_deref().unwrap_or("default");
    let sw = trol_mars::mars8::variant(variant).ok_or_else(|| format!("no variant {variant}"))?;
    let mut unit = trol_mars::Mars8::new(profile.clone(), sw, a.r.homed, a.r.time_scale);
    if let Some(mm) = a.object {
        unit.set_object(profile.gripper_position(mm));
    }
    let opened = open_side(&a.port, profile.baud, Side::Application)?;
    let name = opened.name.clone();
    say!("trol sim: serving on {name}");
    say!(
        "  a MARS 8 with {} on its axes ({}), {} baud, time scale {}, {}",
        profile.name,
        if profile.source.is_empty() {
            "profile"
        } else {
            profile.source.as_str()
        },
        profile.baud,
        a.r.time_scale,
        if a.r.homed { "homed" } else { "not homed" }
    );
    let what = trol_mars::mars8::VARIANTS
        .iter()
        .find(|(n, _)| *n == variant)
        .map(|(_, w)| *w)
        .unwrap_or_default();
    say!("  variant {variant}: {what}");
    say!("  drive it with: port mars:{name} in trol.cfg (mars-profile: the arm's profile)");
    let unit = std::sync::Arc::new(std::sync::Mutex::new(unit));
    if a.console {
        say!("  console: power off|on, stop on|off, silent on|off, say TEXT, object POS|none");
        let unit = unit.clone();
        std::thread::spawn(move || {
            use std::io::BufRead;
            for line in std::io::stdin().lock().lines().map_while(Result::ok) {
                let mut u = unit.lock().unwrap_or_else(|e| e.into_inner());
                match console(&mut u, line.trim()) {
                    Ok(done) => say!("console: {done}"),
                    Err(e) => say!("console: {e}"),
                }
            }
        });
    }
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    trol_mars::mars8::serve(opened.port, unit, stop).map_err(|e| format!("the line failed: {e}"))
}

/// `trol sim --c500c`: the simulated C500C with an A465.
fn run_c500c(a: &SimArgs) -> Result<(), String> {
    use trol_c500c::c500c;
    let variant = a.variant.as_deref().unwrap_or("default");
    let sw = c500c::variant(variant).ok_or_else(|| format!("no variant {variant}"))?;
    let profile = c500c::matching_profile(&sw);
    if a.print_profile {
        say!("{}", profile.to_toml().trim_end());
        return Ok(());
    }
    let mut unit = trol_c500c::C500c::new(sw, a.r.homed, a.r.time_scale);
    // The application's variables, as a lab's `.v3` file holds them.
    let n_vars = match &a.locations {
        Some(p) => {
            let entries = trol_a465::backend::table::load(p)?;
            unit.load_variables(&entries)
                .map_err(|e| format!("{}: {e}", p.display()))?
        }
        None => 0,
    };
    let opened = open_side(&a.port, profile.baud, Side::Application)?;
    let name = opened.name.clone();
    say!("trol sim: serving on {name}");
    say!(
        "  a C500C with an A465, {} baud, time scale {}, {}",
        profile.baud,
        a.r.time_scale,
        if a.r.homed { "homed" } else { "not homed" }
    );
    let what = c500c::VARIANTS
        .iter()
        .find(|(n, _)| *n == variant)
        .map(|(_, w)| *w)
        .unwrap_or_default();
    say!("  variant {variant}: {what}");
    if let Some(p) = &a.locations {
        say!(
            "  the application's variables: {n_vars} location(s) from {}",
            p.display()
        );
    }
    let print = if variant == "default" {
        "trol sim --c500c --print-profile".to_string()
    } else {
        format!("trol sim --c500c --variant {variant} --print-profile")
    };
    say!(
        "  drive it with: port c500c:{name} in trol.cfg (c500c-profile: `{print}` prints \
         the one that matches)"
    );
    let unit = std::sync::Arc::new(std::sync::Mutex::new(unit));
    if a.console {
        say!("  console: power off|on, pendant on|off, say TEXT");
        let unit = unit.clone();
        std::thread::spawn(move || {
            use std::io::BufRead;
            for line in std::io::stdin().lock().lines().map_while(Result::ok) {
                let mut u = unit.lock().unwrap_or_else(|e| e.into_inner());
                match c500c_console(&mut u, line.trim()) {
                    Ok(done) => say!("console: {done}"),
                    Err(e) => say!("console: {e}"),
                }
            }
        });
    }
    // Serve, and log every line the console took (what a person at the terminal would see
    // typed).
    let mut port = opened.port;
    let mut buf = [0u8; 512];
    let mut logged = 0;
    loop {
        let n = port
            .recv(
                &mut buf,
                std::time::Instant::now() + Duration::from_millis(5),
            )
            .map_err(|e| format!("the line failed: {e}"))?;
        let mut unit = unit.lock().unwrap_or_else(|e| e.into_inner());
        let out = unit.feed(&buf[..n]);
        if !out.is_empty() {
            port.send(&out)
                .map_err(|e| format!("the line failed: {e}"))?;
        }
        for line in &unit.received()[logged..] {
            say!("  typed: {line}");
        }
        logged = unit.received().len();
    }
}

/// One line of `trol sim --c500c --console`.
fn c500c_console(u: &mut trol_c500c::C500c, line: &str) -> Result<String, String> {
    let (word, rest) = line.split_once(' ').unwrap_or((line, ""));
    match (word, rest.trim()) {
        ("power", "off") => {
            u.set_power_off();
            Ok("arm power off".into())
        }
        ("power", "on") => {
            u.set_power_on();
            Ok("arm power on".into())
        }
        ("pendant", v @ ("on" | "off")) => {
            u.set_pendant(v == "on");
            Ok(format!(
                "the pendant {} the point of control",
                if v == "on" { "holds" } else { "gave back" }
            ))
        }
        ("say", text) if !text.is_empty() => {
            u.say(text);
            Ok(format!("said `{text}`"))
        }
        _ => Err(format!(
            "`{line}`: one of power off, power on, pendant on, pendant off, say TEXT"
        )),
    }
}

/// One line of `trol sim --mars --console`.
fn console(u: &mut trol_mars::Mars8, line: &str) -> Result<String, String> {
    let (word, rest) = line.split_once(' ').unwrap_or((line, ""));
    let on_off = |v: &str| match v.trim() {
        "on" => Ok(true),
        "off" => Ok(false),
        other => Err(format!("`{line}`: expected on or off, found `{other}`")),
    };
    match word {
        "power" => {
            let on = on_off(rest)?;
            u.set_power_off(!on);
            Ok(format!("arm power {}", if on { "on" } else { "off" }))
        }
        "stop" => {
            let on = on_off(rest)?;
            u.set_motion_stop(on);
            Ok(format!("motion stop {}", if on { "on" } else { "off" }))
        }
        "silent" => {
            let on = on_off(rest)?;
            u.set_silent(on);
            Ok(format!("silent {}", if on { "on" } else { "off" }))
        }
        "say" if !rest.is_empty() => {
            u.say(rest);
            Ok(format!("said `{rest}`"))
        }
        "object" if rest.trim() == "none" => {
            u.set_object(None);
            Ok("no object".into())
        }
        "object" => {
            let pos: f64 = rest
                .trim()
                .parse()
                .map_err(|_| format!("`{line}`: expected object POS (a number) or none"))?;
            u.set_object(Some(pos));
            Ok(format!("an object at gripper position {pos}"))
        }
        _ => Err(format!(
            "`{line}`: expected power on|off, stop on|off, silent on|off, say TEXT, object POS|none"
        )),
    }
}

/// `trol sim --rapl`: the simulated C500 in RAPL-II mode.
fn run_rapl(a: &SimArgs, settings: SimSettings) -> Result<(), String> {
    let (profile, homed) = match (&a.profile, &a.variant) {
        (Some(p), _) => (
            trol_rapl::Profile::from_file(p).map_err(|e| e.to_string())?,
            a.r.homed,
        ),
        (None, Some(v)) => {
            let (p, homed) =
                trol_rapl::c500::variant(v).ok_or_else(|| format!("no variant {v}"))?;
            (p, a.r.homed && homed)
        }
        (None, None) => (trol_rapl::Profile::simulator(), a.r.homed),
    };
    let mut settings = settings;
    settings.arm.homed = homed;
    let mut arm = trol_a465::arm::Arm::new(settings.arm);
    arm.set_tool(settings.tool);
    let mut c500 = trol_rapl::C500::new(profile, arm, settings.locations);
    if a.print_profile {
        say!("{}", c500.describe().to_toml());
        return Ok(());
    }
    let mut opened = open_side(&a.port, c500.describe().baud, Side::Application)?;
    let name = opened.name.clone();
    say!("trol sim: serving on {name}");
    say!(
        "  a C500 in RAPL-II mode ({} at start), {} baud, time scale {}, {}",
        if c500.in_terminal_mode() {
            "terminal mode"
        } else {
            "ACI mode"
        },
        c500.describe().baud,
        a.r.time_scale,
        if homed { "homed" } else { "not homed" }
    );
    if let Some(v) = &a.variant {
        let what = trol_rapl::c500::VARIANTS
            .iter()
            .find(|(n, _)| n == v)
            .map(|(_, w)| *w)
            .unwrap_or_default();
        say!("  variant {v}: {what}");
    }
    say!("  drive it with: trol gateway --controller {name} --port pty");
    let stop = std::sync::atomic::AtomicBool::new(false);
    let pendant = a.pendant.then(|| {
        say!("  pendant: type J1..J6 in degrees, one pose per line");
        let (tx, rx) = std::sync::mpsc::channel::<String>();
        std::thread::spawn(move || {
            use std::io::BufRead;
            for line in std::io::stdin().lock().lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        rx
    });
    let mut going: Option<[f64; 6]> = None;
    trol_rapl::c500::serve_with(
        opened.port.as_mut(),
        &mut c500,
        a.r.time_scale,
        &stop,
        &mut |line| say!("{line}"),
        &mut |c, now| {
            if let Some(rx) = &pendant {
                if let Ok(line) = rx.try_recv() {
                    match parse_pose(&line) {
                        Ok(q) => match c.pendant(q.map(f64::to_radians), now) {
                            0 => going = Some(q),
                            code => say!("pendant: refused ({code}): {}", line.trim()),
                        },
                        Err(e) => say!("pendant: {e}"),
                    }
                }
            }
            if let Some(q) = going {
                if !c.arm_moving(now) {
                    going = None;
                    say!("pendant: at {q:?}");
                }
            }
        },
    )
    .map_err(|e| format!("the line failed: {e}"))
}

/// Six joint values in degrees, separated by blanks or commas.
fn parse_pose(line: &str) -> Result<[f64; 6], String> {
    let v: Vec<f64> = line
        .split([' ', ',', '\t'])
        .filter(|w| !w.is_empty())
        .map(|w| w.parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect::<Option<Vec<f64>>>()
        .ok_or_else(|| format!("`{}` is not six numbers (degrees)", line.trim()))?;
    <[f64; 6]>::try_from(v).map_err(|_| format!("`{}` is not six numbers (degrees)", line.trim()))
}

fn parse_manual_pci(s: &str) -> Result<ManualLayer3, String> {
    match s {
        "zero" => Ok(ManualLayer3::ZeroPci),
        "echo" => Ok(ManualLayer3::EchoPci),
        _ => Err(format!("`{s}`: the replies' PCI is `zero` or `echo`")),
    }
}

fn parse_check(s: &str) -> Result<BlockCheck, String> {
    BlockCheck::from_word(s).ok_or_else(|| format!("`{s}` is no block check: crc16 or lrc"))
}

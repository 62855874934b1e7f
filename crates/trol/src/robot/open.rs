//! Opening a connection: by port name or trol.cfg, in-process controllers (the simulated
//! A465, `rapl:`, `mars:`), over a port already open, and opening again after a cut.

use super::*;

/// The error for a port this build cannot serve: the cargo feature it needs.
#[allow(dead_code)]
pub(super) fn not_built(port: &str, feature: &str, what: &str) -> Error {
    SetupError::Config(format!(
        "port {port}: {what} needs TROL built with the cargo feature `{feature}` (this build \
         has no {what}: add `features = [\"{feature}\"]` to the trol dependency)"
    ))
    .into()
}

/// The link settings of an in-process line: `cfg`'s block check, every timeout at least
/// [`IN_PROCESS_SLACK`].
#[cfg(any(feature = "sim", feature = "rapl", feature = "mars", feature = "c500c"))]
pub(super) fn in_process(cfg: LinkConfig) -> LinkConfig {
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

impl Robot {
    /// A real controller's backend embedded in this process: served over an in-memory line,
    /// with its reply time and its codes.
    #[cfg(any(feature = "rapl", feature = "mars", feature = "c500c"))]
    fn embed<B: trol_controller::Backend + 'static>(
        backend: B,
        codes: &'static CodeTable,
        link: LinkConfig,
    ) -> Robot {
        let reply_time = trol_controller::Backend::reply_time(&backend);
        let link = in_process(link);
        let (line, handle) =
            trol_controller::embedded_with(trol_controller::Pcp::new(backend), link);
        let mut robot = Robot::over(Box::new(line), link, Some(handle));
        robot.set_reply_time(reply_time);
        robot.codes = codes;
        robot
    }

    /// Connect over a port name as layer 1 accepts it (`/dev/ttyUSB0`, `COM1`,
    /// `socket://host:port`, `listen://host:port`), or `sim` for the embedded controller
    /// with default settings, and check the controller: the short form of
    /// `Connect::port(port).baud(baud).connect()` ([`Connect`]).
    pub fn connect(port: &str, baud: u32) -> Result<Robot> {
        Connect::port(port).baud(baud).connect()
    }

    /// The same as [`Robot::connect`].
    #[deprecated(since = "0.2.0", note = "use Robot::connect or trol::Connect")]
    pub fn open(port: &str, baud: u32) -> Result<Robot> {
        Robot::connect(port, baud)
    }

    /// Open the port and check nothing.
    #[deprecated(
        since = "0.2.0",
        note = "use trol::Connect::port(port).baud(baud).without_check().connect() (only for \
                a test double), or .activate() for a controller in terminal mode"
    )]
    pub fn open_unchecked(port: &str, baud: u32) -> Result<Robot> {
        Connect::port(port).baud(baud).without_check().connect()
    }

    /// Connect as trol.cfg says, without the check.
    #[deprecated(
        since = "0.2.0",
        note = "use trol::Connect::config(cfg).connect(), which also checks the controller"
    )]
    pub fn from_config(cfg: &Config) -> Result<Robot> {
        Connect::config(cfg).without_check().connect()
    }

    /// Start an embedded controller (simulated A465) and connect to it.
    #[cfg(feature = "sim")]
    #[deprecated(since = "0.2.0", note = "use trol::Connect::sim(settings).connect()")]
    pub fn embedded(settings: SimSettings) -> Robot {
        Robot::embedded_on(settings, LinkConfig::default())
    }

    /// Open a plain port (not `sim`, `rapl:` or `mars:`) with the block check trol.cfg
    /// names, if any: without one, CRC-16, and the manual's LRC if the controller refuses
    /// every CRC-16 block at first contact and takes LRC ones (a controller that speaks only
    /// the manual's protocol).
    pub(super) fn open_port(port: &str, baud: u32, check: Option<BlockCheck>) -> Result<Robot> {
        let cfg = LinkConfig {
            check: check.unwrap_or_default(),
            ..LinkConfig::for_line(baud, Duration::ZERO)
        };
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

    #[cfg(feature = "rapl")]
    /// Embed the controller with the RAPL-II backend: open DEVICE (a serial device, or
    /// `socket://HOST:PORT`) at the profile's baud rate, open the RAPL-II session, and serve
    /// TROL to this process over an in-memory line (docs/c500.md).
    pub(super) fn open_rapl(
        device: &str,
        profile: trol_rapl::Profile,
        link: LinkConfig,
    ) -> Result<Robot> {
        let settings = PortSettings {
            baud: profile.baud,
            ..PortSettings::default()
        };
        let port = trol_port::open(device, &settings).map_err(SetupError::Port)?;
        // The controller's texts (refusals, what it says unasked, resynchronisations) go to the
        // log as the gateway prints them: `-v` in the utilities, RUST_LOG=trol=info elsewhere;
        // and to the application ([`Robot::take_controller_said`]).
        let said = super::ControllerSaid::default();
        let keep = said.clone();
        let backend = trol_rapl::RaplBackend::connect_with(
            port,
            profile,
            Some(Box::new(move |line: &str| {
                tracing::info!(target: "trol::rapl", "c500: {line}");
                keep.keep(&format!("c500: {line}"));
            })),
            None,
        )
        .map_err(|e| SetupError::NoServer(e.to_string()))?;
        let mut robot = Robot::embed(backend, trol_rapl::RAPL_CODES, link);
        robot.said = Some(said);
        Ok(robot)
    }

    #[cfg(feature = "c500c")]
    /// Embed the controller with the C500C backend: open DEVICE (the front console, or
    /// `socket://HOST:PORT`) at the profile's baud rate, open ash (only reads), and serve
    /// TROL to this process over an in-memory line (docs/c500c.md).
    pub(super) fn open_c500c(
        device: &str,
        profile: trol_c500c::Profile,
        link: LinkConfig,
    ) -> Result<Robot> {
        let settings = PortSettings {
            baud: profile.baud,
            ..PortSettings::default()
        };
        let port = trol_port::open(device, &settings).map_err(SetupError::Port)?;
        let said = super::ControllerSaid::default();
        let keep = said.clone();
        let backend = trol_c500c::C500cBackend::connect(
            port,
            profile,
            Some(Box::new(move |line: &str| {
                tracing::info!(target: "trol::c500c", "c500c: {line}");
                keep.keep(&format!("c500c: {line}"));
            })),
        )
        .map_err(|e| SetupError::NoServer(e.to_string()))?;
        let mut robot = Robot::embed(backend, trol_c500c::C500C_CODES, link);
        robot.said = Some(said);
        Ok(robot)
    }

    #[cfg(feature = "mars")]
    /// Embed the controller with the MARS 8 backend: open DEVICE (a serial device with
    /// RTS/CTS, or `socket://HOST:PORT`) at the profile's baud rate, read the unit's state
    /// (nothing moves), and serve TROL to this process over an in-memory line
    /// (docs/mars.md). TROL's own location table starts with `locations`: the locations and
    /// the file they came from, which TROLSaveLocations writes back (docs/teach.md).
    pub(super) fn open_mars(
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
        let said = super::ControllerSaid::default();
        let keep = said.clone();
        let backend = trol_mars::MarsBackend::connect(
            port,
            profile,
            Some(Box::new(move |line: &str| {
                tracing::info!(target: "trol::mars", "mars: {line}");
                keep.keep(&format!("mars: {line}"));
            })),
            None,
            locations,
        )
        .map_err(|e| SetupError::NoServer(e.to_string()))?;
        let mut backend = backend;
        backend.set_locations_file(file);
        let mut robot = Robot::embed(backend, trol_mars::MARS_CODES, link);
        robot.said = Some(said);
        Ok(robot)
    }

    /// Start an embedded controller (simulated A465) whose live 3D view is served at `addr`
    /// (`host:port`; docs: crates/trol-view), and connect to it. The view lives as long as the
    /// connection; [`Robot::view_url`] says where it is.
    #[cfg(feature = "view")]
    pub(super) fn open_viewed(settings: SimSettings, cfg: LinkConfig, addr: &str) -> Result<Robot> {
        let backend = trol_sim::SimBackend::new(settings);
        let slot = trol_controller::SharedReport::default();
        let view = trol_view::serve(addr, slot.clone())
            .map_err(|e| SetupError::Config(format!("cannot serve the view at {addr}: {e}")))?;
        let cfg = in_process(cfg);
        let (line, handle) = trol_controller::embedded_reporting(
            trol_controller::Pcp::new(backend),
            cfg,
            slot,
            trol_view::REPORT_INTERVAL,
        );
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
    pub(super) fn embedded_on(settings: SimSettings, cfg: LinkConfig) -> Robot {
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
            doubt: None,
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
            said: None,
        };
        robot.default_handlers();
        robot
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
}

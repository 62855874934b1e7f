//! [`Connect`]: the one way to open a connection. Every surface takes it (the utilities,
//! C's InitTROL and trol_connect, Python's `Robot.open` and `Robot.from_config`), so every
//! connection is checked the same way: GetStatus, the protocol version (GetVersion) and the
//! controller's BIOS codes (GetCodes), or the activation of a controller in terminal mode
//! (InitTROL(0), manual section "Initialisierung"), which ends in the same check.

use super::*;

/// How to open a connection, as a builder: start from a port name ([`Connect::port`]), a
/// trol.cfg ([`Connect::config`], [`Connect::default_config`]) or the embedded simulator's
/// settings ([`Connect::sim`]); set what differs; then [`Connect::connect`].
///
/// ```
/// use trol::{Connect, SimSettings};
/// let mut robot = Connect::sim(SimSettings { time_scale: 100.0, ..SimSettings::default() })
///     .repeats(1)
///     .connect()?;
/// assert_eq!(robot.version()?.protocol, trol::table::PROTOCOL_VERSION);
/// # Ok::<(), trol::Error>(())
/// ```
#[derive(Debug)]
#[must_use = "nothing is opened until .connect()"]
pub struct Connect {
    cfg: Config,
    check: bool,
    activate: bool,
    repeats: Option<u8>,
    reply_tenths: Option<u16>,
    delay: Option<Duration>,
    #[cfg(feature = "sim")]
    sim: Option<SimSettings>,
    #[cfg(feature = "rapl")]
    rapl: Option<trol_rapl::Profile>,
    #[cfg(feature = "mars")]
    mars: Option<trol_mars::Profile>,
    #[cfg(feature = "c500c")]
    c500c: Option<trol_c500c::Profile>,
}

impl Connect {
    fn from(cfg: Config) -> Connect {
        Connect {
            cfg,
            check: true,
            activate: false,
            repeats: None,
            reply_tenths: None,
            delay: None,
            #[cfg(feature = "sim")]
            sim: None,
            #[cfg(feature = "rapl")]
            rapl: None,
            #[cfg(feature = "mars")]
            mars: None,
            #[cfg(feature = "c500c")]
            c500c: None,
        }
    }

    /// A port as layer 1 accepts it (`/dev/ttyUSB0`, `COM1`, `socket://host:port`,
    /// `listen://host:port`), `sim` (the embedded simulated A465), `rapl:DEVICE` (a C500 in
    /// RAPL-II, default profile unless [`Connect::rapl_profile`]), `mars:DEVICE` (a MARS 8:
    /// give its arm profile with [`Connect::mars_profile`]) or `c500c:DEVICE` (a C500C, its
    /// profile with `Connect::c500c_profile`); 9600 Bd unless [`Connect::baud`].
    pub fn port(name: &str) -> Connect {
        Connect::from(Config {
            port: name.to_string(),
            ..Config::default()
        })
    }

    /// Everything trol.cfg says: port, baud rate, block check, tool transform, the
    /// simulator's settings and files, the profiles of `rapl:` and `mars:`, the view.
    pub fn config(cfg: &Config) -> Connect {
        Connect::from(cfg.clone())
    }

    /// [`Connect::config`] of ./trol.cfg, or of the file `$TROL_CONFIG` names.
    pub fn default_config() -> Result<Connect> {
        let cfg = Config::load().map_err(|e| SetupError::Config(e.to_string()))?;
        Ok(Connect::config(&cfg))
    }

    /// The embedded simulated A465 (port `sim`) with these settings.
    #[cfg(feature = "sim")]
    pub fn sim(settings: SimSettings) -> Connect {
        let mut c = Connect::port("sim");
        c.sim = Some(settings);
        c
    }

    /// The line's baud rate (trol.cfg's first line).
    pub fn baud(mut self, baud: u32) -> Connect {
        self.cfg.baud = baud;
        self
    }

    /// The link's block check (`check =` in trol.cfg): no fallback to the manual's LRC.
    pub fn block_check(mut self, check: BlockCheck) -> Connect {
        self.cfg.check = Some(check);
        self
    }

    /// The tool transform [`Connect::activate`] sends (trol.cfg's third line).
    pub fn tool(mut self, tool: [f64; 6]) -> Connect {
        self.cfg.tool = tool;
        self
    }

    /// The RAPL-II profile of a `rapl:` port (docs/c500.md).
    #[cfg(feature = "rapl")]
    pub fn rapl_profile(mut self, profile: trol_rapl::Profile) -> Connect {
        self.rapl = Some(profile);
        self
    }

    /// The arm profile of a `mars:` port (docs/mars.md).
    #[cfg(feature = "mars")]
    pub fn mars_profile(mut self, profile: trol_mars::Profile) -> Connect {
        self.mars = Some(profile);
        self
    }

    /// The C500C profile of a `c500c:` port (docs/c500c.md).
    #[cfg(feature = "c500c")]
    pub fn c500c_profile(mut self, profile: trol_c500c::Profile) -> Connect {
        self.c500c = Some(profile);
        self
    }

    /// Serve the embedded simulator's live 3D view at `addr` (`host:port`; `view =` in
    /// trol.cfg); [`Robot::view_url`] says where it is.
    #[cfg(feature = "view")]
    pub fn view(mut self, addr: &str) -> Connect {
        self.cfg.view = Some(addr.to_string());
        self
    }

    /// How often a failed transaction is sent again ([`Robot::set_repeats`]), from the
    /// check on.
    pub fn repeats(mut self, repeats: u8) -> Connect {
        self.repeats = Some(repeats);
        self
    }

    /// The reply timeout in tenths of a second ([`Robot::set_reply_timeout_tenths`], the
    /// manual's SetL3_TO_Intervall), from the check on.
    pub fn reply_timeout_tenths(mut self, tenths: u16) -> Connect {
        self.reply_tenths = Some(tenths);
        self
    }

    /// The pause between two bytes sent ([`Robot::set_delay`], the manual's SetDelay).
    pub fn delay(mut self, delay: Duration) -> Connect {
        self.delay = Some(delay);
        self
    }

    /// Bring a controller in terminal mode into server mode first, with the tool transform
    /// (InitTROL(0), `trol init`; manual section "Initialisierung"); a server already active
    /// is only checked.
    pub fn activate(mut self) -> Connect {
        self.activate = true;
        self
    }

    /// Skip the check: only for a test double that answers no GetStatus. Without it the
    /// connection knows neither the controller's protocol version, nor its codes, nor its
    /// reply time: no repeats, and the manual's 15 s reply timeout.
    pub fn without_check(mut self) -> Connect {
        self.check = false;
        self
    }

    /// Open the port, apply the settings, and check the controller (or activate it): a
    /// [`SetupError`] says what to do when the port does not open, nothing answers, or the
    /// controller speaks another protocol version.
    pub fn connect(self) -> Result<Robot> {
        let mut robot = self.open()?;
        if let Some(n) = self.repeats {
            robot.set_repeats(n);
        }
        if let Some(tenths) = self.reply_tenths {
            robot.set_reply_timeout_tenths(tenths)?;
        }
        if let Some(delay) = self.delay {
            robot.set_delay(delay)?;
        }
        // A locations file that is not there yet is an empty table (docs/teach.md): said
        // once per path (the notice names it whole, and notices are said once each), so that
        // a misspelt name is not a silent empty table, in whatever folder it is misspelt.
        if let Some(file) = self.cfg.locations.as_ref().filter(|f| !f.exists()) {
            let whole = std::path::absolute(file).unwrap_or_else(|_| file.clone());
            robot.add_notice(&format!(
                "{} does not exist yet: the location table starts empty, and \
                 TROLSaveLocations creates the file",
                whole.display()
            ));
        }
        if self.activate {
            crate::activate(&mut robot, &self.cfg.tool)?;
        } else if self.check {
            crate::check_server(&mut robot)?;
        }
        Ok(robot)
    }

    /// The MARS 8 profile this connection uses: the one given, else trol.cfg's file.
    #[cfg(feature = "mars")]
    fn mars_profile_chosen(&self) -> Result<trol_mars::Profile> {
        match (&self.mars, &self.cfg.mars_profile) {
            (Some(p), _) => Ok(p.clone()),
            (None, Some(path)) => trol_mars::Profile::from_file(path)
                .map_err(|e| SetupError::Config(e.to_string()).into()),
            (None, None) => Err(SetupError::Config(format!(
                "port {}: an A465 on a MARS 8 needs its arm profile: add `mars-profile = FILE` \
                 to trol.cfg (crates/trol-mars/profiles/crs93.toml is CTU's CRS93; \
                 docs/mars.md), or give it to Connect::mars_profile",
                self.cfg.port
            ))
            .into()),
        }
    }

    /// The C500C profile this connection uses: the one given, else trol.cfg's file, else the
    /// default (nothing settled: every motion is refused, naming the key).
    #[cfg(feature = "c500c")]
    fn c500c_profile_chosen(&self) -> Result<trol_c500c::Profile> {
        match (&self.c500c, &self.cfg.c500c_profile) {
            (Some(p), _) => Ok(p.clone()),
            (None, Some(path)) => trol_c500c::Profile::from_file(path)
                .map_err(|e| SetupError::Config(e.to_string()).into()),
            (None, None) => Ok(trol_c500c::Profile::default()),
        }
    }

    /// The RAPL-II profile this connection uses: the one given, else trol.cfg's file, else
    /// the default.
    #[cfg(feature = "rapl")]
    fn rapl_profile_chosen(&self) -> Result<trol_rapl::Profile> {
        match (&self.rapl, &self.cfg.rapl_profile) {
            (Some(p), _) => Ok(p.clone()),
            (None, Some(path)) => trol_rapl::Profile::from_file(path)
                .map_err(|e| SetupError::Config(e.to_string()).into()),
            (None, None) => Ok(trol_rapl::Profile::default()),
        }
    }

    /// The line speed this connection opens its port at, and what sets it: a real
    /// controller's profile (`rapl:`, `mars:`, `c500c:`: trol.cfg's `baud` is not used
    /// there), else trol.cfg's `baud` (None for the embedded simulator, which has no line).
    /// Err: the profile cannot be read (the message the connection would give).
    pub fn line_speed(&self) -> Result<Option<(u32, String)>> {
        let cfg = &self.cfg;
        #[cfg_attr(
            not(any(feature = "rapl", feature = "mars", feature = "c500c")),
            allow(unused_variables)
        )]
        let from_profile = |kind: &str, given: bool, file: &Option<std::path::PathBuf>| {
            if given {
                format!("the {kind} profile given to Connect")
            } else if let Some(f) = file {
                format!("the {kind} profile {}", f.display())
            } else {
                format!("the default {kind} profile")
            }
        };
        if cfg.port.starts_with(MARS_PREFIX) {
            #[cfg(feature = "mars")]
            return Ok(Some((
                self.mars_profile_chosen()?.baud,
                from_profile("MARS 8", self.mars.is_some(), &cfg.mars_profile),
            )));
        }
        if cfg.port.starts_with(C500C_PREFIX) {
            #[cfg(feature = "c500c")]
            return Ok(Some((
                self.c500c_profile_chosen()?.baud,
                from_profile("C500C", self.c500c.is_some(), &cfg.c500c_profile),
            )));
        }
        if cfg.port.starts_with(RAPL_PREFIX) {
            #[cfg(feature = "rapl")]
            return Ok(Some((
                self.rapl_profile_chosen()?.baud,
                from_profile("RAPL-II", self.rapl.is_some(), &cfg.rapl_profile),
            )));
        }
        if cfg.port == "sim" {
            return Ok(None);
        }
        Ok(Some((cfg.baud, "trol.cfg's baud".into())))
    }

    /// The connection, unchecked: the embedded controllers by the port's prefix, else the
    /// port itself.
    fn open(&self) -> Result<Robot> {
        let cfg = &self.cfg;
        #[cfg_attr(
            not(any(feature = "sim", feature = "rapl", feature = "mars", feature = "c500c")),
            allow(unused_variables)
        )]
        let link = LinkConfig {
            check: cfg.block_check(),
            ..LinkConfig::default()
        };
        if let Some(device) = cfg.port.strip_prefix(MARS_PREFIX) {
            #[cfg(not(feature = "mars"))]
            return Err(open::not_built(device, "mars", "the MARS 8 backend"));
            #[cfg(feature = "mars")]
            {
                let profile = self.mars_profile_chosen()?;
                let locations = crate::config_locations(cfg)?;
                // TROLSaveLocations writes trol.cfg's locations file back (docs/teach.md).
                return Robot::open_mars(device, profile, (locations, cfg.locations.clone()), link);
            }
        }
        if let Some(device) = cfg.port.strip_prefix(C500C_PREFIX) {
            #[cfg(not(feature = "c500c"))]
            return Err(open::not_built(device, "c500c", "the C500C backend"));
            #[cfg(feature = "c500c")]
            {
                let profile = self.c500c_profile_chosen()?;
                return Robot::open_c500c(device, profile, link);
            }
        }
        if let Some(device) = cfg.port.strip_prefix(RAPL_PREFIX) {
            #[cfg(not(feature = "rapl"))]
            return Err(open::not_built(device, "rapl", "the RAPL-II backend"));
            #[cfg(feature = "rapl")]
            {
                let profile = self.rapl_profile_chosen()?;
                return Robot::open_rapl(device, profile, link);
            }
        }
        if cfg.port == "sim" {
            #[cfg(not(feature = "sim"))]
            return Err(open::not_built(&cfg.port, "sim", "the embedded simulator"));
            #[cfg(feature = "sim")]
            {
                let settings = match &self.sim {
                    Some(s) => s.clone(),
                    None => crate::sim_settings(cfg)?,
                };
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
                        let robot = Robot::open_viewed(settings, link, addr)?;
                        // Asked for: say where it is (port 0 picks one).
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
        }
        Robot::open_port(&cfg.port, cfg.baud, cfg.check)
    }
}

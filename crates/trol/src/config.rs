//! trol.cfg (manual, "Konfiguration").
//!
//! Three entries, one per line: the baud rate, the port, and the tool transform (six
//! numbers: x y z in mm, yaw pitch roll in radians, separated by blanks or commas). The file
//! is read from the current directory, or from the file the environment variable
//! `TROL_CONFIG` names.
//!
//! Further settings of ours may follow, one `key = value` per line; they matter only for the
//! embedded controller (port `sim`):
//!
//! | key | value | default |
//! |---|---|---|
//! | `check` | the link's block check: `crc16` or the manual's `lrc` (docs/protocol.md) | crc16, and lrc for a controller that speaks only the manual's protocol |
//! | `time_scale` | how much faster than real time the simulation runs | 1 |
//! | `locations` | a location file to load (relative to trol.cfg's folder) | none |
//! | `table_z` | the table plane, mm | 0 |
//! | `homed` | `yes`: the simulated arm starts homed | no |
//! | `object` | width of an object held between the fingers at start, mm | none |
//! | `objects` | a file of objects in the world, `NAME x y z width` per line (relative to trol.cfg's folder) | none |
//! | `rapl-profile` | port `rapl:DEVICE`: the RAPL-II profile of the C500 on DEVICE (docs/c500.md; relative to trol.cfg's folder) | the safe default |
//! | `view` | port `sim`: serve the live 3D view of the arm at this address (`host:port`; `127.0.0.1:8465` is this machine only) | none |
//!
//! Blank lines and lines starting with `#` are skipped.

use std::path::{Path, PathBuf};

/// The file name looked for in the current directory.
pub const FILE_NAME: &str = "trol.cfg";
/// The slowest baud rate trol.cfg takes.
pub const MIN_BAUD: u32 = 300;
/// The fastest baud rate trol.cfg takes (USB adapters reach a few Mbaud).
pub const MAX_BAUD: u32 = 4_000_000;
/// The environment variable that names another file.
pub const ENV_VAR: &str = "TROL_CONFIG";

/// The settings of trol.cfg.
#[derive(Clone, Debug, PartialEq)]
pub struct Config {
    /// Baud rate.
    pub baud: u32,
    /// The port (a serial device, `socket://host:port`, `listen://host:port`, or `sim`).
    pub port: String,
    /// The tool transform.
    pub tool: [f64; 6],
    /// Simulation speed-up (port `sim`).
    pub time_scale: f64,
    /// Location file (port `sim`).
    pub locations: Option<PathBuf>,
    /// The objects file of the simulated world.
    pub objects: Option<PathBuf>,
    /// The link's block check, if trol.cfg names one. Without it (the manual's 3-line
    /// trol.cfg) a connection uses CRC-16 and falls back to the manual's LRC for a
    /// controller that checks blocks only so (docs/protocol.md, "A peer of 1998").
    pub check: Option<trol_proto::link::BlockCheck>,
    /// Table plane, mm (port `sim`).
    pub table_z: f64,
    /// The simulated arm starts homed.
    pub homed: bool,
    /// The RAPL-II profile (port `rapl:DEVICE`).
    pub rapl_profile: Option<PathBuf>,
    /// The MARS 8 arm profile (port `mars:DEVICE`).
    pub mars_profile: Option<PathBuf>,
    /// The C500C profile (port `c500c:DEVICE`).
    pub c500c_profile: Option<PathBuf>,
    /// Object width between the fingers, mm.
    pub object: Option<f64>,
    /// Where the embedded simulator serves its live view (`host:port`).
    pub view: Option<String>,
}

impl Config {
    /// The block check a connection starts with: the one named, else CRC-16.
    pub fn block_check(&self) -> trol_proto::link::BlockCheck {
        self.check.unwrap_or_default()
    }
}

impl Default for Config {
    fn default() -> Self {
        Config {
            baud: 9600,
            port: "sim".into(),
            tool: [0.0; 6],
            time_scale: 1.0,
            locations: None,
            objects: None,
            check: None,
            table_z: 0.0,
            homed: false,
            object: None,
            rapl_profile: None,
            mars_profile: None,
            c500c_profile: None,
            view: None,
        }
    }
}

/// Where a configuration comes from ([`Config::locate`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ConfigSource {
    /// The file `$TROL_CONFIG` (or a `--config` flag) names.
    Named(PathBuf),
    /// `./trol.cfg`.
    Found(PathBuf),
    /// No trol.cfg: the defaults (the embedded simulator).
    Defaults,
}

impl std::fmt::Display for ConfigSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ConfigSource::Named(p) | ConfigSource::Found(p) => write!(f, "{}", p.display()),
            ConfigSource::Defaults => write!(
                f,
                "no trol.cfg here and no {ENV_VAR}: using the defaults, port `sim` (the embedded \
                 simulator); write a trol.cfg (see examples/trol.cfg) to drive a controller"
            ),
        }
    }
}

/// A missing or malformed trol.cfg.
#[derive(Clone, Debug, PartialEq)]
pub struct ConfigError {
    /// The file.
    pub file: PathBuf,
    /// The line (1-based), if the error is in one.
    pub line: Option<usize>,
    /// What is wrong and what is expected.
    pub message: String,
}

impl std::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.line {
            Some(l) => write!(f, "{}:{l}: {}", self.file.display(), self.message),
            None => write!(f, "{}: {}", self.file.display(), self.message),
        }
    }
}

impl std::error::Error for ConfigError {}

/// The largest trol.cfg read, bytes.
pub const MAX_FILE: usize = 64 * 1024;

impl Config {
    /// Where trol.cfg is: `$TROL_CONFIG`, else `./trol.cfg`.
    pub fn default_path() -> PathBuf {
        std::env::var_os(ENV_VAR)
            .map(PathBuf::from)
            .unwrap_or_else(|| PathBuf::from(FILE_NAME))
    }

    /// Where the configuration comes from: the file `$TROL_CONFIG` names (it must exist),
    /// else `./trol.cfg` if there is one, else the defaults.
    pub fn locate() -> ConfigSource {
        match std::env::var_os(ENV_VAR) {
            Some(p) => ConfigSource::Named(PathBuf::from(p)),
            None if Path::new(FILE_NAME).exists() => ConfigSource::Found(PathBuf::from(FILE_NAME)),
            None => ConfigSource::Defaults,
        }
    }

    /// Read the configuration the same way in every language and tool (decision, README
    /// "Configuration"): the file `$TROL_CONFIG` names, which must exist; else `./trol.cfg`;
    /// else, with no trol.cfg at all, the defaults, which drive the embedded simulator (port
    /// `sim`), and a note on stderr says so once per process.
    pub fn load() -> Result<Config, ConfigError> {
        match Config::locate() {
            ConfigSource::Named(p) | ConfigSource::Found(p) => Config::from_file(&p),
            ConfigSource::Defaults => {
                static SAID: std::sync::Once = std::sync::Once::new();
                SAID.call_once(|| eprintln!("trol: {}", ConfigSource::Defaults));
                Ok(Config::default())
            }
        }
    }

    /// Read a configuration file (at most [`MAX_FILE`] bytes: a trol.cfg is a few lines, and
    /// a device such as /dev/zero must not be read for ever).
    pub fn from_file(path: &Path) -> Result<Config, ConfigError> {
        use std::io::Read;
        let mut text = String::new();
        let read = std::fs::File::open(path)
            .and_then(|f| f.take(MAX_FILE as u64 + 1).read_to_string(&mut text));
        if read.as_ref().is_ok_and(|n| *n > MAX_FILE) {
            return Err(ConfigError {
                file: path.to_path_buf(),
                line: None,
                message: format!(
                    "it is larger than {} KiB: not a trol.cfg (three lines: the baud rate, the \
                     port, the tool transform); set {ENV_VAR} to the right file",
                    MAX_FILE / 1024
                ),
            });
        }
        read.map_err(|e| ConfigError {
            file: path.to_path_buf(),
            line: None,
            message: format!(
                "cannot read it ({e}); trol.cfg holds three lines: the baud rate, the port, \
                 and the tool transform (x y z yaw pitch roll); set {ENV_VAR} to use another file"
            ),
        })?;
        let mut cfg = Config::parse(&text).map_err(|(line, message)| ConfigError {
            file: path.to_path_buf(),
            line: Some(line),
            message,
        })?;
        let dir = path.parent().unwrap_or(Path::new("."));
        for file in [
            &mut cfg.locations,
            &mut cfg.objects,
            &mut cfg.rapl_profile,
            &mut cfg.mars_profile,
            &mut cfg.c500c_profile,
        ]
        .into_iter()
        .flatten()
        {
            if file.is_relative() {
                *file = dir.join(&*file);
            }
        }
        // A file it names that is not there is this file's error, with its line, not the
        // first command's.
        for (key, file) in [
            ("locations", &cfg.locations),
            ("objects", &cfg.objects),
            ("rapl-profile", &cfg.rapl_profile),
            ("mars-profile", &cfg.mars_profile),
            ("c500c-profile", &cfg.c500c_profile),
        ] {
            let Some(file) = file else { continue };
            if file.is_file() {
                continue;
            }
            // A locations file that does not exist yet, in a folder that does, is an empty
            // table that TROLSaveLocations creates (docs/teach.md).
            let folder_there = file
                .parent()
                .is_none_or(|d| d.as_os_str().is_empty() || d.is_dir());
            if key == "locations" && !file.exists() && folder_there {
                continue;
            }
            let line = text
                .lines()
                .position(|l| {
                    let l = l.trim_start();
                    l.starts_with(key) || l.starts_with(&key.replace('-', "_"))
                })
                .map(|i| i + 1);
            return Err(ConfigError {
                file: path.to_path_buf(),
                line,
                message: if key == "locations" && !folder_there {
                    format!(
                        "{key}: the folder of {} is not there (a relative path counts from \
                         trol.cfg's folder): create it, or name a file in a folder that is",
                        file.display()
                    )
                } else {
                    format!(
                        "{key}: {} is not there (a relative path counts from trol.cfg's folder)",
                        file.display()
                    )
                },
            });
        }
        Ok(cfg)
    }

    /// Parse the text of a configuration file; an error is (line, message).
    pub fn parse(text: &str) -> Result<Config, (usize, String)> {
        let mut cfg = Config::default();
        let mut entry = 0;
        let mut last_line = 0;
        for (i, raw) in text.lines().enumerate() {
            let n = i + 1;
            last_line = n;
            let line = raw.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            match entry {
                0 => {
                    cfg.baud = line
                        .parse()
                        .ok()
                        .filter(|b| (MIN_BAUD..=MAX_BAUD).contains(b))
                        .ok_or((
                            n,
                            format!(
                                "expected the baud rate (a whole number {MIN_BAUD}..{MAX_BAUD} \
                                 such as 9600), found {line:?}"
                            ),
                        ))?;
                }
                1 => {
                    if line.contains(|c: char| c.is_whitespace() || c.is_control()) {
                        return Err((
                            n,
                            format!(
                                "expected the port (a device such as /dev/ttyUSB0 or COM1, \
                                 socket://HOST:PORT, rapl:DEVICE, or sim), found {line:?}"
                            ),
                        ));
                    }
                    cfg.port = line.to_string();
                }
                2 => {
                    let nums: Vec<&str> = line
                        .split(|c: char| c.is_whitespace() || c == ',')
                        .filter(|s| !s.is_empty())
                        .collect();
                    let values: Option<Vec<f64>> = nums
                        .iter()
                        .map(|s| s.parse::<f64>().ok().filter(|x| x.is_finite()))
                        .collect();
                    match values {
                        Some(v)
                            if v.len() == 6
                                && (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
                                    <= trol_proto::application::table::MAX_TOOL_MM =>
                        {
                            cfg.tool.copy_from_slice(&v)
                        }
                        Some(v) if v.len() == 6 => {
                            return Err((
                                n,
                                format!(
                                    "the tool transform's offset is {:.0} mm: a tool longer than \
                                     {} mm is beyond what the arm can carry",
                                    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt(),
                                    trol_proto::application::table::MAX_TOOL_MM
                                ),
                            ));
                        }
                        _ => {
                            return Err((
                                n,
                                format!(
                                    "expected the tool transform: six numbers (x y z in mm, yaw \
                                     pitch roll in radians) separated by blanks or commas, found {line:?}"
                                ),
                            ));
                        }
                    }
                }
                _ => {
                    let (key, value) = line.split_once('=').ok_or((
                        n,
                        format!("expected `key = value` after the three entries, found {line:?}"),
                    ))?;
                    let (key, value) = (key.trim(), value.trim());
                    let number = |what: &str| {
                        value
                            .parse::<f64>()
                            .ok()
                            .filter(|x| x.is_finite())
                            .ok_or((n, format!("{key}: expected {what}, found {value:?}")))
                    };
                    match key {
                        "time_scale" => {
                            cfg.time_scale = number("a positive number")?;
                            if cfg.time_scale <= 0.0 {
                                return Err((n, "time_scale must be positive".into()));
                            }
                        }
                        "locations" => cfg.locations = Some(PathBuf::from(value)),
                        "objects" => cfg.objects = Some(PathBuf::from(value)),
                        "view" => {
                            let ok = value.rsplit_once(':').is_some_and(|(host, port)| {
                                !host.is_empty() && port.parse::<u16>().is_ok()
                            });
                            if !ok {
                                return Err((
                                    n,
                                    format!(
                                        "view: expected host:port, like 127.0.0.1:8465 (this \
                                         machine only), found {value:?}"
                                    ),
                                ));
                            }
                            cfg.view = Some(value.to_string())
                        }
                        "rapl-profile" | "rapl_profile" => {
                            cfg.rapl_profile = Some(PathBuf::from(value))
                        }
                        "mars-profile" | "mars_profile" => {
                            cfg.mars_profile = Some(PathBuf::from(value))
                        }
                        "c500c-profile" | "c500c_profile" => {
                            cfg.c500c_profile = Some(PathBuf::from(value))
                        }
                        "check" => {
                            cfg.check = Some(trol_proto::link::BlockCheck::from_word(value).ok_or(
                                (n, format!("check: expected crc16 or lrc, found {value:?}")),
                            )?)
                        }
                        "table_z" => cfg.table_z = number("a height in mm")?,
                        "object" => cfg.object = Some(number("a width in mm")?),
                        "homed" => {
                            cfg.homed = match value {
                                "yes" | "true" | "1" => true,
                                "no" | "false" | "0" => false,
                                _ => {
                                    return Err((
                                        n,
                                        format!("homed: expected yes or no, found {value:?}"),
                                    ));
                                }
                            }
                        }
                        _ => {
                            return Err((
                                n,
                                format!(
                                    "unknown setting {key:?}; known: check, time_scale, locations, objects, table_z, homed, object, rapl-profile, mars-profile, c500c-profile, view"
                                ),
                            ));
                        }
                    }
                }
            }
            entry += 1;
        }
        if entry < 3 {
            let what = ["the baud rate", "the port", "the tool transform"][entry];
            return Err((
                last_line + 1,
                format!("missing entry {}: {what}", entry + 1),
            ));
        }
        Ok(cfg)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_three_entries_and_settings() {
        let c =
            Config::parse("38400\n/dev/ttyUSB0\n0, 0, 120.5, 0 0 1.5\ntime_scale = 10\n").unwrap();
        assert_eq!(c.baud, 38400);
        assert_eq!(c.port, "/dev/ttyUSB0");
        assert_eq!(c.tool, [0.0, 0.0, 120.5, 0.0, 0.0, 1.5]);
        assert_eq!(c.time_scale, 10.0);
    }

    #[test]
    fn errors_name_the_line_and_the_form() {
        let e = Config::parse("fast\nsim\n0 0 0 0 0 0\n").unwrap_err();
        assert_eq!(e.0, 1);
        assert!(e.1.contains("baud rate"));
        let e = Config::parse("9600\nsim\n0 0 0 0 0\n").unwrap_err();
        assert_eq!(e.0, 3);
        assert!(e.1.contains("six numbers"));
        let e = Config::parse("9600\nsim\n").unwrap_err();
        assert!(e.1.contains("tool transform"), "{e:?}");
        let e = Config::parse("9600\nsim\n0 0 0 0 0 0\nspeed = 3\n").unwrap_err();
        assert_eq!(e.0, 4);
        // A baud rate no port has, a tool no arm carries.
        let e = Config::parse("3840019200\nsim\n0 0 0 0 0 0\n").unwrap_err();
        assert_eq!(e.0, 1);
        assert!(e.1.contains("300..4000000"), "{e:?}");
        let e = Config::parse("9600\nsim\n0 0 1e30 0 0 0\n").unwrap_err();
        assert_eq!(e.0, 3);
        assert!(e.1.contains("beyond what the arm can carry"), "{e:?}");
        // The view's address: host and port.
        for bad in ["8465", ":8465", "localhost:", "127.0.0.1:99999"] {
            let e = Config::parse(&format!("9600\nsim\n0 0 0 0 0 0\nview = {bad}\n")).unwrap_err();
            assert_eq!(e.0, 4, "{bad}");
            assert!(e.1.contains("host:port"), "{e:?}");
        }
        let c = Config::parse("9600\nsim\n0 0 0 0 0 0\nview = 0.0.0.0:8465\n").unwrap();
        assert_eq!(c.view.as_deref(), Some("0.0.0.0:8465"));
        // A control character in the port's name.
        let e = Config::parse("9600\n/dev/tty\u{1b}USB0\n0 0 0 0 0 0\n").unwrap_err();
        assert_eq!(e.0, 2);
        assert!(e.1.contains("expected the port"), "{e:?}");
    }

    #[test]
    fn a_file_that_never_ends_is_refused_not_read_for_ever() {
        let e = Config::from_file(Path::new("/dev/zero")).unwrap_err();
        assert!(e.message.contains("not a trol.cfg"), "{e}");
        let dir = std::env::temp_dir().join(format!("trol-big-cfg-{}", std::process::id()));
        std::fs::write(&dir, "9600\nsim\n0 0 0 0 0 0\n".repeat(10_000)).unwrap();
        let e = Config::from_file(&dir).unwrap_err();
        let _ = std::fs::remove_file(&dir);
        assert!(e.message.contains("larger than 64 KiB"), "{e}");
    }

    #[test]
    fn a_missing_file_is_named() {
        let e = Config::from_file(Path::new("/nonexistent/trol.cfg")).unwrap_err();
        assert!(e.to_string().contains("/nonexistent/trol.cfg"));
        assert!(e.to_string().contains("three lines"));
    }
}

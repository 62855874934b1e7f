//! What the subcommands share: where the controller is (trol.cfg and the flags that override
//! it), logging, and the progress display while the arm works.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use clap::Args;
use trol::{Config, Robot};

/// Where the controller is: trol.cfg, and flags that override it.
#[derive(Args, Clone, Debug, Default)]
pub struct Conn {
    /// The configuration file (default: $TROL_CONFIG, else ./trol.cfg; with neither, the
    /// embedded simulator, port `sim`).
    #[arg(long, value_name = "FILE", global = true)]
    pub config: Option<PathBuf>,
    /// The port, overriding trol.cfg: `sim` (the embedded simulator); a TROL server on a
    /// serial device (/dev/ttyUSB0, /dev/pts/3, COM1), socket://HOST:PORT or
    /// listen://HOST:PORT; or a real controller driven from this PC: rapl:DEVICE (a C500 in
    /// RAPL-II), mars:DEVICE (a MARS 8), c500c:DEVICE (a C500C).
    #[arg(long, value_name = "PORT", global = true)]
    pub port: Option<String>,
    /// The baud rate, overriding trol.cfg.
    #[arg(long, value_name = "BAUD", global = true,
          value_parser = clap::value_parser!(u32).range(300..=4_000_000))]
    pub baud: Option<u32>,
    /// Port `sim`: run the simulation this many times faster than real time.
    #[arg(long, value_name = "N", global = true, value_parser = positive)]
    pub time_scale: Option<f64>,
    /// Port `sim`: the location table to load (docs/a465.md, "Locations"), as `trol sim
    /// --locations` does.
    #[arg(long, value_name = "FILE", global = true)]
    pub locations: Option<PathBuf>,
}

/// A number greater than 0.
pub fn positive(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("`{s}` is not a number greater than 0")),
    }
}

/// The configuration file `config` names (else $TROL_CONFIG, else ./trol.cfg), and where it
/// came from; without one the defaults, with no note (for the utilities that do not connect:
/// `trol sim`, `trol ports`).
pub fn config_file(
    config: Option<PathBuf>,
) -> Result<(Config, trol::config::ConfigSource), String> {
    use trol::config::ConfigSource;
    let source = match config {
        Some(p) => ConfigSource::Named(p),
        None => Config::locate(),
    };
    let cfg = match &source {
        ConfigSource::Named(p) | ConfigSource::Found(p) => {
            Config::from_file(p).map_err(|e| e.to_string())?
        }
        ConfigSource::Defaults => Config::default(),
    };
    Ok((cfg, source))
}

impl Conn {
    /// trol.cfg with the flags applied. A missing default trol.cfg means the defaults (port
    /// `sim`); a missing file named by --config or $TROL_CONFIG is an error.
    pub fn config(&self) -> Result<Config, String> {
        self.config_with_source().map(|(cfg, _)| cfg)
    }

    /// Like [`Conn::config`], with where the file came from. Without a trol.cfg the note
    /// says once that the embedded simulator is used, as in every TROL program.
    pub fn config_with_source(&self) -> Result<(Config, trol::config::ConfigSource), String> {
        use trol::config::ConfigSource;
        let source = match &self.config {
            Some(p) => ConfigSource::Named(p.clone()),
            None => Config::locate(),
        };
        let mut cfg = match &source {
            ConfigSource::Named(p) | ConfigSource::Found(p) => {
                Config::from_file(p).map_err(|e| e.to_string())?
            }
            // A port named on the command line needs no note.
            ConfigSource::Defaults if self.port.is_some() => Config::default(),
            ConfigSource::Defaults => Config::load().map_err(|e| e.to_string())?,
        };
        if let Some(p) = &self.port {
            cfg.port = p.clone();
        }
        if let Some(b) = self.baud {
            cfg.baud = b;
        }
        if let Some(t) = self.time_scale {
            cfg.time_scale = t;
        }
        if let Some(l) = &self.locations {
            // Checked now, not at the first command that needs the table: a misspelt folder,
            // a bad line or a reserved name is the start's failure (issue 44, item 3).
            trol_a465::backend::table::load(l).map_err(|e| format!("--locations: {e}"))?;
            cfg.locations = Some(l.clone());
        }
        Ok((cfg, source))
    }

    /// Connect as the configuration says. On a real port the server must answer
    /// (InitTROL(1)).
    pub fn robot(&self) -> Result<(Robot, Config), String> {
        let cfg = self.config()?;
        // The check every surface makes (trol::Connect): the server answers, speaks this
        // protocol version, and tells its BIOS codes. The embedded controller starts in
        // server mode with the tool of trol.cfg, and answers the same.
        let mut robot = robot_from_config(&cfg, false)?;
        if let Some(notice) = robot.take_notice()
            && trol::notice_due("trol", &cfg.port, &notice)
        {
            crate::tell!(
                "trol: note: {notice} (said once for this port; TROL_VERBOSE=1 says it at every \
                 start)"
            );
        }
        tracing::info!(port = %cfg.port, baud = cfg.baud, "connected");
        Ok((robot, cfg))
    }
}

/// Connect as `cfg` says and check the controller, as [`trol::Connect`] does (with `activate`,
/// bring it from terminal mode into server mode first, as InitTROL(0)); with `view = ADDR`
/// and the embedded simulator, the live view is the utilities' own (the client library and
/// libtrol carry no view): served here and kept with the connection.
pub fn robot_from_config(cfg: &Config, activate: bool) -> Result<Robot, String> {
    match &cfg.view {
        Some(addr) if cfg.port == "sim" => {
            let settings = trol::sim_settings(cfg).map_err(|e| e.to_string())?;
            let link = trol_proto::link::LinkConfig {
                check: cfg.block_check(),
                ..Default::default()
            };
            let viewed = embedded_viewed(settings, link, addr)?;
            crate::tell!("trol: the view of the simulated arm: {}", viewed.url);
            if let Some(w) = &viewed.exposure {
                crate::tell!("trol: warning: {w}");
            }
            let mut robot = viewed.robot;
            trol::check_server(&mut robot).map_err(|e| e.to_string())?;
            Ok(robot)
        }
        _ if activate => trol::Connect::config(cfg)
            .activate()
            .connect()
            .map_err(|e| e.to_string()),
        _ => trol::Connect::config(cfg)
            .connect()
            .map_err(|e| e.to_string()),
    }
}

/// An embedded simulator with its live view.
pub struct Viewed {
    /// The connection; it keeps the view alive.
    pub robot: Robot,
    /// Where the view is.
    pub url: String,
    /// A warning when the view is open to other machines.
    pub exposure: Option<String>,
    /// The pages that opened the view.
    pub watchers: trol_view::Watchers,
}

/// Start the embedded simulator with its live view served at `addr`, and connect to it.
pub fn embedded_viewed(
    settings: trol_sim::SimSettings,
    link: trol_proto::link::LinkConfig,
    addr: &str,
) -> Result<Viewed, String> {
    let backend = trol_sim::SimBackend::new(settings);
    let slot = trol_controller::SharedReport::default();
    let view = trol_view::serve(addr, slot.clone())
        .map_err(|e| format!("cannot serve the view at {addr}: {e}"))?;
    let (url, exposure, watchers) = (view.url(), view.exposure(), view.watchers());
    let (line, handle) = trol_controller::embedded_reporting(
        trol_controller::Pcp::new(backend),
        link,
        slot,
        trol_view::REPORT_INTERVAL,
    );
    let mut robot = Robot::over(Box::new(line), link, Some(handle));
    robot.keep(view);
    Ok(Viewed {
        robot,
        url,
        exposure,
        watchers,
    })
}

/// Logs to stderr: `RUST_LOG` if set, else warnings, and more with each `-v`.
pub fn init_logging(verbose: u8) {
    init_logging_quieting(verbose, "");
}

/// [`init_logging`], with `quiet` (directives such as `rustdds=error`) added to what `-v`
/// asks for: libraries whose own log would drown TROL's.
pub fn init_logging_quieting(verbose: u8, quiet: &str) {
    use tracing_subscriber::EnvFilter;
    let filter = if verbose > 0 {
        let level = match verbose {
            1 => "info",
            2 => "debug",
            _ => "trace",
        };
        EnvFilter::new(if quiet.is_empty() {
            level.to_string()
        } else {
            format!("{level},{quiet}")
        })
    } else {
        EnvFilter::try_from_default_env().unwrap_or_else(|_| {
            EnvFilter::new(if quiet.is_empty() {
                "warn".to_string()
            } else {
                format!("warn,{quiet}")
            })
        })
    };
    // Colour only where a person reads it: a terminal.
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_ansi(std::io::stderr().is_terminal())
        .with_writer(std::io::stderr)
        .with_target(false)
        .try_init();
}

/// Run `f` with a spinner on stderr while it works, if stderr is a terminal; without one,
/// just run it.
pub fn waiting<T>(label: &str, f: impl FnOnce() -> T) -> T {
    if !std::io::stderr().is_terminal() {
        return f();
    }
    let pb = indicatif::ProgressBar::new_spinner();
    pb.set_style(
        indicatif::ProgressStyle::with_template("{spinner} {msg} {elapsed}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
    );
    pb.set_message(label.to_string());
    pb.enable_steady_tick(Duration::from_millis(120));
    let out = f();
    pb.finish_and_clear();
    out
}

/// Ctrl-C while the arm works: the first one asks the running wait to halt the arm and give
/// the prompt back ([`interrupted`]); a second one, before the prompt is back, quits (status
/// 130). Installed once by the subcommands that move the arm.
static INTERRUPT: AtomicBool = AtomicBool::new(false);

/// Catch Ctrl-C as [`INTERRUPT`] says. Without a handler (it could not be installed) Ctrl-C
/// ends the process as usual.
pub fn catch_interrupts() {
    let installed = ctrlc::set_handler(|| {
        if INTERRUPT.swap(true, Ordering::SeqCst) {
            crate::tell!("\ninterrupted twice: quitting");
            std::process::exit(130);
        }
        crate::tell!("\ninterrupted: halting the arm (Ctrl-C again quits)");
    });
    if let Err(e) = installed {
        tracing::warn!("Ctrl-C will end the program without halting the arm: {e}");
    }
}

/// The flag Ctrl-C sets, for [`trol::Robot::finish_unless`].
pub fn interrupted() -> &'static AtomicBool {
    &INTERRUPT
}

/// Forget a Ctrl-C (back at the prompt, or before the next step).
pub fn clear_interrupt() {
    INTERRUPT.store(false, Ordering::SeqCst);
}

/// Sleep `d`, cut short by Ctrl-C (true when it was).
pub fn sleep_unless_interrupted(d: Duration) -> bool {
    let end = std::time::Instant::now() + d;
    loop {
        if INTERRUPT.load(Ordering::SeqCst) {
            return true;
        }
        let left = end.saturating_duration_since(std::time::Instant::now());
        if left.is_zero() {
            return false;
        }
        std::thread::sleep(left.min(trol::POLL));
    }
}

/// Set when a write to stdout failed (the reader went away).
static STDOUT_CLOSED: AtomicBool = AtomicBool::new(false);

/// The writer of a serving process's log: lines go through a bounded queue to a thread that
/// writes them, so serving never waits for a reader of stdout ([`log_in_background`]).
struct Background {
    tx: std::sync::mpsc::SyncSender<String>,
    done: std::sync::mpsc::Receiver<()>,
}

static BACKGROUND: std::sync::Mutex<Option<Background>> = std::sync::Mutex::new(None);
/// Lines dropped because the queue was full (stdout not read), not yet reported.
static DROPPED: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
/// How many log lines may wait for stdout.
const LOG_QUEUE: usize = 4096;

/// From now on, [`say`] never blocks: for `trol sim` and `trol gateway`, whose log must not
/// stop them serving (a Halt included) when nobody reads their stdout. Lines that find the
/// queue full are dropped, counted, and the count is logged once there is room again.
pub fn log_in_background() {
    let mut slot = BACKGROUND.lock().unwrap_or_else(|e| e.into_inner());
    if slot.is_some() {
        return;
    }
    let (tx, rx) = std::sync::mpsc::sync_channel::<String>(LOG_QUEUE);
    let (done_tx, done) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in rx {
            write_line(&line);
        }
        let _ = done_tx.send(());
    });
    *slot = Some(Background { tx, done });
}

/// Write out what the background log still holds, waiting at most a second (stdout may not
/// be read at all); nothing when the log is not in the background.
pub fn finish_log() {
    let taken = BACKGROUND.lock().unwrap_or_else(|e| e.into_inner()).take();
    if let Some(Background { tx, done }) = taken {
        drop(tx);
        let _ = done.recv_timeout(Duration::from_secs(1));
    }
}

fn write_line(line: &str) {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    if writeln!(out, "{line}").and_then(|()| out.flush()).is_err() {
        STDOUT_CLOSED.store(true, Ordering::SeqCst);
    }
}

/// One line to stdout (the [`say!`] macro); a closed stdout is noted, not a panic. In a
/// serving process ([`log_in_background`]) it never blocks.
pub fn say(line: std::fmt::Arguments) {
    use std::sync::mpsc::TrySendError;
    {
        let slot = BACKGROUND.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(bg) = slot.as_ref() {
            let dropped = DROPPED.load(Ordering::SeqCst);
            if dropped > 0 {
                let note = format!(
                    "({dropped} log line(s) dropped: standard output was not read; serving went on)"
                );
                match bg.tx.try_send(note) {
                    Ok(()) => {
                        DROPPED.fetch_sub(dropped, Ordering::SeqCst);
                    }
                    Err(_) => {
                        DROPPED.fetch_add(1, Ordering::SeqCst);
                        return;
                    }
                }
            }
            if let Err(TrySendError::Full(_) | TrySendError::Disconnected(_)) =
                bg.tx.try_send(line.to_string())
            {
                DROPPED.fetch_add(1, Ordering::SeqCst);
            }
            return;
        }
    }
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    if writeln!(out, "{line}").and_then(|()| out.flush()).is_err() {
        STDOUT_CLOSED.store(true, Ordering::SeqCst);
    }
}

/// A line to standard error; a failed write (nobody reads it) is dropped, never a panic.
/// On a terminal it is wrapped at word boundaries to the width ([`wrapped`]); to a pipe or a
/// file it goes whole, for the program that reads it (a test harness may set $COLUMNS).
pub fn tell(line: std::fmt::Arguments) {
    use std::io::{IsTerminal, Write};
    let err = std::io::stderr();
    let width = if err.is_terminal() {
        wrap_width(true, || {
            terminal_size::terminal_size_of(std::io::stderr()).map(|(w, _)| usize::from(w.0))
        })
    } else {
        None
    };
    let text = wrapped(&line.to_string(), width);
    let mut err = err.lock();
    let _ = writeln!(err, "{text}").and_then(|()| err.flush());
}

/// The width messages to a terminal are wrapped to: $COLUMNS where it is set (as clap takes
/// it for `--help`), else the terminal's (`terminal`); None (whole lines) for a stream that
/// is no terminal.
pub fn wrap_width(is_terminal: bool, terminal: impl FnOnce() -> Option<usize>) -> Option<usize> {
    let columns = std::env::var("COLUMNS")
        .ok()
        .and_then(|v| v.trim().parse::<usize>().ok());
    if !is_terminal {
        return None;
    }
    columns.or_else(terminal).map(|w| w.clamp(20, 500))
}

/// `text` with each line longer than `width` broken at word boundaries, its continuation
/// indented two more than the line (`hint: ...` goes on under its text); unchanged without a
/// width.
pub fn wrapped(text: &str, width: Option<usize>) -> String {
    let Some(width) = width else {
        return text.to_string();
    };
    text.split('\n')
        .map(|line| {
            if line.chars().count() <= width {
                return line.to_string();
            }
            let indent: String = line.chars().take_while(|c| *c == ' ').collect();
            let more = format!("{indent}  ");
            // Between words only: a path or a command stays whole.
            let options = textwrap::Options::new(width)
                .subsequent_indent(&more)
                .word_separator(textwrap::WordSeparator::AsciiSpace)
                .word_splitter(textwrap::WordSplitter::NoHyphenation)
                .break_words(false);
            textwrap::fill(line, options)
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Whether nobody reads stdout any more: the demo and the interpreter then halt the arm and
/// stop, rather than move it unwatched; the simulator goes on serving.
pub fn stdout_closed() -> bool {
    STDOUT_CLOSED.load(Ordering::SeqCst)
}

/// `trol config`: the configuration in use, each value with where it came from.
pub fn show_config(conn: &Conn) -> Result<(), String> {
    use trol::config::ConfigSource;
    let (cfg, source) = conn.config_with_source()?;
    let file_text = match &source {
        ConfigSource::Named(p) | ConfigSource::Found(p) => std::fs::read_to_string(p).ok(),
        ConfigSource::Defaults => None,
    };
    let file = match &source {
        ConfigSource::Named(p) => format!(
            "{} (named by --config or ${})",
            p.display(),
            trol::config::ENV_VAR
        ),
        ConfigSource::Found(p) => format!("{} (in the current folder)", p.display()),
        ConfigSource::Defaults => "none: no trol.cfg here and no $TROL_CONFIG".to_string(),
    };
    crate::say!("file: {file}");
    // The first three entries are the file's whenever there is one; a key counts as the
    // file's when a line sets it.
    let in_file = |keys: &[&str]| {
        file_text.as_deref().is_some_and(|t| {
            t.lines().any(|l| {
                let l = l.trim();
                keys.iter().any(|k| {
                    l.strip_prefix(k)
                        .is_some_and(|rest| rest.trim_start().starts_with('='))
                })
            })
        })
    };
    let from = |flag: bool, file: bool| -> String {
        if flag {
            "the command line"
        } else if file {
            "trol.cfg"
        } else {
            "default"
        }
        .to_string()
    };
    let has_file = file_text.is_some();
    let tool: Vec<String> = cfg.tool.iter().map(|v| format!("{v}")).collect();
    let shown = |p: &Option<PathBuf>| {
        p.as_ref()
            .map_or("none".into(), |p| p.display().to_string())
    };
    // The line speed the port is opened at: a real controller's profile sets it there, not
    // trol.cfg's `baud`.
    let cfg_baud = from(conn.baud.is_some(), has_file);
    let (baud, baud_from) = match trol::Connect::config(&cfg).line_speed() {
        Ok(Some((b, source))) if source == "trol.cfg's baud" => (b.to_string(), cfg_baud),
        Ok(Some((b, source))) => (
            b.to_string(),
            format!(
                "{source}; `baud` {} ({cfg_baud}) is not used on this port",
                cfg.baud
            ),
        ),
        Ok(None) => (
            "none".to_string(),
            "the embedded simulator has no line".to_string(),
        ),
        Err(e) => ("unknown".to_string(), format!("{e}")),
    };
    let rows: Vec<(&str, String, String)> = vec![
        (
            "port",
            cfg.port.clone(),
            from(conn.port.is_some(), has_file),
        ),
        ("baud", baud, baud_from),
        ("tool", tool.join(" "), from(false, has_file)),
        (
            "check",
            cfg.block_check().word().to_ascii_lowercase(),
            from(false, in_file(&["check"])),
        ),
        (
            "time_scale",
            cfg.time_scale.to_string(),
            from(
                conn.time_scale.is_some(),
                in_file(&["time_scale", "time-scale"]),
            ),
        ),
        (
            "locations",
            shown(&cfg.locations),
            from(false, in_file(&["locations"])),
        ),
        (
            "objects",
            shown(&cfg.objects),
            from(false, in_file(&["objects"])),
        ),
        (
            "table_z",
            cfg.table_z.to_string(),
            from(false, in_file(&["table_z", "table-z"])),
        ),
        (
            "homed",
            if cfg.homed { "yes" } else { "no" }.into(),
            from(false, in_file(&["homed"])),
        ),
        (
            "object",
            cfg.object.map_or("none".into(), |w| format!("{w} mm")),
            from(false, in_file(&["object"])),
        ),
        (
            "rapl-profile",
            shown(&cfg.rapl_profile),
            from(false, in_file(&["rapl-profile", "rapl_profile"])),
        ),
        (
            "mars-profile",
            shown(&cfg.mars_profile),
            from(false, in_file(&["mars-profile", "mars_profile"])),
        ),
        (
            "c500c-profile",
            shown(&cfg.c500c_profile),
            from(false, in_file(&["c500c-profile", "c500c_profile"])),
        ),
    ];
    for (key, value, src) in rows {
        crate::say!("{key:<13} {value:<30} ({src})");
    }
    Ok(())
}

#[cfg(test)]
mod wrap_tests {
    use super::wrapped;

    #[test]
    fn long_lines_break_between_words_and_go_on_indented() {
        let text = "stdin:1: error: TROLHome failed: cannot open port '/dev/ttyUSB7': No such \
                    file or directory (docs/c500.md); one of error-bracketed, echo-off\n  \
                    hint: is the controller there?";
        let out = wrapped(text, Some(40));
        for line in out.lines() {
            assert!(line.chars().count() <= 40, "{line}");
        }
        // No word is cut: the words are the text's.
        let words = |t: &str| t.split_whitespace().map(str::to_string).collect::<Vec<_>>();
        assert_eq!(words(&out), words(text));
        assert!(out.lines().nth(1).unwrap().starts_with("  "), "{out}");
        // A short line, and no width, stay as they are.
        assert_eq!(wrapped("short", Some(40)), "short");
        assert_eq!(wrapped(text, None), text);
    }
}

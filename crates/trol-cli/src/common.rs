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
    /// The port, overriding trol.cfg: `sim` (the embedded simulator), a serial device
    /// (/dev/ttyUSB0, /dev/pts/3, COM1), socket://HOST:PORT or listen://HOST:PORT.
    #[arg(long, value_name = "PORT", global = true)]
    pub port: Option<String>,
    /// The baud rate, overriding trol.cfg.
    #[arg(long, value_name = "BAUD", global = true,
          value_parser = clap::value_parser!(u32).range(300..=4_000_000))]
    pub baud: Option<u32>,
    /// Port `sim`: run the simulation this many times faster than real time.
    #[arg(long, value_name = "N", global = true, value_parser = positive)]
    pub time_scale: Option<f64>,
}

/// A number greater than 0.
pub fn positive(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("`{s}` is not a number greater than 0")),
    }
}

impl Conn {
    /// trol.cfg with the flags applied. A missing default trol.cfg means the defaults (port
    /// `sim`); a missing file named by --config or $TROL_CONFIG is an error.
    pub fn config(&self) -> Result<Config, String> {
        let named = self
            .config
            .clone()
            .or_else(|| std::env::var_os(trol::config::ENV_VAR).map(PathBuf::from));
        let mut cfg = match &named {
            Some(path) => Config::from_file(path).map_err(|e| e.to_string())?,
            None => {
                let path = PathBuf::from(trol::config::FILE_NAME);
                if path.exists() {
                    Config::from_file(&path).map_err(|e| e.to_string())?
                } else {
                    Config::default()
                }
            }
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
        Ok(cfg)
    }

    /// Connect as the configuration says. On a real port the server must answer
    /// (InitTROL(1)).
    pub fn robot(&self) -> Result<(Robot, Config), String> {
        let cfg = self.config()?;
        let mut robot = Robot::from_config(&cfg).map_err(|e| e.to_string())?;
        // The embedded controller starts in server mode with the tool of trol.cfg.
        if cfg.port != "sim" {
            trol::check_server(&mut robot).map_err(|e| e.to_string())?;
        }
        tracing::info!(port = %cfg.port, baud = cfg.baud, "connected");
        Ok((robot, cfg))
    }
}

/// Logs to stderr: `RUST_LOG` if set, else warnings, and more with each `-v`.
pub fn init_logging(verbose: u8) {
    use tracing_subscriber::EnvFilter;
    let filter = if verbose > 0 {
        EnvFilter::new(match verbose {
            1 => "info",
            2 => "debug",
            _ => "trace",
        })
    } else {
        EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new("warn"))
    };
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
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
            eprintln!("\ninterrupted twice: quitting");
            std::process::exit(130);
        }
        eprintln!("\ninterrupted: halting the arm (Ctrl-C again quits)");
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

/// One line to stdout (the [`say!`] macro); a closed stdout is noted, not a panic.
pub fn say(line: std::fmt::Arguments) {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    if writeln!(out, "{line}").and_then(|()| out.flush()).is_err() {
        STDOUT_CLOSED.store(true, Ordering::SeqCst);
    }
}

/// Whether nobody reads stdout any more: the demo and the interpreter then halt the arm and
/// stop, rather than move it unwatched; the simulator goes on serving.
pub fn stdout_closed() -> bool {
    STDOUT_CLOSED.load(Ordering::SeqCst)
}

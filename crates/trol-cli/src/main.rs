//! `trol`: the TROL utilities in one binary (the manual's "Installation von TROL": inittrol,
//! cluptrol, interp, link, protest), plus the simulator, a tracer, benchmarks and a demo.

/// `println!` that does not panic when nobody reads stdout any more (`trol demo | head -1`):
/// the line is dropped and [`common::stdout_closed`] says so from then on.
macro_rules! say {
    ($($arg:tt)*) => {
        trol_cli::common::say(format_args!($($arg)*))
    };
}

/// `eprintln!` that never panics: a message to a standard error nobody reads any more (`trol
/// demo 2>&1 | head -3`) is dropped instead of ending the program with a panic. It shadows
/// std's macro in every module of the binary.
macro_rules! eprintln {
    ($($arg:tt)*) => {
        trol_cli::common::tell(format_args!($($arg)*))
    };
}

mod beside;
mod c500c;
mod demo;
mod gateway;
mod init;
mod interp;
mod link;
mod mars;
mod rapl;
mod sim;
mod trace;

use std::process::ExitCode;

use trol_cli::common;

use clap::{Parser, Subcommand};

/// TROL, the TU Vienna Robot Control Library: utilities for driving a CRS A465 on a C500 in
/// RAPL-II, on a PiKRON MARS 8, on a C500C, or simulated. Every command reads trol.cfg (or
/// $TROL_CONFIG) like any TROL program; --port, --baud and --config override it. Without
/// trol.cfg the port is `sim`, the embedded simulator.
#[derive(Parser)]
#[command(name = "trol", version, long_about = None, after_help = "\
Examples:
  trol demo                        # the manual's pick example, simulated
  trol interp                      # type TROL commands
  trol sim                         # a simulated controller on a new pty
  trol init --port /dev/pts/3      # activate the controller's TROL server
  trol interp pick.trol --port /dev/pts/3  # run a script against it
  trol cleanup --port /dev/pts/3   # end the server")]
struct Cli {
    /// More log output on stderr (-v info, -vv debug, -vvv trace); RUST_LOG also works.
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    verbose: u8,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// The command interpreter: one TROL API call per line, interactive or from a script.
    Interp(interp::InterpArgs),
    /// Activate the controller's TROL server with trol.cfg's tool transform (inittrol).
    #[command(after_help = "Example: trol init --port /dev/ttyUSB0 --baud 9600")]
    Init(common::Conn),
    /// End the controller's TROL server, back to terminal mode (cluptrol).
    #[command(after_help = "Example: trol cleanup --port /dev/ttyUSB0")]
    Cleanup(common::Conn),
    /// A simulated A465 as its own process: the TROL server (by default), or the twin of a
    /// C500 in RAPL-II (--rapl), a MARS 8 (--mars) or a C500C (--c500c).
    Sim(sim::SimArgs),
    /// TROL's controller side on this PC, driving a real C500 in RAPL-II (docs/c500.md), an
    /// A465 on a MARS 8 (docs/mars.md) or an A465 on its C500C (docs/c500c.md).
    Gateway(gateway::GatewayArgs),
    /// A real C500 in RAPL-II: first contact (probe) and a plain terminal (term).
    #[command(subcommand)]
    Rapl(rapl::Rapl),
    /// An A465 on a PiKRON MARS 8: first contact that only reads (docs/mars.md).
    #[command(subcommand)]
    Mars(mars::Mars),
    /// An A465 on its C500C: first contact that only reads (docs/c500c.md).
    #[command(subcommand)]
    C500c(c500c::C500c),
    /// Relay between the controller's port and an application's (the manual's link.exe).
    Link(link::LinkArgs),
    /// Show the traffic layer by layer, live between two ports or from a capture.
    #[command(subcommand)]
    Trace(trace::Trace),
    /// Show the configuration in use (trol.cfg or $TROL_CONFIG, the flags, the defaults),
    /// each value with where it came from.
    #[command(
        after_help = "Examples:\n  trol config\n  TROL_CONFIG=lab.cfg trol config --port /dev/ttyUSB0"
    )]
    Config(common::Conn),
    /// List the serial ports of this machine.
    Ports {
        /// The configuration file whose port to point out (default: $TROL_CONFIG, else
        /// ./trol.cfg).
        #[arg(long, value_name = "FILE")]
        config: Option<std::path::PathBuf>,
    },
    /// Measure: link throughput, transactions, inverse kinematics, faults, the view (runs
    /// the `trol-bench` program beside this one; `trol bench --help` lists the benchmarks).
    #[command(disable_help_flag = true)]
    Bench {
        /// The benchmark and its arguments, as `trol-bench` takes them.
        #[arg(
            trailing_var_arg = true,
            allow_hyphen_values = true,
            value_name = "ARGS"
        )]
        args: Vec<std::ffi::OsString>,
    },
    /// The arm as a ROS 2 node: joint_states, robot_description, the services home and halt
    /// (runs the `trol-ros2` program beside this one; `trol ros2 --help` says more;
    /// docs/ros2.md).
    #[command(disable_help_flag = true)]
    Ros2 {
        /// Its arguments, as `trol-ros2` takes them.
        #[arg(
            trailing_var_arg = true,
            allow_hyphen_values = true,
            value_name = "ARGS"
        )]
        args: Vec<std::ffi::OsString>,
    },
    /// The manual's pick example on the embedded simulator, step by step.
    Demo(demo::DemoArgs),
    /// Print the A465's URDF (links base_link, link_1..link_6, flange, tool0; joints
    /// joint_1..joint_6 with TROL's zero and directions), generated from the arm's model.
    #[command(
        after_help = "Examples:\n  trol urdf > crs_a465.urdf         # for RViz and description packages\n  trol urdf --srdf > crs_a465.srdf  # for MoveIt, beside it (docs/ros2.md)"
    )]
    Urdf {
        /// Print the SRDF for MoveIt instead (the arm's group, READY, and the pairs of
        /// links joined by a joint, which it need not check).
        #[arg(long)]
        srdf: bool,
    },
    /// Print the completion script for a shell (bash, zsh, fish, elvish, powershell).
    #[command(after_help = "\
Examples:
  trol completions bash > ~/.local/share/bash-completion/completions/trol
  # zsh, with fpath+=(~/.zfunc) in ~/.zshrc:
  trol completions zsh > ~/.zfunc/_trol
  trol completions fish > ~/.config/fish/completions/trol.fish")]
    Completions {
        /// The shell.
        shell: clap_complete::Shell,
    },
    /// Write the man pages (trol.1, and trol-SUBCOMMAND.1 for each subcommand) into a folder.
    #[command(after_help = "\
Example:
  trol man --out target/man && man -l target/man/trol.1")]
    Man {
        /// The folder to write them into (made if missing).
        #[arg(long, default_value = ".")]
        out: std::path::PathBuf,
    },
}

fn completions(shell: clap_complete::Shell) -> Result<(), String> {
    let mut cmd = cli_command();
    let mut out = Vec::new();
    clap_complete::generate(shell, &mut cmd, "trol", &mut out);
    say!("{}", String::from_utf8_lossy(&out).trim_end());
    Ok(())
}

fn man(out: &std::path::Path) -> Result<(), String> {
    std::fs::create_dir_all(out).map_err(|e| format!("cannot make {}: {e}", out.display()))?;
    clap_mangen::generate_to(cli_command(), out)
        .map_err(|e| format!("cannot write the man pages into {}: {e}", out.display()))?;
    say!(
        "man pages written to {} (read one with: man -l {}/trol.1)",
        out.display(),
        out.display()
    );
    Ok(())
}

fn ports(config: Option<std::path::PathBuf>) -> Result<(), String> {
    // The port trol.cfg names, pointed out in the list (or named after it).
    let (cfg, source) = common::config_file(config)?;
    let configured = match source {
        trol::config::ConfigSource::Defaults => None,
        found => Some((cfg.port, cfg.baud, found)),
    };
    let list = trol_port::serial::list().map_err(|e| format!("cannot list the ports: {e}"))?;
    if list.is_empty() {
        say!(
            "no serial ports found (a USB adapter shows up as /dev/ttyUSB0 or COMn once \
             plugged in; `trol sim` makes a pty to try things with)"
        );
    }
    let mut named = false;
    for (name, what) in list {
        let mark = match &configured {
            Some((port, baud, source)) if *port == name => {
                named = true;
                format!("  <- {source} names it (baud {baud})")
            }
            _ => String::new(),
        };
        say!("{name:<24} {what}{mark}");
    }
    if let Some((port, baud, source)) = configured.filter(|_| !named) {
        say!("{source} names port {port} (baud {baud})");
    }
    Ok(())
}

/// The command line's definition, as every surface (parsing, completions, man pages) sees
/// it: a value may be a negative number everywhere (`--linger -1` is then refused by the
/// value's own check, which says what it takes, rather than read as an unknown flag).
fn cli_command() -> clap::Command {
    fn negative_numbers(cmd: clap::Command) -> clap::Command {
        cmd.allow_negative_numbers(true)
            .mut_subcommands(negative_numbers)
    }
    use clap::CommandFactory;
    negative_numbers(Cli::command())
}

fn main() -> ExitCode {
    use clap::FromArgMatches;
    let cli = match Cli::from_arg_matches(&cli_command().get_matches()) {
        Ok(cli) => cli,
        Err(e) => e.exit(),
    };
    common::init_logging(cli.verbose);
    let result = match cli.command {
        Command::Interp(a) => interp::run(a),
        Command::Init(c) => init::init(&c).map(|()| ExitCode::SUCCESS),
        Command::Cleanup(c) => init::cleanup(&c).map(|()| ExitCode::SUCCESS),
        Command::Sim(a) => sim::run(a).map(|()| ExitCode::SUCCESS),
        Command::Link(a) => link::run(a).map(|()| ExitCode::SUCCESS),
        Command::Gateway(a) => gateway::run(a).map(|()| ExitCode::SUCCESS),
        Command::Rapl(r) => rapl::run(r).map(|()| ExitCode::SUCCESS),
        Command::Mars(m) => mars::run(m).map(|()| ExitCode::SUCCESS),
        Command::C500c(c) => c500c::run(c).map(|()| ExitCode::SUCCESS),
        Command::Trace(t) => trace::run(t).map(|()| ExitCode::SUCCESS),
        Command::Ports { config } => ports(config).map(|()| ExitCode::SUCCESS),
        Command::Config(c) => common::show_config(&c).map(|()| ExitCode::SUCCESS),
        Command::Bench { args } => beside::run("trol-bench", "the benchmarks", &args),
        Command::Ros2 { args } => beside::run("trol-ros2", "the ROS 2 node", &args),
        Command::Demo(a) => demo::run(a),
        Command::Urdf { srdf } => {
            let text = if srdf {
                trol_a465::urdf::srdf()
            } else {
                trol_a465::urdf::urdf()
            };
            say!("{}", text.trim_end());
            Ok(ExitCode::SUCCESS)
        }
        Command::Completions { shell } => completions(shell).map(|()| ExitCode::SUCCESS),
        Command::Man { out } => man(&out).map(|()| ExitCode::SUCCESS),
    };
    // What a serving process's log still holds goes out before it ends.
    common::finish_log();
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("trol: {e}");
            ExitCode::FAILURE
        }
    }
}

//! `trol bench ARGS` and `trol ros2 ARGS`: the benchmarks and the ROS 2 node live in their own
//! programs, `trol-bench` (crates/trol-bench) and `trol-ros2` (crates/trol-ros2), so that this
//! binary carries none of their code (nor DDS); this runs one with the same arguments, from
//! beside this program or else from the PATH.

use std::ffi::OsString;
use std::path::PathBuf;
use std::process::{Command, ExitCode};

/// Where program `name` is: beside this program, else wherever the PATH finds it.
fn program(name: &str) -> PathBuf {
    let name = format!("{name}{}", std::env::consts::EXE_SUFFIX);
    match std::env::current_exe() {
        Ok(me) if me.with_file_name(&name).is_file() => me.with_file_name(&name),
        _ => PathBuf::from(name),
    }
}

/// Run program `name` (`trol-bench`, `trol-ros2`; `what` says what it holds) with `args`,
/// and end as it ends.
pub fn run(name: &str, what: &str, args: &[OsString]) -> Result<ExitCode, String> {
    let path = program(name);
    let mut cmd = Command::new(&path);
    cmd.args(args);
    let missing = |e: std::io::Error| {
        format!(
            "cannot run {} ({e}): {what} is its own program; build it with `cargo build \
             --release -p {name}` (or `cargo install --locked --path crates/{name}`)",
            path.display()
        )
    };
    #[cfg(unix)]
    {
        use std::os::unix::process::CommandExt;
        // Only returns when the program could not be started.
        Err(missing(cmd.exec()))
    }
    #[cfg(not(unix))]
    {
        let status = cmd.status().map_err(missing)?;
        Ok(ExitCode::from(
            status.code().map_or(1, |c| u8::try_from(c).unwrap_or(1)),
        ))
    }
}

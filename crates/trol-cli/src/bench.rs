//! `trol bench ARGS`: the benchmarks live in their own program, `trol-bench` (crates/
//! trol-bench), so that this binary carries none of their code; this runs it with the same
//! arguments, from beside this program or else from the PATH.

use std::ffi::OsString;
use std::path::PathBuf;
use std::process::{Command, ExitCode};

/// Where `trol-bench` is: beside this program, else wherever the PATH finds it.
fn program() -> PathBuf {
    let name = format!("trol-bench{}", std::env::consts::EXE_SUFFIX);
    match std::env::current_exe() {
        Ok(me) if me.with_file_name(&name).is_file() => me.with_file_name(&name),
        _ => PathBuf::from(name),
    }
}

/// Run `trol-bench ARGS` and end as it ends.
pub fn run(args: &[OsString]) -> Result<ExitCode, String> {
    let bench = program();
    let mut cmd = Command::new(&bench);
    cmd.args(args);
    let missing = |e: std::io::Error| {
        format!(
            "cannot run {} ({e}): the benchmarks are their own program; build it with `cargo \
             build --release -p trol-bench` (or `cargo install --path crates/trol-bench`)",
            bench.display()
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

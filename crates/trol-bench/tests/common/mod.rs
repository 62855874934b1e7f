//! Helpers of the tests of the built `trol-bench` binary.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

pub const BENCH: &str = env!("CARGO_BIN_EXE_trol-bench");

/// A scratch folder of this call's own, without a trol.cfg (so the port is `sim`).
pub fn scratch(name: &str) -> PathBuf {
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir =
        std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("trol-bench-{name}-{n}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Run `trol-bench ARGS` in `dir`.
pub fn bench(dir: &Path, args: &[&str]) -> Output {
    Command::new(BENCH)
        .args(args)
        .current_dir(dir)
        .env_remove("TROL_CONFIG")
        .env_remove("RUST_LOG")
        .stdin(Stdio::null())
        .output()
        .expect("start trol-bench")
}

pub fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// The JSON a benchmark printed, after checking that it succeeded.
pub fn json(dir: &Path, args: &[&str]) -> serde_json::Value {
    let o = bench(dir, args);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{args:?}: {out}\n{err}");
    serde_json::from_str(&out).unwrap_or_else(|e| panic!("{args:?}: {e}: {out}"))
}

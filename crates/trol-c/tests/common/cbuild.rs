//! Building C programs against libtrol in tests (shared by the tests of `trol` and
//! `trol-cli` through `#[path]`).

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// The repository's root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The folder cargo puts libtrol and the examples in (target/debug for `cargo test`).
pub fn lib_dir() -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    // target/<profile>/deps/TEST-HASH
    exe.parent().unwrap().parent().unwrap().to_path_buf()
}

/// `cargo test` builds the trol crate as a Rust library only; build libtrol.a and .so, and
/// the guide's example programs (`extending_controller`, `extending_client`), once, with the
/// same cargo and profile.
///
/// It builds every library and example of the workspace, as `scripts/test.sh` does after
/// `cargo test --workspace --no-run`: with dev-dependencies in play for the whole workspace,
/// cargo resolves each crate's features as the test build did and finds it all up to date.
/// (`-p trol-c -p trol` alone resolved bitflags without `std`, and rebuilt serialport and
/// every TROL crate above it: 46 s in the middle of the tests.) It builds no program, so it
/// never puts another `trol` in place while a test starts it.
pub fn build_libtrol() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
        let mut cmd = Command::new(cargo);
        cmd.args([
            "build",
            "--workspace",
            "--lib",
            "--examples",
            "--manifest-path",
        ])
        .arg(root().join("Cargo.toml"));
        if lib_dir().ends_with("release") {
            cmd.arg("--release");
        }
        let status = cmd.status().expect("run cargo to build libtrol");
        assert!(status.success(), "building libtrol failed");
    });
}

/// How a program links libtrol.
#[derive(Clone, Copy, Debug)]
pub enum Link {
    /// libtrol.a, linked in.
    Static,
    /// libtrol.so, found at run time through LD_LIBRARY_PATH.
    Shared,
}

/// Compile `source` into a program in the temporary folder; returns its path.
pub fn compile(source: &Path, name: &str, link: Link) -> PathBuf {
    // Once per name and link in this process, under a lock: parallel tests that run the same
    // program must not rewrite it while another runs it (ETXTBSY).
    static BUILT: std::sync::Mutex<Vec<(String, PathBuf)>> = std::sync::Mutex::new(Vec::new());
    let key = format!("{}|{name}|{link:?}", source.display());
    let mut built = BUILT.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, out)) = built.iter().find(|(k, _)| *k == key) {
        return out.clone();
    }
    let out = compile_now(source, name, link);
    built.push((key, out.clone()));
    out
}

fn compile_now(source: &Path, name: &str, link: Link) -> PathBuf {
    build_libtrol();
    let lib = lib_dir();
    let out =
        std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("trol-{name}-{link:?}"));
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let mut cmd = Command::new(&cc);
    cmd.arg(source)
        .arg("-I")
        .arg(root().join("include"))
        .arg("-Wall")
        // The manual passes string literals as TLocName (unsigned char): let that be.
        .arg("-Wno-pointer-sign")
        .arg("-Werror=implicit-function-declaration")
        .arg("-o")
        .arg(&out);
    match link {
        Link::Static => {
            cmd.arg(lib.join("libtrol.a"));
        }
        Link::Shared => {
            cmd.arg("-L").arg(&lib).arg("-ltrol");
        }
    }
    let status = cmd
        .args(["-lpthread", "-ldl", "-lm"])
        .status()
        .expect("run the C compiler (cc); install gcc or set CC");
    assert!(status.success(), "{} did not compile", source.display());
    out
}

/// A command that runs a compiled program, finding libtrol.so.
pub fn program(path: &Path) -> Command {
    let mut cmd = Command::new(path);
    // Every notice at every start (as before notices were said once per port): a test's
    // output does not depend on what an earlier run left in the cache folder.
    cmd.env("LD_LIBRARY_PATH", lib_dir())
        .env_remove("TROL_CONFIG")
        .env("TROL_VERBOSE", "1");
    cmd
}

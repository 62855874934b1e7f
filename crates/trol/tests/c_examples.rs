//! The C examples (examples/*.c), built with the system's C compiler against libtrol and
//! run against the embedded controller (examples/trol.cfg: port `sim`).

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The folder cargo put libtrol.a in (target/debug for `cargo test`).
fn lib_dir() -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    // target/<profile>/deps/c_examples-HASH
    exe.parent().unwrap().parent().unwrap().to_path_buf()
}

/// `cargo test` builds the trol crate as a Rust library only; build libtrol.a (and .so) too,
/// once, with the same cargo and profile (a no-op when it is up to date).
fn build_libtrol() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
        let mut cmd = Command::new(cargo);
        cmd.args(["build", "-p", "trol", "--lib", "--manifest-path"])
            .arg(root().join("Cargo.toml"));
        if lib_dir().ends_with("release") {
            cmd.arg("--release");
        }
        let status = cmd.status().expect("run cargo to build libtrol");
        assert!(status.success(), "building libtrol failed");
    });
}

fn build_and_run(name: &str) -> String {
    build_libtrol();
    let root = root();
    let lib = lib_dir();
    assert!(
        lib.join("libtrol.a").exists(),
        "libtrol.a not in {}; cargo builds it with the trol crate",
        lib.display()
    );
    let out = std::env::temp_dir().join(format!("trol-{name}-{}", std::process::id()));
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let status = Command::new(&cc)
        .arg(root.join("examples").join(format!("{name}.c")))
        .arg("-I")
        .arg(root.join("include"))
        .arg("-Wall")
        // The manual passes string literals as TLocName (unsigned char): let that be.
        .arg("-Wno-pointer-sign")
        .arg("-Werror=implicit-function-declaration")
        .arg("-o")
        .arg(&out)
        // Static, so the test needs no library path at run time.
        .arg(lib.join("libtrol.a"))
        .args(["-lpthread", "-ldl", "-lm"])
        .status()
        .expect("run the C compiler (cc); install gcc or set CC");
    assert!(status.success(), "{name}.c did not compile");
    let run = Command::new(&out)
        .current_dir(root.join("examples"))
        .env_remove("TROL_CONFIG")
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout).into_owned();
    let _ = std::fs::remove_file(&out);
    assert!(
        run.status.success(),
        "{name} failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&run.stderr)
    );
    stdout
}

#[test]
fn the_pick_example_runs_every_step_with_success() {
    let out = build_and_run("pick");
    for step in [
        "TROLAppro(test_001, -90, 1)",
        "TROLMove(test_001, 1)",
        "TROLClose(60)",
        "TROLDepart(&loc, 1)",
    ] {
        let line = out
            .lines()
            .find(|l| l.starts_with(step))
            .unwrap_or_else(|| panic!("{step} missing:\n{out}"));
        assert!(line.ends_with("-> 0"), "{line}");
    }
    assert!(out.contains("pick: done"));
}

#[test]
fn the_position_example_reads_all_forms_and_the_status() {
    let out = build_and_run("position");
    assert!(
        out.contains("GetStatus: BIOS called 1, returned 0"),
        "{out}"
    );
    assert!(
        out.contains("TROLMove(nowhere) -> -32102; GetStatus: BIOS called 0, reason -32102"),
        "{out}"
    );
    assert!(out.contains("position: done"));
}

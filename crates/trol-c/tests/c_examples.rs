//! The C examples (examples/*.c), built with the system's C compiler against libtrol and
//! run against the embedded controller (examples/trol.cfg: port `sim`).

mod common;

use common::cbuild::{Link, compile, program, root};

fn build_and_run(name: &str) -> String {
    let root = root();
    let out = compile(
        &root.join("examples").join(format!("{name}.c")),
        name,
        Link::Static,
    );
    let run = program(&out)
        .current_dir(root.join("examples"))
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout).into_owned();
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

/// scripts/install-c.sh puts libtrol, trol.h and trol.pc under a prefix, and a program
/// builds with `cc app.c $(pkg-config --cflags --libs trol)` and runs.
#[test]
fn the_installed_library_builds_a_program_through_pkg_config() {
    common::cbuild::build_libtrol();
    let root = root();
    let prefix = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("trol-prefix");
    let _ = std::fs::remove_dir_all(&prefix);
    let install = std::process::Command::new("bash")
        .arg(root.join("scripts/install-c.sh"))
        .arg("--prefix")
        .arg(&prefix)
        .env("TROL_LIB_DIR", common::cbuild::lib_dir())
        .output()
        .unwrap();
    assert!(
        install.status.success(),
        "{}",
        String::from_utf8_lossy(&install.stderr)
    );
    for f in [
        "lib/libtrol.so",
        "lib/libtrol.a",
        "include/trol.h",
        "lib/pkgconfig/trol.pc",
    ] {
        assert!(prefix.join(f).exists(), "{f} not installed");
    }
    let exe = prefix.join("position");
    let build = std::process::Command::new("sh")
        .arg("-c")
        .arg(format!(
            "cc {} -Wno-pointer-sign -o {} $(pkg-config --cflags --libs trol)",
            root.join("examples/position.c").display(),
            exe.display()
        ))
        .env("PKG_CONFIG_PATH", prefix.join("lib/pkgconfig"))
        .output()
        .unwrap();
    assert!(
        build.status.success(),
        "{}",
        String::from_utf8_lossy(&build.stderr)
    );
    let run = std::process::Command::new(&exe)
        .current_dir(root.join("examples"))
        .env("LD_LIBRARY_PATH", prefix.join("lib"))
        .env_remove("TROL_CONFIG")
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success() && out.contains("position: done"),
        "{out}"
    );
    let _ = std::fs::remove_dir_all(&prefix);
}

/// libtrol is the client with its backends and the C API, and no live view: none of the
/// view's page or three.js is in it (the utilities serve the view; issue 24).
#[test]
fn libtrol_carries_no_view() {
    common::cbuild::build_libtrol();
    for lib in ["libtrol.so", "libtrol.a"] {
        let bytes = std::fs::read(common::cbuild::lib_dir().join(lib)).unwrap();
        for needle in [
            &b"OrbitControls"[..],
            b"three.module.js",
            b"<!doctype html>",
        ] {
            assert!(
                !bytes.windows(needle.len()).any(|w| w == needle),
                "{lib} carries {}",
                String::from_utf8_lossy(needle)
            );
        }
    }
}

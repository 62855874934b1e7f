//! A 1998 TROL program, unchanged, driving a C500 in RAPL-II: the C examples against
//! `trol sim --rapl` over a pty pair, in-process (`rapl:PTY` in trol.cfg) and through
//! `trol gateway`; `trol init` and `trol cleanup` against the gateway; Halt while the
//! application waits for the motion to end.

#[path = "../../trol/tests/common/cbuild.rs"]
mod cbuild;
mod common;

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use common::{Background, scratch, text, trol};

/// `trol sim --rapl` on a new pty, with the examples' locations, and its profile in `dir`.
fn rapl_sim(dir: &Path, extra: &[&str]) -> Background {
    let root = cbuild::root();
    let locations = root.join("examples/locations.txt");
    let out = trol(dir, &["sim", "--rapl", "--print-profile"], "");
    std::fs::write(dir.join("c500.toml"), &out.stdout).unwrap();
    let mut args = vec!["sim", "--rapl", "--locations", locations.to_str().unwrap()];
    args.extend_from_slice(extra);
    Background::start(dir, &args, "serving on ")
}

fn run_example(name: &str, dir: &Path) -> String {
    let exe = cbuild::compile(
        &cbuild::root().join("examples").join(format!("{name}.c")),
        &format!("{name}-rapl"),
        cbuild::Link::Static,
    );
    let run = cbuild::program(&exe).current_dir(dir).output().unwrap();
    let out = String::from_utf8_lossy(&run.stdout).into_owned();
    assert!(
        run.status.success(),
        "{name}:\n{out}\n{}",
        String::from_utf8_lossy(&run.stderr)
    );
    out
}

fn check_pick(out: &str) {
    for step in [
        "TROLHome(0)",
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
    assert!(out.contains("pick: done"), "{out}");
}

#[test]
fn the_c_examples_run_unchanged_in_process_through_rapl_pty() {
    let dir = scratch("rapl-inproc");
    let sim = rapl_sim(&dir, &["--time-scale", "20"]);
    std::fs::write(
        dir.join("trol.cfg"),
        format!(
            "9600\nrapl:{}\n0 0 0 0 0 0\nrapl-profile = c500.toml\n",
            sim.name
        ),
    )
    .unwrap();
    check_pick(&run_example("pick", &dir));
    let out = run_example("position", &dir);
    assert!(
        out.contains("TROLMove(nowhere) -> -32102; GetStatus: BIOS called 0, reason -32102"),
        "{out}"
    );
    assert!(out.contains("position: done"), "{out}");
    // What the C500 was told, in RAPL-II.
    let said = sim.output().join("\n");
    assert!(said.contains("MOVES TEST_001"), "{said}");
    assert!(said.contains("LISTL NOWHERE"), "{said}");
}

#[test]
fn the_pick_example_runs_through_trol_gateway_with_init_and_cleanup() {
    let dir = scratch("rapl-gateway");
    let sim = rapl_sim(&dir, &["--time-scale", "20"]);
    let gw = Background::start(
        &dir,
        &[
            "gateway",
            "--controller",
            &sim.name,
            "--profile",
            "c500.toml",
        ],
        "serving on ",
    );
    let init = trol(&dir, &["init", "--port", &gw.name], "");
    let (o, e) = text(&init);
    assert!(init.status.success(), "{o}{e}");
    std::fs::write(
        dir.join("trol.cfg"),
        format!("9600\n{}\n0 0 0 0 0 0\n", gw.name),
    )
    .unwrap();
    check_pick(&run_example("pick", &dir));
    // CleanupTROL ended the server (manual); init and cleanup again, as against trol sim.
    let init = trol(&dir, &["init", "--port", &gw.name], "");
    let (o, e) = text(&init);
    assert!(init.status.success(), "{o}{e}");
    let cleanup = trol(&dir, &["cleanup", "--port", &gw.name], "");
    let (o, e) = text(&cleanup);
    let log = gw.output().join("\n");
    assert!(cleanup.status.success(), "{o}{e}\ngateway:\n{log}");
    assert_eq!(log.matches("back in terminal mode").count(), 2, "{log}");
}

#[test]
fn halt_reaches_the_arm_while_the_application_waits_for_the_motion() {
    let dir = scratch("rapl-halt");
    // Real time: the motion takes seconds.
    let sim = rapl_sim(&dir, &["--homed"]);
    let profile = trol_rapl::Profile::from_file(&dir.join("c500.toml")).unwrap();
    let mut robot = trol::Robot::rapl(&sim.name, profile, Default::default()).unwrap();
    robot.joint(1, 2.5).unwrap();
    let halt = AtomicBool::new(false);
    let waited = std::thread::scope(|s| {
        s.spawn(|| {
            std::thread::sleep(Duration::from_millis(500));
            halt.store(true, Ordering::Relaxed);
        });
        robot.finish_unless(&halt).unwrap()
    });
    assert_eq!(waited, trol::Waited::Halted);
    robot.finish().unwrap();
    let q = robot
        .position(trol::Tag::Joint, trol::PosMode::Actual)
        .unwrap();
    let j1 = q.to_array6()[0];
    assert!(j1 > 0.01 && j1 < 2.4, "halted on the way: joint 1 at {j1}");
    let said = sim.output().join("\n");
    assert!(said.contains("HALT"), "{said}");
}

//! A host written from the 1998 manual alone (tests/manual_host/manual_host.py: bytes built
//! by hand from the manual's chapter on the protocol, the bare `PCP TROL`, the LRC, PCI 0,
//! requests not numbered) drives every controller TROL serves as the manual's controller
//! did: `trol sim`, and `trol gateway` in front of a simulated C500 (motions of 1-2 s, real
//! time) and a simulated MARS 8. Its program sends relative motions back to back without
//! Finish between them, as 1998 programs do (issue 38): each is accepted, runs after the
//! one before, and the arm ends where their sum puts it.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::{Background, scratch, trol};

fn script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/manual_host/manual_host.py")
}

/// Run the manual's host against `port`; its output.
fn manual_host(port: &str) -> String {
    let out = Command::new("python3")
        .arg(script())
        .arg(port)
        .output()
        .expect("python3 runs the manual's host");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "the manual's host failed:\n{text}");
    // The script checks that the arm ends where Home left it plus the four Joints.
    assert!(text.contains("10 passed, 0 failed"), "{text}");
    text
}

#[test]
fn a_host_written_from_the_manual_moves_the_arm_of_trol_sim() {
    let dir = scratch("manual-host-sim");
    let sim = Background::start(&dir, &["sim", "--time-scale", "5"], "serving on ");
    let out = manual_host(&sim.name);
    assert!(out.contains("TROLJoint(3, 0.6) -> 0"), "{out}");
    let log = sim.output_until("TROLGetPosition", 1, 30).join("\n");
    assert!(
        log.contains("activated: serving TROL (LRC block check, the manual's record sizes)"),
        "{log}"
    );
    assert!(!log.contains("may have run"), "{log}");
    assert!(!log.contains("ROBOT_UNSURE"), "{log}");
}

#[test]
fn a_host_written_from_the_manual_queues_motions_on_a_c500_through_the_gateway() {
    let dir = scratch("manual-host-rapl");
    let out = trol(&dir, &["sim", "--rapl", "--print-profile"], "");
    std::fs::write(dir.join("c500.toml"), &out.stdout).unwrap();
    // Real time: each motion takes a second or two, far longer than the calls.
    let sim = Background::start(&dir, &["sim", "--rapl"], "serving on ");
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
    manual_host(&gw.name);
    let log = gw
        .output_until("waits for the motion under way", 2, 30)
        .join("\n");
    assert!(
        log.matches("waits for the motion under way").count() >= 2,
        "the motions were sent while others ran: {log}"
    );
}

#[test]
fn a_host_written_from_the_manual_queues_motions_on_a_mars_8_through_the_gateway() {
    let dir = scratch("manual-host-mars");
    let out = trol(&dir, &["sim", "--mars", "--print-profile"], "");
    std::fs::write(dir.join("mars.toml"), &out.stdout).unwrap();
    let sim = Background::start(&dir, &["sim", "--mars", "--time-scale", "5"], "serving on ");
    let controller = format!("mars:{}", sim.name);
    let gw = Background::start(
        &dir,
        &[
            "gateway",
            "--controller",
            &controller,
            "--profile",
            "mars.toml",
        ],
        "serving on ",
    );
    manual_host(&gw.name);
}

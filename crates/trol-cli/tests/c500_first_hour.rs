//! docs/c500.md's first hour with a real arm, run as written against the simulated C500
//! (issue 37, item 8): the page's `trol` commands for steps 3 to 5, in the page's order, with
//! DEVICE replaced by the simulator's pty and the operator's part played by the test (poses
//! by pendant, Enter, `HOME`, `yes`); then step 6's trol.cfg and interpreter session. A page
//! whose steps need a file the step before did not write, or an option the tool does not
//! take, fails here.

mod common;

use std::path::Path;

use common::{Background, probe_with_poses, scratch, text, trol};

/// The backticked `trol ...` commands of the page's first hour that name the controller,
/// whitespace made single.
fn first_hour_commands() -> Vec<String> {
    let page =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/c500.md"))
            .unwrap();
    let start = page
        .find("## The first hour with a real arm")
        .expect("the first hour's section");
    let rest = &page[start + 3..];
    let section = &rest[..rest.find("\n## ").unwrap_or(rest.len())];
    section
        .split('`')
        .skip(1)
        .step_by(2)
        .map(|s| s.split_whitespace().collect::<Vec<_>>().join(" "))
        .filter(|s| s.starts_with("trol ") && s.contains("DEVICE"))
        .collect()
}

#[test]
fn the_first_hour_runs_as_written_against_the_simulated_c500() {
    let dir = scratch("c500-first-hour");
    // Real time: the supervised steps tell a motion's answer at its start from one at its
    // end by the arm's own time.
    let mut sim = Background::start(
        &dir,
        &["sim", "--rapl", "--pendant", "--homed"],
        "serving on ",
    );
    let device = sim.name.clone();
    let commands = first_hour_commands();
    assert!(commands.len() >= 4, "the page's commands: {commands:?}");
    let mut written = Vec::new();
    for command in &commands {
        let args: Vec<String> = command
            .split(' ')
            .skip(1)
            .map(|a| a.replace("DEVICE", &device))
            .collect();
        // Every file a step reads, a step before wrote.
        for w in args.windows(2) {
            if w[0] == "--profile" {
                assert!(
                    written.contains(&w[1]),
                    "`{command}` reads {} before a step wrote it",
                    w[1]
                );
            }
            if w[0] == "--profile-out" {
                written.push(w[1].clone());
            }
        }
        let argv: Vec<&str> = args.iter().map(String::as_str).collect();
        if let Some(i) = args.iter().position(|a| a == "--poses") {
            let n: usize = args[i + 1].parse().unwrap();
            let poses = [
                "10 20 40 30 50 -20",
                "-35 5 70 -60 30 45",
                "60 -15 30 15 -40 100",
                "20 30 60 -30 -60 10",
            ];
            assert!(n <= poses.len(), "{command}");
            let out = probe_with_poses(&dir, &args, &mut sim, &poses[..n]);
            assert!(out.contains("profile written to"), "{command}:\n{out}");
        } else if args.first().map(String::as_str) == Some("rapl") && args[1] == "term" {
            // Step 5's homing by hand: HOME typed in the terminal.
            let run = trol(&dir, &argv, "HOME\n");
            let (o, e) = text(&run);
            assert!(run.status.success(), "{command}:\n{o}\n{e}");
        } else if args.contains(&"--home-pose".to_string()) {
            // The arm where HOME left it, at its marks: yes.
            let run = trol(&dir, &argv, "yes\n");
            let (o, e) = text(&run);
            assert!(run.status.success(), "{command}:\n{o}\n{e}");
            assert!(o.contains("home_joints = ["), "{command}:\n{o}");
            // Then the operator brings the arm into free space by pendant, the tool not
            // pointing up.
            sim.type_line("10 20 40 30 -50 -20");
            sim.wait_for("pendant: at", 120);
        } else if args.contains(&"--measure".to_string()) {
            let run = trol(&dir, &argv, "yes\n");
            let (o, e) = text(&run);
            assert!(run.status.success(), "{command}:\n{o}\n{e}");
            assert!(o.contains("measured: "), "{command}:\n{o}");
        } else {
            let run = trol(&dir, &argv, "");
            let (o, e) = text(&run);
            assert!(run.status.success(), "{command}:\n{o}\n{e}");
        }
    }
    // What the steps settled, in the last file, which step 6 uses.
    let last = written.last().expect("a profile written").clone();
    assert_eq!(last, "c500.toml", "step 6 uses c500.toml");
    let p = trol_rapl::Profile::from_file(&dir.join(&last)).unwrap();
    assert!(!p.simulated);
    assert_eq!(p.angles, "yaw pitch roll");
    assert_eq!(p.joint_units, "degrees");
    assert_eq!(p.jog_frame, "world");
    assert_eq!(p.halt, trol_rapl::profile::Halt::Halt);
    // Where HOME left the simulated arm: every joint 0, to the encoders' dither.
    let home = p.home_joints.expect("home_joints recorded");
    assert!(home.iter().all(|v| v.abs() < 0.01), "{home:?}");
    // Step 6: the first supervised moves through TROL.
    std::fs::write(
        dir.join("trol.cfg"),
        format!("9600\nrapl:{device}\n0 0 0 0 0 0\nrapl-profile = c500.toml\n"),
    )
    .unwrap();
    let run = trol(
        &dir,
        &["interp", "-v"],
        "speed 5\nhome 0\nfinish\nhere p1\njoint 6 0.2\nfinish\nmove p1\nfinish\n\
         joint 6 1.0\nhalt\nfinish\n",
    );
    let (o, e) = text(&run);
    assert!(run.status.success(), "step 6:\n{o}\n{e}");
}

//! The utilities' own surfaces: help, completions and man pages, logs and verbosity,
//! outputs nobody reads, trol.cfg read alike by every subcommand.

use super::*;

#[test]
pub(super) fn subcommands_have_help_with_examples() {
    let dir = scratch("helps");
    for sub in [
        // `bench` runs another program: trol_bench_runs_the_benchmark_program.
        "interp", "init", "cleanup", "sim", "link", "trace", "ports", "demo", "gateway", "config",
        "rapl", "urdf",
    ] {
        let o = trol(&dir, &[sub, "--help"], "");
        let (out, _) = text(&o);
        assert!(o.status.success(), "{sub}");
        assert!(out.contains("Usage: trol"), "{sub}: {out}");
        if !["trace", "ports", "rapl"].contains(&sub) {
            assert!(
                out.contains("Example"),
                "{sub} --help has no example:\n{out}"
            );
        }
    }
}

#[test]
pub(super) fn ports_lists_or_says_there_are_none() {
    let dir = scratch("ports");
    let o = trol(&dir, &["ports"], "");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    assert!(!out.trim().is_empty());
}

#[test]
pub(super) fn completions_and_man_pages_come_from_the_cli_definition() {
    let dir = scratch("completions");
    for shell in ["bash", "zsh", "fish"] {
        let o = trol(&dir, &["completions", shell], "");
        let (out, err) = text(&o);
        assert!(o.status.success(), "{shell}: {err}");
        for sub in ["interp", "gateway", "rapl", "bench", "ros2"] {
            assert!(out.contains(sub), "{shell} completion lacks {sub}");
        }
    }
    // The bash script is valid bash.
    let o = trol(&dir, &["completions", "bash"], "");
    std::fs::write(dir.join("trol.bash"), &o.stdout).unwrap();
    let check = std::process::Command::new("bash")
        .arg("-n")
        .arg(dir.join("trol.bash"))
        .output()
        .unwrap();
    assert!(check.status.success(), "{:?}", text(&check));

    let o = trol(&dir, &["man", "--out", "man"], "");
    assert!(o.status.success(), "{:?}", text(&o));
    for page in ["trol.1", "trol-interp.1", "trol-rapl-probe.1", "trol-sim.1"] {
        let roff = std::fs::read_to_string(dir.join("man").join(page)).unwrap();
        assert!(roff.contains(".TH"), "{page}");
    }
    let interp = std::fs::read_to_string(dir.join("man/trol-interp.1")).unwrap();
    assert!(interp.contains("command interpreter"), "{interp}");
}

/// One behaviour for a missing trol.cfg, in every surface: the embedded simulator, and a
/// note on stderr, once. A file $TROL_CONFIG names must exist; a bad one is reported once,
/// before any command.
#[test]
pub(super) fn a_missing_trol_cfg_means_the_simulator_everywhere_and_a_bad_one_stops_before_any_command()
 {
    let dir = scratch("no-cfg");
    let note = "no trol.cfg here and no TROL_CONFIG: using the defaults, port `sim`";
    let o = trol(&dir, &["interp"], "speed 50\nspeed 60\n");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert_eq!(err.matches(note).count(), 1, "{err}");
    assert!(out.contains("speed 60"), "{out}");

    // The same from C: a program without trol.cfg runs against the simulator.
    let exe = cbuild::compile(
        &cbuild::root().join("examples/position.c"),
        "position-no-cfg",
        cbuild::Link::Static,
    );
    let run = cbuild::program(&exe)
        .current_dir(&dir)
        .env_remove("TROL_CONFIG")
        .output()
        .unwrap();
    let (out, err) = text(&run);
    assert!(run.status.success(), "{out}\n{err}");
    assert!(out.contains("position: done"), "{out}");
    assert_eq!(err.matches(note).count(), 1, "{err}");

    // A file TROL_CONFIG names that does not exist is an error, also with no command.
    let o = std::process::Command::new(common::TROL)
        .arg("interp")
        .current_dir(&dir)
        .env("TROL_CONFIG", dir.join("nonexistent.cfg"))
        .stdin(std::process::Stdio::null())
        .output()
        .unwrap();
    let (_, err) = text(&o);
    assert!(!o.status.success(), "{err}");
    assert!(err.contains("nonexistent.cfg: cannot read it"), "{err}");

    // A bad trol.cfg: said once, with file, line and the expected form; no command ran.
    std::fs::write(dir.join("trol.cfg"), "fast\nsim\n0 0 0 0 0 0\n").unwrap();
    let o = trol(&dir, &["interp", "-k"], "speed 50\nspeed 60\nspeed 70\n");
    let (out, err) = text(&o);
    assert!(!o.status.success());
    assert_eq!(err.matches("trol.cfg:1:").count(), 1, "{err}");
    assert!(!out.contains("speed"), "{out}");

    // `trol config` says where each value came from.
    std::fs::write(
        dir.join("trol.cfg"),
        "38400\nsim\n0 0 0 0 0 0\ntime_scale = 5\n",
    )
    .unwrap();
    let o = trol(&dir, &["config", "--port", "socket://127.0.0.1:9"], "");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    assert!(out.contains("file: trol.cfg"), "{out}");
    let row = |key: &str| {
        out.lines()
            .find(|l| l.starts_with(key))
            .unwrap_or_else(|| panic!("{key}: {out}"))
            .to_string()
    };
    assert!(row("baud").contains("38400") && row("baud").ends_with("(trol.cfg)"));
    assert!(
        row("port").contains("socket://127.0.0.1:9") && row("port").ends_with("(the command line)")
    );
    assert!(row("time_scale").ends_with("(trol.cfg)"));
    assert!(row("check").ends_with("(default)"));

    // On a real controller's port the profile sets the line speed, and `trol config` says
    // so, with every profile key (issue 68, item 2).
    let profiles = [
        ("mars:", "mars-profile", "19200", "the MARS 8 profile"),
        (
            "c500c:",
            "c500c-profile",
            "57600",
            "the default C500C profile",
        ),
        (
            "rapl:",
            "rapl-profile",
            "38400",
            "the default RAPL-II profile",
        ),
    ];
    let crs93 = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../trol-mars/profiles/crs93.toml")
        .canonicalize()
        .unwrap();
    for (prefix, key, baud, source) in profiles {
        let extra = if prefix == "mars:" {
            format!("mars-profile = {}\n", crs93.display())
        } else {
            String::new()
        };
        std::fs::write(
            dir.join("trol.cfg"),
            format!("9600\n{prefix}/dev/ttyUSB0\n0 0 0 0 0 0\n{extra}"),
        )
        .unwrap();
        let o = trol(&dir, &["config"], "");
        let (out, err) = text(&o);
        assert!(o.status.success(), "{err}");
        let baud_row = out.lines().find(|l| l.starts_with("baud")).unwrap();
        assert!(baud_row.contains(baud), "{prefix}: {out}");
        assert!(baud_row.contains(source), "{prefix}: {out}");
        assert!(
            baud_row.contains("`baud` 9600 (trol.cfg) is not used on this port"),
            "{prefix}: {out}"
        );
        for k in ["rapl-profile", "mars-profile", "c500c-profile"] {
            let r = out.lines().find(|l| l.starts_with(k)).unwrap();
            if k == key && prefix == "mars:" {
                assert!(
                    r.contains("crs93.toml") && r.ends_with("(trol.cfg)"),
                    "{out}"
                );
            } else {
                assert!(r.contains("none"), "{k}: {out}");
            }
        }
    }
    // The embedded simulator has no line.
    std::fs::write(dir.join("trol.cfg"), "9600\nsim\n0 0 0 0 0 0\n").unwrap();
    let o = trol(&dir, &["config"], "");
    let (out, _) = text(&o);
    assert!(
        out.lines()
            .any(|l| l.starts_with("baud") && l.contains("the embedded simulator has no line")),
        "{out}"
    );
}

#[test]
pub(super) fn each_v_gives_more_detail_and_logs_have_no_colour_in_a_pipe() {
    let dir = scratch("verbose");
    let run = |flag: &str| {
        let o = trol(&dir, &[flag, "interp", "--port", "sim"], "speed 50\n");
        assert!(o.status.success(), "{:?}", text(&o));
        text(&o).1
    };
    let v = run("-v");
    let vv = run("-vv");
    let vvv = run("-vvv");
    assert!(!v.contains("request TROLSpeed 50"), "{v}");
    assert!(
        vv.contains("request TROLSpeed 50") && vv.contains("reply 0 (success)"),
        "{vv}"
    );
    assert!(!vv.contains("sent ["), "{vv}");
    assert!(
        vvv.contains("sent [") && vvv.contains("received ["),
        "{vvv}"
    );
    for log in [&v, &vv, &vvv] {
        assert!(!log.contains('\u{1b}'), "colour codes in a pipe: {log:?}");
    }
}

#[test]
pub(super) fn help_wraps_at_word_boundaries() {
    let dir = scratch("help-wrap");
    let o = trol(&dir, &["interp"], "help\n");
    let (out, _) = text(&o);
    assert!(o.status.success());
    for line in out.lines() {
        assert!(
            line.chars().count() <= 80,
            "longer than 80 columns: {line:?}"
        );
    }
    // Nothing is cut inside a word: the words of a command's help are all there.
    let flat = out.split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(
        flat.contains(
            "approach a given location (cartesian or precision point), displaced in its tool frame"
        ),
        "{out}"
    );
}

/// `trol demo | head -1` and `trol sim --server | head -1`: no panic; the demo halts the arm
/// and stops, the simulator goes on serving its client.
#[test]
pub(super) fn a_closed_stdout_is_no_panic() {
    use std::io::BufRead;
    let dir = scratch("closed-stdout");
    let first_line_then_close = |args: &[&str]| {
        let mut child = std::process::Command::new(common::TROL)
            .args(args)
            .current_dir(&dir)
            .env_remove("TROL_CONFIG")
            .stdin(std::process::Stdio::null())
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let mut first = String::new();
        std::io::BufReader::new(child.stdout.take().unwrap())
            .read_line(&mut first)
            .unwrap();
        (child, first)
    };
    let (demo, first) = first_line_then_close(&["demo", "--time-scale", "50"]);
    assert!(first.starts_with("trol demo:"), "{first}");
    let o = demo.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.contains("stdout closed"), "{err}");

    let (mut sim, first) = first_line_then_close(&[
        "sim",
        "--port",
        "listen://127.0.0.1:0",
        "--server",
        "--homed",
    ]);
    let port = first
        .split_whitespace()
        .find(|w| w.starts_with("socket://"))
        .unwrap_or_else(|| panic!("no address in {first:?}"))
        .to_string();
    // Each call is logged on the closed stdout; the simulator serves them all.
    let o = trol(
        &dir,
        &["interp", "--port", &port],
        "getstatus\njoint 1 0.1\nfinish wait\ngetstatus\n",
    );
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert!(
        sim.try_wait().unwrap().is_none(),
        "the simulator ended: {:?}",
        sim.wait_with_output()
    );
    sim.kill().unwrap();
    let o = sim.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
pub(super) fn trol_sim_keeps_serving_when_nobody_reads_its_log() {
    use std::io::BufRead;
    let dir = scratch("sim-unread-log");
    let mut child = std::process::Command::new(common::TROL)
        .args(["sim", "--port", "pty", "--server", "--time-scale", "20"])
        .current_dir(&dir)
        .env_remove("TROL_CONFIG")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let mut out = std::io::BufReader::new(child.stdout.take().unwrap());
    let name = loop {
        let mut line = String::new();
        assert!(out.read_line(&mut line).unwrap() > 0, "trol sim ended");
        if let Some(rest) = line.trim().strip_prefix("trol sim: serving on ") {
            break rest.split_whitespace().next().unwrap().to_string();
        }
    };
    // From here on nobody reads: the pipe (64 KiB) and the log queue (4096 lines) hold
    // fewer lines than the calls log.
    let mut robot = trol::Robot::connect(&name, 9600).unwrap();
    for i in 0..7000u32 {
        robot
            .speed(10 + (i % 90) as u16)
            .unwrap_or_else(|e| panic!("call {i}: {e}"));
    }
    // Reading again: the queued lines come, and the count of those dropped.
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in out.lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
    let mut said = Vec::new();
    while std::time::Instant::now() < deadline {
        robot.speed(50).unwrap();
        while let Ok(line) = rx.recv_timeout(std::time::Duration::from_millis(20)) {
            said.push(line);
        }
        if said.iter().any(|l| l.contains("log line(s) dropped")) {
            break;
        }
    }
    let _ = child.kill();
    let _ = child.wait();
    assert!(
        said.iter()
            .any(|l| l.contains("log line(s) dropped: standard output was not read")),
        "{:?}",
        said.last()
    );
}

#[test]
pub(super) fn an_output_nobody_reads_any_more_ends_the_demo_without_a_panic() {
    // `trol demo 2>&1 | head -3`: both streams into one pipe whose reader goes away.
    let dir = scratch("closed-output");
    let (reader, writer) = std::io::pipe().unwrap();
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_trol"))
        .arg("demo")
        .current_dir(&dir)
        .stdin(std::process::Stdio::null())
        .stdout(writer.try_clone().unwrap())
        .stderr(writer)
        .spawn()
        .unwrap();
    let mut first = String::new();
    std::io::BufRead::read_line(&mut std::io::BufReader::new(&reader), &mut first).unwrap();
    drop(reader);
    let status = child.wait().unwrap();
    // 1: it stopped (and halted the arm) because nobody reads; 101 would be a panic.
    assert_eq!(status.code(), Some(1), "{first}");
}

/// `trol sim` and `trol ports` read trol.cfg as every subcommand does: the simulator's
/// settings come from it unless a flag says otherwise, and `--config` names another file.
#[test]
pub(super) fn sim_and_ports_read_trol_cfg_like_every_subcommand() {
    let dir = scratch("sim-config");
    std::fs::write(dir.join("locs.txt"), "p1 400 0 300 0 1.5707963 0\n").unwrap();
    std::fs::write(
        dir.join("lab.cfg"),
        "9600\n/dev/ttyUSB7\n0 0 0 0 0 0\ntime_scale = 20\ntable_z = -5\nlocations = locs.txt\n",
    )
    .unwrap();
    let sim = Background::start(
        &dir,
        &[
            "sim",
            "--config",
            "lab.cfg",
            "--port",
            "listen://127.0.0.1:0",
            "--table-z",
            "-7",
        ],
        "serving on ",
    );
    let lines = sim.wait_for("activate it with", 10).join("\n");
    assert!(
        lines.contains("time scale 20, table at z = -7 mm, 1 location(s)"),
        "{lines}"
    );
    assert!(lines.contains("from lab.cfg"), "{lines}");
    let o = trol(&dir, &["ports", "--config", "lab.cfg"], "");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    assert!(out.contains("/dev/ttyUSB7 (baud 9600)"), "{out}");
    // Without a trol.cfg: no note on either stream (--mars --print-profile prints and
    // exits), and nothing about trol.cfg while serving.
    let bare = scratch("sim-no-config");
    let o = trol(&bare, &["sim", "--mars", "--print-profile"], "");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    assert!(
        !err.contains("trol.cfg") && !out.contains("trol.cfg"),
        "{out}\n{err}"
    );
    let sim = Background::start(
        &bare,
        &["sim", "--port", "listen://127.0.0.1:0"],
        "serving on ",
    );
    let lines = sim.wait_for("activate it with", 10);
    assert!(!lines.join("\n").contains("trol.cfg"), "{lines:?}");
}

#[test]
pub(super) fn trol_urdf_prints_the_arm_with_trols_joints() {
    let dir = scratch("urdf");
    let o = trol(&dir, &["urdf"], "");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    assert!(out.starts_with("<?xml"), "{out}");
    for name in ["joint_1", "joint_6", "base_link", "flange", "tool0"] {
        assert!(out.contains(&format!("name=\"{name}\"")), "{name}");
    }
}

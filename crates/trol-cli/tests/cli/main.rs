//! The built `trol` binary, each subcommand, and the utilities working together across
//! processes over pseudo-terminals and TCP.

#[path = "../common/mod.rs"]
mod common;

use std::time::{Duration, Instant};

use common::{Background, scratch, text, trol};

mod interp;

use interp::SCRIPT;
mod restarts;
mod surfaces;

#[test]
fn demo_runs_to_the_end_and_every_step_succeeds() {
    let dir = scratch("demo");
    let o = trol(&dir, &["demo", "--time-scale", "50"], "");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    let steps: Vec<&str> = out
        .lines()
        .filter(|l| l.contains(" -> ") && !l.trim_start().starts_with('('))
        .collect();
    assert_eq!(steps.len(), 11, "{out}");
    for s in &steps {
        assert!(s.contains("-> 0 (success)"), "{s}");
    }
    assert!(out.contains("all 11 steps succeeded"), "{out}");
    // The arm ends 90 mm above test_001 (400, 0, 150), printed to the micrometre (trailing
    // zeros left out) without -0.
    let last: Vec<&str> = steps.last().unwrap().split_whitespace().collect();
    let at = last.iter().position(|w| *w == "x").expect("x");
    assert_eq!(
        &last[at..at + 7],
        ["x", "400", "y", "0", "z", "240", "mm"],
        "{out}"
    );
    // It says that motion commands return before the motion ends, shows the arm moving,
    // and where the cube it picked up ended: in the gripper, its centre 90 mm above test_001
    // (the world gives an object's base: 15 mm lower).
    assert!(out.contains("motion commands return as soon as"), "{out}");
    assert!(
        out.contains("(0.1 s later, the program not waiting)"),
        "{out}"
    );
    let world = out
        .lines()
        .filter(|l| l.starts_with("trol demo: cube at"))
        .collect::<Vec<_>>()
        .join("\n");
    assert!(
        common::object_is(
            &world,
            "cube",
            [Some(400.0), None, Some(225.0)],
            "in the gripper"
        ),
        "{out}"
    );
}

/// Build `package`'s program (once per test binary, `once`), so that `trol` finds it beside
/// itself; where `scripts/test.sh` built every program of the workspace before its tests
/// (`TROL_TEST_BUILT=1`), nothing. There `cargo build -p trol-ros2` would resolve features
/// for that package alone, build it again (about 30 s) and put it in place while another
/// test may start it.
fn build_once(once: &'static std::sync::Once, package: &str) {
    once.call_once(|| {
        if std::env::var_os("TROL_TEST_BUILT").is_some_and(|v| v == "1") {
            return;
        }
        let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
        let manifest = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../Cargo.toml");
        let status = std::process::Command::new(cargo)
            .args(["build", "-p", package, "--manifest-path"])
            .arg(manifest)
            .status()
            .expect("run cargo");
        assert!(status.success(), "building {package} failed");
    });
}

/// `trol bench ARGS` runs `trol-bench` from beside `trol`, with the same arguments, and ends
/// as it ends.
#[test]
fn trol_bench_runs_the_benchmark_program() {
    static BUILT: std::sync::Once = std::sync::Once::new();
    build_once(&BUILT, "trol-bench");
    let dir = scratch("bench");
    let o = trol(&dir, &["bench", "--help"], "");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    assert!(out.contains("all ") && out.contains("faults"), "{out}");
    let o = trol(&dir, &["bench", "ik", "--poses", "200", "--json"], "");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["poses"], 200);
    // A wrong argument is trol-bench's error, and its exit status.
    let o = trol(&dir, &["bench", "ik", "--poses", "many"], "");
    assert!(!o.status.success());
    assert!(text(&o).1.contains("many"), "{:?}", text(&o));
}

/// `trol ros2 ARGS` runs `trol-ros2` from beside `trol` with the same arguments: its help,
/// and a namespace ROS 2 would refuse, refused before anything starts (tests/ros2 drives the
/// node itself against Cyclone DDS).
#[test]
fn trol_ros2_runs_the_ros2_node_program() {
    static BUILT: std::sync::Once = std::sync::Once::new();
    build_once(&BUILT, "trol-ros2");
    let dir = scratch("ros2");
    let o = trol(&dir, &["ros2", "--help"], "");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    assert!(
        out.contains("--namespace") && out.contains("joint_states"),
        "{out}"
    );
    let o = trol(&dir, &["ros2", "--namespace", "1arm"], "");
    assert!(!o.status.success());
    assert!(text(&o).1.contains("--namespace `1arm`"), "{:?}", text(&o));
}

#[test]
fn init_says_what_to_check_when_the_controller_does_not_answer() {
    let dir = scratch("silent");
    // A pty with nobody behind it.
    let (_master, slave, path) = trol_port::serial::SerialLine::pty_pair().unwrap();
    drop(slave);
    let o = trol(&dir, &["init", "--port", &path], "");
    let (_, err) = text(&o);
    assert!(!o.status.success());
    assert!(err.contains("did not answer"), "{err}");
    assert!(err.contains("baud rate"), "{err}");
    let o = trol(&dir, &["cleanup", "--port", &path], "");
    let (_, err) = text(&o);
    assert!(!o.status.success());
    assert!(err.contains("trol init"), "{err}");

    // Another program has the port open: the message names it. (It must not inherit this
    // test's end of the pty, so it closes every descriptor but the standard ones.)
    let holder = {
        use std::os::unix::process::CommandExt;
        unsafe extern "C" {
            fn close(fd: i32) -> i32;
        }
        let mut cmd = std::process::Command::new("sleep");
        cmd.arg("30").stdin(std::fs::File::open(&path).unwrap());
        // SAFETY: only close(2), async-signal-safe, between fork and exec.
        unsafe {
            cmd.pre_exec(|| {
                for fd in 3..1024 {
                    close(fd);
                }
                Ok(())
            });
        }
        cmd.spawn().unwrap()
    };
    let pid = holder.id();
    let o = trol(&dir, &["init", "--port", &path], "");
    let (_, err) = text(&o);
    let mut holder = holder;
    let _ = holder.kill();
    let _ = holder.wait();
    assert!(!o.status.success());
    assert!(
        err.contains(&format!("also open in process {pid} (sleep)")),
        "{err}"
    );
}

/// The whole chain across processes: `trol sim` on a pty, `trol init` on it, `trol link`
/// from that pty to TCP, a script through the link, `trol cleanup` through it too.
#[test]
fn sim_init_link_interp_cleanup_across_processes() {
    let dir = scratch("chain");
    std::fs::write(
        dir.join("locations.txt"),
        "test_001 400 0 150 0 1.5707963 0\n#park 0 0 0 0 0 0\n",
    )
    .unwrap();
    let sim = Background::start(
        &dir,
        &["sim", "--time-scale", "50", "--locations", "locations.txt"],
        "serving on ",
    );
    assert!(sim.name.starts_with("/dev/"), "{}", sim.name);
    // Before init the controller is in terminal mode: the interpreter finds no server.
    let o = trol(&dir, &["interp", "--port", &sim.name], "getstatus\n");
    assert!(!o.status.success());
    assert!(text(&o).1.contains("trol init"), "{}", text(&o).1);

    let o = trol(&dir, &["init", "--port", &sim.name], "");
    assert!(o.status.success(), "{:?}", text(&o));
    assert!(text(&o).0.contains("is active"));

    let link = Background::start(
        &dir,
        &["link", &sim.name, "listen://127.0.0.1:0", "--no-init"],
        "applications use ",
    );
    assert!(link.name.starts_with("socket://"), "{}", link.name);
    std::fs::write(dir.join("pick.trol"), SCRIPT).unwrap();
    let o = trol(&dir, &["interp", "pick.trol", "--port", &link.name], "");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert!(
        out.contains("getposition cart commanded  ->  c(400, "),
        "{out}"
    );
    // A second client after the first left: the link accepts it.
    let o = trol(
        &dir,
        &["interp", "--port", &link.name],
        "move #park\nfinish\ngetposition prec\n",
    );
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert!(
        out.contains("getposition prec  ->  p(0, 0, 0, 0, 0, 0)"),
        "{out}"
    );

    let o = trol(&dir, &["cleanup", "--port", &link.name], "");
    assert!(o.status.success(), "{:?}", text(&o));
    let log = sim.output_until("back in terminal mode", 1, 30).join("\n");
    assert!(log.contains("activated: serving TROL"), "{log}");
    assert!(log.contains("TROLHome 0 -> 0 (success)"), "{log}");
    assert!(log.contains("TROLTerminatePCP -> 0 (success)"), "{log}");
    assert!(log.contains("back in terminal mode"), "{log}");
}

/// `trol trace spy` between a simulator on TCP and an application, with a capture, then
/// `trol trace read` of the capture.
#[test]
fn trace_spies_on_a_session_and_reads_its_capture() {
    let dir = scratch("trace");
    let sim = Background::start(
        &dir,
        &[
            "sim",
            "--port",
            "listen://127.0.0.1:0",
            "--server",
            "--homed",
            "--time-scale",
            "50",
        ],
        "serving on ",
    );
    let spy = Background::start(
        &dir,
        &[
            "trace",
            "spy",
            &sim.name,
            "listen://127.0.0.1:0",
            "--capture",
            "run.cap",
        ],
        "application on ",
    );
    let o = trol(
        &dir,
        &["interp", "--port", &spy.name],
        "close 500\nhome 9\n",
    );
    // close 500 and home 9 are refused by the interpreter before anything is sent.
    assert!(!o.status.success());
    let o = trol(
        &dir,
        &["interp", "--port", &spy.name],
        "joint 1 0.5\nfinish\ngetposition joint\n",
    );
    assert!(o.status.success(), "{:?}", text(&o));
    // The spy prints as it relays: up to the last request, then its reply.
    let mut live = spy.output_until("TROLGetPosition", 1, 30);
    if !live
        .iter()
        .skip_while(|l| !l.contains("TROLGetPosition"))
        .any(|l| l.contains("REPLY   #"))
    {
        live.extend(spy.output_until("REPLY   #", 1, 30));
    }
    let live = live.join("\n");
    assert!(live.contains("PC  -> CTL  ENQ"), "{live}");
    assert!(live.contains("REQUEST #"), "{live}");
    assert!(live.contains("TROLJoint 1 0.5"), "{live}");
    assert!(live.contains("REPLY   #"), "{live}");
    drop(spy);
    let o = trol(&dir, &["trace", "read", "run.cap"], "");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    assert!(out.contains("HEADER #bytes"), "{out}");
    assert!(out.contains("BCC"), "{out}");
    assert!(out.contains("TROLGetPosition joint commanded"), "{out}");
    assert!(out.contains("j(0.5, 0, 0, 0, 0, 0)"), "{out}");
    assert!(out.contains("ms after the request"), "{out}");
    // A damaged capture is reported with its line.
    std::fs::write(dir.join("bad.cap"), "0.1 pc 99\nnonsense\n").unwrap();
    let o = trol(&dir, &["trace", "read", "bad.cap"], "");
    assert!(!o.status.success());
    assert!(text(&o).1.contains("bad.cap:2:"), "{:?}", text(&o));
}

/// `trol sim`'s options reach the arm: the table height refuses a move that the default
/// table allows; `--homed` allows motion without TROLHome.
#[test]
fn sim_options_set_the_table_and_the_homed_state() {
    let dir = scratch("simopts");
    let sim = Background::start(
        &dir,
        &[
            "sim",
            "--port",
            "listen://127.0.0.1:0",
            "--server",
            "--homed",
            "--time-scale",
            "50",
            "--table-z",
            "900",
        ],
        "serving on ",
    );
    // From READY (the tool tip at z 1041.4) down 200 mm: below a table at 900.
    let o = trol(
        &dir,
        &["interp", "--port", &sim.name],
        "jog (0 0 -100)\nfinish\njog (0 0 -100)\n",
    );
    let (out, err) = text(&o);
    assert!(
        out.contains("jog (0 0 -100)  ->  0 (success)"),
        "{out}\n{err}"
    );
    assert!(
        err.contains("<stdin>:3: error: TROLJog failed: -4 (BIOS_BELOW_TABLE)"),
        "{out}\n{err}"
    );
}

/// `trol sim --objects`: closing on an object picks it up, and the log says where it is.
#[test]
fn sim_objects_are_picked_up_and_the_log_says_where_they_are() {
    let dir = scratch("simobjects");
    std::fs::write(
        dir.join("objects.txt"),
        "; name x y z width\ncube 400 0 135 30\n",
    )
    .unwrap();
    let sim = Background::start(
        &dir,
        &[
            "sim",
            "--port",
            "listen://127.0.0.1:0",
            "--server",
            "--homed",
            "--time-scale",
            "50",
            "--objects",
            "objects.txt",
        ],
        "serving on ",
    );
    let o = trol(
        &dir,
        &["interp", "--port", &sim.name],
        "moveii c(400, 0, 300, 0, 1.5707963, 0)\nmoveii c(400, 0, 150, 0, 1.5707963, 0) straight\n\
         finish\nclose 60\nfinish\ndepart c(-90) straight\nfinish\nopen 50\nfinish\n",
    );
    assert!(o.status.success(), "{:?}", text(&o));
    let log = sim.output_until(" z 0 mm, resting", 1, 30).join("\n");
    // The world line after each step, to the arm's 0.001 mm.
    let worlds: Vec<&str> = log.lines().filter(|l| l.contains("world: ")).collect();
    assert!(
        log.contains("world: cube at x 400 y 0 z 135 mm, resting"),
        "{log}"
    );
    // Taken by its centre (15 mm above its base) at the tool centre point.
    assert!(
        worlds.iter().any(|l| common::object_is(
            l,
            "cube",
            [Some(400.0), None, Some(225.0)],
            "in the gripper"
        )),
        "{log}"
    );
    assert!(
        common::object_is(
            worlds.last().copied().unwrap_or(""),
            "cube",
            [Some(400.0), None, Some(0.0)],
            "resting"
        ),
        "{log}"
    );
}

/// `trol link` reads trol.cfg like every subcommand: the controller is activated with the
/// file's block check and tool transform, and an application with the same file works
/// through the link.
#[test]
fn link_activates_the_controller_as_trol_cfg_says() {
    let dir = scratch("link-cfg");
    std::fs::write(
        dir.join("trol.cfg"),
        "9600\nsim\n10 0 0 0 0 0\ncheck = lrc\n",
    )
    .unwrap();
    let sim = Background::start(&dir, &["sim", "--time-scale", "50"], "serving on ");
    let link = Background::start(
        &dir,
        &["link", &sim.name, "listen://0"],
        "applications use ",
    );
    let o = trol(&dir, &["interp", "--port", &link.name], "getstatus\n");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    let log = sim
        .output_until("TROLSetToolTransform c(10, 0, 0, 0, 0, 0) -> 0", 1, 30)
        .join("\n");
    assert!(
        log.contains("activated: serving TROL (LRC block check)"),
        "{log}"
    );
    assert!(
        log.contains("TROLSetToolTransform c(10, 0, 0, 0, 0, 0) -> 0"),
        "{log}"
    );
}

#[path = "../../../trol-c/tests/common/cbuild.rs"]
mod cbuild;

#[test]
fn a_block_check_mismatch_is_named_not_blamed_on_the_cable() {
    // A controller that checks blocks with the manual's LRC (as a 1998 one does) and a host
    // that asks for CRC-16 by name: every block is refused as damaged; the message says which
    // setting to change.
    let dir = scratch("check-mismatch");
    let sim = Background::start(&dir, &["sim", "--server", "--check", "lrc"], "serving on ");
    std::fs::write(
        dir.join("trol.cfg"),
        format!("9600\n{}\n0 0 0 0 0 0\ncheck = crc16\n", sim.name),
    )
    .unwrap();
    let o = trol(&dir, &["interp"], "ready\n");
    let (out, err) = text(&o);
    assert!(!o.status.success(), "{out}");
    assert!(err.contains("add `check = lrc` to trol.cfg"), "{err}");
    // The manual's 3-line trol.cfg names no check: the host falls back to the LRC the
    // controller takes, says so once, and works (a fresh controller: the first is still
    // riding out the refused blocks).
    let sim = Background::start(&dir, &["sim", "--server", "--check", "lrc"], "serving on ");
    std::fs::write(
        dir.join("trol.cfg"),
        format!("9600\n{}\n0 0 0 0 0 0\n", sim.name),
    )
    .unwrap();
    let o = trol(&dir, &["interp"], "home 0\nready\n");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert!(err.contains("takes the manual's LRC"), "{err}");
    assert_eq!(err.matches("note:").count(), 1, "{err}");
}

/// A controller that speaks only the manual's protocol (`trol sim --manual`: only the bare
/// `PCP TROL`, the LRC, GetStatus in 4 bytes, no memory of the last request, the added
/// commands unknown), with either PCI in its replies: `trol init`, the interpreter and the
/// 1998 C examples with the manual's 3-line trol.cfg work, with nothing configured, and
/// each says once what it found. One test per PCI, so that the two run side by side.
#[test]
fn a_1998_controller_runs_1998_programs_with_the_manuals_trol_cfg() {
    a_1998_controller("zero");
}

#[test]
fn a_1998_controller_that_echoes_the_pci_runs_1998_programs_with_the_manuals_trol_cfg() {
    a_1998_controller("echo");
}

fn a_1998_controller(pci: &str) {
    let root = cbuild::root();
    let locations = root.join("examples/locations.txt");
    {
        let dir = scratch(&format!("manual-{pci}"));
        let sim = Background::start(
            &dir,
            &[
                "sim",
                "--manual",
                pci,
                "--time-scale",
                "50",
                "--locations",
                locations.to_str().unwrap(),
            ],
            "serving on ",
        );
        std::fs::write(
            dir.join("trol.cfg"),
            format!("9600\n{}\n0 0 0 0 0 0\n", sim.name),
        )
        .unwrap();
        let o = trol(&dir, &["init"], "");
        let (out, err) = text(&o);
        assert!(o.status.success(), "{out}\n{err}");
        assert!(out.contains("speaks only the manual's protocol"), "{out}");
        assert!(out.contains("is active"), "{out}");

        let o = trol(
            &dir,
            &["interp"],
            "home 0\njoint 1 0.25\nfinish\ngetposition joint\ngetstatus\n",
        );
        let (out, err) = text(&o);
        assert!(o.status.success(), "{out}\n{err}");
        assert!(out.contains("j(0.25, "), "{out}");
        assert!(
            out.contains("(the manual's reply: no transaction, no epoch)"),
            "{out}"
        );
        assert_eq!(err.matches("speaks only the manual's").count(), 1, "{err}");

        for (name, done) in [("pick", "pick: done"), ("position", "position: done")] {
            // The manual's steps: inittrol, the application, whose CleanupTROL ends the
            // server.
            let o = trol(&dir, &["init"], "");
            assert!(o.status.success(), "{:?}", text(&o));
            let exe = cbuild::compile(
                &root.join("examples").join(format!("{name}.c")),
                &format!("{name}-1998-{pci}"),
                cbuild::Link::Static,
            );
            // The note once per port (a cache folder of this test's own), not at every
            // start of a 1998 program.
            let run = cbuild::program(&exe)
                .current_dir(&dir)
                .env_remove("TROL_CONFIG")
                .env_remove("TROL_VERBOSE")
                .env("XDG_CACHE_HOME", dir.join("cache"))
                .output()
                .unwrap();
            let (out, err) = text(&run);
            assert!(run.status.success(), "{name}: {out}\n{err}");
            assert!(out.contains(done), "{out}");
            assert_eq!(
                err.contains("InitTROL: note: the controller speaks only the manual's"),
                name == "pick",
                "{name}: {err}"
            );
        }
        let log = sim.output_until("TROLDepart", 1, 30).join("\n");
        assert!(
            log.contains("activated: serving TROL (LRC block check, the manual's record sizes)"),
            "{log}"
        );
        // Nothing the manual's server does not know was asked of it.
        for added in [
            "TROLGetVersion",
            "TROLGetCodes",
            "TROLSetWatchdog",
            "TROLGetGripper",
        ] {
            assert!(!log.contains(added), "{added}: {log}");
        }
    }
}

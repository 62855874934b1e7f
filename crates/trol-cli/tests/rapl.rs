//! A 1998 TROL program, unchanged, driving a C500 in RAPL-II: the C examples against
//! `trol sim --rapl` over a pty pair, in-process (`rapl:PTY` in trol.cfg) and through
//! `trol gateway`; `trol init` and `trol cleanup` against the gateway; Halt while the
//! application waits for the motion to end.

#[path = "../../trol-c/tests/common/cbuild.rs"]
mod cbuild;
mod common;

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use common::{Background, check_pick, scratch, text, trol, view_state_at};

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
    let (ok, out, err) = try_example(name, dir);
    assert!(ok, "{name}:\n{out}\n{err}");
    out
}

/// Run a C example in `dir`: whether it succeeded, its stdout and stderr.
fn try_example(name: &str, dir: &Path) -> (bool, String, String) {
    let exe = cbuild::compile(
        &cbuild::root().join("examples").join(format!("{name}.c")),
        &format!("{name}-rapl"),
        cbuild::Link::Static,
    );
    let run = cbuild::program(&exe).current_dir(dir).output().unwrap();
    (
        run.status.success(),
        String::from_utf8_lossy(&run.stdout).into_owned(),
        String::from_utf8_lossy(&run.stderr).into_owned(),
    )
}

/// The variants a 1998 program cannot run on in full: TROL must fail there, visibly.
const FAIL_SAFE: &[&str] = &["warning-then-ack", "no-echo"];

/// `trol sim --rapl --variant NAME` on a new pty, the profile that describes it in `dir`
/// (c500.toml), and a trol.cfg that drives it in-process through `rapl:`.
fn variant_sim(dir: &Path, variant: &str, extra: &[&str]) -> Background {
    let out = trol(
        dir,
        &["sim", "--rapl", "--variant", variant, "--print-profile"],
        "",
    );
    assert!(out.status.success(), "{}", text(&out).1);
    std::fs::write(dir.join("c500.toml"), &out.stdout).unwrap();
    let mut args = vec!["sim", "--rapl", "--variant", variant, "--time-scale", "20"];
    args.extend_from_slice(extra);
    let sim = Background::start(dir, &args, "serving on ");
    std::fs::write(
        dir.join("trol.cfg"),
        format!(
            "9600\nrapl:{}\n0 0 0 0 0 0\nrapl-profile = c500.toml\n",
            sim.name
        ),
    )
    .unwrap();
    sim
}

/// The pick and position examples, unchanged, through `rapl:` against one variant of the
/// simulated C500 with the profile that describes it: they run, or (where TROL cannot drive
/// such a controller safely) they fail and say so; never `pick: done` there.
fn c_examples_on_variant(variant: &str) {
    let dir = scratch(&format!("rapl-variant-{variant}"));
    let locations = cbuild::root().join("examples/locations.txt");
    let sim = variant_sim(&dir, variant, &["--locations", locations.to_str().unwrap()]);
    let (ok, out, err) = try_example("pick", &dir);
    if FAIL_SAFE.contains(&variant) {
        assert!(
            !ok && !out.contains("pick: done"),
            "{variant}:\n{out}\n{err}"
        );
        return;
    }
    assert!(
        ok,
        "{variant}:\n{out}\n{err}\nsimulated C500:\n{}",
        sim.output().join("\n")
    );
    check_pick(&out);
    let out = run_example("position", &dir);
    assert!(out.contains("position: done"), "{variant}: {out}");
}

macro_rules! c_examples_on_variants {
    ($($test:ident => $name:literal),* $(,)?) => {
        $(
            #[test]
            fn $test() {
                c_examples_on_variant($name);
            }
        )*

        #[test]
        fn the_c_examples_run_on_every_variant() {
            let tested = [$($name),*];
            for (name, _) in trol_rapl::c500::VARIANTS {
                assert!(tested.contains(name), "variant {name} has no C example run");
            }
        }
    };
}

c_examples_on_variants! {
    c_examples_default => "default",
    c_examples_colon_refusal => "colon-refusal",
    c_examples_stars_refusal => "stars-refusal",
    c_examples_no_period => "no-period",
    c_examples_ack_at_end => "ack-at-end",
    c_examples_done_lag => "done-lag",
    c_examples_estop_line => "estop-line",
    c_examples_warning_then_ack => "warning-then-ack",
    c_examples_no_ack => "no-ack",
    c_examples_ma_radians => "ma-radians",
    c_examples_inch => "inch",
    c_examples_world_offset => "world-offset",
    c_examples_pulses_g3000 => "pulses-g3000",
    c_examples_nul_after_digit => "nul-after-digit",
    c_examples_no_echo => "no-echo",
    c_examples_not_homed => "not-homed",
    c_examples_home_elsewhere => "home-elsewhere",
    c_examples_jog_tool => "jog-tool",
    c_examples_halt_ignored => "halt-ignored",
    c_examples_ctrl_c_cancels_line => "ctrl-c-cancels-line",
    c_examples_unstoppable => "unstoppable",
    c_examples_finish => "finish",
    c_examples_finish_trusted => "finish-trusted",
    c_examples_finish_at_once => "finish-at-once",
    c_examples_finish_refused => "finish-refused",
    c_examples_finish_deaf => "finish-deaf",
}

#[test]
fn in_process_rapl_logs_the_controller_s_texts() {
    // A refusal the controller words its own way reaches `-v`'s log, word for word.
    let dir = scratch("rapl-log");
    let _sim = variant_sim(&dir, "stars-refusal", &["--homed"]);
    let run = trol(&dir, &["interp", "-v", "-k"], "joint 1 3.3\n");
    let (out, err) = text(&run);
    assert!(err.contains("c500: "), "{out}\n{err}");
    assert!(err.contains("*** JOINT LIMIT ***"), "{out}\n{err}");
    // A form without a number maps to no code of its own: a refusal all the same.
    assert!(out.contains("-10 (BIOS_RAPL_ERROR)"), "{out}\n{err}");
}

#[test]
fn the_c_examples_run_unchanged_in_process_through_rapl_pty() {
    let dir = scratch("rapl-inproc");
    let locations = cbuild::root().join("examples/locations.txt");
    let sim = variant_sim(
        &dir,
        "default",
        &["--locations", locations.to_str().unwrap()],
    );
    check_pick(&run_example("pick", &dir));
    let out = run_example("position", &dir);
    assert!(
        out.contains("TROLMove(nowhere) -> -32102; GetStatus: BIOS called 0, reason -32102"),
        "{out}"
    );
    assert!(out.contains("position: done"), "{out}");
    // What the C500 was told, in RAPL-II.
    let said = sim.output_until("LISTL NOWHERE", 1, 30).join("\n");
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
    // A 1998 program's Close then Depart with no Finish between: the Depart waits for the
    // fingers and runs (issue 62, item 6: it was BIOS_BUSY).
    let run = trol(
        &dir,
        &["interp", "-k"],
        "close 60\ndepart c(-20)\nfinish\nopen 60\njoint 1 0.05\nfinish\n",
    );
    let (o, e) = text(&run);
    assert!(run.status.success(), "{o}{e}");
    assert!(!o.contains("BIOS_BUSY"), "{o}");
    let cleanup = trol(&dir, &["cleanup", "--port", &gw.name], "");
    let (o, e) = text(&cleanup);
    let log = gw.output_until("back in terminal mode", 2, 30).join("\n");
    assert!(cleanup.status.success(), "{o}{e}\ngateway:\n{log}");
    assert_eq!(log.matches("back in terminal mode").count(), 2, "{log}");
}

#[test]
fn halt_reaches_the_arm_while_the_application_waits_for_the_motion() {
    let dir = scratch("rapl-halt");
    // Real time: the motion takes seconds.
    let sim = rapl_sim(&dir, &["--homed"]);
    let profile = trol_rapl::Profile::from_file(&dir.join("c500.toml")).unwrap();
    let mut robot = trol::Connect::port(&format!("rapl:{}", sim.name))
        .rapl_profile(profile)
        .connect()
        .unwrap();
    // At 10 %: about 8 s, so that the Halt half a second in lands on the way even where a
    // loaded machine holds it back for seconds (at the twin's 100 % the move took under a
    // second, and a loaded run's Halt came after its end).
    robot.speed(10).unwrap();
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
    let said = sim.output_until("HALT", 1, 30).join("\n");
    assert!(said.contains("HALT"), "{said}");
}

/// The conventions of a C500 that are not the simulator's defaults: inches, other angles.
fn other_controller(dir: &Path) -> std::path::PathBuf {
    let p = dir.join("controller.toml");
    let profile = trol_rapl::Profile {
        units: trol_rapl::profile::Units::Inch,
        angles: "roll -pitch yaw".into(),
        ..trol_rapl::Profile::simulator()
    };
    std::fs::write(&p, profile.to_toml()).unwrap();
    p
}

#[test]
fn probe_records_first_contact_and_fits_the_conventions_of_pendant_poses() {
    let dir = scratch("rapl-probe");
    let controller = other_controller(&dir);
    let mut sim = Background::start(
        &dir,
        &[
            "sim",
            "--rapl",
            "--pendant",
            "--homed",
            "--time-scale",
            "20",
            "--profile",
            controller.to_str().unwrap(),
        ],
        "serving on ",
    );
    let args: Vec<String> = [
        "rapl",
        "probe",
        "--controller",
        &sim.name,
        "--out",
        "first.txt",
        "--poses",
        "2",
        "--profile-out",
        "fitted.toml",
    ]
    .map(String::from)
    .to_vec();
    let out = common::probe_with_poses(
        &dir,
        &args,
        &mut sim,
        &["10 20 40 30 50 -20", "-35 5 70 -60 30 45"],
    );
    assert!(out.contains("ENGLISH UNITS."), "{out}");
    assert!(
        out.contains("units = \"inch\", angles = \"roll -pitch yaw\""),
        "{out}"
    );
    assert!(out.contains("refusal form: \"NNN-TEXT.\""), "{out}");
    let fitted = trol_rapl::Profile::from_file(&dir.join("fitted.toml")).unwrap();
    assert_eq!(fitted.angles, "roll -pitch yaw");
    assert_eq!(fitted.units, trol_rapl::profile::Units::Inch);
    assert_eq!(fitted.refusal, vec!["NNN-TEXT.".to_string()]);
    // The pulse convention is fitted; MA and MI's units are not read off the JOINTS row.
    assert_eq!(fitted.pulse_scale.len(), 6);
    assert_eq!(fitted.joint_units, "");
    let transcript = std::fs::read_to_string(dir.join("first.txt")).unwrap();
    assert!(
        transcript.contains(" H 52 21 05"),
        "the ACI entry: {transcript}"
    );
    assert!(transcript.contains("WORLD"), "{transcript}");
    // Only commands that cannot move the arm reached the controller.
    let ran: Vec<String> = sim
        .output()
        .into_iter()
        .filter(|l| !l.starts_with(' ') && !l.starts_with("pendant"))
        .collect();
    for line in &ran {
        let word = line.split_whitespace().next().unwrap_or("");
        assert!(
            trol_rapl::probe::READ_ONLY.contains(&word) || ["NOHELP", "HELP"].contains(&word),
            "the probe ran {line}"
        );
    }

    // A second probe does not overwrite the fitted profile.
    let again = trol(
        &dir,
        &[
            "rapl",
            "probe",
            "--controller",
            &sim.name,
            "--out",
            "second.txt",
            "--poses",
            "2",
            "--profile-out",
            "fitted.toml",
        ],
        "",
    );
    let (_, err) = text(&again);
    assert!(
        !again.status.success() && err.contains("fitted.toml exists"),
        "{err}"
    );

    // The plain terminal: lines typed, replies printed, refusals as the controller says
    // them, the session closed.
    let term = trol(
        &dir,
        &[
            "rapl",
            "term",
            "--controller",
            &sim.name,
            "--profile",
            controller.to_str().unwrap(),
            "--out",
            "term.txt",
        ],
        "status\nw2\njoint 1,5\nbogus\n",
    );
    let (out, err) = text(&term);
    assert!(term.status.success(), "{out}\n{err}");
    assert!(out.contains("ENGLISH UNITS."), "{out}");
    assert!(out.contains("WORLD"), "{out}");
    assert!(out.contains("012-COMMAND ERROR."), "{out}");
    assert!(out.contains("session closed"), "{out}");
    sim.wait_for("JOINT 1,5", 10);
    sim.wait_for("BOGUS", 10);
    assert!(
        std::fs::read_to_string(dir.join("term.txt"))
            .unwrap()
            .contains(" H ")
    );
}

#[test]
fn term_ctrl_c_stops_the_controller_and_a_second_closes_the_session() {
    use std::io::Write;
    let dir = scratch("rapl-term-int");
    // Real time: the motion takes many seconds.
    let sim = rapl_sim(&dir, &["--homed"]);
    let mut term = std::process::Command::new(common::TROL)
        .args([
            "rapl",
            "term",
            "--controller",
            &sim.name,
            "--profile",
            "c500.toml",
        ])
        .current_dir(&dir)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut input = term.stdin.take().unwrap();
    // A slow motion, then FINISH, which waits for it: Ctrl-C during the wait.
    writeln!(input, "speed 5\njoint 1,90\nfinish").unwrap();
    sim.wait_for("FINISH", 30);
    let int = || {
        let ok = std::process::Command::new("kill")
            .args(["-INT", &term.id().to_string()])
            .status()
            .unwrap()
            .success();
        assert!(ok, "kill -INT");
    };
    int();
    sim.wait_for("HALT", 30);
    // A second Ctrl-C closes the session cleanly (HELP, two Ctrl-Z) and leaves, with its
    // input still open.
    int();
    sim.wait_for("HELP", 30);
    let out = term.wait_with_output().unwrap();
    drop(input);
    let (o, e) = (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    );
    assert!(out.status.success(), "{o}\n{e}");
    assert!(
        e.contains("interrupted: stopping the controller"),
        "{o}\n{e}"
    );
    assert!(o.contains("interrupted: Ctrl-C sent"), "{o}\n{e}");
    assert!(o.contains("session closed"), "{o}\n{e}");
}

#[test]
fn probe_measure_moves_only_after_yes_and_settles_what_no_reading_tells() {
    let dir = scratch("rapl-measure");
    // Real time: whether a motion's answer comes while it runs is the point.
    let mut sim = Background::start(
        &dir,
        &[
            "sim",
            "--rapl",
            "--variant",
            "ma-radians",
            "--homed",
            "--pendant",
        ],
        "serving on ",
    );
    // The operator puts the arm in free space first, the tool not pointing up.
    sim.type_line("10 20 40 30 -50 -20");
    sim.wait_for("pendant: at", 60);
    // The profile the poses of step 4 fitted (the simulator's angles).
    std::fs::write(dir.join("poses.toml"), "angles = \"yaw pitch roll\"\n").unwrap();
    let probe = |answer: &str, out: &str| {
        trol(
            &dir,
            &[
                "rapl",
                "probe",
                "--controller",
                &sim.name,
                "--profile",
                "poses.toml",
                "--out",
                "steps.txt",
                "--measure",
                "--profile-out",
                out,
            ],
            answer,
        )
    };
    let no = probe("no\n", "no.toml");
    let (o, e) = text(&no);
    assert!(o.contains("not confirmed: nothing moved"), "{o}\n{e}");
    assert!(
        !sim.output()
            .iter()
            .any(|l| l.starts_with("MI ") || l.starts_with("JOG")),
        "{:?}",
        sim.output()
    );
    let yes = probe("yes\n", "yes.toml");
    let (o, e) = text(&yes);
    assert!(yes.status.success(), "{o}\n{e}");
    assert!(
        o.contains(
            "measured: joint_units = \"radians\", jog_frame = \"world\", motion_ack = \"start\""
        ),
        "{o}\n{e}"
    );
    let p = trol_rapl::Profile::from_file(&dir.join("yes.toml")).unwrap();
    assert_eq!(p.joint_units, "radians");
    assert_eq!(p.jog_frame, "world");
}

#[test]
fn the_gateway_s_view_shows_the_arm_the_c500_reports() {
    let dir = scratch("rapl-gateway-view");
    let sim = rapl_sim(&dir, &["--time-scale", "20", "--homed"]);
    let gw = Background::start(
        &dir,
        &[
            "gateway",
            "--controller",
            &sim.name,
            "--profile",
            "c500.toml",
            "--server",
            "--view",
            "127.0.0.1:0",
        ],
        "serving on ",
    );
    let url = gw
        .wait_for("the view: ", 30)
        .last()
        .and_then(|l| l.split("the view: ").nth(1))
        .expect("the view's address")
        .trim()
        .to_string();
    std::fs::write(
        dir.join("trol.cfg"),
        format!("9600\n{}\n0 0 0 0 0 0\n", gw.name),
    )
    .unwrap();
    let o = trol(
        &dir,
        &["interp"],
        "ma j(0.2, 0.1, 0.8, 0, 0.6, 0)\nfinish\n",
    );
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    // W2's joints, read about ten times a second, in the view's form.
    let s = view_state_at(&url, [0.2, 0.1, 0.8, 0.0, 0.6, 0.0]);
    assert_eq!(s["reported"], true, "{s}");
    assert!(s["gripper_mm"].is_null(), "{s}");
}

/// POST a pendant request to the view at `url` (`http://host:port/`): the JSON answer.
fn pendant_post(url: &str, path: &str) -> serde_json::Value {
    use std::io::{Read, Write};
    let addr = url.trim_start_matches("http://").trim_end_matches('/');
    let mut s = std::net::TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(std::time::Duration::from_secs(20)))
        .unwrap();
    write!(s, "POST {path} HTTP/1.1\r\nHost: {addr}\r\n\r\n").unwrap();
    let mut all = String::new();
    s.read_to_string(&mut all).unwrap();
    let body = all.split_once("\r\n\r\n").map_or("", |(_, b)| b);
    serde_json::from_str(body).unwrap_or_else(|e| panic!("{e}: {all}"))
}

/// The gateway's pendant (`--view --control`, docs/teach.md): its requests reach the C500
/// through the backend's fail-safe rules: a joint moves, the place is stored with HERE.
#[test]
fn the_gateway_s_pendant_drives_the_c500() {
    let dir = scratch("rapl-gateway-pendant");
    let sim = rapl_sim(&dir, &["--time-scale", "20", "--homed"]);
    let gw = Background::start(
        &dir,
        &[
            "gateway",
            "--controller",
            &sim.name,
            "--profile",
            "c500.toml",
            "--server",
            "--view",
            "127.0.0.1:0",
            "--control",
        ],
        "serving on ",
    );
    let line = gw.wait_for("#token=", 30).pop().unwrap();
    let pendant = line.split(": ").last().unwrap().trim().to_string();
    let (url, token) = pendant.split_once("#token=").unwrap();
    let joint = pendant_post(
        url,
        &format!("/control/joint?joint=1&radians=0.2&token={token}"),
    );
    assert_eq!(joint["ok"], true, "{joint}");
    let s = view_state_at(url, [0.2, 0.0, 0.0, 0.0, 0.0, 0.0]);
    assert_eq!(s["reported"], true, "{s}");
    let here = pendant_post(url, &format!("/control/here?name=p7&token={token}"));
    assert_eq!(here["ok"], true, "{here}");
    let wrong = pendant_post(url, &format!("/control/here?name=p8&token=x{token}"));
    assert_eq!(wrong["ok"], false, "{wrong}");
}

/// Per-connection state in C (issue 38, item 5): a program with two connections, a C500
/// through rapl: and a simulated A465, names each controller's BIOS codes as that controller
/// does (trol_strerror_for), and one connection's failure stays its own: the second
/// controller killed, its last communication error is kept while another thread's calls on
/// the first succeed (it used to be one per process, reset by any call); one ErrOnSend for
/// both tells which one failed (trol_current, trol_get_user).
#[test]
fn c_connections_keep_their_own_codes_and_errors() {
    use std::io::{BufRead, BufReader, Write};
    let dir = scratch("rapl-comm-state");
    let c500 = rapl_sim(&dir, &["--homed"]);
    let sim = Background::start(&dir, &["sim", "--server"], "serving on ");
    let exe = cbuild::compile(
        &cbuild::root().join("crates/trol-cli/tests/c/comm_state.c"),
        "comm_state",
        cbuild::Link::Static,
    );
    let mut child = cbuild::program(&exe)
        .current_dir(&dir)
        .args([format!("rapl:{}", c500.name), sim.name.clone()])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut text = String::new();
    loop {
        let mut line = String::new();
        assert!(
            out.read_line(&mut line).unwrap() > 0,
            "it ended early:\n{text}"
        );
        text.push_str(&line);
        if line.starts_with("stop b") {
            break;
        }
    }
    drop(sim);
    writeln!(child.stdin.as_mut().unwrap()).unwrap();
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut out, &mut rest).unwrap();
    text.push_str(&rest);
    assert!(child.wait().unwrap().success(), "{text}");
    assert!(text.contains("a -9: BIOS_NO_ANGLES"), "{text}");
    assert!(text.contains("b -9: code -9: not one of TROL's"), "{text}");
    assert!(text.contains("b -1: BIOS_NOT_HOMED"), "{text}");
    assert!(
        text.contains("b: -32001, last comm error 0x0008 (side 1), changed 0 times"),
        "{text}"
    );
    assert!(
        text.contains("a: 0 calls failed, last comm error 0x0000"),
        "{text}"
    );
    assert!(text.contains("default connection: 0x0000"), "{text}");
    assert!(text.contains("the shared handler saw: b"), "{text}");
    assert!(text.ends_with("done\n"), "{text}");
}

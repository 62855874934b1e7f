//! Opening a connection: trol.cfg, the activation and its block check, the version and
//! code check, the link settings, a 1998 host.

use super::*;

#[test]
pub(super) fn robots_from_a_config_file() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("trol-cfg");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("locs.txt"), "p2 420 0 400 0 1.5707963 0\n").unwrap();
    std::fs::write(dir.join("objs.txt"), "cube 420 0 385 30\n").unwrap();
    // With the feature `view`, trol.cfg's `view = ADDR` serves the live view; without it,
    // saying so is a clear error.
    let view = "view = 127.0.0.1:0\n";
    std::fs::write(
        dir.join("trol.cfg"),
        "9600\nsim\n0 0 0 0 0 0\ntime_scale = 50\nlocations = locs.txt\nhomed = yes\n\
         objects = objs.txt\n"
            .to_string()
            + if cfg!(feature = "view") { view } else { "" },
    )
    .unwrap();
    if !cfg!(feature = "view") {
        std::fs::write(
            dir.join("viewed.cfg"),
            format!("9600\nsim\n0 0 0 0 0 0\n{view}"),
        )
        .unwrap();
        let cfg = trol::Config::from_file(&dir.join("viewed.cfg")).unwrap();
        let e = trol::Connect::config(&cfg)
            .connect()
            .expect_err("no view in this build");
        assert!(e.to_string().contains("`view =`"), "{e}");
    }
    let cfg = trol::Config::from_file(&dir.join("trol.cfg")).unwrap();
    let mut r = trol::Connect::config(&cfg).connect().unwrap();
    r.move_to("p2", false).unwrap();
    r.finish().unwrap();
    let c = r
        .position(Tag::Cart, PosMode::Commanded)
        .unwrap()
        .to_array6();
    assert!((c[0] - 420.0).abs() < 1e-2, "{c:?}");
    // The objects file's cube is at p2: closing there picks it up.
    r.close_gripper(50).unwrap();
    r.finish().unwrap();
    let world = r.world().unwrap();
    assert!(
        world.ends_with("in the gripper")
            && world
                .strip_prefix("cube at x ")
                .and_then(|r| r.split(' ').next())
                .and_then(|x| x.parse::<f64>().ok())
                .is_some_and(|x| (x - 420.0).abs() < 0.05),
        "{world}"
    );
    // A grasp can be checked (GetGripper): the fingers stopped at the cube's 30 mm.
    let g = r.gripper().unwrap();
    assert_eq!(g.held, trol::Held::Object("cube".into()));
    assert!((g.opening_mm - 30.0).abs() < 0.5, "{g:?}");
    // `view = ADDR`: the embedded controller serves the live view; /state tells the same.
    #[cfg(feature = "view")]
    {
        let url = r.view_url().expect("trol.cfg's view is served");
        let state = view_state(&url);
        let q = r.position(Tag::Joint, PosMode::Actual).unwrap().to_array6();
        for (i, qi) in q.iter().enumerate() {
            let shown = state["joints"][i].as_f64().unwrap();
            assert!(
                (shown - qi).abs() < 1e-3,
                "joint {}: {shown} against {qi}",
                i + 1
            );
        }
        assert_eq!(state["objects"][0]["name"], "cube");
        assert_eq!(state["objects"][0]["held"], true);
        assert!(
            (state["tcp"][0].as_f64().unwrap() - 420.0).abs() < 0.1,
            "{state}"
        );
    }
    // A file trol.cfg names that is not there: the configuration's error, with its line.
    std::fs::write(
        dir.join("missing.cfg"),
        "9600\nsim\n0 0 0 0 0 0\ntime_scale = 2\nobjects = gone.txt\n",
    )
    .unwrap();
    let e = trol::Config::from_file(&dir.join("missing.cfg")).unwrap_err();
    assert_eq!(e.line, Some(5), "{e}");
    assert!(e.to_string().contains("gone.txt is not there"), "{e}");
    std::fs::write(dir.join("bad.cfg"), "9600\nsim\n1 2 3\n").unwrap();
    let e = trol::Config::from_file(&dir.join("bad.cfg")).unwrap_err();
    assert_eq!(e.line, Some(3));
    assert!(e.to_string().contains("bad.cfg:3"));
}

/// The activation line agrees on the block check: a host with the manual's LRC activates a
/// controller in terminal mode, which then speaks LRC; a host with CRC-16 gets nowhere with it.
///
/// The probe that found the controller in terminal mode failed, and a failed transfer leaves
/// the sender deaf for two reset periods; the activation itself starts both links afresh, so
/// InitTROL(0) does not wait them out. Here a reset period is a minute: activation and the
/// first call after it take far less than the two minutes a wait would.
#[test]
pub(super) fn activation_agrees_on_the_block_check() {
    use trol_controller::{Controller, Embedded, Mode};
    use trol_proto::link::BlockCheck;
    let (host, ctl) = trol_port::memory::pair(None);
    let controller = Controller::new(
        ctl,
        steady(),
        Pcp::new(SimBackend::new(settings())),
        Mode::Terminal,
    );
    let handle = Embedded::spawn(controller);
    let mut lrc = LinkConfig {
        check: BlockCheck::Lrc,
        ..steady()
    };
    lrc.timeouts.reset = Duration::from_secs(60);
    let mut robot = Robot::over(Box::new(host), lrc, None);
    let started = std::time::Instant::now();
    trol::activate(&mut robot, &[0.0; 6]).unwrap();
    assert_eq!(robot.status().unwrap(), (true, SUCCESS));
    assert!(
        started.elapsed() < Duration::from_secs(60),
        "activation waited out the failed probe's reset ({:?})",
        started.elapsed()
    );
    robot.home(0).unwrap();
    // The same controller (still running), a host that computes CRC-16: its header is refused
    // with NAK ERR_BCC until the retries run out.
    let port = robot.into_port();
    let mut other = Robot::over(port, steady(), None);
    let e = other.status().unwrap_err();
    assert_eq!(e.code(), TROL_ERR_COMM, "{e}");
    assert_eq!(
        other.last_comm_error().map(|e| e.code()),
        Some(0x0007),
        "ERR_LIMIT_EXCEEDED after NAK ERR_BCC"
    );
    drop(handle);
}

/// A 1998 controller whose server takes a moment to start after it answered the activation
/// line (the bytes sent meanwhile are lost) is activated all the same: the host tries its
/// check again, one ENQ each, within `trol::ACTIVATION_WINDOW` (issue 67, item 3: with one
/// try, 0 of 4 activations at a 50 ms start). Each pause of the issue, and none.
#[test]
pub(super) fn a_1998_controller_that_starts_slowly_is_activated() {
    use trol_controller::{Embedded, Mode};
    use trol_proto::transaction::ManualLayer3;
    for pause_ms in [0u64, 50, 200, 1000] {
        let cfg = lrc_steady();
        let (host, ctl) = trol_port::memory::pair(None);
        let mut controller = sim_controller(ctl, cfg, Mode::Terminal);
        controller.speak_manual_only(ManualLayer3::ZeroPci);
        controller.set_start_pause(Duration::from_millis(pause_ms));
        let handle = Embedded::spawn(controller);
        let mut robot = Robot::over(Box::new(host), cfg, None);
        robot.keep(handle);
        trol::activate(&mut robot, &[0.0; 6])
            .unwrap_or_else(|e| panic!("a start of {pause_ms} ms: {e}"));
        assert!(robot.speaks_manual_only(), "{pause_ms} ms");
        assert_eq!(robot.status().unwrap(), (true, SUCCESS), "{pause_ms} ms");
        robot.home(0).unwrap();
    }
}

/// A controller that never starts its server after the activation line is given up on once
/// the activation window has passed, with the cable hint, not waited for without end.
#[test]
pub(super) fn a_controller_whose_server_never_starts_is_given_up_on() {
    use trol_controller::{Controller, Embedded, Mode};
    let (host, ctl) = trol_port::memory::pair(None);
    let mut controller = Controller::new(
        ctl,
        steady(),
        Pcp::new(SimBackend::new(settings())),
        Mode::Terminal,
    );
    controller.set_start_pause(Duration::from_secs(3600));
    let handle = Embedded::spawn(controller);
    let mut robot = Robot::over(Box::new(host), steady(), None);
    robot.keep(handle);
    let e = trol::activate(&mut robot, &[0.0; 6]).unwrap_err();
    assert!(e.to_string().contains("does not answer"), "{e}");
}

/// Settings that cannot work are refused with TROL_ERR_ARG_RANGE and change nothing; the
/// inter-character delay lengthens the link's timeouts.
#[test]
pub(super) fn impossible_link_settings_are_refused_and_the_delay_counts_in_the_timeouts() {
    let mut rig = rig();
    let e = rig.robot.set_reply_timeout_tenths(0).unwrap_err();
    assert_eq!(e.code(), TROL_ERR_ARG_RANGE, "{e}");
    let e = rig.robot.set_delay(Duration::from_secs(65)).unwrap_err();
    assert_eq!(e.code(), TROL_ERR_ARG_RANGE, "{e}");
    assert!(e.to_string().contains("50 ms"), "{e}");
    let char_time = |r: &mut Robot| r.link_config().char_time;
    let before = char_time(&mut rig.robot);
    rig.robot.set_delay(Duration::from_millis(5)).unwrap();
    assert_eq!(char_time(&mut rig.robot), before + Duration::from_millis(5));
    rig.robot.set_delay(Duration::from_millis(2)).unwrap();
    assert_eq!(char_time(&mut rig.robot), before + Duration::from_millis(2));
    // The link still works.
    rig.robot.status().unwrap();
    // A tool no arm carries: the controller refuses it, and the old one stays.
    let e = rig
        .robot
        .set_tool_transform(&[0.0, 0.0, 1e30, 0.0, 0.0, 0.0])
        .unwrap_err();
    assert_eq!(e.code(), TROL_ERR_ARG_RANGE, "{e}");
}

/// The code table travels with the version handshake (docs/protocol.md, "Codes"): a
/// controller's own BIOS codes are named as it names them, whatever its kind; one that does
/// not know GetCodes, or answers it wrongly, leaves its codes named by number.
#[test]
pub(super) fn a_controller_names_its_own_codes_at_connect() {
    let jammed = trol::CodeEntry {
        value: -77,
        name: "BIOS_GANTRY_JAMMED".into(),
        meaning: "the gantry is jammed".into(),
    };
    let mut robot = controller_with_codes(Reply::Codes(vec![jammed.clone()]).encode());
    trol::check_server(&mut robot).unwrap();
    assert_eq!(Code(-77).name(robot.codes()), Some("BIOS_GANTRY_JAMMED"));
    let e = robot.move_to("p1", false).unwrap_err();
    assert_eq!(e.code(), Code(-77));
    assert!(e.to_string().contains("BIOS_GANTRY_JAMMED"), "{e}");
    assert!(e.to_string().contains("the gantry is jammed"), "{e}");

    // Older controllers: TROL_ERR_UNKNOWN, and a reply that breaks the rules (a TROL code
    // in the table): connected, codes by number.
    let mut bad = Reply::Codes(vec![jammed]).encode();
    bad[2..4].copy_from_slice(&(-32001i16).to_le_bytes());
    for reply in [Reply::Code(TROL_ERR_UNKNOWN).encode(), bad] {
        let mut robot = controller_with_codes(reply);
        trol::check_server(&mut robot).unwrap();
        assert_eq!(Code(-77).name(robot.codes()), None);
        let e = robot.move_to("p1", false).unwrap_err();
        assert!(e.to_string().contains("-77"), "{e}");
    }

    // The simulator tells its own, the simulated A465's.
    let mut robot = trol::Connect::sim(settings()).connect().unwrap();
    let told = robot.get_codes().unwrap();
    assert_eq!(told.len(), trol_sim::SIM_CODES.len());
    assert!(told.iter().any(|c| c.name == "BIOS_NOT_HOMED"));
}

#[test]
pub(super) fn an_in_process_controller_keeps_its_slack_after_the_version_check() {
    // The version check learns the controller's reply time and keep-alive again: for an
    // in-process one, a busy machine may hold its thread back, so both keep the slack
    // (issue 44: InitTROL(1) put them back to the bare figures, and a 1998 program's
    // first TROLHome on `rapl:` came back TROL_ERR_COMM under load; a poll of its Finish
    // had 2 s, and one reading a C500's STATUS missed them under load).
    let mut robot = trol::Connect::sim(settings()).connect().unwrap();
    let before = robot
        .call_reply_timeout()
        .expect("the backend says its reply time");
    assert!(before >= trol::IN_PROCESS_SLACK, "{before:?}");
    trol::check_server(&mut robot).unwrap();
    assert_eq!(robot.call_reply_timeout(), Some(before));
    // A poll of a wait too: it may read a real controller's line (a C500's STATUS).
    let poll = robot.poll_reply_timeout();
    assert!(
        poll > trol::POLL_REPLY_TIMEOUT
            && poll >= before.min(trol::POLL_REPLY_TIMEOUT + trol::IN_PROCESS_SLACK),
        "{poll:?}"
    );
    let silence = robot
        .keepalive_silence()
        .expect("the simulator keeps the line alive");
    assert!(
        silence >= trol::KEEPALIVE_SILENCE + trol::IN_PROCESS_SLACK,
        "{silence:?}"
    );
    // The application's own reply timeout is the bound of every wait, as the manual's.
    robot.set_reply_timeout_tenths(20).unwrap();
    assert_eq!(robot.call_reply_timeout(), None);
    assert_eq!(robot.keepalive_silence(), None);
    assert_eq!(robot.poll_reply_timeout(), Duration::from_secs(2));
}

#[test]
pub(super) fn the_host_checks_the_controllers_version_and_kind() {
    // The simulator: this library's version; its codes are the simulated A465's.
    let mut robot = trol::Connect::sim(settings()).connect().unwrap();
    let v = robot.check_version().unwrap();
    assert_eq!(v.protocol, trol::table::PROTOCOL_VERSION);
    assert_eq!(v.kind, "simulated A465");
    trol::check_server(&mut robot).unwrap();

    // Another protocol version: refused with both numbers and what to do.
    let mut robot = controller_of_version(Some(2));
    let e = trol::check_server(&mut robot).unwrap_err();
    // Typed: both numbers, for a program to act on.
    assert!(
        matches!(
            &e,
            Error::Setup(trol::SetupError::Incompatible {
                ours: trol::table::PROTOCOL_VERSION,
                theirs: Some(2),
                ..
            })
        ),
        "{e:?}"
    );
    let text = e.to_string();
    assert!(
        text.contains("version 2")
            && text.contains(&format!("version {}", trol::table::PROTOCOL_VERSION))
            && text.contains("same TROL"),
        "{text}"
    );
    assert!(
        !text.contains("  "),
        "one sentence, no runs of spaces: {text}"
    );

    // A controller that does not know GetVersion: older than this library.
    let mut robot = controller_of_version(None);
    let e = trol::check_server(&mut robot).unwrap_err().to_string();
    assert!(e.contains("does not know TROLGetVersion"), "{e}");
    assert!(!e.contains("  "), "one sentence, no runs of spaces: {e}");
}

/// A 1998 host (the manual's bare `PCP TROL`) gets the manual's answer and sizes from this
/// controller: `PCP TROL ACTIVE` without a word, the LRC, GetStatus in 4 bytes. A host of
/// this protocol that asks for the LRC by name gets the longer GetStatus.
#[test]
pub(super) fn a_1998_host_gets_the_manuals_answer_and_sizes() {
    use trol_controller::{Controller, Embedded, Mode};
    use trol_proto::link::BlockCheck;
    for (line, answer, manual) in [
        ("PCP TROL", "PCP TROL\r\nPCP TROL ACTIVE\r\n", true),
        (
            "PCP TROL LRC",
            "PCP TROL LRC\r\nPCP TROL ACTIVE LRC\r\n",
            false,
        ),
    ] {
        let (mut host, ctl) = trol_port::memory::pair(None);
        let controller = Controller::new(
            ctl,
            quick(),
            Pcp::new(SimBackend::new(settings())),
            Mode::Terminal,
        );
        let handle = Embedded::spawn(controller);
        host.send(format!("{line}\r").as_bytes()).unwrap();
        let mut seen = Vec::new();
        let deadline = Instant::now() + Duration::from_secs(10);
        let mut buf = [0u8; 64];
        while !String::from_utf8_lossy(&seen).contains("ACTIVE") || !seen.ends_with(b"\r\n") {
            let n = host.recv(&mut buf, deadline).unwrap();
            assert!(n > 0, "no answer to {line}: {seen:?}");
            seen.extend_from_slice(&buf[..n]);
        }
        assert_eq!(String::from_utf8_lossy(&seen), answer);
        // The controller drops its input once it has answered (as `trol::activate` waits).
        std::thread::sleep(Duration::from_millis(200));
        let lrc = LinkConfig {
            check: BlockCheck::Lrc,
            ..quick()
        };
        let mut robot = Robot::over(Box::new(host), lrc, None);
        robot.keep(handle);
        let reply = robot.transact_raw(&[trol::table::TROL_GET_STATUS]).unwrap();
        assert_eq!(reply.len(), if manual { 4 } else { 8 }, "{line}: {reply:?}");
        assert_eq!(robot.status_record().unwrap().epoch == 0, manual, "{line}");
    }
}

/// The one connect path (issue 39, item 5): `Connect` always checks the controller (the
/// embedded simulator's version check grants the repeats and learns its codes), applies the
/// settings given before the check, refuses a bad one with the manual's code, and says what a
/// `mars:` port lacks before anything opens.
#[test]
pub(super) fn connect_checks_the_controller_and_applies_its_settings() {
    let mut robot = trol::Connect::sim(settings())
        .reply_timeout_tenths(40)
        .delay(Duration::from_millis(2))
        .connect()
        .unwrap();
    assert_eq!(
        robot.version().unwrap().protocol,
        trol::table::PROTOCOL_VERSION
    );
    assert_eq!(robot.reply_timeout(), Duration::from_secs(4));
    assert!(robot.repeats() > 0, "the version check grants the repeats");
    robot.home(0).unwrap();

    // Set before the check, the repeats stay as the application set them.
    let robot = trol::Connect::sim(settings()).repeats(0).connect().unwrap();
    assert_eq!(robot.repeats(), 0);

    let e = trol::Connect::sim(settings())
        .reply_timeout_tenths(0)
        .connect()
        .unwrap_err();
    assert_eq!(e.code(), TROL_ERR_ARG_RANGE, "{e}");

    #[cfg(feature = "mars")]
    {
        let e = trol::Connect::port("mars:/dev/nowhere")
            .connect()
            .unwrap_err();
        assert!(e.to_string().contains("mars-profile = FILE"), "{e}");
    }
}

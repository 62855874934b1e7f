//! The manual's callbacks, the manual's way: a C program that defines ErrOnSend,
//! ErrOnReceive, ErrAppTimeOut and FatalError under those names (no setter) sees each called
//! on the failure that should call it, linked against libtrol.a and against libtrol.so. A
//! scripted controller on TCP provokes the failures.

mod common;

use std::time::{Duration, Instant};

use common::cbuild::{Link, compile, program, root};
use trol_comm::{Driver, Server, receive_data, send_data};
use trol_port::Port;
use trol_port::tcp::TcpLine;
use trol_proto::application::code::{SUCCESS, TROL_ERR_LOCATION};
use trol_proto::application::{Reply, table};
use trol_proto::link::codes::NakCode;
use trol_proto::link::control::{ACK, ENQ, NAK};
use trol_proto::link::frame::HEADER_LEN;
use trol_proto::link::{Link as L2, LinkConfig};

/// Serve InitTROL's GetStatus and GetVersion properly, then misbehave once per step of
/// callbacks.c.
fn scripted_controller(line: TcpLine) {
    let cfg = LinkConfig::default();
    let mut server = Server::new(line, cfg);
    // InitTROL(1): GetStatus.
    server
        .serve(Duration::from_secs(20), &mut |_| {
            Reply::Status {
                bios_called: false,
                last: SUCCESS,
                transaction: 0,
                epoch: 1,
            }
            .encode()
        })
        .unwrap();
    // InitTROL(1): GetVersion.
    server
        .serve(Duration::from_secs(20), &mut |_| {
            Reply::Version {
                protocol: table::PROTOCOL_VERSION,
                kind: "scripted controller".into(),
            }
            .encode()
        })
        .unwrap();
    // InitTROL(1): GetCodes, which this controller does not know (as a TROL controller older
    // than the command): InitTROL goes on, with the codes named by number.
    server
        .serve(Duration::from_secs(20), &mut |req| {
            assert_eq!(req.first(), Some(&table::TROL_GET_CODES), "{req:02x?}");
            Reply::Code(trol_proto::application::code::TROL_ERR_UNKNOWN).encode()
        })
        .unwrap();
    // InitTROL(1): GetReplyTime, likewise unknown: the calls keep the manual's reply timeout.
    server
        .serve(Duration::from_secs(20), &mut |req| {
            assert_eq!(req.first(), Some(&table::TROL_GET_REPLY_TIME), "{req:02x?}");
            Reply::Code(trol_proto::application::code::TROL_ERR_UNKNOWN).encode()
        })
        .unwrap();
    let mut driver = Driver::new(server.into_port());
    let receive = |driver: &mut Driver<TcpLine>| {
        let mut link = L2::new(cfg);
        receive_data(driver, &mut link, Duration::from_secs(20)).expect("a request")
    };
    let reply = |driver: &mut Driver<TcpLine>, pci: u16, r: Reply| {
        let mut link = L2::new(cfg);
        send_data(driver, &mut link, &r.encode(), pci & 0xFF).expect("the reply goes out");
    };
    // 1: TROLHalt: accept the ENQ, then refuse the header with a fatal NAK (ERR_TOO_LARGE):
    // the host's SendData fails at once with ERR_NAK, and its ErrOnSend gives up.
    let mut seen = Vec::new();
    let mut buf = [0u8; 64];
    let deadline = Instant::now() + Duration::from_secs(20);
    while !seen.contains(&ENQ) {
        let n = driver.port_mut().recv(&mut buf, deadline).unwrap();
        assert!(n > 0, "no ENQ for TROLHalt");
        seen.extend_from_slice(&buf[..n]);
    }
    driver.port_mut().send(&[ACK]).unwrap();
    let at = seen.iter().position(|b| *b == ENQ).unwrap();
    let mut header = seen[at + 1..].to_vec();
    while header.len() < HEADER_LEN {
        let n = driver.port_mut().recv(&mut buf, deadline).unwrap();
        assert!(n > 0, "no header for TROLHalt");
        header.extend_from_slice(&buf[..n]);
    }
    assert_eq!(header[5], table::TROL_HALT, "{header:02x?}");
    driver
        .port_mut()
        .send(&[NAK, NakCode::TooLarge as u8])
        .unwrap();
    // 2: TROLReady: receive it, answer with a stray byte where ENQ belongs, then the reply.
    let (pci, req) = receive(&mut driver);
    assert_eq!(req, [table::TROL_READY]);
    driver.port_mut().send(&[0x00]).unwrap();
    std::thread::sleep(Duration::from_millis(300));
    reply(&mut driver, pci, Reply::Code(SUCCESS));
    // 3: TROLGrip: the reply comes after 0.7 s, the reply timeout is 0.2 s.
    let (pci, req) = receive(&mut driver);
    assert_eq!(req[0], table::TROL_GRIP);
    std::thread::sleep(Duration::from_millis(700));
    reply(&mut driver, pci, Reply::Code(SUCCESS));
    // 4: TROLMove: refused.
    let (pci, req) = receive(&mut driver);
    assert_eq!(req[0], table::TROL_MOVE);
    reply(&mut driver, pci, Reply::Code(TROL_ERR_LOCATION));
    // 5: TROLOpen: a stray byte where ENQ belongs, and no reply. The application's
    // ErrOnReceive gives up (RECOVERY_FAIL): its word is final, so no repeat may come.
    let (_pci, req) = receive(&mut driver);
    assert_eq!(req[0], table::TROL_OPEN);
    driver.port_mut().send(&[0x00]).unwrap();
    let quiet_until = Instant::now() + Duration::from_secs(4);
    let mut after = Vec::new();
    while Instant::now() < quiet_until {
        match driver.port_mut().recv(&mut buf, quiet_until) {
            Ok(0) | Err(_) => break,
            Ok(n) => after.extend_from_slice(&buf[..n]),
        }
    }
    assert!(
        !after.contains(&ENQ),
        "the request was sent again after RECOVERY_FAIL: {after:02x?}"
    );
}

fn run_with(link: Link) -> String {
    let exe = compile(
        &root().join("crates/trol-c/tests/c/callbacks.c"),
        "callbacks",
        link,
    );
    let line = TcpLine::listen("127.0.0.1:0", Duration::from_secs(10)).unwrap();
    let addr = line.local_addr().unwrap();
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("trol-callbacks-dir-{link:?}"));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("trol.cfg"),
        format!("9600\nsocket://{addr}\n0 0 0 0 0 0\n"),
    )
    .unwrap();
    let controller = std::thread::spawn(move || scripted_controller(line));
    let out = program(&exe).current_dir(&dir).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    controller
        .join()
        .expect("the scripted controller saw what it expected");
    text
}

fn check(out: &str) {
    // 1: SendData failed: ErrOnSend got the request, then FatalError got TROL_ERR_COMM.
    assert!(
        out.contains("ErrOnSend: 1 bytes, command 6, GetLastCommErr 0x0402, side 1"),
        "{out}"
    );
    assert!(out.contains("FatalError: command 6, code -32001"), "{out}");
    assert!(out.contains("TROLHalt -> -32001"), "{out}");
    // 2: ErrOnReceive was asked after ERR_BAD_ENQ and received the reply itself.
    assert!(
        out.contains("ErrOnReceive: GetLastCommErr 0x0085, side 2"),
        "{out}"
    );
    assert!(out.contains("ErrOnReceive: received 2 bytes"), "{out}");
    assert!(out.contains("TROLReady -> 0"), "{out}");
    // 3: ErrAppTimeOut was asked with the command and waited on; nothing was waiting then.
    assert!(out.contains("ErrAppTimeOut: command 5"), "{out}");
    assert!(out.contains("TROLGrip -> 0"), "{out}");
    // 4: FatalError got the controller's refusal.
    assert!(out.contains("FatalError: command 12, code -32102"), "{out}");
    assert!(out.contains("TROLMove -> -32102"), "{out}");
    // 5: ErrOnReceive said RECOVERY_FAIL: the call ended with TROL_ERR_COMM, no repeat.
    assert!(out.contains("TROLOpen -> -32001"), "{out}");
    assert!(
        !out.contains("after TROLOpen: GetLastCommErr 0x0000"),
        "{out}"
    );
    // 6: a call refused before the line leaves no code of an earlier call (docs/protocol.md,
    // "Decision (GetLastCommErr)").
    assert!(
        out.contains("TROLSpeed(0) -> -32003, GetLastCommErr 0x0000"),
        "{out}"
    );
    assert!(
        out.contains("calls: send 1 receive 2 timeout ") && out.contains(" fatal 3;"),
        "{out}"
    );
    assert!(out.contains("buffer empty at first timeout 1"), "{out}");
}

#[test]
fn handlers_named_as_in_the_manual_are_called_with_the_static_library() {
    check(&run_with(Link::Static));
}

#[test]
fn handlers_named_as_in_the_manual_are_called_with_the_shared_library() {
    check(&run_with(Link::Shared));
}

/// TROLHalt from a second thread while the first waits in TROLFinish(FINISH_WAIT).
#[test]
fn halt_from_another_thread_gets_through_while_one_waits_in_finish() {
    let text = run_c(
        "halt_thread",
        Link::Static,
        &[("trol.cfg", "9600\nsim\n0 0 0 0 0 0\nhomed = yes\n")],
        &[],
    );
    assert!(
        text.contains("TROLJoint -> 0") && text.contains("TROLHalt -> 0"),
        "{text}"
    );
    assert!(text.contains("TROLFinish -> 0"), "{text}");
    let waited: f64 = text
        .split("waited ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(waited < 3.0, "{text}");
    let j1: f64 = text.split("j1 ").nth(1).unwrap().trim().parse().unwrap();
    assert!(j1 > 0.0 && j1 < 1.0, "{text}");
}

/// The manual's GetStatus method from C, exact: TROLLastTransaction, then TROLGetStatusOf.
#[test]
fn the_getstatus_method_tells_from_c_which_call_a_status_belongs_to() {
    let text = run_c(
        "status_of",
        Link::Static,
        &[("trol.cfg", "9600\nsim\n0 0 0 0 0 0\ntime_scale = 50\n")],
        &[],
    );
    let lines: Vec<&str> = text.lines().collect();
    // The refused Joint: its own request's status, BIOS called, BIOS_NOT_HOMED.
    let n: Vec<&str> = lines[0].split(&[' ', ';', ':'][..]).collect();
    let request = n[n.iter().position(|w| *w == "request").unwrap() + 1];
    let of = n[n.iter().position(|w| *w == "of").unwrap() + 1];
    assert_eq!(request, of, "{text}");
    assert!(
        lines[0].starts_with("TROLJoint -> -1;")
            && lines[0].contains("called 1, last -1; epoch set"),
        "{text}"
    );
    // The Joint that ran: the first GetStatusOf (a transaction of its own) does not change
    // which command the status belongs to.
    let n: Vec<&str> = lines[1].split(&[' ', ';', ':'][..]).collect();
    let request = n[n.iter().position(|w| *w == "request").unwrap() + 1];
    let of = n[n.iter().position(|w| *w == "of").unwrap() + 1];
    assert_eq!(request, of, "{text}");
    assert!(lines[1].contains("called 1, last 0"), "{text}");
    assert_eq!(lines[2], "NULL -> -32003", "{text}");
}

/// A simulated controller in server mode on a new pty, on a thread: (the path, the flag
/// that stops it, its thread; the other end kept open, as a cable).
fn sim_on_pty() -> (
    String,
    std::sync::Arc<std::sync::atomic::AtomicBool>,
    std::thread::JoinHandle<()>,
    trol_port::serial::SerialLine,
) {
    let (master, other, path) = trol_port::serial::SerialLine::pty_pair().unwrap();
    let backend = trol_sim::SimBackend::new(trol_sim::SimSettings {
        time_scale: 20.0,
        ..Default::default()
    });
    let mut controller = trol_controller::Controller::new(
        master,
        LinkConfig::for_line(38400, Duration::ZERO),
        trol_controller::Pcp::new(backend),
        trol_controller::Mode::Server,
    );
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let flag = stop.clone();
    let thread = std::thread::spawn(move || {
        let _ = controller.run(&flag);
    });
    (path, stop, thread, other)
}

/// Two arms in one process, each from its own thread through trol_connect; a handler that
/// calls TROL on its own connection gets TROL_ERR_COMM at once, and the other works.
#[test]
fn two_arms_from_two_threads_and_a_handler_that_calls_trol() {
    use std::io::{BufRead, BufReader, Write};
    let exe = compile(
        &root().join("crates/trol-c/tests/c/two_arms.c"),
        "two_arms",
        Link::Static,
    );
    let (a, stop_a, thread_a, _keep_a) = sim_on_pty();
    let (b, stop_b, thread_b, _keep_b) = sim_on_pty();
    let mut child = program(&exe)
        .args([&a, &b])
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
        if line.starts_with("kill the first") {
            break;
        }
    }
    // The first controller goes away (its pty closes).
    stop_a.store(true, std::sync::atomic::Ordering::Relaxed);
    thread_a.join().unwrap();
    writeln!(child.stdin.as_mut().unwrap()).unwrap();
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut out, &mut rest).unwrap();
    text.push_str(&rest);
    let status = child.wait().unwrap();
    stop_b.store(true, std::sync::atomic::Ordering::Relaxed);
    thread_b.join().unwrap();
    assert!(status.success(), "{text}");
    assert!(text.contains("arm 0: 0, joint 1 at 0.400"), "{text}");
    assert!(text.contains("arm 1: 0, joint 1 at -0.700"), "{text}");
    assert!(
        text.contains("strerror(-1): BIOS_NOT_HOMED: the arm must be homed first"),
        "{text}"
    );
    assert!(
        text.contains("strerror(-32102): TROL_ERR_LOCATION"),
        "{text}"
    );
    assert!(text.contains("NULL handle: -32003"), "{text}");
    // In its handler: its own connection TROL_ERR_COMM (no deadlock), the other one's
    // GetStatus answered (1: the last command called the BIOS).
    assert!(
        text.contains("in its handler: own -32001, other 1"),
        "{text}"
    );
    assert!(text.contains("halt on the dead one: -32001"), "{text}");
    assert!(text.ends_with("done\n"), "{text}");
}

/// A call before InitTROL: TROL_ERR_COMM, told apart from a failed line by one stderr line.
#[test]
fn a_call_before_inittrol_says_so_once() {
    let exe = compile(
        &root().join("crates/trol-c/tests/c/before_init.c"),
        "before_init",
        Link::Static,
    );
    let out = program(&exe).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(
        text.starts_with("-32004\n-32004\n-32004: TROL_ERR_NOT_INIT"),
        "{text}\n{err}"
    );
    assert_eq!(err.matches("called with no connection").count(), 1, "{err}");
    assert!(
        err.contains("TROLHome called with no connection (before InitTROL"),
        "{err}"
    );
}

/// trol_connect's failures come typed (trol_connect_error_kind), as the Rust API's
/// SetupError: a port that cannot be opened, and a controller of another protocol version
/// with both numbers (trol_connect_versions).
#[test]
fn trol_connect_says_what_kind_of_failure_it_met() {
    // A controller of protocol version 2: it answers GetStatus, then GetVersion with 2.
    let (addr, controller) = scripted_tcp(2, |code| {
        (code == table::TROL_GET_VERSION).then(|| {
            Reply::Version {
                protocol: 2,
                kind: "an older TROL".into(),
            }
            .encode()
        })
    });
    let port = format!("socket://{addr}");
    let out = run_c("connect_errors", Link::Static, &[], &[&port]);
    assert!(out.contains("no port: kind 1"), "{out}");
    assert!(
        out.contains(&format!(
            "old controller: kind 4, ours {}, theirs 2",
            table::PROTOCOL_VERSION
        )),
        "{out}"
    );
    let _ = controller.join();
}

/// InitTROL(0) finds a controller in terminal mode by a probe that fails, then activates
/// it: the application's ErrOnSend and ErrOnReceive are not called for InitTROL's own probes.
#[test]
fn inittrol_does_not_call_the_applications_handlers_for_its_probes() {
    let line = TcpLine::listen("127.0.0.1:0", Duration::from_secs(20)).unwrap();
    let addr = line.local_addr().unwrap();
    let backend = trol_sim::SimBackend::new(trol_sim::SimSettings::default());
    let mut controller = trol_controller::Controller::new(
        line,
        LinkConfig::default(),
        trol_controller::Pcp::new(backend),
        trol_controller::Mode::Terminal,
    );
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let flag = stop.clone();
    let thread = std::thread::spawn(move || {
        let _ = controller.run(&flag);
    });
    let cfg = format!("9600\nsocket://{addr}\n0 0 0 0 0 0\n");
    let out = run_c("init_probe", Link::Static, &[("trol.cfg", &cfg)], &[]);
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    let _ = thread.join();
    assert!(out.contains("handler calls during InitTROL(0): 0"), "{out}");
    assert!(out.contains("TROLSpeed -> 0"), "{out}");
}

/// TROLFinish(FINISH_WAIT) is polled, and still bounded as the manual's one long request:
/// after SetL3_TO_Intervall the application's ErrAppTimeOut decides, and RECOVERY_FAIL ends
/// the wait with TROL_ERR_COMM; RECOVERY_SUCCESS lets it go on to the motion's end.
#[test]
fn errapptimeout_bounds_finish_wait() {
    let out = run_c(
        "finish_bound",
        Link::Static,
        &[("trol.cfg", "9600\nsim\n0 0 0 0 0 0\nhomed = yes\n")],
        &[],
    );
    assert!(out.contains("TROLJoint -> 0"), "{out}");
    // The handler was asked about the Finish (command 4), once, and its FAIL was final.
    assert!(out.contains("ErrAppTimeOut: command 4"), "{out}");
    assert!(
        out.contains("gave up: TROLFinish -> -32001 after 1 call(s)"),
        "{out}"
    );
    let waited = out
        .lines()
        .find_map(|l| l.strip_prefix("waited: TROLFinish -> 0 after "))
        .unwrap_or_else(|| panic!("{out}"));
    let calls: u32 = waited.split(' ').next().unwrap().parse().unwrap();
    assert!(calls >= 1, "{out}");
}

/// A grasp checked from C: TROLGetGripper says nothing is held after closing on air, and
/// the cube (by name, at its width) after closing at it; NULL pointers are refused.
#[test]
fn trolgetgripper_tells_a_missed_grasp_from_a_held_object() {
    let out = run_c(
        "gripper",
        Link::Shared,
        &[
            ("locs.txt", "p2 420 0 400 0 1.5707963 0\n"),
            ("objs.txt", "cube 420 0 385 30\n"),
            (
                "trol.cfg",
                "9600\nsim\n0 0 0 0 0 0\ntime_scale = 50\nhomed = yes\n\
                 locations = locs.txt\nobjects = objs.txt\n",
            ),
        ],
        &[],
    );
    assert!(out.contains("NULL -> -32003"), "{out}");
    assert!(out.contains("name NULL with a size -> -32003"), "{out}");
    assert!(
        out.contains("on air: 0, opening 0.0 mm, held 0, name \"\""),
        "{out}"
    );
    assert!(
        out.contains("at the cube: 0, opening 30.0 mm, held 1, name \"cube\""),
        "{out}"
    );
}

/// Teaching from C (issue 28, docs/teach.md): TROLHere, TROLDefine, TROLListLocations,
/// TROLDeleteLocation, TROLSaveLocations; a wrong name form and a NULL count are refused
/// with TROL_ERR_ARG_RANGE, and the saved file holds what was taught.
#[test]
fn teaching_from_c_stores_lists_deletes_and_saves() {
    let dir_files = [
        ("taught.txt", ""),
        (
            "trol.cfg",
            "9600\nsim\n0 0 0 0 0 0\ntime_scale = 50\nhomed = yes\nlocations = taught.txt\n",
        ),
    ];
    let out = run_c("teach", Link::Shared, &dir_files, &[]);
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("trol-c-teach");
    let saved = std::fs::read_to_string(dir.join("taught.txt")).unwrap();
    assert!(
        saved.contains("\np1 4") && !saved.contains("#park"),
        "{saved}"
    );
    for line in [
        "here p1 -> 0",
        "here without # as prec -> -32003",
        "define #park -> 0",
        "count only -> 0",
        "count 2",
        "NULL count -> -32003",
        "after teaching: 0, 2 location(s): #park(tag 0) p1(tag 2)",
        "delete #park -> 0",
        "delete #park again -> -32102",
        "after deleting: 0, 1 location(s): p1(tag 2)",
        "move p1 -> 0",
        "at x 420.0 y -50.0 z 330.0",
        "save -> 0",
    ] {
        assert!(out.contains(line), "{line:?} in {out}");
    }
}

/// A trajectory from C (TROLTrajectory, docs/protocol.md "Trajectory"): timed on the
/// simulated A465 and the arm at its last waypoint; a NULL array, no points, times that go
/// back and a call without a connection are TROL_ERR_ARG_RANGE; one faster than the arm is
/// BIOS_TOO_FAST.
#[test]
fn a_trajectory_from_c_runs_timed_and_bad_ones_are_refused() {
    let dir_files = [(
        "trol.cfg",
        "9600\nsim\n0 0 0 0 0 0\ntime_scale = 50\nhomed = yes\n",
    )];
    let out = run_c("trajectory", Link::Shared, &dir_files, &[]);
    for line in [
        "trajectory -> 0",
        "finish -> 0",
        "at 0.500 0.250 0.750 0.000 0.000 0.000",
        "NULL points -> -32003",
        "no points -> -32003",
        "times back -> -32003",
        "too fast -> -30",
        "no connection -> -32003",
    ] {
        assert!(out.contains(line), "{line:?} in {out}");
    }
}

/// trol_strerror names a controller's own BIOS codes once InitTROL has read them
/// (TROLGetCodes), whatever kind of controller it is.
#[test]
fn trol_strerror_names_the_controllers_own_codes() {
    let (addr, controller) = scripted_tcp(4, |code| match code {
        table::TROL_GET_VERSION => Some(
            Reply::Version {
                protocol: table::PROTOCOL_VERSION,
                kind: "gantry".into(),
            }
            .encode(),
        ),
        table::TROL_GET_CODES => Some(
            Reply::Codes(vec![trol_client::CodeEntry {
                value: -77,
                name: "BIOS_GANTRY_JAMMED".into(),
                meaning: "the gantry is jammed".into(),
            }])
            .encode(),
        ),
        _ => None,
    });
    let cfg = format!("9600\nsocket://{addr}\n0 0 0 0 0 0\n");
    let out = run_c("strerror", Link::Static, &[("trol.cfg", &cfg)], &[]);
    assert!(out.contains("before: code -77: not one of TROL's"), "{out}");
    assert!(
        out.contains("after: BIOS_GANTRY_JAMMED: the gantry is jammed"),
        "{out}"
    );
    assert!(out.contains("TROL's own: TROL_ERR_LOCATION"), "{out}");
    let _ = controller.join();
}

/// Compile the C program `name` (crates/trol-c/tests/c/NAME.c), run it in a folder of its
/// own with `files` (trol.cfg and what it names) and `args`, and return its standard output
/// after checking that it succeeded.
fn run_c(name: &str, link: Link, files: &[(&str, &str)], args: &[&str]) -> String {
    let exe = compile(
        &root().join(format!("crates/trol-c/tests/c/{name}.c")),
        name,
        link,
    );
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("trol-c-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for (file, text) in files {
        std::fs::write(dir.join(file), text).unwrap();
    }
    let o = program(&exe).current_dir(&dir).args(args).output().unwrap();
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        o.status.success(),
        "{name}: {out}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    out
}

/// A scripted controller on a TCP port of its own, on a thread: `answer` gives the reply to
/// each request it knows (`None`: a GetStatus record), for up to `requests` requests.
fn scripted_tcp(
    requests: usize,
    answer: impl Fn(u8) -> Option<Vec<u8>> + Send + 'static,
) -> (std::net::SocketAddr, std::thread::JoinHandle<()>) {
    let line = TcpLine::listen("127.0.0.1:0", Duration::from_secs(20)).unwrap();
    let addr = line.local_addr().unwrap();
    let thread = std::thread::spawn(move || {
        let mut server = Server::new(line, LinkConfig::default());
        for _ in 0..requests {
            let r = server.serve(Duration::from_secs(20), &mut |req| {
                answer(req.first().copied().unwrap_or(0)).unwrap_or_else(|| {
                    Reply::Status {
                        bios_called: false,
                        last: SUCCESS,
                        transaction: 0,
                        epoch: 1,
                    }
                    .encode()
                })
            });
            if r.is_err() {
                break;
            }
        }
    });
    (addr, thread)
}

/// Code written the manual's way calls FatalError; a program that defines none still links,
/// with either library, and the default returns the error code (docs/protocol.md, the
/// handlers' table).
#[test]
fn fatal_error_has_a_default_the_manuals_extension_code_links_against() {
    for link in [Link::Static, Link::Shared] {
        let out = run_c(
            "fatal_default",
            link,
            &[("trol.cfg", "9600\nsim\n0 0 0 0 0 0\nhomed = yes\n")],
            &[],
        );
        assert!(
            out.contains("FatalError(TROL_MOVE, -5) -> -5"),
            "{link:?}: {out}"
        );
        assert!(out.contains("MyMoveNowhere -> -32102"), "{link:?}: {out}");
    }
}

/// NULL where the manual's layer functions write their results is refused at once (issue
/// 38): ReceiveData(&out, NULL) waited 15 s; each says why on stderr; the next call works.
#[test]
fn null_results_are_refused_at_once() {
    let text = run_c(
        "null_args",
        Link::Static,
        &[("trol.cfg", "9600\nsim\n0 0 0 0 0 0\n")],
        &[],
    );
    assert!(
        text.contains("ReceiveData(&out, NULL) -> 0x00ff after 0.0 s"),
        "{text}"
    );
    assert!(text.contains("TransSR(NULL, &resp) -> 1"), "{text}");
    assert!(text.contains("TROLSpeed(50) -> 0"), "{text}");
}

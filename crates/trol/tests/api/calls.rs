//! Every API function and every error code over the whole stack, and a command added only
//! in the tests.

use super::*;

#[test]
pub(super) fn every_api_function_over_the_whole_stack() {
    let mut rig = rig();
    let r = &mut rig.robot;
    // Motion before Home is refused by the BIOS, and GetStatus says it was called.
    let e = r.joint(1, 0.1).unwrap_err();
    assert!(e.is_refusal());
    assert_eq!(e.code(), Code(trol_a465::arm::code::NOT_HOMED));
    assert_eq!(
        r.status().unwrap(),
        (true, Code(trol_a465::arm::code::NOT_HOMED))
    );
    // Home returns when homing is done, as on the arm.
    r.home(0).unwrap();
    assert!(!r.is_moving().unwrap());
    r.finish().unwrap();
    r.speed(150).unwrap();
    r.joint(1, 0.3).unwrap();
    r.finish().unwrap();
    assert!((joints(r)[0] - 0.3).abs() < 1e-6);
    r.mi(&[0.1, 0.2]).unwrap();
    r.finish().unwrap();
    let q = joints(r);
    assert!((q[0] - 0.4).abs() < 1e-6 && (q[1] - 0.2).abs() < 1e-6);
    r.ma(&[0.0, 0.3, 1.2, 0.0, 0.3]).unwrap();
    r.finish().unwrap();
    assert!((joints(r)[2] - 1.2).abs() < 1e-6);
    r.move_to("p1", false).unwrap();
    r.finish().unwrap();
    let c = r
        .position(Tag::Cart, PosMode::Commanded)
        .unwrap()
        .to_array6();
    assert!(
        (c[0] - 400.0).abs() < 1e-2 && (c[2] - 300.0).abs() < 1e-2,
        "{c:?}"
    );
    r.depart(&[-50.0], true).unwrap();
    r.finish().unwrap();
    let c = r
        .position(Tag::Cart, PosMode::Commanded)
        .unwrap()
        .to_array6();
    assert!(
        (c[2] - 350.0).abs() < 1e-2,
        "tool x points down: depart -50 goes up: {c:?}"
    );
    r.appro("p1", &[-20.0], true).unwrap();
    r.finish().unwrap();
    let c = r
        .position(Tag::Cart, PosMode::Commanded)
        .unwrap()
        .to_array6();
    assert!((c[2] - 320.0).abs() < 1e-2, "{c:?}");
    r.jog(&[10.0, 5.0], true).unwrap();
    r.finish().unwrap();
    let c = r
        .position(Tag::Cart, PosMode::Commanded)
        .unwrap()
        .to_array6();
    assert!(
        (c[0] - 410.0).abs() < 1e-2 && (c[1] - 5.0).abs() < 1e-2,
        "{c:?}"
    );
    let target = Location::Cart(vec![
        420.0,
        50.0,
        250.0,
        0.0,
        std::f64::consts::FRAC_PI_2,
        0.0,
    ]);
    r.move_ii(&target, false).unwrap();
    r.appro_ii(&target, &[-30.0], false).unwrap();
    r.finish().unwrap();
    let c = r
        .position(Tag::Cart, PosMode::Commanded)
        .unwrap()
        .to_array6();
    assert!((c[2] - 280.0).abs() < 1e-2, "{c:?}");
    // Precision point round trip.
    let prec = r.position(Tag::Prec, PosMode::Commanded).unwrap();
    r.ready().unwrap();
    r.finish().unwrap();
    assert!(joints(r).iter().all(|x| x.abs() < 1e-9));
    r.move_ii(&prec, false).unwrap();
    r.finish().unwrap();
    assert_eq!(r.position(Tag::Prec, PosMode::Commanded).unwrap(), prec);
    // At rest the actual position stays within the servo's dither of the commanded one, and
    // is never identical to it (manual, "TROLGetPosition").
    std::thread::sleep(Duration::from_millis(20));
    let (Location::Prec(act), Location::Prec(cmd)) =
        (r.position(Tag::Prec, PosMode::Actual).unwrap(), &prec)
    else {
        panic!("precision points")
    };
    for i in 0..6 {
        let off = (act[i] - cmd[i]).abs();
        assert!(
            (1..=trol_a465::arm::DITHER_COUNTS).contains(&off),
            "{act:?} {cmd:?}"
        );
    }
    // Halt in mid-motion: the arm stops and stays.
    r.speed(10).unwrap();
    r.joint(1, 1.0).unwrap();
    std::thread::sleep(Duration::from_millis(20));
    let start_j1 = joints(r)[0];
    r.halt().unwrap();
    // Halt brakes along the path; once stopped the arm stays, short of the target.
    r.finish().unwrap();
    let stopped = joints(r);
    assert!(!r.is_moving().unwrap());
    std::thread::sleep(Duration::from_millis(20));
    assert_eq!(joints(r), stopped);
    assert!(stopped[0] < start_j1 + 0.5, "{stopped:?}");
    // Gripper. Closing on nothing is a missed grasp GetGripper tells: closed, nothing held.
    r.close_gripper(60).unwrap();
    r.finish().unwrap();
    let g = r.gripper().unwrap();
    assert_eq!(g.held, trol::Held::Nothing);
    assert!(g.opening_mm < 1.0, "{g:?}");
    r.open_gripper(100).unwrap();
    r.grip(25).unwrap();
    r.finish().unwrap();
    let g = r.gripper().unwrap();
    assert!((g.opening_mm - 25.0).abs() < 0.5, "{g:?}");
    // Tool transform: the TCP moves 100 mm along the tool x axis.
    let before = r
        .position(Tag::Cart, PosMode::Commanded)
        .unwrap()
        .to_array6();
    r.set_tool_transform(&[100.0]).unwrap();
    let after = r
        .position(Tag::Cart, PosMode::Commanded)
        .unwrap()
        .to_array6();
    let moved = ((after[0] - before[0]).powi(2)
        + (after[1] - before[1]).powi(2)
        + (after[2] - before[2]).powi(2))
    .sqrt();
    assert!((moved - 100.0).abs() < 1e-2, "{moved}");
    r.terminate_pcp().unwrap();
}

#[test]
pub(super) fn every_error_code_on_the_side_that_detects_it() {
    let mut rig = rig_with(extended_pcp());
    let r = &mut rig.robot;
    // Host: TROL_ERR_ARG_RANGE, nothing sent.
    for e in [
        r.close_gripper(0).unwrap_err(),
        r.open_gripper(101).unwrap_err(),
        r.grip(51).unwrap_err(),
        r.speed(151).unwrap_err(),
        r.home(7).unwrap_err(),
        r.joint(0, 0.1).unwrap_err(),
        r.jog(&[1.0, 2.0, 3.0, 4.0], false).unwrap_err(),
        r.move_to("9bad", false).unwrap_err(),
        r.move_ii(&Location::Joint(vec![0.0]), false).unwrap_err(),
        r.mi(&[]).unwrap_err(),
    ] {
        assert!(matches!(e, Error::Argument(_)), "{e}");
        assert_eq!(e.code(), TROL_ERR_ARG_RANGE);
    }
    // Controller: TROL_ERR_UNKNOWN, TROL_ERR_BAD_CSIZE, TROL_ERR_ARG_RANGE, TROL_ERR_LOCATION.
    assert_eq!(
        r.transact_raw(&[99]).unwrap(),
        TROL_ERR_UNKNOWN.0.to_le_bytes()
    );
    assert_eq!(r.status().unwrap(), (false, TROL_ERR_UNKNOWN));
    assert_eq!(
        r.transact_raw(&[200]).unwrap(),
        TROL_ERR_UNKNOWN.0.to_le_bytes()
    );
    assert_eq!(
        r.transact_raw(&[6, 0]).unwrap(),
        TROL_ERR_BAD_CSIZE.0.to_le_bytes()
    );
    assert_eq!(r.status().unwrap(), (false, TROL_ERR_BAD_CSIZE));
    assert_eq!(
        r.transact_raw(&[2, 0]).unwrap(),
        TROL_ERR_ARG_RANGE.0.to_le_bytes()
    );
    let e = r.move_to("nowhere", false).unwrap_err();
    assert!(e.is_refusal());
    assert_eq!(e.code(), TROL_ERR_LOCATION);
    assert_eq!(r.status().unwrap(), (false, TROL_ERR_LOCATION));
    assert_eq!(
        r.appro("nowhere", &[1.0], false).unwrap_err().code(),
        TROL_ERR_LOCATION
    );
    // Controller: TROL_RETVAL_RANGE, the real value through GetStatus.
    r.add_command(ODD_BIOS).unwrap();
    r.add_command(BAD_REPLY).unwrap();
    let e = r.cat1_transaction(&[ODD_BIOS.code]).unwrap_err();
    assert_eq!(e.code(), TROL_RETVAL_RANGE);
    assert_eq!(r.status().unwrap(), (true, Code(-32500)));
    // Host: TROL_ERR_BAD_RSIZE.
    let e = r.cat1_transaction(&[BAD_REPLY.code]).unwrap_err();
    assert!(
        matches!(
            e,
            Error::BadReply {
                command: "TROLBadReply",
                len: 3
            }
        ),
        "{e}"
    );
    assert_eq!(e.code(), TROL_ERR_BAD_RSIZE);
    // Host: TROL_ERR_COMM, the link is gone.
    rig.deaf.store(true, Ordering::SeqCst);
    let e = rig.robot.halt().unwrap_err();
    assert!(matches!(e, Error::Link { .. }), "{e}");
    assert_eq!(e.code(), TROL_ERR_COMM);
    assert!(rig.robot.last_comm_error().is_some());
}

/// CAT1: a BIOS call that returns a value in TROL's range (record: the code alone).
pub(super) const ODD_BIOS: CommandDef = CommandDef {
    code: trol::table::LAST_CAT1_CODE + 1,
    name: "TROLOddBios",
    args: &[],
    reply: ReplyKind::Code,
    success: &[],
    wait: Wait::Reply,
    help: "a BIOS value in TROL's range",
};

/// CAT2: read the finger distance (reply: i16 0, f32 mm).
pub(super) const GET_FINGERS: CommandDef = CommandDef {
    code: 64,
    name: "TROLGetFingers",
    args: &[],
    reply: ReplyKind::Reals { min: 1, max: 1 },
    success: &[],
    wait: Wait::Reply,
    help: "the finger distance, mm",
};

/// CAT2: a handler that answers with a reply of the wrong size.
pub(super) const BAD_REPLY: CommandDef = CommandDef {
    code: 65,
    name: "TROLBadReply",
    args: &[],
    reply: ReplyKind::Code,
    success: &[],
    wait: Wait::Reply,
    help: "answers three bytes",
};

pub(super) fn odd_bios(_backend: &mut SimBackend, _call: &Call<'_>) -> Result<Executed, Code> {
    Ok(Executed::Now(-32500))
}

pub(super) fn get_fingers(ctx: &mut Context<'_, SimBackend>, _call: &Call<'_>) -> Reply {
    let now = ctx.backend.now();
    let mm = ctx.backend.arm().fingers(now);
    Reply::Reals {
        value: ctx.status.record_bios(0),
        values: vec![mm],
    }
}

pub(super) fn bad_reply(_ctx: &mut Context<'_, SimBackend>, _call: &Call<'_>) -> Reply {
    Reply::Bytes {
        value: SUCCESS,
        bytes: vec![0],
    }
}

pub(super) fn extended_pcp() -> Pcp<SimBackend> {
    let mut pcp = Pcp::new(SimBackend::new(settings()));
    pcp.register(ODD_BIOS, Handler::Cat1(odd_bios)).unwrap();
    pcp.register(GET_FINGERS, Handler::Other(get_fingers))
        .unwrap();
    pcp.register(BAD_REPLY, Handler::Other(bad_reply)).unwrap();
    // The table rejects gaps, handlers of the wrong class, and names taken.
    let gap = CommandDef {
        code: 70,
        name: "TROLGap",
        ..BAD_REPLY
    };
    assert!(pcp.register(gap, Handler::Other(bad_reply)).is_err());
    let wrong = CommandDef {
        code: 66,
        name: "TROLWrong",
        ..BAD_REPLY
    };
    assert!(pcp.register(wrong, Handler::Cat1(odd_bios)).is_err());
    let taken = CommandDef {
        code: 66,
        ..BAD_REPLY
    };
    assert!(pcp.register(taken, Handler::Other(bad_reply)).is_err());
    assert_eq!(pcp.last_code(trol_proto::application::Class::Cat2), 65);
    pcp
}

/// The added API function: a typed call through the command's description.
pub(super) fn get_fingers_api(robot: &mut Robot) -> trol::Result<f64> {
    match robot.call(&GET_FINGERS, &[])? {
        Reply::Reals { values, .. } => Ok(values[0]),
        other => panic!("{other:?}"),
    }
}

#[test]
pub(super) fn a_command_added_only_in_the_tests_works_end_to_end() {
    let mut rig = rig_with(extended_pcp());
    rig.robot.add_command(GET_FINGERS).unwrap();
    assert_eq!(get_fingers_api(&mut rig.robot).unwrap(), 50.0);
    rig.robot.grip(20).unwrap();
    rig.robot.finish().unwrap();
    assert_eq!(get_fingers_api(&mut rig.robot).unwrap(), 20.0);
    assert_eq!(rig.robot.status().unwrap(), (true, SUCCESS));
    // The built-in commands are untouched.
    assert_eq!(
        rig.robot.move_to("nowhere", false).unwrap_err().code(),
        TROL_ERR_LOCATION
    );
}

/// A position in another form than the one asked for answers no GetPosition of this host:
/// TROL_ERR_BAD_RSIZE through `call` too (the interpreter's and the trace's path), not a
/// location printed as if it were the one asked for.
#[test]
pub(super) fn a_position_in_another_form_is_bad_rsize_on_every_path() {
    let mut robot = scripted(2, |code| {
        (code == trol::table::TROL_GET_POSITION).then(|| {
            Reply::Position(Location::Cart(vec![400.0, 0.0, 150.0, 0.0, 0.0, 0.0])).encode()
        })
    });
    let joint = [
        trol::Value::Int(Tag::Joint as u8),
        trol::Value::Int(trol::table::POS_COMMANDED),
    ];
    let e = robot.call(&trol::table::GET_POSITION, &joint).unwrap_err();
    assert_eq!(e.code(), TROL_ERR_BAD_RSIZE, "{e}");
    let cart = [
        trol::Value::Int(Tag::Cart as u8),
        trol::Value::Int(trol::table::POS_COMMANDED),
    ];
    assert!(matches!(
        robot.call(&trol::table::GET_POSITION, &cart).unwrap(),
        Reply::Position(loc) if loc.tag() == Tag::Cart
    ));
}

#[test]
pub(super) fn adding_a_command_keeps_the_handlers_the_application_installed() {
    // A controller that never answers: every send fails, and the handler is told.
    let (host, _silent) = trol_port::memory::pair(None);
    let cfg = LinkConfig {
        timeouts: Timeouts::uniform(Duration::from_millis(100)),
        ..LinkConfig::default()
    };
    let mut r = Robot::over(Box::new(host), cfg, None);
    let told = Arc::new(std::sync::atomic::AtomicUsize::new(0));
    r.set_handlers(Box::new(Counting(told.clone())));
    r.add_command(GET_FINGERS).unwrap();
    assert!(r.status().is_err());
    assert!(told.load(Ordering::SeqCst) >= 1, "the handler was replaced");
}

/// TROLTrajectory through the whole stack: timed on the simulated A465 and the arm at the
/// last waypoint after Finish; what the host can check is refused before anything is sent;
/// what the arm cannot do is the controller's BIOS_TOO_FAST, with its name, and nothing
/// moves.
#[test]
pub(super) fn a_trajectory_over_the_whole_stack() {
    use trol::{Timing, Waypoint};
    let mut rig = rig();
    let r = &mut rig.robot;
    r.home(0).unwrap();
    r.finish().unwrap();
    let start = joints(r);
    let end = [0.5, 0.3, 0.8, 0.1, 0.3, 0.2];
    let path = [
        Waypoint {
            time: 0.0,
            joints: start,
        },
        Waypoint {
            time: 1.0,
            joints: [0.3, 0.2, 0.5, 0.0, 0.2, 0.0],
        },
        Waypoint {
            time: 2.0,
            joints: end,
        },
    ];
    assert_eq!(r.trajectory(&path).unwrap(), Timing::Timed);
    r.finish().unwrap();
    let q = joints(r);
    assert!((0..6).all(|i| (q[i] - end[i]).abs() < 1e-6), "{q:?}");
    // Checked on the host: nothing goes out.
    let sent = r.last_transaction();
    for bad in [
        Vec::new(),
        vec![path[2], path[1]],
        vec![Waypoint {
            time: f64::NAN,
            joints: end,
        }],
    ] {
        let e = r.trajectory(&bad).unwrap_err();
        assert_eq!(e.code(), TROL_ERR_ARG_RANGE, "{e}");
    }
    assert_eq!(r.last_transaction(), sent, "nothing was sent");
    // Faster than the arm: refused by the controller, named, and nothing moves.
    let e = r
        .trajectory(&[Waypoint {
            time: 0.05,
            joints: [-1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        }])
        .unwrap_err();
    assert!(e.is_refusal());
    assert_eq!(e.code(), Code(trol_a465::arm::code::TOO_FAST));
    assert!(e.to_string().contains("BIOS_TOO_FAST"), "{e}");
    r.finish().unwrap();
    let q = joints(r);
    assert!((0..6).all(|i| (q[i] - end[i]).abs() < 1e-6), "{q:?}");
}

/// A port that keeps a copy of every byte it received.
struct Tap<P> {
    inner: P,
    heard: Arc<std::sync::Mutex<Vec<u8>>>,
}

impl<P: Port> Port for Tap<P> {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.inner.send(bytes)
    }
    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        let n = self.inner.recv(buf, deadline)?;
        self.heard.lock().unwrap().extend_from_slice(&buf[..n]);
        Ok(n)
    }
    fn available(&mut self) -> io::Result<usize> {
        self.inner.available()
    }
    fn flush_input(&mut self) -> io::Result<()> {
        self.inner.flush_input()
    }
    fn name(&self) -> String {
        "tap".into()
    }
}

/// Issue 67, item 4: with the manual's LRC and framing, a command the controller does not
/// have is answered TROL_ERR_UNKNOWN (-32051), the manual's code, and not TROL_ERR_COMM:
/// - from a TROL host (it numbers its requests) the controller aborts the first transfer
///   with NAK ERR_FID, since noise may have made the request (docs/protocol.md "Checked as
///   the bytes allow"); layer 3 sends the same bytes again, which are taken;
/// - a host that does not number its requests (the manual's, which never sends a refused
///   request again) is answered at once, as the 1998 server answered it.
///
/// Both with a request of three frames (600 bytes) and with an added CAT1 command.
#[test]
pub(super) fn with_the_lrc_a_command_the_controller_lacks_is_answered_unknown() {
    use trol_controller::{Embedded, Mode};
    use trol_proto::link::control::NAK;
    const ADDED: CommandDef = CommandDef {
        code: trol::table::LAST_CAT1_CODE + 1,
        name: "TROLAdded",
        args: &[trol_proto::application::Arg {
            name: "value",
            kind: trol_proto::application::ArgKind::Real,
        }],
        reply: ReplyKind::Code,
        success: &[],
        wait: Wait::Reply,
        help: "a command this controller lacks",
    };
    let fid = [NAK, trol_proto::link::NakCode::Fid.byte()];
    for activated in [true, false] {
        let cfg = lrc_steady();
        let (host, ctl) = trol_port::memory::pair(None);
        let mode = if activated {
            Mode::Terminal
        } else {
            Mode::Server
        };
        let controller = sim_controller(ctl, cfg, mode);
        let handle = Embedded::spawn(controller);
        let heard = Arc::new(std::sync::Mutex::new(Vec::new()));
        let tap = Tap {
            inner: host,
            heard: heard.clone(),
        };
        let mut robot = Robot::over(Box::new(tap), cfg, None);
        robot.keep(handle);
        if activated {
            trol::activate(&mut robot, &[0.0; 6]).unwrap();
        }
        heard.lock().unwrap().clear();
        let mut long = vec![ADDED.code];
        long.resize(600, 0x5A);
        let who = if activated {
            "a TROL host"
        } else {
            "a host that does not number"
        };
        assert_eq!(
            robot
                .transact_raw(&long)
                .unwrap_or_else(|e| panic!("{who}: {e}")),
            TROL_ERR_UNKNOWN.0.to_le_bytes(),
            "{who}"
        );
        let refused = heard
            .lock()
            .unwrap()
            .windows(2)
            .filter(|w| *w == fid)
            .count();
        assert_eq!(refused, usize::from(activated), "{who}: NAK ERR_FID");
        robot.add_command(ADDED).unwrap();
        let e = robot.call(&ADDED, &[trol::Value::Real(1.5)]).unwrap_err();
        assert_eq!(e.code(), TROL_ERR_UNKNOWN, "{who}: {e}");
        assert_eq!(robot.status().unwrap(), (false, TROL_ERR_UNKNOWN), "{who}");
        // The line works on.
        robot.home(0).unwrap();
    }
}

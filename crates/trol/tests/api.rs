//! The API over the whole stack (Rust API, layers 1-4, the controller's server, the
//! simulated A465): every function, every error code on the side that detects it,
//! exactly-once after a lost reply or a lost request, and a command added only here.

use std::io;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use trol::code::*;
use trol::{Code, Error, Location, PosMode, Robot, SimSettings, Tag};
use trol_a465::arm::Stored;
use trol_controller::{Call, Context, Executed, Handler, Pcp};
use trol_port::Port;
use trol_proto::application::{CommandDef, Reply, ReplyKind, Wait};
use trol_proto::link::{LinkConfig, Timeouts};
use trol_sim::SimBackend;

fn quick() -> LinkConfig {
    LinkConfig {
        timeouts: Timeouts::uniform(Duration::from_millis(150)),
        ..LinkConfig::default()
    }
}

/// Link timeouts a loaded 2-core machine keeps (a controller thread may wait its turn for
/// a good part of 150 ms there), for the tests whose controller must answer every ENQ: they
/// failed now and then under load with [`quick`] (issue 44).
fn steady() -> LinkConfig {
    LinkConfig {
        timeouts: Timeouts::uniform(Duration::from_millis(500)),
        ..LinkConfig::default()
    }
}

fn settings() -> SimSettings {
    SimSettings {
        time_scale: 50.0,
        locations: vec![
            (
                "p1".into(),
                Stored::Cart([400.0, 0.0, 300.0, 0.0, std::f64::consts::FRAC_PI_2, 0.0]),
            ),
            ("#zero".into(), Stored::Prec([0; 6])),
        ],
        ..SimSettings::default()
    }
}

/// A port whose two directions can be cut: `deaf` drops what arrives, `mute` what is sent.
struct Switchable<P> {
    inner: P,
    deaf: Arc<AtomicBool>,
    mute: Arc<AtomicBool>,
    deaf_after_eot: Arc<AtomicBool>,
    drop_next_eot: Arc<AtomicBool>,
}

impl<P: Port> Port for Switchable<P> {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        if self.mute.load(Ordering::SeqCst) {
            return Ok(());
        }
        // Lose the request's EOT once: the controller never gets the request.
        if bytes.contains(&0x87) && self.drop_next_eot.swap(false, Ordering::SeqCst) {
            let kept: Vec<u8> = bytes.iter().copied().filter(|b| *b != 0x87).collect();
            return self.inner.send(&kept);
        }
        self.inner.send(bytes)?;
        // The request's EOT went out: from now on lose what comes back (the reply).
        if bytes.contains(&0x87) && self.deaf_after_eot.swap(false, Ordering::SeqCst) {
            self.deaf.store(true, Ordering::SeqCst);
        }
        Ok(())
    }
    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        let n = self.inner.recv(buf, deadline)?;
        if self.deaf.load(Ordering::SeqCst) {
            Ok(0)
        } else {
            Ok(n)
        }
    }
    fn available(&mut self) -> io::Result<usize> {
        self.inner.available()
    }
    fn flush_input(&mut self) -> io::Result<()> {
        self.inner.flush_input()
    }
    fn name(&self) -> String {
        "switchable".into()
    }
}

struct Rig {
    robot: Robot,
    deaf: Arc<AtomicBool>,
    mute: Arc<AtomicBool>,
    deaf_after_eot: Arc<AtomicBool>,
    drop_next_eot: Arc<AtomicBool>,
}

fn rig_with(pcp: Pcp<SimBackend>) -> Rig {
    let (line, handle) = trol_controller::embedded_with(pcp, quick());
    let deaf = Arc::new(AtomicBool::new(false));
    let mute = Arc::new(AtomicBool::new(false));
    let deaf_after_eot = Arc::new(AtomicBool::new(false));
    let drop_next_eot = Arc::new(AtomicBool::new(false));
    let port = Switchable {
        inner: line,
        deaf: deaf.clone(),
        mute: mute.clone(),
        deaf_after_eot: deaf_after_eot.clone(),
        drop_next_eot: drop_next_eot.clone(),
    };
    let mut robot = Robot::over(Box::new(port), quick(), Some(handle));
    robot.set_reply_timeout_tenths(10).unwrap();
    Rig {
        robot,
        deaf,
        mute,
        deaf_after_eot,
        drop_next_eot,
    }
}

fn rig() -> Rig {
    rig_with(Pcp::new(SimBackend::new(settings())))
}

fn joints(r: &mut Robot) -> [f64; 6] {
    r.position(Tag::Joint, PosMode::Commanded)
        .unwrap()
        .to_array6()
}

#[test]
fn every_api_function_over_the_whole_stack() {
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
fn every_error_code_on_the_side_that_detects_it() {
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

/// A relative move whose reply is lost: GetStatus afterwards says the BIOS was called and
/// with what result, so the application does not repeat it.
#[test]
fn exactly_once_when_the_reply_is_lost_for_good() {
    let mut rig = rig();
    rig.robot.home(0).unwrap();
    rig.robot.finish().unwrap();
    rig.deaf_after_eot.store(true, Ordering::SeqCst);
    let e = rig.robot.joint(1, 0.25).unwrap_err();
    assert_eq!(e.code(), TROL_ERR_COMM);
    rig.deaf.store(false, Ordering::SeqCst);
    // Give both link ends their reset time, then ask.
    std::thread::sleep(Duration::from_millis(800));
    let _ = rig.robot.flush_input();
    assert_eq!(
        rig.robot.status().unwrap(),
        (true, SUCCESS),
        "the Joint ran once"
    );
    rig.robot.finish().unwrap();
    assert!((joints(&mut rig.robot)[0] - 0.25).abs() < 1e-6);
}

/// By default a lost reply costs nothing: the request goes out again marked as a repeat, the
/// controller answers it from memory, and the relative move ran exactly once.
#[test]
fn a_lost_reply_is_repeated_and_the_move_runs_exactly_once() {
    let mut rig = rig();
    rig.robot.home(0).unwrap();
    rig.robot.finish().unwrap();
    rig.deaf_after_eot.store(true, Ordering::SeqCst);
    let deaf = rig.deaf.clone();
    // The reply is lost; the line is back before the repeat (reply timeout 1 s).
    let heal = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(500));
        deaf.store(false, Ordering::SeqCst);
    });
    rig.robot.joint(1, 0.25).unwrap();
    heal.join().unwrap();
    let joint = rig.robot.last_transaction();
    // GetStatus says which transaction its status belongs to: the Joint's.
    let status = rig.robot.status_record().unwrap();
    assert_eq!((status.bios_called, status.last), (true, SUCCESS));
    assert_eq!(status.transaction, joint);
    rig.robot.finish().unwrap();
    assert!((joints(&mut rig.robot)[0] - 0.25).abs() < 1e-6, "ran once");
}

/// A request whose EOT is lost never reached the controller: the repeat runs it, once.
#[test]
fn a_lost_request_is_repeated_and_the_move_runs_exactly_once() {
    let mut rig = rig();
    rig.robot.home(0).unwrap();
    rig.robot.finish().unwrap();
    rig.drop_next_eot.store(true, Ordering::SeqCst);
    rig.robot.joint(1, 0.25).unwrap();
    rig.robot.finish().unwrap();
    assert!((joints(&mut rig.robot)[0] - 0.25).abs() < 1e-6, "ran once");
}

/// With repeats off (the manual's behaviour) a lost request fails the call, and GetStatus
/// still describes the command before, so the application knows the move did not run and
/// sends it again.
#[test]
fn exactly_once_when_the_request_is_lost() {
    let mut rig = rig();
    rig.robot.home(0).unwrap();
    rig.robot.finish().unwrap();
    // A command that leaves a status the move cannot leave.
    assert_eq!(
        rig.robot.move_to("nowhere", false).unwrap_err().code(),
        TROL_ERR_LOCATION
    );
    rig.robot.set_repeats(0);
    rig.mute.store(true, Ordering::SeqCst);
    assert_eq!(rig.robot.joint(1, 0.25).unwrap_err().code(), TROL_ERR_COMM);
    rig.mute.store(false, Ordering::SeqCst);
    std::thread::sleep(Duration::from_millis(800));
    let _ = rig.robot.flush_input();
    assert_eq!(
        rig.robot.status().unwrap(),
        (false, TROL_ERR_LOCATION),
        "the Joint never ran"
    );
    assert_eq!(joints(&mut rig.robot)[0], 0.0);
    rig.robot.joint(1, 0.25).unwrap();
    rig.robot.finish().unwrap();
    assert!((joints(&mut rig.robot)[0] - 0.25).abs() < 1e-6);
}

// Extending TROL with new commands, as the manual's section "Erweiterung von TROL um eigene
// Kommandos" describes, without touching the library: a code in its class's range (the
// next free one), a record, a handler in the dispatch table, and an API function.

/// CAT1: a BIOS call that returns a value in TROL's range (record: the code alone).
const ODD_BIOS: CommandDef = CommandDef {
    code: trol::table::LAST_CAT1_CODE + 1,
    name: "TROLOddBios",
    args: &[],
    reply: ReplyKind::Code,
    success: &[],
    wait: Wait::Reply,
    help: "a BIOS value in TROL's range",
};
/// CAT2: read the finger distance (reply: i16 0, f32 mm).
const GET_FINGERS: CommandDef = CommandDef {
    code: 64,
    name: "TROLGetFingers",
    args: &[],
    reply: ReplyKind::Reals { min: 1, max: 1 },
    success: &[],
    wait: Wait::Reply,
    help: "the finger distance, mm",
};
/// CAT2: a handler that answers with a reply of the wrong size.
const BAD_REPLY: CommandDef = CommandDef {
    code: 65,
    name: "TROLBadReply",
    args: &[],
    reply: ReplyKind::Code,
    success: &[],
    wait: Wait::Reply,
    help: "answers three bytes",
};

fn odd_bios(_backend: &mut SimBackend, _call: &Call<'_>) -> Result<Executed, Code> {
    Ok(Executed::Now(-32500))
}

fn get_fingers(ctx: &mut Context<'_, SimBackend>, _call: &Call<'_>) -> Reply {
    let now = ctx.backend.now();
    let mm = ctx.backend.arm().fingers(now);
    Reply::Reals {
        value: ctx.status.record_bios(0),
        values: vec![mm],
    }
}

fn bad_reply(_ctx: &mut Context<'_, SimBackend>, _call: &Call<'_>) -> Reply {
    Reply::Bytes {
        value: SUCCESS,
        bytes: vec![0],
    }
}

fn extended_pcp() -> Pcp<SimBackend> {
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
fn get_fingers_api(robot: &mut Robot) -> trol::Result<f64> {
    match robot.call(&GET_FINGERS, &[])? {
        Reply::Reals { values, .. } => Ok(values[0]),
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_command_added_only_in_the_tests_works_end_to_end() {
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

#[test]
fn the_default_err_app_timeout_waits_for_a_long_finish() {
    // Reply timeout 0.1 s; a homing that takes 2 s (x 6 axes / 50) must not time out.
    let mut rig = rig();
    rig.robot.set_reply_timeout_tenths(1).unwrap();
    rig.robot.home(0).unwrap();
    rig.robot.finish().unwrap();
    assert!(!rig.robot.is_moving().unwrap());
}

#[test]
fn robots_from_a_config_file() {
    let dir = std::env::temp_dir().join(format!("trol-cfg-{}", std::process::id()));
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
        let e = Robot::from_config(&cfg).expect_err("no view in this build");
        assert!(e.to_string().contains("`view =`"), "{e}");
    }
    let cfg = trol::Config::from_file(&dir.join("trol.cfg")).unwrap();
    let mut r = Robot::from_config(&cfg).unwrap();
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
#[test]
fn activation_agrees_on_the_block_check() {
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
    let lrc = LinkConfig {
        check: BlockCheck::Lrc,
        ..steady()
    };
    let mut robot = Robot::over(Box::new(host), lrc, None);
    trol::activate(&mut robot, &[0.0; 6]).unwrap();
    assert_eq!(robot.status().unwrap(), (true, SUCCESS));
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

/// Halt from a second thread while the first waits for the arm: the wait polls with the
/// robot's lock free between polls, so the Halt gets through and the arm stops short.
#[test]
fn halt_from_another_thread_stops_the_arm_while_one_waits() {
    let mut sim = settings();
    sim.time_scale = 1.0;
    sim.arm.homed = true;
    let robot = Arc::new(std::sync::Mutex::new(Robot::embedded(sim)));
    let shared = robot.clone();
    let waiter = std::thread::spawn(move || {
        let mut r = shared.lock().unwrap();
        r.speed(10).unwrap();
        r.joint(1, 2.0).unwrap(); // over 6 s at 10 %
        drop(r);
        let started = Instant::now();
        trol::wait_idle(&shared).unwrap();
        started.elapsed()
    });
    std::thread::sleep(Duration::from_millis(500));
    robot.lock().unwrap().halt().unwrap();
    let waited = waiter.join().unwrap();
    assert!(waited < Duration::from_secs(3), "waited {waited:?}");
    let j1 = joints(&mut robot.lock().unwrap())[0];
    assert!(j1 > 0.0 && j1 < 1.0, "{j1}");
}

/// Halt answers only once the arm stands (issue 37): right after it nothing moves, and the
/// arm stands short of its target. (At half real time the A465 brakes from full speed for
/// 0.5 s, so an answer at the start of the braking would find the arm moving.)
#[test]
fn halt_answers_only_with_the_arm_standing() {
    let mut sim = settings();
    sim.time_scale = 0.5;
    sim.arm.homed = true;
    let mut r = Robot::embedded(sim);
    r.speed(100).unwrap();
    r.joint(1, 3.0).unwrap(); // 2.4 s at half real time
    std::thread::sleep(Duration::from_millis(300));
    r.halt().unwrap();
    assert!(!r.is_moving().unwrap(), "Halt answered while the arm moved");
    let j1 = joints(&mut r)[0];
    assert!(j1 > 0.0 && j1 < 2.9, "halted on the way: joint 1 at {j1}");
    // Its own Halt is no news to the program: Finish succeeds.
    r.finish().unwrap();
}

/// Settings that cannot work are refused with TROL_ERR_ARG_RANGE and change nothing; the
/// inter-character delay lengthens the link's timeouts.
#[test]
fn impossible_link_settings_are_refused_and_the_delay_counts_in_the_timeouts() {
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

/// A scripted controller on a thread: `answer` gives the reply to each request it knows
/// (`None`: a GetStatus record), for up to `requests` requests.
fn scripted(requests: usize, answer: impl Fn(u8) -> Option<Vec<u8>> + Send + 'static) -> Robot {
    let (host, ctl) = trol_port::memory::pair(None);
    std::thread::spawn(move || {
        let mut server = trol_comm::Server::new(ctl, LinkConfig::default());
        for _ in 0..requests {
            let r = server.serve(Duration::from_secs(5), &mut |req| {
                answer(req.first().copied().unwrap_or(0)).unwrap_or_else(|| {
                    Reply::Status {
                        bios_called: false,
                        last: SUCCESS,
                        transaction: 0,
                        epoch: 7,
                    }
                    .encode()
                })
            });
            if r.is_err() {
                break;
            }
        }
    });
    Robot::over(Box::new(host), LinkConfig::default(), None)
}

/// A controller that answers GetStatus and, to GetVersion, `version` (None:
/// TROL_ERR_UNKNOWN, as a controller that does not know the command).
fn controller_of_version(version: Option<u16>) -> Robot {
    scripted(4, move |code| {
        (code == trol::table::TROL_GET_VERSION).then(|| match version {
            Some(protocol) => Reply::Version {
                protocol,
                kind: "elsewhere".into(),
            }
            .encode(),
            None => Reply::Code(TROL_ERR_UNKNOWN).encode(),
        })
    })
}

/// A controller that answers GetVersion with this library's version, GetCodes with `codes`
/// (the reply's bytes), Move with BIOS code -77, and GetStatus.
fn controller_with_codes(codes: Vec<u8>) -> Robot {
    scripted(6, move |code| match code {
        trol::table::TROL_GET_VERSION => Some(
            Reply::Version {
                protocol: trol::table::PROTOCOL_VERSION,
                kind: "gantry".into(),
            }
            .encode(),
        ),
        trol::table::TROL_GET_CODES => Some(codes.clone()),
        trol::table::TROL_MOVE => Some(Reply::Code(Code(-77)).encode()),
        _ => None,
    })
}

/// The code table travels with the version handshake (docs/protocol.md, "Codes"): a
/// controller's own BIOS codes are named as it names them, whatever its kind; one that does
/// not know GetCodes, or answers it wrongly, leaves its codes named by number.
#[test]
fn a_controller_names_its_own_codes_at_connect() {
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
    let mut robot = Robot::embedded(settings());
    let told = robot.get_codes().unwrap();
    assert_eq!(told.len(), trol_sim::SIM_CODES.len());
    assert!(told.iter().any(|c| c.name == "BIOS_NOT_HOMED"));
}

#[test]
fn an_in_process_controller_keeps_its_slack_after_the_version_check() {
    // The version check learns the controller's reply time and keep-alive again: for an
    // in-process one, a busy machine may hold its thread back, so both keep the slack
    // (issue 44: InitTROL(1) put them back to the bare figures, and a 1998 program's
    // first TROLHome on `rapl:` came back TROL_ERR_COMM under load).
    let mut robot = Robot::embedded(settings());
    let before = robot
        .call_reply_timeout()
        .expect("the backend says its reply time");
    assert!(before >= trol::IN_PROCESS_SLACK, "{before:?}");
    trol::check_server(&mut robot).unwrap();
    assert_eq!(robot.call_reply_timeout(), Some(before));
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
}

#[test]
fn the_host_checks_the_controllers_version_and_kind() {
    // The simulator: this library's version; its codes are the simulated A465's.
    let mut robot = Robot::embedded(settings());
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

#[test]
#[cfg(feature = "view")]
fn the_watchdog_halts_the_arm_when_the_application_falls_silent() {
    let mut robot = Robot::embedded_viewed(
        SimSettings {
            time_scale: 1.0,
            ..settings()
        },
        Default::default(),
        "127.0.0.1:0",
    )
    .unwrap();
    robot.home(0).unwrap();
    robot.finish().unwrap();
    assert!(
        robot
            .set_watchdog(Duration::from_secs(26))
            .unwrap_err()
            .code()
            == TROL_ERR_ARG_RANGE
    );
    robot.set_watchdog(Duration::from_millis(300)).unwrap();

    // Fed by the polls of a wait, it lets a motion of a second end where it should.
    robot.speed(20).unwrap();
    robot.joint(1, 0.3).unwrap();
    robot.finish().unwrap();
    let j1 = joints(&mut robot)[0];
    assert!((j1 - 0.3).abs() < 1e-3, "joint 1 at {j1}");

    // Silent for five times its limit during a motion of several seconds: the arm was
    // halted on the way.
    robot.joint(1, 1.0).unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    // The live view learnt of the halt without a request.
    let state = view_state(&robot.view_url().unwrap());
    assert_eq!(
        state["moving"], false,
        "the view shows the arm moving: {state}"
    );
    // The program learns of it at its next Finish: TROL_ERR_HALTED, once; then the arm
    // stands as usual.
    let e = robot.is_moving().unwrap_err();
    assert_eq!(e.code(), trol::code::TROL_ERR_HALTED, "{e}");
    assert!(!robot.is_moving().unwrap(), "the arm still moves");
    let j1 = joints(&mut robot)[0];
    assert!(j1 > 0.31 && j1 < 1.25, "halted on the way: joint 1 at {j1}");

    // The next call works as usual, and the watchdog can be turned off: a motion of about a
    // second, through a silence twice the old limit, ends where it should.
    robot.set_watchdog(Duration::ZERO).unwrap();
    robot.joint(1, -0.5).unwrap();
    std::thread::sleep(Duration::from_millis(600));
    robot.finish().unwrap();
    let end = joints(&mut robot)[0];
    assert!((end - (j1 - 0.5)).abs() < 1e-3, "{end} after {j1}");
}

/// `/state` of the live view at `url`.
#[cfg(feature = "view")]
fn view_state(url: &str) -> serde_json::Value {
    use std::io::{Read, Write};
    let addr = url.trim_start_matches("http://").trim_end_matches('/');
    let mut s = std::net::TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    write!(s, "GET /state HTTP/1.1\r\n\r\n").unwrap();
    let mut reply = String::new();
    s.read_to_string(&mut reply).unwrap();
    serde_json::from_str(reply.split_once("\r\n\r\n").unwrap().1).unwrap()
}

/// CAT1: a command the controller answers only after 0.6 s.
const SLOW: CommandDef = CommandDef {
    code: trol::table::LAST_CAT1_CODE + 1,
    name: "TROLSlow",
    args: &[],
    reply: ReplyKind::Code,
    success: &[],
    wait: Wait::Reply,
    help: "answers late",
};

fn slow(_backend: &mut SimBackend, _call: &Call<'_>) -> Result<Executed, Code> {
    std::thread::sleep(Duration::from_millis(600));
    Ok(Executed::Now(0))
}

#[test]
fn a_reply_that_comes_after_the_timeout_is_dropped_and_the_next_calls_work() {
    let mut pcp = Pcp::new(SimBackend::new(settings()));
    pcp.register(SLOW, Handler::Cat1(slow)).unwrap();
    let mut rig = rig_with(pcp);
    rig.robot.add_command(SLOW).unwrap();
    // 0.2 s for a reply, no repeats: the call fails, and its reply arrives afterwards.
    rig.robot.set_reply_timeout_tenths(2).unwrap();
    let repeats = rig.robot.repeats();
    rig.robot.set_repeats(0);
    let e = rig.robot.call(&SLOW, &[]).unwrap_err();
    assert_eq!(e.code(), TROL_ERR_COMM, "{e}");
    rig.robot.set_repeats(repeats);
    // A call made at once finds the controller silent for longer than an ENQ timeout (it
    // still runs the slow handler): it fails with TROL_ERR_COMM rather than repeating into
    // the silence, or works if the controller answered in time; never the late reply.
    match rig.robot.status() {
        Ok(s) => assert_eq!(s, (true, SUCCESS)),
        Err(e) => assert_eq!(e.code(), TROL_ERR_COMM, "{e}"),
    }
    // The next calls, while the late reply lands and after: each works and gets its own
    // answer, not the late one.
    std::thread::sleep(Duration::from_millis(700));
    for _ in 0..3 {
        assert_eq!(rig.robot.status().unwrap(), (true, SUCCESS));
        rig.robot.speed(40).unwrap();
        std::thread::sleep(Duration::from_millis(300));
    }
}

/// Counts the layer-3 failures it is told of, and gives up.
struct Counting(Arc<std::sync::atomic::AtomicUsize>);

impl trol_comm::ErrorHandlers for Counting {
    fn err_on_send(&mut self, _ctx: &trol_comm::FailureContext<'_>) -> trol_comm::Recovery {
        self.0.fetch_add(1, Ordering::SeqCst);
        trol_comm::Recovery::Fail
    }
}

#[test]
fn adding_a_command_keeps_the_handlers_the_application_installed() {
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

/// A polled Finish is bounded as the one long request was: after the reply timeout the
/// handlers' ErrAppTimeOut decides. Handlers that keep the manual's default for it (the trait's
/// default) wait the motion out; handlers that give up end the wait with TRANS_TIMEOUT.
#[test]
fn an_applications_errapptimeout_bounds_finish() {
    struct GivesUp;
    impl trol_comm::ErrorHandlers for GivesUp {
        fn err_app_timeout(
            &mut self,
            _ctx: &trol_comm::AppTimeoutContext<'_>,
        ) -> trol_comm::TimeoutAction {
            trol_comm::TimeoutAction::Fail
        }
    }
    let told = Arc::new(std::sync::atomic::AtomicUsize::new(0));
    for give_up in [false, true] {
        let mut r = Robot::embedded(SimSettings {
            time_scale: 1.0,
            arm: trol_a465::arm::ArmSettings {
                homed: true,
                ..Default::default()
            },
            ..settings()
        });
        if give_up {
            r.set_handlers(Box::new(GivesUp));
        } else {
            r.set_handlers(Box::new(Counting(told.clone())));
        }
        r.set_reply_timeout_tenths(3).unwrap();
        r.speed(15).unwrap();
        // A motion of about two seconds against a reply timeout of 0.3 s: a poll finds it
        // moving after the timeout however busy the machine.
        r.joint(1, 1.0).unwrap();
        let waited = r.finish();
        if give_up {
            let e = waited.unwrap_err();
            assert_eq!(e.code(), TROL_ERR_COMM, "{e}");
            assert!(e.to_string().contains("TROLFinish"), "{e}");
            assert!(
                r.is_moving().unwrap(),
                "the arm still moves: only the wait ended"
            );
            r.halt().unwrap();
        } else {
            waited.unwrap();
            assert!((joints(&mut r)[0] - 1.0).abs() < 1e-3);
        }
    }
}

/// A controller that answers `polls` FINISH_STATUS polls with "moving", then takes the next
/// request (`answer_last`: false, and goes silent with it; true: goes silent before it) and
/// never says another byte, its end of the line still open (as a cable whose far end died).
fn dies_during_a_wait(polls: usize, take_last: bool) -> Robot {
    let (host, ctl) = trol_port::memory::pair(None);
    std::thread::spawn(move || {
        let mut server = trol_comm::Server::new(ctl, LinkConfig::default());
        let mut answered = 0;
        while answered < polls {
            if let Ok(trol_comm::ServerEvent::Executed) = server
                .serve(Duration::from_secs(5), &mut |_| {
                    Reply::Code(Code(1)).encode()
                })
            {
                answered += 1;
            }
        }
        if take_last {
            let _ = server.serve_deferrable(Duration::from_secs(5), &mut |_, _| None);
        }
        // Silent, the line kept open.
        std::thread::sleep(Duration::from_secs(60));
        drop(server);
    });
    Robot::over(Box::new(host), LinkConfig::default(), None)
}

#[test]
fn a_controller_that_goes_silent_during_a_wait_is_noticed_within_seconds() {
    // Silent between two polls: one unanswered ENQ (1 s), no repeat into silence; the old
    // repeats took 7 s.
    let mut r = dies_during_a_wait(3, false);
    let t = Instant::now();
    let e = r.finish().unwrap_err();
    assert_eq!(e.code(), TROL_ERR_COMM, "{e}");
    assert!(t.elapsed() < Duration::from_secs(5), "{:?}", t.elapsed());
    // Silent with a poll in hand: the poll's short reply timeout (2 s), then one unanswered
    // ENQ; the old wait was the usual reply timeout, 15 s, and more.
    let mut r = dies_during_a_wait(3, true);
    let t = Instant::now();
    let e = r.finish().unwrap_err();
    assert_eq!(e.code(), TROL_ERR_COMM, "{e}");
    assert!(t.elapsed() < Duration::from_secs(10), "{:?}", t.elapsed());
    eprintln!("noticed after {:?}", t.elapsed());
}

#[test]
fn a_halt_reaches_the_arm_while_it_homes() {
    // Real time: homing all axes takes 12 s. The controller answers Home at once and the
    // API waits by polling, so another thread's Halt gets through; the axes stay unhomed.
    let robot = std::sync::Mutex::new(Robot::embedded(SimSettings::default()));
    robot
        .lock()
        .unwrap()
        .call(&trol::table::HOME, &[trol::Value::Int(0)])
        .unwrap();
    std::thread::scope(|s| {
        s.spawn(|| {
            std::thread::sleep(Duration::from_millis(300));
            robot.lock().unwrap().halt().unwrap();
        });
        // A halted Home is a failure (issue 37): the wait for it ends in BIOS_NOT_HOMED.
        let e = trol::wait_idle(&robot).unwrap_err();
        assert_eq!(e.code(), Code(-1), "{e}");
    });
    let e = robot.lock().unwrap().joint(1, 0.1).unwrap_err();
    assert_eq!(e.code(), Code(-1), "{e}");
    // Home from the API, halted from another thread: Home fails.
    std::thread::scope(|s| {
        s.spawn(|| {
            std::thread::sleep(Duration::from_millis(300));
            // The Home call holds the lock only per poll.
            robot.lock().unwrap().halt().unwrap();
        });
        let r = {
            let mut g = robot.lock().unwrap();
            g.call(&trol::table::HOME, &[trol::Value::Int(0)]).unwrap();
            drop(g);
            trol::wait_idle(&robot)
        };
        assert_eq!(r.unwrap_err().code(), Code(-1));
    });
    // Homed in full, the same wait succeeds.
    let mut r = robot.into_inner().unwrap();
    r.call(&trol::table::HOME, &[trol::Value::Int(0)]).unwrap();
    r.finish().unwrap();
    r.joint(1, 0.1).unwrap();
}

/// Repeats follow the version handshake (docs/protocol.md, "A peer of 1998"): none before
/// it; the default once a controller of this protocol answered it; none for a controller that
/// speaks only the manual's protocol, which has no memory of its last request, so that a
/// repeated relative move would run twice there (shown with repeats forced on).
#[test]
fn repeats_go_only_to_a_controller_that_announced_its_memory() {
    use trol_controller::{Controller, Embedded, Mode};
    use trol_proto::link::BlockCheck;
    use trol_proto::transaction::ManualLayer3;
    for manual in [
        None,
        Some(ManualLayer3::ZeroPci),
        Some(ManualLayer3::EchoPci),
    ] {
        for forced in [None, Some(1)] {
            let cfg = LinkConfig {
                check: BlockCheck::Lrc,
                ..steady()
            };
            let (host, ctl) = trol_port::memory::pair(None);
            let mut controller = Controller::new(
                ctl,
                cfg,
                Pcp::new(SimBackend::new(settings())),
                Mode::Server,
            );
            if let Some(pci) = manual {
                controller.speak_manual_only(pci);
            }
            let handle = Embedded::spawn(controller);
            let deaf = Arc::new(AtomicBool::new(false));
            let deaf_after_eot = Arc::new(AtomicBool::new(false));
            let port = Switchable {
                inner: host,
                deaf: deaf.clone(),
                mute: Arc::new(AtomicBool::new(false)),
                deaf_after_eot: deaf_after_eot.clone(),
                drop_next_eot: Arc::new(AtomicBool::new(false)),
            };
            let mut robot = Robot::over(Box::new(port), cfg, None);
            robot.keep(handle);
            // Longer than the controller's failed reply and its reset (3 link timeouts),
            // so that the repeat finds it listening; the line heals before.
            robot.set_reply_timeout_tenths(35).unwrap();
            assert_eq!(robot.repeats(), 0, "no repeats before the handshake");
            if let Some(n) = forced {
                robot.set_repeats(n);
            }
            trol::check_server(&mut robot).unwrap();
            let case = format!("{manual:?}, repeats {forced:?}");
            assert_eq!(robot.speaks_manual_only(), manual.is_some(), "{case}");
            let repeats = forced.unwrap_or(if manual.is_some() { 0 } else { 2 });
            assert_eq!(robot.repeats(), repeats, "{case}");
            assert_eq!(robot.take_notice().is_some(), manual.is_some(), "{case}");
            assert_eq!(robot.take_notice(), None, "said once");
            robot.home(0).unwrap();
            robot.finish().unwrap();
            // The Joint's reply is lost; the line is back before a repeat would go out.
            deaf_after_eot.store(true, Ordering::SeqCst);
            let heal = {
                let deaf = deaf.clone();
                std::thread::spawn(move || {
                    std::thread::sleep(Duration::from_millis(500));
                    deaf.store(false, Ordering::SeqCst);
                })
            };
            let result = robot.joint(1, 0.25);
            heal.join().unwrap();
            if repeats == 0 {
                // The manual's behaviour: the call fails, GetStatus says it ran.
                assert_eq!(result.unwrap_err().code(), TROL_ERR_COMM, "{case}");
                std::thread::sleep(Duration::from_millis(800));
                let _ = robot.flush_input();
                assert_eq!(robot.status().unwrap(), (true, SUCCESS), "{case}");
            } else {
                result.unwrap();
            }
            robot.finish().unwrap();
            let j1 = joints(&mut robot)[0];
            // Only a repeat forced onto a controller without memory runs the move twice.
            let want = if manual.is_some() && repeats > 0 {
                0.5
            } else {
                0.25
            };
            assert!((j1 - want).abs() < 1e-6, "{case}: J1 {j1}");
        }
    }
}

/// A 1998 host (the manual's bare `PCP TROL`) gets the manual's answer and sizes from this
/// controller: `PCP TROL ACTIVE` without a word, the LRC, GetStatus in 4 bytes. A host of
/// this protocol that asks for the LRC by name gets the longer GetStatus.
#[test]
fn a_1998_host_gets_the_manuals_answer_and_sizes() {
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

/// A position in another form than the one asked for answers no GetPosition of this host:
/// TROL_ERR_BAD_RSIZE through `call` too (the interpreter's and the trace's path), not a
/// location printed as if it were the one asked for.
#[test]
fn a_position_in_another_form_is_bad_rsize_on_every_path() {
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

/// A controller's port that stops its process inside a read (as SIGSTOP, a debugger or a
/// suspended machine would) once the request's EOT is among the bytes read: the read returns
/// them `frozen` later.
struct Freezing<P> {
    inner: P,
    armed: Arc<AtomicBool>,
    frozen: Duration,
}

impl<P: Port> Port for Freezing<P> {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.inner.send(bytes)
    }
    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        let n = self.inner.recv(buf, deadline)?;
        if buf[..n].contains(&0x87) && self.armed.swap(false, Ordering::SeqCst) {
            std::thread::sleep(self.frozen);
        }
        Ok(n)
    }
    fn available(&mut self) -> io::Result<usize> {
        self.inner.available()
    }
    fn flush_input(&mut self) -> io::Result<()> {
        self.inner.flush_input()
    }
    fn name(&self) -> String {
        "freezing".into()
    }
}

/// A controller frozen while the request's last byte waits for it, thawed after its host
/// gave up on the call: its timers fire before the bytes are read, so the request its host
/// reported failed is dropped, not executed (issue: a thawed controller ran such a move
/// about 20 s later).
#[test]
fn a_thawed_controller_drops_the_request_its_host_gave_up_on() {
    use trol_controller::{Controller, Embedded, Mode};
    let (host, ctl) = trol_port::memory::pair(None);
    let armed = Arc::new(AtomicBool::new(false));
    let port = Freezing {
        inner: ctl,
        armed: armed.clone(),
        frozen: Duration::from_millis(2500),
    };
    let mut sim = settings();
    sim.arm.homed = true;
    let controller = Controller::new(port, quick(), Pcp::new(SimBackend::new(sim)), Mode::Server);
    let handle = Embedded::spawn(controller);
    let mut robot = Robot::over(Box::new(host), quick(), None);
    robot.keep(handle);
    robot.set_reply_timeout_tenths(10).unwrap();
    robot.set_repeats(0);
    robot.joint(2, 0.1).unwrap();
    robot.finish().unwrap();
    armed.store(true, Ordering::SeqCst);
    let e = robot.joint(1, 0.25).unwrap_err();
    assert_eq!(e.code(), TROL_ERR_COMM, "{e}");
    let failed = robot.last_transaction();
    // The controller thaws and rides out its reset; then the host asks.
    std::thread::sleep(Duration::from_millis(2500));
    let _ = robot.flush_input();
    let status = robot.status_record().unwrap();
    assert_ne!(
        status.transaction, failed,
        "GetStatus speaks of the Joint(1): it ran"
    );
    robot.finish().unwrap();
    let j = joints(&mut robot);
    assert!(
        j[0].abs() < 1e-9,
        "the Joint(1) the host gave up on ran: J1 {}",
        j[0]
    );
    assert!((j[1] - 0.1).abs() < 1e-6);
}

/// A controller port that fails (an I/O error, as a pty whose other end is gone) on the next
/// reply it starts (its ENQ) once `broken` is set: the request has been received and run.
struct BreaksOnReply<P> {
    inner: P,
    broken: Arc<AtomicBool>,
}

impl<P: Port> Port for BreaksOnReply<P> {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        if bytes.first() == Some(&trol_proto::link::control::ENQ)
            && self.broken.load(Ordering::SeqCst)
        {
            return Err(io::Error::new(
                io::ErrorKind::BrokenPipe,
                "the line is gone",
            ));
        }
        self.inner.send(bytes)
    }
    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        self.inner.recv(buf, deadline)
    }
    fn available(&mut self) -> io::Result<usize> {
        self.inner.available()
    }
    fn flush_input(&mut self) -> io::Result<()> {
        self.inner.flush_input()
    }
    fn name(&self) -> String {
        "breaks on reply".into()
    }
}

/// The controller's log holds every request it ran (issue 26, item 5), also one whose reply
/// could not go out because the line failed under it: the entry says it ran, and the count
/// of entries that ran equals the count of requests the PCP server ran.
#[test]
fn the_log_holds_every_execution_even_when_the_line_fails_under_the_reply() {
    use trol_comm::ServerEvent;
    use trol_controller::{Controller, Mode};
    use trol_proto::link::{LinkError, SendError};
    let (host, ctl) = trol_port::memory::pair(None);
    let broken = Arc::new(AtomicBool::new(false));
    let port = BreaksOnReply {
        inner: ctl,
        broken: broken.clone(),
    };
    let mut controller = Controller::new(
        port,
        quick(),
        Pcp::new(SimBackend::new(settings())),
        Mode::Server,
    );
    type Logged = (Vec<u8>, ServerEvent, bool);
    let log: Arc<std::sync::Mutex<Vec<Logged>>> = Arc::default();
    let sink = log.clone();
    controller.set_log(Box::new(move |e| {
        sink.lock()
            .unwrap()
            .push((e.request.to_vec(), e.event, e.executed));
    }));
    let server = std::thread::spawn(move || {
        let failed = loop {
            if let Err(e) = controller.step(Duration::from_millis(20)) {
                break e;
            }
        };
        (controller, failed)
    });
    let mut robot = Robot::over(Box::new(host), quick(), None);
    robot.set_reply_timeout_tenths(5).unwrap();
    robot.home(0).unwrap();
    let Location::Joint(before) = robot.position(Tag::Joint, PosMode::Commanded).unwrap() else {
        panic!("a joint position")
    };
    broken.store(true, Ordering::SeqCst);
    let e = robot.joint(1, 0.1).unwrap_err();
    assert_eq!(e.code(), TROL_ERR_COMM, "{e}");
    let (mut controller, failed) = server.join().unwrap();
    assert_eq!(failed.kind(), io::ErrorKind::BrokenPipe);
    let log = log.lock().unwrap();
    let ran: Vec<_> = log.iter().filter(|(_, _, ran)| *ran).collect();
    assert_eq!(
        ran.len() as u64,
        controller.pcp_mut().handled(),
        "every request run is logged: {log:?}"
    );
    let (request, event, _) = ran.last().unwrap();
    assert_eq!(
        request.first(),
        Some(&trol_proto::application::table::JOINT.code)
    );
    assert_eq!(
        *event,
        ServerEvent::ReplyFailed(LinkError::Send(SendError::Port))
    );
    // And it did run: the arm took the joint's new target.
    let target = controller
        .pcp_mut()
        .backend_mut()
        .arm()
        .planned_at(f64::MAX);
    assert!(
        (target[0] - before[0] - 0.1).abs() < 1e-6,
        "{before:?} -> {target:?}"
    );
}

/// Where a controller dies in [`dead_controller`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Death {
    /// Before the request: not one byte more (a frozen process, a cut line).
    Before,
    /// Mid-request: it acknowledges ENQ, takes the header and says nothing more.
    MidRequest,
    /// With the request complete (EOT): it may have run it; no reply comes.
    RequestComplete,
    /// During its reply: ENQ, acknowledged, then half a header and nothing more.
    DuringReply,
}

/// A controller of this protocol (the simulator behind TROL's server) that serves until
/// `die` is set, then meets the next request as `how` says, its end of the line kept open
/// (as a cable whose far end died), and comes back (a server listening again, the line's
/// leftovers flushed) once `revive` is set.
fn dead_controller(how: Death, die: Arc<AtomicBool>, revive: Arc<AtomicBool>) -> Robot {
    let (host, ctl) = trol_port::memory::pair(None);
    std::thread::spawn(move || {
        let mut pcp = Pcp::new(SimBackend::new(settings()));
        let handle = |pcp: &mut Pcp<SimBackend>, req: &[u8]| match pcp.handle(req) {
            trol_controller::Handled::Reply(r) => r,
            trol_controller::Handled::Pending => Reply::Code(Code(0)).encode(),
        };
        let mut server = trol_comm::Server::new(ctl, LinkConfig::default());
        while !die.load(Ordering::SeqCst) {
            let _ = server.serve(Duration::from_millis(20), &mut |req| handle(&mut pcp, req));
        }
        let mut port = server.into_port();
        let far = Instant::now() + Duration::from_secs(30);
        let byte = |port: &mut trol_port::memory::MemoryLine| {
            let mut b = [0u8; 1];
            while port.recv(&mut b, far).unwrap_or(0) == 0 {
                if Instant::now() > far {
                    return None;
                }
            }
            Some(b[0])
        };
        const ENQ: u8 = 0x99;
        const ACK: u8 = 0xB4;
        const SOH: u8 = 0x1E;
        const EOT: u8 = 0x87;
        if how != Death::Before {
            while byte(&mut port) != Some(ENQ) {}
            port.send(&[ACK]).unwrap();
            let mut header = [0u8; 10];
            for b in header.iter_mut() {
                *b = byte(&mut port).unwrap_or(0);
            }
            if how != Death::MidRequest {
                port.send(&[ACK]).unwrap();
                let len = usize::from(u16::from_le_bytes([header[1], header[2]]));
                if len > 2 {
                    // One frame (every request here is short): data, frame-ID, BCC, end.
                    for _ in 0..len - 2 + 5 {
                        byte(&mut port);
                    }
                    port.send(&[ACK]).unwrap();
                }
                while byte(&mut port).is_some_and(|b| b != EOT) {}
                if how == Death::DuringReply {
                    port.send(&[ENQ]).unwrap();
                    byte(&mut port);
                    port.send(&[SOH, 2, 0, 1]).unwrap();
                }
            }
        }
        // Dead, the line open, until it comes back.
        while !revive.load(Ordering::SeqCst) {
            std::thread::sleep(Duration::from_millis(10));
        }
        std::thread::sleep(Duration::from_millis(200));
        let _ = port.flush_input();
        let mut server = trol_comm::Server::new(port, LinkConfig::default());
        let stop = Instant::now() + Duration::from_secs(60);
        while Instant::now() < stop {
            let _ = server.serve(Duration::from_millis(20), &mut |req| handle(&mut pcp, req));
        }
    });
    let mut robot = Robot::over(Box::new(host), LinkConfig::default(), None);
    trol::check_server(&mut robot).expect("the version check");
    robot
}

/// No call waits more than 3 s for a dead controller, whatever it was doing (issue 38): the
/// simulator says it answers within 0.5 s (TROLGetReplyTime, asked by the version check),
/// so a call waits 1.5 s for its reply (`trol::prompt_reply_timeout`) and then one ENQ
/// timeout (1 s) for its repeat; a controller that stops mid-request is not repeated into
/// (the request never reached its EOT, so it did not run). The line stays open throughout (an in-memory line
/// that nobody closes, as a cable whose far end died); once the controller is back, the
/// next call works. The times are docs/reliability.md's.
#[test]
fn no_call_waits_more_than_3_s_for_a_dead_controller() {
    for how in [
        Death::Before,
        Death::MidRequest,
        Death::RequestComplete,
        Death::DuringReply,
    ] {
        let die = Arc::new(AtomicBool::new(false));
        let revive = Arc::new(AtomicBool::new(false));
        let mut robot = dead_controller(how, die.clone(), revive.clone());
        robot.home(0).unwrap();
        robot.finish().unwrap();
        die.store(true, Ordering::SeqCst);
        // Let the controller's loop see it between two transactions.
        std::thread::sleep(Duration::from_millis(100));
        let t = Instant::now();
        let e = robot.joint(1, 0.1).unwrap_err();
        let took = t.elapsed();
        eprintln!("{how:?}: TROLJoint failed after {took:?}: {e}");
        assert_eq!(e.code(), TROL_ERR_COMM, "{how:?}: {e}");
        // At most 3.0 s by the timeouts; the bound leaves a loaded machine its scheduling.
        assert!(took < Duration::from_secs(4), "{how:?}: {took:?}");
        revive.store(true, Ordering::SeqCst);
        std::thread::sleep(Duration::from_millis(400));
        let back = robot.position(Tag::Joint, PosMode::Actual);
        assert!(back.is_ok(), "{how:?}: the next call: {back:?}");
    }
}

/// A repeat that reaches a controller which remembers no request (it restarted after the
/// host first sent it) is refused unrun, and the controller's log names that request and
/// its answer (it said `undecodable request []`, the entry of no request, issue 38); the
/// answer's text says the controller cannot tell whether it ran, not that a link to the
/// robot was lost.
#[test]
fn a_refused_repeat_is_logged_by_its_own_name() {
    use trol_comm::{Driver, receive_data, send_data};
    use trol_controller::{Controller, Mode};
    let (host, ctl) = trol_port::memory::pair(None);
    let mut controller = Controller::new(
        ctl,
        LinkConfig::default(),
        Pcp::new(SimBackend::new(settings())),
        Mode::Server,
    );
    let logged = Arc::new(std::sync::Mutex::new(Vec::new()));
    let keep = logged.clone();
    controller.set_log(Box::new(move |e| {
        keep.lock().unwrap().push(format!(
            "{} -> {}",
            e.catalog.request_text(e.request),
            e.catalog
                .reply_text(e.request, e.reply, trol_sim::SIM_CODES)
        ));
    }));
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    let server = std::thread::spawn(move || controller.run(&flag));
    let mut driver = Driver::new(host);
    let mut link = trol_proto::Link::new(LinkConfig::default());
    // TROLJoint(1, 0.25), marked REPEAT under number 7.
    let joint = trol_proto::application::record::encode(
        &trol::table::JOINT,
        &[trol::Value::Int(1), trol::Value::Real(0.25)],
    )
    .unwrap();
    send_data(&mut driver, &mut link, &joint, 0x0107).unwrap();
    let (_, reply) = receive_data(&mut driver, &mut link, Duration::from_secs(10)).unwrap();
    assert_eq!(reply, Reply::Code(TROL_ERR_ROBOT_UNSURE).encode());
    let deadline = Instant::now() + Duration::from_secs(10);
    while logged.lock().unwrap().is_empty() && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(10));
    }
    stop.store(true, Ordering::SeqCst);
    let _ = server.join();
    let log = logged.lock().unwrap().join("\n");
    assert!(
        log.starts_with("TROLJoint 1 0.25 -> -32054 (TROL_ERR_ROBOT_UNSURE)"),
        "{log}"
    );
    assert!(!log.contains("undecodable"), "{log}");
    let meaning = TROL_ERR_ROBOT_UNSURE
        .meaning(trol_sim::SIM_CODES)
        .unwrap_or_default();
    assert!(
        meaning.contains("cannot tell whether the command ran"),
        "{meaning}"
    );
}

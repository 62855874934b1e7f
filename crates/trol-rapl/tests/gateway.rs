//! The RAPL-II backend against the simulated C500 over an in-memory line paced at the
//! profile's baud rate: the profile's variants configured alike and mismatched, the safe
//! default, and faults on the line.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use trol_a465::arm::{Arm, ArmSettings};
use trol_controller::backend::{Backend, BackendError, PosMode, Target};
use trol_port::Port;
use trol_port::faulty::{FaultConfig, Faulty};
use trol_proto::application::{LocName, Location, Tag};
use trol_rapl::backend::{NO_ANGLES, NO_JOINT_UNITS};
use trol_rapl::profile::{Ack, Entry, Units};
use trol_rapl::{C500, Profile, RaplBackend};

mod common;
use common::{Mangle, robot, start, start_scaled};

fn wait_idle(b: &mut RaplBackend) {
    for _ in 0..2000 {
        if !b.moving().unwrap() {
            return;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    panic!("the arm did not stop");
}

fn name(s: &str) -> LocName {
    LocName::new(s).unwrap()
}

/// What a user checks: a move by name arrives, a cartesian move arrives where asked, the
/// position reads back in every form.
fn drive(b: &mut RaplBackend) {
    assert_eq!(b.speed(50).unwrap(), 0);
    assert_eq!(
        b.move_to(&Target::Name(name("test_001")), false).unwrap(),
        0
    );
    wait_idle(b);
    let c = b
        .position(Tag::Cart, PosMode::Commanded)
        .unwrap()
        .to_array6();
    assert!(
        (c[0] - 400.0).abs() < 1e-3 && (c[2] - 150.0).abs() < 1e-3,
        "{c:?}"
    );
    let target = [380.0, 20.0, 200.0, 0.0, std::f64::consts::FRAC_PI_2, 0.0];
    let loc = Location::from_array6(Tag::Cart, target);
    assert_eq!(b.move_to(&Target::Location(loc), true).unwrap(), 0);
    wait_idle(b);
    let c = b.position(Tag::Cart, PosMode::Actual).unwrap().to_array6();
    for i in 0..3 {
        assert!((c[i] - target[i]).abs() < 0.1, "{c:?}");
    }
    let j = b
        .position(Tag::Joint, PosMode::Commanded)
        .unwrap()
        .to_array6();
    let p = b
        .position(Tag::Prec, PosMode::Commanded)
        .unwrap()
        .to_array6();
    let from_counts = trol_a465::model::counts_to_joints(&p);
    for i in 0..6 {
        assert!(
            (j[i] - from_counts[i]).abs() < 1e-3,
            "{j:?} {from_counts:?}"
        );
    }
    assert_eq!(
        b.move_to(&Target::Name(name("nowhere")), false)
            .unwrap_err()
            .to_string(),
        BackendError::UnknownLocation(name("nowhere")).to_string()
    );
}

#[test]
fn every_variant_configured_alike_drives_the_arm() {
    let mut variants = Vec::new();
    for entry in [Entry::Aci, Entry::AciEmpty, Entry::Terminal] {
        variants.push(Profile {
            entry,
            ..Profile::simulator()
        });
    }
    for ack in [Ack::Required, Ack::Never] {
        variants.push(Profile {
            ack,
            ..Profile::simulator()
        });
    }
    variants.push(Profile {
        extra_after_digit: 0,
        help_at_start: false,
        ..Profile::simulator()
    });
    variants.push(Profile {
        units: Units::Inch,
        angles: "roll -pitch yaw".into(),
        joint_units: "radians".into(),
        baud: 9600,
        ..Profile::simulator()
    });
    for sim in variants {
        let described = {
            let arm = Arm::new(ArmSettings::default());
            C500::new(sim.clone(), arm, Vec::new()).describe()
        };
        let (port, _sim) = start(sim.clone(), None);
        let mut b =
            RaplBackend::connect(port, described).unwrap_or_else(|e| panic!("{sim:?}: {e}"));
        drive(&mut b);
    }
}

#[test]
fn the_reader_tolerates_what_it_is_meant_to() {
    // The gateway allows four extra bytes, the controller sends none; the gateway accepts
    // an ACK or none, the controller sends none; units auto, STATUS says inches.
    let sim = Profile {
        extra_after_digit: 0,
        ack: Ack::Never,
        units: Units::Inch,
        ..Profile::simulator()
    };
    let (port, _sim) = start(sim, None);
    let gw = Profile {
        units: Units::Auto,
        ..Profile::simulator()
    };
    let mut b = RaplBackend::connect(port, gw).unwrap();
    drive(&mut b);
}

#[test]
fn mismatched_profiles_fail_clearly_and_move_nothing() {
    // An ACK required, none sent: the session does not open.
    let (port, sim) = start(
        Profile {
            ack: Ack::Never,
            ..Profile::simulator()
        },
        None,
    );
    let gw = Profile {
        ack: Ack::Required,
        ..Profile::simulator()
    };
    let e = RaplBackend::connect(port, gw).err().unwrap().to_string();
    assert!(e.contains("ack = \"auto\""), "{e}");
    assert!(!sim.ran().iter().any(|l| l.starts_with("MOVE")));

    // Extra bytes the gateway does not expect: the line is cancelled before it runs.
    let (port, sim) = start(Profile::simulator(), None);
    let gw = Profile {
        extra_after_digit: 0,
        ..Profile::simulator()
    };
    let mut b = RaplBackend::connect(port, gw).unwrap();
    let e = b.joint(1, 0.5).unwrap_err();
    assert!(matches!(e, BackendError::Link(_)), "{e}");
    assert!(e.to_string().contains("raise extra_after_digit"), "{e}");
    assert!(
        !sim.ran().iter().any(|l| l.starts_with("JOINT")),
        "{:?}",
        sim.ran()
    );
    // The session is back at the prompt: a command without digits works.
    assert_eq!(b.ready().unwrap(), 0);

    // Other units than the controller's: refused at the opening.
    let (port, _sim) = start(Profile::simulator(), None);
    let gw = Profile {
        units: Units::Inch,
        ..Profile::simulator()
    };
    let e = RaplBackend::connect(port, gw).err().unwrap().to_string();
    assert!(e.contains("STATUS says METRIC UNITS"), "{e}");
}

/// A profile written by `trol sim --rapl --print-profile` says so (`simulated = true`), and
/// drives only the simulator: a controller that is not it refuses the session at the opening,
/// with what to do, before anything that moves (issue 37, item 8: a simulator's profile
/// turned a real J6 by 164 degrees).
#[test]
fn a_simulators_profile_drives_only_the_simulator() {
    let describes = |p: &Profile| {
        trol_rapl::C500::new(
            p.clone(),
            trol_a465::arm::Arm::new(Default::default()),
            Vec::new(),
        )
        .describe()
    };
    let printed = describes(&Profile::simulator());
    assert!(printed.simulated);
    let text = printed.to_toml();
    assert!(text.contains("simulated = true"), "{text}");
    assert!(text.contains("SIMULATED C500"), "{text}");
    assert_eq!(Profile::parse(&text).unwrap(), printed);
    // Against the simulator: it opens.
    let (port, _sim) = start(Profile::simulator(), None);
    RaplBackend::connect(port, printed.clone()).unwrap();
    // Against a controller that does not name itself (a real C500): refused, nothing moved.
    let real = Profile {
        twin: trol_rapl::profile::Twin {
            names_itself: false,
            ..Default::default()
        },
        ..Profile::simulator()
    };
    let (port, sim) = start(real.clone(), None);
    let e = RaplBackend::connect(port, printed.clone())
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("simulated = true"), "{e}");
    assert!(e.contains("trol rapl probe"), "{e}");
    assert!(
        sim.ran()
            .iter()
            .all(|l| ["STATUS", "NOH", "NOHELP", "QZXTROL"]
                .iter()
                .any(|w| l.starts_with(w))),
        "{:?}",
        sim.ran()
    );
    // The same file without the line: the user's decision, it opens.
    let (port, _sim) = start(real, None);
    let confirmed = Profile {
        simulated: false,
        ..printed
    };
    RaplBackend::connect(port, confirmed).unwrap();
}

#[test]
fn the_safe_default_refuses_what_a_wrong_guess_would_turn_into_a_wrong_motion() {
    let (port, sim) = start(Profile::simulator(), None);
    let mut b = RaplBackend::connect(port, Profile::default()).unwrap();
    let before = b.position(Tag::Joint, PosMode::Commanded).unwrap();
    let loc = Location::from_array6(Tag::Cart, [380.0, 20.0, 200.0, 0.0, 1.5, 0.0]);
    assert_eq!(b.move_to(&Target::Location(loc), false).unwrap(), NO_ANGLES);
    assert_eq!(b.ma([0.1; 6]).unwrap(), NO_JOINT_UNITS);
    assert_eq!(b.mi([0.1; 6]).unwrap(), NO_JOINT_UNITS);
    assert_eq!(
        b.set_tool([0.0, 0.0, 100.0, 0.0, 0.0, 0.0]).unwrap(),
        NO_ANGLES
    );
    let meaning = |v: i16| {
        trol_rapl::RAPL_CODES
            .iter()
            .find(|c| c.value == v)
            .unwrap()
            .meaning
    };
    assert!(meaning(NO_ANGLES).contains("set `angles`"));
    assert!(meaning(NO_JOINT_UNITS).contains("set `joint_units`"));
    assert!(b.log_lines().iter().any(|l| l.contains("set angles")));
    // Nothing moved, nothing was sent that could.
    let after = b.position(Tag::Joint, PosMode::Commanded).unwrap();
    assert_eq!(before, after);
    assert!(
        !sim.ran()
            .iter()
            .any(|l| l.starts_with("MOVE") || l.starts_with("MA")),
        "{:?}",
        sim.ran()
    );
    // What needs no convention works: a named location, a joint in degrees.
    assert_eq!(
        b.move_to(&Target::Name(name("test_001")), false).unwrap(),
        0
    );
}

#[test]
fn a_noisy_line_never_runs_a_damaged_command_and_says_what_ran() {
    // Bit errors and dropped, doubled bytes both ways; each JOINT line is unique, so the
    // controller's log tells which ran.
    let faults = |seed| FaultConfig {
        bit_error_rate: 2e-4,
        drop_rate: 5e-4,
        duplicate_rate: 5e-4,
        ..FaultConfig::seeded(seed)
    };
    let (port, sim) = start(Profile::simulator(), Some(faults(7)));
    let port: Box<dyn Port> = Box::new(Faulty::new(port, faults(8)));
    let mut b = match RaplBackend::connect(port, Profile::simulator()) {
        Ok(b) => b,
        Err(e) => panic!("{e}"),
    };
    let (mut ok, mut not_run, mut unsure) = (0, 0, 0);
    for i in 0..60u32 {
        let deg = 0.01 * f64::from(i + 1);
        let line = format!("JOINT 6,{}", trol_rapl::text::num(deg));
        let r = b.joint(6, deg.to_radians());
        let ran = sim.ran().iter().filter(|l| **l == line).count();
        match r {
            Ok(0) => {
                ok += 1;
                assert_eq!(ran, 1, "{line} answered success");
            }
            Ok(c) => panic!("{line}: {c}"),
            Err(BackendError::Link(e)) => {
                not_run += 1;
                assert_eq!(ran, 0, "{line} said not run: {e}");
            }
            Err(BackendError::Unsure(_)) => unsure += 1,
            Err(e) => panic!("{e}"),
        }
        // No line ran that was not typed: every JOINT the controller ran is one we sent.
        for l in sim.ran() {
            if let Some(v) = l.strip_prefix("JOINT 6,") {
                let v: f64 = v.parse().unwrap_or(-1.0);
                assert!(
                    (v * 100.0 - (v * 100.0).round()).abs() < 1e-6 && v > 0.0 && v < 0.62,
                    "a damaged line ran: {l}"
                );
            }
        }
    }
    assert!(ok > 30, "ok {ok}, not run {not_run}, unsure {unsure}");
    assert!(not_run + unsure > 0, "the faults did nothing");
}

#[test]
fn a_controller_that_goes_silent_mid_motion_ends_the_wait_with_a_link_error() {
    let (port, sim) = start(Profile::simulator(), None);
    let mut b = RaplBackend::connect(port, Profile::simulator()).unwrap();
    assert_eq!(b.joint(1, 1.5).unwrap(), 0);
    drop(sim);
    let e = b.moving().unwrap_err();
    assert!(
        matches!(e, BackendError::Link(_) | BackendError::Unsure(_)),
        "{e}"
    );
}

/// A port that, once armed, loses the next `J` it sends (a byte of a JOINT line lost on the
/// line; the reads before the motion line have none).
struct LoseNextByte {
    inner: Box<dyn Port>,
    armed: Arc<AtomicBool>,
}

impl Port for LoseNextByte {
    fn send(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        match bytes.split_first() {
            Some((b'J', rest)) if self.armed.swap(false, Ordering::SeqCst) => self.inner.send(rest),
            _ => self.inner.send(bytes),
        }
    }
    fn recv(&mut self, buf: &mut [u8], deadline: std::time::Instant) -> std::io::Result<usize> {
        self.inner.recv(buf, deadline)
    }
    fn available(&mut self) -> std::io::Result<usize> {
        self.inner.available()
    }
    fn flush_input(&mut self) -> std::io::Result<()> {
        self.inner.flush_input()
    }
    fn name(&self) -> String {
        self.inner.name()
    }
}

#[test]
fn faults_on_the_rapl_line_end_in_defined_codes_and_get_status_tells_what_ran() {
    use trol_proto::application::code::{TROL_ERR_ROBOT, TROL_ERR_ROBOT_UNSURE};
    // Short waits, so a lost prompt is given up for lost within a second.
    let profile = Profile {
        reply_timeout_ms: 500,
        motion_timeout_s: 1,
        ..Profile::simulator()
    };
    let (port, sim) = start(profile.clone(), None);
    let lose_prompt = Arc::new(AtomicBool::new(false));
    let lose_byte = Arc::new(AtomicBool::new(false));
    let port = Box::new(LoseNextByte {
        inner: port,
        armed: lose_byte.clone(),
    });
    // While armed, the prompt (two `>`) after the echo of `JOINT 6` vanishes: the motion
    // line's answer, not that of the reads before it.
    let armed = lose_prompt.clone();
    let (mut seen, mut dropped) = (Vec::new(), 0);
    let port = Box::new(Mangle {
        inner: port,
        f: Box::new(move |v: &mut Vec<u8>| {
            if !armed.load(Ordering::SeqCst) {
                seen.clear();
                return;
            }
            seen.extend_from_slice(v);
            if seen.windows(7).any(|w| w == b"JOINT 6") {
                v.retain(|b| {
                    let drop = *b == b'>' && dropped < 2;
                    dropped += usize::from(drop);
                    !drop
                });
                if dropped == 2 {
                    dropped = 0;
                    seen.clear();
                    armed.store(false, Ordering::SeqCst);
                }
            }
        }),
    });
    let backend = RaplBackend::connect(port, profile).unwrap();
    let cfg = trol_proto::link::LinkConfig::default();
    let (line, handle) = trol_controller::embedded_with(trol_controller::Pcp::new(backend), cfg);
    let mut robot = trol::Robot::over(Box::new(line), cfg, Some(handle));
    robot.set_codes(trol_rapl::RAPL_CODES);
    let ran = |line: &str| sim.ran().iter().filter(|l| *l == line).count();

    // An error line: refused with the controller's meaning; the BIOS was called.
    let e = robot.joint(1, 3.3).unwrap_err();
    assert_eq!(e.code().0, trol_a465::arm::code::JOINT_LIMIT, "{e}");
    assert_eq!(
        robot.status().unwrap(),
        (
            true,
            trol_proto::application::Code(trol_a465::arm::code::JOINT_LIMIT)
        )
    );

    // A lost prompt after a motion was typed whole: it ran, nobody can be sure, so the call
    // says TROL_ERR_ROBOT_UNSURE and GetStatus says the BIOS was called.
    lose_prompt.store(true, Ordering::SeqCst);
    let e = robot.joint(6, 0.11).unwrap_err();
    assert_eq!(e.code(), TROL_ERR_ROBOT_UNSURE, "{e}");
    assert_eq!(ran("JOINT 6,6.3025"), 1, "{:?}", sim.ran());
    assert_eq!(robot.status().unwrap(), (true, TROL_ERR_ROBOT_UNSURE));
    // The session resynchronised: the next call works.
    robot.finish().unwrap();
    robot.speed(40).unwrap();

    // A byte of a command lost on its way out: the echo never comes, the line is cancelled
    // before its terminator, so it surely did not run, and GetStatus says so.
    lose_byte.store(true, Ordering::SeqCst);
    let e = robot.joint(6, 0.12).unwrap_err();
    assert_eq!(e.code(), TROL_ERR_ROBOT, "{e}");
    assert!(
        !sim.ran().iter().any(|l| l.starts_with("JOINT 6,6.87")),
        "{:?}",
        sim.ran()
    );
    assert_eq!(robot.status().unwrap(), (false, TROL_ERR_ROBOT));
    robot.joint(6, 0.12).unwrap();
    robot.finish().unwrap();
    assert_eq!(ran("JOINT 6,6.8755"), 1, "{:?}", sim.ran());
}

/// A long motion at time scale 5 (about 10 s of wall time) that Halt must stop short.
fn long_joint_motion(r: &mut trol::Robot, sim: &common::Sim) -> [f64; 6] {
    r.speed(2).unwrap();
    let before = sim.planned_end();
    r.joint(1, 1.5).unwrap_or_else(|e| {
        // The call itself may be the one whose answer is lost.
        assert_eq!(
            e.code(),
            trol_proto::application::code::TROL_ERR_ROBOT_UNSURE,
            "{e}"
        );
    });
    for _ in 0..4000 {
        if sim.moving() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    assert!(sim.moving(), "the motion did not start");
    before
}

fn halted_short(r: &mut trol::Robot, sim: &common::Sim, before: [f64; 6]) {
    assert!(
        sim.moving(),
        "Halt came after the motion ended: the test proves nothing"
    );
    r.halt().unwrap();
    r.finish().unwrap();
    let turned = (sim.planned_end()[0] - before[0]).abs();
    assert!(
        turned < 1.4,
        "Halt did not stop the arm: joint 1 turned {turned} of 1.5 rad"
    );
}

#[test]
fn halt_gets_through_an_xoff_that_no_xon_follows() {
    let profile = Profile {
        reply_timeout_ms: 500,
        ..Profile::simulator()
    };
    let (port, sim) = start_scaled(profile.clone(), true, None, 5.0);
    let armed = Arc::new(AtomicBool::new(false));
    let xoff = armed.clone();
    let port = Box::new(Mangle {
        inner: port,
        f: Box::new(move |v: &mut Vec<u8>| {
            if !v.is_empty() && xoff.swap(false, Ordering::SeqCst) {
                v.push(trol_rapl::session::XOFF);
            }
        }),
    });
    let mut r = robot(port, profile);
    let before = long_joint_motion(&mut r, &sim);
    // One XOFF byte from the controller (noise, or an XON lost after it).
    armed.store(true, Ordering::SeqCst);
    r.position(Tag::Joint, PosMode::Actual).unwrap();
    halted_short(&mut r, &sim, before);
    // The XOFF is given up: the next commands go out.
    r.speed(10).unwrap();
    r.position(Tag::Joint, PosMode::Commanded).unwrap();
}

#[test]
fn a_lost_prompt_after_a_motion_holds_halt_no_longer_than_a_short_command() {
    // The profile's motion timeout stays at its default (120 s): the motion line waits only
    // the short reply timeout, so Halt reaches the arm while it still moves.
    let profile = Profile {
        reply_timeout_ms: 500,
        ..Profile::simulator()
    };
    let (port, sim) = start_scaled(profile.clone(), true, None, 5.0);
    let (mut seen, mut dropped) = (Vec::new(), 0);
    let port = Box::new(Mangle {
        inner: port,
        f: Box::new(move |v: &mut Vec<u8>| {
            seen.extend_from_slice(v);
            if dropped < 2 && seen.windows(7).any(|w| w == b"JOINT 1") {
                v.retain(|b| {
                    if *b == b'>' && dropped < 2 {
                        dropped += 1;
                        false
                    } else {
                        true
                    }
                });
            }
        }),
    });
    let mut r = robot(port, profile);
    let before = long_joint_motion(&mut r, &sim);
    assert!(sim.ran().iter().any(|l| l.starts_with("JOINT 1,")));
    halted_short(&mut r, &sim, before);
}

#[test]
fn a_scratch_location_not_confirmed_sends_no_move() {
    let (port, sim) = start(Profile::simulator(), None);
    let armed = Arc::new(AtomicBool::new(false));
    let flag = armed.clone();
    let mut seen = Vec::new();
    let port = Box::new(Mangle {
        inner: port,
        f: Box::new(move |v: &mut Vec<u8>| {
            seen.extend_from_slice(v);
            // While armed: an answer to POINT that is not its success form.
            if flag.load(Ordering::SeqCst) && seen.windows(6).any(|w| w == b"POINT ") {
                if let Some(i) = v.iter().position(|b| *b == trol_rapl::session::ACK) {
                    v.splice(i..i, b"\r\nWHAT?".iter().copied());
                    flag.store(false, Ordering::SeqCst);
                    seen.clear();
                }
            }
            if !flag.load(Ordering::SeqCst) {
                seen.clear();
            }
        }),
    });
    let mut r = robot(port, Profile::simulator());
    let a = [380.0, 20.0, 200.0, 0.0, std::f64::consts::FRAC_PI_2, 0.0];
    r.move_ii(&Location::from_array6(Tag::Cart, a), false)
        .unwrap();
    r.finish().unwrap();
    let at_a = sim.planned_end();
    let moves = |sim: &common::Sim| sim.ran().iter().filter(|l| l.starts_with("MOVE")).count();
    let n = moves(&sim);
    armed.store(true, Ordering::SeqCst);
    let b = [420.0, -30.0, 180.0, 0.0, std::f64::consts::FRAC_PI_2, 0.0];
    let e = r
        .move_ii(&Location::from_array6(Tag::Cart, b), false)
        .unwrap_err();
    // Not run: the arm stays, and no MOVE went out (neither to B nor to A's old target).
    assert_eq!(
        e.code(),
        trol_proto::application::code::TROL_ERR_ROBOT,
        "{e}"
    );
    assert_eq!(moves(&sim), n, "{:?}", sim.ran());
    r.finish().unwrap();
    assert_eq!(sim.planned_end(), at_a);
    // (The controller's words are in the log: `c500: ... printed `WHAT?` ...`.)
    // The next call works.
    r.move_ii(&Location::from_array6(Tag::Cart, b), false)
        .unwrap();
    r.finish().unwrap();
}

/// Teaching through the RAPL-II backend (issue 28, docs/teach.md), on every variant
/// configured alike: HERE, POINT, DLOCN and LISTL, each confirmed by LISTL before it counts
/// as done; a taught location is moved to; what RAPL-II cannot hold (joint angles, a name
/// the backend uses for its scratch locations) is refused before anything is sent.
#[test]
fn teaching_maps_to_here_point_dlocn_and_listl_on_every_variant() {
    use trol_rapl::backend::UNSUPPORTED;
    for sim_profile in [
        Profile::simulator(),
        Profile {
            ack: Ack::Never,
            ..Profile::simulator()
        },
        Profile {
            units: Units::Inch,
            angles: "roll -pitch yaw".into(),
            joint_units: "radians".into(),
            baud: 9600,
            ..Profile::simulator()
        },
    ] {
        let described = {
            let arm = Arm::new(ArmSettings::default());
            C500::new(sim_profile.clone(), arm, Vec::new()).describe()
        };
        let (port, sim) = start(sim_profile.clone(), None);
        let mut b = RaplBackend::connect(port, described).unwrap();
        let case = format!("{sim_profile:?}");
        // Somewhere, taught two ways.
        let target = [380.0, 20.0, 200.0, 0.0, std::f64::consts::FRAC_PI_2, 0.0];
        let loc = Location::from_array6(Tag::Cart, target);
        assert_eq!(b.move_to(&Target::Location(loc), false).unwrap(), 0);
        wait_idle(&mut b);
        let at = b
            .position(Tag::Joint, PosMode::Commanded)
            .unwrap()
            .to_array6();
        assert_eq!(b.here(name("p1"), Tag::Cart).unwrap(), 0, "{case}");
        assert_eq!(b.here(name("#pp"), Tag::Prec).unwrap(), 0, "{case}");
        let up = Location::from_array6(Tag::Cart, [420.0, -60.0, 320.0, 0.0, 1.5, 0.0]);
        assert_eq!(b.define(name("up"), &up).unwrap(), 0, "{case}");
        let names: Vec<String> = b
            .locations()
            .unwrap()
            .into_iter()
            .map(|(n, _)| n.as_str().to_string())
            .collect();
        assert_eq!(names, ["#pp", "p1", "test_001", "up"], "{case}");
        let listed = b.locations().unwrap();
        let p1 = listed[1].1.to_array6();
        for i in 0..3 {
            assert!((p1[i] - target[i]).abs() < 0.05, "{case}: {p1:?}");
        }
        // Away and back to each taught form.
        for n in ["p1", "#pp"] {
            assert_eq!(b.move_to(&Target::Name(name("up")), false).unwrap(), 0);
            wait_idle(&mut b);
            assert_eq!(b.move_to(&Target::Name(name(n)), false).unwrap(), 0);
            wait_idle(&mut b);
            let back = b
                .position(Tag::Joint, PosMode::Commanded)
                .unwrap()
                .to_array6();
            for i in 0..6 {
                assert!(
                    (back[i] - at[i]).abs() < 2e-3,
                    "{case} {n}: {back:?} {at:?}"
                );
            }
        }
        // Delete: gone, and deleting it again is TROL_ERR_LOCATION.
        assert_eq!(b.delete_location(name("up")).unwrap(), 0);
        assert!(matches!(
            b.delete_location(name("up")),
            Err(BackendError::UnknownLocation(_))
        ));
        // Refused before sending.
        let sent = sim.ran().len();
        assert_eq!(b.here(name("pj"), Tag::Joint).unwrap(), UNSUPPORTED);
        assert_ne!(b.here(name("t1"), Tag::Cart).unwrap(), 0);
        assert_eq!(sim.ran().len(), sent, "{:?}", &sim.ran()[sent..]);
        // The C500 keeps its table itself, and whether it outlives a power cycle cannot be
        // told: Save is refused rather than reported done.
        assert_eq!(b.save_locations().unwrap(), UNSUPPORTED);
        let ran = sim.ran();
        for word in ["HERE P1", "HERE #PP", "POINT UP", "DLOCN UP", "LISTL"] {
            assert!(
                ran.iter().any(|l| l.starts_with(word)),
                "{case}: {word} in {ran:?}"
            );
        }
    }
}

/// The lines the controller ran after the first `from`.
fn ran_since(sim: &common::Sim, from: usize) -> Vec<String> {
    sim.ran().into_iter().skip(from).collect()
}

/// Issue 43: a motion right after another was seen to end goes without a read first (the
/// STATUS that showed the end, and the end itself, stand in for STATUS and W0); a relative
/// motion is computed from that end. What the arm does meanwhile is still the arm's to say:
/// power lost since is refused by the motion's own reply, and nothing moves.
#[test]
fn a_motion_after_a_seen_end_goes_at_once_and_a_lost_power_still_refuses_it() {
    let (port, sim) = start(Profile::simulator(), None);
    let mut b = RaplBackend::connect(port, Profile::simulator()).unwrap();
    // However busy the machine running this test, the sighting stands (a wall-clock bound
    // would make the test depend on the machine's load).
    b.set_seen_for(std::time::Duration::from_secs(600));
    assert_eq!(b.ma([0.0, 0.2, 0.3, 0.0, 0.0, 0.0]).unwrap(), 0);
    wait_idle(&mut b);
    let mark = sim.ran().len();
    assert_eq!(b.joint(6, 0.1).unwrap(), 0);
    let typed = ran_since(&sim, mark);
    assert!(
        typed.first().is_some_and(|l| l.starts_with("JOINT 6,")),
        "the motion first, no read before it: {typed:?}"
    );
    wait_idle(&mut b);
    let q = sim.planned_end();
    assert!((q[5] - 0.1).abs() < 1e-3, "{q:?}");
    // Power lost while it stands, and no word of it on the line (this controller prints
    // none): the next motion is refused by the controller, and the arm stays.
    sim.emergency_stop();
    while sim.has_power() {
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    let before = sim.planned_end();
    let c = match b.joint(6, -0.1) {
        Ok(c) => c,
        Err(BackendError::Refused(c)) => c,
        Err(e) => panic!("{e}"),
    };
    assert_eq!(c, trol_rapl::backend::ARM_POWER, "{:?}", b.log_lines());
    assert_eq!(sim.planned_end(), before);
    assert!(!sim.moving());
}

/// What was seen stands in for a read only for a moment ([`trol_rapl::backend::SEEN_FOR`]):
/// after that, STATUS and W0 are read before the motion.
#[test]
fn an_old_sighting_is_read_again_before_a_motion() {
    let (port, sim) = start(Profile::simulator(), None);
    let mut b = RaplBackend::connect(port, Profile::simulator()).unwrap();
    assert_eq!(b.ma([0.0, 0.2, 0.3, 0.0, 0.0, 0.0]).unwrap(), 0);
    wait_idle(&mut b);
    std::thread::sleep(trol_rapl::backend::SEEN_FOR + std::time::Duration::from_millis(50));
    let mark = sim.ran().len();
    assert_eq!(b.joint(6, 0.1).unwrap(), 0);
    let typed = ran_since(&sim, mark);
    let status = typed.iter().position(|l| l == "STATUS");
    let w0 = typed.iter().position(|l| l == "W0");
    let joint = typed.iter().position(|l| l.starts_with("JOINT 6,"));
    assert!(
        status.is_some() && w0.is_some() && status < joint && w0 < joint,
        "STATUS and W0 before the motion: {typed:?}"
    );
}

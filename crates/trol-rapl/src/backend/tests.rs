//! The backend's pieces against the simulated C500 ([`crate::c500::C500`], sans-IO) driven
//! on the caller's thread: every byte the backend sends is fed to the twin at once, and the
//! twin's time is the test's clock at 20x. No thread, no pacing: what is checked is what the
//! backend types and what it makes of the answers.

use std::time::Instant as StdInstant;

use trol_a465::arm::{Arm, ArmSettings, Stored};
use trol_controller::backend::Backend;

use super::halt::Stop;
use super::*;
use crate::c500::{self, C500};

/// The twin as a port on the caller's thread.
struct TwinPort {
    c500: C500,
    epoch: StdInstant,
    scale: f64,
    log: Arc<Mutex<Vec<String>>>,
}

impl TwinPort {
    fn now(&self) -> f64 {
        self.epoch.elapsed().as_secs_f64() * self.scale
    }
    fn turn(&mut self) {
        let now = self.now();
        self.c500.tick(now);
        let ran = self.c500.take_log();
        self.log.lock().unwrap().extend(ran);
    }
}

impl Port for TwinPort {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        let now = self.now();
        self.c500.feed(bytes, now);
        self.turn();
        Ok(())
    }
    fn recv(&mut self, buf: &mut [u8], deadline: StdInstant) -> io::Result<usize> {
        loop {
            self.turn();
            let out = self.c500.take_output(buf.len());
            if !out.is_empty() {
                buf[..out.len()].copy_from_slice(&out);
                return Ok(out.len());
            }
            if StdInstant::now() >= deadline {
                return Ok(0);
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }
    fn available(&mut self) -> io::Result<usize> {
        self.turn();
        Ok(usize::from(self.c500.has_output()))
    }
    fn flush_input(&mut self) -> io::Result<()> {
        self.turn();
        let _ = self.c500.take_output(usize::MAX);
        Ok(())
    }
    fn name(&self) -> String {
        "twin".into()
    }
}

/// A backend on the twin of variant `name`, its arm homed or not; the lines the twin ran.
fn on(name: &str, homed: bool) -> (RaplBackend, Arc<Mutex<Vec<String>>>) {
    on_scaled(name, homed, 20.0)
}

/// [`on`] at another time scale (1.0: the arm's own pace).
fn on_scaled(name: &str, homed: bool, scale: f64) -> (RaplBackend, Arc<Mutex<Vec<String>>>) {
    let (profile, _) = c500::variant(name).expect("a variant");
    let arm = Arm::new(ArmSettings {
        homed,
        ..Default::default()
    });
    let test_001 = [400.0, 0.0, 150.0, 0.0, std::f64::consts::FRAC_PI_2, 0.0];
    let twin = C500::new(
        profile,
        arm,
        vec![("test_001".into(), Stored::Cart(test_001))],
    );
    // The profile that describes this controller, as `trol sim --rapl --print-profile`.
    let profile = twin.describe();
    let log = Arc::new(Mutex::new(Vec::new()));
    let port = TwinPort {
        c500: twin,
        epoch: StdInstant::now(),
        scale,
        log: log.clone(),
    };
    let b = RaplBackend::connect(Box::new(port), profile).expect("the session opens");
    (b, log)
}

/// The code of a call that must reach the controller (a failure of the line fails the test).
fn code(r: BiosResult) -> i16 {
    r.unwrap_or_else(|e| panic!("{e}"))
}

fn ran(log: &Arc<Mutex<Vec<String>>>) -> Vec<String> {
    log.lock().unwrap().clone()
}

/// Finish until the arm is done (at most 10 s of the test's clock).
fn finish(b: &mut RaplBackend) -> Result<(), BackendError> {
    let until = StdInstant::now() + Duration::from_secs(10);
    while b.moving()? {
        assert!(StdInstant::now() < until, "the motion did not end");
    }
    Ok(())
}

#[test]
fn opening_reads_the_state_and_types_nothing_that_moves() {
    let (b, log) = on("not-homed", false);
    let st = b.opening_status().expect("STATUS read at opening");
    assert!(!st.homed.iter().all(|h| *h));
    let lines = ran(&log);
    assert!(lines.contains(&"STATUS".to_string()), "{lines:?}");
    assert!(
        lines
            .iter()
            .all(|l| RaplBackend::only_reads(l) || l == "NOHELP"),
        "{lines:?}"
    );
}

#[test]
fn the_gate_refuses_before_typing_on_an_arm_not_homed() {
    let (mut b, log) = on("not-homed", false);
    let before = ran(&log).len();
    assert_eq!(code(b.joint(1, 0.1)), sim_code::NOT_HOMED);
    let typed = ran(&log)[before..].to_vec();
    assert!(
        typed.iter().all(|l| RaplBackend::only_reads(l)),
        "{typed:?}"
    );
}

#[test]
fn a_motion_while_one_runs_waits_in_the_queue_and_goes_after_it() {
    let (mut b, log) = on("default", true);
    assert_eq!(code(b.joint(1, 0.3)), 0);
    assert_eq!(code(b.joint(1, -0.3)), 0);
    // The second is not on the line while the first runs.
    let joints = |l: &[String]| l.iter().filter(|l| l.starts_with("JOINT 1,")).count();
    assert_eq!(joints(&ran(&log)), 1, "{:?}", ran(&log));
    finish(&mut b).unwrap();
    assert_eq!(joints(&ran(&log)), 2, "{:?}", ran(&log));
    assert!(b.queue.is_empty() && b.outstanding.is_none());
}

#[test]
fn a_motion_behind_a_home_waits_for_it_and_goes_once_the_arm_is_homed() {
    // The shared gate (real::gate): not homed, but a HOME of TROL's is under way, so the
    // motion waits behind it (as on the simulated A465) instead of being refused.
    let (mut b, log) = on("not-homed", false);
    assert_eq!(code(b.home(0)), 0);
    assert_eq!(code(b.joint(1, 0.3)), 0);
    let joints = |l: &[String]| l.iter().filter(|l| l.starts_with("JOINT 1,")).count();
    assert_eq!(joints(&ran(&log)), 0, "{:?}", ran(&log));
    finish(&mut b).unwrap();
    assert_eq!(joints(&ran(&log)), 1, "{:?}", ran(&log));
    assert!(b.queue.is_empty() && b.outstanding.is_none());
}

/// A C500 has no timed path: a trajectory goes as one MA per waypoint, queued behind each
/// other (one on the line at a time), answered TRAJECTORY_UNTIMED; more waypoints than the
/// queue holds is refused before anything is typed.
#[test]
fn a_trajectory_goes_as_one_ma_per_waypoint_untimed() {
    use trol_proto::application::Waypoint;
    let (mut b, log) = on("default", true);
    let path: Vec<Waypoint> = [0.2, -0.1, 0.3]
        .iter()
        .enumerate()
        .map(|(k, q)| Waypoint {
            time: (k + 1) as f64,
            joints: [*q, 0.0, 0.0, 0.0, 0.0, 0.0],
        })
        .collect();
    let before = ran(&log).len();
    assert_eq!(
        code(b.trajectory(&path)),
        trol_proto::application::table::TRAJECTORY_UNTIMED
    );
    let mas = |l: &[String]| l.iter().filter(|l| l.starts_with("MA ")).count();
    assert_eq!(mas(&ran(&log)[before..]), 1, "{:?}", ran(&log));
    finish(&mut b).unwrap();
    assert_eq!(mas(&ran(&log)[before..]), 3, "{:?}", ran(&log));
    let many: Vec<Waypoint> = (0..=trol_controller::UNTIMED_WAYPOINTS)
        .map(|k| Waypoint {
            time: (k + 1) as f64,
            joints: [0.01 * k as f64, 0.0, 0.0, 0.0, 0.0, 0.0],
        })
        .collect();
    let before = ran(&log).len();
    match b.trajectory(&many) {
        Err(BackendError::Explained(c, why)) => {
            assert_eq!(c, trol_proto::application::code::TROL_ERR_ARG_RANGE.0);
            assert!(why.contains("at most 16"), "{why}");
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(mas(&ran(&log)[before..]), 0, "{:?}", ran(&log));
}

/// The speeds a trajectory's times imply (issue 41): SPEED before each waypoint's MA, typed
/// while the arm stands, never above the user's setting; the user's setting typed back
/// before the next motion; a waypoint too fast for the setting, or one at time 0 away from
/// the arm, refused before anything is typed.
#[test]
fn a_trajectory_goes_at_the_speeds_its_times_imply_and_the_setting_comes_back() {
    use trol_proto::application::Waypoint;
    let (mut b, log) = on("default", true);
    assert_eq!(code(b.speed(50)), 0);
    let from = b.standing_joints().unwrap().unwrap().map(f64::to_radians);
    let top = trol_a465::model::max_speeds();
    let by = |q: [f64; 6], j: usize, f: f64| {
        let mut q = q;
        q[j] += f * top[j];
        q
    };
    // 20 % (joint 1 at a fifth of its top speed for 0.5 s), 30 %, then 5 %.
    let q1 = by(from, 0, 0.1);
    let q2 = by(q1, 2, 0.15);
    let q3 = by(q2, 0, -0.05);
    let path = [
        Waypoint {
            time: 0.5,
            joints: q1,
        },
        Waypoint {
            time: 1.0,
            joints: q2,
        },
        Waypoint {
            time: 2.0,
            joints: q3,
        },
    ];
    let typed = |l: &[String]| -> Vec<String> {
        l.iter()
            .filter(|l| l.starts_with("SPEED") || l.starts_with("MA "))
            .map(|l| {
                l.split(' ').next().unwrap().to_string() + " " + l.split(' ').nth(1).unwrap_or("")
            })
            .collect()
    };
    let before = ran(&log).len();
    assert_eq!(
        code(b.trajectory(&path)),
        trol_proto::application::table::TRAJECTORY_UNTIMED
    );
    finish(&mut b).unwrap();
    let at = b.standing_joints().unwrap().unwrap().map(f64::to_radians);
    assert!(
        at.iter().zip(&q3).all(|(a, z)| (a - z).abs() < 1e-3),
        "{at:?}"
    );
    assert_eq!(code(b.ma(from)), 0);
    finish(&mut b).unwrap();
    let seen = typed(&ran(&log)[before..]);
    let speeds: Vec<&str> = seen
        .iter()
        .filter(|l| l.starts_with("SPEED"))
        .map(|l| &l[6..])
        .collect();
    assert_eq!(speeds, ["20", "30", "5", "50"], "{seen:?}");
    // Each SPEED right before its MA.
    assert_eq!(seen.len(), 8, "{seen:?}");
    assert!(
        seen.chunks(2)
            .all(|c| c[0].starts_with("SPEED") && c[1].starts_with("MA ")),
        "{seen:?}"
    );

    // 60 % for 0.5 s where the setting is 50 %: too fast, nothing typed.
    let before = ran(&log).len();
    let fast = [Waypoint {
        time: 0.5,
        joints: by(from, 0, 0.3),
    }];
    assert_eq!(code(b.trajectory(&fast)), code_of("BIOS_TOO_FAST"));
    let far_later = [
        Waypoint {
            time: 1.0,
            joints: by(from, 0, 0.1),
        },
        Waypoint {
            time: 1.1,
            joints: by(from, 0, 0.2),
        },
    ];
    assert_eq!(code(b.trajectory(&far_later)), code_of("BIOS_TOO_FAST"));
    assert!(typed(&ran(&log)[before..]).is_empty(), "{:?}", ran(&log));
    // At time 0 where the arm stands, as its readings give it (f32): taken, nothing to do.
    let here = from.map(|x| f64::from(x as f32) + 1e-6);
    assert_eq!(
        code(b.trajectory(&[Waypoint {
            time: 0.0,
            joints: here
        }])),
        trol_proto::application::table::TRAJECTORY_UNTIMED
    );
    finish(&mut b).unwrap();
    let before = ran(&log).len();
    let away_at_0 = [Waypoint {
        time: 0.0,
        joints: by(from, 0, 0.1),
    }];
    assert_eq!(code(b.trajectory(&away_at_0)), code_of("BIOS_BAD_ARGUMENT"));
    assert!(typed(&ran(&log)[before..]).is_empty(), "{:?}", ran(&log));

    // Behind a motion under way: the first waypoint's pace is taken from where that one
    // ends, when its turn comes (15 % for 0.15 of joint 3's top speed in 1 s).
    let before = ran(&log).len();
    assert_eq!(code(b.ma(q1)), 0);
    let behind = [Waypoint {
        time: 1.0,
        joints: q2,
    }];
    assert_eq!(
        code(b.trajectory(&behind)),
        trol_proto::application::table::TRAJECTORY_UNTIMED
    );
    finish(&mut b).unwrap();
    let seen = typed(&ran(&log)[before..]);
    assert_eq!(
        seen.iter().filter(|l| l.starts_with("MA ")).count(),
        2,
        "{seen:?}"
    );
    assert_eq!(
        seen.iter().filter(|l| *l == "SPEED 15").count(),
        1,
        "{seen:?}"
    );
}

#[test]
fn finish_ends_a_motion_only_with_the_arm_at_its_end() {
    let (mut b, log) = on("default", true);
    assert_eq!(code(b.joint(2, 0.2)), 0);
    finish(&mut b).unwrap();
    // The end was seen on the arm (W2), not taken from the DONE row alone.
    assert!(ran(&log).iter().any(|l| l == "W2"), "{:?}", ran(&log));
}

#[test]
fn scratch_points_rotate_and_are_read_back_before_a_move_names_them() {
    let (mut b, log) = on("default", true);
    let a = b.scratch_name();
    let c = b.scratch_name();
    assert_ne!(a, c);
    let target = Target::Location(Location::Cart(vec![
        400.0,
        50.0,
        240.0,
        0.0,
        std::f64::consts::FRAC_PI_2,
        0.0,
    ]));
    assert_eq!(code(b.move_to(&target, false)), 0);
    let lines = ran(&log);
    let point = lines.iter().position(|l| l.starts_with("POINT ")).unwrap();
    let name = lines[point].split_whitespace().nth(1).unwrap().to_string();
    let listl = lines.iter().position(|l| *l == format!("LISTL {name}"));
    let mv = lines.iter().position(|l| *l == format!("MOVE {name}"));
    assert!(
        matches!((listl, mv), (Some(r), Some(m)) if point < r && r < m),
        "{lines:?}"
    );
    finish(&mut b).unwrap();
}

#[test]
fn the_stops_go_in_the_profile_s_order_and_halt_is_success_only_when_seen() {
    let (mut b, _) = on("default", true);
    assert_eq!(b.stop_order(), [Stop::Halt, Stop::Abort, Stop::CtrlC]);
    b.profile.halt = Halt::Abort;
    assert_eq!(b.stop_order(), [Stop::Abort, Stop::Halt, Stop::CtrlC]);
    b.profile.halt = Halt::CtrlC;
    assert_eq!(b.stop_order(), [Stop::CtrlC, Stop::Halt, Stop::Abort]);
    b.profile.halt = Halt::Halt;
    // A motion answered at its end keeps the interpreter busy: Ctrl-C first.
    b.awaiting = Some("MOVE X".into());
    assert_eq!(b.stop_order()[0], Stop::CtrlC);
    b.awaiting = None;

    // A controller that ignores HALT: ABORT stops the arm, and only then is Halt done.
    // At the arm's own pace and 10 % speed, so that no motion ends by itself meanwhile.
    let (mut b, log) = on_scaled("halt-ignored", true, 1.0);
    assert_eq!(code(b.speed(10)), 0);
    assert_eq!(code(b.joint(1, 1.5)), 0);
    assert_eq!(code(b.halt()), 0);
    let lines = ran(&log);
    assert!(lines.iter().any(|l| l == "ABORT"), "{lines:?}");
    assert!(!b.moving().unwrap());

    // One no stop stops: never success.
    let (mut b, _) = on_scaled("unstoppable", true, 1.0);
    assert_eq!(code(b.speed(10)), 0);
    assert_eq!(code(b.joint(1, 1.5)), 0);
    assert!(matches!(b.halt(), Err(BackendError::NotStopped(_))));
}

#[test]
fn a_refusal_in_the_profile_s_form_is_a_refusal_with_its_code() {
    let (mut b, _) = on("stars-refusal", true);
    // Past J1's limit: the twin refuses, in stars.
    let r = code(b.joint(1, 10.0));
    assert_eq!(r, RAPL_ERROR, "{:?}", b.log_lines());
    assert!(b.log_lines().iter().any(|l| l.contains("***")));
}

/// A HOME is done only with W2 reading the arm at the profile's `home_joints` (issue 62,
/// item 1): the matching profile (every joint's zero) ends it in success; a profile whose home
/// pose is a degree off sees the arm stand elsewhere and ends it in BIOS_NOT_AT_TARGET, however
/// STATUS's HOMED row reads.
#[test]
fn home_is_done_only_at_the_profile_s_home_pose() {
    // On a controller that homes every joint to 0, and on one whose HOME leaves the arm
    // elsewhere (the twin's switch for the open point): the profile that agrees, one a
    // degree off, and the other controller's.
    let elsewhere = c500::variant("home-elsewhere").unwrap().0.twin.home_deg;
    let cases = [
        ("default", [0.0; 6], None),
        (
            "default",
            [0.0, 1.0, 0.0, 0.0, 0.0, 0.0],
            Some(NOT_AT_TARGET),
        ),
        ("default", elsewhere, Some(NOT_AT_TARGET)),
        ("home-elsewhere", elsewhere, None),
        ("home-elsewhere", [0.0; 6], Some(NOT_AT_TARGET)),
    ];
    for (name, home, want) in cases {
        let off = format!("{name} with {home:?}");
        let (mut b, _log) = on(name, true);
        b.profile.home_joints = Some(home);
        assert_eq!(code(b.joint(2, 0.2)), 0);
        finish(&mut b).unwrap();
        assert_eq!(code(b.home(0)), 0);
        let got = finish(&mut b);
        match want {
            None => assert!(got.is_ok(), "home pose {off} off: {got:?}"),
            Some(c) => assert!(
                matches!(got, Err(BackendError::Refused(x)) if x == c),
                "home pose {off} off: {got:?}"
            ),
        }
    }
    // The pose gone from the profile while the HOME runs: never done on STATUS's word.
    let (mut b, _log) = on("default", true);
    assert_eq!(code(b.joint(2, 0.2)), 0);
    finish(&mut b).unwrap();
    assert_eq!(code(b.home(0)), 0);
    b.profile.home_joints = None;
    assert!(
        finish(&mut b).is_err(),
        "a HOME done with no home pose to see"
    );
    // Without it, refused before anything is typed: STATUS's word alone is not the arm seen.
    let (mut b, log) = on("not-homed", false);
    b.profile.home_joints = None;
    assert_eq!(code(b.home(0)), UNSETTLED);
    assert!(!ran(&log).iter().any(|l| l == "HOME"), "{:?}", ran(&log));
}

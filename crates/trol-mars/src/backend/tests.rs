//! The backend's pieces against the simulated MARS 8 ([`crate::mars8::Mars8`], sans-IO)
//! driven on the caller's thread: what the backend sends is fed to the unit at once, and
//! what the unit prints is read back. The unit runs at 10x on the test's clock with CTU's
//! CRS93 profile at REGMS x 10, so the backend's plan and the unit agree (as in
//! tests/variants.rs).

use std::time::Instant as StdInstant;

use trol_controller::backend::Backend;

use super::*;
use crate::mars8::{self, Mars8};

struct TwinPort {
    unit: Arc<Mutex<Mars8>>,
    out: VecDeque<u8>,
}

impl Port for TwinPort {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        let said = self.unit.lock().unwrap().feed(bytes);
        self.out.extend(said);
        Ok(())
    }
    fn recv(&mut self, buf: &mut [u8], deadline: StdInstant) -> io::Result<usize> {
        loop {
            let said = self.unit.lock().unwrap().tick();
            self.out.extend(said);
            if !self.out.is_empty() {
                let n = buf.len().min(self.out.len());
                for (b, x) in buf.iter_mut().zip(self.out.drain(..n)) {
                    *b = x;
                }
                return Ok(n);
            }
            if StdInstant::now() >= deadline {
                return Ok(0);
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }
    fn available(&mut self) -> io::Result<usize> {
        let said = self.unit.lock().unwrap().tick();
        self.out.extend(said);
        Ok(self.out.len())
    }
    fn flush_input(&mut self) -> io::Result<()> {
        self.out.clear();
        Ok(())
    }
    fn name(&self) -> String {
        "twin".into()
    }
}

fn fast() -> Profile {
    let mut p = Profile::crs93();
    p.speed = p.speed.map(|v| v * 10);
    p
}

/// A backend on the unit of variant `name`, its arm homed or not.
fn on(name: &str, homed: bool) -> (MarsBackend, Arc<Mutex<Mars8>>) {
    on_paced(name, homed, false)
}

/// [`on`], at the arm's own pace (`slow`: CTU's CRS93 as it is, the unit at 1x), so that
/// no motion ends by itself while a Halt is tried.
fn on_paced(name: &str, homed: bool, slow: bool) -> (MarsBackend, Arc<Mutex<Mars8>>) {
    let sw = mars8::variant(name).expect("a variant");
    let scale = if slow { 1.0 } else { 10.0 };
    let unit = Arc::new(Mutex::new(Mars8::new(Profile::crs93(), sw, homed, scale)));
    let port = TwinPort {
        unit: unit.clone(),
        out: VecDeque::new(),
    };
    let mut profile = if slow { Profile::crs93() } else { fast() };
    profile.assume_homed = homed;
    let b = MarsBackend::connect(Box::new(port), profile, None, None, Vec::new())
        .expect("the session opens");
    (b, unit)
}

fn received(unit: &Arc<Mutex<Mars8>>) -> Vec<String> {
    unit.lock().unwrap().received().to_vec()
}

fn code(r: BiosResult) -> i16 {
    r.unwrap_or_else(|e| panic!("{e}"))
}

fn finish(b: &mut MarsBackend) {
    let until = StdInstant::now() + Duration::from_secs(20);
    while b.moving().unwrap_or_else(|e| panic!("{e}")) {
        assert!(StdInstant::now() < until, "the motion did not end");
    }
}

const READS: [&str; 5] = ["ECHO:0", "VER?", "ST?", "COORDAP?", "STAMP"];

fn reads_only(lines: &[String]) -> bool {
    lines.iter().all(|l| READS.iter().any(|r| l.starts_with(r)))
}

#[test]
fn opening_reads_only() {
    let (_b, unit) = on("default", false);
    let lines = received(&unit);
    assert!(lines.iter().any(|l| l == "VER?"), "{lines:?}");
    assert!(reads_only(&lines), "{lines:?}");
}

#[test]
fn the_gate_refuses_a_motion_before_home_and_sends_nothing_that_moves() {
    let (mut b, unit) = on("default", false);
    let before = received(&unit).len();
    assert_eq!(code(b.joint(1, 0.1)), code::NOT_HOMED);
    let sent = received(&unit)[before..].to_vec();
    assert!(reads_only(&sent), "{sent:?}");
}

#[test]
fn a_motion_goes_as_segments_confirmed_by_stamp_and_ends_at_its_target() {
    let (mut b, unit) = on("default", true);
    let before = received(&unit).len();
    assert_eq!(code(b.joint(1, 0.2)), 0);
    let sent = received(&unit)[before..].to_vec();
    assert!(sent.iter().any(|l| l.starts_with("COORDMVT:")), "{sent:?}");
    let last_move = sent
        .iter()
        .rposition(|l| l.starts_with("COORDMVT:"))
        .unwrap();
    assert!(
        sent[last_move..].iter().any(|l| l.starts_with("STAMP:")),
        "{sent:?}"
    );
    finish(&mut b);
    let q = unit.lock().unwrap().joints();
    assert!((q[0] - 0.2).abs() < 1e-3, "{q:?}");
}

/// A trajectory keeps its times on a MARS 8: coordinated segments whose durations add up to
/// the trajectory's, passing each waypoint (in the unit's IRC) at its time; Finish ends with
/// the arm at the last one.
#[test]
fn a_trajectory_goes_as_segments_that_pass_each_waypoint_at_its_time() {
    let (mut b, unit) = on("default", true);
    let before = received(&unit).len();
    let path = [
        trol_proto::application::Waypoint {
            time: 1.0,
            joints: [0.2, 0.1, 0.0, 0.0, 0.0, 0.0],
        },
        trol_proto::application::Waypoint {
            time: 2.0,
            joints: [0.1, 0.2, 0.1, 0.0, 0.0, 0.0],
        },
    ];
    assert_eq!(code(b.trajectory(&path)), 0);
    let sent = received(&unit)[before..].to_vec();
    let mut t_ms = 0i64;
    let mut at: Vec<(i64, Vec<f64>)> = Vec::new();
    for l in sent.iter().filter_map(|l| l.strip_prefix("COORDMVT:")) {
        let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
        t_ms += v[0] as i64;
        at.push((t_ms, v[1..].to_vec()));
    }
    assert!(at.len() > 2, "sampled, not one segment: {sent:?}");
    assert!((t_ms - 2000).abs() <= at.len() as i64, "{t_ms} ms");
    let profile = fast();
    for w in &path {
        let want = profile.joints_to_irc(&w.joints);
        let ms = (w.time * 1000.0) as i64;
        let (_, irc) = at
            .iter()
            .min_by_key(|(t, _)| (t - ms).abs())
            .expect("a segment");
        for j in 0..6 {
            assert!(
                (irc[j] - want[j].round()).abs() <= 2.0,
                "{irc:?} against {want:?}"
            );
        }
    }
    finish(&mut b);
    let q = unit.lock().unwrap().joints();
    assert!(
        (q[1] - 0.2).abs() < 1e-3 && (q[2] - 0.1).abs() < 1e-3,
        "{q:?}"
    );
}

/// A trajectory longer than the unit's queue holds (more segments than QUEUE), at the arm's
/// own pace: the segments are fed as the queue drains, and Finish ends with the arm at the
/// last waypoint.
#[test]
fn a_trajectory_longer_than_the_unit_s_queue_is_fed_as_it_drains() {
    let (mut b, unit) = on_paced("default", true, true);
    let path = [
        trol_proto::application::Waypoint {
            time: 3.0,
            joints: [0.1, 0.05, 0.4, 0.05, 0.3, 0.05],
        },
        trol_proto::application::Waypoint {
            time: 6.0,
            joints: [0.2, 0.1, 0.6, 0.1, 0.5, 0.1],
        },
    ];
    assert_eq!(code(b.trajectory(&path)), 0);
    let until = StdInstant::now() + Duration::from_secs(30);
    loop {
        match b.moving() {
            Ok(true) => {}
            Ok(false) => break,
            Err(e) => panic!("{e}"),
        }
        assert!(StdInstant::now() < until, "the motion did not end");
        std::thread::sleep(Duration::from_millis(20));
    }
    let q = unit.lock().unwrap().joints();
    assert!(
        (q[2] - 0.6).abs() < 1e-3 && (q[4] - 0.5).abs() < 1e-3,
        "{q:?}"
    );
}

#[test]
fn halt_is_success_only_when_the_unit_shows_the_arm_standing() {
    // STOP: works.
    let (mut b, unit) = on_paced("default", true, true);
    assert_eq!(code(b.speed(10)), 0);
    assert_eq!(code(b.joint(1, 1.5)), 0);
    assert_eq!(code(b.halt()), 0);
    assert!(!unit.lock().unwrap().is_moving());
    assert!(!received(&unit).iter().any(|l| l == "PURGE:"));

    // STOP: is taken and ignored: PURGE: stops it, and the arm must be homed again.
    let (mut b, unit) = on_paced("stop-ignored", true, true);
    assert_eq!(code(b.speed(10)), 0);
    assert_eq!(code(b.joint(1, 1.5)), 0);
    assert_eq!(code(b.halt()), 0);
    assert!(received(&unit).iter().any(|l| l == "PURGE:"));
    assert!(!unit.lock().unwrap().is_moving());
    assert_eq!(code(b.joint(1, 0.1)), code::NOT_HOMED);

    // Nothing stops it: never success.
    let (mut b, _) = on_paced("unstoppable", true, true);
    assert_eq!(code(b.speed(10)), 0);
    assert_eq!(code(b.joint(1, 1.5)), 0);
    assert!(matches!(b.halt(), Err(BackendError::NotStopped(_))));
}

/// The lines sent from `before` on, up to the first motion line: the reads a motion made
/// before it went.
fn reads_before_motion(unit: &Arc<Mutex<Mars8>>, before: usize) -> Vec<String> {
    received(unit)[before..]
        .iter()
        .take_while(|l| !l.starts_with("COORDISCONT") && !l.starts_with("COORDMVT"))
        .cloned()
        .collect()
}

/// Issue 43: the arm seen standing at a motion's end stands in for the next motion's ST?
/// and COORDAP?, so its lines go first; the motion still ends where it should. Past
/// SEEN_FOR, or after a line that is not a read, the reads come first again.
#[test]
fn a_motion_right_after_a_finish_goes_without_reads_first() {
    let (mut b, unit) = on("default", true);
    assert_eq!(code(b.joint(1, 0.2)), 0);
    finish(&mut b);
    let before = received(&unit).len();
    assert_eq!(code(b.joint(1, -0.3)), 0);
    assert_eq!(reads_before_motion(&unit, before), Vec::<String>::new());
    // The segment first: the discontinuity the unit has from the motion before.
    let sent = received(&unit)[before..].to_vec();
    assert!(sent[0].starts_with("COORDMVT:"), "{sent:?}");
    finish(&mut b);
    let q = unit.lock().unwrap().joints();
    assert!((q[0] + 0.1).abs() < 1e-3, "{q:?}");

    // A read between (GetPosition) keeps it.
    b.position(Tag::Joint, PosMode::Actual).unwrap();
    let before = received(&unit).len();
    assert_eq!(code(b.joint(1, 0.1)), 0);
    assert_eq!(reads_before_motion(&unit, before), Vec::<String>::new());
    finish(&mut b);

    // Too old (a window of zero: every reading is): read again.
    b.seen.set_window(Duration::ZERO);
    let before = received(&unit).len();
    assert_eq!(code(b.joint(1, 0.1)), 0);
    let reads = reads_before_motion(&unit, before);
    assert!(reads.iter().any(|l| l == "ST?"), "{reads:?}");
    assert!(reads.iter().any(|l| l == "COORDAP?"), "{reads:?}");
    finish(&mut b);

    // A line that is not a read (a Halt's STOP:) forgets it.
    b.seen.set_window(SEEN_FOR);
    assert_eq!(code(b.joint(1, -0.1)), 0);
    finish(&mut b);
    assert_eq!(code(b.halt()), 0);
    let before = received(&unit).len();
    assert_eq!(code(b.joint(1, 0.1)), 0);
    let reads = reads_before_motion(&unit, before);
    assert!(reads.iter().any(|l| l == "COORDAP?"), "{reads:?}");
    // And the discontinuity goes again, before the segment, with no look between.
    let sent = received(&unit)[before + reads.len()..].to_vec();
    assert!(sent[0].starts_with("COORDISCONT:"), "{sent:?}");
    assert!(sent[1].starts_with("COORDMVT:"), "{sent:?}");
    finish(&mut b);
}

/// The rule for real controllers with the reads left out: the arm's power lost after the
/// Finish that saw it standing, the motion sent on what was seen is refused by the ST? read
/// right after its lines (BIOS_ARM_POWER), never a success, and the arm does not move.
#[test]
fn a_fault_after_the_finish_is_caught_by_the_read_after_the_lines() {
    let (mut b, unit) = on("default", true);
    assert_eq!(code(b.joint(1, 0.2)), 0);
    finish(&mut b);
    let q0 = unit.lock().unwrap().joints();
    unit.lock().unwrap().set_power_off(true);
    assert_eq!(code(b.joint(1, 0.3)), ARM_POWER);
    std::thread::sleep(Duration::from_millis(50));
    let q1 = unit.lock().unwrap().joints();
    assert!((q1[0] - q0[0]).abs() < 1e-6, "{q0:?} -> {q1:?}");
}

//! First contact against the simulated C500: only commands that cannot move the arm are
//! sent, every byte is recorded, and the conventions are fitted from W2 readings at poses an
//! operator sets by pendant.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};

use trol_a465::arm::{Arm, ArmSettings};
use trol_port::Port;
use trol_port::memory;
use trol_rapl::probe::{self, READ_ONLY};
use trol_rapl::profile::Units;
use trol_rapl::{C500, Profile, RaplBackend};

/// A simulated C500 on a thread with a pendant: each joint target sent on the channel is
/// moved to, and the reply channel hears once the arm stands there.
struct Sim {
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
    lines: Arc<Mutex<Vec<String>>>,
    pendant: mpsc::Sender<[f64; 6]>,
    arrived: mpsc::Receiver<i16>,
}

impl Drop for Sim {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn start(profile: Profile) -> (Box<dyn Port>, Sim) {
    start_at(profile, 20.0)
}

/// Like [`start`], at time scale `scale`.
fn start_at(profile: Profile, scale: f64) -> (Box<dyn Port>, Sim) {
    let (host, mut ctl) = memory::pair(Some(profile.baud));
    let stop = Arc::new(AtomicBool::new(false));
    let lines = Arc::new(Mutex::new(Vec::new()));
    let (pendant, targets) = mpsc::channel::<[f64; 6]>();
    let (arrived_tx, arrived) = mpsc::channel();
    let (flag, keep) = (stop.clone(), lines.clone());
    let thread = std::thread::spawn(move || {
        let arm = Arm::new(ArmSettings {
            homed: true,
            ..Default::default()
        });
        let mut c = C500::new(profile, arm, Vec::new());
        let mut going = false;
        let _ = trol_rapl::c500::serve_with(
            &mut ctl,
            &mut c,
            scale,
            &flag,
            &mut |l| keep.lock().unwrap().push(l.to_string()),
            &mut |c, now| {
                if let Ok(q) = targets.try_recv() {
                    let code = c.pendant(q, now);
                    if code != 0 {
                        let _ = arrived_tx.send(code);
                    } else {
                        going = true;
                    }
                }
                if going && !c.arm_moving(now) {
                    going = false;
                    let _ = arrived_tx.send(0);
                }
            },
        );
    });
    (
        Box::new(host),
        Sim {
            stop,
            thread: Some(thread),
            lines,
            pendant,
            arrived,
        },
    )
}

const POSES_DEG: [[f64; 6]; 3] = [
    [10.0, 20.0, 40.0, 30.0, 50.0, -20.0],
    [-35.0, 5.0, 70.0, -60.0, 30.0, 45.0],
    [60.0, -15.0, 30.0, 15.0, -40.0, 100.0],
];

#[test]
fn first_contact_moves_nothing_records_every_byte_and_fits_the_conventions() {
    // A controller unlike TROL's simulator on every point the probe can read: inches,
    // another angle order, a tool frame turned 90 degrees, the G3000 driver's negative
    // one-pulse-per-line table, refusals with a colon.
    let (g3000, _) = trol_rapl::c500::variant("pulses-g3000").unwrap();
    let controller = Profile {
        units: Units::Inch,
        angles: "roll -pitch yaw".into(),
        tool_rotation: [0.0, 90.0, 0.0],
        pulse_scale: g3000.pulse_scale.clone(),
        pulse_zero: g3000.pulse_zero.clone(),
        twin: trol_rapl::profile::Twin {
            refusal: ":NNN-TEXT.".into(),
            ..Default::default()
        },
        ..Profile::simulator()
    };
    let (port, sim) = start(controller);
    // The safe default profile: nothing settled but what opening a session needs.
    let record = trol_rapl::backend::Recorder::default();
    let mut b =
        RaplBackend::connect_with(port, Profile::default(), None, Some(record.clone())).unwrap();
    let mut asked = Vec::new();
    let contact = probe::first_contact(&mut b, POSES_DEG.len(), &mut |k, n| {
        asked.push((k, n));
        sim.pendant
            .send(POSES_DEG[k - 1].map(f64::to_radians))
            .unwrap();
        let code = sim
            .arrived
            .recv_timeout(std::time::Duration::from_secs(30))
            .unwrap();
        assert_eq!(code, 0, "the pendant could not reach pose {k}");
        Ok(true)
    });
    b.close();
    assert_eq!(asked, vec![(1, 3), (2, 3), (3, 3)]);
    for (line, r) in &contact.replies {
        assert!(r.is_ok(), "{line}: {r:?}");
    }
    assert_eq!(contact.refusal, Some(Ok(":NNN-TEXT.".to_string())));
    assert!(
        contact.replies[0]
            .1
            .as_ref()
            .unwrap()
            .contains("ENGLISH UNITS")
    );
    assert_eq!(contact.readings.len(), 1 + POSES_DEG.len());
    let fit = contact.fit.unwrap().unwrap();
    assert_eq!(fit.units, Units::Inch);
    assert_eq!(fit.angles, "roll -pitch yaw");
    assert_eq!(fit.tool_rotation, [0.0, 90.0, 0.0]);
    let (scale, zero) = fit.pulses.clone().unwrap();
    for i in 0..6 {
        // The readings are whole pulses and four-decimal degrees, and the pendant stops
        // within its tolerance, not on the pose, so the line is known to about a pulse
        // where the poses lie: it must give the controller's count within two pulses
        // anywhere between the poses (further out, the error grows with the distance).
        let joints: Vec<f64> = contact.readings.iter().map(|r| r.joints[i]).collect();
        let (lo, hi) = joints
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &q| (a.min(q), b.max(q)));
        for q in [lo, (lo + hi) / 2.0, hi] {
            let ours = zero[i] + scale[i] * q;
            let theirs = g3000.pulse_zero[i] + g3000.pulse_scale[i] * q;
            assert!(
                (ours - theirs).abs() <= 2.0,
                "joint {}: {ours} pulses for {theirs} at {q} degrees ({scale:?} {zero:?})",
                i + 1
            );
        }
    }
    let written = fit.apply(&Profile::default());
    assert_eq!(written.angles, "roll -pitch yaw");
    // MA and MI's units are not read off the JOINTS row.
    assert_eq!(written.joint_units, "");
    assert_eq!(Profile::parse(&written.to_toml()).unwrap(), written);

    // Nothing ran that could move the arm or change a setting.
    let ran = sim.lines.lock().unwrap().clone();
    assert!(!ran.is_empty());
    for line in &ran {
        let word = line.split_whitespace().next().unwrap_or("");
        assert!(
            READ_ONLY.contains(&word) || ["NOH", "NOHELP", "HELP"].contains(&word),
            "the probe sent {line}"
        );
    }
    assert_eq!(
        ran.last().map(String::as_str),
        Some("HELP"),
        "closed with HELP"
    );
    // Every byte both ways is in the transcript, the close included.
    let text = record.lock().unwrap().to_text();
    assert!(text.contains(" H 57  W\n"), "W typed:\n{text}");
    assert!(text.contains(" C ") && text.contains("WORLD"));
    assert!(text.trim_end().ends_with("1a 1a  .."), "closed:\n{text}");
}

#[test]
fn an_operator_who_stops_early_gets_a_fit_that_says_what_is_missing() {
    let (port, _sim) = start(Profile::simulator());
    let mut b = RaplBackend::connect(port, Profile::default()).unwrap();
    let contact = probe::first_contact(&mut b, 4, &mut |_, _| Ok(false));
    let e = contact.fit.unwrap().unwrap_err();
    assert!(e.contains("at least two poses"), "{e}");
    // A line that could move the arm is refused before it is sent.
    let e = b.read_only("MOVE T1").unwrap_err().to_string();
    assert!(e.contains("not sent"), "{e}");
}

// The supervised steps run in real time (the answer to JOINT 6,20 must come while the joint
// turns), so each variant is a test of its own: they run side by side, not one after another.
#[test]
fn the_supervised_steps_measure_what_no_reading_tells_default() {
    supervised_steps("default", "degrees", MotionAck::Start);
}

#[test]
fn the_supervised_steps_measure_what_no_reading_tells_ma_radians() {
    supervised_steps("ma-radians", "radians", MotionAck::Start);
}

#[test]
fn the_supervised_steps_measure_what_no_reading_tells_ack_at_end() {
    supervised_steps("ack-at-end", "degrees", MotionAck::End);
}

#[test]
fn the_supervised_steps_measure_what_no_reading_tells_jog_tool() {
    supervised_steps("jog-tool", "degrees", MotionAck::Start);
}

#[test]
fn the_supervised_steps_measure_what_no_reading_tells_halt_ignored() {
    supervised_steps("halt-ignored", "degrees", MotionAck::Start);
}

use trol_rapl::profile::MotionAck;

fn supervised_steps(variant: &str, units: &str, ack: MotionAck) {
    let (controller, _) = trol_rapl::c500::variant(variant).unwrap();
    // Real time: the answer to JOINT 6,20 must come while the joint turns (2.3 s).
    let (port, sim) = start_at(controller, 1.0);
    // The poses of step 4 fitted the angles (the twin's: TROL's own).
    let fitted = Profile {
        angles: "yaw pitch roll".into(),
        ..Profile::default()
    };
    let mut b = RaplBackend::connect(port, fitted).unwrap();
    // The operator puts the arm in free space first (all joints zero is full stretch),
    // the tool not pointing up (where JOG's frame could not be told).
    sim.pendant
        .send([10.0f64, 20.0, 40.0, 30.0, -50.0, -20.0].map(f64::to_radians))
        .unwrap();
    let code = sim
        .arrived
        .recv_timeout(std::time::Duration::from_secs(60))
        .unwrap();
    assert_eq!(code, 0);
    let before = {
        let r = b.read_only("W2").unwrap();
        trol_rapl::text::read_position(&r.text).unwrap()
    };
    let m = probe::measure(&mut b, &mut |l| eprintln!("probe: {l}"))
        .unwrap_or_else(|e| panic!("{variant}: {e}"));
    assert_eq!(m.joint_units, units, "{variant}");
    let frame = if variant == "jog-tool" {
        "tool"
    } else {
        "world"
    };
    assert_eq!(m.jog_frame, frame, "{variant}");
    assert_eq!(m.motion_ack, ack, "{variant}");
    // The stop it saw stop a running motion: ABORT where HALT is only acknowledged; none
    // measured where a motion holds the line (Ctrl-C is then the only way in).
    use trol_rapl::profile::Halt;
    let halt = match variant {
        "halt-ignored" => Some(Halt::Abort),
        "ack-at-end" => None,
        _ => Some(Halt::Halt),
    };
    assert_eq!(m.halt, halt, "{variant}");
    // Every step undone: the arm is back where it was.
    let after = {
        let r = b.read_only("W2").unwrap();
        trol_rapl::text::read_position(&r.text).unwrap()
    };
    for i in 0..6 {
        assert!(
            (after.joints[i] - before.joints[i]).abs() < 0.02,
            "{variant}: {after:?}"
        );
    }
    // Only the steps' lines moved it.
    let ran = sim.lines.lock().unwrap().clone();
    for line in ran {
        let word = line.split_whitespace().next().unwrap_or("");
        assert!(
            READ_ONLY.contains(&word)
                || ["NOH", "NOHELP", "HELP"].contains(&word)
                || probe::MEASURE.contains(&line.as_str())
                // The stop steps turn joint 6 back by what it turned.
                || line.starts_with("JOINT 6,"),
            "{variant}: {line}"
        );
    }
    b.close();
}

/// At the homed pose (all joints zero) the tool's z axis is the world's, and a JOG in either
/// frame moves the same: the probe sends no JOG there, leaves jog_frame unset and says which
/// pose to set (issue 37: it wrote "world" for a flange-frame JOG).
#[test]
fn the_jog_frame_is_not_measured_where_it_cannot_be_told() {
    // The public convention: the tool frame is the world's at all joints zero (TROL's
    // model's is pitched -90 degrees: tool_rotation says so), and JOG along the tool's axes.
    let (offset, _) = trol_rapl::c500::variant("world-offset").unwrap();
    let controller = Profile {
        twin: trol_rapl::profile::Twin {
            jog_tool: true,
            ..offset.twin.clone()
        },
        ..offset.clone()
    };
    let (port, sim) = start_at(controller, 1.0);
    let fitted = Profile {
        angles: "yaw pitch roll".into(),
        tool_rotation: offset.tool_rotation,
        ..Profile::default()
    };
    let mut b = RaplBackend::connect(port, fitted).unwrap();
    let mut said = Vec::new();
    let m = probe::measure(&mut b, &mut |l| said.push(l.to_string())).unwrap();
    assert_eq!(m.jog_frame, "");
    assert!(
        said.iter()
            .any(|l| l.contains("Turn joint 5 by 45 degrees")),
        "{said:?}"
    );
    let ran = sim.lines.lock().unwrap().clone();
    assert!(!ran.iter().any(|l| l.starts_with("JOG")), "{ran:?}");
    // A profile that knew it keeps it.
    let known = Profile {
        jog_frame: "tool".into(),
        ..Profile::default()
    };
    assert_eq!(m.apply(&known).jog_frame, "tool");
    b.close();
}

//! `trol bench gateway`: a C500 in RAPL-II through the gateway or in-process, from the call
//! to the motion's start and from its end to the call's return, with RobWork's way beside.

use super::*;

#[derive(Serialize)]
pub(super) struct GatewayReport {
    pub(super) baud: u32,
    /// `trol gateway` as a process between two relay processes (`--processes`), not all in
    /// one process over paced in-memory lines.
    pub(super) through_processes: bool,
    /// RobWork's way, on the RAPL-II line alone: the same absolute motion sent again, its
    /// answer held by the controller until the first ended; from the stand to that answer.
    pub(super) robwork_second_motion: Spread,
    pub(super) speed_round_trip: Spread,
    pub(super) get_position_cart_actual: Spread,
    pub(super) finish: Vec<FinishReport>,
}

/// The whole path: Robot -> TROL line -> PCP server + RAPL-II backend -> RAPL-II line ->
/// simulated C500 (time scale 1). The C500's loop notes when the arm comes to a stand.
pub(super) struct GatewayPath {
    pub(super) robot: trol::Robot,
    pub(super) twin: C500Twin,
    /// With `--processes`: the two relays, the `trol gateway` process and its profile
    /// file, kept for as long as the path is used.
    _processes: Option<Processes>,
}

/// The processes of the path through real processes, ended when dropped (the gateway
/// first: it holds both lines).
struct Processes {
    gateway: SimProcess,
    _trol_line: super::relay::Relay,
    _rapl_line: super::relay::Relay,
    profile: std::path::PathBuf,
}

impl Drop for Processes {
    fn drop(&mut self) {
        let _ = self.gateway.0.kill();
        let _ = self.gateway.0.wait();
        let _ = std::fs::remove_file(&self.profile);
    }
}

/// The simulated C500 (time scale 1) serving a line paced at the profile's baud rate; its
/// loop notes when the arm comes to a stand.
pub(super) struct C500Twin {
    pub(super) stopped_at: std::sync::Arc<std::sync::Mutex<Option<Instant>>>,
    /// When the arm last started to move.
    pub(super) started_at: std::sync::Arc<std::sync::Mutex<Option<Instant>>>,
    /// When a command that waited for the arm (a motion behind another) went on.
    pub(super) released_at: std::sync::Arc<std::sync::Mutex<Option<Instant>>>,
    pub(super) stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
    pub(super) c500: Option<std::thread::JoinHandle<()>>,
}

impl Drop for C500Twin {
    fn drop(&mut self) {
        self.stop.store(true, std::sync::atomic::Ordering::Relaxed);
        if let Some(t) = self.c500.take() {
            let _ = t.join();
        }
    }
}

/// The simulated C500 and the RAPL-II backend's session with it.
pub(super) fn c500_line(
    profile: trol_rapl::Profile,
) -> Result<(trol_rapl::RaplBackend, C500Twin), String> {
    let (rapl_host, rapl_ctl) = memory::pair(Some(profile.baud));
    let twin = c500_twin(profile.clone(), Box::new(rapl_ctl));
    let backend = trol_rapl::RaplBackend::connect(Box::new(rapl_host), profile)
        .map_err(|e| format!("the gateway could not open the simulated C500: {e}"))?;
    Ok((backend, twin))
}

/// The simulated C500 (time scale 1) serving `port`, on a thread of its own; its loop
/// notes when the arm starts, when it stands and when a held command goes on.
fn c500_twin(profile: trol_rapl::Profile, mut rapl_ctl: Box<dyn trol_port::Port>) -> C500Twin {
    use std::sync::atomic::AtomicBool;
    use std::sync::{Arc, Mutex};
    let stop = Arc::new(AtomicBool::new(false));
    let stopped_at = Arc::new(Mutex::new(None));
    let started_at = Arc::new(Mutex::new(None));
    let released_at = Arc::new(Mutex::new(None));
    let (flag, noted, released) = (stop.clone(), stopped_at.clone(), released_at.clone());
    let started = started_at.clone();
    let c500_profile = profile.clone();
    let c500 = std::thread::spawn(move || {
        let arm = trol_a465::arm::Arm::new(trol_a465::arm::ArmSettings {
            homed: true,
            ..Default::default()
        });
        let mut c = trol_rapl::C500::new(c500_profile, arm, Vec::new());
        let mut was_moving = false;
        let mut was_waiting = false;
        let _ = trol_rapl::c500::serve_with(
            &mut *rapl_ctl,
            &mut c,
            1.0,
            &flag,
            &mut |_| {},
            &mut |c, now| {
                let moving = c.arm_moving(now);
                if was_moving && !moving {
                    *noted.lock().unwrap() = Some(Instant::now());
                }
                if !was_moving && moving {
                    *started.lock().unwrap() = Some(Instant::now());
                }
                was_moving = moving;
                let waiting = c.is_waiting();
                if was_waiting && !waiting {
                    *released.lock().unwrap() = Some(Instant::now());
                }
                was_waiting = waiting;
            },
        );
    });
    C500Twin {
        stopped_at,
        started_at,
        released_at,
        stop,
        c500: Some(c500),
    }
}

/// The completions `trol bench gateway` compares: the profile's name for each and the
/// settings that make it.
pub(super) fn completions() -> Vec<(&'static str, trol_rapl::Profile)> {
    use trol_rapl::profile::Completion;
    let base = trol_rapl::Profile::simulator();
    let finish = trol_rapl::Profile {
        completion: Completion::Finish,
        ctrl_c_ends_finish: true,
        ..base.clone()
    };
    vec![
        ("status (the default)", base.clone()),
        (
            "w5",
            trol_rapl::Profile {
                completion: Completion::W5,
                ..base.clone()
            },
        ),
        ("finish, W2 confirms", finish.clone()),
        (
            "finish, finish_ack_means_arrived",
            trol_rapl::Profile {
                finish_ack_means_arrived: true,
                twin: trol_rapl::profile::Twin {
                    finish_stopped: 37,
                    ..finish.twin.clone()
                },
                ..finish
            },
        ),
    ]
}

/// RobWork's way (c500-rapl.md §1.1 item 7): the motion, then the same absolute motion
/// again, whose answer the controller holds until the first has ended; the time from the
/// arm's stand to that answer, on the RAPL-II line alone (no TROL link, no server).
pub(super) fn robwork_anchor(baud: u32, moves: u32) -> Result<Spread, String> {
    let (mut backend, twin) = c500_line(trol_rapl::Profile {
        baud,
        ..trol_rapl::Profile::simulator()
    })?;
    let t = Duration::from_secs(30);
    let mut after = Vec::new();
    for i in 0..moves {
        let deg = if i % 2 == 0 { 17.19 } else { 0.0 };
        let ma = format!("MA 0,0,0,0,0,{deg}");
        *twin.released_at.lock().unwrap() = None;
        for _ in 0..2 {
            let r = backend
                .type_line(&ma, t)
                .map_err(|e| format!("`{ma}`: {e}"))?;
            if !r.ack {
                return Err(format!("`{ma}` was not acknowledged: {:?}", r.text));
            }
        }
        let answered = Instant::now();
        // The second MA waited in the controller until the first motion ended.
        let Some(stood) = *twin.released_at.lock().unwrap() else {
            return Err("the second MA was answered before the first motion ended".into());
        };
        after.push(answered.duration_since(stood).as_secs_f64() * 1e3);
    }
    Ok(Spread::of(after))
}

/// The echo and reply limits of the path through processes, ms.
const PROCESS_LIMIT_MS: u64 = 15_000;

/// The whole path through real processes: the simulated C500 here, on one end of a relay
/// paced at the baud rate (the RAPL-II line); `trol gateway` as a process of its own between
/// that relay's other end and a second relay (TROL's line); the application's `Robot` here,
/// on the second relay's other end.
fn gateway_processes(profile: trol_rapl::Profile) -> Result<GatewayPath, String> {
    // The echo and reply limits are a real C500's: it answers within a character time and
    // never stalls. Here the controller, both lines and the gateway are processes sharing
    // the machine's cores; on a busy machine one of them can sit unscheduled for seconds
    // (a CI run saw NOHELP's CR go 2 s without its echo). The bench times what happens
    // and does not test the limits, so its processes get room to be late.
    let profile = trol_rapl::Profile {
        echo_timeout_ms: profile.echo_timeout_ms.max(PROCESS_LIMIT_MS),
        reply_timeout_ms: profile.reply_timeout_ms.max(PROCESS_LIMIT_MS),
        ..profile
    };
    let baud = profile.baud;
    let rapl_line = super::relay::Relay::start(baud)?;
    let trol_line = super::relay::Relay::start(baud)?;
    let port = trol_port::serial::SerialLine::open(&rapl_line.ends.0, baud)
        .map_err(|e| format!("the C500's end {}: {e}", rapl_line.ends.0))?;
    let twin = c500_twin(profile.clone(), Box::new(port));
    let file = std::env::temp_dir().join(format!(
        "trol-bench-gateway-{}-{}.toml",
        std::process::id(),
        rapl_line.ends.1.replace('/', "_")
    ));
    std::fs::write(&file, profile.to_toml())
        .map_err(|e| format!("cannot write the profile for trol gateway: {e}"))?;
    let baud_text = baud.to_string();
    let started = start_trol_sim(
        &[
            "gateway",
            "--controller",
            &rapl_line.ends.1,
            "--port",
            &trol_line.ends.0,
            "--baud",
            &baud_text,
            "--profile",
            &file.to_string_lossy(),
            "--server",
        ],
        &["serving on "],
    );
    let gateway = match started {
        Ok((g, _)) => g,
        Err(e) => {
            let _ = std::fs::remove_file(&file);
            return Err(e);
        }
    };
    let processes = Processes {
        gateway,
        _trol_line: trol_line,
        _rapl_line: rapl_line,
        profile: file,
    };
    let robot = trol::Connect::port(&processes._trol_line.ends.1)
        .baud(baud)
        .connect()
        .map_err(|e| format!("TROL through trol gateway: {e}"))?;
    Ok(GatewayPath {
        robot,
        twin,
        _processes: Some(processes),
    })
}

pub(super) fn gateway_path(
    profile: trol_rapl::Profile,
    processes: bool,
) -> Result<GatewayPath, String> {
    if processes {
        return gateway_processes(profile);
    }
    let baud = profile.baud;
    let (backend, twin) = c500_line(profile)?;
    let (trol_host, trol_ctl) = memory::pair(Some(baud));
    let cfg = LinkConfig::for_line(baud, Duration::ZERO);
    let controller = trol_controller::Controller::new(
        trol_ctl,
        cfg,
        trol_controller::Pcp::new(backend),
        trol_controller::Mode::Server,
    );
    let handle = trol_controller::Embedded::spawn(controller);
    let mut robot = trol::Robot::over(Box::new(trol_host), cfg, Some(handle));
    robot.set_codes(trol_rapl::RAPL_CODES);
    Ok(GatewayPath {
        robot,
        twin,
        _processes: None,
    })
}

pub(super) fn gateway(a: GatewayArgs) -> Result<(), String> {
    let err = |e: trol::Error| e.to_string();
    let base = trol_rapl::Profile {
        baud: a.baud,
        ..trol_rapl::Profile::simulator()
    };
    let mut path = gateway_path(base, a.processes)?;
    let robot = &mut path.robot;
    robot.speed(100).map_err(err)?;
    let mut speed = Vec::new();
    let mut position = Vec::new();
    for _ in 0..a.count {
        let t = Instant::now();
        robot.speed(100).map_err(err)?;
        speed.push(t.elapsed().as_secs_f64() * 1e3);
        let t = Instant::now();
        robot
            .position(trol::Tag::Cart, trol::PosMode::Actual)
            .map_err(err)?;
        position.push(t.elapsed().as_secs_f64() * 1e3);
    }
    drop(path);

    let mut finish = Vec::new();
    for (completion, profile) in completions() {
        let mut path = gateway_path(
            trol_rapl::Profile {
                baud: a.baud,
                ..profile
            },
            a.processes,
        )?;
        let mut after = Vec::new();
        let (mut joint_start, mut ma_start) = (Vec::new(), Vec::new());
        for i in 0..a.moves {
            // Joint 6 by 0.3 rad (TROLJoint), and back (TROLMA): about a quarter of a
            // second each at full speed.
            *path.twin.stopped_at.lock().unwrap() = None;
            *path.twin.started_at.lock().unwrap() = None;
            let called = Instant::now();
            if i % 2 == 0 {
                path.robot.joint(6, 0.3).map_err(err)?;
            } else {
                path.robot.ma(&[0.0; 6]).map_err(err)?;
            }
            path.robot.finish().map_err(err)?;
            let returned = Instant::now();
            let Some(started) = *path.twin.started_at.lock().unwrap() else {
                return Err(format!(
                    "Finish returned before the arm started (completion {completion})"
                ));
            };
            let to_start = started.duration_since(called).as_secs_f64() * 1e3;
            if i % 2 == 0 {
                joint_start.push(to_start);
            } else {
                ma_start.push(to_start);
            }
            let Some(stood) = *path.twin.stopped_at.lock().unwrap() else {
                return Err(format!(
                    "Finish returned before the arm stood (completion {completion})"
                ));
            };
            after.push(returned.duration_since(stood).as_secs_f64() * 1e3);
        }
        finish.push(FinishReport {
            completion: completion.to_string(),
            moves: a.moves,
            after_motion_end: Spread::of(after),
            joint_call_to_start: Spread::of(joint_start),
            ma_call_to_start: Spread::of(ma_start),
        });
    }
    let robwork = robwork_anchor(a.baud, a.moves)?;
    let r = GatewayReport {
        baud: a.baud,
        through_processes: a.processes,
        robwork_second_motion: robwork,
        speed_round_trip: Spread::of(speed),
        get_position_cart_actual: Spread::of(position),
        finish,
    };
    print_report(&r, a.json, |r| {
        let line = |what: &str, s: &Spread| {
            format!(
                "  {what}: median {:.1} ms, mean {:.1} ms, max {:.1} ms\n",
                s.median_ms, s.mean_ms, s.max_ms
            )
        };
        let mut t = format!(
            "the whole path to a simulated C500, both lines at {} baud{}:\n",
            r.baud,
            if r.through_processes {
                ", through trol gateway and two relays, each a process of its own"
            } else {
                ", in one process"
            }
        );
        t += &line("TROLSpeed round trip", &r.speed_round_trip);
        t += &line(
            "TROLGetPosition (cart, actual)",
            &r.get_position_cart_actual,
        );
        for f in &r.finish {
            t += &line(
                &format!(
                    "Finish(FINISH_WAIT) after the motion's end, completion = {} ({} moves)",
                    f.completion, f.moves
                ),
                &f.after_motion_end,
            );
            t += &line(
                &format!(
                    "  TROLJoint, the call to the arm's start ({})",
                    f.completion
                ),
                &f.joint_call_to_start,
            );
            t += &line(
                &format!("  TROLMA, the call to the arm's start ({})", f.completion),
                &f.ma_call_to_start,
            );
        }
        t += &line(
            "RobWork's way (the motion sent twice; the RAPL-II line alone), after the end",
            &r.robwork_second_motion,
        );
        t.trim_end().to_string()
    })
}

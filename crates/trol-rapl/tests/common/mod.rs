//! The simulated C500 on a thread, over an in-memory line paced at the profile's baud rate,
//! for the backend's tests: what it ran, where its arm is headed, and an emergency stop.

#![allow(dead_code)]

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

use trol_a465::arm::{Arm, ArmSettings, Stored};
use trol_port::Port;
use trol_port::faulty::{FaultConfig, Faulty, Flip, FlipSwitch};
use trol_port::memory;
use trol_rapl::{C500, Profile};

/// The pick example's location.
pub const TEST_001: [f64; 6] = [400.0, 0.0, 150.0, 0.0, std::f64::consts::FRAC_PI_2, 0.0];

/// A simulated C500 on a thread; stops when dropped.
pub struct Sim {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    lines: Arc<Mutex<Vec<String>>>,
    end: Arc<Mutex<[f64; 6]>>,
    estop: Arc<AtomicBool>,
    stall: Arc<AtomicBool>,
    moving: Arc<AtomicBool>,
    power: Arc<AtomicBool>,
}

impl Drop for Sim {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Sim {
    /// Every command line the controller ran.
    pub fn ran(&self) -> Vec<String> {
        self.lines.lock().unwrap().clone()
    }

    /// Where the arm will be once what the controller accepted has ended (radians).
    pub fn planned_end(&self) -> [f64; 6] {
        *self.end.lock().unwrap()
    }

    /// Whether the arm moves.
    pub fn moving(&self) -> bool {
        self.moving.load(Ordering::SeqCst)
    }

    /// Whether the arm has power.
    pub fn has_power(&self) -> bool {
        self.power.load(Ordering::SeqCst)
    }

    /// Cut the arm's power at the controller's next turn (an emergency stop).
    pub fn emergency_stop(&self) {
        self.estop.store(true, Ordering::SeqCst);
    }

    /// Stop the arm silently at the controller's next turn (a servo fault), and wait until it
    /// has.
    pub fn stall(&self) {
        self.stall.store(true, Ordering::SeqCst);
        while self.stall.load(Ordering::SeqCst) {
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
    }
}

/// A simulated C500 as `profile` says, its arm homed or not, at time scale 20.
pub fn start_with(
    profile: Profile,
    homed: bool,
    faults: Option<FaultConfig>,
) -> (Box<dyn Port>, Sim) {
    start_scaled(profile, homed, faults, 20.0)
}

/// Like [`start_with`], at another time scale.
pub fn start_scaled(
    profile: Profile,
    homed: bool,
    faults: Option<FaultConfig>,
    scale: f64,
) -> (Box<dyn Port>, Sim) {
    start_flipped(profile, homed, faults, scale, FlipSwitch::default())
}

/// Like [`start_scaled`], the controller's line damaging a bit when `flip` says so.
pub fn start_flipped(
    profile: Profile,
    homed: bool,
    faults: Option<FaultConfig>,
    scale: f64,
    flip: FlipSwitch,
) -> (Box<dyn Port>, Sim) {
    let (host, ctl) = memory::pair(Some(profile.baud));
    let ctl = Flip::new(ctl, flip);
    let stop = Arc::new(AtomicBool::new(false));
    let lines = Arc::new(Mutex::new(Vec::new()));
    let end = Arc::new(Mutex::new([0.0; 6]));
    let estop = Arc::new(AtomicBool::new(false));
    let stall = Arc::new(AtomicBool::new(false));
    let moving = Arc::new(AtomicBool::new(false));
    let power = Arc::new(AtomicBool::new(true));
    let (flag, keep, ends, cut) = (stop.clone(), lines.clone(), end.clone(), estop.clone());
    let (moves, powered, stalls) = (moving.clone(), power.clone(), stall.clone());
    let thread = std::thread::spawn(move || {
        let arm = Arm::new(ArmSettings {
            homed,
            ..Default::default()
        });
        let locations = vec![("test_001".to_string(), Stored::Cart(TEST_001))];
        let mut c = C500::new(profile, arm, locations);
        let mut port: Box<dyn Port> = match faults {
            Some(f) => Box::new(Faulty::new(ctl, f)),
            None => Box::new(ctl),
        };
        let _ = trol_rapl::c500::serve_with(
            port.as_mut(),
            &mut c,
            scale,
            &flag,
            &mut |l| keep.lock().unwrap().push(l.to_string()),
            &mut |c, now| {
                if cut.swap(false, Ordering::SeqCst) {
                    c.power_off(now);
                }
                if stalls.load(Ordering::SeqCst) {
                    c.stall(now);
                    stalls.store(false, Ordering::SeqCst);
                }
                *ends.lock().unwrap() = c.planned_end();
                moves.store(c.arm_moving(now), Ordering::SeqCst);
                powered.store(c.has_power(), Ordering::SeqCst);
            },
        );
    });
    (
        Box::new(host),
        Sim {
            stop,
            thread: Some(thread),
            lines,
            end,
            estop,
            stall,
            moving,
            power,
        },
    )
}

/// A simulated C500 as `profile` says, its arm homed.
pub fn start(profile: Profile, faults: Option<FaultConfig>) -> (Box<dyn Port>, Sim) {
    start_with(profile, true, faults)
}

/// What a [`Mangle`] does to each incoming chunk.
pub type ChunkFn = Box<dyn FnMut(&mut Vec<u8>) + Send>;

/// A port whose incoming bytes pass through `f` (which sees every chunk, and may change it).
pub struct Mangle {
    pub inner: Box<dyn Port>,
    pub f: ChunkFn,
}

impl Port for Mangle {
    fn send(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.inner.send(bytes)
    }
    fn recv(&mut self, buf: &mut [u8], deadline: std::time::Instant) -> std::io::Result<usize> {
        let n = self.inner.recv(buf, deadline)?;
        let mut v = buf[..n].to_vec();
        (self.f)(&mut v);
        let n = v.len().min(buf.len());
        buf[..n].copy_from_slice(&v[..n]);
        Ok(n)
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

/// TROL's API over the RAPL-II backend on `port`, as `rapl:` embeds it.
pub fn robot(port: Box<dyn Port>, profile: Profile) -> trol::Robot {
    // The backend's log goes to the test's output (shown when it fails).
    let backend = trol_rapl::RaplBackend::connect_with(
        port,
        profile,
        Some(Box::new(|l: &str| eprintln!("c500: {l}"))),
        None,
    )
    .expect("the session opens");
    let cfg = trol_proto::link::LinkConfig::default();
    let (line, handle) = trol_controller::embedded_with(trol_controller::Pcp::new(backend), cfg);
    let mut robot = trol::Robot::over(Box::new(line), cfg, Some(handle));
    robot.set_codes(trol_rapl::RAPL_CODES);
    robot
}

//! `trol bench faults`: the whole stack (Rust API, layers 1-4, the controller's server, the
//! simulated A465) over a damaged line, and what came of every request on both ends.
//!
//! The host's port is wrapped in [`Line`], which damages both directions: bit errors at a
//! rate (noise), or the line going dead at a random byte of a relative move for a while
//! (cuts). The controller logs each request it executed with its reply; at the end the
//! host's calls and the controller's executions are lined up, and counted:
//!
//! - a corrupted request executed: an execution that matches no request the host sent;
//! - a corrupted reply accepted: a call that succeeded with a reply other than the one the
//!   controller sent for it;
//! - a lost move: a relative move reported done that never ran (or, with the manual's
//!   GetStatus method, one the method decided not to send again and that never ran);
//! - a repeated move: a relative move that ran more than once.
//!
//! The soak mode sends mixed moves at time scale 1 and reports the process's memory.

use std::io;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use trol::{PosMode, Robot, Tag};
use trol_a465::arm::ArmSettings;
use trol_controller::{Controller, Mode, Pcp};
use trol_port::faulty::{FaultConfig, FaultInjector};
use trol_port::{Port, memory};
use trol_proto::application::record::{self, Value};
use trol_proto::application::{CommandDef, Location, Reply, table};
use trol_proto::link::{BlockCheck, LinkConfig, Timeouts};
use trol_sim::{SimBackend, SimSettings};

/// What to do to the line.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum FaultMode {
    /// Random bit errors in both directions at --ber.
    Noise,
    /// For each relative move, the line goes dead at a random byte of its request
    /// (--side request) or of its reply (--side reply) for a while.
    Cut,
    /// Mixed moves at time scale 1 on a clean line; report the memory the process uses.
    Soak,
}

/// Which direction a cut hits.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    /// The request, host to controller.
    Request,
    /// The reply, controller to host.
    Reply,
}

/// How an application recovers from a failed call.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Recovery {
    /// TROL's default: the host repeats the request under the same number (exactly once).
    Api,
    /// trol.h's method: repeats off; after a failure, GetStatus with the transaction it
    /// speaks of (TROLGetStatusOf, TROLLastTransaction) decides whether to send the move
    /// again.
    Getstatus,
    /// The manual's plain method: repeats off; after a failure, GetStatus's BIOSCalled alone
    /// decides (called: it ran, its result is lastBIOSRetVal; not called: send it again).
    Manual,
}

/// One experiment.
#[derive(Clone, Debug)]
pub struct Plan {
    pub mode: FaultMode,
    pub count: u64,
    pub ber: f64,
    pub seed: u64,
    pub side: Side,
    pub recovery: Recovery,
    pub check: BlockCheck,
    /// Soak: how long to run.
    pub seconds: f64,
    /// Cut: how long the line stays dead.
    pub cut_length: Duration,
}

/// What came of it.
#[derive(Debug, Default, Serialize)]
pub struct Report {
    pub mode: String,
    pub check: String,
    pub recovery: String,
    pub ber: f64,
    pub seed: u64,
    /// Calls made.
    pub transactions: u64,
    /// Calls that ended in an error (TROL_ERR_COMM, TROL_ERR_BAD_RSIZE).
    pub failed_calls: u64,
    /// Bits flipped on the line, both directions.
    pub flipped_bits: u64,
    /// Cuts made, and how long each lasted, ms.
    pub cuts: u64,
    pub cut_ms: u64,
    /// Requests the controller executed that the host never sent (corrupted on the way).
    pub corrupted_requests_executed: u64,
    /// Replies the host accepted that the controller never sent.
    pub corrupted_replies_accepted: u64,
    /// Relative moves sent.
    pub relative_moves: u64,
    /// Relative moves that never ran though the application was told (or decided) they had.
    pub lost_moves: u64,
    /// Relative moves that ran more than once.
    pub repeated_moves: u64,
    /// Relative moves that failed with TROL_ERR_COMM but ran (the API's failure is then
    /// ambiguous, and GetStatus tells).
    pub failed_but_ran: u64,
    /// Requests the controller ran that its log does not show (every execution must be
    /// logged, whatever became of its reply).
    pub unlogged_executions: u64,
    /// Soak: the process's resident memory at the start and the end, kB.
    pub rss_start_kb: Option<u64>,
    pub rss_end_kb: Option<u64>,
    pub seconds: f64,
}

/// A cut in the making: after `at` more bytes in the chosen direction the line is dead until
/// `until`.
#[derive(Default)]
struct Cut {
    at: Option<(Side, u64)>,
    until: Option<Instant>,
    length: Duration,
    made: u64,
}

impl Cut {
    fn dead(&mut self) -> bool {
        match self.until {
            Some(t) if Instant::now() < t => true,
            Some(_) => {
                self.until = None;
                false
            }
            None => false,
        }
    }

    /// `n` bytes pass in `side`: returns how many get through before the line dies.
    fn pass(&mut self, side: Side, n: usize) -> usize {
        if self.dead() {
            return 0;
        }
        match self.at {
            Some((s, left)) if s == side => {
                if (n as u64) <= left {
                    self.at = Some((s, left - n as u64));
                    n
                } else {
                    self.at = None;
                    self.until = Some(Instant::now() + self.length);
                    self.made += 1;
                    left as usize
                }
            }
            _ => n,
        }
    }
}

/// The host's port with a damaged line behind it, both directions.
struct Line<P> {
    inner: P,
    tx: FaultInjector,
    rx: FaultInjector,
    cut: Arc<Mutex<Cut>>,
    scratch: Vec<u8>,
    /// Bits flipped so far, both directions.
    flipped: Arc<AtomicU64>,
}

impl<P> Line<P> {
    fn count(&self) {
        let n = self.tx.stats().flipped_bits + self.rx.stats().flipped_bits;
        self.flipped.store(n, Ordering::Relaxed);
    }
}

impl<P: Port> Port for Line<P> {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        let n = self
            .cut
            .lock()
            .map_err(|_| io::Error::other("poisoned"))?
            .pass(Side::Request, bytes.len());
        self.scratch.clear();
        self.tx.apply(&bytes[..n], &mut self.scratch);
        self.count();
        if self.scratch.is_empty() {
            return Ok(());
        }
        self.inner.send(&self.scratch)
    }

    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        loop {
            let n = self.inner.recv(buf, deadline)?;
            if n == 0 {
                return Ok(0);
            }
            let kept = self
                .cut
                .lock()
                .map_err(|_| io::Error::other("poisoned"))?
                .pass(Side::Reply, n);
            if kept > 0 {
                self.scratch.clear();
                self.rx.apply(&buf[..kept], &mut self.scratch);
                self.count();
                let m = self.scratch.len().min(buf.len());
                buf[..m].copy_from_slice(&self.scratch[..m]);
                return Ok(m);
            }
            if Instant::now() >= deadline {
                return Ok(0);
            }
        }
    }

    fn available(&mut self) -> io::Result<usize> {
        self.inner.available()
    }

    fn flush_input(&mut self) -> io::Result<()> {
        self.inner.flush_input()
    }

    fn name(&self) -> String {
        format!("damaged({})", self.inner.name())
    }
}

/// What the controller executed.
struct Execution {
    request: Vec<u8>,
    reply: Vec<u8>,
}

/// What the host asked, and what it accepted.
struct Asked {
    request: Vec<u8>,
    /// The reply the API returned, as bytes; None when the call failed (or not checked).
    accepted: Option<Vec<u8>>,
    relative: bool,
}

/// The link's times for a memory line: short, so that faults cost little time (the
/// proportions between them as for a serial line).
fn link(check: BlockCheck) -> LinkConfig {
    LinkConfig {
        timeouts: Timeouts::uniform(Duration::from_millis(15)),
        check,
        ..LinkConfig::default()
    }
}

/// Run one experiment.
pub fn run(plan: &Plan) -> Result<Report, String> {
    let started = Instant::now();
    let soak = plan.mode == FaultMode::Soak;
    let settings = SimSettings {
        arm: ArmSettings {
            homed: true,
            ..ArmSettings::default()
        },
        time_scale: if soak { 1.0 } else { 1e6 },
        ..SimSettings::default()
    };
    let cfg = link(plan.check);
    let (host, ctl) = memory::pair(None);
    let mut controller =
        Controller::new(ctl, cfg, Pcp::new(SimBackend::new(settings)), Mode::Server);
    let executed: Arc<Mutex<Vec<Execution>>> = Arc::default();
    if !soak {
        let log = executed.clone();
        controller.set_log(Box::new(move |e| {
            if e.executed
                && let Ok(mut l) = log.lock()
            {
                l.push(Execution {
                    request: e.request.to_vec(),
                    reply: e.reply.to_vec(),
                });
            }
        }));
    }
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    let server = std::thread::spawn(move || {
        let _ = controller.run(&flag);
        controller
    });

    let noise = |seed| FaultConfig {
        seed,
        bit_error_rate: if plan.mode == FaultMode::Noise {
            plan.ber
        } else {
            0.0
        },
        ..FaultConfig::default()
    };
    let cut = Arc::new(Mutex::new(Cut {
        length: plan.cut_length,
        ..Cut::default()
    }));
    let flipped = Arc::new(AtomicU64::new(0));
    let line = Line {
        inner: host,
        tx: FaultInjector::new(noise(plan.seed.wrapping_mul(2).wrapping_add(1))),
        rx: FaultInjector::new(noise(plan.seed.wrapping_mul(2).wrapping_add(2))),
        cut: cut.clone(),
        scratch: Vec::new(),
        flipped: flipped.clone(),
    };
    let mut robot = Robot::over(Box::new(line), cfg, None);
    robot
        .set_reply_timeout_tenths(3)
        .map_err(|e| e.to_string())?;
    // The controller is this process's own, with its memory of the last request: the
    // repeats a version handshake would grant, without one over the noisy line.
    robot.set_repeats(match plan.recovery {
        Recovery::Api => trol_comm::DEFAULT_REPEATS,
        Recovery::Getstatus | Recovery::Manual => 0,
    });
    let mut rng = ChaCha8Rng::seed_from_u64(plan.seed);
    let mut asked: Vec<Asked> = Vec::new();
    let mut report = Report {
        mode: format!("{:?}", plan.mode).to_lowercase(),
        check: format!("{:?}", plan.check).to_lowercase(),
        recovery: format!("{:?}", plan.recovery).to_lowercase(),
        ber: if plan.mode == FaultMode::Noise {
            plan.ber
        } else {
            0.0
        },
        seed: plan.seed,
        rss_start_kb: rss_kb(),
        ..Report::default()
    };
    // First contact (InitTROL makes one with GetStatus): the controller then remembers a
    // transaction, so a repeat of the first move is placed. A repeat that reaches a
    // controller remembering nothing is answered TROL_ERR_ROBOT_UNSURE and not run.
    if !soak {
        let args = [Value::Int(100)];
        let request = record::encode(&table::SPEED, &args).map_err(|e| e.to_string())?;
        let mut contact = Err(String::new());
        for _ in 0..20 {
            contact = robot.call(&table::SPEED, &args).map_err(|e| e.to_string());
            if contact.is_ok() {
                break;
            }
        }
        contact.map_err(|e| format!("first contact failed 20 times: {e}"))?;
        asked.push(Asked {
            request,
            accepted: None,
            relative: false,
        });
        // And the controller's epoch, as InitTROL's check reads it: a call in doubt before
        // the host knew an epoch would be answered UNSURE (docs/reliability.md).
        let mut status = Err(String::new());
        for _ in 0..20 {
            status = robot.status_record().map_err(|e| e.to_string());
            if status.is_ok() {
                break;
            }
        }
        status.map_err(|e| format!("GetStatus at first contact failed 20 times: {e}"))?;
        asked.push(Asked {
            request: record::encode(&table::GET_STATUS, &[]).map_err(|e| e.to_string())?,
            accepted: None,
            relative: false,
        });
    }
    let deadline = started + Duration::from_secs_f64(plan.seconds);
    let mut n = 0u64;
    while if soak {
        Instant::now() < deadline
    } else {
        n < plan.count
    } {
        n += 1;
        let pick = rng.random_range(0..10);
        if soak {
            soak_step(&mut robot, &mut rng, pick);
            report.transactions += 1;
            continue;
        }
        // Mostly relative moves (what must run exactly once), with positions and speeds.
        let (def, args): (&CommandDef, Vec<Value>) = match pick {
            0..=5 => {
                // A unique increment per move, so that every request is told apart.
                let dq: Vec<f64> = (0..6)
                    .map(|j| {
                        let unique = (n as f64) * 1e-7;
                        if j == 0 {
                            unique
                        } else {
                            rng.random_range(-1e-4..1e-4)
                        }
                    })
                    .collect();
                (&table::MI, vec![Value::Loc(Location::Joint(dq))])
            }
            6..=8 => (
                &table::GET_POSITION,
                vec![
                    Value::Int(Tag::Joint as u8),
                    Value::Int(table::POS_COMMANDED),
                ],
            ),
            _ => (&table::SPEED, vec![Value::Int(rng.random_range(1..=100))]),
        };
        let relative = def.code == table::MI.code;
        if relative && plan.mode == FaultMode::Cut {
            let side = plan.side;
            // A random byte of the move's exchange on that side (a request of MI is about
            // 40 bytes on the line with framing, a reply about 12).
            let span = if side == Side::Request { 40 } else { 12 };
            if let Ok(mut c) = cut.lock() {
                c.at = Some((side, rng.random_range(0..span)));
            }
        }
        let request = record::encode(def, &args).map_err(|e| e.to_string())?;
        let number_before = robot.last_transaction();
        let result = if def.code == table::GET_POSITION.code {
            robot
                .position(Tag::Joint, PosMode::Commanded)
                .map(|loc| Reply::Position(loc).encode())
        } else {
            robot
                .call(def, &args)
                .map(|r| r.encode())
                .or_else(|e| match e {
                    trol::Error::Refused { code, .. } => Ok(Reply::Code(code).encode()),
                    e => Err(e),
                })
        };
        report.transactions += 1;
        if let Ok(mut c) = cut.lock() {
            c.at = None;
        }
        let mut accepted = result.as_ref().ok().cloned();
        if result.is_err() {
            report.failed_calls += 1;
            if relative && plan.recovery != Recovery::Api {
                accepted = if plan.recovery == Recovery::Manual {
                    manual_method(&mut robot, def, &args, &mut report)?
                } else {
                    getstatus_method(&mut robot, def, &args, number_before, &mut report)?
                };
                // Its GetStatus requests were sent by the host too.
                asked.push(Asked {
                    request: record::encode(&table::GET_STATUS, &[]).map_err(|e| e.to_string())?,
                    accepted: None,
                    relative: false,
                });
            }
        }
        asked.push(Asked {
            request,
            accepted,
            relative,
        });
    }
    // Let the controller log its last transaction, then stop it.
    std::thread::sleep(Duration::from_millis(200));
    stop.store(true, Ordering::SeqCst);
    drop(robot);
    let handled = server
        .join()
        .map_err(|_| "the controller's thread panicked")?
        .pcp_mut()
        .handled();
    report.flipped_bits = flipped.load(Ordering::Relaxed);
    if plan.mode == FaultMode::Cut {
        report.cut_ms = plan.cut_length.as_millis() as u64;
    }
    report.cuts = cut.lock().map(|c| c.made).unwrap_or(0);
    report.rss_end_kb = rss_kb();
    report.seconds = started.elapsed().as_secs_f64();
    if !soak {
        let executed = std::mem::take(&mut *executed.lock().map_err(|_| "poisoned")?);
        report.unlogged_executions = handled.saturating_sub(executed.len() as u64);
        line_up(&asked, &executed, &mut report);
    }
    Ok(report)
}

/// The manual's method after a failed relative move (section "Transaktions-Schicht",
/// GetStatus): wait for the line, ask GetStatus; if its status belongs to the move's
/// transaction the move ran, else send it again. Returns the reply finally accepted.
fn getstatus_method(
    robot: &mut Robot,
    def: &CommandDef,
    args: &[Value],
    number_before: u8,
    report: &mut Report,
) -> Result<Option<Vec<u8>>, String> {
    let mut before = number_before;
    let mut sent = robot.last_transaction();
    for _ in 0..20 {
        std::thread::sleep(Duration::from_millis(150));
        let _ = robot.flush_input();
        report.transactions += 1;
        let Ok(status) = robot.status_record() else {
            report.failed_calls += 1;
            continue;
        };
        if sent != before && status.transaction == sent && status.bios_called {
            if status.last == trol::code::TROL_ERR_ROBOT_UNSURE {
                // It may have run, and GetStatus cannot tell (the controller restarted): the
                // documented method reads the arm; this bench has no restarts, so say so.
                return Err(format!(
                    "GetStatus answered TROL_ERR_ROBOT_UNSURE for transaction {sent} with no \
                     restart of the controller"
                ));
            }
            // It ran: its result is GetStatus's.
            return Ok(Some(Reply::Code(status.last).encode()));
        }
        // It did not run: send it again (a new transaction).
        report.transactions += 1;
        before = robot.last_transaction();
        match robot.call(def, args) {
            Ok(r) => return Ok(Some(r.encode())),
            Err(trol::Error::Refused { code, .. }) => return Ok(Some(Reply::Code(code).encode())),
            Err(_) => {
                report.failed_calls += 1;
                sent = robot.last_transaction();
            }
        }
    }
    Err("the line did not come back for the GetStatus method".into())
}

/// The manual's GetStatus method after a failed call: BIOSCalled says whether it ran (then
/// lastBIOSRetVal is its result), else it is sent again. TROL_ERR_ROBOT_UNSURE (the
/// controller cannot place it) stops the run: the manual's method would have to read the
/// arm, and this bench has no restarts.
fn manual_method(
    robot: &mut Robot,
    def: &CommandDef,
    args: &[Value],
    report: &mut Report,
) -> Result<Option<Vec<u8>>, String> {
    for _ in 0..20 {
        std::thread::sleep(Duration::from_millis(150));
        let _ = robot.flush_input();
        report.transactions += 1;
        let Ok((called, last)) = robot.status() else {
            report.failed_calls += 1;
            continue;
        };
        if last == trol::code::TROL_ERR_ROBOT_UNSURE {
            return Err("GetStatus answered TROL_ERR_ROBOT_UNSURE with no restart".into());
        }
        if called {
            return Ok(Some(Reply::Code(last).encode()));
        }
        report.transactions += 1;
        match robot.call(def, args) {
            Ok(r) => return Ok(Some(r.encode())),
            Err(trol::Error::Refused { code, .. }) => return Ok(Some(Reply::Code(code).encode())),
            Err(_) => report.failed_calls += 1,
        }
    }
    Err("the line did not come back for the GetStatus method".into())
}

/// Count what came of the host's calls by the controller's executions. Every relative move
/// is unique (its first increment carries its number), so its executions are counted by its
/// bytes; any execution of bytes the host never sent was corrupted on the way.
fn line_up(asked: &[Asked], executed: &[Execution], report: &mut Report) {
    use std::collections::{HashMap, HashSet};
    let mut replies: HashMap<&[u8], Vec<&[u8]>> = HashMap::new();
    for e in executed {
        replies.entry(&e.request).or_default().push(&e.reply);
    }
    let sent: HashSet<&[u8]> = asked.iter().map(|a| a.request.as_slice()).collect();
    report.corrupted_requests_executed = executed
        .iter()
        .filter(|e| !sent.contains(e.request.as_slice()))
        .count() as u64;
    for a in asked {
        let ran = replies
            .get(a.request.as_slice())
            .map_or(&[][..], |v| v.as_slice());
        if let Some(got) = &a.accepted
            && !ran.contains(&got.as_slice())
        {
            report.corrupted_replies_accepted += 1;
            // Each one is worth a look: what was asked, what was taken, what ran.
            tell!(
                "a reply the controller never sent was accepted: request {:02x?}, accepted \
                 {got:02x?}, the controller's {} replies to those bytes (the first 3) {:02x?}",
                a.request,
                ran.len(),
                &ran[..ran.len().min(3)]
            );
        }
        if a.relative {
            report.relative_moves += 1;
            match (ran.len(), a.accepted.is_some()) {
                (0, true) => report.lost_moves += 1,
                (1, false) => report.failed_but_ran += 1,
                (k, _) if k >= 2 => report.repeated_moves += 1,
                _ => {}
            }
        }
    }
}

/// The soak's traffic: mixed moves as a program sends them, waiting when the controller's
/// queue is full.
fn soak_step(robot: &mut Robot, rng: &mut ChaCha8Rng, pick: u32) {
    let r = match pick {
        0..=3 => {
            let q: Vec<f64> = (0..6).map(|_| rng.random_range(-0.3..0.3)).collect();
            robot.ma(&q)
        }
        4..=5 => robot.mi(&[rng.random_range(-0.05..0.05), 0.0, 0.0]),
        6 => robot.position(Tag::Cart, PosMode::Actual).map(drop),
        7 => robot.is_moving().map(drop),
        8 => robot.speed(rng.random_range(50..=150)),
        _ => robot.halt(),
    };
    if let Err(e) = r
        && e.code().0 == trol_a465::arm::code::QUEUE_FULL
    {
        let _ = robot.halt();
    }
}

/// The process's resident memory, kB (Linux; None elsewhere).
pub fn rss_kb() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    status
        .lines()
        .find(|l| l.starts_with("VmRSS:"))?
        .split_whitespace()
        .nth(1)?
        .parse()
        .ok()
}

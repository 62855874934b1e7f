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

mod calls;
mod connect;
mod exactly_once;
mod waits;

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

/// The manual's LRC on [`steady`] timeouts.
fn lrc_steady() -> LinkConfig {
    LinkConfig {
        check: trol_proto::link::BlockCheck::Lrc,
        ..steady()
    }
}

/// The simulated A465 ([`settings`]) behind the PCP server on `port`, in `mode`.
fn sim_controller<P: Port>(
    port: P,
    cfg: LinkConfig,
    mode: trol_controller::Mode,
) -> trol_controller::Controller<P, SimBackend> {
    trol_controller::Controller::new(port, cfg, Pcp::new(SimBackend::new(settings())), mode)
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

// Extending TROL with new commands, as the manual's section "Erweiterung von TROL um eigene
// Kommandos" describes, without touching the library: a code in its class's range (the
// next free one), a record, a handler in the dispatch table, and an API function.

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

/// Counts the layer-3 failures it is told of, and gives up.
struct Counting(Arc<std::sync::atomic::AtomicUsize>);

impl trol_comm::ErrorHandlers for Counting {
    fn err_on_send(&mut self, _ctx: &trol_comm::FailureContext<'_>) -> trol_comm::Recovery {
        self.0.fetch_add(1, Ordering::SeqCst);
        trol_comm::Recovery::Fail
    }
}

//! A live 3D view of the simulated A465 in the browser (`trol sim --view`, `trol demo
//! --view`, trol.cfg's `view = ADDR`).
//!
//! The controller side serves it, so every client (C, Rust, Python, the interpreter) gets it
//! without code of its own. The server answers GET requests only:
//!
//! | path | what |
//! |---|---|
//! | `/` | the page: the arm drawn from its URDF (three.js), the table, the tool's trail, the target of the motion under way, the gripper and the world's objects, each joint's value against its limits, a plot of the joints over the last seconds |
//! | `/state` | the state as JSON: `joints` (6, rad), `tcp` (x, y, z mm, yaw, pitch, roll rad), `moving`, `gripper_mm`, `objects`, `time` (s, the simulation's), and `target`, `limits`, `table_z` |
//! | `/events` | the same state as server-sent events: 50 a second while the arm moves, one when it stops, then a comment every 10 s to keep the connection |
//! | `/urdf` | the arm's URDF (`trol urdf`) |
//! | `/three.module.js`, `/three.core.js`, `/OrbitControls.js` | three.js 0.187.0 from the npm registry, embedded (MIT licence: `/LICENSE-three.js.txt`, THIRD_PARTY.md) |
//!
//! The view never slows the controller: the controller renews what its backend reports of
//! the arm ([`trol_controller::Backend::report`], a few numbers, no copy of the arm) at most
//! every [`REPORT_INTERVAL`]; this server's threads encode it once for every viewer. A client that stops reading is
//! dropped once its socket's buffer is full and a write has waited a second; one that closes
//! is noticed within a round. Each kind of request has its own limit: [`MAX_CLIENTS`] for the
//! page, its files and `/state`, [`MAX_STREAMS`] `/events` streams, [`MAX_CONTROL`]
//! pendant requests and [`MAX_HALT`] Halts besides, so that no number of open pages, nor of
//! other pendant requests, keeps a Halt from the pendant out. Connections still sending
//! their request's head wait in one thread ([`intake`]): however many send nothing, a
//! request that comes whole is read at once. Only requests for this machine's names or the
//! view's own address are answered, and from no other page's scripts (DNS rebinding).
//!
//! With `--control`, the page is also a pendant that drives the arm ([`pendant`]); without
//! it, nothing can be moved through the view.
//!
//! The server is a few dozen lines on `std::net` and mio instead of an HTTP crate: it serves
//! GET (and the pendant's POST, whose arguments are in the query), and each event stream
//! needs a write timeout of its own, which std gives directly.

#![forbid(unsafe_code)]
#![warn(missing_docs, missing_debug_implementations)]

pub mod intake;
pub mod pendant;

pub use intake::{HEAD_DEADLINE, MAX_WAITING};
pub use pendant::Control;

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use serde_json::json;
use trol_a465::model::LIMITS_RAD;
use trol_controller::SharedReport;

/// The address the view listens on by default: this machine only.
pub const DEFAULT_ADDR: &str = "127.0.0.1:8465";

/// How often a moving arm's state is sent.
pub const EVENT_INTERVAL: Duration = Duration::from_millis(20);

/// How long a request waits for the controller's report of now after a time with nobody
/// watching (the controller renews its report only while someone reads it); past that it gets
/// the latest report there is.
pub const FRESH_WAIT: Duration = Duration::from_millis(300);

/// How often the controller renews its report for a view of the simulated arm
/// ([`trol_controller::Controller::share_reports`]); a real controller's backend, which asks
/// the controller for each, is asked less often (`trol gateway`: every 100 ms).
pub const REPORT_INTERVAL: Duration = EVENT_INTERVAL;

/// At most this many requests for the page, its files and `/state` are answered at once
/// (a page opens a few while it loads); more get 503.
pub const MAX_CLIENTS: usize = 32;

/// At most this many `/events` streams are held open at once (one per open page); more get
/// 503. Apart from [`MAX_CLIENTS`] and [`MAX_CONTROL`]: open pages never keep the page's
/// files, nor the pendant, out.
pub const MAX_STREAMS: usize = 32;

/// At most this many pendant requests (`/control/...`) are answered at once, apart from every
/// viewer: a Halt from the pendant never waits behind open pages (issue 37).
pub const MAX_CONTROL: usize = 8;

/// At most this many pendant Halts (`/control/halt`) are answered at once, apart from the
/// other pendant requests: a Halt never waits behind jogs or a flood of them (issue 67).
pub const MAX_HALT: usize = 4;

const INDEX: &str = include_str!("../assets/index.html");
const APP: &str = include_str!("../assets/app.js");
const THREE_MODULE: &str = include_str!("../vendor/three/three.module.js");
const THREE_CORE: &str = include_str!("../vendor/three/three.core.js");
const ORBIT: &str = include_str!("../vendor/three/OrbitControls.js");
const THREE_LICENCE: &str = include_str!("../vendor/three/LICENSE-three.js.txt");

/// The arm's state as `/state` and `/events` give it, from what its backend last reported
/// ([`trol_controller::ArmReport`]: the simulated arm, or a real arm behind `trol gateway`);
/// `None` before the first report. `time` is the controller's clock (the simulation's), or
/// seconds from when this process first served a report; `objects` are the simulated
/// world's (a real controller knows of none).
pub fn state(shared: &SharedReport) -> Option<serde_json::Value> {
    static EPOCH: std::sync::OnceLock<std::time::Instant> = std::sync::OnceLock::new();
    let epoch = *EPOCH.get_or_init(std::time::Instant::now);
    let (r, at) = shared.latest()?;
    let at = &at;
    let kin = trol_a465::kinematics::Kinematics::new(r.tool);
    let tcp = kin.fk_xyzypr(&r.joints);
    let target_tcp = r.target.map(|t| kin.fk_xyzypr(&t));
    let objects: Vec<serde_json::Value> = r
        .objects
        .iter()
        .map(|o| {
            json!({
                "name": o.name,
                "x": o.pos[0], "y": o.pos[1], "z": o.pos[2],
                "width": o.width,
                "held": o.held,
            })
        })
        .collect();
    let time = r
        .time
        .unwrap_or_else(|| at.saturating_duration_since(epoch).as_secs_f64());
    let mut state = json!({
        "joints": r.joints,
        "tcp": tcp,
        "moving": r.moving,
        "gripper_mm": r.gripper_mm,
        "objects": objects,
        "time": time,
        "target": r.target,
        "target_tcp": target_tcp,
        "limits": LIMITS_RAD,
        "table_z": r.table_z.unwrap_or(0.0),
        "tool": r.tool,
    });
    if !r.simulated {
        state["homed"] = json!(r.homed);
        state["reported"] = json!(true);
    }
    Some(state)
}

/// One encoding of the arm's state, shared by every viewer.
#[derive(Debug)]
struct Frame {
    state: serde_json::Value,
    text: String,
}

/// The arm's state as the viewers get it: taken from the source and encoded at most once per
/// half [`EVENT_INTERVAL`], whatever the number of viewers (each stream used to take and
/// encode its own).
struct Frames {
    source: SharedReport,
    last: Mutex<Option<(std::time::Instant, Arc<Frame>)>>,
    /// How long a frame serves.
    max_age: Duration,
}

impl Frames {
    fn new(source: SharedReport) -> Frames {
        Frames::with_age(source, EVENT_INTERVAL / 2)
    }

    fn with_age(source: SharedReport, max_age: Duration) -> Frames {
        Frames {
            source,
            last: Mutex::new(None),
            max_age,
        }
    }

    /// The newest frame; `None` before the controller shared its arm.
    fn frame(&self) -> Option<Arc<Frame>> {
        let mut last = self.last.lock().unwrap_or_else(|p| p.into_inner());
        // The controller renews its report only while someone reads it: after a time with
        // nobody watching, wait (a little) for a report of now.
        let asked = std::time::Instant::now();
        if !self.source.want() {
            while asked.elapsed() < FRESH_WAIT
                && self.source.latest().is_none_or(|(_, at)| at < asked)
            {
                std::thread::sleep(Duration::from_millis(2));
            }
        } else if let Some((at, frame)) = last.as_ref() {
            if at.elapsed() < self.max_age {
                return Some(frame.clone());
            }
        }
        let state = state(&self.source)?;
        let text = state.to_string();
        let frame = Arc::new(Frame { state, text });
        *last = Some((std::time::Instant::now(), frame.clone()));
        Some(frame)
    }
}

/// A running view server; it stops when dropped.
#[derive(Debug)]
pub struct ViewServer {
    addr: SocketAddr,
    stop: Arc<AtomicBool>,
    watchers: Watchers,
}

/// How many pages have watched a view: its `/events` streams opened since it started (a
/// page opens one as it loads). A program that shows a short motion waits for the first
/// ([`ViewServer::watchers`]; `trol demo --view`).
#[derive(Clone, Debug, Default)]
pub struct Watchers(Arc<AtomicUsize>);

impl Watchers {
    /// The streams opened so far.
    pub fn opened(&self) -> usize {
        self.0.load(Ordering::SeqCst)
    }
}

impl ViewServer {
    /// The address it listens on (with the port the system gave, for port 0).
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// Who watches: the pages that opened the view's event stream.
    pub fn watchers(&self) -> Watchers {
        self.watchers.clone()
    }

    /// The page's address.
    pub fn url(&self) -> String {
        format!("http://{}/", self.addr)
    }

    /// A warning to show when the view is open to other machines (an address that is not
    /// loopback); `None` for this machine only.
    pub fn exposure(&self) -> Option<String> {
        (!self.addr.ip().is_loopback()).then(|| {
            format!(
                "the view at {} is open to every machine that can reach this one, without a \
                 password (it shows the arm; only this machine, or an address named with \
                 --control-from, can drive it, and only with --control and its token)",
                self.addr
            )
        })
    }
}

impl Drop for ViewServer {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        // Wake the accept loop.
        let _ = TcpStream::connect_timeout(&self.addr, Duration::from_millis(200));
    }
}

/// Serve the view of what a backend reports ([`trol_controller::Controller::share_reports`]:
/// the simulated arm, or a real one behind `trol gateway`) on `addr` (`host:port`; port 0
/// picks a free one), on threads of its own.
pub fn serve(addr: &str, shared: SharedReport) -> std::io::Result<ViewServer> {
    serve_controlled(addr, shared, None)
}

/// [`serve`], and with `control` the pendant ([`pendant`]).
pub fn serve_controlled(
    addr: &str,
    shared: SharedReport,
    control: Option<Control>,
) -> std::io::Result<ViewServer> {
    let control = Arc::new(control);
    let listener = TcpListener::bind(addr).map_err(|e| {
        let hint = match e.kind() {
            std::io::ErrorKind::AddrInUse => {
                " (another program uses that port: name another, like 127.0.0.1:8466)"
            }
            std::io::ErrorKind::AddrNotAvailable => {
                " (no interface of this machine has that address: 127.0.0.1 is this machine only)"
            }
            _ => "",
        };
        std::io::Error::new(e.kind(), format!("{e}{hint}"))
    })?;
    let local = listener.local_addr()?;
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    let served = Served {
        slots: Arc::new(Slots::default()),
        frames: Arc::new(Frames::new(shared)),
        control,
        names: intake::Names::new(addr),
        stop: stop.clone(),
    };
    let watchers = Watchers::default();
    let opened = watchers.clone();
    std::thread::Builder::new()
        .name("trol-view".into())
        .spawn(move || {
            let _ = intake::run(listener, &flag, |conn, head| {
                served.dispatch(conn, head, &opened);
            });
        })?;
    Ok(ViewServer {
        addr: local,
        stop,
        watchers,
    })
}

/// What every request is answered from.
struct Served {
    slots: Arc<Slots>,
    frames: Arc<Frames>,
    control: Arc<Option<Control>>,
    names: intake::Names,
    stop: Arc<AtomicBool>,
}

impl Served {
    /// A request whose head came whole: checked, and answered on a thread of its own if its
    /// kind has room (else 503).
    fn dispatch(&self, mut conn: TcpStream, head: intake::Head, opened: &Watchers) {
        // What is written here is small enough for a new connection's buffer; the limit
        // keeps the intake from waiting on a client that does not read in any case.
        let _ = conn.set_write_timeout(Some(Duration::from_millis(200)));
        if let Err(why) = self.names.check(&head, intake::local_ip(&conn)) {
            let _ = refuse(&mut conn, &head.target, "403 Forbidden", &why);
            return;
        }
        let kind = Kind::of(&head.target);
        let slots = self.slots.clone();
        if slots.of(kind).fetch_add(1, Ordering::SeqCst) >= kind.limit() {
            slots.of(kind).fetch_sub(1, Ordering::SeqCst);
            too_many(&mut conn);
            return;
        }
        if kind == Kind::Stream {
            opened.0.fetch_add(1, Ordering::SeqCst);
        }
        let (frames, control, stop) =
            (self.frames.clone(), self.control.clone(), self.stop.clone());
        let spawned = std::thread::Builder::new()
            .name("trol-view-client".into())
            .spawn(move || {
                let _ = answer(conn, head, &frames, &stop, control.as_ref().as_ref());
                slots.of(kind).fetch_sub(1, Ordering::SeqCst);
            });
        if spawned.is_err() {
            self.slots.of(kind).fetch_sub(1, Ordering::SeqCst);
        }
    }
}

/// The kinds of request, each with a limit of its own.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// The page, its files, `/state`: [`MAX_CLIENTS`].
    File,
    /// `/events`: [`MAX_STREAMS`].
    Stream,
    /// The pendant's requests but Halt: [`MAX_CONTROL`].
    Control,
    /// The pendant's Halt: [`MAX_HALT`].
    Halt,
}

impl Kind {
    fn of(target: &str) -> Kind {
        let bare = target.split('?').next().unwrap_or(target);
        if bare == "/control/halt" {
            Kind::Halt
        } else if bare == "/control" || bare.starts_with("/control/") {
            Kind::Control
        } else if bare == "/events" {
            Kind::Stream
        } else {
            Kind::File
        }
    }

    fn limit(self) -> usize {
        match self {
            Kind::File => MAX_CLIENTS,
            Kind::Stream => MAX_STREAMS,
            Kind::Control => MAX_CONTROL,
            Kind::Halt => MAX_HALT,
        }
    }
}

/// The requests answered now, by kind.
#[derive(Default)]
struct Slots {
    files: AtomicUsize,
    streams: AtomicUsize,
    control: AtomicUsize,
    halts: AtomicUsize,
}

impl Slots {
    fn of(&self, kind: Kind) -> &AtomicUsize {
        match kind {
            Kind::File => &self.files,
            Kind::Stream => &self.streams,
            Kind::Control => &self.control,
            Kind::Halt => &self.halts,
        }
    }
}

/// Turn a connection away: the server is full.
fn too_many(conn: &mut TcpStream) {
    let _ = respond(
        conn,
        "503 Service Unavailable",
        "text/plain",
        b"too many viewers at once: close a page and reload\n",
    );
}

/// Refuse a request in words: the pendant's JSON for its paths (as its other answers), text
/// for the others.
fn refuse(
    conn: &mut TcpStream,
    target: &str,
    status: &'static str,
    why: &str,
) -> std::io::Result<()> {
    if matches!(Kind::of(target), Kind::Control | Kind::Halt) {
        let (status, body) = pendant::refusal(status, why);
        respond(
            conn,
            status,
            "application/json",
            body.to_string().as_bytes(),
        )
    } else {
        respond(conn, status, "text/plain", format!("{why}\n").as_bytes())
    }
}

fn respond(conn: &mut TcpStream, status: &str, kind: &str, body: &[u8]) -> std::io::Result<()> {
    write!(
        conn,
        "HTTP/1.1 {status}\r\nContent-Type: {kind}\r\nContent-Length: {}\r\n\
         Cache-Control: no-store\r\nConnection: close\r\n\r\n",
        body.len()
    )?;
    conn.write_all(body)?;
    conn.flush()
}

/// Answer one request, whose head was read.
fn answer(
    mut conn: TcpStream,
    head: intake::Head,
    shared: &Frames,
    stop: &AtomicBool,
    control: Option<&Control>,
) -> std::io::Result<()> {
    conn.set_read_timeout(Some(Duration::from_secs(5)))?;
    // A client that stops reading is dropped: every write must go through within a second.
    conn.set_write_timeout(Some(Duration::from_secs(1)))?;
    let intake::Head {
        method,
        target: path,
        ..
    } = head;
    if path == "/control" || path.starts_with("/control/") || path.starts_with("/control?") {
        let peer = conn.peer_addr().ok().map(|a| a.ip());
        let (status, body) = pendant::answer(&method, &path, peer, control);
        return respond(
            &mut conn,
            status,
            "application/json",
            body.to_string().as_bytes(),
        );
    }
    if method != "GET" {
        return respond(
            &mut conn,
            "405 Method Not Allowed",
            "text/plain",
            b"GET only\n",
        );
    }
    let path = path.split('?').next().unwrap_or(&path);
    let js = "text/javascript; charset=utf-8";
    match path {
        "/" | "/index.html" => respond(
            &mut conn,
            "200 OK",
            "text/html; charset=utf-8",
            INDEX.as_bytes(),
        ),
        "/app.js" => respond(&mut conn, "200 OK", js, APP.as_bytes()),
        "/three.module.js" => respond(&mut conn, "200 OK", js, THREE_MODULE.as_bytes()),
        "/three.core.js" => respond(&mut conn, "200 OK", js, THREE_CORE.as_bytes()),
        "/OrbitControls.js" => respond(&mut conn, "200 OK", js, ORBIT.as_bytes()),
        "/LICENSE-three.js.txt" => respond(
            &mut conn,
            "200 OK",
            "text/plain; charset=utf-8",
            THREE_LICENCE.as_bytes(),
        ),
        "/urdf" => respond(
            &mut conn,
            "200 OK",
            "application/xml",
            trol_a465::urdf::urdf().as_bytes(),
        ),
        "/state" => match shared.frame() {
            Some(f) => respond(&mut conn, "200 OK", "application/json", f.text.as_bytes()),
            None => respond(
                &mut conn,
                "503 Service Unavailable",
                "text/plain",
                b"no arm yet\n",
            ),
        },
        "/events" => events(conn, shared, stop),
        // Browsers ask for it unasked; no icon, and no 404 in the page's console.
        "/favicon.ico" => respond(&mut conn, "204 No Content", "image/x-icon", b""),
        _ => respond(&mut conn, "404 Not Found", "text/plain", b"not here\n"),
    }
}

/// Server-sent events: the state while the arm moves, once when it stops, then quiet.
fn events(mut conn: TcpStream, shared: &Frames, stop: &AtomicBool) -> std::io::Result<()> {
    write!(
        conn,
        "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\n\
         Connection: keep-alive\r\n\r\n"
    )?;
    let mut last_sent: Option<Arc<Frame>> = None;
    let mut quiet = std::time::Instant::now();
    while !stop.load(Ordering::Relaxed) {
        // One round each EVENT_INTERVAL, whatever the round itself takes.
        let next = std::time::Instant::now() + EVENT_INTERVAL;
        if let Some(frame) = shared.frame() {
            let s = &frame.state;
            let moving = s["moving"].as_bool().unwrap_or(false);
            // Still: only a change is sent (a new tool, an object put down), not the time or
            // the servo's dither of a count or two.
            let changed = match &last_sent {
                None => true,
                // The frame already sent (several rounds may fall within one frame).
                Some(prev) if Arc::ptr_eq(prev, &frame) => false,
                Some(prev) => {
                    let prev = &prev.state;
                    moving
                        || prev["moving"] != s["moving"]
                        || prev["gripper_mm"] != s["gripper_mm"]
                        || prev["objects"] != s["objects"]
                        || tcp_moved(prev, s)
                }
            };
            if changed {
                conn.write_all(b"data: ")?;
                conn.write_all(frame.text.as_bytes())?;
                conn.write_all(b"\n\n")?;
                conn.flush()?;
                last_sent = Some(frame.clone());
                quiet = std::time::Instant::now();
            } else if quiet.elapsed() > Duration::from_secs(10) {
                conn.write_all(b": still\n\n")?;
                conn.flush()?;
                quiet = std::time::Instant::now();
            }
        }
        if client_gone(&mut conn) {
            break;
        }
        std::thread::sleep(next.saturating_duration_since(std::time::Instant::now()));
    }
    Ok(())
}

/// Whether the client of an event stream has closed its side (it sends nothing after its
/// request), looking for at most a millisecond: its slot comes free at once, not at the next
/// write that fails.
fn client_gone(conn: &mut TcpStream) -> bool {
    if conn
        .set_read_timeout(Some(Duration::from_millis(1)))
        .is_err()
    {
        return true;
    }
    let mut buf = [0u8; 256];
    match conn.peek(&mut buf) {
        Ok(0) => true,
        // Bytes after the request (nothing a browser sends): read and forget them.
        Ok(_) => conn.read(&mut buf).is_err(),
        Err(e) => !matches!(
            e.kind(),
            std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
        ),
    }
}

/// Whether the tool centre point is more than half a millimetre from where it was.
fn tcp_moved(a: &serde_json::Value, b: &serde_json::Value) -> bool {
    (0..3).any(|i| {
        let (x, y) = (a["tcp"][i].as_f64(), b["tcp"][i].as_f64());
        matches!((x, y), (Some(x), Some(y)) if (x - y).abs() > 0.5)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_viewer_gets_the_same_encoding_of_one_moment() {
        let shared = SharedReport::default();
        shared.want();
        shared.put(trol_controller::ArmReport::default());
        // Within a frame's age every viewer gets the same frame, encoded once.
        let frames = Frames::with_age(shared.clone(), Duration::from_secs(3600));
        let a = frames.frame().unwrap();
        let b = frames.frame().unwrap();
        assert!(Arc::ptr_eq(&a, &b));
        assert_eq!(a.text, a.state.to_string());
        // Past it, a new one.
        let frames = Frames::with_age(shared, Duration::ZERO);
        let a = frames.frame().unwrap();
        assert!(!Arc::ptr_eq(&a, &frames.frame().unwrap()));
    }
}

//! The view's server on its own, over loopback: what it serves, the state's form, event
//! streams that speak while the arm moves and keep quiet while it stands, and the limit on
//! clients that keeps it from hurting the controller (the limit on a request's size is the
//! library's unit test).

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use trol_controller::{Backend, SharedReport};
use trol_sim::{SimBackend, SimSettings};

/// A simulated arm, a thread that renews its report as a controller does (every
/// [`trol_view::REPORT_INTERVAL`]), and the view of those reports.
struct Viewed {
    backend: Arc<Mutex<SimBackend>>,
    stop: Arc<AtomicBool>,
    reporter: Option<std::thread::JoinHandle<()>>,
}

impl Drop for Viewed {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.reporter.take() {
            let _ = t.join();
        }
    }
}

fn viewed() -> (Viewed, trol_view::ViewServer) {
    let mut settings = SimSettings::default();
    settings.arm.homed = true;
    let backend = Arc::new(Mutex::new(SimBackend::new(settings)));
    let slot = SharedReport::default();
    let stop = Arc::new(AtomicBool::new(false));
    let reporter = {
        let (backend, slot, stop) = (backend.clone(), slot.clone(), stop.clone());
        let renew = move || {
            if let Some(r) = backend.lock().unwrap().report() {
                slot.put(r);
            }
        };
        renew();
        std::thread::spawn(move || {
            while !stop.load(Ordering::Relaxed) {
                std::thread::sleep(trol_view::REPORT_INTERVAL);
                renew();
            }
        })
    };
    let server = trol_view::serve("127.0.0.1:0", slot).unwrap();
    let v = Viewed {
        backend,
        stop,
        reporter: Some(reporter),
    };
    (v, server)
}

fn request(server: &trol_view::ViewServer, head: &str) -> String {
    let mut s = TcpStream::connect(server.addr()).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    s.write_all(head.as_bytes()).unwrap();
    let mut all = String::new();
    let _ = s.read_to_string(&mut all);
    all
}

#[test]
fn it_serves_the_page_its_scripts_the_urdf_and_the_state() {
    let (_backend, server) = viewed();
    let get = |path: &str| request(&server, &format!("GET {path} HTTP/1.1\r\n\r\n"));
    for (path, kind) in [
        ("/", "text/html"),
        ("/app.js", "text/javascript"),
        ("/three.module.js", "text/javascript"),
        ("/three.core.js", "text/javascript"),
        ("/OrbitControls.js", "text/javascript"),
        ("/urdf", "application/xml"),
        ("/LICENSE-three.js.txt", "text/plain"),
        ("/state?x=1", "application/json"),
    ] {
        let r = get(path);
        assert!(
            r.starts_with("HTTP/1.1 200 OK"),
            "{path}: {}",
            r.lines().next().unwrap_or("")
        );
        assert!(r.contains(&format!("Content-Type: {kind}")), "{path}");
    }
    assert!(get("/LICENSE-three.js.txt").contains("MIT License"));
    assert!(get("/nowhere").starts_with("HTTP/1.1 404"));
    assert!(request(&server, "POST /state HTTP/1.1\r\n\r\n").starts_with("HTTP/1.1 405"));

    let body = get("/state");
    let state: serde_json::Value =
        serde_json::from_str(body.split_once("\r\n\r\n").unwrap().1).unwrap();
    assert_eq!(state["joints"].as_array().unwrap().len(), 6);
    assert_eq!(state["tcp"].as_array().unwrap().len(), 6);
    assert_eq!(state["moving"], false);
    assert!(state["gripper_mm"].as_f64().unwrap() > 0.0);
    assert!(state["objects"].as_array().unwrap().is_empty());
    assert!(state["time"].as_f64().unwrap() >= 0.0);
    assert!(
        state["target"].is_null(),
        "a standing arm has no target: {state}"
    );
}

/// Updates on an event stream until `until`: (arrival, moving) each.
fn updates(reader: &mut BufReader<TcpStream>, until: Instant) -> Vec<(Instant, bool)> {
    let mut seen = Vec::new();
    let mut line = String::new();
    while Instant::now() < until {
        line.clear();
        match reader.read_line(&mut line) {
            Ok(0) => break,
            Ok(_) => {
                if let Some(data) = line.strip_prefix("data: ") {
                    let v: serde_json::Value = serde_json::from_str(data).unwrap();
                    seen.push((Instant::now(), v["moving"] == true));
                }
            }
            Err(_) => {} // the read timeout: look at the clock again
        }
    }
    seen
}

#[test]
fn events_flow_while_the_arm_moves_and_stop_when_it_stands() {
    let (viewed, server) = viewed();
    let mut s = TcpStream::connect(server.addr()).unwrap();
    s.set_read_timeout(Some(Duration::from_millis(100)))
        .unwrap();
    s.write_all(b"GET /events HTTP/1.1\r\n\r\n").unwrap();
    let mut reader = BufReader::new(s);
    // Standing: the state once, then nothing.
    let still = updates(&mut reader, Instant::now() + Duration::from_millis(600));
    assert_eq!(still.len(), 1, "{still:?}");
    assert!(!still[0].1);

    // A motion of about a second (joint 1 by 1 rad at full speed is well under that at the
    // A465's 180 degrees a second; joints 2 and 3 take longer), shared as the controller
    // would after the request.
    {
        let mut backend = viewed.backend.lock().unwrap();
        backend.speed(100).unwrap();
        backend.ma([1.0, 0.6, 1.0, 0.0, 0.0, 0.0]).unwrap();
    }
    let deadline = Instant::now() + Duration::from_secs(20);
    let mut seen = Vec::new();
    while Instant::now() < deadline {
        seen.extend(updates(
            &mut reader,
            Instant::now() + Duration::from_millis(200),
        ));
        if seen.iter().any(|u| u.1) && !seen.last().unwrap().1 {
            break;
        }
    }
    let moving = seen.iter().filter(|u| u.1).count();
    // Not a rate (that is `trol bench view`'s): several updates, ending with the stop.
    assert!(moving >= 3, "{moving} updates while moving");
    assert!(
        !seen.last().unwrap().1,
        "the last update says the arm stands"
    );
    // Standing again: quiet.
    let after = updates(&mut reader, Instant::now() + Duration::from_millis(600));
    assert!(after.is_empty(), "{after:?}");
}

#[test]
fn too_many_streams_are_turned_away_until_one_leaves() {
    let (_backend, server) = viewed();
    // MAX_STREAMS event streams held open; one more is turned away with 503, the page's
    // `/state` is still answered (streams have their own limit), and a slot comes free when a
    // stream ends.
    let open_stream = || {
        let mut s = TcpStream::connect(server.addr()).unwrap();
        s.write_all(b"GET /events HTTP/1.1\r\n\r\n").unwrap();
        s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
        let mut head = Vec::new();
        let mut byte = [0u8; 1];
        while !head.ends_with(b"\r\n") {
            match s.read(&mut byte) {
                Ok(1) => head.push(byte[0]),
                _ => break,
            }
        }
        (s, String::from_utf8_lossy(&head).into_owned())
    };
    let mut held = Vec::new();
    for _ in 0..trol_view::MAX_STREAMS {
        let (s, status) = open_stream();
        assert!(status.starts_with("HTTP/1.1 200 OK"), "{status}");
        held.push(s);
    }
    let (_refused, status) = open_stream();
    assert!(status.starts_with("HTTP/1.1 503"), "{status}");
    let r = request(&server, "GET /state HTTP/1.1\r\n\r\n");
    assert!(
        r.starts_with("HTTP/1.1 200"),
        "open streams kept /state out: {r}"
    );
    held.truncate(trol_view::MAX_STREAMS - 1);
    // The ended stream's thread notices within its next round (20 ms); try for up to 10 s.
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        let (_s, status) = open_stream();
        if status.starts_with("HTTP/1.1 200") {
            break;
        }
        assert!(Instant::now() < deadline, "no slot came free: {status}");
        std::thread::sleep(Duration::from_millis(200));
    }
}

#[test]
fn connections_that_send_nothing_or_trickle_never_keep_viewers_out() {
    let (_backend, server) = viewed();
    // More connections that send nothing than viewers may be answered at once: they wait for
    // their heads apart from the viewers, so a viewer still gets in.
    let idle: Vec<TcpStream> = (0..trol_view::MAX_CLIENTS + 8)
        .map(|_| TcpStream::connect(server.addr()).unwrap())
        .collect();
    std::thread::sleep(Duration::from_millis(200));
    let r = request(&server, "GET /state HTTP/1.1\r\n\r\n");
    assert!(r.starts_with("HTTP/1.1 200"), "{r}");
    // A head that trickles in, a byte every 100 ms, is cut off once HEAD_DEADLINE has passed
    // (it used to hold its place for as long as each byte came within 5 s). 10 s is the
    // bound with headroom for a busy machine.
    let mut slow = TcpStream::connect(server.addr()).unwrap();
    let mut writer = slow.try_clone().unwrap();
    let trickle = std::thread::spawn(move || {
        let head = b"GET /state HTTP/1.1\r\nX-Slow: ";
        for b in head
            .iter()
            .copied()
            .chain(std::iter::repeat(b'a'))
            .take(200)
        {
            if writer.write_all(&[b]).is_err() {
                return;
            }
            std::thread::sleep(Duration::from_millis(100));
        }
    });
    slow.set_read_timeout(Some(Duration::from_secs(10)))
        .unwrap();
    let started = Instant::now();
    let mut got = Vec::new();
    // Closed: the end of the stream, or a reset (the server closed with bytes unread).
    let closed = match slow.read_to_end(&mut got) {
        Ok(_) => true,
        Err(e) => matches!(
            e.kind(),
            std::io::ErrorKind::ConnectionReset | std::io::ErrorKind::ConnectionAborted
        ),
    };
    assert!(
        closed && started.elapsed() < Duration::from_secs(10),
        "still open after {:?}",
        started.elapsed()
    );
    trickle.join().unwrap();
    drop(idle);
}

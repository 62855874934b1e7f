//! The controller's keep-alive (docs/protocol.md, "Keep-alive"): while it executes a request
//! for a host of this protocol, a thread of its own puts SYN on the line every interval, so
//! that the host tells a controller that works long (a C500 behind the gateway stopping its
//! arm) from one that died.
//!
//! The thread writes only between [`Keepalive::start`] and [`Keepalive::stop`], and each
//! write holds the lock that `stop` takes: once `stop` has returned, no SYN can follow, so
//! the reply's ENQ is never overtaken by one.

use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use trol_port::Beacon;
use trol_proto::link::control::SYN;

/// How often the controller says "still working" while it executes a request.
pub const KEEPALIVE_INTERVAL: Duration = Duration::from_millis(250);

#[derive(Default)]
struct State {
    /// Where SYN goes while a request executes.
    beacon: Option<Beacon>,
    /// When the next SYN is due.
    due: Option<Instant>,
    quit: bool,
    /// The thread waits with no time set (nothing due): only a notify wakes it.
    idle: bool,
    /// SYNs sent so far.
    sent: u64,
}

type Shared = Arc<(Mutex<State>, Condvar)>;

/// The keep-alive thread of one server.
pub struct Keepalive {
    shared: Shared,
    interval: Duration,
    thread: Option<std::thread::JoinHandle<()>>,
}

fn lock(m: &Mutex<State>) -> MutexGuard<'_, State> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

impl Keepalive {
    /// A keep-alive that sends SYN every `interval` while started.
    pub fn new(interval: Duration) -> std::io::Result<Keepalive> {
        let shared: Shared = Arc::default();
        let theirs = shared.clone();
        let thread = std::thread::Builder::new()
            .name("trol-keepalive".into())
            .spawn(move || run(&theirs, interval))?;
        Ok(Keepalive {
            shared,
            interval,
            thread: Some(thread),
        })
    }

    /// The interval.
    pub fn interval(&self) -> Duration {
        self.interval
    }

    /// Say "still working" through `beacon` every interval from now on, until
    /// [`Keepalive::stop`].
    pub fn start(&self, beacon: Beacon) {
        let (m, cv) = &*self.shared;
        let mut s = lock(m);
        s.beacon = Some(beacon);
        s.due = Some(Instant::now() + self.interval);
        // A thread already waiting for an earlier time wakes by itself and waits again for
        // this one; only an idle thread needs waking. So back-to-back short requests cost
        // the line no wake-up of another thread before their replies.
        if s.idle {
            cv.notify_all();
        }
    }

    /// Stop; no SYN goes out after this returns (the thread writes only under the lock and
    /// only when something is due). The thread is not woken: it finds nothing due when its
    /// time comes.
    pub fn stop(&self) {
        let (m, _) = &*self.shared;
        let mut s = lock(m);
        s.beacon = None;
        s.due = None;
    }

    /// SYNs sent so far (for tests and traces).
    pub fn sent(&self) -> u64 {
        lock(&self.shared.0).sent
    }
}

fn run(shared: &Shared, interval: Duration) {
    let (m, cv) = &**shared;
    let mut s = lock(m);
    loop {
        if s.quit {
            return;
        }
        let Some(due) = s.due else {
            s.idle = true;
            s = cv.wait(s).unwrap_or_else(|e| e.into_inner());
            s.idle = false;
            continue;
        };
        let now = Instant::now();
        if now < due {
            s = cv
                .wait_timeout(s, due - now)
                .map(|(g, _)| g)
                .unwrap_or_else(|e| e.into_inner().0);
            continue;
        }
        let failed = match s.beacon.as_mut() {
            Some(b) => b(&[SYN]).is_err(),
            None => true,
        };
        if failed {
            // The line is gone: the server finds out by itself.
            s.beacon = None;
            s.due = None;
        } else {
            s.sent += 1;
            s.due = Some(Instant::now() + interval);
        }
    }
}

impl Drop for Keepalive {
    fn drop(&mut self) {
        {
            let (m, cv) = &*self.shared;
            let mut s = lock(m);
            s.quit = true;
            s.beacon = None;
            cv.notify_all();
        }
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl std::fmt::Debug for Keepalive {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Keepalive")
            .field("interval", &self.interval)
            .finish_non_exhaustive()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sends_only_between_start_and_stop() {
        let got = Arc::new(Mutex::new(Vec::new()));
        let k = Keepalive::new(Duration::from_millis(5)).unwrap();
        let sink = got.clone();
        k.start(Box::new(move |b: &[u8]| {
            sink.lock().unwrap().extend_from_slice(b);
            Ok(())
        }));
        // Wait for a few, however slow the machine.
        let deadline = Instant::now() + Duration::from_secs(30);
        while k.sent() < 3 && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(5));
        }
        k.stop();
        let after_stop = got.lock().unwrap().len();
        assert!(after_stop >= 3, "{after_stop} SYNs");
        assert!(got.lock().unwrap().iter().all(|b| *b == SYN));
        std::thread::sleep(Duration::from_millis(50));
        assert_eq!(got.lock().unwrap().len(), after_stop, "a SYN after stop");
    }

    /// Start and stop wake the thread only when it waits with nothing due: a start right
    /// after a stop (the thread still waiting for the stopped one's time) and a start long
    /// after (the thread idle) both get their SYNs.
    #[test]
    fn a_start_after_a_stop_sends_whether_the_thread_waits_or_idles() {
        let k = Keepalive::new(Duration::from_millis(20)).unwrap();
        let beacon = || -> Beacon { Box::new(|_: &[u8]| Ok(())) };
        for round in 0..4 {
            k.start(beacon());
            k.stop();
            let before = k.sent();
            k.start(beacon());
            let deadline = Instant::now() + Duration::from_secs(30);
            while k.sent() == before && Instant::now() < deadline {
                std::thread::sleep(Duration::from_millis(2));
            }
            k.stop();
            assert!(k.sent() > before, "round {round}: no SYN after a start");
            let stopped = k.sent();
            if round % 2 == 1 {
                // Long enough for the thread to find nothing due and idle.
                std::thread::sleep(Duration::from_millis(60));
            }
            assert_eq!(k.sent(), stopped, "round {round}: a SYN after stop");
        }
    }

    #[test]
    fn a_failing_line_ends_the_keepalive_quietly() {
        let k = Keepalive::new(Duration::from_millis(1)).unwrap();
        k.start(Box::new(|_: &[u8]| {
            Err(std::io::ErrorKind::BrokenPipe.into())
        }));
        std::thread::sleep(Duration::from_millis(20));
        assert_eq!(k.sent(), 0);
        k.stop();
    }
}

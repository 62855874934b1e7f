//! A simulated controller's arm watched from the bench's side (`trol bench mars`, `trol
//! bench c500c`): a thread looks every millisecond and notes when the arm starts and when
//! it stands, and a client's (call, return) pairs are timed against those notes.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use super::*;

/// One client's figures.
#[derive(Serialize)]
pub struct Client {
    /// From the call to the arm's start, ms.
    pub call_to_start: Spread,
    /// From the arm's stand to the wait's return, ms.
    pub end_to_return: Spread,
}

/// The serving thread and the watching thread of a simulated controller.
pub struct ArmWatch {
    stop: Arc<AtomicBool>,
    changes: Arc<Mutex<Vec<(Instant, bool)>>>,
    threads: Vec<std::thread::JoinHandle<()>>,
}

impl ArmWatch {
    /// Start `serve` (which serves until the flag it is given is set) and a watcher of
    /// `moving`.
    pub fn start(
        serve: impl FnOnce(Arc<AtomicBool>) + Send + 'static,
        moving: impl Fn() -> bool + Send + 'static,
    ) -> ArmWatch {
        let stop = Arc::new(AtomicBool::new(false));
        let changes = Arc::new(Mutex::new(Vec::new()));
        let s = stop.clone();
        let serving = std::thread::spawn(move || serve(s));
        let (s, w) = (stop.clone(), changes.clone());
        let watching = std::thread::spawn(move || {
            let mut last = false;
            while !s.load(Ordering::Relaxed) {
                let now = moving();
                if now != last {
                    w.lock()
                        .unwrap_or_else(|e| e.into_inner())
                        .push((Instant::now(), now));
                    last = now;
                }
                std::thread::sleep(Duration::from_millis(1));
            }
        });
        ArmWatch {
            stop,
            changes,
            threads: vec![serving, watching],
        }
    }

    /// Call-to-start and end-to-return, ms, of each (call, return) pair: the first start
    /// after the call, and the first stand after that. (The watcher notes each when it sees
    /// it: on a loaded machine it may see a stand after the wait has returned; the wait
    /// cannot have returned before the arm stood, as the controller answers from its arm, so
    /// that is the watcher's lateness, and the time after the end counts as 0.)
    pub fn timings(&self, pairs: &[(Instant, Instant)]) -> Result<Client, String> {
        // The watcher's last look after the last return.
        std::thread::sleep(Duration::from_millis(100));
        let changes = self.changes.lock().unwrap_or_else(|e| e.into_inner());
        let (mut to_start, mut after) = (Vec::new(), Vec::new());
        for &(call, returned) in pairs {
            let start = changes
                .iter()
                .find(|(t, moving)| *moving && *t >= call)
                .map(|(t, _)| *t)
                .ok_or("the arm was never seen moving after the call")?;
            let stood = changes
                .iter()
                .find(|(t, moving)| !*moving && *t >= start)
                .map(|(t, _)| *t)
                .ok_or("the arm was never seen standing after the motion")?;
            to_start.push(start.duration_since(call).as_secs_f64() * 1e3);
            after.push(returned.saturating_duration_since(stood).as_secs_f64() * 1e3);
        }
        Ok(Client {
            call_to_start: Spread::of(to_start),
            end_to_return: Spread::of(after),
        })
    }
}

impl Drop for ArmWatch {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

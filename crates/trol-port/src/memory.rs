//! An in-memory line joining two ends in one process, for tests and benchmarks.
//!
//! Unpaced, a byte is readable as soon as it is sent. Paced at a baud rate, each byte takes
//! 10 bit times of line time (8N1: start bit, 8 data bits, stop bit) and becomes readable when
//! its last bit has arrived; bytes queue behind each other as on a real UART.

use std::collections::VecDeque;
use std::io;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use crate::Port;

#[derive(Debug, Default)]
struct Direction {
    queue: VecDeque<(Instant, u8)>,
    line_free_at: Option<Instant>,
    carried: u64,
    closed: bool,
}

#[derive(Debug)]
struct Shared {
    dirs: [Mutex<Direction>; 2],
    ready: [Condvar; 2],
    char_time: Duration,
}

/// Bytes the line has carried, in each direction.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LineStats {
    /// Bytes sent from end A to end B.
    pub a_to_b: u64,
    /// Bytes sent from end B to end A.
    pub b_to_a: u64,
}

impl LineStats {
    /// Bytes carried in both directions.
    pub fn total(&self) -> u64 {
        self.a_to_b + self.b_to_a
    }
}

/// One end of an in-memory line.
#[derive(Debug)]
pub struct MemoryLine {
    shared: Arc<Shared>,
    tx: usize,
    rx: usize,
    name: &'static str,
}

/// A new line: `(end A, end B)`. With `baud`, bytes are paced at that rate.
pub fn pair(baud: Option<u32>) -> (MemoryLine, MemoryLine) {
    let char_time = baud
        .filter(|b| *b > 0)
        .map(|b| Duration::from_nanos(10_000_000_000 / u64::from(b)))
        .unwrap_or(Duration::ZERO);
    let shared = Arc::new(Shared {
        dirs: [Mutex::default(), Mutex::default()],
        ready: [Condvar::new(), Condvar::new()],
        char_time,
    });
    (
        MemoryLine {
            shared: shared.clone(),
            tx: 0,
            rx: 1,
            name: "memory-a",
        },
        MemoryLine {
            shared,
            tx: 1,
            rx: 0,
            name: "memory-b",
        },
    )
}

fn lock(m: &Mutex<Direction>) -> MutexGuard<'_, Direction> {
    // A panic in another thread while holding the lock leaves plain data behind; go on.
    m.lock().unwrap_or_else(|e| e.into_inner())
}

impl MemoryLine {
    /// Bytes carried so far, in both directions, seen from end A.
    pub fn stats(&self) -> LineStats {
        let a = lock(&self.shared.dirs[0]).carried;
        let b = lock(&self.shared.dirs[1]).carried;
        LineStats {
            a_to_b: a,
            b_to_a: b,
        }
    }

    /// Line time of one byte (zero when unpaced).
    pub fn char_time(&self) -> Duration {
        self.shared.char_time
    }
}

impl Drop for MemoryLine {
    fn drop(&mut self) {
        lock(&self.shared.dirs[self.tx]).closed = true;
        self.shared.ready[self.tx].notify_all();
    }
}

impl Port for MemoryLine {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        put(&self.shared, self.tx, bytes);
        Ok(())
    }

    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        let mut dir = lock(&self.shared.dirs[self.rx]);
        loop {
            let now = Instant::now();
            let mut n = 0;
            while n < buf.len() {
                match dir.queue.front() {
                    Some(&(t, b)) if t <= now => {
                        buf[n] = b;
                        n += 1;
                        dir.queue.pop_front();
                    }
                    _ => break,
                }
            }
            if n > 0 || buf.is_empty() {
                return Ok(n);
            }
            if now >= deadline {
                return Ok(0);
            }
            let wake = match dir.queue.front() {
                Some(&(t, _)) => t.min(deadline),
                None if dir.closed => return Ok(0),
                None => deadline,
            };
            let wait = wake.saturating_duration_since(now);
            dir = self.shared.ready[self.rx]
                .wait_timeout(dir, wait)
                .map(|(g, _)| g)
                .unwrap_or_else(|e| e.into_inner().0);
        }
    }

    fn available(&mut self) -> io::Result<usize> {
        let now = Instant::now();
        let dir = lock(&self.shared.dirs[self.rx]);
        Ok(dir.queue.iter().take_while(|(t, _)| *t <= now).count())
    }

    fn flush_input(&mut self) -> io::Result<()> {
        let now = Instant::now();
        let mut dir = lock(&self.shared.dirs[self.rx]);
        while dir.queue.front().is_some_and(|(t, _)| *t <= now) {
            dir.queue.pop_front();
        }
        Ok(())
    }

    fn name(&self) -> String {
        self.name.to_string()
    }

    fn offers_beacon(&self) -> bool {
        true
    }

    fn beacon(&mut self) -> Option<crate::Beacon> {
        let shared = self.shared.clone();
        let tx = self.tx;
        Some(Box::new(move |bytes: &[u8]| {
            put(&shared, tx, bytes);
            Ok(())
        }))
    }
}

/// Queue `bytes` in direction `tx`, each readable once its line time has passed.
fn put(shared: &Shared, tx: usize, bytes: &[u8]) {
    let now = Instant::now();
    let mut dir = lock(&shared.dirs[tx]);
    let mut t = dir.line_free_at.map_or(now, |f| f.max(now));
    for &b in bytes {
        t += shared.char_time;
        dir.queue.push_back((t, b));
    }
    dir.line_free_at = Some(t);
    dir.carried += bytes.len() as u64;
    drop(dir);
    shared.ready[tx].notify_all();
}

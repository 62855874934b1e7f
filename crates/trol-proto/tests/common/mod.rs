//! A simulated line between two sans-IO ends, with a virtual clock: no threads, no sleeps.
#![allow(dead_code)]

use std::collections::VecDeque;
use std::time::Duration;

use trol_port::faulty::{FaultConfig, FaultInjector};
use trol_proto::Instant;

pub use trol_proto::Machine as End;

/// A scripted peer: records what it receives; sends what the test tells it to.
#[derive(Default)]
pub struct Script {
    pub received: Vec<u8>,
    pub to_send: Vec<u8>,
}

impl End for Script {
    fn feed(&mut self, bytes: &[u8], _now: Instant) {
        self.received.extend_from_slice(bytes);
    }
    fn tick(&mut self, _now: Instant) {}
    fn next_deadline(&self) -> Option<Instant> {
        None
    }
    fn transmit(&mut self, out: &mut Vec<u8>) {
        out.append(&mut self.to_send);
    }
    fn wants_flush(&mut self) -> bool {
        false
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dir {
    AtoB,
    BtoA,
}

pub struct Wire {
    pub now: Instant,
    pub char_time: Duration,
    ab: VecDeque<(Instant, u8)>,
    ba: VecDeque<(Instant, u8)>,
    ab_free: Instant,
    ba_free: Instant,
    fault_ab: Option<FaultInjector>,
    fault_ba: Option<FaultInjector>,
    pub transcript: Vec<(Dir, Vec<u8>)>,
    pub carried: u64,
    pub flushes: u32,
    /// Drop everything the B end sends (a line cut in one direction).
    pub deaf_b_to_a: bool,
    scratch: Vec<u8>,
}

impl Wire {
    pub fn new() -> Wire {
        Wire::paced(Duration::ZERO)
    }

    pub fn paced(char_time: Duration) -> Wire {
        Wire {
            now: Instant::ZERO,
            char_time,
            ab: VecDeque::new(),
            ba: VecDeque::new(),
            ab_free: Instant::ZERO,
            ba_free: Instant::ZERO,
            fault_ab: None,
            fault_ba: None,
            transcript: Vec::new(),
            carried: 0,
            flushes: 0,
            deaf_b_to_a: false,
            scratch: Vec::new(),
        }
    }

    pub fn with_faults(mut self, ab: FaultConfig, ba: FaultConfig) -> Wire {
        self.fault_ab = Some(FaultInjector::new(ab));
        self.fault_ba = Some(FaultInjector::new(ba));
        self
    }

    fn push(&mut self, dir: Dir, bytes: Vec<u8>) {
        if bytes.is_empty() || (dir == Dir::BtoA && self.deaf_b_to_a) {
            return;
        }
        let (q, free, fault) = match dir {
            Dir::AtoB => (&mut self.ab, &mut self.ab_free, &mut self.fault_ab),
            Dir::BtoA => (&mut self.ba, &mut self.ba_free, &mut self.fault_ba),
        };
        let mut sent = bytes.clone();
        let mut delay = Duration::ZERO;
        if let Some(f) = fault {
            let mut out = Vec::new();
            delay = f.apply(&bytes, &mut out);
            sent = out;
        }
        let mut t = (*free).max(self.now) + delay;
        for b in &sent {
            t = t + self.char_time;
            q.push_back((t, *b));
        }
        *free = t;
        self.carried += sent.len() as u64;
        match self.transcript.last_mut() {
            Some((d, v)) if *d == dir => v.extend_from_slice(&bytes),
            _ => self.transcript.push((dir, bytes)),
        }
    }

    fn transmit_all<A: End, B: End>(&mut self, a: &mut A, b: &mut B) {
        let mut out = std::mem::take(&mut self.scratch);
        out.clear();
        a.transmit(&mut out);
        self.push(Dir::AtoB, out.clone());
        out.clear();
        b.transmit(&mut out);
        self.push(Dir::BtoA, out.clone());
        self.scratch = out;
        let now = self.now;
        if a.wants_flush() {
            self.flushes += 1;
            while self.ba.front().is_some_and(|(t, _)| *t <= now) {
                self.ba.pop_front();
            }
        }
        if b.wants_flush() {
            self.flushes += 1;
            while self.ab.front().is_some_and(|(t, _)| *t <= now) {
                self.ab.pop_front();
            }
        }
    }

    /// One step: advance the clock to the next event if nothing is due now, run timers,
    /// carry bytes. Returns false when nothing can happen any more.
    pub fn step<A: End, B: End>(&mut self, a: &mut A, b: &mut B) -> bool {
        self.transmit_all(a, b);
        let now = self.now;
        let due = self.ab.front().is_some_and(|x| x.0 <= now)
            || self.ba.front().is_some_and(|x| x.0 <= now)
            || a.next_deadline().is_some_and(|t| t <= now)
            || b.next_deadline().is_some_and(|t| t <= now);
        if !due {
            let next = [
                self.ab.front().map(|x| x.0),
                self.ba.front().map(|x| x.0),
                a.next_deadline(),
                b.next_deadline(),
            ]
            .into_iter()
            .flatten()
            .min();
            match next {
                Some(t) => self.now = t,
                None => return false,
            }
        }
        let now = self.now;
        a.tick(now);
        b.tick(now);
        self.transmit_all(a, b);
        let chunk: Vec<u8> = drain_arrived(&mut self.ab, now);
        if !chunk.is_empty() {
            b.feed(&chunk, now);
        }
        let chunk: Vec<u8> = drain_arrived(&mut self.ba, now);
        if !chunk.is_empty() {
            a.feed(&chunk, now);
        }
        self.transmit_all(a, b);
        true
    }

    /// Step until `done` or nothing can happen or `limit` of virtual time passed.
    pub fn run<A: End, B: End>(
        &mut self,
        a: &mut A,
        b: &mut B,
        limit: Duration,
        mut done: impl FnMut(&mut A, &mut B) -> bool,
    ) -> bool {
        self.run_t(a, b, limit, |a, b, _| done(a, b))
    }

    /// [`Wire::run`], with the current time passed to `done`.
    pub fn run_t<A: End, B: End>(
        &mut self,
        a: &mut A,
        b: &mut B,
        limit: Duration,
        mut done: impl FnMut(&mut A, &mut B, Instant) -> bool,
    ) -> bool {
        let end = self.now + limit;
        for _ in 0..10_000_000 {
            if done(a, b, self.now) {
                return true;
            }
            if self.now > end || !self.step(a, b) {
                return done(a, b, self.now);
            }
        }
        panic!("simulation did not settle");
    }

    /// Advance virtual time.
    pub fn advance(&mut self, d: Duration) {
        self.now = self.now + d;
    }
}

fn drain_arrived(q: &mut VecDeque<(Instant, u8)>, now: Instant) -> Vec<u8> {
    let mut v = Vec::new();
    while q.front().is_some_and(|(t, _)| *t <= now) {
        v.push(q.pop_front().map(|x| x.1).unwrap_or_default());
    }
    v
}

/// Parse hex bytes separated by blanks.
pub fn hex(s: &str) -> Vec<u8> {
    s.split_whitespace()
        .map(|t| u8::from_str_radix(t, 16).expect("hex byte"))
        .collect()
}

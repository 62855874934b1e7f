//! A fault-injecting line: wraps any port and damages what it sends.
//!
//! Faults are drawn from a ChaCha8 generator seeded by [`FaultConfig::seed`], so a run that
//! failed can be replayed byte for byte. [`FaultInjector`] is the pure part (bytes in, damaged
//! bytes out) and is also used by the sans-IO tests without any port; [`Faulty`] applies it
//! to a [`Port`].

use std::io;
use std::time::{Duration, Instant};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::Port;

/// What to damage, and how often.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaultConfig {
    /// Seed of the generator.
    pub seed: u64,
    /// Probability that any one bit is flipped (bit error rate).
    pub bit_error_rate: f64,
    /// Probability that a byte is dropped.
    pub drop_rate: f64,
    /// Probability that a random byte is inserted before a byte.
    pub insert_rate: f64,
    /// Probability that a byte is sent twice.
    pub duplicate_rate: f64,
    /// Probability that a send is held back by a delay.
    pub delay_rate: f64,
    /// Longest such delay (drawn uniformly up to this).
    pub max_delay: Duration,
    /// Cut the line for good after this many bytes have passed.
    pub cut_after: Option<u64>,
}

impl Default for FaultConfig {
    fn default() -> Self {
        FaultConfig {
            seed: 0,
            bit_error_rate: 0.0,
            drop_rate: 0.0,
            insert_rate: 0.0,
            duplicate_rate: 0.0,
            delay_rate: 0.0,
            max_delay: Duration::ZERO,
            cut_after: None,
        }
    }
}

impl FaultConfig {
    /// A clean line with this seed (set the rates you want on it).
    pub fn seeded(seed: u64) -> Self {
        FaultConfig {
            seed,
            ..FaultConfig::default()
        }
    }
}

/// Counters of the faults injected so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FaultStats {
    /// Bytes that passed the injector.
    pub bytes: u64,
    /// Bits flipped.
    pub flipped_bits: u64,
    /// Bytes dropped.
    pub dropped: u64,
    /// Bytes inserted.
    pub inserted: u64,
    /// Bytes duplicated.
    pub duplicated: u64,
    /// Sends delayed.
    pub delayed: u64,
    /// Bytes lost to the cut.
    pub cut: u64,
}

/// The pure fault injector.
#[derive(Debug, Clone)]
pub struct FaultInjector {
    cfg: FaultConfig,
    rng: ChaCha8Rng,
    stats: FaultStats,
}

impl FaultInjector {
    /// An injector for `cfg`.
    pub fn new(cfg: FaultConfig) -> Self {
        FaultInjector {
            cfg,
            rng: ChaCha8Rng::seed_from_u64(cfg.seed),
            stats: FaultStats::default(),
        }
    }

    /// Counters so far.
    pub fn stats(&self) -> FaultStats {
        self.stats
    }

    /// Whether the line has been cut.
    pub fn is_cut(&self) -> bool {
        self.cfg.cut_after.is_some_and(|n| self.stats.bytes >= n)
    }

    /// Damage `input`, appending what arrives at the far end to `out`. Returns the delay to
    /// hold these bytes back by (zero mostly).
    pub fn apply(&mut self, input: &[u8], out: &mut Vec<u8>) -> Duration {
        let mut delay = Duration::ZERO;
        if self.cfg.delay_rate > 0.0 && self.rng.random_bool(self.cfg.delay_rate.min(1.0)) {
            let max = self.cfg.max_delay.as_micros() as u64;
            delay = Duration::from_micros(self.rng.random_range(0..=max));
            self.stats.delayed += 1;
        }
        for &byte in input {
            if self.is_cut() {
                self.stats.cut += 1;
                self.stats.bytes += 1;
                continue;
            }
            self.stats.bytes += 1;
            if self.chance(self.cfg.insert_rate) {
                out.push(self.rng.random());
                self.stats.inserted += 1;
            }
            if self.chance(self.cfg.drop_rate) {
                self.stats.dropped += 1;
                continue;
            }
            let mut b = byte;
            if self.cfg.bit_error_rate > 0.0 {
                for bit in 0..8 {
                    if self.rng.random_bool(self.cfg.bit_error_rate.min(1.0)) {
                        b ^= 1 << bit;
                        self.stats.flipped_bits += 1;
                    }
                }
            }
            out.push(b);
            if self.chance(self.cfg.duplicate_rate) {
                out.push(b);
                self.stats.duplicated += 1;
            }
        }
        delay
    }

    fn chance(&mut self, p: f64) -> bool {
        p > 0.0 && self.rng.random_bool(p.min(1.0))
    }
}

/// A port whose outgoing bytes pass a [`FaultInjector`]. Wrap both ends (with different
/// seeds) to damage both directions. Once cut, nothing passes either way.
#[derive(Debug)]
pub struct Faulty<P> {
    inner: P,
    injector: FaultInjector,
    scratch: Vec<u8>,
}

impl<P: Port> Faulty<P> {
    /// Wrap `inner`.
    pub fn new(inner: P, cfg: FaultConfig) -> Self {
        Faulty {
            inner,
            injector: FaultInjector::new(cfg),
            scratch: Vec::new(),
        }
    }

    /// Counters so far.
    pub fn stats(&self) -> FaultStats {
        self.injector.stats()
    }

    /// The wrapped port.
    pub fn inner(&self) -> &P {
        &self.inner
    }
}

impl<P: Port> Port for Faulty<P> {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.scratch.clear();
        let delay = self.injector.apply(bytes, &mut self.scratch);
        if !delay.is_zero() {
            std::thread::sleep(delay);
        }
        if self.scratch.is_empty() {
            return Ok(());
        }
        self.inner.send(&self.scratch)
    }

    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        if self.injector.is_cut() {
            let _ = self.inner.flush_input();
            std::thread::sleep(deadline.saturating_duration_since(Instant::now()));
            return Ok(0);
        }
        self.inner.recv(buf, deadline)
    }

    fn available(&mut self) -> io::Result<usize> {
        if self.injector.is_cut() {
            return Ok(0);
        }
        self.inner.available()
    }

    fn flush_input(&mut self) -> io::Result<()> {
        self.inner.flush_input()
    }

    fn name(&self) -> String {
        format!("faulty({})", self.inner.name())
    }
}

/// Which way a byte goes through a [`Flip`]ped port.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Way {
    /// Sent by the port's owner.
    Out,
    /// Received by the port's owner.
    In,
}

/// One bit of one byte to damage, once: bit `bit` of the byte at `at` of the next `pattern`
/// that passes `way` (a byte of a known line, as the tests of a console need: "flip bit 3 of
/// the 7th byte of `joint 3,0.500`").
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FlipPlan {
    /// Which way.
    pub way: Way,
    /// The bytes looked for.
    pub pattern: Vec<u8>,
    /// The byte of them damaged (from 0).
    pub at: usize,
    /// The bit flipped (0..8).
    pub bit: u8,
}

#[derive(Debug, Default)]
struct FlipState {
    plan: Option<FlipPlan>,
    /// How much of the pattern has passed.
    matched: usize,
    /// The plan was carried out.
    done: bool,
}

impl FlipState {
    fn apply(&mut self, way: Way, bytes: &mut [u8]) {
        let Some(plan) = self.plan.as_ref().filter(|p| p.way == way && !self.done) else {
            return;
        };
        let (pattern, at, mask) = (plan.pattern.clone(), plan.at, 1u8 << (plan.bit & 7));
        for b in bytes {
            if self.matched == at && *b == pattern[at] {
                *b ^= mask;
                self.done = true;
                return;
            }
            self.matched = if *b == pattern[self.matched] {
                self.matched + 1
            } else {
                // Restart, the byte perhaps the pattern's first (the lines TROL types repeat
                // no prefix of their own inside them, so this is exact for them).
                usize::from(*b == pattern[0])
            };
        }
    }
}

/// The switch of a [`Flip`]: arm a plan, and see whether it was carried out. Clone it to keep
/// a handle while the port is served elsewhere.
#[derive(Clone, Debug, Default)]
pub struct FlipSwitch(std::sync::Arc<std::sync::Mutex<FlipState>>);

impl FlipSwitch {
    /// Damage as `plan` says, once (a plan whose `at` is outside its pattern, or whose
    /// pattern is empty, is ignored).
    pub fn arm(&self, plan: FlipPlan) {
        let mut s = self.0.lock().unwrap_or_else(|e| e.into_inner());
        let valid = plan.at < plan.pattern.len();
        *s = FlipState {
            plan: valid.then_some(plan),
            matched: 0,
            done: false,
        };
    }

    /// The armed plan was carried out.
    pub fn done(&self) -> bool {
        self.0.lock().unwrap_or_else(|e| e.into_inner()).done
    }

    /// Disarm.
    pub fn clear(&self) {
        *self.0.lock().unwrap_or_else(|e| e.into_inner()) = FlipState::default();
    }
}

/// A port that damages one bit of one chosen byte when its [`FlipSwitch`] says so: the
/// simulated controllers' switch for a flipped bit on their console, either way.
#[derive(Debug)]
pub struct Flip<P> {
    inner: P,
    switch: FlipSwitch,
    scratch: Vec<u8>,
}

impl<P: Port> Flip<P> {
    /// Wrap `inner`; `switch` arms it.
    pub fn new(inner: P, switch: FlipSwitch) -> Self {
        Flip {
            inner,
            switch,
            scratch: Vec::new(),
        }
    }
}

impl<P: Port> Port for Flip<P> {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.scratch.clear();
        self.scratch.extend_from_slice(bytes);
        self.switch
            .0
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .apply(Way::Out, &mut self.scratch);
        self.inner.send(&self.scratch)
    }

    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        let n = self.inner.recv(buf, deadline)?;
        self.switch
            .0
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .apply(Way::In, &mut buf[..n]);
        Ok(n)
    }

    fn available(&mut self) -> io::Result<usize> {
        self.inner.available()
    }

    fn flush_input(&mut self) -> io::Result<()> {
        self.inner.flush_input()
    }

    fn name(&self) -> String {
        self.inner.name()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_flip_damages_the_chosen_bit_of_the_chosen_byte_once() {
        let mut s = FlipState {
            plan: Some(FlipPlan {
                way: Way::Out,
                pattern: b"joint 3,0.500".to_vec(),
                at: 8,
                bit: 2,
            }),
            ..FlipState::default()
        };
        // Another way: untouched.
        let mut other = b"joint 3,0.500".to_vec();
        s.apply(Way::In, &mut other);
        assert_eq!(other, b"joint 3,0.500");
        // A near miss first, then the line split over two writes.
        let mut a = b"w2\rjoint 3,1\rjoint 3,".to_vec();
        let mut b = b"0.500\r".to_vec();
        s.apply(Way::Out, &mut a);
        s.apply(Way::Out, &mut b);
        assert_eq!(a, b"w2\rjoint 3,1\rjoint 3,");
        assert_eq!(b, b"4.500\r");
        assert!(s.done);
        let mut again = b"joint 3,0.500".to_vec();
        s.apply(Way::Out, &mut again);
        assert_eq!(again, b"joint 3,0.500");
    }
}

//! The loop that runs a sans-IO machine over a port.

use std::io;
use std::time::Duration;

use trol_port::Port;
use trol_proto::{Instant, Machine};

/// Maps the real monotonic clock onto the core's [`Instant`].
#[derive(Clone, Copy, Debug)]
pub struct Clock {
    epoch: std::time::Instant,
}

impl Default for Clock {
    fn default() -> Self {
        Clock {
            epoch: std::time::Instant::now(),
        }
    }
}

impl Clock {
    /// Now, as the core sees it.
    pub fn now(&self) -> Instant {
        Instant::from_duration(self.epoch.elapsed())
    }

    /// A core instant as a real one.
    pub fn to_std(&self, t: Instant) -> std::time::Instant {
        self.epoch + t.since_epoch()
    }
}

/// Which way bytes went, for traces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    /// Received from the line.
    In,
    /// Put on the line.
    Out,
}

/// A trace hook: called with every chunk of bytes that crosses layer 1.
pub type TraceFn = Box<dyn FnMut(Direction, &[u8], Instant) + Send>;

/// Longest single wait on the port when the machine has no timer, so that callers can check
/// their own deadlines and stop flags.
const IDLE_POLL: Duration = Duration::from_millis(50);

/// How late past a timer a read must return for its process to count as stopped meanwhile
/// (docs/reliability.md, "What each fault ends in": the controller freezes).
pub const THAWED: Duration = Duration::from_millis(500);

/// Runs state machines over one port.
pub struct Driver<P> {
    port: P,
    clock: Clock,
    delay: Duration,
    out: Vec<u8>,
    rx: Vec<u8>,
    trace: Option<TraceFn>,
}

impl<P: Port> Driver<P> {
    /// A driver for `port`.
    pub fn new(port: P) -> Self {
        Driver {
            port,
            clock: Clock::default(),
            delay: Duration::ZERO,
            out: Vec::with_capacity(512),
            rx: vec![0; 4096],
            trace: None,
        }
    }

    /// The clock the driver reads.
    pub fn clock(&self) -> &Clock {
        &self.clock
    }

    /// The port.
    pub fn port(&self) -> &P {
        &self.port
    }

    /// The port, mutably.
    pub fn port_mut(&mut self) -> &mut P {
        &mut self.port
    }

    /// Take the port back.
    pub fn into_port(self) -> P {
        self.port
    }

    /// SetDelay: pause between two bytes sent. The manual used 5 ms so that the C500's 286
    /// could take each character from its UART in time; modern ports need none (default 0).
    pub fn set_delay(&mut self, delay: Duration) {
        self.delay = delay;
    }

    /// The inter-character delay.
    pub fn delay(&self) -> Duration {
        self.delay
    }

    /// Install a trace hook (or remove it with `None`).
    pub fn set_trace(&mut self, trace: Option<TraceFn>) {
        self.trace = trace;
    }

    fn transmit<M: Machine>(&mut self, m: &mut M) -> io::Result<()> {
        self.out.clear();
        m.transmit(&mut self.out);
        if self.out.is_empty() {
            return Ok(());
        }
        tracing::trace!("sent {:02x?}", self.out);
        if let Some(trace) = self.trace.as_mut() {
            trace(Direction::Out, &self.out, self.clock.now());
        }
        if self.delay.is_zero() {
            self.port.send(&self.out)
        } else {
            for (i, b) in self.out.iter().enumerate() {
                if i > 0 {
                    std::thread::sleep(self.delay);
                }
                self.port.send(std::slice::from_ref(b))?;
            }
            Ok(())
        }
    }

    /// Run `m` until `poll(m)` gives something, and return it; `None` once `until` passed
    /// without (the one loop every caller takes: send_data, receive_data, the transactor,
    /// the server).
    pub fn next<M: Machine, T>(
        &mut self,
        m: &mut M,
        until: Option<Instant>,
        mut poll: impl FnMut(&mut M) -> Option<T>,
    ) -> io::Result<Option<T>> {
        let mut got = None;
        self.run(m, until, |m| {
            got = poll(m);
            got.is_some()
        })?;
        Ok(got)
    }

    /// Run `m` until `done(m)` says so, or until `until` passes (checked only between
    /// events). Bytes the machine queues are sent before `done` is asked.
    pub fn run<M: Machine>(
        &mut self,
        m: &mut M,
        until: Option<Instant>,
        mut done: impl FnMut(&mut M) -> bool,
    ) -> io::Result<()> {
        loop {
            // The manual's reset: wait, flush, then retry. A reset that ends queues the
            // deferred transfer's first byte (ENQ) and asks for the flush in one tick, so the
            // flush goes first: else a fast peer's answer to that ENQ would be flushed away.
            if m.wants_flush() {
                self.port.flush_input()?;
            }
            self.transmit(m)?;
            if done(m) {
                return Ok(());
            }
            let now = self.clock.now();
            if until.is_some_and(|u| now >= u) {
                return Ok(());
            }
            let timer = m.next_deadline();
            if timer.is_some_and(|t| t <= now) {
                m.tick(now);
                continue;
            }
            let mut wake = timer.unwrap_or(now + IDLE_POLL).min(now + IDLE_POLL);
            if let Some(u) = until {
                wake = wake.min(u);
            }
            let n = self.port.recv(&mut self.rx, self.clock.to_std(wake))?;
            let now = self.clock.now();
            // A process stopped inside this read (SIGSTOP, a debugger, a suspended machine)
            // comes back with bytes that arrived while its timers ran out: the timers fire
            // first, so a transfer the peer gave up on is dropped, not completed (a thawed
            // controller must not run a move its host reported failed). A read that is late
            // by less than THAWED is a busy machine's, and its bytes count.
            if n > 0 && timer.is_some_and(|t| now > t + THAWED) {
                m.tick(now);
            }
            if n > 0 {
                tracing::trace!("received {:02x?}", &self.rx[..n]);
                if let Some(trace) = self.trace.as_mut() {
                    trace(Direction::In, &self.rx[..n], now);
                }
                m.feed(&self.rx[..n], now);
            }
            m.tick(now);
        }
    }
}

impl<P> std::fmt::Debug for Driver<P> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Driver")
            .field("delay", &self.delay)
            .finish_non_exhaustive()
    }
}

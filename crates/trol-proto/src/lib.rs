//! The TROL protocol core, shared by the host library and the controller.
//!
//! TROL (TU Vienna Robot Control Library) talks to a CRS A465's C500 controller over a serial
//! line in four layers (manual, chapter "Kommunikation"). This crate holds layers 2 to 4 as
//! sans-IO code: no I/O, no clock, no sleeps. Bytes come in, bytes go out, and the caller
//! passes in the time.
//!
//! - [`link`]: layer 2, the BSC-like link (SendData / ReceiveData);
//! - [`transaction`]: layer 3, transactions (TransSR on the PC, TransRS on the controller);
//! - [`application`]: layer 4, the command records of every API call and their replies;
//! - [`activation`]: the line that turns a controller's terminal into the TROL server.
//!
//! Layer 1 (ports) and the drivers that run these machines live in `trol-port` and
//! `trol-comm`. The byte-exact specification is docs/protocol.md.

#![forbid(unsafe_code)]
#![warn(missing_docs, missing_debug_implementations)]

pub mod activation;
pub mod application;
pub mod link;
pub mod time;
pub mod transaction;

pub use time::Instant;

// The machines and the types every user of the core meets, at the root; the layers' modules
// hold the details (frame layout, control codes, the command table).
pub use application::{Catalog, CodeTable, CommandDef, Reply, Value};
pub use link::{BlockCheck, Link, LinkConfig, LinkError};
pub use transaction::{Initiator, Responder, TransCode};

/// What every sans-IO machine of this crate offers to whoever moves its bytes and keeps its
/// time: the driver in `trol-comm`, or a test's simulated line. Implemented by
/// [`link::Link`], [`transaction::Initiator`] and [`transaction::Responder`].
pub trait Machine {
    /// Feed bytes received from the line.
    fn feed(&mut self, input: &[u8], now: Instant);
    /// Tell the time; runs timers that have expired.
    fn tick(&mut self, now: Instant);
    /// When [`Machine::tick`] must be called next, if a timer runs.
    fn next_deadline(&self) -> Option<Instant>;
    /// Move the bytes to put on the line into `out` (appending).
    fn transmit(&mut self, out: &mut Vec<u8>);
    /// Whether layer 1's input must be flushed now (reading clears the request).
    fn wants_flush(&mut self) -> bool;
}

macro_rules! machine_for {
    ($t:ty) => {
        impl Machine for $t {
            fn feed(&mut self, input: &[u8], now: Instant) {
                let _ = self.handle_input(input, now);
            }
            fn tick(&mut self, now: Instant) {
                self.handle_timeout(now)
            }
            fn next_deadline(&self) -> Option<Instant> {
                self.poll_timeout()
            }
            fn transmit(&mut self, out: &mut Vec<u8>) {
                self.drain_transmit(out)
            }
            fn wants_flush(&mut self) -> bool {
                self.take_flush_request()
            }
        }
    };
}

machine_for!(link::Link);
machine_for!(transaction::Initiator);
machine_for!(transaction::Responder);

/// Entry points for the fuzz targets in `fuzz/` (and their stable-toolchain test); not API.
#[doc(hidden)]
pub mod fuzzing {
    use crate::link::{Link, LinkConfig, Outcome, frame};
    use crate::time::Instant;
    use std::time::Duration;

    /// Feed `data` to a receiving link end as the line would: the first byte of each
    /// chunk says how many bytes the chunk has and how much time passes before it. Whatever
    /// the bytes, the link must not panic, must end every transfer with a message no longer
    /// than the header announced, or with a code, and must keep its timers in the future.
    pub fn receive(data: &[u8]) {
        let cfg = LinkConfig {
            max_message: 4096,
            ..LinkConfig::default()
        };
        let mut link = Link::new(cfg);
        let mut now = Instant::ZERO;
        let _ = link.receive(now);
        let mut out = Vec::new();
        let mut rest = data;
        while let Some((&ctl, tail)) = rest.split_first() {
            let n = usize::from(ctl & 0x3F).min(tail.len());
            now = now + Duration::from_millis(u64::from(ctl >> 6) * 400);
            link.handle_timeout(now);
            let (chunk, tail) = tail.split_at(n);
            let mut input = chunk;
            while !input.is_empty() {
                let used = link.handle_input(input, now);
                input = &input[used..];
                if !link.is_busy() {
                    let _ = link.receive(now);
                }
            }
            link.drain_transmit(&mut out);
            if let Some(t) = link.poll_timeout() {
                assert!(t >= now, "a timer in the past");
            }
            match link.poll_outcome() {
                Some(Outcome::Received) => {
                    let (_, msg) = link.take_received().expect("a received message");
                    assert!(msg.len() <= cfg.max_message.min(frame::MAX_MESSAGE));
                    let _ = link.receive(now);
                }
                Some(Outcome::Failed(e)) => assert!(e.code() != 0),
                _ => {}
            }
            rest = tail;
        }
    }
}

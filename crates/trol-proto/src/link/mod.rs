//! Layer 2, the data link ("Sicherungs-Schicht"): a BSC-like half-duplex protocol that moves
//! messages of 0..65535 bytes reliably over a byte line.
//!
//! Everything here is sans-IO: bytes in, bytes out, the current time passed in. The pieces:
//!
//! - [`control`]: the control codes and the one-bit tolerance;
//! - [`frame`]: header and frame layout, the LRC, FRAME_SIZE, MAX_RETRIES;
//! - [`monitor`]: a passive reader of one direction of a line (the tracer's);
//! - [`codes`]: NAK codes and the return values of SendData / ReceiveData;
//! - [`config`]: timeouts and limits;
//! - [`Sender`] and [`Receiver`]: the two state machines;
//! - [`Link`]: one end of the line, running one transfer at a time and performing the
//!   manual's reset after a failure.

pub mod codes;
pub mod config;
pub mod control;
pub mod frame;
pub mod monitor;
mod receiver;
mod sender;

pub use codes::{LinkError, NakClass, NakCode, ReceiveError, SendError};
pub use config::{BlockCheck, LinkConfig, Timeouts};
pub use receiver::{Plausible, Received, Receiver};
pub use sender::{MessageTooLong, Sender};

use crate::time::Instant;

/// How a transfer of a [`Link`] ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// SendData returned 0: the message was sent and EOT queued.
    Sent,
    /// ReceiveData returned 0: a message is ready in [`Link::take_received`].
    Received,
    /// The transfer failed with this code; the link is resetting.
    Failed(LinkError),
}

/// Why a transfer could not be started.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StartError {
    /// The message is longer than 65535 bytes.
    TooLong(MessageTooLong),
    /// A transfer is already under way on this link.
    Busy,
}

impl std::fmt::Display for StartError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StartError::TooLong(e) => e.fmt(f),
            StartError::Busy => f.write_str("a transfer is already under way on this link"),
        }
    }
}

impl std::error::Error for StartError {}

#[derive(Debug)]
enum Role {
    Idle,
    Sending,
    Receiving,
}

#[derive(Debug)]
enum Deferred {
    Send(Vec<u8>, u16),
    Receive,
}

/// Counters of one link end, for traces and benchmarks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LinkStats {
    /// Bytes handed in from the line.
    pub bytes_in: u64,
    /// Bytes handed out to the line.
    pub bytes_out: u64,
    /// Bytes dropped while resetting.
    pub bytes_dropped: u64,
    /// Transfers that failed.
    pub failures: u64,
}

/// One end of the line: SendData and ReceiveData, one at a time, with the manual's reset.
///
/// After a failed transfer the link stays deaf for one reset period (after ReceiveData) or two
/// (after SendData), dropping every byte that arrives, and then asks the driver to flush the
/// input of layer 1 ([`Link::take_flush_request`]). A transfer started meanwhile begins when
/// the reset is over. So no byte of a failed transfer can become part of the next message.
#[derive(Debug)]
pub struct Link {
    sender: Sender,
    receiver: Receiver,
    role: Role,
    outcome: Option<Outcome>,
    quiet_until: Option<Instant>,
    deferred: Option<Deferred>,
    flush: bool,
    last_error: Option<LinkError>,
    stats: LinkStats,
}

impl Link {
    /// An idle link end.
    pub fn new(cfg: LinkConfig) -> Self {
        Link {
            sender: Sender::new(cfg),
            receiver: Receiver::new(cfg),
            role: Role::Idle,
            outcome: None,
            quiet_until: None,
            deferred: None,
            flush: false,
            last_error: None,
            stats: LinkStats::default(),
        }
    }

    /// The settings.
    pub fn config(&self) -> &LinkConfig {
        self.sender.config()
    }

    /// Change the settings; takes effect with the next transfer.
    pub fn set_config(&mut self, cfg: LinkConfig) {
        self.sender.set_config(cfg);
        self.receiver.set_config(cfg);
    }

    /// Take SYN while a message's ENQ is awaited as the peer's "still working"
    /// ([`Receiver::set_keepalive`]): a host's end.
    pub fn set_keepalive(&mut self, on: bool) {
        self.receiver.set_keepalive(on);
    }

    /// While ENQ is awaited: when the peer's last SYN came, if one did since the wait began.
    pub fn alive_at(&self) -> Option<Instant> {
        match self.role {
            Role::Receiving => self.receiver.alive_at(),
            _ => None,
        }
    }

    /// With the manual's LRC: check each whole message received before its last block is
    /// acknowledged ([`Plausible`]); `None`, the block check alone. No effect with CRC-16.
    pub fn set_plausible(&mut self, plausible: Option<Plausible>) {
        self.receiver.set_plausible(plausible);
    }

    /// Counters.
    pub fn stats(&self) -> LinkStats {
        self.stats
    }

    /// The code of the last failed transfer (the manual's GetLastCommErr).
    pub fn last_error(&self) -> Option<LinkError> {
        self.last_error
    }

    /// Forget the last failure (a new transaction starts: what GetLastCommErr reports
    /// afterwards belongs to it).
    pub fn clear_last_error(&mut self) {
        self.last_error = None;
    }

    /// Record a failure the link could not see itself: the port failed under it
    /// ([`SendError::Port`], [`ReceiveError::Port`]).
    pub fn note_failure(&mut self, err: LinkError) {
        self.stats.failures += 1;
        self.last_error = Some(err);
    }

    /// Whether a transfer is under way (or waits for the reset to end).
    pub fn is_busy(&self) -> bool {
        !matches!(self.role, Role::Idle) || self.deferred.is_some()
    }

    /// Whether the link is resetting after a failure.
    pub fn is_resetting(&self) -> bool {
        self.quiet_until.is_some()
    }

    /// Whether the receiver has answered ENQ and is inside a transfer.
    pub fn receive_in_progress(&self) -> bool {
        matches!(self.role, Role::Receiving) && self.receiver.in_transfer()
    }

    /// SendData: start sending `message` with `pci`.
    pub fn send(&mut self, message: &[u8], pci: u16, now: Instant) -> Result<(), StartError> {
        if message.len() > frame::MAX_MESSAGE {
            return Err(StartError::TooLong(MessageTooLong(message.len())));
        }
        if self.is_busy() {
            return Err(StartError::Busy);
        }
        self.outcome = None;
        if self.quiet_until.is_some() {
            self.deferred = Some(Deferred::Send(message.to_vec(), pci));
            return Ok(());
        }
        self.begin_send(message, pci, now);
        Ok(())
    }

    /// ReceiveData: start waiting for a message.
    pub fn receive(&mut self, _now: Instant) -> Result<(), StartError> {
        if self.is_busy() {
            return Err(StartError::Busy);
        }
        self.outcome = None;
        if self.quiet_until.is_some() {
            self.deferred = Some(Deferred::Receive);
            return Ok(());
        }
        self.receiver.start();
        self.role = Role::Receiving;
        Ok(())
    }

    /// Give up waiting for a message that has not started (ENQ not yet received). Returns
    /// false when a transfer is already under way, which must be let run to its end.
    pub fn cancel_receive(&mut self) -> bool {
        match self.role {
            Role::Receiving if !self.receiver.in_transfer() => {
                self.receiver.reset();
                self.role = Role::Idle;
                true
            }
            _ if matches!(self.deferred, Some(Deferred::Receive)) => {
                self.deferred = None;
                true
            }
            _ => false,
        }
    }

    /// Drop whatever transfer is under way, without a word on the line, and go idle: for
    /// when layer 1 itself failed (the port is gone), so that the next transfer starts clean.
    /// The caller should flush the port's input before it starts one.
    pub fn abort(&mut self) {
        self.sender.reset();
        self.receiver.reset();
        self.role = Role::Idle;
        self.deferred = None;
        self.quiet_until = None;
        self.outcome = None;
        self.flush = false;
    }

    fn begin_send(&mut self, message: &[u8], pci: u16, now: Instant) {
        // Length was checked by the caller.
        let _ = self.sender.start(message, pci, now);
        self.role = Role::Sending;
    }

    /// How the last transfer ended, once (None while it runs).
    pub fn poll_outcome(&mut self) -> Option<Outcome> {
        self.outcome.take()
    }

    /// The message of a successful ReceiveData: (PCI, bytes).
    pub fn take_received(&mut self) -> Option<(u16, Vec<u8>)> {
        self.receiver.take_message()
    }

    /// Whether layer 1's input must be flushed now (the end of a reset). Reading clears it.
    pub fn take_flush_request(&mut self) -> bool {
        std::mem::take(&mut self.flush)
    }

    /// Move the bytes to put on the line into `out` (appending).
    pub fn drain_transmit(&mut self, out: &mut Vec<u8>) {
        let before = out.len();
        self.sender.drain_transmit(out);
        self.receiver.drain_transmit(out);
        self.stats.bytes_out += (out.len() - before) as u64;
    }

    /// When [`Link::handle_timeout`] must be called next.
    pub fn poll_timeout(&self) -> Option<Instant> {
        if let Some(q) = self.quiet_until {
            return Some(q);
        }
        match self.role {
            Role::Sending => self.sender.poll_timeout(),
            Role::Receiving => self.receiver.poll_timeout(),
            Role::Idle => None,
        }
    }

    /// Feed bytes from the line. Returns how many the link consumed; the rest arrived after
    /// the transfer ended and belong to whatever the caller starts next.
    pub fn handle_input(&mut self, input: &[u8], now: Instant) -> usize {
        self.stats.bytes_in += input.len() as u64;
        if self.quiet_until.is_some() {
            self.stats.bytes_dropped += input.len() as u64;
            return input.len();
        }
        let used = match self.role {
            Role::Sending => self.sender.handle_input(input, now),
            Role::Receiving => self.receiver.handle_input(input, now),
            // Nobody listens: the byte is noise or a late byte of a finished exchange.
            Role::Idle => {
                self.stats.bytes_dropped += input.len() as u64;
                input.len()
            }
        };
        self.settle(now);
        used
    }

    /// Tell the link the time: runs timers and ends a reset.
    pub fn handle_timeout(&mut self, now: Instant) {
        if let Some(q) = self.quiet_until {
            if now < q {
                return;
            }
            self.quiet_until = None;
            self.flush = true;
            match self.deferred.take() {
                Some(Deferred::Send(msg, pci)) => self.begin_send(&msg, pci, now),
                Some(Deferred::Receive) => {
                    self.receiver.start();
                    self.role = Role::Receiving;
                }
                None => {}
            }
            return;
        }
        match self.role {
            Role::Sending => self.sender.handle_timeout(now),
            Role::Receiving => self.receiver.handle_timeout(now),
            Role::Idle => {}
        }
        self.settle(now);
    }

    fn settle(&mut self, now: Instant) {
        let result = match self.role {
            Role::Sending => match self.sender.outcome() {
                None => return,
                Some(Ok(())) => Ok(Outcome::Sent),
                Some(Err(e)) => Err((LinkError::Send(e), 2)),
            },
            Role::Receiving => match self.receiver.outcome() {
                None => return,
                Some(Ok(_)) => Ok(Outcome::Received),
                Some(Err(e)) => Err((LinkError::Receive(e), 1)),
            },
            Role::Idle => return,
        };
        self.role = Role::Idle;
        self.sender.reset_if_done();
        match result {
            Ok(outcome) => self.outcome = Some(outcome),
            Err((err, periods)) => {
                self.receiver.reset();
                self.stats.failures += 1;
                self.last_error = Some(err);
                self.outcome = Some(Outcome::Failed(err));
                self.quiet_until = Some(now + self.config().timeouts.reset * periods);
            }
        }
    }
}

impl Sender {
    fn reset_if_done(&mut self) {
        if !self.is_active() {
            self.reset();
        }
    }
}

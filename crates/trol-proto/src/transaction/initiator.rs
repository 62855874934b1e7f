//! TransSR: the PC's side of a transaction.

use std::time::Duration;

use super::{Decision, Failure, PCI_REPEAT, TransCode, pci, pci_number, reply_timeout_from_tenths};
use crate::link::{Link, LinkConfig, LinkError, Outcome, StartError};
use crate::time::Instant;

/// What the initiator has to say.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InitiatorEvent {
    /// The reply arrived: take it with [`Initiator::take_reply`].
    Reply,
    /// Something failed; call [`Initiator::decide`].
    NeedDecision(Failure),
    /// The transaction ended without a reply.
    Failed(TransCode),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    Idle,
    Sending,
    AwaitReply,
    Deciding(Failure),
    Finished,
}

/// TransSR as a sans-IO state machine over one [`Link`].
#[derive(Debug)]
pub struct Initiator {
    link: Link,
    state: State,
    number: u8,
    request: Vec<u8>,
    reply: Option<Vec<u8>>,
    /// Whether the request goes out again (with the REPEAT bit).
    repeat: bool,
    reply_timeout: Duration,
    sent_at: Instant,
    reply_deadline: Option<Instant>,
    /// When the current wait for the reply began.
    awaiting_since: Instant,
    /// With a controller that keeps the line alive while it works: the longest silence
    /// taken before the reply is given up ([`Initiator::set_silence`]).
    silence: Option<Duration>,
    event: Option<InitiatorEvent>,
    stale_replies: u64,
}

impl Initiator {
    /// An idle initiator with the default reply timeout of 15 s.
    pub fn new(cfg: LinkConfig) -> Self {
        let mut link = Link::new(cfg);
        // A controller of this protocol says "still working" with SYN while it executes.
        link.set_keepalive(true);
        Initiator {
            link,
            state: State::Idle,
            number: 0,
            request: Vec::new(),
            reply: None,
            repeat: false,
            reply_timeout: reply_timeout_from_tenths(super::DEFAULT_REPLY_TIMEOUT_TENTHS),
            sent_at: Instant::ZERO,
            reply_deadline: None,
            awaiting_since: Instant::ZERO,
            silence: None,
            event: None,
            stale_replies: 0,
        }
    }

    /// For a controller that sends SYN while it executes a request (it said so in
    /// TROLGetReplyTime, docs/protocol.md "Keep-alive"): give the reply up once the line has
    /// been silent for `silence` (no SYN, no reply), however long the reply timeout. So a
    /// controller that died is told from one that works long. `None`: the reply timeout alone.
    pub fn set_silence(&mut self, silence: Option<Duration>) {
        self.silence = silence;
    }

    /// The longest silence taken while a reply is awaited ([`Initiator::set_silence`]).
    pub fn silence(&self) -> Option<Duration> {
        self.silence
    }

    /// When the wait for the reply ends: its deadline, or earlier, a silence too long.
    fn reply_ends(&self) -> Option<Instant> {
        let deadline = self.reply_deadline?;
        Some(match self.silence {
            Some(s) => {
                let heard = self
                    .link
                    .alive_at()
                    .map_or(self.awaiting_since, |a| a.max(self.awaiting_since));
                deadline.min(heard + s)
            }
            None => deadline,
        })
    }

    /// The link underneath (settings, counters, last error).
    pub fn link(&self) -> &Link {
        &self.link
    }

    /// The link underneath, to change its settings.
    pub fn link_mut(&mut self) -> &mut Link {
        &mut self.link
    }

    /// SetL3_TO_Intervall: how long to wait for a reply, in tenths of a second.
    pub fn set_reply_timeout(&mut self, timeout: Duration) {
        self.reply_timeout = timeout;
    }

    /// The reply timeout.
    pub fn reply_timeout(&self) -> Duration {
        self.reply_timeout
    }

    /// The last layer-2 failure (GetLastCommErr).
    pub fn last_comm_error(&self) -> Option<LinkError> {
        self.link.last_error()
    }

    /// Replies dropped because they answered an earlier transaction.
    pub fn stale_replies(&self) -> u64 {
        self.stale_replies
    }

    /// The request of the current (or last) transaction.
    pub fn request(&self) -> &[u8] {
        &self.request
    }

    /// The PCI the current request carries.
    pub fn current_pci(&self) -> u16 {
        if self.repeat {
            pci(self.number) | PCI_REPEAT
        } else {
            pci(self.number)
        }
    }

    /// The number of the current (or last) transaction.
    pub fn number(&self) -> u8 {
        self.number
    }

    /// Send the last request again, with its number and the REPEAT bit, after the transaction
    /// failed without a reply: a controller that executed it answers from its memory, one
    /// that did not executes it. Returns false if there is nothing to repeat.
    pub fn repeat(&mut self, now: Instant) -> bool {
        if self.is_busy() || self.request.is_empty() && self.number == 0 {
            return false;
        }
        self.repeat = true;
        self.reply = None;
        self.event = None;
        self.send_request(now).is_ok()
    }

    /// Whether the request is on its way out (a failure now is SendData's; later, while the
    /// reply is awaited, ReceiveData's).
    pub fn is_sending(&self) -> bool {
        matches!(self.state, State::Sending)
    }

    /// Whether a transaction is under way.
    pub fn is_busy(&self) -> bool {
        !matches!(self.state, State::Idle | State::Finished)
    }

    /// Start a transaction: send `request`, then wait for its reply.
    pub fn start(&mut self, request: &[u8], now: Instant) -> Result<(), StartError> {
        if self.is_busy() {
            return Err(StartError::Busy);
        }
        if request.len() > crate::link::frame::MAX_MESSAGE {
            return Err(StartError::TooLong(crate::link::MessageTooLong(
                request.len(),
            )));
        }
        // 1, 2, ..., 255, 1, ...: 0 is never a request's number, so that a reply numbered 0
        // can only come from a controller that does not number its replies.
        self.number = self.number.checked_add(1).unwrap_or(1);
        self.link.clear_last_error();
        self.repeat = false;
        self.request.clear();
        self.request.extend_from_slice(request);
        self.reply = None;
        self.event = None;
        self.send_request(now)
    }

    fn send_request(&mut self, now: Instant) -> Result<(), StartError> {
        self.link.send(&self.request, self.current_pci(), now)?;
        self.state = State::Sending;
        Ok(())
    }

    /// Abandon the current transaction (the port failed under it): the link drops its
    /// transfer and the initiator is idle again, so the next [`Initiator::start`] works.
    pub fn abort(&mut self) {
        self.link.abort();
        self.state = State::Idle;
        self.reply = None;
        self.reply_deadline = None;
        self.event = None;
    }

    /// The next event, once.
    pub fn poll_event(&mut self) -> Option<InitiatorEvent> {
        self.event.take()
    }

    /// The reply of a finished transaction.
    pub fn take_reply(&mut self) -> Option<Vec<u8>> {
        self.reply.take()
    }

    /// Answer a [`InitiatorEvent::NeedDecision`].
    pub fn decide(&mut self, decision: Decision, now: Instant) {
        let State::Deciding(failure) = self.state else {
            return;
        };
        match (failure, decision) {
            (_, Decision::GiveUp) => {
                let code = match failure {
                    Failure::Send(_) => TransCode::ErrSend,
                    Failure::Receive(_) => TransCode::ErrReceive,
                    Failure::Timeout { .. } => TransCode::Timeout,
                };
                self.state = State::Finished;
                self.event = Some(InitiatorEvent::Failed(code));
            }
            (Failure::Send(_), _) => {
                if self.send_request(now).is_err() {
                    self.state = State::Finished;
                    self.event = Some(InitiatorEvent::Failed(TransCode::ErrSend));
                }
            }
            (Failure::Receive(_), Decision::WaitMore(extra)) => self.await_reply(now, now + extra),
            (Failure::Receive(_), _) => self.await_reply(now, now + self.reply_timeout),
            (Failure::Timeout { .. }, Decision::WaitMore(extra)) => {
                self.await_reply(now, now + extra)
            }
            (Failure::Timeout { .. }, _) => self.await_reply(now, now + self.reply_timeout),
        }
    }

    fn await_reply(&mut self, now: Instant, deadline: Instant) {
        self.state = State::AwaitReply;
        self.reply_deadline = Some(deadline);
        self.awaiting_since = now;
        if !self.link.is_busy() {
            // Cannot be busy: the link is idle whenever a decision is asked for.
            let _ = self.link.receive(deadline);
        }
    }

    /// When [`Initiator::handle_timeout`] must be called next.
    pub fn poll_timeout(&self) -> Option<Instant> {
        let link = self.link.poll_timeout();
        let reply = match self.state {
            State::AwaitReply if !self.link.receive_in_progress() => self.reply_ends(),
            _ => None,
        };
        match (link, reply) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// Move the bytes to put on the line into `out`.
    pub fn drain_transmit(&mut self, out: &mut Vec<u8>) {
        self.link.drain_transmit(out);
    }

    /// Whether layer 1's input must be flushed now.
    pub fn take_flush_request(&mut self) -> bool {
        self.link.take_flush_request()
    }

    /// Whether a reply may be arriving (the receiver answered ENQ).
    pub fn reply_in_progress(&self) -> bool {
        self.link.receive_in_progress()
    }

    /// Feed bytes from the line.
    pub fn handle_input(&mut self, input: &[u8], now: Instant) {
        let mut rest = input;
        loop {
            let used = self.link.handle_input(rest, now);
            self.settle(now);
            rest = &rest[used..];
            if rest.is_empty() || !self.link.is_busy() {
                break;
            }
        }
    }

    /// Tell the initiator the time.
    pub fn handle_timeout(&mut self, now: Instant) {
        self.link.handle_timeout(now);
        self.settle(now);
        if self.state == State::AwaitReply
            && !self.link.receive_in_progress()
            && self.reply_ends().is_some_and(|d| now >= d)
            && self.link.cancel_receive()
        {
            self.reply_deadline = None;
            self.ask(Failure::Timeout {
                waited: now.saturating_since(self.sent_at),
            });
        }
    }

    fn ask(&mut self, failure: Failure) {
        self.state = State::Deciding(failure);
        self.event = Some(InitiatorEvent::NeedDecision(failure));
    }

    fn settle(&mut self, now: Instant) {
        let Some(outcome) = self.link.poll_outcome() else {
            return;
        };
        match (self.state, outcome) {
            (State::Sending, Outcome::Sent) => {
                self.sent_at = now;
                self.await_reply(now, now + self.reply_timeout);
            }
            (State::Sending, Outcome::Failed(LinkError::Send(e))) => self.ask(Failure::Send(e)),
            (State::AwaitReply, Outcome::Received) => {
                let Some((reply_pci, data)) = self.link.take_received() else {
                    return;
                };
                // The reply carries its request's number; a controller that speaks only the
                // manual's protocol (its PCI is "not needed") sends 0, and that is taken too.
                let number = pci_number(reply_pci);
                if number == self.number || number == 0 {
                    self.reply = Some(data);
                    self.state = State::Finished;
                    self.event = Some(InitiatorEvent::Reply);
                } else {
                    // A late reply to a transaction the PC gave up on.
                    self.stale_replies += 1;
                    self.awaiting_since = self.awaiting_since.max(now);
                    let _ = self.link.receive(now);
                }
            }
            (State::AwaitReply, Outcome::Failed(LinkError::Receive(e))) => {
                self.ask(Failure::Receive(e))
            }
            _ => {}
        }
    }
}

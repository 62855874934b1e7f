//! TransRS: the controller's side of a transaction.

use super::{Decision, Failure, TransCode, pci_is_repeat, pci_number};
use crate::link::{Link, LinkConfig, LinkError, Outcome};
use crate::time::Instant;

/// What the responder has to say.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ResponderEvent {
    /// A request arrived: read it with [`Responder::request`], answer with
    /// [`Responder::respond`] (the manual's MsgReceived).
    Request,
    /// The reply went out: the transaction is done (the manual's TransactionDone).
    Done,
    /// Something failed; call [`Responder::decide`].
    NeedDecision(Failure),
    /// The transaction ended with this code; the responder listens again.
    Failed(TransCode),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    Idle,
    Listening,
    Executing,
    Replying,
    Deciding(Failure),
}

/// TransRS as a sans-IO state machine over one [`Link`]. After each transaction it listens
/// for the next request by itself.
#[derive(Debug)]
pub struct Responder {
    link: Link,
    state: State,
    request_pci: u16,
    request: Vec<u8>,
    reply: Vec<u8>,
    event: Option<ResponderEvent>,
    /// The number of the last request executed, and its reply (exactly once).
    memory: Option<(u8, Vec<u8>)>,
    /// Requests answered from memory.
    repeats_answered: u64,
    /// The manual's layer 3 (a 1998 controller, simulated), if set.
    manual: Option<ManualLayer3>,
    /// The host said it numbers its requests (it activated with TROL's worded line).
    numbered_host: bool,
    /// The numbers of the last requests run, newest first: a host whose numbers are seen
    /// to change numbers its requests; one of 1998 leaves the PCI alone.
    recent_numbers: [Option<u8>; 3],
    /// The host was seen to number its requests since it activated (for the keep-alive:
    /// a repeat, which carries the number again, does not make it a 1998 host).
    seen_numbering: bool,
    /// What the link's LRC check ([`Responder::set_request_check`]) knows of the host's
    /// numbering: bit 8 set when the host numbers its requests, bits 0..7 the number of the
    /// last request run.
    numbering: std::sync::Arc<std::sync::atomic::AtomicU16>,
}

/// How far ahead of the last request run a numbering host's next request may be (requests
/// the controller never got in between, each failed at the host).
pub const NUMBER_WINDOW: u8 = 4;

/// Whether a request's PCI fits a host that numbers its requests, whose last request run was
/// `last`: the reserved bits 9..15 clear, and the number the next few (or `last` marked
/// REPEAT). With the LRC, a PCI that does not fit is damage the sum missed.
pub fn pci_fits(pci: u16, last: u8) -> bool {
    let n = pci_number(pci);
    if pci & 0xFE00 != 0 || n == 0 {
        return false;
    }
    if pci_is_repeat(pci) {
        return n == last;
    }
    // Numbers run 1..=255 and then 1 again.
    let ahead = (i16::from(n) - i16::from(last)).rem_euclid(255);
    (1..=i16::from(NUMBER_WINDOW)).contains(&ahead)
}

/// How a responder that speaks only the manual's layer 3 (a 1998 PCP server) numbers its
/// replies: the manual says the PCI "is not needed" and does not say what goes in it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ManualLayer3 {
    /// Every reply's PCI is 0.
    ZeroPci,
    /// Every reply's PCI is its request's.
    EchoPci,
}

impl Responder {
    /// A responder that does not listen yet; call [`Responder::listen`].
    pub fn new(cfg: LinkConfig) -> Self {
        Responder {
            link: Link::new(cfg),
            state: State::Idle,
            request_pci: 0,
            request: Vec::new(),
            reply: Vec::new(),
            event: None,
            memory: None,
            repeats_answered: 0,
            manual: None,
            numbered_host: false,
            recent_numbers: [None; 3],
            seen_numbering: false,
            numbering: Default::default(),
        }
    }

    /// With the manual's LRC: check every request from a host that numbers its requests
    /// (a TROL host, which sends a refused request again) before its last block is
    /// acknowledged (docs/protocol.md, "Checked as the bytes allow"): `fits(request)` says
    /// whether its bytes are a request the controller knows, whose fields fit its record
    /// (the controller's command table), and the PCI must fit ([`pci_fits`]). A request that
    /// does not is damage the sum let through: asked for again, never run as another
    /// command; the same bytes a second time are taken. A host that does not number its
    /// requests (the manual's) never sends a refused request again: its requests are taken
    /// as the 1998 server took them, and the server answers one it cannot run with its code
    /// (TROL_ERR_UNKNOWN, TROL_ERR_BAD_CSIZE, ...). `None`: the block check alone.
    pub fn set_request_check(&mut self, fits: Option<crate::link::Plausible>) {
        let Some(fits) = fits else {
            self.link.set_plausible(None);
            return;
        };
        let numbering = self.numbering.clone();
        self.link
            .set_plausible(Some(crate::link::Plausible::new(move |pci, request| {
                let known = numbering.load(std::sync::atomic::Ordering::Relaxed);
                let numbered = known & 0x0100 != 0;
                !numbered || fits.check(pci, request) && pci_fits(pci, (known & 0xFF) as u8)
            })));
    }

    fn share_numbering(&self) {
        let last = self.recent_numbers[0].unwrap_or(0);
        let known = if self.host_numbers_requests() && last != 0 {
            0x0100 | u16::from(last)
        } else {
            0
        };
        self.numbering
            .store(known, std::sync::atomic::Ordering::Relaxed);
    }

    /// Whether the host numbers its requests, as TROL's host does: it said so (a host that
    /// activated server mode with TROL's worded line, [`Responder::set_numbered_host`]), or
    /// its last three requests carried three different numbers, none 0. A host written
    /// from the manual alone leaves the PCI as it is (the manual: "not needed"), so the
    /// same number on two requests means nothing from it; from a numbering host it means
    /// the same request again.
    pub fn host_numbers_requests(&self) -> bool {
        if self.numbered_host {
            return true;
        }
        match self.recent_numbers {
            [Some(a), Some(b), Some(c)] => a != 0 && b != 0 && c != 0 && a != b && b != c && a != c,
            _ => false,
        }
    }

    /// Whether the host is one of this protocol, which takes SYN while it waits for a reply
    /// (docs/protocol.md, "Keep-alive"): one that agreed on CRC-16 (no 1998 host can), that
    /// activated with TROL's worded line, or that was seen to number its requests. Never a
    /// host written from the manual alone, whose layer 2 would fail on the byte; never with
    /// the manual's layer 3 ([`Responder::set_manual`]).
    pub fn host_takes_keepalive(&self) -> bool {
        self.manual.is_none()
            && (self.link.config().check == crate::link::BlockCheck::Crc16
                || self.numbered_host
                || self.seen_numbering
                || self.host_numbers_requests())
    }

    /// Say whether the host numbers its requests (`true` after TROL's worded activation
    /// line; `false` after the manual's bare one, or for a new host). Forgets the numbers
    /// seen so far.
    pub fn set_numbered_host(&mut self, numbered: bool) {
        self.numbered_host = numbered;
        self.recent_numbers = [None; 3];
        self.seen_numbering = false;
        self.share_numbering();
    }

    /// Speak only the manual's layer 3, as a 1998 controller does: no memory of the last
    /// request (every request executes, the REPEAT bit unknown, so a repeated relative move
    /// runs twice) and the reply's PCI as `how` says. For the simulated 1998 controller.
    pub fn set_manual(&mut self, how: Option<ManualLayer3>) {
        self.manual = how;
        self.memory = None;
    }

    /// How many repeated requests were answered from memory, not executed again.
    pub fn repeats_answered(&self) -> u64 {
        self.repeats_answered
    }

    /// Whether the request in hand is marked REPEAT while this responder remembers no request
    /// at all: it started (or restarted) after the PC first sent it, so whether an earlier run
    /// of the controller executed it cannot be told. It must not run (a relative move would
    /// run twice); the server answers TROL_ERR_ROBOT_UNSURE.
    pub fn request_is_unknown_repeat(&self) -> bool {
        self.manual.is_none() && pci_is_repeat(self.request_pci) && self.memory.is_none()
    }

    /// Whether the request in hand, with the manual's LRC, is a motion or another CAT1/CAT2
    /// command that is not marked REPEAT yet carries the number of the request last executed:
    /// the host numbers each new request anew, so it is that request again with its REPEAT
    /// bit lost to noise the LRC let through (a relative move would run twice). It must not
    /// run; the server answers TROL_ERR_ROBOT_UNSURE. CRC-16 protects the bit; a controller
    /// without memory (the manual's layer 3) cannot tell.
    ///
    /// Only a host that numbers its requests ([`Responder::host_numbers_requests`]) is held
    /// to this: a 1998 host sends every request under the same PCI (0), and each runs, as
    /// the manual's controller ran them.
    pub fn request_is_suspect_duplicate(&self) -> bool {
        self.manual.is_none()
            && self.link.config().check == crate::link::BlockCheck::Lrc
            && !pci_is_repeat(self.request_pci)
            && pci_number(self.request_pci) != 0
            && self.host_numbers_requests()
            && self.request.first().is_some_and(|code| *code < 128)
            && self
                .memory
                .as_ref()
                .is_some_and(|(n, _)| *n == pci_number(self.request_pci))
    }

    /// Remember `number` as the last request executed, answered with `reply`: a repeat of it
    /// gets that reply, nothing run (a controller's journal, restored after a restart).
    /// Ignored with the manual's layer 3, which has no memory.
    pub fn remember(&mut self, number: u8, reply: Vec<u8>) {
        if self.manual.is_none() {
            self.memory = Some((number, reply));
        }
    }

    /// Forget the last executed request (the manual's behaviour: every request executes).
    pub fn forget(&mut self) {
        self.memory = None;
    }

    /// The link underneath.
    pub fn link(&self) -> &Link {
        &self.link
    }

    /// The link underneath, to change its settings.
    pub fn link_mut(&mut self) -> &mut Link {
        &mut self.link
    }

    /// The last layer-2 failure.
    pub fn last_comm_error(&self) -> Option<LinkError> {
        self.link.last_error()
    }

    /// Start listening for requests.
    pub fn listen(&mut self, now: Instant) {
        if self.state == State::Idle {
            self.state = State::Listening;
            let _ = self.link.receive(now);
        }
    }

    /// Stop listening (only between transactions). Returns whether it stopped.
    pub fn stop(&mut self) -> bool {
        match self.state {
            State::Idle => true,
            State::Listening if self.link.cancel_receive() => {
                self.state = State::Idle;
                true
            }
            _ => false,
        }
    }

    /// Whether a request is being received, executed or answered.
    pub fn in_transaction(&self) -> bool {
        match self.state {
            State::Listening => self.link.receive_in_progress(),
            State::Idle => false,
            _ => true,
        }
    }

    /// The request being executed.
    pub fn request(&self) -> &[u8] {
        &self.request
    }

    /// The reply being sent (what ErrOnSend is handed when sending it fails).
    pub fn reply(&self) -> &[u8] {
        &self.reply
    }

    /// The PCI of the request received.
    pub fn request_pci(&self) -> u16 {
        self.request_pci
    }

    /// The next event, once.
    pub fn poll_event(&mut self) -> Option<ResponderEvent> {
        self.event.take()
    }

    /// Send `reply` to the request being executed.
    pub fn respond(&mut self, reply: &[u8], now: Instant) {
        if self.state != State::Executing {
            return;
        }
        if !self.request_is_suspect_duplicate() && !self.request_is_unknown_repeat() {
            // A request that ran (or was refused on its own merits): its number is the
            // host's newest.
            self.recent_numbers = [
                Some(pci_number(self.request_pci)),
                self.recent_numbers[0],
                self.recent_numbers[1],
            ];
            self.share_numbering();
            self.seen_numbering |= self.host_numbers_requests();
        }
        self.reply.clear();
        self.reply.extend_from_slice(reply);
        if self.manual.is_none() {
            self.memory = Some((pci_number(self.request_pci), reply.to_vec()));
        }
        self.send_reply(now);
    }

    fn send_reply(&mut self, now: Instant) {
        // The reply carries the request's transaction number (the PCI's low byte).
        let reply_pci = match self.manual {
            Some(ManualLayer3::ZeroPci) => 0,
            Some(ManualLayer3::EchoPci) => self.request_pci,
            None => self.request_pci & 0x00FF,
        };
        if self.link.send(&self.reply, reply_pci, now).is_ok() {
            self.state = State::Replying;
        } else {
            self.event = Some(ResponderEvent::Failed(TransCode::ErrSend));
            self.relisten(now);
        }
    }

    /// Answer a [`ResponderEvent::NeedDecision`].
    pub fn decide(&mut self, decision: Decision, now: Instant) {
        let State::Deciding(failure) = self.state else {
            return;
        };
        match (failure, decision) {
            (Failure::Send(_), Decision::Retry | Decision::WaitMore(_)) => self.send_reply(now),
            (Failure::Send(_), Decision::GiveUp) => {
                self.event = Some(ResponderEvent::Failed(TransCode::ErrSend));
                self.relisten(now);
            }
            (_, Decision::GiveUp) => {
                self.event = Some(ResponderEvent::Failed(TransCode::ErrReceive));
                self.relisten(now);
            }
            _ => self.relisten(now),
        }
    }

    fn relisten(&mut self, now: Instant) {
        self.state = State::Idle;
        self.listen(now);
    }

    /// When [`Responder::handle_timeout`] must be called next.
    pub fn poll_timeout(&self) -> Option<Instant> {
        self.link.poll_timeout()
    }

    /// Move the bytes to put on the line into `out`.
    pub fn drain_transmit(&mut self, out: &mut Vec<u8>) {
        self.link.drain_transmit(out);
    }

    /// Whether layer 1's input must be flushed now.
    pub fn take_flush_request(&mut self) -> bool {
        self.link.take_flush_request()
    }

    /// Feed bytes from the line.
    pub fn handle_input(&mut self, input: &[u8], now: Instant) {
        let mut rest = input;
        loop {
            let used = self.link.handle_input(rest, now);
            self.settle(now);
            rest = &rest[used..];
            if rest.is_empty() || self.state != State::Listening {
                break;
            }
        }
    }

    /// Tell the responder the time.
    pub fn handle_timeout(&mut self, now: Instant) {
        self.link.handle_timeout(now);
        self.settle(now);
    }

    fn settle(&mut self, now: Instant) {
        let Some(outcome) = self.link.poll_outcome() else {
            return;
        };
        match (self.state, outcome) {
            (State::Listening, Outcome::Received) => {
                let Some((req_pci, data)) = self.link.take_received() else {
                    return;
                };
                self.request_pci = req_pci;
                self.request = data;
                match &self.memory {
                    // A repeat of the request last executed: its reply again, nothing run.
                    Some((n, reply)) if pci_is_repeat(req_pci) && *n == pci_number(req_pci) => {
                        self.reply = reply.clone();
                        self.repeats_answered += 1;
                        self.send_reply(now);
                    }
                    _ => {
                        self.state = State::Executing;
                        self.event = Some(ResponderEvent::Request);
                    }
                }
            }
            (State::Listening, Outcome::Failed(LinkError::Receive(e))) => {
                self.state = State::Deciding(Failure::Receive(e));
                self.event = Some(ResponderEvent::NeedDecision(Failure::Receive(e)));
            }
            (State::Replying, Outcome::Sent) => {
                self.event = Some(ResponderEvent::Done);
                self.relisten(now);
            }
            (State::Replying, Outcome::Failed(LinkError::Send(e))) => {
                self.state = State::Deciding(Failure::Send(e));
                self.event = Some(ResponderEvent::NeedDecision(Failure::Send(e)));
            }
            _ => {}
        }
    }
}

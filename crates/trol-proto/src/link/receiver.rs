//! The receiving side of layer 2 (the manual's ReceiveData) as a sans-IO state machine.
//!
//! The receiver knows from the header how long every frame is, so it reads each block by its
//! length and then checks it, in this order (the first failing check decides):
//!
//! 1. the first byte is (within one bit) SOH / STX, else NAK ERR_SOH / ERR_STX (retry);
//! 2. the last byte is the expected terminator; the other terminator is NAK ERR_ETB (fatal),
//!    any other byte NAK ERR_ETX (retry);
//! 3. the BCC matches, else NAK ERR_BCC (retry);
//! 4. header: #bytes within the receiver's limit, else NAK ERR_TOO_LARGE (fatal);
//!    frame: the frame-ID is the one expected, else NAK ERR_FID (fatal);
//! 5. CRC-16 mode: the frame-ID field's second CRC, and, on the block that completes the
//!    message, the message check in the PCI's bits 9..15; else NAK ERR_BCC (retry).
//!
//! A refused block is NAK'd and expected again, at most MAX_RETRIES times. Bytes that were
//! handed in together with a refused block arrived before the NAK went out, so they cannot be
//! the retransmission: they are dropped.

use super::codes::{NakCode, ReceiveError};
use super::config::{BlockCheck, LinkConfig};
use super::control::{self, ACK, ENQ, EOT, ETB, ETX, NAK, SOH, STX};
use super::frame::{self, HEADER_LEN, Header};
use crate::time::Instant;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Block {
    Header,
    Frame(usize),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    Idle,
    AwaitEnq,
    AwaitStart(Block),
    InBlock(Block),
    AwaitEot,
    Done,
    Failed(ReceiveError),
}

/// A message received by layer 2.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Received<'a> {
    /// The PCI from the header.
    pub pci: u16,
    /// The message bytes.
    pub data: &'a [u8],
}

/// What happened to one byte or block; for traces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Check {
    Ok,
    Retry(NakCode),
    Fatal(NakCode),
}

/// ReceiveData as a state machine.
#[derive(Debug)]
pub struct Receiver {
    cfg: LinkConfig,
    state: State,
    block: Vec<u8>,
    need: usize,
    len: usize,
    pci: u16,
    /// The PCI as it came on the line (in CRC-16 mode with the message check).
    line_pci: u16,
    message: Vec<u8>,
    naks: u8,
    deadline: Option<Instant>,
    out: Vec<u8>,
    /// With the LRC: what the message must be to be taken ([`Plausible`]).
    plausible: Option<Plausible>,
    /// The last message refused as implausible (PCI, bytes): the same bytes again are
    /// taken, since noise does not repeat itself (a peer that means them gets its answer).
    doubted: Option<(u16, Vec<u8>)>,
    /// Whether a SYN while ENQ is awaited is the peer's "still working" ([`control::SYN`]).
    keepalive: bool,
    /// When the last SYN came (since the last [`Receiver::start`]).
    alive_at: Option<Instant>,
}

/// With the manual's LRC, which lets damage through that a CRC finds, a check of a whole
/// message (its PCI and bytes) before its last block is acknowledged: what the layers above
/// know it must be (a request of a known command whose fields fit its record; the reply the
/// pending request can have). An implausible message is asked for again (NAK ERR_BCC) when
/// it travels in the header alone, and its transfer aborted (NAK ERR_FID, fatal: layer 3
/// sends the request again) when it has frames, whose header a NAK would not bring again.
/// The same bytes a second time are taken.
#[derive(Clone)]
pub struct Plausible(std::sync::Arc<PlausibleFn>);

/// The check inside a [`Plausible`]: `(pci, message) -> passes`.
type PlausibleFn = dyn Fn(u16, &[u8]) -> bool + Send + Sync;

impl Plausible {
    /// The check `f(pci, message)`.
    pub fn new(f: impl Fn(u16, &[u8]) -> bool + Send + Sync + 'static) -> Self {
        Plausible(std::sync::Arc::new(f))
    }

    /// Whether `message` under `pci` passes.
    pub fn check(&self, pci: u16, message: &[u8]) -> bool {
        (self.0)(pci, message)
    }
}

impl std::fmt::Debug for Plausible {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Plausible(..)")
    }
}

impl Receiver {
    /// An idle receiver.
    pub fn new(cfg: LinkConfig) -> Self {
        Receiver {
            cfg,
            state: State::Idle,
            block: Vec::with_capacity(frame::FRAME_SIZE + frame::FRAME_OVERHEAD),
            need: 0,
            len: 0,
            pci: 0,
            line_pci: 0,
            message: Vec::new(),
            naks: 0,
            deadline: None,
            out: Vec::new(),
            plausible: None,
            doubted: None,
            keepalive: false,
            alive_at: None,
        }
    }

    /// Take SYN while ENQ is awaited as the peer's "still working" (a host of this protocol
    /// waiting for its reply, docs/protocol.md "Keep-alive"); off, SYN there fails the
    /// transfer as any byte but ENQ (the manual's).
    pub fn set_keepalive(&mut self, on: bool) {
        self.keepalive = on;
    }

    /// When the last SYN arrived since the wait for ENQ began, if one did.
    pub fn alive_at(&self) -> Option<Instant> {
        self.alive_at
    }

    /// Check each message with the LRC ([`Plausible`]); `None`: the block check alone.
    pub fn set_plausible(&mut self, plausible: Option<Plausible>) {
        self.plausible = plausible;
        self.doubted = None;
    }

    /// With the LRC and a [`Plausible`] check: whether the whole message passes (or came
    /// twice the same); an implausible one is remembered.
    fn plausible(&mut self, pci: u16, whole: &[u8]) -> bool {
        let Some(check) = &self.plausible else {
            return true;
        };
        if self.cfg.check != BlockCheck::Lrc || check.check(pci, whole) {
            return true;
        }
        if self
            .doubted
            .as_ref()
            .is_some_and(|(p, m)| *p == pci && m == whole)
        {
            self.doubted = None;
            return true;
        }
        self.doubted = Some((pci, whole.to_vec()));
        false
    }

    /// The settings.
    pub fn config(&self) -> &LinkConfig {
        &self.cfg
    }

    /// Change the settings; takes effect with the next transfer.
    pub fn set_config(&mut self, cfg: LinkConfig) {
        self.cfg = cfg;
    }

    /// Start waiting for ENQ. Waiting for ENQ has no timeout at this layer: the layer above
    /// decides how long it waits for a message.
    pub fn start(&mut self) {
        self.state = State::AwaitEnq;
        self.deadline = None;
        self.alive_at = None;
        self.naks = 0;
        self.message.clear();
        self.out.clear();
    }

    /// Whether a transfer is under way or awaited.
    pub fn is_active(&self) -> bool {
        matches!(
            self.state,
            State::AwaitEnq | State::AwaitStart(_) | State::InBlock(_) | State::AwaitEot
        )
    }

    /// Whether the sender has started (ENQ was answered) and the transfer is not over yet.
    pub fn in_transfer(&self) -> bool {
        self.is_active() && self.state != State::AwaitEnq
    }

    /// `Some(Ok(message))` once EOT arrived, `Some(Err(_))` once the transfer failed.
    pub fn outcome(&self) -> Option<Result<Received<'_>, ReceiveError>> {
        match self.state {
            State::Done => Some(Ok(Received {
                pci: self.pci,
                data: &self.message,
            })),
            State::Failed(e) => Some(Err(e)),
            _ => None,
        }
    }

    /// Take the received message out (leaves the receiver idle).
    pub fn take_message(&mut self) -> Option<(u16, Vec<u8>)> {
        if self.state == State::Done {
            self.state = State::Idle;
            Some((self.pci, std::mem::take(&mut self.message)))
        } else {
            None
        }
    }

    /// Forget the outcome of the last transfer.
    pub fn reset(&mut self) {
        self.state = State::Idle;
        self.deadline = None;
    }

    /// When [`Receiver::handle_timeout`] must be called next, if a timer runs.
    pub fn poll_timeout(&self) -> Option<Instant> {
        if self.is_active() {
            self.deadline
        } else {
            None
        }
    }

    /// Move the bytes to put on the line into `out` (appending).
    pub fn drain_transmit(&mut self, out: &mut Vec<u8>) {
        out.append(&mut self.out);
    }

    /// Bytes waiting to be put on the line.
    pub fn pending_transmit(&self) -> &[u8] {
        &self.out
    }

    /// Tell the receiver the time; fails the transfer if its timer ran out.
    pub fn handle_timeout(&mut self, now: Instant) {
        let Some(deadline) = self.poll_timeout() else {
            return;
        };
        if now < deadline {
            return;
        }
        let err = match self.state {
            State::AwaitStart(Block::Header) => ReceiveError::TimeoutSoh,
            State::AwaitStart(Block::Frame(_)) => ReceiveError::TimeoutStx,
            State::InBlock(_) => ReceiveError::TimeoutTermc,
            State::AwaitEot => ReceiveError::TimeoutEot,
            _ => return,
        };
        self.fail(err);
    }

    /// Feed bytes received from the line. Returns how many were consumed (dropped bytes
    /// count as consumed); once the transfer has ended, the rest are not the receiver's.
    pub fn handle_input(&mut self, input: &[u8], now: Instant) -> usize {
        let mut i = 0;
        while i < input.len() && self.is_active() {
            match self.state {
                State::InBlock(_) => {
                    let take = (self.need - self.block.len()).min(input.len() - i);
                    self.block.extend_from_slice(&input[i..i + take]);
                    i += take;
                    // A block whose bytes keep coming is alive: a sender that pauses between
                    // bytes (the manual's SetDelay, which this end cannot know) gets its
                    // termc after its last byte, not after the block's line time.
                    if take > 0 {
                        let alive = now + self.cfg.timeouts.termc;
                        self.deadline = self.deadline.map(|d| d.max(alive));
                    }
                    if self.block.len() == self.need {
                        match self.finish_block(now) {
                            Check::Ok => {}
                            // Bytes that came with a refused block predate the NAK.
                            Check::Retry(_) | Check::Fatal(_) => return input.len(),
                        }
                    }
                }
                _ => {
                    let byte = input[i];
                    i += 1;
                    self.on_byte(byte, now);
                }
            }
        }
        i
    }

    fn fail(&mut self, err: ReceiveError) {
        self.state = State::Failed(err);
        self.deadline = None;
    }

    fn expect_start(&mut self, block: Block, now: Instant, just_sent: usize) {
        self.state = State::AwaitStart(block);
        self.deadline = Some(now + self.cfg.line_time(just_sent) + self.cfg.timeouts.start);
    }

    fn on_byte(&mut self, byte: u8, now: Instant) {
        match self.state {
            State::AwaitEnq => {
                if control::accepts(byte, ENQ) {
                    self.out.push(ACK);
                    self.expect_start(Block::Header, now, 1);
                } else if self.keepalive && control::accepts(byte, control::SYN) {
                    self.alive_at = Some(now);
                } else {
                    self.fail(ReceiveError::BadEnq);
                }
            }
            State::AwaitStart(block) => {
                self.need = match block {
                    Block::Header => HEADER_LEN,
                    Block::Frame(i) => frame::frame_wire_len(self.len, i),
                };
                self.block.clear();
                self.block.push(byte);
                self.state = State::InBlock(block);
                self.deadline = Some(now + self.cfg.line_time(self.need) + self.cfg.timeouts.termc);
            }
            State::AwaitEot => {
                if control::accepts(byte, EOT) {
                    self.state = State::Done;
                    self.deadline = None;
                } else {
                    self.fail(ReceiveError::BadEot);
                }
            }
            State::InBlock(_) | State::Idle | State::Done | State::Failed(_) => {}
        }
    }

    fn check_block(&mut self, block: Block) -> Check {
        let b = &self.block;
        let last = b[b.len() - 1];
        let (start, start_err) = match block {
            Block::Header => (SOH, NakCode::Soh),
            Block::Frame(_) => (STX, NakCode::Stx),
        };
        if !control::accepts(b[0], start) {
            return Check::Retry(start_err);
        }
        let terminator = match block {
            Block::Header => ETX,
            Block::Frame(i) if i + 1 == frame::frame_count(self.len) => ETX,
            Block::Frame(_) => ETB,
        };
        let other = if terminator == ETX { ETB } else { ETX };
        if !control::accepts(last, terminator) {
            return if control::accepts(last, other) {
                Check::Fatal(NakCode::Etb)
            } else {
                Check::Retry(NakCode::Etx)
            };
        }
        let n = b.len();
        let bcc = u16::from_le_bytes([b[n - 3], b[n - 2]]);
        let computed = match block {
            Block::Header => frame::bcc(self.cfg.check, &b[1..n - 3]),
            Block::Frame(_) => frame::frame_bcc(self.cfg.check, &b[1..n - 5], [b[n - 5], b[n - 4]]),
        };
        if computed != bcc {
            return Check::Retry(NakCode::Bcc);
        }
        let check = self.cfg.check;
        match block {
            Block::Header => {
                let len = u16::from_le_bytes([b[1], b[2]]);
                if usize::from(len) > self.cfg.max_message {
                    return Check::Fatal(NakCode::TooLarge);
                }
                // A message that travels in the header alone: its check now.
                let pci = u16::from_le_bytes([b[3], b[4]]);
                let first = &b[5..5 + usize::from(len).min(2)];
                if frame::frame_count(usize::from(len)) == 0
                    && frame::line_pci(check, pci, first) != pci
                {
                    return Check::Retry(NakCode::Bcc);
                }
                if frame::frame_count(usize::from(len)) == 0 {
                    let first = first.to_vec();
                    if !self.plausible(pci, &first) {
                        return Check::Retry(NakCode::Bcc);
                    }
                }
            }
            Block::Frame(i) => {
                let data = &b[1..n - 5];
                let field = u16::from_le_bytes([b[n - 5], b[n - 4]]);
                let named = usize::from(frame::frame_index_of(check, field, data));
                if named != i {
                    // Another frame than the one expected (the one before, sent again after
                    // a lost ACK, or the one after) is the manual's fatal ERR_FID; in CRC-16
                    // mode a field that names any other index is damage the BCC missed: the
                    // frame is asked for again.
                    return if check == BlockCheck::Lrc || named + 1 == i || named == i + 1 {
                        Check::Fatal(NakCode::Fid)
                    } else {
                        Check::Retry(NakCode::Bcc)
                    };
                }
                // The last frame completes the message: its check (CRC-16 mode).
                if i + 1 == frame::frame_count(self.len) && check == BlockCheck::Crc16 {
                    let mut whole = Vec::with_capacity(self.len);
                    whole.extend_from_slice(&self.message);
                    whole.extend_from_slice(data);
                    if frame::line_pci(check, self.pci, &whole) != self.line_pci {
                        return Check::Retry(NakCode::Bcc);
                    }
                }
                // With the LRC: the whole message as the layers above know it must be.
                if i + 1 == frame::frame_count(self.len)
                    && check == BlockCheck::Lrc
                    && self.plausible.is_some()
                {
                    let mut whole = Vec::with_capacity(self.len);
                    whole.extend_from_slice(&self.message);
                    whole.extend_from_slice(data);
                    if !self.plausible(self.pci, &whole) {
                        return Check::Fatal(NakCode::Fid);
                    }
                }
            }
        }
        Check::Ok
    }

    fn finish_block(&mut self, now: Instant) -> Check {
        let State::InBlock(block) = self.state else {
            return Check::Ok;
        };
        let check = self.check_block(block);
        match check {
            Check::Ok => {
                self.naks = 0;
                self.out.push(ACK);
                let next = match block {
                    Block::Header => {
                        let mut hdr = [0u8; HEADER_LEN];
                        hdr.copy_from_slice(&self.block);
                        let header = Header::decode_fields(&hdr);
                        self.len = usize::from(header.len);
                        self.line_pci = header.pci;
                        // Layer 3 gets its own bits; in CRC-16 mode the rest is the check.
                        self.pci = match self.cfg.check {
                            BlockCheck::Lrc => header.pci,
                            BlockCheck::Crc16 => header.pci & frame::PCI_LAYER3_BITS,
                        };
                        self.message.clear();
                        self.message.reserve(self.len);
                        self.message
                            .extend_from_slice(&header.first_word[..self.len.min(2)]);
                        0
                    }
                    Block::Frame(i) => {
                        let n = self.block.len();
                        self.message.extend_from_slice(&self.block[1..n - 5]);
                        i + 1
                    }
                };
                if next < frame::frame_count(self.len) {
                    self.expect_start(Block::Frame(next), now, 1);
                } else {
                    self.state = State::AwaitEot;
                    self.deadline = Some(now + self.cfg.line_time(1) + self.cfg.timeouts.eot);
                }
            }
            Check::Retry(code) => {
                self.out.extend_from_slice(&[NAK, code.byte()]);
                self.naks += 1;
                if self.naks > self.cfg.max_retries {
                    self.fail(ReceiveError::LimitExceeded);
                } else {
                    self.expect_start(block, now, 2);
                }
            }
            Check::Fatal(code) => {
                self.out.extend_from_slice(&[NAK, code.byte()]);
                self.fail(ReceiveError::Abort(code));
            }
        }
        check
    }
}

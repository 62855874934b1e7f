//! The sending side of layer 2 (the manual's SendData) as a sans-IO state machine.
//!
//! ```text
//! SENDER                    RECEIVER
//! ENQ            ->
//!                <-         ACK
//! HEADER         ->
//!                <-         ACK            (or NAK code: send the header again)
//! FRAME(0..N-1)  ->
//!                <-         ACK            (or NAK code: send the frame again)
//! EOT            ->
//! ```

use super::codes::{NakClass, NakCode, SendError};
use super::config::LinkConfig;
use super::control::{self, ACK, ENQ, EOT, NAK};
use super::frame::{self, Header, MAX_MESSAGE};
use crate::time::Instant;

/// The message handed to SendData is longer than the 65535 bytes the header can announce.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MessageTooLong(pub usize);

impl std::fmt::Display for MessageTooLong {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "message of {} bytes is longer than the {} bytes layer 2 can carry",
            self.0, MAX_MESSAGE
        )
    }
}

impl std::error::Error for MessageTooLong {}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Block {
    Header,
    Frame(usize),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    Idle,
    AwaitEnqAck,
    AwaitAck(Block),
    AwaitNakCode(Block),
    Done,
    Failed(SendError),
}

/// SendData as a state machine: feed it the bytes from the line and the passing time, and
/// put on the line what it asks for.
#[derive(Debug)]
pub struct Sender {
    cfg: LinkConfig,
    state: State,
    message: Vec<u8>,
    pci: u16,
    retries: u8,
    deadline: Option<Instant>,
    out: Vec<u8>,
}

impl Sender {
    /// An idle sender.
    pub fn new(cfg: LinkConfig) -> Self {
        Sender {
            cfg,
            state: State::Idle,
            message: Vec::new(),
            pci: 0,
            retries: 0,
            deadline: None,
            out: Vec::new(),
        }
    }

    /// The settings.
    pub fn config(&self) -> &LinkConfig {
        &self.cfg
    }

    /// Change the settings; takes effect with the next transfer.
    pub fn set_config(&mut self, cfg: LinkConfig) {
        self.cfg = cfg;
    }

    /// Start sending `message` with `pci` in the header: queues ENQ.
    pub fn start(&mut self, message: &[u8], pci: u16, now: Instant) -> Result<(), MessageTooLong> {
        if message.len() > MAX_MESSAGE {
            return Err(MessageTooLong(message.len()));
        }
        self.message.clear();
        self.message.extend_from_slice(message);
        self.pci = pci;
        self.retries = 0;
        self.out.clear();
        self.out.push(ENQ);
        self.state = State::AwaitEnqAck;
        self.deadline = Some(now + self.cfg.line_time(1) + self.cfg.timeouts.enq);
        Ok(())
    }

    /// Whether a transfer is under way.
    pub fn is_active(&self) -> bool {
        matches!(
            self.state,
            State::AwaitEnqAck | State::AwaitAck(_) | State::AwaitNakCode(_)
        )
    }

    /// `Some(Ok(()))` once EOT has been queued, `Some(Err(_))` once the transfer failed.
    pub fn outcome(&self) -> Option<Result<(), SendError>> {
        match self.state {
            State::Done => Some(Ok(())),
            State::Failed(e) => Some(Err(e)),
            _ => None,
        }
    }

    /// Forget the outcome of the last transfer.
    pub fn reset(&mut self) {
        self.state = State::Idle;
        self.deadline = None;
    }

    /// When [`Sender::handle_timeout`] must be called next, if a timer runs.
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

    /// Feed bytes received from the line. Returns how many were consumed: once the transfer
    /// has ended, the rest are not the sender's.
    pub fn handle_input(&mut self, input: &[u8], now: Instant) -> usize {
        let mut used = 0;
        for &byte in input {
            if !self.is_active() {
                break;
            }
            used += 1;
            self.on_byte(byte, now);
        }
        used
    }

    /// Tell the sender the time; fails the transfer if its timer ran out.
    pub fn handle_timeout(&mut self, now: Instant) {
        let Some(deadline) = self.poll_timeout() else {
            return;
        };
        if now < deadline {
            return;
        }
        let err = match self.state {
            State::AwaitEnqAck => SendError::TimeoutEnq,
            State::AwaitAck(_) => SendError::TimeoutEtx,
            State::AwaitNakCode(_) => SendError::TimeoutNak,
            _ => return,
        };
        self.fail(err);
    }

    fn fail(&mut self, err: SendError) {
        self.state = State::Failed(err);
        self.deadline = None;
    }

    fn on_byte(&mut self, byte: u8, now: Instant) {
        match self.state {
            State::AwaitEnqAck => {
                if control::accepts(byte, ACK) {
                    self.send_block(Block::Header, now);
                } else if control::accepts(byte, NAK) {
                    self.await_nak_code(Block::Header, now);
                } else {
                    self.fail(SendError::WrongCchar);
                }
            }
            State::AwaitAck(block) => {
                if control::accepts(byte, ACK) {
                    self.retries = 0;
                    let next = match block {
                        Block::Header => 0,
                        Block::Frame(i) => i + 1,
                    };
                    if next < frame::frame_count(self.message.len()) {
                        self.send_block(Block::Frame(next), now);
                    } else {
                        self.out.push(EOT);
                        self.state = State::Done;
                        self.deadline = None;
                    }
                } else if control::accepts(byte, NAK) {
                    self.await_nak_code(block, now);
                } else {
                    self.fail(SendError::WrongCchar);
                }
            }
            State::AwaitNakCode(block) => match NakCode::classify(byte) {
                NakClass::Fatal(code) => self.fail(SendError::Nak(code)),
                NakClass::Retry => {
                    self.retries += 1;
                    if self.retries > self.cfg.max_retries {
                        self.fail(SendError::LimitExceeded);
                    } else {
                        self.send_block(block, now);
                    }
                }
            },
            State::Idle | State::Done | State::Failed(_) => {}
        }
    }

    fn await_nak_code(&mut self, block: Block, now: Instant) {
        self.state = State::AwaitNakCode(block);
        self.deadline = Some(now + self.cfg.timeouts.nak_code);
    }

    fn send_block(&mut self, block: Block, now: Instant) {
        let before = self.out.len();
        match block {
            Block::Header => {
                let pci = frame::line_pci(self.cfg.check, self.pci, &self.message);
                let header = Header::for_message(&self.message, pci);
                self.out.extend_from_slice(&header.encode(self.cfg.check));
            }
            Block::Frame(i) => frame::encode_frame(&self.message, i, self.cfg.check, &mut self.out),
        }
        let sent = self.out.len() - before;
        self.state = State::AwaitAck(block);
        self.deadline = Some(now + self.cfg.line_time(sent) + self.cfg.timeouts.ack);
    }
}

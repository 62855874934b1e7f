//! Settings of layer 2: timeouts, retries and the receiver's size limit.

use std::time::Duration;

use super::frame::{MAX_MESSAGE, MAX_RETRIES};

/// Every layer-2 timeout, named after the return value it produces.
///
/// Each timeout guards one state; the table in docs/protocol.md lists them. Where a timeout
/// runs while bytes are still being sent, the line time of those bytes (see
/// [`LinkConfig::char_time`]) is added to it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Timeouts {
    /// Sender: after ENQ, until ACK (ERR_TIMEOUT_ENQ).
    pub enq: Duration,
    /// Sender: after ETX or ETB of a block, until ACK or NAK (ERR_TIMEOUT_ETX).
    pub ack: Duration,
    /// Sender: after NAK, until its code (ERR_TIMEOUT_NAK).
    pub nak_code: Duration,
    /// Receiver: after its ACK or NAK, until SOH (ERR_TIMEOUT_SOH) or STX (ERR_TIMEOUT_STX).
    pub start: Duration,
    /// Receiver: from SOH or STX until the block is complete (ERR_TIMEOUT_TERMC).
    pub termc: Duration,
    /// Receiver: after the ACK of the last block, until EOT (ERR_TIMEOUT_EOT).
    pub eot: Duration,
    /// The manual's "Timeoutperiode" for the reset after a failure: the receiver stays deaf
    /// for one period, the sender for two, and then the input is flushed.
    pub reset: Duration,
}

impl Default for Timeouts {
    fn default() -> Self {
        Timeouts::uniform(Duration::from_millis(1000))
    }
}

impl Timeouts {
    /// Every timeout set to `t`.
    pub const fn uniform(t: Duration) -> Self {
        Timeouts {
            enq: t,
            ack: t,
            nak_code: t,
            start: t,
            termc: t,
            eot: t,
            reset: t,
        }
    }
}

/// How the BCC of a block is computed. Both ends must agree; the activation line does
/// (docs/protocol.md, "Block check").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum BlockCheck {
    /// The manual's LRC: the sum of the bytes modulo 2^16. Two errors in one bit column
    /// cancel, so it misses many corrupted blocks on a noisy line.
    Lrc,
    /// CRC-16/CCITT (polynomial 0x1021, initial value 0xFFFF): every error of 1, 2 or 3 bits
    /// and every burst of up to 16 bits in a block is caught. TROL's default.
    #[default]
    Crc16,
}

impl BlockCheck {
    /// The word the activation line uses: `LRC`, `CRC16`.
    pub fn word(self) -> &'static str {
        match self {
            BlockCheck::Lrc => "LRC",
            BlockCheck::Crc16 => "CRC16",
        }
    }

    /// The check with this word (any case).
    pub fn from_word(word: &str) -> Option<BlockCheck> {
        match word.to_ascii_uppercase().as_str() {
            "LRC" => Some(BlockCheck::Lrc),
            "CRC16" | "CRC" => Some(BlockCheck::Crc16),
            _ => None,
        }
    }
}

/// Settings of one end of the link. Both ends must agree on `max_retries` and `check`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LinkConfig {
    /// The timeouts.
    pub timeouts: Timeouts,
    /// How often one block may be sent again (MAX_RETRIES).
    pub max_retries: u8,
    /// Largest message this end accepts as a receiver; a larger header is refused with
    /// NAK ERR_TOO_LARGE.
    pub max_message: usize,
    /// Line time of one byte (10 bit times at the baud rate, plus the inter-character delay
    /// of the sender). Added to timeouts that run while bytes travel. Zero for an unpaced line.
    pub char_time: Duration,
    /// The block check.
    pub check: BlockCheck,
}

impl Default for LinkConfig {
    fn default() -> Self {
        LinkConfig {
            timeouts: Timeouts::default(),
            max_retries: MAX_RETRIES,
            max_message: MAX_MESSAGE,
            char_time: Duration::ZERO,
            check: BlockCheck::default(),
        }
    }
}

impl LinkConfig {
    /// Defaults for a line at `baud` (8N1: 10 bits a byte) with `delay` between the
    /// characters a sender puts out.
    pub fn for_line(baud: u32, delay: Duration) -> Self {
        LinkConfig {
            char_time: char_time(baud) + delay,
            ..LinkConfig::default()
        }
    }

    /// Line time of `bytes` bytes.
    pub fn line_time(&self, bytes: usize) -> Duration {
        self.char_time
            .saturating_mul(u32::try_from(bytes).unwrap_or(u32::MAX))
    }
}

/// Time one byte takes on an 8N1 line at `baud` (start bit, 8 data bits, stop bit).
pub fn char_time(baud: u32) -> Duration {
    if baud == 0 {
        Duration::ZERO
    } else {
        Duration::from_nanos(10_000_000_000 / u64::from(baud))
    }
}

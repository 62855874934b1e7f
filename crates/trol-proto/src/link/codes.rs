//! Error codes of layer 2 (manual, "Fehlercodes der Schicht 2"): NAK codes, and the return
//! values of the services SendData and ReceiveData.

use std::fmt;

/// NAK codes: sent by the receiver after NAK (manual, "NAK-Codes").
///
/// Subgroup 1 is fatal: the receiver aborts the connection. Subgroup 2 asks the sender to send
/// the header or frame again. Codes of one subgroup differ pairwise in at least 2 bits, codes of
/// different subgroups in at least 4 bits, so a NAK code with one bit flipped still falls into
/// the right subgroup.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum NakCode {
    /// Fatal: the frame-ID is not the one expected.
    Fid = 0x01,
    /// Fatal: ETB was received where ETX belongs, or ETX where ETB belongs.
    Etb = 0x02,
    /// Fatal: the message is larger than the receiver accepts.
    TooLarge = 0x04,
    /// Retry: the block check characters are wrong.
    Bcc = 0xF1,
    /// Retry: STX was expected, another byte was received.
    Stx = 0xF2,
    /// Retry: ETX (or ETB) was expected at the end of a block, another byte was received.
    Etx = 0xF4,
    /// Retry: SOH was expected, another byte was received.
    Soh = 0xF8,
}

/// How a sender reads the byte that follows a NAK.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NakClass {
    /// Within one bit of a fatal code: the receiver has aborted.
    Fatal(NakCode),
    /// Any other byte: send the block again (counted against MAX_RETRIES).
    Retry,
}

impl NakCode {
    /// Every NAK code, subgroup 1 first.
    pub const ALL: [NakCode; 7] = [
        NakCode::Fid,
        NakCode::Etb,
        NakCode::TooLarge,
        NakCode::Bcc,
        NakCode::Stx,
        NakCode::Etx,
        NakCode::Soh,
    ];

    /// The byte on the line.
    pub const fn byte(self) -> u8 {
        self as u8
    }

    /// The code with this exact value.
    pub fn from_byte(byte: u8) -> Option<NakCode> {
        NakCode::ALL.into_iter().find(|c| c.byte() == byte)
    }

    /// Whether this code ends the connection (subgroup 1).
    pub const fn is_fatal(self) -> bool {
        matches!(self, NakCode::Fid | NakCode::Etb | NakCode::TooLarge)
    }

    /// The manual's name.
    pub const fn name(self) -> &'static str {
        match self {
            NakCode::Fid => "ERR_FID",
            NakCode::Etb => "ERR_ETB",
            NakCode::TooLarge => "ERR_TOO_LARGE",
            NakCode::Bcc => "ERR_BCC",
            NakCode::Stx => "ERR_STX",
            NakCode::Etx => "ERR_ETX",
            NakCode::Soh => "ERR_SOH",
        }
    }

    /// Classify a received NAK code byte. A byte within one bit of a fatal code is taken as
    /// that code; every other byte (a retry code, or a code damaged beyond recognition) asks
    /// for the block again, which is safe: the retry counter bounds it.
    pub fn classify(byte: u8) -> NakClass {
        for code in [NakCode::Fid, NakCode::Etb, NakCode::TooLarge] {
            if (byte ^ code.byte()).count_ones() <= 1 {
                return NakClass::Fatal(code);
            }
        }
        NakClass::Retry
    }
}

impl fmt::Display for NakCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} (0x{:02X})", self.name(), self.byte())
    }
}

/// Why SendData failed (manual, "Rückgabewerte von SendData").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SendError {
    /// 0x01: ACK or NAK was expected, another byte was received.
    WrongCchar,
    /// 0x02: the receiver aborted with a fatal NAK code (carried in the high byte).
    Nak(NakCode),
    /// 0x03: the receiver did not answer ENQ.
    TimeoutEnq,
    /// 0x04: NAK was received but its code did not follow in time.
    TimeoutNak,
    /// 0x05: no ACK or NAK after ETX / ETB.
    TimeoutEtx,
    /// 0x07: one block was refused more than MAX_RETRIES times.
    LimitExceeded,
    /// 0x08 (added; the manual's serial driver could not fail): the port itself failed while
    /// sending, an I/O error (the process behind a pty or a TCP connection is gone).
    Port,
}

impl SendError {
    /// The manual's return value: the code in the low byte, the NAK code in the high byte for
    /// ERR_NAK.
    pub const fn code(self) -> u16 {
        match self {
            SendError::WrongCchar => 0x01,
            SendError::Nak(nak) => 0x02 | ((nak as u16) << 8),
            SendError::TimeoutEnq => 0x03,
            SendError::TimeoutNak => 0x04,
            SendError::TimeoutEtx => 0x05,
            SendError::LimitExceeded => 0x07,
            SendError::Port => 0x08,
        }
    }

    /// The manual's name.
    pub const fn name(self) -> &'static str {
        match self {
            SendError::WrongCchar => "ERR_WRONG_CCHAR",
            SendError::Nak(_) => "ERR_NAK",
            SendError::TimeoutEnq => "ERR_TIMEOUT_ENQ",
            SendError::TimeoutNak => "ERR_TIMEOUT_NAK",
            SendError::TimeoutEtx => "ERR_TIMEOUT_ETX",
            SendError::LimitExceeded => "ERR_LIMIT_EXCEEDED",
            SendError::Port => "ERR_PORT",
        }
    }
}

/// Why ReceiveData failed (manual, "Rückgabewerte von ReceiveData").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ReceiveError {
    /// 0x80: a fatal error; the NAK code sent to the sender is in the high byte.
    Abort(NakCode),
    /// 0x81: no SOH after the ACK of ENQ (or after a NAK of the header).
    TimeoutSoh,
    /// 0x82: no STX after the ACK of the previous block (or after a NAK of the frame).
    TimeoutStx,
    /// 0x83: a header or frame was started but did not end in time.
    TimeoutTermc,
    /// 0x84: no EOT after the ACK of the last block.
    TimeoutEot,
    /// 0x85: ENQ was expected, another byte was received.
    BadEnq,
    /// 0x86: EOT was expected, another byte was received.
    BadEot,
    /// 0x07: one block had to be refused more than MAX_RETRIES times.
    LimitExceeded,
    /// 0x88 (added): the port itself failed while receiving, an I/O error.
    Port,
}

impl ReceiveError {
    /// The manual's return value: the code in the low byte, the NAK code in the high byte for
    /// ERR_ABORT.
    pub const fn code(self) -> u16 {
        match self {
            ReceiveError::Abort(nak) => 0x80 | ((nak as u16) << 8),
            ReceiveError::TimeoutSoh => 0x81,
            ReceiveError::TimeoutStx => 0x82,
            ReceiveError::TimeoutTermc => 0x83,
            ReceiveError::TimeoutEot => 0x84,
            ReceiveError::BadEnq => 0x85,
            ReceiveError::BadEot => 0x86,
            ReceiveError::LimitExceeded => 0x07,
            ReceiveError::Port => 0x88,
        }
    }

    /// The manual's name.
    pub const fn name(self) -> &'static str {
        match self {
            ReceiveError::Abort(_) => "ERR_ABORT",
            ReceiveError::TimeoutSoh => "ERR_TIMEOUT_SOH",
            ReceiveError::TimeoutStx => "ERR_TIMEOUT_STX",
            ReceiveError::TimeoutTermc => "ERR_TIMEOUT_TERMC",
            ReceiveError::TimeoutEot => "ERR_TIMEOUT_EOT",
            ReceiveError::BadEnq => "ERR_BAD_ENQ",
            ReceiveError::BadEot => "ERR_BAD_EOT",
            ReceiveError::LimitExceeded => "ERR_LIMIT_EXCEEDED",
            ReceiveError::Port => "ERR_PORT",
        }
    }
}

/// A failure of either layer-2 service; what GetLastCommErr reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LinkError {
    /// SendData failed.
    Send(SendError),
    /// ReceiveData failed.
    Receive(ReceiveError),
}

impl LinkError {
    /// The manual's return value of the failed service.
    pub const fn code(self) -> u16 {
        match self {
            LinkError::Send(e) => e.code(),
            LinkError::Receive(e) => e.code(),
        }
    }

    /// The manual's name of the failure.
    pub const fn name(self) -> &'static str {
        match self {
            LinkError::Send(e) => e.name(),
            LinkError::Receive(e) => e.name(),
        }
    }

    /// The NAK code carried in the high byte, if any.
    pub const fn nak(self) -> Option<NakCode> {
        match self {
            LinkError::Send(SendError::Nak(n)) | LinkError::Receive(ReceiveError::Abort(n)) => {
                Some(n)
            }
            _ => None,
        }
    }
}

impl fmt::Display for SendError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(&LinkError::Send(*self), f)
    }
}

impl fmt::Display for ReceiveError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(&LinkError::Receive(*self), f)
    }
}

impl fmt::Display for LinkError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} (0x{:04X})", self.name(), self.code())?;
        if let Some(nak) = self.nak() {
            write!(f, ", NAK code {nak}")?;
        }
        Ok(())
    }
}

impl std::error::Error for SendError {}
impl std::error::Error for ReceiveError {}
impl std::error::Error for LinkError {}

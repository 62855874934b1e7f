//! Layer 3, transactions ("Transaktions-Schicht"): a command from the PC and its reply from
//! the controller, as one unit.
//!
//! Transactions are master/slave: only the PC starts one ([`Initiator`], the manual's TransSR),
//! one at a time; the controller answers ([`Responder`], TransRS). Failures are not handled
//! here but reported as [`Failure`]s that wait for a decision; the drivers ask the
//! application's error handlers (ErrOnSend, ErrOnReceive, ErrAppTimeOut) for it.
//!
//! # The PCI
//!
//! The manual carries a 16-bit PCI in every header and reserves it for layer 3. We use it as:
//!
//! | bits  | meaning |
//! |-------|---------|
//! | 0..7  | transaction number, counted by the PC; a reply carries its request's number |
//! | 8     | REPEAT: the PC sends this request again, with the number it had |
//! | 9..15 | layer 2's: with the CRC-16 block check they carry the message check on the line and never reach layer 3; with the LRC reserved, sent as 0, ignored |
//!
//! A reply whose number is not that of the pending request is stale (from a transaction the
//! PC gave up on) and is dropped.
//!
//! # Exactly once
//!
//! The controller remembers the number of the last request it executed and its reply. A
//! request marked REPEAT with that number is answered from this memory and not executed
//! again: so the PC may send a request again whenever it does not know whether the first one
//! arrived (its reply was lost, or its EOT), and the command runs exactly once. A request
//! not marked REPEAT is always executed, whatever its number (a PC that restarted counts from
//! 1 again). A request marked REPEAT that reaches a controller remembering no request at all
//! (it started after the PC first sent it) is not executed: whether its earlier run executed
//! it cannot be told ([`Responder::request_is_unknown_repeat`]); the server answers
//! TROL_ERR_ROBOT_UNSURE.
//!
//! # Delivery
//!
//! Layer 2 delivers a message only when EOT arrives, and EOT is the last thing SendData
//! does. So when SendData fails, the message was not delivered, and sending it again cannot
//! execute a command twice. When SendData succeeds the EOT may still be lost; the controller
//! then has not executed the command, the PC sees no reply (TRANS_TIMEOUT), and GetStatus
//! tells which of the two happened.

mod initiator;
mod responder;

pub use initiator::{Initiator, InitiatorEvent};
pub use responder::{ManualLayer3, NUMBER_WINDOW, Responder, ResponderEvent, pci_fits};

use crate::link::{ReceiveError, SendError};
use std::time::Duration;

/// The manual's return values of TransSR / TransRS.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum TransCode {
    /// 0x00: the transaction succeeded.
    Success = 0x00,
    /// 0x01: SendData failed and ErrOnSend could not recover.
    ErrSend = 0x01,
    /// 0x02: ReceiveData failed and ErrOnReceive could not recover.
    ErrReceive = 0x02,
    /// 0x03: no reply within the layer-3 timeout and ErrAppTimeOut could not recover.
    Timeout = 0x03,
}

impl TransCode {
    /// The manual's name.
    pub const fn name(self) -> &'static str {
        match self {
            TransCode::Success => "TRANS_SUCCESS",
            TransCode::ErrSend => "TRANS_ERR_SEND",
            TransCode::ErrReceive => "TRANS_ERR_RECEIVE",
            TransCode::Timeout => "TRANS_TIMEOUT",
        }
    }
}

impl std::fmt::Display for TransCode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} (0x{:02X})", self.name(), *self as u8)
    }
}

/// Default time the PC waits for a reply: 15 s (manual, TRANS_TIMEOUT), set in tenths of a
/// second with SetL3_TO_Intervall.
pub const DEFAULT_REPLY_TIMEOUT_TENTHS: u16 = 150;

/// The reply timeout for a SetL3_TO_Intervall value in tenths of a second.
pub fn reply_timeout_from_tenths(tenths: u16) -> Duration {
    Duration::from_millis(u64::from(tenths) * 100)
}

/// The PCI's REPEAT bit.
pub const PCI_REPEAT: u16 = 0x0100;

/// Build the PCI of transaction `number`.
pub const fn pci(number: u8) -> u16 {
    number as u16
}

/// Whether a PCI marks a repeated request.
pub const fn pci_is_repeat(pci: u16) -> bool {
    pci & PCI_REPEAT != 0
}

/// The transaction number of a PCI.
pub const fn pci_number(pci: u16) -> u8 {
    (pci & 0xFF) as u8
}

/// A failure that waits for the application's decision.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Failure {
    /// SendData failed (ErrOnSend decides).
    Send(SendError),
    /// ReceiveData failed (ErrOnReceive decides).
    Receive(ReceiveError),
    /// No reply came in time (ErrAppTimeOut decides); `waited` is the time since the request
    /// was sent.
    Timeout {
        /// Time since the request went out.
        waited: Duration,
    },
}

/// What an error handler decided.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Decision {
    /// RECOVERY_FAIL: end the transaction with its error code.
    GiveUp,
    /// RECOVERY_SUCCESS: send the request (or reply) again after a send failure (it was not
    /// delivered), or wait for the message again after a receive failure.
    Retry,
    /// RECOVERY_SUCCESS after a timeout: wait this much longer for the reply.
    WaitMore(Duration),
}

//! Runs the sans-IO protocol core of `trol-proto` over a layer-1 [`Port`] with a real clock.
//!
//! - [`Driver`]: the loop that moves bytes between a port and a state machine, runs timers,
//!   applies the inter-character delay (the manual's SetDelay) and flushes input when the
//!   core asks for it.
//! - [`send_data`] / [`receive_data`]: the layer-2 services as blocking calls.
//! - [`Transactor`]: TransSR for the PC, with the application's error handlers.
//! - [`Server`]: TransRS for the controller.
//!
//! Both ends use the same driver; only the state machine differs.

#![forbid(unsafe_code)]
#![warn(missing_docs, missing_debug_implementations)]

mod channel;
mod driver;
mod handlers;
mod keepalive;
mod server;
mod transactor;

pub use channel::{Channel, LineChannel, NOTHING_ARRIVED, PORT_FAILED};
pub use driver::{Clock, Direction, Driver, TraceFn};
pub use handlers::{
    AppTimeoutContext, DefaultHandlers, ErrorHandlers, ExtraWait, FailureContext, Recovery,
    TimeoutAction, TimeoutPolicy, prompt_policy, timeout_policy,
};
pub use keepalive::{KEEPALIVE_INTERVAL, Keepalive};
pub use server::{Server, ServerEvent};
pub use transactor::{DEFAULT_REPEATS, TransError, Transactor};
pub use trol_proto::Machine;

use std::time::Duration;

use trol_port::Port;
use trol_proto::link::{Link, Outcome, ReceiveError, SendError};

/// A blocking layer-2 call failed.
#[derive(Debug)]
pub enum LinkCallError<E> {
    /// The protocol failed with the manual's code.
    Protocol(E),
    /// Nothing arrived before the caller's deadline (ReceiveData only: waiting for ENQ has no
    /// layer-2 timeout).
    Idle,
    /// The port failed.
    Io(std::io::Error),
}

impl<E: std::fmt::Display> std::fmt::Display for LinkCallError<E> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LinkCallError::Protocol(e) => write!(f, "{e}"),
            LinkCallError::Idle => f.write_str("no message arrived in time"),
            LinkCallError::Io(e) => write!(f, "port error: {e}"),
        }
    }
}

impl<E: std::fmt::Debug + std::fmt::Display> std::error::Error for LinkCallError<E> {}

/// SendData: send `message` with `pci` over `link`, blocking until done. A failure leaves the
/// link resetting; the next call waits the reset out.
pub fn send_data<P: Port>(
    driver: &mut Driver<P>,
    link: &mut Link,
    message: &[u8],
    pci: u16,
) -> Result<(), LinkCallError<SendError>> {
    let now = driver.clock().now();
    if let Err(e) = link.send(message, pci, now) {
        return Err(LinkCallError::Io(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            e.to_string(),
        )));
    }
    let outcome = driver
        .next(link, None, Link::poll_outcome)
        .map_err(LinkCallError::Io)?;
    match outcome {
        Some(Outcome::Sent) => Ok(()),
        Some(Outcome::Failed(trol_proto::link::LinkError::Send(e))) => {
            Err(LinkCallError::Protocol(e))
        }
        _ => Err(LinkCallError::Idle),
    }
}

/// ReceiveData: wait up to `wait` for a message to start, then receive it. Returns
/// `(PCI, bytes)`.
pub fn receive_data<P: Port>(
    driver: &mut Driver<P>,
    link: &mut Link,
    wait: Duration,
) -> Result<(u16, Vec<u8>), LinkCallError<ReceiveError>> {
    let now = driver.clock().now();
    if link.receive(now).is_err() {
        return Err(LinkCallError::Io(std::io::Error::other("link busy")));
    }
    let give_up = now + wait;
    let mut outcome = driver
        .next(link, Some(give_up), Link::poll_outcome)
        .map_err(LinkCallError::Io)?;
    if outcome.is_none() && !link.cancel_receive() {
        // The transfer started just before the deadline: let it end.
        outcome = driver
            .next(link, None, Link::poll_outcome)
            .map_err(LinkCallError::Io)?;
    }
    match outcome {
        Some(Outcome::Received) => link.take_received().ok_or(LinkCallError::Idle),
        Some(Outcome::Failed(trol_proto::link::LinkError::Receive(e))) => {
            Err(LinkCallError::Protocol(e))
        }
        _ => Err(LinkCallError::Idle),
    }
}

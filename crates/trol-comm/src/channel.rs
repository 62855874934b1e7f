//! The line itself, for error handlers that mend a failure by hand (manual,
//! "Callback-Routinen"): ErrOnReceive may receive the message itself with ReceiveData and
//! hand it to layer 3; ErrAppTimeOut may look for a waiting ENQ with BufferEmpty without
//! taking it. A [`Channel`] offers the layer-1 and layer-2 services over the port a
//! transaction runs on.

use std::time::Duration;

use trol_port::Port;
use trol_proto::link::{Link, LinkConfig};

use crate::driver::Driver;
use crate::{LinkCallError, receive_data, send_data};

/// What SendData / ReceiveData return besides the layer-2 codes when the port itself failed.
pub const PORT_FAILED: u16 = 0x00FF;
/// What ReceiveData returns when no message started within its wait (ERR_TIMEOUT_SOH: no
/// layer-2 code names a missing ENQ).
pub const NOTHING_ARRIVED: u16 = 0x0081;

/// Layer 1 and layer 2 of one line.
pub trait Channel {
    /// SendData: 0, or the layer-2 code (the NAK code in the high byte for ERR_NAK).
    fn send_data(&mut self, message: &[u8], pci: u16) -> u16;
    /// ReceiveData: the PCI and the message, or the layer-2 code.
    fn receive_data(&mut self) -> Result<(u16, Vec<u8>), u16>;
    /// BufferEmpty: whether no byte waits in the input.
    fn buffer_empty(&mut self) -> bool;
    /// FlushBuffer: drop the waiting input.
    fn flush_buffer(&mut self);
}

/// A [`Channel`] over a driver's port, with a link of its own.
pub struct LineChannel<'a, P> {
    driver: &'a mut Driver<P>,
    link: Link,
    wait: Duration,
}

impl<'a, P: Port> LineChannel<'a, P> {
    /// The services over `driver`'s port; ReceiveData waits up to `wait` for a message to
    /// start.
    pub fn new(driver: &'a mut Driver<P>, cfg: LinkConfig, wait: Duration) -> Self {
        let mut link = Link::new(cfg);
        // An application's handler that receives the reply itself meets the controller's
        // "still working" as TransSR does (docs/protocol.md, "Keep-alive").
        link.set_keepalive(true);
        LineChannel { driver, link, wait }
    }
}

fn code<E>(e: LinkCallError<E>, idle: u16, of: impl Fn(E) -> u16) -> u16 {
    match e {
        LinkCallError::Protocol(e) => of(e),
        LinkCallError::Idle => idle,
        LinkCallError::Io(_) => PORT_FAILED,
    }
}

impl<P: Port> Channel for LineChannel<'_, P> {
    fn send_data(&mut self, message: &[u8], pci: u16) -> u16 {
        match send_data(self.driver, &mut self.link, message, pci) {
            Ok(()) => 0,
            Err(e) => code(e, PORT_FAILED, |e| e.code()),
        }
    }

    fn receive_data(&mut self) -> Result<(u16, Vec<u8>), u16> {
        receive_data(self.driver, &mut self.link, self.wait)
            .map_err(|e| code(e, NOTHING_ARRIVED, |e| e.code()))
    }

    fn buffer_empty(&mut self) -> bool {
        self.driver
            .port_mut()
            .available()
            .map(|n| n == 0)
            .unwrap_or(true)
    }

    fn flush_buffer(&mut self) {
        let _ = self.driver.port_mut().flush_input();
    }
}

impl<P> std::fmt::Debug for LineChannel<'_, P> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LineChannel")
            .field("wait", &self.wait)
            .finish_non_exhaustive()
    }
}

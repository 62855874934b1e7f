//! TransSR over a port: the PC's side of layer 3, with the application's error handlers.

use std::io;
use std::time::Duration;

use trol_port::Port;
use trol_proto::link::{LinkConfig, LinkError, NakCode, ReceiveError, SendError};
use trol_proto::transaction::{Decision, Failure, Initiator, InitiatorEvent, TransCode};

use crate::channel::LineChannel;
use crate::driver::Driver;
use crate::handlers::{
    AppTimeoutContext, DefaultHandlers, ErrorHandlers, FailureContext, Recovery, TimeoutAction,
};

/// Why TransSR returned no reply.
#[derive(Debug)]
pub enum TransError {
    /// The transaction failed with the manual's layer-3 code; `last_comm` is the layer-2
    /// code of the last failure (GetLastCommErr), if any.
    Failed {
        /// TRANS_ERR_SEND, TRANS_ERR_RECEIVE or TRANS_TIMEOUT.
        code: TransCode,
        /// The last layer-2 failure.
        last_comm: Option<LinkError>,
    },
    /// The request could not be started (too long).
    Request(String),
    /// The port failed.
    Io(io::Error),
}

impl std::fmt::Display for TransError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TransError::Failed { code, last_comm } => {
                write!(f, "transaction failed: {code}")?;
                if let Some(e) = last_comm {
                    write!(f, "; last link error {e}")?;
                }
                Ok(())
            }
            TransError::Request(why) => write!(f, "bad request: {why}"),
            TransError::Io(e) => write!(f, "port error: {e}"),
        }
    }
}

impl std::error::Error for TransError {}

impl TransError {
    /// The manual's layer-3 code of this failure (port errors count as the failed direction
    /// being unknown: TRANS_ERR_SEND).
    pub fn code(&self) -> TransCode {
        match self {
            TransError::Failed { code, .. } => *code,
            TransError::Request(_) | TransError::Io(_) => TransCode::ErrSend,
        }
    }
}

/// How often a transaction whose reply was lost is sent again (exactly once), by default.
pub const DEFAULT_REPEATS: u8 = 2;

/// The PC's end of layer 3: sends commands and returns their replies.
pub struct Transactor<P> {
    driver: Driver<P>,
    initiator: Initiator,
    handlers: Box<dyn ErrorHandlers>,
    repeats: u8,
}

impl<P: Port> Transactor<P> {
    /// A transactor over `port` with the default handlers.
    pub fn new(port: P, cfg: LinkConfig) -> Self {
        Transactor {
            driver: Driver::new(port),
            initiator: Initiator::new(cfg),
            handlers: Box::new(DefaultHandlers::default()),
            repeats: DEFAULT_REPEATS,
        }
    }

    /// Exactly once: how often a transaction that ended without its reply (a timeout, or a
    /// failed receive) is sent again with its number and the REPEAT bit, so that a controller
    /// that executed it answers from memory and one that did not executes it. 0 is the
    /// manual's behaviour: the call fails, and the application asks GetStatus.
    pub fn set_repeats(&mut self, repeats: u8) {
        self.repeats = repeats;
    }

    /// How often a failed request is sent again ([`Transactor::set_repeats`]).
    pub fn repeats(&self) -> u8 {
        self.repeats
    }

    /// The number of the current (or last) transaction (the PCI's low byte).
    pub fn transaction_number(&self) -> u8 {
        self.initiator.number()
    }

    /// Replace the error handlers.
    pub fn set_handlers(&mut self, handlers: Box<dyn ErrorHandlers>) {
        self.handlers = handlers;
    }

    /// The driver (port, delay, trace hook).
    pub fn driver_mut(&mut self) -> &mut Driver<P> {
        &mut self.driver
    }

    /// The driver.
    pub fn driver(&self) -> &Driver<P> {
        &self.driver
    }

    /// Give the port back (a relay that activated the controller goes on with it).
    pub fn into_port(self) -> P {
        self.driver.into_port()
    }

    /// Go on over a new port (the old one failed, and was opened again): the error
    /// handlers, settings and transaction numbering stay; a transaction under way is dropped.
    pub fn replace_port(&mut self, port: P) {
        let delay = self.driver.delay();
        self.initiator.abort();
        self.driver = Driver::new(port);
        self.driver.set_delay(delay);
    }

    /// The state machine (link settings, counters).
    pub fn initiator(&self) -> &Initiator {
        &self.initiator
    }

    /// The state machine, mutably.
    pub fn initiator_mut(&mut self) -> &mut Initiator {
        &mut self.initiator
    }

    /// SetL3_TO_Intervall, in tenths of a second.
    pub fn set_reply_timeout_tenths(&mut self, tenths: u16) {
        self.initiator
            .set_reply_timeout(trol_proto::transaction::reply_timeout_from_tenths(tenths));
    }

    /// The reply timeout.
    pub fn reply_timeout(&self) -> Duration {
        self.initiator.reply_timeout()
    }

    /// GetLastCommErr: the last layer-2 failure.
    pub fn last_comm_error(&self) -> Option<LinkError> {
        self.initiator.last_comm_error()
    }

    /// TransSR: send `request` and return the controller's reply.
    ///
    /// If the port fails (an I/O error), the failure is recorded for GetLastCommErr as
    /// ERR_PORT of the side it hit (SendData's while the request goes out, ReceiveData's
    /// after), the manual's handler of that side is told (ErrOnSend or ErrOnReceive; a dead
    /// port cannot be mended, so the call fails whatever it answers), the transaction is
    /// abandoned, the port's input is flushed, and the next call starts afresh.
    pub fn trans_sr(&mut self, request: &[u8]) -> Result<Vec<u8>, TransError> {
        let result = self.run_transaction(request);
        if let Err(TransError::Io(_)) = result {
            let error = if self.initiator.is_sending() {
                LinkError::Send(SendError::Port)
            } else {
                LinkError::Receive(trol_proto::link::ReceiveError::Port)
            };
            self.initiator.link_mut().note_failure(error);
            self.tell_port_failure(error);
            self.initiator.abort();
            let _ = self.driver.port_mut().flush_input();
        }
        result
    }

    /// Tell the handler of the side the port failed on.
    fn tell_port_failure(&mut self, error: LinkError) {
        let cfg = *self.initiator.link().config();
        let wait = self.initiator.reply_timeout();
        let pci = self.initiator.current_pci();
        let request = self.initiator.request().to_vec();
        let mut line = LineChannel::new(&mut self.driver, cfg, wait);
        let ctx = FailureContext {
            error,
            message: if matches!(error, LinkError::Send(_)) {
                &request
            } else {
                &[]
            },
            pci,
            attempts: 0,
        };
        let _ = match error {
            LinkError::Send(_) => self.handlers.err_on_send_on(&ctx, &mut line),
            LinkError::Receive(_) => self.handlers.err_on_receive_on(&ctx, &mut line),
        };
    }

    fn run_transaction(&mut self, request: &[u8]) -> Result<Vec<u8>, TransError> {
        let now = self.driver.clock().now();
        self.initiator
            .start(request, now)
            .map_err(|e| TransError::Request(e.to_string()))?;
        let mut attempts = 0u32;
        let mut repeated = 0u8;
        // What the peer had sent before the latest attempt: a peer that sends not one byte
        // during an attempt is silent, and another repeat cannot help.
        let mut heard_before = self.initiator.link().stats().bytes_in;
        // The previous attempt ended without a byte of reply (TRANS_TIMEOUT): the controller
        // took the request and went quiet.
        let mut went_quiet = false;
        // The application's handler said RECOVERY_FAIL: its word is final, no repeat.
        let mut aborted = false;
        // The failure that started the repeats: what the caller hears if they fail too.
        let mut first_failure = None;
        // The request was sent again after the controller refused its frames (NAK ERR_FID).
        let mut resent_after_fid = false;
        loop {
            let event = self
                .driver
                .next(&mut self.initiator, None, Initiator::poll_event)
                .map_err(TransError::Io)?;
            match event {
                Some(InitiatorEvent::Reply) => {
                    return self.initiator.take_reply().ok_or(TransError::Failed {
                        code: TransCode::ErrReceive,
                        last_comm: self.last_comm_error(),
                    });
                }
                Some(InitiatorEvent::Failed(code)) => {
                    // The request or the reply was lost: send the request again, marked as
                    // a repeat. Safe either way: a controller that executed it answers the
                    // repeat from memory, one that never got it executes it now. A request
                    // the controller refused outright (a fatal NAK) is not sent again.
                    let refused = matches!(
                        self.last_comm_error(),
                        Some(LinkError::Send(SendError::Nak(_)))
                    );
                    // ENQ unanswered and not one byte from the peer since this attempt began,
                    // on the first attempt or after the controller went quiet with the
                    // request in hand: the peer is silent (dead, or its cable cut with the far
                    // end still open), this request never left (nothing can run twice), and a
                    // repeat would only add the manual's reset and another ENQ timeout, 3 s
                    // each. (A silent attempt after a damaged reply is noise: repeat.)
                    let silent = matches!(
                        self.last_comm_error(),
                        Some(LinkError::Send(SendError::TimeoutEnq))
                    ) && self.initiator.link().stats().bytes_in == heard_before
                        && (repeated == 0 || went_quiet);
                    // The controller took a block of the request and went silent before
                    // acknowledging the next (a process killed or frozen, a line cut
                    // mid-request): the request never reached its EOT, so it did not run,
                    // and a repeat would only add the manual's reset and an ENQ timeout.
                    // (Noise damages an ACK; it does not swallow it: that is WrongCchar.)
                    let stopped = matches!(
                        self.last_comm_error(),
                        Some(LinkError::Send(SendError::TimeoutEtx))
                    );
                    if !refused && !aborted && !silent && !stopped && repeated < self.repeats {
                        first_failure.get_or_insert(code);
                        repeated += 1;
                        heard_before = self.initiator.link().stats().bytes_in;
                        // The controller went quiet with the request in hand: no reply in
                        // time, or its reply broke off (a timeout, not damage).
                        went_quiet = code == TransCode::Timeout
                            || matches!(
                                self.last_comm_error(),
                                Some(LinkError::Receive(
                                    ReceiveError::TimeoutSoh
                                        | ReceiveError::TimeoutStx
                                        | ReceiveError::TimeoutTermc
                                        | ReceiveError::TimeoutEot
                                ))
                            );
                        let now = self.driver.clock().now();
                        if self.initiator.repeat(now) {
                            continue;
                        }
                    }
                    return Err(TransError::Failed {
                        code: first_failure.unwrap_or(code),
                        last_comm: self.last_comm_error(),
                    });
                }
                Some(InitiatorEvent::NeedDecision(failure)) => {
                    let decision = match self.ask(failure, attempts)? {
                        Asked::Decision(d) => d,
                        Asked::Received(message) => {
                            // The handler received the reply itself.
                            self.initiator.abort();
                            return Ok(message);
                        }
                        Asked::Abort => {
                            aborted = true;
                            Decision::GiveUp
                        }
                    };
                    // The controller aborted the request's transfer with NAK ERR_FID (a
                    // frame it did not expect, or, with the LRC, a request that fits no
                    // command it knows: docs/protocol.md "Checked as the bytes allow"). The
                    // request never reached its EOT, so it did not run: send it once more,
                    // the same bytes under the same PCI, which such a controller takes the
                    // second time. Not after the application's handler gave up for good.
                    let decision = if decision == Decision::GiveUp
                        && !aborted
                        && !resent_after_fid
                        && failure == Failure::Send(SendError::Nak(NakCode::Fid))
                    {
                        resent_after_fid = true;
                        Decision::Retry
                    } else {
                        decision
                    };
                    attempts += 1;
                    let now = self.driver.clock().now();
                    self.initiator.decide(decision, now);
                }
                None => {}
            }
        }
    }

    fn ask(&mut self, failure: Failure, attempts: u32) -> Result<Asked, TransError> {
        let cfg = *self.initiator.link().config();
        let wait = self.initiator.reply_timeout();
        let mut line = LineChannel::new(&mut self.driver, cfg, wait);
        let decision = match failure {
            Failure::Send(e) => {
                let ctx = FailureContext {
                    error: LinkError::Send(e),
                    message: self.initiator.request(),
                    pci: self.initiator.current_pci(),
                    attempts,
                };
                match self.handlers.err_on_send_on(&ctx, &mut line) {
                    Recovery::Abort => return Ok(Asked::Abort),
                    other => recovery(other),
                }
            }
            Failure::Receive(e) => {
                let ctx = FailureContext {
                    error: LinkError::Receive(e),
                    message: &[],
                    pci: self.initiator.current_pci(),
                    attempts,
                };
                match self.handlers.err_on_receive_on(&ctx, &mut line) {
                    Recovery::Received { message, .. } => return Ok(Asked::Received(message)),
                    Recovery::Abort => return Ok(Asked::Abort),
                    other => recovery(other),
                }
            }
            Failure::Timeout { waited } => {
                let input_pending = !crate::Channel::buffer_empty(&mut line);
                let ctx = AppTimeoutContext {
                    request: self.initiator.request(),
                    waited,
                    reply_timeout: self.initiator.reply_timeout(),
                    input_pending,
                };
                match self.handlers.err_app_timeout_on(&ctx, &mut line) {
                    TimeoutAction::Fail => Decision::GiveUp,
                    TimeoutAction::WaitMore(d) => Decision::WaitMore(d),
                }
            }
        };
        Ok(Asked::Decision(decision))
    }

    /// ErrAppTimeOut for a wait the host keeps by polling instead of by one long request
    /// (Finish(FINISH_WAIT)): `request` is the request the manual would have sent and
    /// `waited` how long the wait has lasted. The handlers decide as for a late reply: wait
    /// more, or give up.
    pub fn app_timeout(&mut self, request: &[u8], waited: Duration) -> TimeoutAction {
        let cfg = *self.initiator.link().config();
        let reply_timeout = self.initiator.reply_timeout();
        let mut line = LineChannel::new(&mut self.driver, cfg, reply_timeout);
        let input_pending = !crate::Channel::buffer_empty(&mut line);
        let ctx = AppTimeoutContext {
            request,
            waited,
            reply_timeout,
            input_pending,
        };
        self.handlers.err_app_timeout_on(&ctx, &mut line)
    }

    /// Layer 1 and layer 2 of this transactor's line, outside a transaction (the manual's
    /// SendData, ReceiveData, BufferEmpty and FlushBuffer called by the application).
    pub fn channel(&mut self) -> LineChannel<'_, P> {
        let cfg = *self.initiator.link().config();
        let wait = self.initiator.reply_timeout();
        LineChannel::new(&mut self.driver, cfg, wait)
    }
}

/// What asking a handler gave.
enum Asked {
    Decision(Decision),
    Received(Vec<u8>),
    /// The application's handler gave up for good ([`Recovery::Abort`]).
    Abort,
}

fn recovery(r: Recovery) -> Decision {
    match r {
        Recovery::Success | Recovery::Received { .. } => Decision::Retry,
        Recovery::Fail | Recovery::Abort => Decision::GiveUp,
    }
}

impl<P> std::fmt::Debug for Transactor<P> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Transactor")
            .field("driver", &self.driver)
            .field("initiator", &self.initiator)
            .field("repeats", &self.repeats)
            .finish_non_exhaustive()
    }
}

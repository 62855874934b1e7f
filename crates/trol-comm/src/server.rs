//! TransRS over a port: the controller's side of layer 3.

use std::io;
use std::time::Duration;

use trol_port::Port;
use trol_proto::link::{LinkConfig, LinkError};
use trol_proto::transaction::{Decision, Failure, Responder, ResponderEvent};

use crate::driver::Driver;
use crate::handlers::{DefaultHandlers, ErrorHandlers, FailureContext, Recovery};

/// How one call of [`Server::serve`] ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ServerEvent {
    /// A request was executed and its reply sent.
    Executed,
    /// A request was executed but its reply could not be sent (TRANS_ERR_SEND).
    ReplyFailed(LinkError),
    /// A request could not be received (TRANS_ERR_RECEIVE); nothing was executed.
    ReceiveFailed(LinkError),
    /// Nothing arrived in the time given.
    Idle,
}

/// The controller's end of layer 3: receives requests, has them executed, sends replies.
pub struct Server<P> {
    driver: Driver<P>,
    responder: Responder,
    handlers: Box<dyn ErrorHandlers>,
}

impl<P: Port> Server<P> {
    /// A server over `port` with the default handlers, listening.
    pub fn new(port: P, cfg: LinkConfig) -> Self {
        let driver = Driver::new(port);
        let mut responder = Responder::new(cfg);
        responder.listen(driver.clock().now());
        Server {
            driver,
            responder,
            handlers: Box::new(DefaultHandlers::default()),
        }
    }

    /// Replace the error handlers (ErrOnSend and ErrOnReceive are asked on this side).
    pub fn set_handlers(&mut self, handlers: Box<dyn ErrorHandlers>) {
        self.handlers = handlers;
    }

    /// The driver.
    pub fn driver_mut(&mut self) -> &mut Driver<P> {
        &mut self.driver
    }

    /// The state machine.
    pub fn responder(&self) -> &Responder {
        &self.responder
    }

    /// The state machine, mutably (link settings).
    pub fn responder_mut(&mut self) -> &mut Responder {
        &mut self.responder
    }

    /// Serve until one transaction has ended, or until `idle` has passed with no request
    /// under way. `execute` gets the request bytes and returns the reply bytes (the manual's
    /// MsgReceived).
    pub fn serve(
        &mut self,
        idle: Duration,
        execute: &mut dyn FnMut(&[u8]) -> Vec<u8>,
    ) -> io::Result<ServerEvent> {
        let give_up = self.driver.clock().now() + idle;
        let mut attempts = 0u32;
        let mut reply_len = 0usize;
        loop {
            let mut event = None;
            let until = if self.responder.in_transaction() {
                None
            } else {
                Some(give_up)
            };
            self.driver.run(&mut self.responder, until, |m| {
                event = m.poll_event();
                event.is_some() || (until.is_some() && m.in_transaction())
            })?;
            let now = self.driver.clock().now();
            match event {
                None if self.responder.in_transaction() => continue,
                None => return Ok(ServerEvent::Idle),
                Some(ResponderEvent::Request) => {
                    let reply = execute(self.responder.request());
                    reply_len = reply.len();
                    // Executing may take long (Finish waits for the arm): time the reply
                    // from when it is ready, not from when the request arrived.
                    let ready = self.driver.clock().now();
                    self.responder.respond(&reply, ready);
                }
                Some(ResponderEvent::Done) => return Ok(ServerEvent::Executed),
                Some(ResponderEvent::NeedDecision(failure)) => {
                    let (error, recovery) = match failure {
                        Failure::Send(e) => {
                            let error = LinkError::Send(e);
                            let ctx = FailureContext {
                                error,
                                message: &[],
                                pci: self.responder.request_pci(),
                                attempts,
                            };
                            (error, self.handlers.err_on_send(&ctx))
                        }
                        Failure::Receive(e) => {
                            let error = LinkError::Receive(e);
                            let ctx = FailureContext {
                                error,
                                message: &[],
                                pci: 0,
                                attempts,
                            };
                            (error, self.handlers.err_on_receive(&ctx))
                        }
                        Failure::Timeout { .. } => continue,
                    };
                    attempts += 1;
                    let decision = match recovery {
                        Recovery::Success => Decision::Retry,
                        Recovery::Fail => Decision::GiveUp,
                    };
                    self.responder.decide(decision, now);
                    if decision == Decision::GiveUp {
                        // The responder reports Failed next; report the cause instead.
                        let _ = self.responder.poll_event();
                        return Ok(match failure {
                            Failure::Send(_) => ServerEvent::ReplyFailed(error),
                            _ => ServerEvent::ReceiveFailed(error),
                        });
                    }
                }
                Some(ResponderEvent::Failed(code)) => {
                    // Only a reply that layer 2 refused to start ends up here: the request
                    // was executed, the reply could not go out, and the server listens again.
                    let _ = code;
                    return Err(io::Error::new(
                        io::ErrorKind::InvalidInput,
                        format!(
                            "the reply of {reply_len} bytes is longer than the {} bytes layer 2 can carry; \
                             it was not sent",
                            trol_proto::link::frame::MAX_MESSAGE
                        ),
                    ));
                }
            }
        }
    }
}

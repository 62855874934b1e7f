//! TransRS over a port: the controller's side of layer 3.

use std::io;
use std::time::Duration;

use trol_port::Port;
use trol_proto::application::Reply;
use trol_proto::application::code::TROL_ERR_ROBOT_UNSURE;
use trol_proto::link::{LinkConfig, LinkError};
use trol_proto::transaction::{Decision, Failure, Responder, ResponderEvent};

use crate::driver::Driver;
use crate::handlers::{DefaultHandlers, ErrorHandlers, FailureContext, Recovery};
use crate::keepalive::Keepalive;

/// What executes a request for [`Server::serve_deferrable`]: its bytes and PCI in, its
/// reply out (or `None`: later, with [`Server::respond`]).
pub type Execute<'a> = dyn FnMut(&[u8], u16) -> Option<Vec<u8>> + 'a;

/// How one call of [`Server::serve`] ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ServerEvent {
    /// A request was executed and its reply sent.
    Executed,
    /// A repeated request (the PC had lost the reply) was answered from memory, not executed
    /// again.
    Repeated,
    /// A request was executed but its reply could not be sent (TRANS_ERR_SEND).
    ReplyFailed(LinkError),
    /// A repeated request was answered from memory (nothing ran), but that reply could not be
    /// sent either (TRANS_ERR_SEND).
    RepeatReplyFailed(LinkError),
    /// A request was executed but its reply is longer than layer 2 can carry
    /// (`trol_proto::link::frame::MAX_MESSAGE`); it was not sent.
    ReplyTooLong {
        /// The reply's length.
        len: usize,
    },
    /// A request could not be received (TRANS_ERR_RECEIVE); nothing was executed.
    ReceiveFailed(LinkError),
    /// A request marked REPEAT arrived while the controller remembered no request: it
    /// (re)started after the PC first sent it, and whether its earlier run executed it cannot
    /// be told. It was not run; the reply is TROL_ERR_ROBOT_UNSURE (docs/reliability.md).
    UnknownRepeat,
    /// With the manual's LRC, a CAT1/CAT2 request without the REPEAT bit arrived under the
    /// number of the request last executed: that request again, its REPEAT bit lost to noise.
    /// It was not run; the reply is TROL_ERR_ROBOT_UNSURE (docs/reliability.md).
    SuspectDuplicate,
    /// Nothing arrived in the time given.
    Idle,
    /// A request arrived and `execute` deferred its reply: send it with [`Server::respond`],
    /// then call [`Server::serve`] again to finish the transaction.
    Pending,
}

/// The controller's end of layer 3: receives requests, has them executed, sends replies.
pub struct Server<P> {
    driver: Driver<P>,
    responder: Responder,
    handlers: Box<dyn ErrorHandlers>,
    keepalive: Option<Keepalive>,
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
            keepalive: None,
        }
    }

    /// Say "still working" (SYN every `interval`) while a request executes, to a host that
    /// takes it ([`Responder::host_takes_keepalive`]), where the port offers a second way
    /// onto the line ([`Port::beacon`]); `None` turns it off. docs/protocol.md, "Keep-alive".
    pub fn set_keepalive(&mut self, interval: Option<Duration>) -> io::Result<()> {
        self.keepalive = match interval {
            Some(i) if !i.is_zero() => Some(Keepalive::new(i)?),
            _ => None,
        };
        Ok(())
    }

    /// The keep-alive interval this host gets while its requests execute, if it gets one
    /// (what TROLGetReplyTime tells it).
    pub fn keepalive_for_host(&self) -> Option<Duration> {
        let k = self.keepalive.as_ref()?;
        (self.driver.port().offers_beacon() && self.responder.host_takes_keepalive())
            .then(|| k.interval())
    }

    /// SYNs sent while requests executed.
    pub fn keepalives_sent(&self) -> u64 {
        self.keepalive.as_ref().map_or(0, Keepalive::sent)
    }

    fn start_keepalive(&mut self) {
        let Some(k) = &self.keepalive else {
            return;
        };
        if !self.responder.host_takes_keepalive() {
            return;
        }
        if let Some(beacon) = self.driver.port_mut().beacon() {
            k.start(beacon);
        }
    }

    fn stop_keepalive(&self) {
        if let Some(k) = &self.keepalive {
            k.stop();
        }
    }

    /// Replace the error handlers (ErrOnSend and ErrOnReceive are asked on this side).
    pub fn set_handlers(&mut self, handlers: Box<dyn ErrorHandlers>) {
        self.handlers = handlers;
    }

    /// Give the port back.
    pub fn into_port(self) -> P {
        self.driver.into_port()
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

    /// The request being executed (after [`ServerEvent::Pending`]).
    pub fn request(&self) -> &[u8] {
        self.responder.request()
    }

    /// Send the reply of a request whose execution was deferred.
    pub fn respond(&mut self, reply: &[u8]) {
        self.stop_keepalive();
        let now = self.driver.clock().now();
        self.responder.respond(reply, now);
    }

    /// Let `d` pass while a deferred request executes, keeping the port's input moving.
    pub fn wait(&mut self, d: Duration) -> io::Result<()> {
        let until = self.driver.clock().now() + d;
        self.driver.run(&mut self.responder, Some(until), |_| false)
    }

    /// Serve until one transaction has ended, or until `idle` has passed with no request
    /// under way. `execute` gets the request bytes and returns the reply bytes (the manual's
    /// MsgReceived).
    pub fn serve(
        &mut self,
        idle: Duration,
        execute: &mut dyn FnMut(&[u8]) -> Vec<u8>,
    ) -> io::Result<ServerEvent> {
        self.serve_deferrable(idle, &mut |req, _| Some(execute(req)))
    }

    /// Like [`Server::serve`], but `execute` also gets the request's PCI (its transaction
    /// number in the low byte), and may return `None` to defer the reply
    /// ([`ServerEvent::Pending`]): the server then waits for [`Server::respond`].
    pub fn serve_deferrable(
        &mut self,
        idle: Duration,
        execute: &mut Execute<'_>,
    ) -> io::Result<ServerEvent> {
        let give_up = self.driver.clock().now() + idle;
        let mut attempts = 0u32;
        let answered_before = self.responder.repeats_answered();
        let mut unknown_repeat = false;
        let mut duplicate = false;
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
                Some(ResponderEvent::Request) if self.responder.request_is_unknown_repeat() => {
                    unknown_repeat = true;
                    let reply = Reply::Code(TROL_ERR_ROBOT_UNSURE).encode();
                    self.responder.respond(&reply, now);
                }
                Some(ResponderEvent::Request) if self.responder.request_is_suspect_duplicate() => {
                    duplicate = true;
                    let reply = Reply::Code(TROL_ERR_ROBOT_UNSURE).encode();
                    self.responder.respond(&reply, now);
                }
                Some(ResponderEvent::Done) if unknown_repeat => {
                    return Ok(ServerEvent::UnknownRepeat);
                }
                Some(ResponderEvent::Done) if duplicate => {
                    return Ok(ServerEvent::SuspectDuplicate);
                }
                Some(ResponderEvent::Request) => {
                    let pci = self.responder.request_pci();
                    self.start_keepalive();
                    let Some(reply) = execute(self.responder.request(), pci) else {
                        return Ok(ServerEvent::Pending);
                    };
                    self.stop_keepalive();
                    // Executing may take long (Finish waits for the arm): time the reply
                    // from when it is ready, not from when the request arrived.
                    let ready = self.driver.clock().now();
                    self.responder.respond(&reply, ready);
                }
                Some(ResponderEvent::Done)
                    if self.responder.repeats_answered() > answered_before =>
                {
                    return Ok(ServerEvent::Repeated);
                }
                Some(ResponderEvent::Done) => return Ok(ServerEvent::Executed),
                Some(ResponderEvent::NeedDecision(failure)) => {
                    let (error, recovery) = match failure {
                        Failure::Send(e) => {
                            let error = LinkError::Send(e);
                            let ctx = FailureContext {
                                error,
                                message: self.responder.reply(),
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
                        Recovery::Success | Recovery::Received { .. } => Decision::Retry,
                        Recovery::Fail | Recovery::Abort => Decision::GiveUp,
                    };
                    self.responder.decide(decision, now);
                    if decision == Decision::GiveUp {
                        // The responder reports Failed next; report the cause instead.
                        let _ = self.responder.poll_event();
                        let repeat = self.responder.repeats_answered() > answered_before;
                        return Ok(match failure {
                            Failure::Send(_) if repeat => ServerEvent::RepeatReplyFailed(error),
                            Failure::Send(_) => ServerEvent::ReplyFailed(error),
                            _ => ServerEvent::ReceiveFailed(error),
                        });
                    }
                }
                Some(ResponderEvent::Failed(code)) => {
                    // Only a reply that layer 2 refused to start ends up here: the request
                    // was executed, the reply could not go out, and the server listens again.
                    let _ = code;
                    return Ok(ServerEvent::ReplyTooLong {
                        len: self.responder.reply().len(),
                    });
                }
            }
        }
    }
}

impl<P> std::fmt::Debug for Server<P> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Server")
            .field("driver", &self.driver)
            .field("responder", &self.responder)
            .finish_non_exhaustive()
    }
}

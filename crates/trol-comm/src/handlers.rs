//! The application's error handlers of layer 3 (manual, "Callback-Routinen").
//!
//! The manual lets an application replace ErrOnSend, ErrOnReceive and ErrAppTimeOut (and the
//! layer-4 FatalError, which lives in the host API). Here they are the methods of
//! [`ErrorHandlers`]; [`DefaultHandlers`] behaves as the manual's `callback.c` is described:
//!
//! - ErrOnSend, ErrOnReceive: give up (RECOVERY_FAIL). Layer 2 has already retried every block
//!   MAX_RETRIES times and performed its reset, so a failure here is a broken link.
//! - ErrAppTimeOut: give up, except for the commands its [`TimeoutPolicy`] names: the manual
//!   waits 90 s more for Home and without limit for Finish(FINISH_WAIT). The host API installs
//!   that policy, since only layer 4 knows the command codes.
//!
//! A handler that returns [`Recovery::Success`] after a send failure makes layer 3 send the
//! message again (a failed SendData never delivered it, so nothing runs twice); after a
//! receive failure, it waits for the message again.

use std::time::Duration;

use trol_proto::application::Catalog;
use trol_proto::link::LinkError;

use crate::channel::Channel;

/// The manual's RECOVERY_SUCCESS / RECOVERY_FAIL.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Recovery {
    /// RECOVERY_SUCCESS: try again (send again; after a receive failure, wait for the
    /// message again).
    Success,
    /// RECOVERY_SUCCESS after a receive failure, with the message the handler received
    /// itself (the manual's ErrOnReceive filling `*out` and `*PCI`): layer 3 takes it as the
    /// reply.
    Received {
        /// Its PCI.
        pci: u16,
        /// The message.
        message: Vec<u8>,
    },
    /// RECOVERY_FAIL: give up this attempt. The library's own handlers say this; layer 3
    /// may still send the request again, marked REPEAT (exactly once, docs/protocol.md).
    Fail,
    /// RECOVERY_FAIL from the application's own handler: the application decided, so the
    /// call ends now with the manual's code and nothing is sent again (no repeat).
    Abort,
}

/// What ErrAppTimeOut decided.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimeoutAction {
    /// RECOVERY_FAIL: TransSR returns TRANS_TIMEOUT.
    Fail,
    /// RECOVERY_SUCCESS: wait this much longer (the handler is asked again if that runs out).
    WaitMore(Duration),
}

/// What a failed send or receive handler is told.
#[derive(Clone, Copy, Debug)]
pub struct FailureContext<'a> {
    /// The layer-2 code (GetLastCommErr).
    pub error: LinkError,
    /// The message that was being sent (the request on the PC, the reply on the controller);
    /// empty for a failed receive.
    pub message: &'a [u8],
    /// The PCI of that message.
    pub pci: u16,
    /// How many times the handler was already asked in this transaction.
    pub attempts: u32,
}

/// What ErrAppTimeOut is told.
#[derive(Clone, Copy, Debug)]
pub struct AppTimeoutContext<'a> {
    /// The request that was sent; its first byte is the command code.
    pub request: &'a [u8],
    /// Time since the request was sent.
    pub waited: Duration,
    /// The reply timeout (SetL3_TO_Intervall).
    pub reply_timeout: Duration,
    /// Whether bytes wait in the input buffer (the manual's `!BufferEmpty()`); the handler
    /// may look but cannot take them.
    pub input_pending: bool,
}

/// The application's error handlers. Every method has the manual's default.
pub trait ErrorHandlers: Send {
    /// ErrOnSend: SendData failed.
    fn err_on_send(&mut self, ctx: &FailureContext<'_>) -> Recovery {
        let _ = ctx;
        Recovery::Fail
    }

    /// ErrOnReceive: ReceiveData failed.
    fn err_on_receive(&mut self, ctx: &FailureContext<'_>) -> Recovery {
        let _ = ctx;
        Recovery::Fail
    }

    /// ErrAppTimeOut: no reply within the reply timeout. The manual's default: 90 s more for
    /// Home, no limit for Finish(FINISH_WAIT), no more for the other built-in commands and
    /// for added ones (whose descriptions [`DefaultHandlers::with_policy`] can take).
    fn err_app_timeout(&mut self, ctx: &AppTimeoutContext<'_>) -> TimeoutAction {
        DefaultHandlers::app_timeout(Some(&timeout_policy(Catalog::builtin())), ctx)
    }

    /// ErrOnSend with the line at hand (SendData, ReceiveData, BufferEmpty, FlushBuffer);
    /// by default [`ErrorHandlers::err_on_send`].
    fn err_on_send_on(&mut self, ctx: &FailureContext<'_>, line: &mut dyn Channel) -> Recovery {
        let _ = line;
        self.err_on_send(ctx)
    }

    /// ErrOnReceive with the line at hand: it may receive the message itself and return
    /// [`Recovery::Received`]; by default [`ErrorHandlers::err_on_receive`].
    fn err_on_receive_on(&mut self, ctx: &FailureContext<'_>, line: &mut dyn Channel) -> Recovery {
        let _ = line;
        self.err_on_receive(ctx)
    }

    /// ErrAppTimeOut with the line at hand (it may look with BufferEmpty, but must not take
    /// a byte); by default [`ErrorHandlers::err_app_timeout`].
    fn err_app_timeout_on(
        &mut self,
        ctx: &AppTimeoutContext<'_>,
        line: &mut dyn Channel,
    ) -> TimeoutAction {
        let _ = line;
        self.err_app_timeout(ctx)
    }
}

/// The ErrAppTimeOut policy of `catalog`'s commands, from their descriptions: 90 s more for
/// Home, no limit for Finish(FINISH_WAIT), as the manual's default handler; no more for a
/// command whose description asks for none, or one the catalog does not know.
pub fn timeout_policy(catalog: Catalog) -> TimeoutPolicy {
    std::sync::Arc::new(move |request: &[u8]| {
        let def = catalog.get(*request.first()?)?;
        match def.extra_wait(request) {
            Some(d) if d.is_zero() => None,
            Some(d) => Some(ExtraWait::Up(d)),
            None => Some(ExtraWait::Unlimited),
        }
    })
}

/// The ErrAppTimeOut policy against a controller of this protocol, which answers every
/// request at once (Home and motions at their start; the host waits for the arm by polling):
/// no limit for Finish(FINISH_WAIT) and whatever else `catalog`'s descriptions say waits
/// without limit, nothing more for the others. The manual's 90 s more for Home were for a
/// 1998 server that answered Home at its end; here they would only keep a call waiting on
/// a controller that died.
pub fn prompt_policy(catalog: Catalog) -> TimeoutPolicy {
    std::sync::Arc::new(move |request: &[u8]| {
        let def = catalog.get(*request.first()?)?;
        match def.extra_wait(request) {
            None => Some(ExtraWait::Unlimited),
            Some(_) => None,
        }
    })
}

/// Which requests ErrAppTimeOut waits longer for, by their bytes (the host API builds it
/// from its commands' descriptions).
pub type TimeoutPolicy = std::sync::Arc<dyn Fn(&[u8]) -> Option<ExtraWait> + Send + Sync>;

/// How much longer the default ErrAppTimeOut waits for a request.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExtraWait {
    /// This much beyond the reply timeout, in all.
    Up(Duration),
    /// Without limit (the manual's Finish(FINISH_WAIT)).
    Unlimited,
}

/// The manual's default handlers, with a policy for ErrAppTimeOut.
#[derive(Clone, Default)]
pub struct DefaultHandlers {
    policy: Option<TimeoutPolicy>,
}

impl DefaultHandlers {
    /// Defaults whose ErrAppTimeOut waits longer for the requests `policy` names.
    pub fn with_policy(policy: TimeoutPolicy) -> Self {
        DefaultHandlers {
            policy: Some(policy),
        }
    }

    /// The manual's ErrAppTimeOut for this policy (usable by other handler sets).
    pub fn app_timeout(
        policy: Option<&TimeoutPolicy>,
        ctx: &AppTimeoutContext<'_>,
    ) -> TimeoutAction {
        match policy.and_then(|p| p(ctx.request)) {
            Some(ExtraWait::Unlimited) => TimeoutAction::WaitMore(ctx.reply_timeout),
            Some(ExtraWait::Up(extra)) => {
                let limit = ctx.reply_timeout + extra;
                if ctx.waited < limit {
                    TimeoutAction::WaitMore(limit - ctx.waited)
                } else {
                    TimeoutAction::Fail
                }
            }
            None => TimeoutAction::Fail,
        }
    }
}

impl ErrorHandlers for DefaultHandlers {
    fn err_app_timeout(&mut self, ctx: &AppTimeoutContext<'_>) -> TimeoutAction {
        DefaultHandlers::app_timeout(self.policy.as_ref(), ctx)
    }
}

impl std::fmt::Debug for DefaultHandlers {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DefaultHandlers")
            .field("reply_waits", &self.policy.is_some())
            .finish()
    }
}

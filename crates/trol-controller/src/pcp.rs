//! The PCP server's layer 4 (manual, "Erstellen von Kommando-Handlern", "PCP\PCPTROL.C"):
//! one dispatch table per transaction class, indexed by `code - 64·class`, and the
//! bookkeeping of BIOSCalled and lastErrorCode for GetStatus.
//!
//! It is sans-IO: [`Pcp::handle`] takes a request's bytes and returns the reply's bytes
//! (the manual's MsgReceived). [`crate::Controller`] runs it behind layer 3.

use trol_proto::application::codes::{Class, Command};
use trol_proto::application::errors::{TROL_ERR_UNKNOWN, TROL_RETVAL_RANGE, is_trol_code};
use trol_proto::application::{Reply, Request};

use crate::bios::Bios;

/// What GetStatus reports: whether the last CAT1/CAT2 command called the BIOS, and the
/// BIOS's value or the TROL code that kept it from being called.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Status {
    /// BIOSCalled.
    pub bios_called: bool,
    /// lastErrorCode.
    pub last_error_code: i16,
}

impl Status {
    /// Record a BIOS call's value; returns what the reply carries (TROL_RETVAL_RANGE for a
    /// value in TROL's range, as CAT2 handlers must do themselves).
    pub fn record_bios(&mut self, value: i16) -> i16 {
        self.bios_called = true;
        self.last_error_code = value;
        if is_trol_code(value) {
            TROL_RETVAL_RANGE
        } else {
            value
        }
    }

    /// Record that the BIOS was not called, and why.
    pub fn record_refusal(&mut self, code: i16) {
        self.bios_called = false;
        self.last_error_code = code;
    }
}

/// A CAT1 handler: decodes its request, checks it, calls the BIOS once. `Ok(value)`: the
/// BIOS was called and returned `value`. `Err(code)`: it was not, for this TROL code. The
/// server builds the reply from that (manual: CAT1 handlers build no reply themselves).
pub type Cat1Handler<B> = fn(&mut B, &[u8]) -> Result<i16, i16>;

/// What CAT2..CAT4 handlers work with.
pub struct Context<'a, B> {
    /// The BIOS.
    pub bios: &'a mut B,
    /// BIOSCalled / lastErrorCode (CAT2 handlers must keep it).
    pub status: &'a mut Status,
    /// Set to end server mode once the reply is sent (TerminatePCP).
    pub terminate: &'a mut bool,
}

/// A handler of CAT2..CAT4: builds its reply itself.
pub type OtherHandler<B> = fn(&mut Context<'_, B>, &[u8]) -> Vec<u8>;

/// A dispatch-table entry.
pub enum Handler<B> {
    /// A CAT1 command.
    Cat1(Cat1Handler<B>),
    /// A CAT2, CAT3 or CAT4 command.
    Other(OtherHandler<B>),
}

impl<B> Clone for Handler<B> {
    fn clone(&self) -> Self {
        match self {
            Handler::Cat1(h) => Handler::Cat1(*h),
            Handler::Other(h) => Handler::Other(*h),
        }
    }
}

/// Why a handler could not be added.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RegisterError(pub String);

impl std::fmt::Display for RegisterError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for RegisterError {}

/// The PCP server's layer 4 over a BIOS.
pub struct Pcp<B> {
    bios: B,
    tables: [Vec<Handler<B>>; 4],
    status: Status,
    terminate: bool,
}

impl<B: Bios> Pcp<B> {
    /// A server with every built-in command in its table (the manual's `entrypoint()`).
    pub fn new(bios: B) -> Pcp<B> {
        let mut pcp = Pcp {
            bios,
            tables: [Vec::new(), Vec::new(), Vec::new(), Vec::new()],
            status: Status::default(),
            terminate: false,
        };
        for &c in Command::ALL {
            let h = match c.class() {
                Class::Cat1 => Handler::Cat1(builtin_cat1::<B> as Cat1Handler<B>),
                Class::Cat2 => unreachable!("no built-in CAT2 commands"),
                Class::Cat3 | Class::Cat4 => Handler::Other(builtin_other::<B> as OtherHandler<B>),
            };
            pcp.register(c.code(), h)
                .expect("built-in codes have no gaps");
        }
        pcp
    }
}

impl<B> Pcp<B> {
    /// Add a command (manual, "Modifikation der betroffenen Source-Dateien", step 3:
    /// `dispatchTableX[code - X*64] = handler`). The code must be the next one of its class,
    /// so that the table has no gaps; a CAT1 code needs a [`Handler::Cat1`].
    pub fn register(&mut self, code: u8, handler: Handler<B>) -> Result<(), RegisterError> {
        let class = Class::of(code);
        let table = &mut self.tables[class.index()];
        let next = class.base() as usize + table.len();
        if code as usize != next {
            return Err(RegisterError(format!(
                "code {code} leaves a gap or repeats one: the next {class} code is {next}"
            )));
        }
        if matches!(handler, Handler::Cat1(_)) != (class == Class::Cat1) {
            return Err(RegisterError(format!(
                "code {code} is {class}; CAT1 codes take a CAT1 handler and the others not"
            )));
        }
        table.push(handler);
        Ok(())
    }

    /// The largest code of a class (LAST_CATx_CODE), one below the base if it is empty.
    pub fn last_code(&self, class: Class) -> i32 {
        class.base() as i32 + self.tables[class.index()].len() as i32 - 1
    }

    /// The BIOS.
    pub fn bios(&self) -> &B {
        &self.bios
    }

    /// The BIOS, mutably.
    pub fn bios_mut(&mut self) -> &mut B {
        &mut self.bios
    }

    /// BIOSCalled and lastErrorCode.
    pub fn status(&self) -> Status {
        self.status
    }

    /// Whether TerminatePCP asked to end server mode (reading clears it).
    pub fn take_terminate(&mut self) -> bool {
        std::mem::take(&mut self.terminate)
    }

    /// MsgReceived: execute a request and build its reply.
    pub fn handle(&mut self, request: &[u8]) -> Vec<u8> {
        let Some(&code) = request.first() else {
            self.status.record_refusal(TROL_ERR_UNKNOWN);
            return TROL_ERR_UNKNOWN.to_le_bytes().to_vec();
        };
        let class = Class::of(code);
        let index = (code - class.base()) as usize;
        let Some(handler) = self.tables[class.index()].get(index).cloned() else {
            if matches!(class, Class::Cat1 | Class::Cat2) {
                self.status.record_refusal(TROL_ERR_UNKNOWN);
            }
            return TROL_ERR_UNKNOWN.to_le_bytes().to_vec();
        };
        match handler {
            Handler::Cat1(h) => {
                let value = match h(&mut self.bios, request) {
                    Ok(v) => self.status.record_bios(v),
                    Err(code) => {
                        self.status.record_refusal(code);
                        code
                    }
                };
                value.to_le_bytes().to_vec()
            }
            Handler::Other(h) => {
                let mut ctx = Context {
                    bios: &mut self.bios,
                    status: &mut self.status,
                    terminate: &mut self.terminate,
                };
                h(&mut ctx, request)
            }
        }
    }
}

fn six(v: &[f32]) -> [f64; 6] {
    let mut out = [0.0; 6];
    for (o, x) in out.iter_mut().zip(v) {
        *o = *x as f64;
    }
    out
}

/// The handler of every built-in CAT1 command: decode (size, then ranges), look names up,
/// call the BIOS.
fn builtin_cat1<B: Bios>(bios: &mut B, bytes: &[u8]) -> Result<i16, i16> {
    use trol_proto::application::errors::TROL_ERR_LOCATION;
    let req = Request::decode(bytes).map_err(|e| e.code())?;
    Ok(match req {
        Request::Appro {
            name,
            disp,
            straight,
        } => {
            let target = bios.location(&name).ok_or(TROL_ERR_LOCATION)?;
            bios.appro(&target, six(&disp), straight)
        }
        Request::ApproII {
            target,
            disp,
            straight,
        } => bios.appro(&target, six(&disp), straight),
        Request::Close { force } => bios.close(force),
        Request::Depart { disp, straight } => bios.depart(six(&disp), straight),
        Request::Finish { mode } => bios.finish(mode),
        Request::Grip { dist } => bios.grip(dist),
        Request::Halt => bios.halt(),
        Request::Home { axis } => bios.home(axis),
        Request::Jog { disp, straight } => {
            let d = six(&disp);
            bios.jog([d[0], d[1], d[2]], straight)
        }
        Request::Joint { joint, radians } => bios.joint(joint, radians as f64),
        Request::Ma { joints } => bios.ma(six(&joints)),
        Request::Mi { joints } => bios.mi(six(&joints)),
        Request::Move { name, straight } => {
            let target = bios.location(&name).ok_or(TROL_ERR_LOCATION)?;
            bios.move_to(&target, straight)
        }
        Request::MoveII { target, straight } => bios.move_to(&target, straight),
        Request::Open { force } => bios.open(force),
        Request::Ready => bios.ready(),
        Request::SetToolTransform { tool } => bios.set_tool(six(&tool)),
        Request::Speed { percent } => bios.speed(percent),
        Request::GetPosition { .. } | Request::TerminatePcp | Request::GetStatus => {
            return Err(TROL_ERR_UNKNOWN);
        }
    })
}

/// The handler of the built-in CAT3 and CAT4 commands.
fn builtin_other<B: Bios>(ctx: &mut Context<'_, B>, bytes: &[u8]) -> Vec<u8> {
    let req = match Request::decode(bytes) {
        Ok(r) => r,
        Err(e) => return e.code().to_le_bytes().to_vec(),
    };
    match req {
        Request::GetPosition { tag, mode } => {
            Reply::Position(ctx.bios.position(tag, mode)).encode()
        }
        Request::TerminatePcp => {
            *ctx.terminate = true;
            Reply::Code(0).encode()
        }
        Request::GetStatus => Reply::Status {
            bios_called: ctx.status.bios_called,
            last: ctx.status.last_error_code,
        }
        .encode(),
        _ => TROL_ERR_UNKNOWN.to_le_bytes().to_vec(),
    }
}

//! The manual's C API (`include/trol.h`): the same names, types and return codes.
//!
//! One connection per process, as in the original. Every function returns the manual's
//! codes; no panic crosses the C boundary (each entry point catches it and returns
//! TROL_ERR_COMM). Error handlers installed from C are called on the caller's thread while a
//! transaction runs; they may call GetLastCommErr() but no other TROL function.

//!
//! # Safety
//!
//! Every pointer argument must be NULL or point to a valid object of its C type
//! (SLocData, an 8-byte TLocName or a NUL-terminated shorter name, an int); NULL gives
//! TROL_ERR_ARG_RANGE. This holds for each `unsafe` function here.

#![allow(non_snake_case, non_camel_case_types, clippy::missing_safety_doc)]

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU16, Ordering};
use std::time::Duration;

use trol_comm::{
    AppTimeoutContext, DefaultHandlers, ErrorHandlers, FailureContext, Recovery, TimeoutAction,
};
use trol_proto::application::codes::Command;
use trol_proto::application::errors::{TROL_ERR_ARG_RANGE, TROL_ERR_COMM};
use trol_proto::application::{FinishMode, LocName, Location, PosMode, Reply, Request, Tag};

use crate::config::Config;
use crate::robot::{Error, Robot, timeout_policy};

/// signed 32 bit.
pub type TLONG = i32;
/// unsigned 16 bit.
pub type TUINT = u16;
/// signed 16 bit.
pub type TINT = i16;
/// unsigned 8 bit.
pub type TUCHAR = u8;

/// RECOVERY_SUCCESS.
pub const RECOVERY_SUCCESS: TUINT = 0;
/// RECOVERY_FAIL.
pub const RECOVERY_FAIL: TUINT = 1;
/// INITTROL_SUCCESS.
pub const INITTROL_SUCCESS: TUINT = 0;
/// INITTROL_FAILURE.
pub const INITTROL_FAILURE: TUINT = 1;

/// SLocData: tag, numDims, eight values (packed to 2 bytes, as the manual requires).
#[repr(C, packed(2))]
#[derive(Clone, Copy)]
pub struct SLocData {
    /// POS_PREC, POS_JOINT or POS_CART.
    pub tag: TUCHAR,
    /// How many values are relevant.
    pub numDims: TUCHAR,
    /// The values: TLONG for POS_PREC, float otherwise.
    pub data: [u32; 8],
}

/// A message handed to an error handler (the manual's SInData / SOutData).
#[repr(C)]
pub struct SInData {
    /// Its length.
    pub numBytes: TUINT,
    /// Its bytes.
    pub data: *mut TUCHAR,
}

/// ErrOnSend / ErrOnReceive from C.
pub type ErrOnFn = Option<unsafe extern "C" fn(*mut SInData, *mut TUINT) -> TUINT>;
/// ErrAppTimeOut from C.
pub type ErrAppTimeOutFn = Option<unsafe extern "C" fn(*mut SInData) -> TUINT>;
/// FatalError from C.
pub type FatalErrorFn = Option<unsafe extern "C" fn(TUINT, TINT) -> TINT>;

#[derive(Clone, Copy, Default)]
struct Callbacks {
    on_send: ErrOnFn,
    on_receive: ErrOnFn,
    app_timeout: ErrAppTimeOutFn,
    fatal: FatalErrorFn,
}

struct State {
    robot: Option<Robot>,
    callbacks: Callbacks,
    reply_tenths: u16,
    delay: Duration,
}

static STATE: Mutex<State> = Mutex::new(State {
    robot: None,
    callbacks: Callbacks {
        on_send: None,
        on_receive: None,
        app_timeout: None,
        fatal: None,
    },
    reply_tenths: trol_proto::transaction::DEFAULT_REPLY_TIMEOUT_TENTHS,
    delay: Duration::ZERO,
});

static LAST_COMM_ERR: AtomicU16 = AtomicU16::new(0);

fn state() -> std::sync::MutexGuard<'static, State> {
    STATE.lock().unwrap_or_else(|p| p.into_inner())
}

/// The layer-3 handlers that call the application's C functions.
struct CHandlers(Callbacks);

fn call_on(f: ErrOnFn, ctx: &FailureContext<'_>) -> Recovery {
    LAST_COMM_ERR.store(ctx.error.code(), Ordering::Relaxed);
    let Some(f) = f else { return Recovery::Fail };
    let mut copy = ctx.message.to_vec();
    let mut data = SInData {
        numBytes: copy.len() as TUINT,
        data: copy.as_mut_ptr(),
    };
    let mut pci = ctx.pci;
    // SAFETY: the application's handler gets pointers to live locals.
    match unsafe { f(&mut data, &mut pci) } {
        RECOVERY_SUCCESS => Recovery::Success,
        _ => Recovery::Fail,
    }
}

impl ErrorHandlers for CHandlers {
    fn err_on_send(&mut self, ctx: &FailureContext<'_>) -> Recovery {
        call_on(self.0.on_send, ctx)
    }
    fn err_on_receive(&mut self, ctx: &FailureContext<'_>) -> Recovery {
        call_on(self.0.on_receive, ctx)
    }
    fn err_app_timeout(&mut self, ctx: &AppTimeoutContext<'_>) -> TimeoutAction {
        match self.0.app_timeout {
            None => DefaultHandlers::app_timeout(Some(timeout_policy), ctx),
            Some(f) => {
                let mut copy = ctx.request.to_vec();
                let mut data = SInData {
                    numBytes: copy.len() as TUINT,
                    data: copy.as_mut_ptr(),
                };
                // SAFETY: as above.
                match unsafe { f(&mut data) } {
                    RECOVERY_SUCCESS => TimeoutAction::WaitMore(ctx.reply_timeout),
                    _ => TimeoutAction::Fail,
                }
            }
        }
    }
}

fn guard<T>(fallback: T, f: impl FnOnce() -> T) -> T {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or(fallback)
}

/// Run a built-in request; errors other than TROL_ERR_ARG_RANGE go through FatalError.
fn run(
    command: Command,
    build: impl FnOnce() -> Result<Request, TINT>,
    ok: &[TINT],
    read: impl FnOnce(Reply),
) -> TINT {
    guard(TROL_ERR_COMM, || {
        let req = match build() {
            Ok(r) => r,
            Err(code) => return code,
        };
        let (result, fatal) = {
            let mut st = state();
            let fatal = st.callbacks.fatal;
            let Some(robot) = st.robot.as_mut() else {
                return fatal_or(fatal, command, TROL_ERR_COMM);
            };
            let r = robot.request(&req);
            if let Some(e) = robot.last_comm_error() {
                LAST_COMM_ERR.store(e.code(), Ordering::Relaxed);
            }
            (r, fatal)
        };
        match result {
            Ok(Reply::Code(v)) if v == 0 || ok.contains(&v) => v,
            Ok(Reply::Code(v)) => fatal_or(fatal, command, v),
            Ok(reply) => {
                let v = reply.value();
                read(reply);
                v
            }
            Err(Error::Argument(_)) => TROL_ERR_ARG_RANGE,
            Err(e) => fatal_or(fatal, command, e.code()),
        }
    })
}

fn fatal_or(fatal: FatalErrorFn, command: Command, code: TINT) -> TINT {
    match fatal {
        // SAFETY: the application's handler, called with plain values.
        Some(f) => unsafe { f(command.code() as TUINT, code) },
        None => code,
    }
}

/// Read a location from C, with the tags `allowed`.
unsafe fn location(p: *const SLocData, allowed: &[Tag]) -> Result<Location, TINT> {
    if p.is_null() {
        return Err(TROL_ERR_ARG_RANGE);
    }
    // SAFETY: the caller passes a valid SLocData; it is read unaligned (packed).
    let loc = unsafe { std::ptr::read_unaligned(p) };
    let tag = Tag::from_u8(loc.tag)
        .filter(|t| allowed.contains(t))
        .ok_or(TROL_ERR_ARG_RANGE)?;
    let n = loc.numDims as usize;
    if !(1..=8).contains(&n) {
        return Err(TROL_ERR_ARG_RANGE);
    }
    let data = loc.data;
    let words = &data[..n];
    Ok(match tag {
        Tag::Prec => Location::Prec(words.iter().map(|w| *w as i32).collect()),
        Tag::Joint => Location::Joint(words.iter().map(|w| f32::from_bits(*w)).collect()),
        Tag::Cart => Location::Cart(words.iter().map(|w| f32::from_bits(*w)).collect()),
    })
}

unsafe fn cart(p: *const SLocData) -> Result<Vec<f32>, TINT> {
    match unsafe { location(p, &[Tag::Cart]) }? {
        Location::Cart(v) => Ok(v),
        _ => Err(TROL_ERR_ARG_RANGE),
    }
}

unsafe fn name(p: *const TUCHAR) -> Result<LocName, TINT> {
    if p.is_null() {
        return Err(TROL_ERR_ARG_RANGE);
    }
    let mut raw = Vec::with_capacity(8);
    for i in 0..8 {
        // SAFETY: a TLocName has 8 bytes; a shorter C string ends at its NUL, read no further.
        let b = unsafe { *p.add(i) };
        if b == 0 {
            break;
        }
        raw.push(b);
    }
    LocName::from_bytes(&raw).map_err(|_| TROL_ERR_ARG_RANGE)
}

fn byte(v: TUINT) -> Result<u8, TINT> {
    u8::try_from(v).map_err(|_| TROL_ERR_ARG_RANGE)
}

/// TROLAppro.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLAppro(
    locName: *const TUCHAR,
    pDisp: *const SLocData,
    straight: TUINT,
) -> TINT {
    run(
        Command::Appro,
        || {
            Ok(Request::Appro {
                name: unsafe { name(locName) }?,
                disp: unsafe { cart(pDisp) }?,
                straight: straight != 0,
            })
        },
        &[],
        drop,
    )
}

/// TROLApproII.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLApproII(
    pTarget: *const SLocData,
    pDisp: *const SLocData,
    straight: TUINT,
) -> TINT {
    run(
        Command::ApproII,
        || {
            Ok(Request::ApproII {
                target: unsafe { location(pTarget, &[Tag::Cart, Tag::Prec]) }?,
                disp: unsafe { cart(pDisp) }?,
                straight: straight != 0,
            })
        },
        &[],
        drop,
    )
}

/// TROLClose.
#[unsafe(no_mangle)]
pub extern "C" fn TROLClose(perForce: TUINT) -> TINT {
    run(
        Command::Close,
        || {
            Ok(Request::Close {
                force: byte(perForce)?,
            })
        },
        &[],
        drop,
    )
}

/// TROLDepart.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLDepart(pDisp: *const SLocData, straight: TUINT) -> TINT {
    run(
        Command::Depart,
        || {
            Ok(Request::Depart {
                disp: unsafe { cart(pDisp) }?,
                straight: straight != 0,
            })
        },
        &[],
        drop,
    )
}

/// TROLFinish: FINISH_STATUS (0) returns 1 while moving, FINISH_WAIT (1) waits.
#[unsafe(no_mangle)]
pub extern "C" fn TROLFinish(mode: TUINT) -> TINT {
    run(
        Command::Finish,
        || match mode {
            0 => Ok(Request::Finish {
                mode: FinishMode::Status,
            }),
            1 => Ok(Request::Finish {
                mode: FinishMode::Wait,
            }),
            _ => Err(TROL_ERR_ARG_RANGE),
        },
        &[1],
        drop,
    )
}

/// TROLGrip.
#[unsafe(no_mangle)]
pub extern "C" fn TROLGrip(dist: TUINT) -> TINT {
    run(
        Command::Grip,
        || Ok(Request::Grip { dist: byte(dist)? }),
        &[],
        drop,
    )
}

/// TROLHalt.
#[unsafe(no_mangle)]
pub extern "C" fn TROLHalt() -> TINT {
    run(Command::Halt, || Ok(Request::Halt), &[], drop)
}

/// TROLHome.
#[unsafe(no_mangle)]
pub extern "C" fn TROLHome(axis: TUINT) -> TINT {
    run(
        Command::Home,
        || Ok(Request::Home { axis: byte(axis)? }),
        &[],
        drop,
    )
}

/// TROLJog.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLJog(pDisp: *const SLocData, straight: TUINT) -> TINT {
    run(
        Command::Jog,
        || {
            Ok(Request::Jog {
                disp: unsafe { cart(pDisp) }?,
                straight: straight != 0,
            })
        },
        &[],
        drop,
    )
}

/// TROLJoint.
#[unsafe(no_mangle)]
pub extern "C" fn TROLJoint(jointNum: TUINT, radians: f32) -> TINT {
    run(
        Command::Joint,
        || {
            Ok(Request::Joint {
                joint: byte(jointNum)?,
                radians,
            })
        },
        &[],
        drop,
    )
}

unsafe fn joints(p: *const SLocData) -> Result<Vec<f32>, TINT> {
    match unsafe { location(p, &[Tag::Joint]) }? {
        Location::Joint(v) => Ok(v),
        _ => Err(TROL_ERR_ARG_RANGE),
    }
}

/// TROLMA.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLMA(pTarget: *const SLocData) -> TINT {
    run(
        Command::Ma,
        || {
            Ok(Request::Ma {
                joints: unsafe { joints(pTarget) }?,
            })
        },
        &[],
        drop,
    )
}

/// TROLMI.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLMI(pDisp: *const SLocData) -> TINT {
    run(
        Command::Mi,
        || {
            Ok(Request::Mi {
                joints: unsafe { joints(pDisp) }?,
            })
        },
        &[],
        drop,
    )
}

/// TROLMove.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLMove(locName: *const TUCHAR, straight: TUINT) -> TINT {
    run(
        Command::Move,
        || {
            Ok(Request::Move {
                name: unsafe { name(locName) }?,
                straight: straight != 0,
            })
        },
        &[],
        drop,
    )
}

/// TROLMoveII.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLMoveII(pTarget: *const SLocData, straight: TUINT) -> TINT {
    run(
        Command::MoveII,
        || {
            Ok(Request::MoveII {
                target: unsafe { location(pTarget, &[Tag::Cart, Tag::Prec]) }?,
                straight: straight != 0,
            })
        },
        &[],
        drop,
    )
}

/// TROLOpen.
#[unsafe(no_mangle)]
pub extern "C" fn TROLOpen(perForce: TUINT) -> TINT {
    run(
        Command::Open,
        || {
            Ok(Request::Open {
                force: byte(perForce)?,
            })
        },
        &[],
        drop,
    )
}

/// TROLReady.
#[unsafe(no_mangle)]
pub extern "C" fn TROLReady() -> TINT {
    run(Command::Ready, || Ok(Request::Ready), &[], drop)
}

/// TROLSetToolTransform.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLSetToolTransform(md: *const SLocData) -> TINT {
    run(
        Command::SetToolTransform,
        || {
            Ok(Request::SetToolTransform {
                tool: unsafe { cart(md) }?,
            })
        },
        &[],
        drop,
    )
}

/// TROLSpeed.
#[unsafe(no_mangle)]
pub extern "C" fn TROLSpeed(perMaxSpeed: TUINT) -> TINT {
    run(
        Command::Speed,
        || {
            Ok(Request::Speed {
                percent: byte(perMaxSpeed)?,
            })
        },
        &[],
        drop,
    )
}

/// TROLGetPosition: the form is read from pos->tag; mode POS_COMMANDED (0) or POS_ACT (1).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLGetPosition(pos: *mut SLocData, mode: TINT) -> TINT {
    if pos.is_null() {
        return TROL_ERR_ARG_RANGE;
    }
    // SAFETY: a valid SLocData from the caller.
    let tag_byte = unsafe { std::ptr::read_unaligned(pos) }.tag;
    let mut out = None;
    let r = run(
        Command::GetPosition,
        || {
            let tag = Tag::from_u8(tag_byte).ok_or(TROL_ERR_ARG_RANGE)?;
            let mode = match mode {
                0 => PosMode::Commanded,
                1 => PosMode::Actual,
                _ => return Err(TROL_ERR_ARG_RANGE),
            };
            Ok(Request::GetPosition { tag, mode })
        },
        &[],
        |reply| {
            if let Reply::Position(loc) = reply {
                out = Some(loc);
            }
        },
    );
    if let Some(loc) = out {
        let mut data = [0u32; 8];
        let n = loc.num_dims().min(8);
        match &loc {
            Location::Prec(v) => v
                .iter()
                .take(8)
                .enumerate()
                .for_each(|(i, x)| data[i] = *x as u32),
            Location::Joint(v) | Location::Cart(v) => v
                .iter()
                .take(8)
                .enumerate()
                .for_each(|(i, x)| data[i] = x.to_bits()),
        }
        let value = SLocData {
            tag: loc.tag() as u8,
            numDims: n as u8,
            data,
        };
        // SAFETY: as above.
        unsafe { std::ptr::write_unaligned(pos, value) };
    }
    r
}

/// TROLTerminatePCP.
#[unsafe(no_mangle)]
pub extern "C" fn TROLTerminatePCP() -> TINT {
    run(
        Command::TerminatePcp,
        || Ok(Request::TerminatePcp),
        &[],
        drop,
    )
}

/// TROLGetStatus: 1 if the last CAT1/CAT2 command called the BIOS (its value in
/// *lastBIOSRetVal), 0 if not (the TROL code why in *lastBIOSRetVal).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLGetStatus(lastBIOSRetVal: *mut std::ffi::c_int) -> TINT {
    let mut last = None;
    let r = run(
        Command::GetStatus,
        || Ok(Request::GetStatus),
        &[1],
        |reply| {
            if let Reply::Status { last: l, .. } = reply {
                last = Some(l);
            }
        },
    );
    if let (Some(l), false) = (last, lastBIOSRetVal.is_null()) {
        // SAFETY: the caller's int.
        unsafe { *lastBIOSRetVal = l as std::ffi::c_int };
    }
    r
}

fn open_from_config() -> Result<(Robot, Config), String> {
    let cfg = Config::load().map_err(|e| e.to_string())?;
    let robot = Robot::from_config(&cfg).map_err(|e| e.to_string())?;
    Ok((robot, cfg))
}

/// InitTROL(1): open the port of trol.cfg and check that the server answers.
/// InitTROL(0) (the init utility): also bring the controller from terminal mode into server
/// mode and apply trol.cfg's tool transform.
#[unsafe(no_mangle)]
pub extern "C" fn InitTROL(serOnly: TUINT) -> TUINT {
    guard(INITTROL_FAILURE, || {
        let (mut robot, cfg) = match open_from_config() {
            Ok(x) => x,
            Err(why) => {
                eprintln!("InitTROL: {why}");
                return INITTROL_FAILURE;
            }
        };
        let (callbacks, tenths, delay) = {
            let st = state();
            (st.callbacks, st.reply_tenths, st.delay)
        };
        robot.set_handlers(Box::new(CHandlers(callbacks)));
        robot.set_reply_timeout_tenths(tenths);
        robot.set_delay(delay);
        let ok = if serOnly == 0 {
            crate::activate(&mut robot, &cfg.tool)
                .map_err(|e| eprintln!("InitTROL: {e}"))
                .is_ok()
        } else {
            crate::check_server(&mut robot)
                .map_err(|e| eprintln!("InitTROL: {e}"))
                .is_ok()
        };
        if !ok {
            return INITTROL_FAILURE;
        }
        state().robot = Some(robot);
        INITTROL_SUCCESS
    })
}

/// CleanupTROL: end server mode (TerminatePCP) and close the port.
#[unsafe(no_mangle)]
pub extern "C" fn CleanupTROL() -> TUINT {
    guard(INITTROL_FAILURE, || {
        let robot = state().robot.take();
        match robot {
            Some(mut r) => match r.terminate_pcp() {
                Ok(()) => INITTROL_SUCCESS,
                Err(e) => {
                    eprintln!("CleanupTROL: {e}");
                    INITTROL_FAILURE
                }
            },
            None => INITTROL_FAILURE,
        }
    })
}

/// SetL3_TO_Intervall: the reply timeout in tenths of a second.
#[unsafe(no_mangle)]
pub extern "C" fn SetL3_TO_Intervall(TO_Intervall: TUINT) {
    guard((), || {
        let mut st = state();
        st.reply_tenths = TO_Intervall;
        if let Some(r) = st.robot.as_mut() {
            r.set_reply_timeout_tenths(TO_Intervall);
        }
    })
}

/// SetDelay: a pause of `delay` milliseconds between two bytes sent.
#[unsafe(no_mangle)]
pub extern "C" fn SetDelay(delay: TUINT) {
    guard((), || {
        let mut st = state();
        st.delay = Duration::from_millis(delay as u64);
        if let Some(r) = st.robot.as_mut() {
            r.set_delay(Duration::from_millis(delay as u64));
        }
    })
}

/// GetLastCommErr: the layer-2 code of the last failure (NAK code in the high byte), 0 if
/// none. Handlers may call it.
#[unsafe(no_mangle)]
pub extern "C" fn GetLastCommErr() -> TUINT {
    LAST_COMM_ERR.load(Ordering::Relaxed)
}

fn set_callbacks(f: impl FnOnce(&mut Callbacks)) {
    guard((), || {
        let mut st = state();
        f(&mut st.callbacks);
        let cb = st.callbacks;
        if let Some(r) = st.robot.as_mut() {
            r.set_handlers(Box::new(CHandlers(cb)));
        }
    })
}

/// Install ErrOnSend (NULL: the default, RECOVERY_FAIL).
#[unsafe(no_mangle)]
pub extern "C" fn TROLSetErrOnSend(handler: ErrOnFn) {
    set_callbacks(|c| c.on_send = handler)
}

/// Install ErrOnReceive (NULL: the default, RECOVERY_FAIL).
#[unsafe(no_mangle)]
pub extern "C" fn TROLSetErrOnReceive(handler: ErrOnFn) {
    set_callbacks(|c| c.on_receive = handler)
}

/// Install ErrAppTimeOut (NULL: the default, 90 s more for Home, no limit for
/// Finish(FINISH_WAIT)).
#[unsafe(no_mangle)]
pub extern "C" fn TROLSetErrAppTimeOut(handler: ErrAppTimeOutFn) {
    set_callbacks(|c| c.app_timeout = handler)
}

/// Install FatalError (NULL: the default, which returns the error code).
#[unsafe(no_mangle)]
pub extern "C" fn TROLSetFatalError(handler: FatalErrorFn) {
    set_callbacks(|c| c.fatal = handler)
}

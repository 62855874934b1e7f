//! The manual's C API (`include/trol.h`): the same names, types and return codes.
//!
//! The manual's functions drive one default connection per process, as in the original.
//! Beside them, libmodbus-style, any number of connections: `TROL *trol_connect(port,
//! baud)`, and for every manual function `TROLName(args)` a `trol_name(TROL *, args)` (see
//! [`per_connection`] below); each connection has its own error handlers. Every function
//! returns the manual's codes; no panic crosses the C boundary (each entry point catches it
//! and returns TROL_ERR_COMM). Error handlers are called on the caller's thread while a
//! transaction runs; a handler that calls TROL on its own connection gets TROL_ERR_COMM at
//! once (that connection is busy with the call that failed), never a deadlock; other
//! connections work.

//!
//! # Safety
//!
//! Every pointer argument must be NULL or point to a valid object of its C type
//! (SLocData, an 8-byte TLocName or a NUL-terminated shorter name, an int); NULL gives
//! TROL_ERR_ARG_RANGE. This holds for each `unsafe` function here.

#![allow(non_snake_case, non_camel_case_types, clippy::missing_safety_doc)]

use std::cell::{Cell, RefCell};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU16, Ordering};
use std::time::Duration;

use trol_comm::{
    AppTimeoutContext, Channel, DefaultHandlers, ErrorHandlers, FailureContext, Recovery,
    TimeoutAction,
};
use trol_proto::application::code::{TROL_ERR_ARG_RANGE, TROL_ERR_COMM, TROL_ERR_NOT_INIT};
use trol_proto::application::record::Value;
use trol_proto::application::table::{self, FINISH_STATUS, FINISH_WAIT, POS_ACT, POS_COMMANDED};
use trol_proto::application::{CommandDef, LocName, Location, Reply, Tag};
use trol_proto::transaction::TransCode;

use trol_client::config::Config;
use trol_client::{Error, Robot};

const ARG_RANGE: TINT = TROL_ERR_ARG_RANGE.0;
const COMM: TINT = TROL_ERR_COMM.0;
const NOT_INIT: TINT = TROL_ERR_NOT_INIT.0;

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
    /// TROLSetRepeats's choice; `None`: as the controller's version handshake allows.
    repeats: Option<u8>,
}

const FRESH: State = State {
    robot: None,
    callbacks: Callbacks {
        on_send: None,
        on_receive: None,
        app_timeout: None,
        fatal: None,
    },
    reply_tenths: trol_proto::transaction::DEFAULT_REPLY_TIMEOUT_TENTHS,
    delay: Duration::ZERO,
    repeats: None,
};

/// The default connection: the manual's functions drive it.
static STATE: TROL = TROL::fresh(FRESH);
/// GetLastCommSide: SendData failed.
pub const COMM_SIDE_SEND: TUINT = 1;
/// GetLastCommSide: ReceiveData failed.
pub const COMM_SIDE_RECEIVE: TUINT = 2;

/// Keep `error` for GetLastCommErr and GetLastCommSide (None: the call had no failure).
fn note_comm(error: Option<trol_proto::link::LinkError>) {
    let (code, side) = match error {
        Some(e @ trol_proto::link::LinkError::Send(_)) => (e.code(), COMM_SIDE_SEND),
        Some(e @ trol_proto::link::LinkError::Receive(_)) => (e.code(), COMM_SIDE_RECEIVE),
        None => (0, 0),
    };
    note_code(code, side);
}

/// Keep a layer-2 code for the connection of this call (GetLastCommErr, GetLastCommSide):
/// each connection has its own, so one connection's calls never reset another's.
fn note_code(code: u16, side: TUINT) {
    let c = conn();
    c.last_err.store(code, Ordering::Relaxed);
    c.last_side.store(side, Ordering::Relaxed);
}

/// The C type `TROL`: one connection with its settings and handlers (opaque to C).
pub struct TROL {
    inner: Mutex<State>,
    /// GetLastCommErr's code and GetLastCommSide's side for this connection: outside the
    /// lock, so that a handler may read them while its call holds it.
    last_err: AtomicU16,
    /// Which service failed last: 0 none, [`COMM_SIDE_SEND`], [`COMM_SIDE_RECEIVE`].
    last_side: AtomicU16,
    /// The BIOS codes this connection's controller told (TROLGetCodes, read when it
    /// connected), for trol_strerror and trol_strerror_for: a lock of its own, never held
    /// during a call, so that an error handler may ask.
    told: Mutex<Option<&'static trol_client::CodeTable>>,
    /// The application's pointer for this connection (trol_set_user), for a handler
    /// shared by several connections to tell them apart.
    user: std::sync::atomic::AtomicPtr<std::ffi::c_void>,
}

impl TROL {
    const fn fresh(state: State) -> TROL {
        TROL {
            inner: Mutex::new(state),
            last_err: AtomicU16::new(0),
            last_side: AtomicU16::new(0),
            told: Mutex::new(None),
            user: std::sync::atomic::AtomicPtr::new(std::ptr::null_mut()),
        }
    }
}

thread_local! {
    /// The connection the calls on this thread use while a `trol_*` function runs; `None`:
    /// the default one (the manual's functions).
    static CONN: Cell<Option<&'static TROL>> = const { Cell::new(None) };
    /// The connections whose lock this thread holds (a call on it is under way, and its
    /// error handler runs): a call on one of them from here would wait for itself.
    static HOLDING: RefCell<Vec<usize>> = const { RefCell::new(Vec::new()) };
}

fn conn() -> &'static TROL {
    CONN.get().unwrap_or(&STATE)
}

fn state() -> std::sync::MutexGuard<'static, State> {
    conn().inner.lock().unwrap_or_else(|p| p.into_inner())
}

/// The connection locked for a call, released when dropped.
struct Held {
    guard: std::sync::MutexGuard<'static, State>,
    addr: usize,
}

impl std::ops::Deref for Held {
    type Target = State;
    fn deref(&self) -> &State {
        &self.guard
    }
}

impl std::ops::DerefMut for Held {
    fn deref_mut(&mut self) -> &mut State {
        &mut self.guard
    }
}

impl Drop for Held {
    fn drop(&mut self) {
        HOLDING.with_borrow_mut(|h| {
            if let Some(i) = h.iter().rposition(|a| *a == self.addr) {
                h.remove(i);
            }
        });
    }
}

/// Lock the connection for a call; `None` when this thread holds it already (an error
/// handler calling TROL on its own connection): the caller returns at once instead of
/// waiting for itself.
fn state_for_call() -> Option<Held> {
    let c = conn();
    let addr = c as *const TROL as usize;
    if HOLDING.with_borrow(|h| h.contains(&addr)) {
        return None;
    }
    let guard = c.inner.lock().unwrap_or_else(|p| p.into_inner());
    HOLDING.with_borrow_mut(|h| h.push(addr));
    Some(Held { guard, addr })
}

unsafe extern "C" {
    fn trol_weak_err_on_send() -> ErrOnFn;
    fn trol_weak_err_on_receive() -> ErrOnFn;
    fn trol_weak_err_app_timeout() -> ErrAppTimeOutFn;
    fn trol_weak_fatal_error() -> FatalErrorFn;
}

impl Callbacks {
    /// The handlers in force: one installed with a TROLSet* setter, else one the application
    /// defines under the manual's name (csrc/callbacks.c), else none (TROL's default).
    fn resolved(self) -> Callbacks {
        // SAFETY: the C functions return the address of a weak symbol, or NULL.
        unsafe {
            Callbacks {
                on_send: self.on_send.or_else(|| trol_weak_err_on_send()),
                on_receive: self.on_receive.or_else(|| trol_weak_err_on_receive()),
                app_timeout: self.app_timeout.or_else(|| trol_weak_err_app_timeout()),
                fatal: self.fatal.or_else(|| trol_weak_fatal_error()),
            }
        }
    }
}

thread_local! {
    /// The line of the transaction whose error handler runs on this thread, so that the
    /// handler's SendData, ReceiveData, BufferEmpty and FlushBuffer use it.
    static LINE: Cell<Option<*mut (dyn Channel + 'static)>> = const { Cell::new(None) };
    /// What ReceiveData received last on this thread (`out->data` points here).
    static RECEIVED: RefCell<Vec<u8>> = const { RefCell::new(Vec::new()) };
    /// What TransSR received last on this thread (`resp->data` points here).
    static REPLY: RefCell<Vec<u8>> = const { RefCell::new(Vec::new()) };
}

/// Run `f` (a C handler) with `line` reachable by the layer-1/2 functions.
fn with_line<R>(line: &mut dyn Channel, f: impl FnOnce() -> R) -> R {
    let ptr: *mut (dyn Channel + '_) = line;
    // SAFETY: only the lifetime is erased; the pointer is set only while `f` runs on this
    // thread, and `line` stays mutably borrowed by us (unused) all that time.
    let ptr: *mut (dyn Channel + 'static) = unsafe { std::mem::transmute(ptr) };
    let previous = LINE.replace(Some(ptr));
    let r = f();
    LINE.set(previous);
    r
}

/// Use the line: the one of the handler running on this thread, else the connection's.
fn on_line<R>(f: impl FnOnce(&mut dyn Channel) -> R) -> Option<R> {
    if let Some(ptr) = LINE.get() {
        // SAFETY: set by `with_line` for the duration of a handler call on this thread.
        return Some(f(unsafe { &mut *ptr }));
    }
    let mut st = state();
    let robot = st.robot.as_mut()?;
    let mut line = robot.channel();
    Some(f(&mut line))
}

/// The layer-3 handlers that call the application's C functions.
/// The C error handlers of a connection, and the reply-wait policy of the commands it knows
/// (built-in and added), for the default ErrAppTimeOut.
struct CHandlers(Callbacks, trol_comm::TimeoutPolicy);

impl CHandlers {
    fn of(callbacks: Callbacks, robot: &Robot) -> CHandlers {
        CHandlers(callbacks, robot.timeout_policy())
    }
}

fn message_for_c(bytes: &[u8]) -> (Vec<u8>, SInData) {
    let mut copy = bytes.to_vec();
    let data = SInData {
        numBytes: copy.len() as TUINT,
        data: copy.as_mut_ptr(),
    };
    (copy, data)
}

impl ErrorHandlers for CHandlers {
    fn err_on_send_on(&mut self, ctx: &FailureContext<'_>, line: &mut dyn Channel) -> Recovery {
        note_comm(Some(ctx.error));
        let Some(f) = self.0.resolved().on_send else {
            return Recovery::Fail;
        };
        let (_keep, mut data) = message_for_c(ctx.message);
        let mut pci = ctx.pci;
        // SAFETY: the application's handler gets pointers to live locals.
        match with_line(line, || unsafe { f(&mut data, &mut pci) }) {
            RECOVERY_SUCCESS => Recovery::Success,
            // The application decided: the call ends, nothing is sent again.
            _ => Recovery::Abort,
        }
    }
    fn err_on_receive_on(&mut self, ctx: &FailureContext<'_>, line: &mut dyn Channel) -> Recovery {
        note_comm(Some(ctx.error));
        let Some(f) = self.0.resolved().on_receive else {
            return Recovery::Fail;
        };
        let mut out = SInData {
            numBytes: 0,
            data: std::ptr::null_mut(),
        };
        let mut pci = ctx.pci;
        // SAFETY: as above.
        match with_line(line, || unsafe { f(&mut out, &mut pci) }) {
            // The manual: with RECOVERY_SUCCESS, *out holds the message received.
            RECOVERY_SUCCESS if !out.data.is_null() => {
                // SAFETY: the handler points `out` at numBytes readable bytes (ReceiveData's
                // buffer, or its own).
                let message =
                    unsafe { std::slice::from_raw_parts(out.data, out.numBytes as usize) }.to_vec();
                Recovery::Received { pci, message }
            }
            RECOVERY_SUCCESS => Recovery::Success,
            // The application decided: the call ends, nothing is sent again.
            _ => Recovery::Abort,
        }
    }
    fn err_app_timeout_on(
        &mut self,
        ctx: &AppTimeoutContext<'_>,
        line: &mut dyn Channel,
    ) -> TimeoutAction {
        match self.0.resolved().app_timeout {
            None => DefaultHandlers::app_timeout(Some(&self.1), ctx),
            Some(f) => {
                let (_keep, mut data) = message_for_c(ctx.request);
                // SAFETY: as above.
                match with_line(line, || unsafe { f(&mut data) }) {
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

/// Call a described command; errors other than TROL_ERR_ARG_RANGE go through FatalError.
/// `read` gets the reply of a successful call.
fn run(
    def: &'static CommandDef,
    build: impl FnOnce() -> Result<Vec<Value>, TINT>,
    read: impl FnOnce(Reply),
) -> TINT {
    guard(COMM, || {
        // GetLastCommErr speaks of this call from now on, even if it never reaches the line.
        note_comm(None);
        let args = match build() {
            Ok(a) => a,
            Err(code) => return code,
        };
        let (result, fatal) = {
            let Some(mut st) = state_for_call() else {
                return COMM;
            };
            let fatal = st.callbacks.resolved().fatal;
            let Some(robot) = st.robot.as_mut() else {
                not_connected(def.name);
                return fatal_or(fatal, def.code, NOT_INIT);
            };
            let r = robot.call(def, &args);
            note_comm(robot.last_comm_error());
            (r, fatal)
        };
        match result {
            Ok(reply) => {
                let v = reply.value().0;
                read(reply);
                v
            }
            Err(Error::Argument(_)) => ARG_RANGE,
            Err(e) => fatal_or(fatal, def.code, e.code().0),
        }
    })
}

/// A call with no connection (before InitTROL, after CleanupTROL, or on a handle not
/// connected): TROL_ERR_NOT_INIT, and once per process a line on stderr that says why.
fn not_connected(command: &str) {
    static SAID: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);
    if !SAID.swap(true, Ordering::Relaxed) {
        use std::io::Write;
        let _ = writeln!(
            std::io::stderr(),
            "TROL: {command} called with no connection (before InitTROL, or after \
             CleanupTROL): nothing was sent; it returns TROL_ERR_NOT_INIT"
        );
    }
}

fn fatal_or(fatal: FatalErrorFn, command: u8, code: TINT) -> TINT {
    match fatal {
        // SAFETY: the application's handler, called with plain values.
        Some(f) => unsafe { f(command as TUINT, code) },
        None => code,
    }
}

/// Read a location from C, with the tags `allowed`.
unsafe fn location(p: *const SLocData, allowed: &[Tag]) -> Result<Location, TINT> {
    if p.is_null() {
        return Err(ARG_RANGE);
    }
    // SAFETY: the caller passes a valid SLocData; it is read unaligned (packed).
    let loc = unsafe { std::ptr::read_unaligned(p) };
    let tag = Tag::from_u8(loc.tag)
        .filter(|t| allowed.contains(t))
        .ok_or(ARG_RANGE)?;
    let n = loc.numDims as usize;
    if !(1..=8).contains(&n) {
        return Err(ARG_RANGE);
    }
    let data = loc.data;
    let words = &data[..n];
    let real = |w: &u32| f64::from(f32::from_bits(*w));
    Ok(match tag {
        Tag::Prec => Location::Prec(words.iter().map(|w| *w as i32).collect()),
        Tag::Joint => Location::Joint(words.iter().map(real).collect()),
        Tag::Cart => Location::Cart(words.iter().map(real).collect()),
    })
}

/// A location argument: an SLocData of one of `allowed`'s tags.
unsafe fn loc_arg(p: *const SLocData, allowed: &[Tag]) -> Result<Value, TINT> {
    unsafe { location(p, allowed) }.map(Value::Loc)
}

unsafe fn name(p: *const TUCHAR) -> Result<Value, TINT> {
    if p.is_null() {
        return Err(ARG_RANGE);
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
    LocName::from_bytes(&raw)
        .map(Value::Name)
        .map_err(|_| ARG_RANGE)
}

fn byte(v: TUINT) -> Result<Value, TINT> {
    u8::try_from(v).map(Value::Int).map_err(|_| ARG_RANGE)
}

const CART: &[Tag] = &[Tag::Cart];
const TARGET: &[Tag] = &[Tag::Cart, Tag::Prec];
const JOINT: &[Tag] = &[Tag::Joint];

/// TROLAppro.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLAppro(
    locName: *const TUCHAR,
    pDisp: *const SLocData,
    straight: TUINT,
) -> TINT {
    run(
        &table::APPRO,
        || {
            Ok(vec![
                unsafe { name(locName) }?,
                unsafe { loc_arg(pDisp, CART) }?,
                Value::Flag(straight != 0),
            ])
        },
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
        &table::APPRO_II,
        || {
            Ok(vec![
                unsafe { loc_arg(pTarget, TARGET) }?,
                unsafe { loc_arg(pDisp, CART) }?,
                Value::Flag(straight != 0),
            ])
        },
        drop,
    )
}

/// TROLClose.
#[unsafe(no_mangle)]
pub extern "C" fn TROLClose(perForce: TUINT) -> TINT {
    run(&table::CLOSE, || Ok(vec![byte(perForce)?]), drop)
}

/// TROLDepart.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLDepart(pDisp: *const SLocData, straight: TUINT) -> TINT {
    run(
        &table::DEPART,
        || {
            Ok(vec![
                unsafe { loc_arg(pDisp, CART) }?,
                Value::Flag(straight != 0),
            ])
        },
        drop,
    )
}

/// TROLFinish: FINISH_STATUS (0) returns 1 while moving, FINISH_WAIT (1) waits.
#[unsafe(no_mangle)]
pub extern "C" fn TROLFinish(mode: TUINT) -> TINT {
    if mode == TUINT::from(FINISH_WAIT) {
        return wait_idle();
    }
    run(&table::FINISH, || Ok(vec![byte(mode)?]), drop)
}

/// Wait until the arm is done by polling FINISH_STATUS, the connection free between two polls
/// (another thread's TROLHalt gets through; a dead controller is noticed within a link
/// timeout). Returns 0, or the failed poll's code.
fn wait_idle() -> TINT {
    // Bounded as the manual's one long request was: after SetL3_TO_Intervall the
    // connection's ErrAppTimeOut decides (the default grants FINISH_WAIT no limit).
    let mut wait = {
        let Some(st) = state_for_call() else {
            return COMM;
        };
        match st.robot.as_ref() {
            Some(r) => r.finish_wait(),
            None => return run(&table::FINISH, || Ok(vec![Value::Int(FINISH_STATUS)]), drop),
        }
    };
    loop {
        let status = FINISH_STATUS;
        match run(&table::FINISH, || Ok(vec![Value::Int(status)]), drop) {
            1 => {
                let (checked, fatal) = {
                    let Some(mut st) = state_for_call() else {
                        return COMM;
                    };
                    let fatal = st.callbacks.resolved().fatal;
                    let Some(robot) = st.robot.as_mut() else {
                        return NOT_INIT;
                    };
                    (wait.check(robot), fatal)
                };
                if let Err(e) = checked {
                    return fatal_or(fatal, table::FINISH.code, e.code().0);
                }
                std::thread::sleep(trol_client::POLL)
            }
            code => return code,
        }
    }
}

/// TROLGrip.
#[unsafe(no_mangle)]
pub extern "C" fn TROLGrip(dist: TUINT) -> TINT {
    run(&table::GRIP, || Ok(vec![byte(dist)?]), drop)
}

/// TROLHalt.
#[unsafe(no_mangle)]
pub extern "C" fn TROLHalt() -> TINT {
    run(&table::HALT, || Ok(vec![]), drop)
}

/// TROLHome.
#[unsafe(no_mangle)]
pub extern "C" fn TROLHome(axis: TUINT) -> TINT {
    // Returns when homing is done, waiting as TROLFinish(FINISH_WAIT) does.
    match run(&table::HOME, || Ok(vec![byte(axis)?]), drop) {
        0 => wait_idle(),
        code => code,
    }
}

/// TROLJog.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLJog(pDisp: *const SLocData, straight: TUINT) -> TINT {
    run(
        &table::JOG,
        || {
            Ok(vec![
                unsafe { loc_arg(pDisp, CART) }?,
                Value::Flag(straight != 0),
            ])
        },
        drop,
    )
}

/// TROLJoint.
#[unsafe(no_mangle)]
pub extern "C" fn TROLJoint(jointNum: TUINT, radians: f32) -> TINT {
    run(
        &table::JOINT,
        || Ok(vec![byte(jointNum)?, Value::Real(f64::from(radians))]),
        drop,
    )
}

/// TROLMA.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLMA(pTarget: *const SLocData) -> TINT {
    run(
        &table::MA,
        || Ok(vec![unsafe { loc_arg(pTarget, JOINT) }?]),
        drop,
    )
}

/// TROLMI.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLMI(pDisp: *const SLocData) -> TINT {
    run(
        &table::MI,
        || Ok(vec![unsafe { loc_arg(pDisp, JOINT) }?]),
        drop,
    )
}

/// TROLMove.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLMove(locName: *const TUCHAR, straight: TUINT) -> TINT {
    run(
        &table::MOVE,
        || Ok(vec![unsafe { name(locName) }?, Value::Flag(straight != 0)]),
        drop,
    )
}

/// TROLMoveII.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLMoveII(pTarget: *const SLocData, straight: TUINT) -> TINT {
    run(
        &table::MOVE_II,
        || {
            Ok(vec![
                unsafe { loc_arg(pTarget, TARGET) }?,
                Value::Flag(straight != 0),
            ])
        },
        drop,
    )
}

/// TROLOpen.
#[unsafe(no_mangle)]
pub extern "C" fn TROLOpen(perForce: TUINT) -> TINT {
    run(&table::OPEN, || Ok(vec![byte(perForce)?]), drop)
}

/// TROLReady.
#[unsafe(no_mangle)]
pub extern "C" fn TROLReady() -> TINT {
    run(&table::READY, || Ok(vec![]), drop)
}

/// TROLSetToolTransform.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLSetToolTransform(md: *const SLocData) -> TINT {
    run(
        &table::SET_TOOL_TRANSFORM,
        || Ok(vec![unsafe { loc_arg(md, CART) }?]),
        drop,
    )
}

/// TROLSpeed.
#[unsafe(no_mangle)]
pub extern "C" fn TROLSpeed(perMaxSpeed: TUINT) -> TINT {
    run(&table::SPEED, || Ok(vec![byte(perMaxSpeed)?]), drop)
}

/// TROLGetPosition: the form is read from pos->tag; mode POS_COMMANDED (0) or POS_ACT (1).
/// A reply in another form than asked for is TROL_ERR_BAD_RSIZE, and *pos is left alone.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLGetPosition(pos: *mut SLocData, mode: TINT) -> TINT {
    if pos.is_null() {
        return ARG_RANGE;
    }
    // SAFETY: a valid SLocData from the caller.
    let tag_byte = unsafe { std::ptr::read_unaligned(pos) }.tag;
    let mut out = None;
    let r = run(
        &table::GET_POSITION,
        || {
            let mode = match mode {
                0 => POS_COMMANDED,
                1 => POS_ACT,
                _ => return Err(ARG_RANGE),
            };
            Ok(vec![Value::Int(tag_byte), Value::Int(mode)])
        },
        |reply| {
            if let Reply::Position(loc) = reply {
                out = Some(loc);
            }
        },
    );
    match out {
        Some(loc) if loc.tag() as u8 == tag_byte => {
            // SAFETY: as above.
            unsafe { std::ptr::write_unaligned(pos, sloc(&loc)) };
            r
        }
        Some(_) => trol_proto::application::code::TROL_ERR_BAD_RSIZE.0,
        None => r,
    }
}

/// A location as the C API's SLocData.
fn sloc(loc: &Location) -> SLocData {
    let mut data = [0u32; 8];
    let n = loc.num_dims().min(8);
    match loc {
        Location::Prec(v) => v
            .iter()
            .take(8)
            .enumerate()
            .for_each(|(i, x)| data[i] = *x as u32),
        Location::Joint(v) | Location::Cart(v) => v
            .iter()
            .take(8)
            .enumerate()
            .for_each(|(i, x)| data[i] = (*x as f32).to_bits()),
    }
    SLocData {
        tag: loc.tag() as u8,
        numDims: n as u8,
        data,
    }
}

/// A precision point's name starts with '#', and only a precision point's: else
/// TROL_ERR_ARG_RANGE before anything is sent (docs/teach.md).
fn precision_name(name: &Value, tag: u8) -> Result<(), TINT> {
    match name {
        Value::Name(n) if n.is_precision() == (tag == Tag::Prec as u8) => Ok(()),
        _ => Err(ARG_RANGE),
    }
}

const ANY_FORM: &[Tag] = &[Tag::Cart, Tag::Joint, Tag::Prec];

/// TROLHere (added, docs/teach.md): store where the arm is (commanded) under locName, in the
/// form pos (POS_CART, POS_JOINT, or POS_PREC for a name starting with '#').
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLHere(locName: *const TUCHAR, pos: TINT) -> TINT {
    run(
        &table::HERE,
        || {
            let n = unsafe { name(locName) }?;
            let tag = u8::try_from(pos)
                .ok()
                .filter(|t| Tag::from_u8(*t).is_some())
                .ok_or(ARG_RANGE)?;
            precision_name(&n, tag)?;
            Ok(vec![n, Value::Int(tag)])
        },
        drop,
    )
}

/// TROLDefine (added, docs/teach.md): store *pLoc (six values: POS_CART, POS_JOINT or
/// POS_PREC, whose name starts with '#') under locName.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLDefine(locName: *const TUCHAR, pLoc: *const SLocData) -> TINT {
    run(
        &table::DEFINE,
        || {
            let n = unsafe { name(locName) }?;
            let loc = unsafe { loc_arg(pLoc, ANY_FORM) }?;
            let Value::Loc(l) = &loc else {
                return Err(ARG_RANGE);
            };
            precision_name(&n, l.tag() as u8)?;
            Ok(vec![n, loc])
        },
        drop,
    )
}

/// TROLDeleteLocation (added, docs/teach.md): forget locName (TROL_ERR_LOCATION if there is
/// none).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLDeleteLocation(locName: *const TUCHAR) -> TINT {
    run(
        &table::DELETE_LOCATION,
        || Ok(vec![unsafe { name(locName) }?]),
        drop,
    )
}

/// TROLSaveLocations (added, docs/teach.md): keep the table across a restart.
#[unsafe(no_mangle)]
pub extern "C" fn TROLSaveLocations() -> TINT {
    run(&table::SAVE_LOCATIONS, || Ok(vec![]), drop)
}

/// TROLListLocations (added, docs/teach.md): up to `max` of the controller's locations,
/// sorted by name, their names into `names` (each NUL-padded to 8 bytes, as TLocName) and
/// their values into `locs`; how many there are into *count (which may be more than `max`).
/// `names` and `locs` may be NULL only with `max` 0 (to ask the count); a NULL count is
/// TROL_ERR_ARG_RANGE, and nothing is sent.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLListLocations(
    names: *mut [TUCHAR; 8],
    locs: *mut SLocData,
    max: TUINT,
    count: *mut TUINT,
) -> TINT {
    if count.is_null() || (max > 0 && (names.is_null() || locs.is_null())) {
        return ARG_RANGE;
    }
    let mut got = None;
    let r = run(
        &table::LIST_LOCATIONS,
        || Ok(vec![]),
        |reply| {
            if let Reply::Locations(all) = reply {
                got = Some(all);
            }
        },
    );
    if let Some(all) = got {
        // SAFETY: the caller's TUINT, and arrays of `max` TLocNames and SLocDatas.
        unsafe {
            *count = TUINT::try_from(all.len()).unwrap_or(TUINT::MAX);
            for (i, (n, l)) in all.iter().take(usize::from(max)).enumerate() {
                let mut padded = [0u8; 8];
                let text = n.as_str().as_bytes();
                padded[..text.len()].copy_from_slice(text);
                std::ptr::write_unaligned(names.add(i), padded);
                std::ptr::write_unaligned(locs.add(i), sloc(l));
            }
        }
    }
    r
}

/// TROLTerminatePCP.
#[unsafe(no_mangle)]
pub extern "C" fn TROLTerminatePCP() -> TINT {
    run(&table::TERMINATE_PCP, || Ok(vec![]), drop)
}

/// TROLGetStatus: 1 if the last CAT1/CAT2 command called the BIOS (its value in
/// *lastBIOSRetVal), 0 if not (the TROL code why in *lastBIOSRetVal). NULL is
/// TROL_ERR_ARG_RANGE, and nothing is sent.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLGetStatus(lastBIOSRetVal: *mut std::ffi::c_int) -> TINT {
    if lastBIOSRetVal.is_null() {
        return ARG_RANGE;
    }
    let mut last = None;
    let r = run(
        &table::GET_STATUS,
        || Ok(vec![]),
        |reply| {
            if let Reply::Status { last: l, .. } = reply {
                last = Some(l);
            }
        },
    );
    if let Some(l) = last {
        // SAFETY: the caller's int.
        unsafe { *lastBIOSRetVal = std::ffi::c_int::from(l.0) };
    }
    r
}

/// TROLGetStatusOf: TROLGetStatus, and which transaction the status belongs to (*transaction)
/// and the controller's epoch (*epoch; it changes when the controller restarts). The manual's
/// method after a failed call: read TROLLastTransaction() first, then call this; if
/// *transaction is that number, the status is the failed call's (1: it ran). Any pointer may
/// be NULL except lastBIOSRetVal (TROL_ERR_ARG_RANGE, nothing sent).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLGetStatusOf(
    lastBIOSRetVal: *mut std::ffi::c_int,
    transaction: *mut TUINT,
    epoch: *mut TUINT,
) -> TINT {
    if lastBIOSRetVal.is_null() {
        return ARG_RANGE;
    }
    let mut got = None;
    let r = run(
        &table::GET_STATUS,
        || Ok(vec![]),
        |reply| {
            if let Reply::Status {
                last,
                transaction,
                epoch,
                ..
            } = reply
            {
                got = Some((last, transaction, epoch));
            }
        },
    );
    if let Some((l, t, e)) = got {
        // SAFETY: the caller's variables, each checked for NULL.
        unsafe {
            *lastBIOSRetVal = std::ffi::c_int::from(l.0);
            if !transaction.is_null() {
                *transaction = TUINT::from(t);
            }
            if !epoch.is_null() {
                *epoch = TUINT::from(e);
            }
        }
    }
    r
}

/// TROLLastTransaction: the number of the last request this host sent (0..255; 0 before the
/// first), to compare with TROLGetStatusOf's *transaction after a failed call.
#[unsafe(no_mangle)]
pub extern "C" fn TROLLastTransaction() -> TUINT {
    guard(0, || {
        state()
            .robot
            .as_ref()
            .map_or(0, |r| TUINT::from(r.last_transaction()))
    })
}

/// TROLGetVersion: the controller's protocol version in *protocol and its kind in `kind`
/// (at most kindSize - 1 bytes and a NUL). A NULL pointer or a kindSize of 0 is
/// TROL_ERR_ARG_RANGE, and nothing is sent.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLGetVersion(
    protocol: *mut TUINT,
    kind: *mut std::ffi::c_char,
    kindSize: TUINT,
) -> TINT {
    if protocol.is_null() || kind.is_null() || kindSize == 0 {
        return ARG_RANGE;
    }
    let mut got = None;
    let r = run(
        &table::GET_VERSION,
        || Ok(vec![]),
        |reply| {
            if let Reply::Version { protocol, kind } = reply {
                got = Some((protocol, kind));
            }
        },
    );
    if let Some((p, k)) = got {
        let n = k.len().min(usize::from(kindSize) - 1);
        // SAFETY: the caller's TUINT and a buffer of kindSize bytes.
        unsafe {
            *protocol = p;
            std::ptr::copy_nonoverlapping(k.as_ptr(), kind.cast::<u8>(), n);
            *kind.add(n) = 0;
        }
    }
    r
}

/// TROLGetGripper: the fingers' opening in *openingMm and what they hold in *held
/// (GRIPPER_EMPTY, GRIPPER_HOLDS, GRIPPER_UNKNOWN when the controller cannot tell); with
/// GRIPPER_HOLDS, the object's name in `name` (at most nameSize - 1 bytes and a NUL; empty
/// when the controller knows no name). `name` may be NULL (with nameSize 0); a NULL
/// openingMm or held is TROL_ERR_ARG_RANGE, and nothing is sent.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLGetGripper(
    openingMm: *mut f32,
    held: *mut TINT,
    name: *mut std::ffi::c_char,
    nameSize: TUINT,
) -> TINT {
    if openingMm.is_null() || held.is_null() || (name.is_null() && nameSize > 0) {
        return ARG_RANGE;
    }
    let mut got = None;
    let r = run(
        &table::GET_GRIPPER,
        || Ok(vec![]),
        |reply| {
            if let Reply::Gripper(g) = reply {
                got = Some(g);
            }
        },
    );
    if let Some(g) = got {
        use trol_proto::application::Held;
        let (kind, object) = match &g.held {
            Held::Nothing => (0, ""),
            Held::Object(n) => (1, n.as_str()),
            _ => (2, ""),
        };
        // SAFETY: the caller's float and TINT, and a buffer of nameSize bytes (or NULL).
        unsafe {
            *openingMm = g.opening_mm as f32;
            *held = kind;
            if !name.is_null() && nameSize > 0 {
                let n = object.len().min(usize::from(nameSize) - 1);
                std::ptr::copy_nonoverlapping(object.as_ptr(), name.cast::<u8>(), n);
                *name.add(n) = 0;
            }
        }
    }
    r
}

/// TROLGetCodes: the controller's BIOS codes (docs/protocol.md, "Codes"): up to `max` of
/// their values into `values`, how many it has into *count (which may be more than `max`);
/// trol_strerror names each as that controller does. A NULL pointer is TROL_ERR_ARG_RANGE,
/// and nothing is sent.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLGetCodes(values: *mut TINT, max: TUINT, count: *mut TUINT) -> TINT {
    if values.is_null() || count.is_null() {
        return ARG_RANGE;
    }
    let mut got = None;
    let r = run(
        &table::GET_CODES,
        || Ok(vec![]),
        |reply| {
            if let Reply::Codes(codes) = reply {
                got = Some(codes);
            }
        },
    );
    if let Some(codes) = got {
        // SAFETY: the caller's TUINT and an array of `max` TINTs.
        unsafe {
            *count = TUINT::try_from(codes.len()).unwrap_or(TUINT::MAX);
            for (i, c) in codes.iter().take(usize::from(max)).enumerate() {
                *values.add(i) = c.value;
            }
        }
    }
    r
}

/// TROLGetReplyTime: the longest the controller takes to answer a request, in seconds
/// (docs/protocol.md, "Reply time"), into *seconds; InitTROL and trol_connect read it, and
/// each call then waits that and a margin for its reply unless SetL3_TO_Intervall set the
/// reply timeout. A NULL pointer is TROL_ERR_ARG_RANGE, and nothing is sent.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLGetReplyTime(seconds: *mut f32) -> TINT {
    if seconds.is_null() {
        return ARG_RANGE;
    }
    let mut got = None;
    let r = run(
        &table::GET_REPLY_TIME,
        || Ok(vec![]),
        |reply| {
            if let Reply::Reals { values, .. } = reply {
                got = values.first().copied();
            }
        },
    );
    if let Some(t) = got {
        // SAFETY: the caller's float.
        unsafe { *seconds = t as f32 };
    }
    r
}

/// TROLSetWatchdog: the controller halts the arm when no call arrives for tenths/10 s
/// (1..250); 0 turns it off.
#[unsafe(no_mangle)]
pub extern "C" fn TROLSetWatchdog(tenths: TUINT) -> TINT {
    run(
        &table::SET_WATCHDOG,
        || {
            Ok(vec![Value::Int(
                u8::try_from(tenths).map_err(|_| ARG_RANGE)?,
            )])
        },
        drop,
    )
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
        let (callbacks, tenths, delay, repeats) = {
            let st = state();
            (st.callbacks, st.reply_tenths, st.delay, st.repeats)
        };
        if let Some(n) = repeats {
            robot.set_repeats(n);
        }
        // Both were checked when they were set.
        let _ = robot.set_reply_timeout_tenths(tenths);
        let _ = robot.set_delay(delay);
        let ok = if serOnly == 0 {
            trol_client::activate(&mut robot, &cfg.tool)
                .map_err(|e| eprintln!("InitTROL: {e}"))
                .is_ok()
        } else {
            trol_client::check_server(&mut robot)
                .map_err(|e| eprintln!("InitTROL: {e}"))
                .is_ok()
        };
        if !ok {
            return INITTROL_FAILURE;
        }
        if let Some(notice) = robot.take_notice()
            && trol_client::notice_due("InitTROL", &cfg.port, &notice)
        {
            eprintln!(
                "InitTROL: note: {notice} (said once for this port; TROL_VERBOSE=1 says it at \
                 every start)"
            );
        }
        // The application's handlers from now on: InitTROL's own probes (is a server there,
        // which version, which codes; the activation) are not the application's calls, and a
        // probe that fails is how InitTROL(0) finds a controller in terminal mode.
        let handlers = CHandlers::of(callbacks, &robot);
        robot.set_handlers(Box::new(handlers));
        *STATE.told.lock().unwrap_or_else(|p| p.into_inner()) = Some(robot.codes());
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

/// SetL3_TO_Intervall: the reply timeout in tenths of a second, 1..6000. The manual's
/// function returns nothing: a value out of range changes nothing and is reported on stderr.
#[unsafe(no_mangle)]
pub extern "C" fn SetL3_TO_Intervall(TO_Intervall: TUINT) {
    guard((), || {
        let tenths = TO_Intervall;
        if !(1..=trol_client::MAX_REPLY_TENTHS).contains(&tenths) {
            eprintln!("SetL3_TO_Intervall({TO_Intervall}): out of range 1..6000, ignored");
            return;
        }
        let mut st = state();
        st.reply_tenths = tenths;
        if let Some(r) = st.robot.as_mut() {
            let _ = r.set_reply_timeout_tenths(tenths);
        }
    })
}

/// TROLSetRepeats: how often a request whose reply was lost is sent again, marked REPEAT, so
/// that it runs exactly once (docs/protocol.md, "Exactly once"); 0..10. Without this call, 2
/// for a controller whose version handshake announced its memory of the last request, and 0
/// for one that speaks only the manual's protocol. 0 is the manual's behaviour: the call
/// fails, and the application decides with TROLGetStatus. An
/// error handler of the application's that returns RECOVERY_FAIL ends the call without a
/// repeat whatever this says. A value out of range changes nothing and is reported on stderr.
#[unsafe(no_mangle)]
pub extern "C" fn TROLSetRepeats(repeats: TUINT) {
    guard((), || {
        if repeats > 10 {
            eprintln!("TROLSetRepeats({repeats}): out of range 0..10, ignored");
            return;
        }
        let n = repeats as u8;
        let mut st = state();
        st.repeats = Some(n);
        if let Some(r) = st.robot.as_mut() {
            r.set_repeats(n);
        }
    })
}

/// SetDelay: a pause of `delay` milliseconds between two bytes sent, 0..50; every timeout
/// grows with it. A value out of range changes nothing and is reported on stderr.
#[unsafe(no_mangle)]
pub extern "C" fn SetDelay(delay: TUINT) {
    guard((), || {
        if u64::from(delay) > trol_client::MAX_DELAY_MS {
            eprintln!("SetDelay({delay}): out of range 0..50 ms, ignored");
            return;
        }
        let mut st = state();
        let delay = Duration::from_millis(u64::from(delay));
        st.delay = delay;
        if let Some(r) = st.robot.as_mut() {
            let _ = r.set_delay(delay);
        }
    })
}

/// Bytes a C caller hands over in an SInData.
unsafe fn bytes_of<'a>(p: *const SInData) -> Option<&'a [u8]> {
    if p.is_null() {
        return None;
    }
    // SAFETY: the caller's SInData.
    let m = unsafe { &*p };
    if m.data.is_null() {
        return (m.numBytes == 0).then_some(&[]);
    }
    // SAFETY: numBytes readable bytes at data, as SInData promises.
    Some(unsafe { std::slice::from_raw_parts(m.data, m.numBytes as usize) })
}

/// Point `out` at `bytes` kept in `cell` until the next call of the same kind on this thread.
unsafe fn hand_out(
    cell: &'static std::thread::LocalKey<RefCell<Vec<u8>>>,
    bytes: Vec<u8>,
    out: *mut SInData,
) {
    cell.with(|c| {
        let mut buf = c.borrow_mut();
        *buf = bytes;
        // SAFETY: the caller's SInData.
        unsafe {
            (*out).numBytes = buf.len() as TUINT;
            (*out).data = buf.as_mut_ptr();
        }
    });
}

/// TransSR (layer 3): send the request `*req` and receive the reply into `*resp` (its data
/// stays valid until the next TransSR on this thread). Returns TRANS_SUCCESS, TRANS_ERR_SEND,
/// TRANS_ERR_RECEIVE or TRANS_TIMEOUT, after the error handlers had their say; for any command,
/// of any class, added or built in.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TransSR(req: *mut SInData, resp: *mut SInData) -> TUINT {
    guard(TransCode::ErrSend as TUINT, || {
        note_comm(None);
        // TRANS_ERR_SEND: nothing was sent (the manual's codes have no other for it); the
        // reason on stderr.
        let Some(request) = (unsafe { bytes_of(req) }) else {
            eprintln!("TransSR: req is NULL (or its data): nothing sent");
            return TransCode::ErrSend as TUINT;
        };
        if resp.is_null() {
            eprintln!("TransSR: resp is NULL: nothing sent");
            return TransCode::ErrSend as TUINT;
        }
        let result = {
            let Some(mut st) = state_for_call() else {
                return TransCode::ErrSend as TUINT;
            };
            let Some(robot) = st.robot.as_mut() else {
                return TransCode::ErrSend as TUINT;
            };
            let r = robot.transact_raw(request);
            note_comm(robot.last_comm_error());
            r
        };
        match result {
            Ok(reply) => {
                unsafe { hand_out(&REPLY, reply, resp) };
                TransCode::Success as TUINT
            }
            Err(Error::Link { error, .. }) => error.code() as TUINT,
            Err(_) => TransCode::ErrSend as TUINT,
        }
    })
}

/// Cat1Transaction (send.h): send the CAT1 request `*req` and return its reply's value, as
/// the built-in API functions do: errors, and values its description does not count as
/// success, go through FatalError.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn Cat1Transaction(req: *mut SInData) -> TINT {
    guard(COMM, || {
        note_comm(None);
        let Some(request) = (unsafe { bytes_of(req) }) else {
            return ARG_RANGE;
        };
        let Some(&code) = request.first() else {
            return ARG_RANGE;
        };
        let (result, fatal) = {
            let Some(mut st) = state_for_call() else {
                return COMM;
            };
            let fatal = st.callbacks.resolved().fatal;
            let Some(robot) = st.robot.as_mut() else {
                not_connected("Cat1Transaction");
                return fatal_or(fatal, code, NOT_INIT);
            };
            let r = robot.cat1_transaction(request);
            note_comm(robot.last_comm_error());
            (r, fatal)
        };
        match result {
            Ok(v) => v,
            Err(e) => fatal_or(fatal, code, e.code().0),
        }
    })
}

/// SendData (layer 2): send `*in` with `PCI`. 0, or the layer-2 code.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn SendData(in_: *mut SInData, PCI: TUINT) -> TUINT {
    guard(trol_comm::PORT_FAILED, || {
        let Some(message) = (unsafe { bytes_of(in_) }) else {
            return trol_comm::PORT_FAILED;
        };
        let code = on_line(|l| l.send_data(message, PCI)).unwrap_or(trol_comm::PORT_FAILED);
        if code != 0 {
            note_code(code, COMM_SIDE_SEND);
        }
        code
    })
}

/// ReceiveData (layer 2): receive a message into `*out` (its data stays valid until the next
/// ReceiveData on this thread) and its PCI into `*PCI`. 0, or the layer-2 code.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ReceiveData(out: *mut SInData, PCI: *mut TUINT) -> TUINT {
    guard(trol_comm::PORT_FAILED, || {
        // Both are the manual's outputs: a NULL one is refused at once (it used to wait
        // for a message it could not hand over).
        if out.is_null() || PCI.is_null() {
            eprintln!(
                "ReceiveData: {} is NULL: nothing received",
                if out.is_null() { "out" } else { "PCI" }
            );
            return trol_comm::PORT_FAILED;
        }
        match on_line(|l| l.receive_data()).unwrap_or(Err(trol_comm::PORT_FAILED)) {
            Ok((pci, message)) => {
                unsafe { hand_out(&RECEIVED, message, out) };
                if !PCI.is_null() {
                    // SAFETY: the caller's TUINT.
                    unsafe { *PCI = pci };
                }
                0
            }
            Err(code) => {
                note_code(code, COMM_SIDE_RECEIVE);
                code
            }
        }
    })
}

/// BufferEmpty (layer 1): 1 if no byte waits in the input, else 0. ErrAppTimeOut may look
/// with it for a waiting ENQ; it takes no byte.
#[unsafe(no_mangle)]
pub extern "C" fn BufferEmpty() -> TUINT {
    guard(1, || {
        TUINT::from(on_line(|l| l.buffer_empty()).unwrap_or(true))
    })
}

/// FlushBuffer (layer 1): drop the waiting input.
#[unsafe(no_mangle)]
pub extern "C" fn FlushBuffer() {
    guard((), || {
        on_line(|l| l.flush_buffer());
    })
}

/// GetLastCommErr: the layer-2 code of the last call's failure (NAK code in the high byte;
/// ERR_PORT 0x08 / 0x88 when the port itself failed), 0 if the last call had none. Handlers
/// may call it.
#[unsafe(no_mangle)]
pub extern "C" fn GetLastCommErr() -> TUINT {
    conn().last_err.load(Ordering::Relaxed)
}

/// GetLastCommSide (added): which service GetLastCommErr's failure belongs to:
/// COMM_SIDE_SEND (1, SendData), COMM_SIDE_RECEIVE (2, ReceiveData), or 0. The manual's
/// codes tell the side apart by the low byte's 0x80 bit, except ERR_LIMIT_EXCEEDED (0x07 on
/// both sides).
#[unsafe(no_mangle)]
pub extern "C" fn GetLastCommSide() -> TUINT {
    conn().last_side.load(Ordering::Relaxed)
}

fn set_callbacks(f: impl FnOnce(&mut Callbacks)) {
    guard((), || {
        let mut st = state();
        f(&mut st.callbacks);
        let cb = st.callbacks;
        if let Some(r) = st.robot.as_mut() {
            let handlers = CHandlers::of(cb, r);
            r.set_handlers(Box::new(handlers));
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

// ---------------------------------------------------------------------------------------
// Connections, libmodbus-style: `TROL *trol_connect(port, baud)`, `trol_disconnect`,
// `trol_strerror`, and `trol_name(TROL *, args)` for every manual function.

/// trol_connect_error_kind's kinds (trol.h): the Rust API's SetupError, for C.
pub const TROL_SETUP_NONE: std::ffi::c_int = 0;
/// The port could not be opened.
pub const TROL_SETUP_PORT: std::ffi::c_int = 1;
/// The port's name, an argument or a setting is wrong.
pub const TROL_SETUP_CONFIG: std::ffi::c_int = 2;
/// The controller's TROL server does not answer, or cannot be activated.
pub const TROL_SETUP_NO_SERVER: std::ffi::c_int = 3;
/// The controller speaks another protocol version (trol_connect_versions).
pub const TROL_SETUP_INCOMPATIBLE: std::ffi::c_int = 4;
/// Anything else (the text says what).
pub const TROL_SETUP_OTHER: std::ffi::c_int = 5;

/// Why the last trol_connect on this thread failed: the text, the kind, and (for
/// TROL_SETUP_INCOMPATIBLE) this library's protocol version and the controller's.
#[derive(Default)]
struct ConnectError {
    text: std::ffi::CString,
    kind: std::ffi::c_int,
    versions: (u16, u16),
}

thread_local! {
    static CONNECT_ERROR: RefCell<ConnectError> = RefCell::new(ConnectError::default());
}

fn connect_failed(why: String, kind: std::ffi::c_int, versions: (u16, u16)) -> *mut TROL {
    let text = std::ffi::CString::new(why.replace('\0', " ")).unwrap_or_default();
    CONNECT_ERROR.with_borrow_mut(|e| {
        *e = ConnectError {
            text,
            kind,
            versions,
        }
    });
    std::ptr::null_mut()
}

/// Run `f` (a manual function) on connection `c`. NULL: `fallback`.
fn on_conn<R>(c: *mut TROL, fallback: R, f: impl FnOnce() -> R) -> R {
    if c.is_null() {
        return fallback;
    }
    // SAFETY: a handle from trol_connect, not yet given to trol_disconnect (the caller's
    // promise, as with every C handle); it lives in a Box until then.
    let conn: &'static TROL = unsafe { &*c };
    let previous = CONN.replace(Some(conn));
    let r = f();
    CONN.set(previous);
    r
}

/// trol_current: the connection whose call runs on this thread (in an error handler, the
/// connection of the call that failed), or NULL for the default connection (the manual's
/// functions) or outside any call. A handler shared by several connections tells them
/// apart by it (and by trol_get_user).
#[unsafe(no_mangle)]
pub extern "C" fn trol_current() -> *mut TROL {
    CONN.get()
        .map_or(std::ptr::null_mut(), |c| c as *const TROL as *mut TROL)
}

/// trol_set_user: keep the application's pointer `user` with connection `c` (NULL: the
/// default connection), for its handlers (trol_get_user(trol_current())).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn trol_set_user(c: *mut TROL, user: *mut std::ffi::c_void) {
    // SAFETY: a handle from trol_connect that the caller has not disconnected, or NULL.
    let c = unsafe { c.as_ref() }.unwrap_or(&STATE);
    c.user.store(user, Ordering::Relaxed);
}

/// trol_get_user: the pointer trol_set_user kept with connection `c` (NULL: the default
/// connection's); NULL if none.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn trol_get_user(c: *const TROL) -> *mut std::ffi::c_void {
    // SAFETY: as trol_set_user.
    let c = unsafe { c.as_ref() }.unwrap_or(&STATE);
    c.user.load(Ordering::Relaxed)
}

/// trol_connect: connect to the controller on `port` (as trol.cfg's second line names it:
/// a serial device, socket://HOST:PORT, `sim` for an embedded simulated A465, `rapl:DEVICE`)
/// at `baud`, and check it as InitTROL(1) does (one GetStatus, then the protocol version).
/// NULL on failure, with the reason from trol_connect_error().
#[unsafe(no_mangle)]
pub unsafe extern "C" fn trol_connect(port: *const std::ffi::c_char, baud: TLONG) -> *mut TROL {
    let fail = |why: String| connect_failed(why, TROL_SETUP_CONFIG, (0, 0));
    guard(std::ptr::null_mut(), || {
        if port.is_null() {
            return fail("trol_connect: the port is NULL".into());
        }
        // SAFETY: the caller's NUL-terminated string.
        let Ok(name) = unsafe { std::ffi::CStr::from_ptr(port) }.to_str() else {
            return fail("trol_connect: the port's name is not UTF-8".into());
        };
        let Ok(baud) = u32::try_from(baud) else {
            return fail(format!("trol_connect: baud rate {baud} is negative"));
        };
        // The one connect path every surface takes: open, GetStatus, GetVersion, GetCodes.
        let mut robot = match Robot::connect(name, baud) {
            Ok(r) => r,
            Err(e) => {
                use trol_client::SetupError as S;
                let (kind, versions) = match &e {
                    Error::Setup(S::Port(_)) => (TROL_SETUP_PORT, (0, 0)),
                    Error::Setup(S::Config(_)) => (TROL_SETUP_CONFIG, (0, 0)),
                    Error::Setup(S::NoServer(_)) => (TROL_SETUP_NO_SERVER, (0, 0)),
                    Error::Setup(S::Incompatible { ours, theirs, .. }) => {
                        (TROL_SETUP_INCOMPATIBLE, (*ours, theirs.unwrap_or(0)))
                    }
                    _ => (TROL_SETUP_OTHER, (0, 0)),
                };
                return connect_failed(format!("trol_connect({name}): {e}"), kind, versions);
            }
        };
        if let Some(notice) = robot.take_notice()
            && trol_client::notice_due("trol_connect", name, &notice)
        {
            eprintln!(
                "trol_connect({name}): note: {notice} (said once for this port; TROL_VERBOSE=1 \
                 says it at every start)"
            );
        }
        let fresh = FRESH;
        let handlers = CHandlers::of(fresh.callbacks, &robot);
        robot.set_handlers(Box::new(handlers));
        CONNECT_ERROR.with_borrow_mut(|e| *e = ConnectError::default());
        let c = TROL::fresh(State {
            robot: None,
            ..fresh
        });
        *c.told.lock().unwrap_or_else(|p| p.into_inner()) = Some(robot.codes());
        c.inner.lock().unwrap_or_else(|p| p.into_inner()).robot = Some(robot);
        Box::into_raw(Box::new(c))
    })
}

/// trol_connect_error: why the last trol_connect on this thread returned NULL (empty after a
/// success). Valid until the next trol_connect on this thread.
#[unsafe(no_mangle)]
pub extern "C" fn trol_connect_error() -> *const std::ffi::c_char {
    CONNECT_ERROR.with_borrow(|e| e.text.as_ptr())
}

/// trol_connect_error_kind: what kind of failure the last trol_connect on this thread met
/// (TROL_SETUP_NONE after a success): the Rust API's SetupError, typed for C.
#[unsafe(no_mangle)]
pub extern "C" fn trol_connect_error_kind() -> std::ffi::c_int {
    CONNECT_ERROR.with_borrow(|e| e.kind)
}

/// trol_connect_versions: after TROL_SETUP_INCOMPATIBLE, this library's protocol version and
/// the controller's (0 when it does not know TROLGetVersion); 0 and 0 otherwise. NULL
/// pointers are skipped.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn trol_connect_versions(ours: *mut TUINT, theirs: *mut TUINT) {
    let (o, t) = CONNECT_ERROR.with_borrow(|e| e.versions);
    // SAFETY: the caller's TUINTs, or NULL.
    unsafe {
        if !ours.is_null() {
            *ours = o;
        }
        if !theirs.is_null() {
            *theirs = t;
        }
    }
}

/// trol_disconnect: close the connection and free it (the controller's server stays in
/// server mode; trol_terminate_pcp ends it). NULL is ignored.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn trol_disconnect(c: *mut TROL) {
    if c.is_null() {
        return;
    }
    guard((), || {
        // SAFETY: a handle from trol_connect, given back once.
        drop(unsafe { Box::from_raw(c) });
    })
}

/// trol_strerror: a return code as text, "NAME: meaning": TROL's codes, and BIOS codes as the
/// controller names them: the controller of the connection whose call runs on this thread
/// (an error handler's), else the default connection's (after InitTROL; before it, the
/// simulated A465's; a code nobody named, by number). The string is static.
#[unsafe(no_mangle)]
pub extern "C" fn trol_strerror(code: std::ffi::c_int) -> *const std::ffi::c_char {
    strerror_of(conn(), code)
}

/// trol_strerror_for: trol_strerror with the BIOS codes of connection `c`'s controller (as
/// trol_connect read them); NULL: the default connection's. The string is static.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn trol_strerror_for(
    c: *const TROL,
    code: std::ffi::c_int,
) -> *const std::ffi::c_char {
    // SAFETY: a handle from trol_connect that the caller has not disconnected, or NULL.
    let c = unsafe { c.as_ref() }.unwrap_or(&STATE);
    strerror_of(c, code)
}

fn strerror_of(c: &TROL, code: std::ffi::c_int) -> *const std::ffi::c_char {
    type Texts = Vec<(std::ffi::c_int, usize, std::ffi::CString)>;
    static TEXTS: Mutex<Texts> = Mutex::new(Vec::new());
    guard(c"TROL_ERR_COMM".as_ptr(), || {
        let table = c
            .told
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .unwrap_or_else(trol_client::default_codes);
        let key = table.as_ptr() as usize;
        let mut texts = TEXTS.lock().unwrap_or_else(|p| p.into_inner());
        if let Some((_, _, t)) = texts.iter().find(|(c, k, _)| *c == code && *k == key) {
            return t.as_ptr();
        }
        let text = match i16::try_from(code) {
            Ok(v) => {
                let c = trol_proto::application::code::Code(v);
                match (c.name(table), c.meaning(table)) {
                    (Some(n), Some(m)) => format!("{n}: {m}"),
                    (Some(n), None) => n.to_string(),
                    _ if v == 0 => "success".to_string(),
                    _ => format!("code {v}: not one of TROL's (a controller's own BIOS code?)"),
                }
            }
            Err(_) => format!("code {code}: out of range for a TROL code"),
        };
        let text = std::ffi::CString::new(text).unwrap_or_default();
        texts.push((code, key, text));
        texts
            .last()
            .map_or(std::ptr::null(), |(_, _, t)| t.as_ptr())
    })
}

/// For every manual function `TROLName(args)` a `trol_name(TROL *c, args)`: the same call on
/// connection `c` (NULL: the fallback value, and nothing is sent).
macro_rules! per_connection {
    ($( fn $new:ident($($arg:ident : $ty:ty),*) -> $ret:ty = $old:ident else $fallback:expr; )*) => {
        $(
            #[doc = concat!("`", stringify!($old), "` on connection `c`.")]
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn $new(c: *mut TROL, $($arg: $ty),*) -> $ret {
                #[allow(unused_unsafe)]
                on_conn(c, $fallback, || unsafe { $old($($arg),*) })
            }
        )*
    };
}

per_connection! {
    fn trol_appro(locName: *const TUCHAR, pDisp: *const SLocData, straight: TUINT) -> TINT = TROLAppro else ARG_RANGE;
    fn trol_appro_ii(pTarget: *const SLocData, pDisp: *const SLocData, straight: TUINT) -> TINT = TROLApproII else ARG_RANGE;
    fn trol_close(perForce: TUINT) -> TINT = TROLClose else ARG_RANGE;
    fn trol_depart(pDisp: *const SLocData, straight: TUINT) -> TINT = TROLDepart else ARG_RANGE;
    fn trol_finish(mode: TUINT) -> TINT = TROLFinish else ARG_RANGE;
    fn trol_grip(dist: TUINT) -> TINT = TROLGrip else ARG_RANGE;
    fn trol_halt() -> TINT = TROLHalt else ARG_RANGE;
    fn trol_home(axis: TUINT) -> TINT = TROLHome else ARG_RANGE;
    fn trol_jog(pDisp: *const SLocData, straight: TUINT) -> TINT = TROLJog else ARG_RANGE;
    fn trol_joint(jointNum: TUINT, radians: f32) -> TINT = TROLJoint else ARG_RANGE;
    fn trol_ma(pTarget: *const SLocData) -> TINT = TROLMA else ARG_RANGE;
    fn trol_mi(pDisp: *const SLocData) -> TINT = TROLMI else ARG_RANGE;
    fn trol_move(locName: *const TUCHAR, straight: TUINT) -> TINT = TROLMove else ARG_RANGE;
    fn trol_move_ii(pTarget: *const SLocData, straight: TUINT) -> TINT = TROLMoveII else ARG_RANGE;
    fn trol_open(perForce: TUINT) -> TINT = TROLOpen else ARG_RANGE;
    fn trol_ready() -> TINT = TROLReady else ARG_RANGE;
    fn trol_set_tool_transform(md: *const SLocData) -> TINT = TROLSetToolTransform else ARG_RANGE;
    fn trol_speed(perMaxSpeed: TUINT) -> TINT = TROLSpeed else ARG_RANGE;
    fn trol_get_position(pos: *mut SLocData, mode: TINT) -> TINT = TROLGetPosition else ARG_RANGE;
    fn trol_terminate_pcp() -> TINT = TROLTerminatePCP else ARG_RANGE;
    fn trol_get_status(lastBIOSRetVal: *mut std::ffi::c_int) -> TINT = TROLGetStatus else ARG_RANGE;
    fn trol_get_status_of(lastBIOSRetVal: *mut std::ffi::c_int, transaction: *mut TUINT, epoch: *mut TUINT) -> TINT = TROLGetStatusOf else ARG_RANGE;
    fn trol_last_transaction() -> TUINT = TROLLastTransaction else 0;
    fn trol_get_version(protocol: *mut TUINT, kind: *mut std::ffi::c_char, kindSize: TUINT) -> TINT = TROLGetVersion else ARG_RANGE;
    fn trol_set_watchdog(tenths: TUINT) -> TINT = TROLSetWatchdog else ARG_RANGE;
    fn trol_get_codes(values: *mut TINT, max: TUINT, count: *mut TUINT) -> TINT = TROLGetCodes else ARG_RANGE;
    fn trol_get_last_comm_err() -> TUINT = GetLastCommErr else 0;
    fn trol_get_last_comm_side() -> TUINT = GetLastCommSide else 0;
    fn trol_get_reply_time(seconds: *mut f32) -> TINT = TROLGetReplyTime else ARG_RANGE;
    fn trol_here(locName: *const TUCHAR, pos: TINT) -> TINT = TROLHere else ARG_RANGE;
    fn trol_define(locName: *const TUCHAR, pLoc: *const SLocData) -> TINT = TROLDefine else ARG_RANGE;
    fn trol_delete_location(locName: *const TUCHAR) -> TINT = TROLDeleteLocation else ARG_RANGE;
    fn trol_save_locations() -> TINT = TROLSaveLocations else ARG_RANGE;
    fn trol_list_locations(names: *mut [TUCHAR; 8], locs: *mut SLocData, max: TUINT, count: *mut TUINT) -> TINT = TROLListLocations else ARG_RANGE;
    fn trol_get_gripper(openingMm: *mut f32, held: *mut TINT, name: *mut std::ffi::c_char, nameSize: TUINT) -> TINT = TROLGetGripper else ARG_RANGE;
    fn trol_set_reply_timeout(tenths: TUINT) -> () = SetL3_TO_Intervall else ();
    fn trol_set_repeats(repeats: TUINT) -> () = TROLSetRepeats else ();
    fn trol_set_delay(delay: TUINT) -> () = SetDelay else ();
    fn trol_trans_sr(req: *mut SInData, resp: *mut SInData) -> TUINT = TransSR else TransCode::ErrSend as TUINT;
    fn trol_cat1_transaction(req: *mut SInData) -> TINT = Cat1Transaction else ARG_RANGE;
    fn trol_set_err_on_send(handler: ErrOnFn) -> () = TROLSetErrOnSend else ();
    fn trol_set_err_on_receive(handler: ErrOnFn) -> () = TROLSetErrOnReceive else ();
    fn trol_set_err_app_timeout(handler: ErrAppTimeOutFn) -> () = TROLSetErrAppTimeOut else ();
    fn trol_set_fatal_error(handler: FatalErrorFn) -> () = TROLSetFatalError else ();
}

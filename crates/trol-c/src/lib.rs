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

/// STrajPoint (added, TROLTrajectory): when, in seconds from the trajectory's start, the
/// arm is to be at these six joint angles (radians).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct STrajPoint {
    /// Seconds after the start: 0 or more, increasing from point to point.
    pub time: f32,
    /// The joint angles, radians.
    pub joints: [f32; 6],
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
    /// SetL3_TO_Intervall's choice; `None`: the controller's reply time decides (TROL's
    /// controllers), or the manual's 15 s (a 1998 controller).
    reply_tenths: Option<u16>,
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
    reply_tenths: None,
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
    /// Why this connection's last call failed, in words (trol_last_error_text): outside the
    /// call's lock, as `told`.
    last_text: Mutex<Option<std::ffi::CString>>,
}

impl TROL {
    const fn fresh(state: State) -> TROL {
        TROL {
            inner: Mutex::new(state),
            last_err: AtomicU16::new(0),
            last_side: AtomicU16::new(0),
            told: Mutex::new(None),
            user: std::sync::atomic::AtomicPtr::new(std::ptr::null_mut()),
            last_text: Mutex::new(None),
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
            // What the controller logs from here on is this call's.
            robot.take_controller_said();
            let r = robot.call(def, &args);
            note_comm(robot.last_comm_error());
            if let Err(e) = &r {
                let said = robot.take_controller_said();
                set_last_text(if said.is_empty() {
                    e.to_string()
                } else {
                    format!("{e}; the controller said: {}", said.join(" | "))
                });
            }
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

/// Keep `text` as why this connection's last call failed (trol_last_error_text).
fn set_last_text(text: String) {
    let text = std::ffi::CString::new(text.replace('\0', " ")).unwrap_or_default();
    *conn().last_text.lock().unwrap_or_else(|p| p.into_inner()) = Some(text);
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

mod calls;
mod conn;
mod layers;
mod setup;

pub use calls::*;
pub use conn::*;
pub use layers::*;
pub use setup::*;

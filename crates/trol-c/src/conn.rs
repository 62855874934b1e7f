//! Connections, libmodbus-style: `TROL *trol_connect(port, baud)`, `trol_disconnect`,
//! `trol_strerror`, and `trol_name(TROL *, args)` for every manual function.

use super::*;

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
pub(crate) struct ConnectError {
    text: std::ffi::CString,
    kind: std::ffi::c_int,
    versions: (u16, u16),
}

thread_local! {
    static CONNECT_ERROR: RefCell<ConnectError> = RefCell::new(ConnectError::default());
}

pub(crate) fn connect_failed(
    why: String,
    kind: std::ffi::c_int,
    versions: (u16, u16),
) -> *mut TROL {
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
pub(crate) fn on_conn<R>(c: *mut TROL, fallback: R, f: impl FnOnce() -> R) -> R {
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

/// trol_last_error_text: why connection `c`'s last failed call failed, in words (NULL: the
/// default connection, the manual's functions'): the code's name and meaning, and what an
/// in-process controller's backend said about it (which profile key a BIOS_UNSETTLED needs,
/// what the controller printed). "" before any failure. The text lives until that
/// connection's next failed call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn trol_last_error_text(c: *const TROL) -> *const std::ffi::c_char {
    // SAFETY: a handle from trol_connect that the caller has not disconnected, or NULL.
    let c = unsafe { c.as_ref() }.unwrap_or(&STATE);
    guard(c"".as_ptr(), || {
        c.last_text
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .as_ref()
            .map_or(c"".as_ptr(), |t| t.as_ptr())
    })
}

pub(crate) fn strerror_of(c: &TROL, code: std::ffi::c_int) -> *const std::ffi::c_char {
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
    fn trol_trajectory(points: *const STrajPoint, count: TUINT) -> TINT = TROLTrajectory else ARG_RANGE;
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

//! The manual's lower layers for a program of its own: TransSR, Cat1Transaction,
//! SendData and ReceiveData, the buffer and the last comm error, and the error handlers.

use super::*;

/// Bytes a C caller hands over in an SInData.
pub(crate) unsafe fn bytes_of<'a>(p: *const SInData) -> Option<&'a [u8]> {
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
pub(crate) unsafe fn hand_out(
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

pub(crate) fn set_callbacks(f: impl FnOnce(&mut Callbacks)) {
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

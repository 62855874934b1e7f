//! The manual's calls (TROLAppro ... TROLGetStatus) and the added ones (TROLGetVersion,
//! TROLGetCodes, TROLGetReplyTime, TROLSetWatchdog), on the current connection.

use super::*;

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
pub(crate) fn wait_idle() -> TINT {
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
pub(crate) fn sloc(loc: &Location) -> SLocData {
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
pub(crate) fn precision_name(name: &Value, tag: u8) -> Result<(), TINT> {
    match name {
        Value::Name(n) if n.is_precision() == (tag == Tag::Prec as u8) => Ok(()),
        _ => Err(ARG_RANGE),
    }
}

pub(crate) const ANY_FORM: &[Tag] = &[Tag::Cart, Tag::Joint, Tag::Prec];

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

/// TROLTrajectory (added, docs/protocol.md "Trajectory"): one motion through `count`
/// waypoints at their times. 0: it runs as timed; TRAJECTORY_UNTIMED (1): the controller
/// runs it through the waypoints without their times. A NULL `points` (with a count), no
/// points, more than MAX_WAYPOINTS, or times that do not increase are TROL_ERR_ARG_RANGE,
/// and nothing is sent.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn TROLTrajectory(points: *const STrajPoint, count: TUINT) -> TINT {
    run(
        &table::TRAJECTORY,
        || {
            if points.is_null() || count == 0 {
                return Err(ARG_RANGE);
            }
            // SAFETY: the caller hands `count` points at `points` (checked non-NULL).
            let given = unsafe { std::slice::from_raw_parts(points, usize::from(count)) };
            let path = given
                .iter()
                .map(|p| trol_proto::application::Waypoint {
                    time: f64::from(p.time),
                    joints: p.joints.map(f64::from),
                })
                .collect();
            Ok(vec![Value::Path(path)])
        },
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

//! InitTROL and CleanupTROL (trol.cfg), and the settings a 1998 program makes
//! (SetL3_TO_Intervall, TROLSetRepeats, SetDelay).

use super::*;

/// InitTROL(1): open the port of trol.cfg and check that the server answers.
/// InitTROL(0) (the init utility): also bring the controller from terminal mode into server
/// mode and apply trol.cfg's tool transform.
#[unsafe(no_mangle)]
pub extern "C" fn InitTROL(serOnly: TUINT) -> TUINT {
    guard(INITTROL_FAILURE, || {
        let cfg = match Config::load() {
            Ok(cfg) => cfg,
            Err(why) => {
                eprintln!("InitTROL: {why}");
                return INITTROL_FAILURE;
            }
        };
        let (callbacks, tenths, delay, repeats) = {
            let st = state();
            (st.callbacks, st.reply_tenths, st.delay, st.repeats)
        };
        // The one connect path (trol::Connect), with what the application set before
        // (SetL3_TO_Intervall, SetDelay, the repeats; each checked when it was set).
        // A reply timeout only when the application set one: else a controller of this
        // protocol says how long it takes (TROLGetReplyTime), so that a dead one costs a call
        // 3 s and not the manual's 15 (issue 67, item 2).
        let mut connect = trol_client::Connect::config(&cfg).delay(delay);
        if let Some(tenths) = tenths {
            connect = connect.reply_timeout_tenths(tenths);
        }
        if let Some(n) = repeats {
            connect = connect.repeats(n);
        }
        if serOnly == 0 {
            connect = connect.activate();
        }
        let mut robot = match connect.connect() {
            Ok(robot) => robot,
            Err(e) => {
                eprintln!("InitTROL: {e}");
                return INITTROL_FAILURE;
            }
        };
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
        st.reply_tenths = Some(tenths);
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

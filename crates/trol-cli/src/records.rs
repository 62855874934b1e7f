//! Layer-4 records in words, for the simulator's log and the trace.

use trol_proto::application::{Command, Reply, Request};

use crate::interp::commands::format_location;

/// A request: `TROLHome(axis 0)`, or what is wrong with it.
pub fn request(bytes: &[u8]) -> String {
    match Request::decode(bytes) {
        Ok(r) => {
            // Debug's `LocName("test_001")` reads better as `"test_001"`.
            let args = format!("{r:?}").replace("LocName(", "(");
            // `Home { axis: 0 }` -> `axis: 0`
            let inner = args
                .split_once('{')
                .map(|(_, rest)| rest.trim_end_matches('}').trim().to_string())
                .unwrap_or_default();
            format!("{}({inner})", r.command().api_name())
        }
        Err(e) => format!(
            "undecodable request {:02x?}: {e} ({})",
            &bytes[..bytes.len().min(16)],
            trol::describe(e.code())
        ),
    }
}

/// A reply to `request`: its value with its name, a location, or the status.
pub fn reply(request: &[u8], bytes: &[u8]) -> String {
    let Some(command) = request.first().and_then(|c| Command::from_code(*c)) else {
        return format!("reply {bytes:02x?}");
    };
    match Reply::decode(command, bytes) {
        Ok(r) => reply_text(&r),
        Err(e) => format!("reply {bytes:02x?} does not fit {command}: {e}"),
    }
}

/// A decoded reply: `0 (success)`, `c(400.000, ...)`, `BIOSCalled 1, lastErrorCode 0 (success)`.
pub fn reply_text(r: &Reply) -> String {
    match r {
        Reply::Code(v) => trol::describe(*v),
        Reply::Position(loc) => format_location(loc),
        Reply::Status { bios_called, last } => format!(
            "BIOSCalled {}, lastErrorCode {}",
            u8::from(*bios_called),
            trol::describe(*last)
        ),
    }
}

/// What a return value means, from the BIOS's or the manual's code list (empty if neither
/// knows it).
pub fn meaning(v: i16) -> &'static str {
    trol_a465::arm::code::describe(v)
        .map(|(_, m)| m)
        .or_else(|| {
            trol::errors::TROL_CODES
                .iter()
                .find(|c| c.0 == v)
                .map(|c| c.2)
        })
        .unwrap_or("")
}

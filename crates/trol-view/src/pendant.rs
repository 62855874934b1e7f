//! The pendant: driving the arm from the page (`--control`, docs/teach.md, "The pendant").
//!
//! Off unless the program that serves the view was started with `--control`. Then, besides
//! the GET requests of the view, the server takes POST requests under `/control/`, each
//! with the token printed at start (`?token=...`), from this machine (or an address named
//! with `--control-from`). Each becomes one request record of the command table, run by the
//! controller between two transactions of its line ([`trol_controller::Pendant`]), through the
//! same checks as an API call: limits, the table, reach. Without `--control`, every such
//! request is refused (403) and nothing moves; another method than GET or POST is 405.
//!
//! | request | command |
//! |---|---|
//! | `GET /control` | whether the pendant is on (`{"control": true}`); no token needed |
//! | `GET /control/locations` | TROLListLocations |
//! | `POST /control/jog?dx=&dy=&dz=&straight=0\|1` | TROLJog (mm, world frame) |
//! | `POST /control/turn?axis=x\|y\|z&degrees=&straight=0\|1` | the tool turned about a world axis through its tip: TROLGetPosition, then TROLMoveII |
//! | `POST /control/depart?dx=&dy=&dz=&dyaw=&dpitch=&droll=&straight=0\|1` | TROLDepart (mm and rad, the tool's frame) |
//! | `POST /control/open?force=1..100` | TROLOpen |
//! | `POST /control/close?force=1..100` | TROLClose |
//! | `POST /control/grip?mm=0..50` | TROLGrip |
//! | `POST /control/joint?joint=1..6&radians=` | TROLJoint |
//! | `POST /control/speed?percent=1..150` | TROLSpeed |
//! | `POST /control/home` | TROLHome(0) |
//! | `POST /control/here?name=&form=cart\|joint\|prec` | TROLHere |
//! | `POST /control/move?name=&straight=0\|1` | TROLMove |
//! | `POST /control/delete?name=` | TROLDeleteLocation |
//! | `POST /control/save` | TROLSaveLocations |
//! | `POST /control/halt` | TROLHalt |
//!
//! Every answer is JSON: `ok`, `value` (the return value), `text` (it in words), and for the
//! list `locations` (`name`, `form`, `values`).

use std::collections::HashMap;
use std::net::IpAddr;
use std::time::Duration;

use serde_json::json;
use trol_controller::Pendant;
use trol_proto::application::code::CodeTable;
use trol_proto::application::record::{self, Value};
use trol_proto::application::{CommandDef, LocName, Location, Reply, Tag, table};

/// How long a pendant request waits for the controller.
pub const CALL_LIMIT: Duration = Duration::from_secs(3);

/// Driving the arm from the page: what `--control` gives the view.
#[derive(Clone, Debug)]
pub struct Control {
    /// What every request must carry (`?token=`): printed when the server starts.
    pub token: String,
    /// The controller's way in.
    pub pendant: Pendant,
    /// Addresses besides this machine's that may drive the arm (`--control-from`).
    pub from: Vec<IpAddr>,
    /// The controller's BIOS codes, to put return values in words.
    pub codes: &'static CodeTable,
}

impl Control {
    /// A control with a fresh token.
    pub fn new(pendant: Pendant, codes: &'static CodeTable) -> Control {
        Control {
            token: new_token(),
            pendant,
            from: Vec::new(),
            codes,
        }
    }
}

/// 128 bits from the system's seeded hashers (std has no random source of its own; each
/// `RandomState` is seeded from the OS).
fn new_token() -> String {
    use std::hash::{BuildHasher, Hasher};
    let part = || {
        let mut h = std::collections::hash_map::RandomState::new().build_hasher();
        h.write_u128(
            std::time::SystemTime::now()
                .elapsed()
                .map_or(0, |d| d.as_nanos()),
        );
        h.finish()
    };
    format!("{:016x}{:016x}", part(), part())
}

/// An answer: HTTP status and a JSON body.
pub type Answer = (&'static str, serde_json::Value);

pub(crate) fn refusal(status: &'static str, why: impl Into<String>) -> Answer {
    (status, json!({"ok": false, "error": why.into()}))
}

/// Answer a request under `/control` (`target` with its query) from `peer`.
pub fn answer(
    method: &str,
    target: &str,
    peer: Option<IpAddr>,
    control: Option<&Control>,
) -> Answer {
    let (path, query) = target.split_once('?').unwrap_or((target, ""));
    if method != "GET" && method != "POST" {
        return refusal("405 Method Not Allowed", "GET or POST only");
    }
    if path == "/control" {
        return ("200 OK", json!({"control": control.is_some()}));
    }
    let Some(control) = control else {
        return refusal(
            "403 Forbidden",
            "the view only shows: start it with --control to drive the arm from the page",
        );
    };
    let allowed = peer.is_some_and(|p| p.is_loopback() || control.from.contains(&p));
    if !allowed {
        return refusal(
            "403 Forbidden",
            "the pendant takes requests from this machine only (or an address named with \
             --control-from)",
        );
    }
    let args = parse_query(query);
    if args.get("token").map(String::as_str) != Some(control.token.as_str()) {
        return refusal(
            "403 Forbidden",
            "a wrong or missing token: open the address the program printed at start",
        );
    }
    let wants_post = path != "/control/locations";
    if wants_post != (method == "POST") {
        return refusal(
            "405 Method Not Allowed",
            if wants_post { "POST only" } else { "GET only" },
        );
    }
    if path == "/control/turn" {
        return turned(&args, control);
    }
    let call = request(path, &args);
    let (def, values) = match call {
        Ok(call) => call,
        Err(Refused::Bad(e)) => return refusal("400 Bad Request", e),
    };
    let bytes = match record::encode(def, &values) {
        Ok(b) => b,
        Err(e) => return refusal("400 Bad Request", e.to_string()),
    };
    let reply = match control.pendant.call(bytes, CALL_LIMIT) {
        Ok(r) => r,
        Err(e) => return refusal("503 Service Unavailable", e.to_string()),
    };
    answered(def, &reply, control)
}

/// Why a pendant request was not sent: a bad request.
enum Refused {
    Bad(String),
}

impl From<String> for Refused {
    fn from(e: String) -> Refused {
        Refused::Bad(e)
    }
}

impl From<&str> for Refused {
    fn from(e: &str) -> Refused {
        Refused::Bad(e.to_string())
    }
}

/// A turn of the tool about a world axis through its tip (`axis` x, y or z, `degrees`): where
/// the tool is (TROLGetPosition, commanded), turned, as a TROLMoveII. Both run in one step of
/// the controller ([`trol_controller::Pendant::call_then`]): a motion the line's host sends
/// cannot come between them and make the turn start from where the tool no longer is.
fn turned(args: &HashMap<String, String>, control: &Control) -> Answer {
    let axis = match args.get("axis").map(String::as_str) {
        Some("x") => glam::DVec3::X,
        Some("y") => glam::DVec3::Y,
        Some("z") => glam::DVec3::Z,
        Some(v) => return refusal("400 Bad Request", format!("`axis`: {v:?} is not x, y or z")),
        None => return refusal("400 Bad Request", "`axis` is missing"),
    };
    let Some(degrees) = args
        .get("degrees")
        .and_then(|d| d.parse::<f64>().ok())
        .filter(|d| d.is_finite() && d.abs() <= 90.0)
    else {
        return refusal(
            "400 Bad Request",
            "`degrees`: a number of at most 90 either way",
        );
    };
    let straight = matches!(args.get("straight").map(String::as_str), Some("1" | "true"));
    let Ok(where_) = record::encode(
        &table::GET_POSITION,
        &[
            Value::Int(Tag::Cart as u8),
            Value::Int(trol_proto::application::table::POS_COMMANDED),
        ],
    ) else {
        return refusal(
            "500 Internal Server Error",
            "GetPosition could not be encoded",
        );
    };
    let follow: trol_controller::FollowUp = Box::new(move |reply: &[u8]| {
        let Ok(Reply::Position(loc)) = Reply::decode(&table::GET_POSITION, reply) else {
            return None;
        };
        let v = loc.to_array6();
        if v.iter().any(|x| !x.is_finite()) {
            return None;
        }
        let pose = trol_a465::Pose::from_xyzypr(v);
        let turn = glam::DMat3::from_axis_angle(axis, degrees.to_radians());
        let new = trol_a465::Pose {
            rot: turn * pose.rot,
            pos: pose.pos,
        }
        .to_xyzypr();
        record::encode(
            &table::MOVE_II,
            &[
                Value::Loc(Location::Cart(new.to_vec())),
                Value::Flag(straight),
            ],
        )
        .ok()
    });
    match control.pendant.call_then(where_, Some(follow), CALL_LIMIT) {
        Ok((reply, true)) => answered(&table::MOVE_II, &reply, control),
        // Where the tool is could not be read: that answer, as the page reads it.
        Ok((reply, false)) => {
            let (status, mut body) = answered(&table::GET_POSITION, &reply, control);
            if let Some(o) = body.as_object_mut() {
                o.insert("ok".into(), json!(false));
            }
            (status, body)
        }
        Err(e) => refusal("503 Service Unavailable", e.to_string()),
    }
}

/// The controller's reply to `def` as the page reads it.
fn answered(def: &'static CommandDef, reply: &[u8], control: &Control) -> Answer {
    match Reply::decode(def, reply) {
        Ok(r) => {
            let value = r.value();
            let mut body = json!({
                "ok": def.is_success(value.0),
                "command": def.name,
                "value": value.0,
                "text": r.text(control.codes),
            });
            if let (Reply::Locations(all), Some(o)) = (&r, body.as_object_mut()) {
                o.insert("locations".into(), locations_json(all));
            }
            if let (Reply::Position(loc), Some(o)) = (&r, body.as_object_mut()) {
                o.insert("position".into(), json!(loc.to_array6()));
            }
            ("200 OK", body)
        }
        Err(e) => refusal("502 Bad Gateway", e.to_string()),
    }
}

fn locations_json(all: &[(LocName, Location)]) -> serde_json::Value {
    all.iter()
        .map(|(n, l)| {
            json!({
                "name": n.as_str(),
                "form": match l.tag() {
                    Tag::Cart => "cart",
                    Tag::Joint => "joint",
                    Tag::Prec => "prec",
                },
                "values": l.to_array6(),
            })
        })
        .collect()
}

/// The command and its arguments for a pendant path.
fn request(
    path: &str,
    args: &HashMap<String, String>,
) -> Result<(&'static CommandDef, Vec<Value>), Refused> {
    let real = |key: &str, default: Option<f64>| -> Result<f64, String> {
        match args.get(key) {
            Some(v) => v
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| format!("`{key}`: {v:?} is not a number")),
            None => default.ok_or_else(|| format!("`{key}` is missing")),
        }
    };
    let small = |key: &str| -> Result<u8, String> {
        let v = args.get(key).ok_or_else(|| format!("`{key}` is missing"))?;
        v.parse::<u8>()
            .map_err(|_| format!("`{key}`: {v:?} is not a whole number 0..255"))
    };
    let small_or = |key: &str, default: u8| -> Result<u8, String> {
        match args.get(key) {
            Some(_) => small(key),
            None => Ok(default),
        }
    };
    let flag = |key: &str| -> Result<bool, String> {
        match args.get(key).map(String::as_str) {
            None | Some("0") | Some("false") => Ok(false),
            Some("1") | Some("true") => Ok(true),
            Some(v) => Err(format!("`{key}`: {v:?} is not 0 or 1")),
        }
    };
    let name = || -> Result<Value, String> {
        let v = args.get("name").ok_or("`name` is missing")?;
        LocName::new(v).map(Value::Name).map_err(|e| e.to_string())
    };
    Ok(match path {
        "/control/locations" => (&table::LIST_LOCATIONS, vec![]),
        "/control/jog" => {
            let d = [
                real("dx", Some(0.0))?,
                real("dy", Some(0.0))?,
                real("dz", Some(0.0))?,
            ];
            (
                &table::JOG,
                vec![
                    Value::Loc(Location::Cart(d.to_vec())),
                    Value::Flag(flag("straight")?),
                ],
            )
        }
        "/control/joint" => (
            &table::JOINT,
            vec![
                Value::Int(small("joint")?),
                Value::Real(real("radians", None)?),
            ],
        ),
        "/control/speed" => (&table::SPEED, vec![Value::Int(small("percent")?)]),
        "/control/home" => (&table::HOME, vec![Value::Int(0)]),
        "/control/here" => {
            let form = match args.get("form").map(String::as_str) {
                None | Some("cart") => Tag::Cart,
                Some("joint") => Tag::Joint,
                Some("prec") => Tag::Prec,
                Some(v) => return Err(format!("`form`: {v:?} is not cart, joint or prec").into()),
            };
            let n = name()?;
            if let Value::Name(l) = &n {
                if l.is_precision() != (form == Tag::Prec) {
                    return Err(
                        "a precision point's name starts with '#', and only a precision point's"
                            .into(),
                    );
                }
            }
            (&table::HERE, vec![n, Value::Int(form as u8)])
        }
        "/control/move" => (&table::MOVE, vec![name()?, Value::Flag(flag("straight")?)]),
        "/control/depart" => {
            let d = [
                real("dx", Some(0.0))?,
                real("dy", Some(0.0))?,
                real("dz", Some(0.0))?,
                real("dyaw", Some(0.0))?,
                real("dpitch", Some(0.0))?,
                real("droll", Some(0.0))?,
            ];
            (
                &table::DEPART,
                vec![
                    Value::Loc(Location::Cart(d.to_vec())),
                    Value::Flag(flag("straight")?),
                ],
            )
        }
        "/control/open" => (&table::OPEN, vec![Value::Int(small_or("force", 50)?)]),
        "/control/close" => (&table::CLOSE, vec![Value::Int(small_or("force", 50)?)]),
        "/control/grip" => (&table::GRIP, vec![Value::Int(small("mm")?)]),
        "/control/delete" => (&table::DELETE_LOCATION, vec![name()?]),
        "/control/save" => (&table::SAVE_LOCATIONS, vec![]),
        "/control/halt" => (&table::HALT, vec![]),
        other => return Err(format!("{other}: no such pendant request").into()),
    })
}

/// `a=1&b=%23x` as a map (percent-decoded; `+` is a blank).
fn parse_query(query: &str) -> HashMap<String, String> {
    query
        .split('&')
        .filter(|p| !p.is_empty())
        .map(|p| {
            let (k, v) = p.split_once('=').unwrap_or((p, ""));
            (decode(k), decode(v))
        })
        .collect()
}

fn decode(s: &str) -> String {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'+' => out.push(b' '),
            b'%' if i + 2 < bytes.len() => {
                let hex = |b: u8| (b as char).to_digit(16);
                match (hex(bytes[i + 1]), hex(bytes[i + 2])) {
                    (Some(h), Some(l)) => {
                        out.push((h * 16 + l) as u8);
                        i += 2;
                    }
                    _ => out.push(b'%'),
                }
            }
            b => out.push(b),
        }
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn queries_decode() {
        let q = parse_query("token=ab&name=%23park&x=1+2&bad=%zz&end=%2");
        assert_eq!(q["name"], "#park");
        assert_eq!(q["x"], "1 2");
        assert_eq!(q["bad"], "%zz");
        assert_eq!(q["end"], "%2");
    }

    #[test]
    fn tokens_differ() {
        assert_ne!(new_token(), new_token());
        assert_eq!(new_token().len(), 32);
    }
}

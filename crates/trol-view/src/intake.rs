//! The view's intake: the connections whose request head is still arriving, and the check
//! of the names a request is made for.
//!
//! One thread waits on the listener and on every such connection at once (mio: epoll or
//! kqueue), so a connection that sends nothing costs no thread. A head must arrive whole
//! within [`HEAD_DEADLINE`] of the connection; when [`MAX_WAITING`] connections wait, the
//! one that has sent least, and of those the oldest, is closed to make room for the new
//! one. So no number of connections that send nothing, or a byte now and then, keeps out a
//! request that comes whole at once, such as the pendant's Halt (issue 67, item 5). A whole
//! head goes to the server's dispatch; the answer is written on a thread of its own.
//!
//! A browser sends every request with the name it was made for (`Host`), and a request from
//! a script of another page with that page's `Origin`. [`Names`] takes only this machine's
//! names (`localhost`, a loopback address), the address the view was started on, and the
//! address the connection came in on: a page elsewhere whose name was made to point at this
//! machine (DNS rebinding) is refused, and so is a script of another page.

use std::collections::HashMap;
use std::io::{ErrorKind, Read, Write};
use std::net::{IpAddr, SocketAddr};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use mio::net::{TcpListener, TcpStream};
use mio::{Events, Interest, Poll, Token};

/// At most this many connections may be still sending their request's head; when more come,
/// the one that has sent least (and of those the oldest) is closed. Apart from every answer
/// under way ([`crate::MAX_CLIENTS`], ...).
pub const MAX_WAITING: usize = 256;

/// A request's head must arrive whole within this time of the connection.
pub const HEAD_DEADLINE: Duration = Duration::from_secs(2);

/// The most a request's head may take.
pub(crate) const MAX_HEAD: usize = 16 * 1024;

/// The longest the intake sleeps without looking at its stop flag.
const LOOK_AGAIN: Duration = Duration::from_millis(250);

const LISTENER: Token = Token(0);

/// A request's head: what the server reads of it.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct Head {
    /// `GET`, `POST`, ...
    pub method: String,
    /// The path with its query.
    pub target: String,
    /// The `Host` header, if it came.
    pub host: Option<String>,
    /// The `Origin` header, if it came.
    pub origin: Option<String>,
}

/// What the bytes of a head so far are.
#[derive(Debug, PartialEq, Eq)]
pub(crate) enum Parsed {
    /// Not yet whole.
    Incomplete,
    /// Larger than [`MAX_HEAD`] without its end.
    TooLarge,
    /// Whole: up to its blank line, or cut short by the client.
    Whole(Head),
}

/// Read a head from `bytes`; `ended`: the client sent all it will (a head cut short is taken
/// as it is).
pub(crate) fn parse_head(bytes: &[u8], ended: bool) -> Parsed {
    let end = find(bytes, b"\r\n\r\n").or_else(|| find(bytes, b"\n\n"));
    let head = match end {
        Some(end) if end <= MAX_HEAD => &bytes[..end],
        Some(_) => return Parsed::TooLarge,
        None if bytes.len() >= MAX_HEAD => return Parsed::TooLarge,
        None if ended && !bytes.is_empty() => bytes,
        None => return Parsed::Incomplete,
    };
    let text = String::from_utf8_lossy(head);
    let mut lines = text.split('\n').map(|l| l.trim_end_matches('\r'));
    let mut parts = lines.next().unwrap_or("").split_whitespace();
    let mut parsed = Head {
        method: parts.next().unwrap_or("").to_string(),
        target: parts.next().unwrap_or("").to_string(),
        ..Head::default()
    };
    for line in lines {
        let Some((name, value)) = line.split_once(':') else {
            continue;
        };
        let value = Some(value.trim().to_string());
        if name.trim().eq_ignore_ascii_case("host") {
            parsed.host = value;
        } else if name.trim().eq_ignore_ascii_case("origin") {
            parsed.origin = value;
        }
    }
    Parsed::Whole(parsed)
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// The names requests may be made for: this machine's, and the one the view was started on.
#[derive(Clone, Debug)]
pub(crate) struct Names {
    /// The host the view was started on (`--view NAME:PORT`), lower case; `None` for an
    /// address that means every interface (0.0.0.0, ::).
    configured: Option<String>,
}

impl Names {
    /// The names for a view started on `addr` (`host:port`).
    pub fn new(addr: &str) -> Names {
        let host = host_of(addr).to_ascii_lowercase();
        let every = host.parse::<IpAddr>().is_ok_and(|ip| ip.is_unspecified());
        Names {
            configured: (!every && !host.is_empty()).then_some(host),
        }
    }

    /// Whether `name` (a host, without port) is one of them, for a connection that came in
    /// on `local`.
    fn allows(&self, name: &str, local: Option<IpAddr>) -> bool {
        let name = name.trim_end_matches('.').to_ascii_lowercase();
        if name == "localhost" || name.ends_with(".localhost") {
            return true;
        }
        if let Ok(ip) = name.parse::<IpAddr>() {
            if ip.is_loopback() || Some(ip) == local {
                return true;
            }
        }
        self.configured.as_deref() == Some(name.as_str())
    }

    /// Whether `head` may be answered on a connection that came in on `local`: its `Host`
    /// and its `Origin` (when they came) name this machine or the view's address. The words
    /// of a refusal.
    pub fn check(&self, head: &Head, local: Option<IpAddr>) -> Result<(), String> {
        let these = match &self.configured {
            Some(name) => format!("localhost, this machine's addresses and {name}"),
            None => "localhost and this machine's addresses".to_string(),
        };
        if let Some(host) = &head.host {
            if !self.allows(host_of(host), local) {
                return Err(format!(
                    "this view answers for {these}, not for '{host}': open it by one of those \
                     (or start it on that name: --view NAME:PORT)"
                ));
            }
        }
        if let Some(origin) = &head.origin {
            let authority = origin
                .split_once("://")
                .map(|(_, rest)| rest.split('/').next().unwrap_or(rest));
            if !authority.is_some_and(|a| self.allows(host_of(a), local)) {
                return Err(format!(
                    "a request from a page of '{origin}' is refused: this view takes requests \
                     from its own page only ({these})"
                ));
            }
        }
        Ok(())
    }
}

/// The host of an authority (`name:port`, `[v6]:port`, `name`), without its port.
fn host_of(authority: &str) -> &str {
    let a = authority.trim();
    if let Some(rest) = a.strip_prefix('[') {
        return rest.split(']').next().unwrap_or(rest);
    }
    match a.rsplit_once(':') {
        // One colon: name and port. More: a bare IPv6 address.
        Some((host, _)) if !host.contains(':') => host,
        _ => a,
    }
}

/// A connection whose head is still arriving.
struct Arriving {
    conn: TcpStream,
    head: Vec<u8>,
    since: Instant,
}

/// Take connections on `listener` until `stop` is set, and hand each whole head to
/// `dispatch` with its connection (blocking again). A head too large is answered 431 here;
/// a connection that sends no whole head in time is closed.
pub(crate) fn run(
    listener: std::net::TcpListener,
    stop: &AtomicBool,
    mut dispatch: impl FnMut(std::net::TcpStream, Head),
) -> std::io::Result<()> {
    listener.set_nonblocking(true)?;
    let mut listener = TcpListener::from_std(listener);
    let mut poll = Poll::new()?;
    poll.registry()
        .register(&mut listener, LISTENER, Interest::READABLE)?;
    let mut events = Events::with_capacity(256);
    let mut waiting: HashMap<Token, Arriving> = HashMap::new();
    let mut next = 1usize;
    while !stop.load(Ordering::Relaxed) {
        let now = Instant::now();
        let first_end = waiting.values().map(|a| a.since + HEAD_DEADLINE).min();
        let sleep = first_end.map_or(LOOK_AGAIN, |end| {
            end.saturating_duration_since(now).min(LOOK_AGAIN)
        });
        if let Err(e) = poll.poll(&mut events, Some(sleep)) {
            if e.kind() != ErrorKind::Interrupted {
                std::thread::sleep(Duration::from_millis(10));
            }
            continue;
        }
        let mut ready = Vec::new();
        for event in events.iter() {
            if event.token() == LISTENER {
                loop {
                    match listener.accept() {
                        Ok((conn, _)) => {
                            let token = Token(next);
                            next = next.checked_add(1).unwrap_or(1);
                            if admit(&poll, &mut waiting, token, conn) {
                                // Its head may be there already.
                                ready.push(token);
                            }
                        }
                        Err(e) if e.kind() == ErrorKind::WouldBlock => break,
                        Err(e) if e.kind() == ErrorKind::Interrupted => {}
                        // Out of file descriptors, say: the next round tries again.
                        Err(_) => break,
                    }
                }
            } else {
                ready.push(event.token());
            }
        }
        for token in ready {
            take_in(&poll, &mut waiting, token, &mut dispatch);
        }
        let now = Instant::now();
        let late: Vec<Token> = waiting
            .iter()
            .filter(|(_, a)| now >= a.since + HEAD_DEADLINE)
            .map(|(t, _)| *t)
            .collect();
        for token in late {
            if let Some(mut a) = waiting.remove(&token) {
                let _ = poll.registry().deregister(&mut a.conn);
            }
        }
    }
    Ok(())
}

/// Wait for `conn`'s head, closing the idlest waiting connection when [`MAX_WAITING`] wait.
fn admit(
    poll: &Poll,
    waiting: &mut HashMap<Token, Arriving>,
    token: Token,
    mut conn: TcpStream,
) -> bool {
    if waiting.len() >= MAX_WAITING {
        let idlest = waiting
            .iter()
            .min_by_key(|(_, a)| (a.head.len(), a.since))
            .map(|(t, _)| *t);
        if let Some(mut a) = idlest.and_then(|t| waiting.remove(&t)) {
            let _ = poll.registry().deregister(&mut a.conn);
        }
    }
    if poll
        .registry()
        .register(&mut conn, token, Interest::READABLE)
        .is_err()
    {
        return false;
    }
    waiting.insert(
        token,
        Arriving {
            conn,
            head: Vec::new(),
            since: Instant::now(),
        },
    );
    true
}

/// Read what `token`'s connection sent; a whole head goes to `dispatch`.
fn take_in(
    poll: &Poll,
    waiting: &mut HashMap<Token, Arriving>,
    token: Token,
    dispatch: &mut impl FnMut(std::net::TcpStream, Head),
) {
    let Some(a) = waiting.get_mut(&token) else {
        return;
    };
    let mut buf = [0u8; 4096];
    let mut ended = false;
    loop {
        match a.conn.read(&mut buf) {
            Ok(0) => {
                ended = true;
                break;
            }
            Ok(n) => {
                a.head.extend_from_slice(&buf[..n]);
                if a.head.len() > MAX_HEAD {
                    break;
                }
            }
            Err(e) if e.kind() == ErrorKind::WouldBlock => break,
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(_) => {
                ended = true;
                a.head.clear();
                break;
            }
        }
    }
    let parsed = parse_head(&a.head, ended);
    if parsed == Parsed::Incomplete && !ended {
        return;
    }
    let Some(mut a) = waiting.remove(&token) else {
        return;
    };
    let _ = poll.registry().deregister(&mut a.conn);
    match parsed {
        Parsed::Whole(head) => {
            let conn = std::net::TcpStream::from(a.conn);
            if conn.set_nonblocking(false).is_ok() {
                dispatch(conn, head);
            }
        }
        Parsed::TooLarge => {
            // Small enough for the socket's buffer: never waits.
            let _ = a.conn.write_all(
                b"HTTP/1.1 431 Request Header Fields Too Large\r\nContent-Type: text/plain\r\n\
                  Content-Length: 31\r\nConnection: close\r\n\r\nthe request's head is too large\n",
            );
        }
        Parsed::Incomplete => {}
    }
}

/// The address a connection came in on, for [`Names::check`].
pub(crate) fn local_ip(conn: &std::net::TcpStream) -> Option<IpAddr> {
    conn.local_addr().ok().as_ref().map(SocketAddr::ip)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_head_is_read_to_its_blank_line_and_no_further_than_the_limit() {
        let whole = parse_head(
            b"GET /state?x HTTP/1.1\r\nHost: a:80\r\nOrigin: http://a\r\n\r\nrest",
            false,
        );
        assert_eq!(
            whole,
            Parsed::Whole(Head {
                method: "GET".into(),
                target: "/state?x".into(),
                host: Some("a:80".into()),
                origin: Some("http://a".into()),
            })
        );
        assert_eq!(
            parse_head(b"GET / HTTP/1.1\r\nHo", false),
            Parsed::Incomplete
        );
        // A head without an end, past the limit: refused.
        let mut big = b"GET / HTTP/1.1\r\nX: ".to_vec();
        big.extend(std::iter::repeat_n(b'a', MAX_HEAD));
        assert_eq!(parse_head(&big, false), Parsed::TooLarge);
        // A head cut short by the client is taken as it is.
        let Parsed::Whole(cut) = parse_head(b"GET /urdf HTTP/1.1\r\n", true) else {
            panic!("a cut head")
        };
        assert_eq!((cut.method.as_str(), cut.target.as_str()), ("GET", "/urdf"));
        assert_eq!(parse_head(b"", true), Parsed::Incomplete);
    }

    #[test]
    fn only_this_machines_names_and_the_views_own_are_answered() {
        let head = |host: Option<&str>, origin: Option<&str>| Head {
            method: "GET".into(),
            target: "/".into(),
            host: host.map(str::to_string),
            origin: origin.map(str::to_string),
        };
        let local: Option<IpAddr> = Some("192.168.1.5".parse().unwrap());
        let names = Names::new("0.0.0.0:8465");
        for ok in [
            "localhost:8465",
            "LOCALHOST",
            "app.localhost:1",
            "127.0.0.1:8465",
            "[::1]:8465",
            "192.168.1.5:8465",
        ] {
            assert_eq!(names.check(&head(Some(ok), None), local), Ok(()), "{ok}");
        }
        // No Host (not a browser): answered.
        assert_eq!(names.check(&head(None, None), local), Ok(()));
        for bad in [
            "evil.example:8465",
            "192.168.1.6:8465",
            "localhost.evil.example",
        ] {
            let e = names.check(&head(Some(bad), None), local).unwrap_err();
            assert!(e.contains(bad) && e.contains("--view NAME:PORT"), "{e}");
        }
        for bad in ["http://evil.example", "null", "http://evil.example:8465/x"] {
            let e = names
                .check(&head(Some("127.0.0.1:8465"), Some(bad)), local)
                .unwrap_err();
            assert!(e.contains(bad), "{e}");
        }
        assert_eq!(
            names.check(
                &head(Some("127.0.0.1:1"), Some("http://127.0.0.1:1")),
                local
            ),
            Ok(())
        );
        // Started on a name: that name too.
        let named = Names::new("lab-pc:8465");
        assert_eq!(named.check(&head(Some("Lab-PC:8465"), None), None), Ok(()));
        assert!(names.check(&head(Some("lab-pc:8465"), None), None).is_err());
    }
}

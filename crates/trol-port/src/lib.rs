//! Layer 1 of TROL ("Bitübertragungs-Schicht"): moving bytes over a line.
//!
//! The manual gives layer 1 four services: send a byte (SendByte), get a byte (GetByte),
//! ask whether input is waiting (BufferEmpty) and drop waiting input (FlushBuffer). [`Port`]
//! offers them for every kind of line, each with a deadline so that nothing waits forever on
//! a silent line:
//!
//! | name | port |
//! |------|------|
//! | `/dev/ttyUSB0`, `/dev/pts/3`, `COM1`, ... | [`serial::SerialLine`]: a serial device or pty, 8N1, raw |
//! | `socket://HOST:PORT` | [`tcp::TcpLine`]: connects to a TCP server |
//! | `listen://HOST:PORT` | [`tcp::TcpLine`]: waits for one client to connect |
//! | (in process) | [`memory::pair`]: two ends of an in-memory line, optionally paced |
//!
//! [`faulty::Faulty`] wraps any port and injects bit errors, drops, insertions, duplicates,
//! delays and a cut, from a seed so that a failure can be replayed.

#![deny(unsafe_code)]
#![warn(missing_docs, missing_debug_implementations)]

pub mod faulty;
pub mod memory;
pub mod serial;
pub mod tcp;

use std::io;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// One end of a byte line.
pub trait Port: Send {
    /// Put `bytes` on the line (SendByte / a buffer of them). Returns once the port took them.
    fn send(&mut self, bytes: &[u8]) -> io::Result<()>;

    /// Read what has arrived into `buf`, waiting until `deadline` for the first byte
    /// (GetByte with a deadline). Returns 0 when the deadline passed with nothing received.
    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize>;

    /// Bytes waiting to be read (0 means the manual's BufferEmpty() is true). Never consumes.
    fn available(&mut self) -> io::Result<usize>;

    /// Drop all input waiting to be read (FlushBuffer).
    fn flush_input(&mut self) -> io::Result<()>;

    /// A name for messages and traces.
    fn name(&self) -> String;

    /// A second way to put bytes on this line, for another thread, while this end's owner
    /// is busy elsewhere and sends nothing: the controller's keep-alive while it executes a
    /// request (docs/protocol.md, "Keep-alive"). `None` (the default) where the line has no
    /// such way (the keep-alive is then not offered).
    fn beacon(&mut self) -> Option<Beacon> {
        None
    }

    /// Whether this kind of line has a [`Port::beacon`] (a listening TCP line has one once a
    /// client is connected).
    fn offers_beacon(&self) -> bool {
        false
    }
}

/// Puts bytes on a line from another thread ([`Port::beacon`]).
pub type Beacon = Box<dyn FnMut(&[u8]) -> io::Result<()> + Send>;

impl<P: Port + ?Sized> Port for Box<P> {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        (**self).send(bytes)
    }
    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        (**self).recv(buf, deadline)
    }
    fn available(&mut self) -> io::Result<usize> {
        (**self).available()
    }
    fn flush_input(&mut self) -> io::Result<()> {
        (**self).flush_input()
    }
    fn name(&self) -> String {
        (**self).name()
    }
    fn beacon(&mut self) -> Option<Beacon> {
        (**self).beacon()
    }
    fn offers_beacon(&self) -> bool {
        (**self).offers_beacon()
    }
}

/// Settings for opening a port by name.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PortSettings {
    /// Baud rate of a serial device (ignored by TCP).
    pub baud: u32,
    /// How long opening (connecting, waiting for a client) may take.
    pub open_timeout: Duration,
    /// RTS/CTS hardware flow control on a serial device (a MARS 8's line).
    pub rts_cts: bool,
}

impl Default for PortSettings {
    fn default() -> Self {
        PortSettings {
            baud: 9600,
            open_timeout: Duration::from_secs(10),
            rts_cts: false,
        }
    }
}

/// Why a port could not be opened.
#[derive(Debug, thiserror::Error)]
pub enum OpenError {
    /// The name is not of a form layer 1 knows.
    #[error("'{name}' is not a port name: {why}")]
    BadName {
        /// The name given.
        name: String,
        /// What is wrong with it.
        why: String,
    },
    /// Another process holds the device (it was opened for exclusive use).
    #[error(
        "cannot open port '{name}': it is in use{}; only one program can use a port at a \
         time: end that one, or use another port",
        held_by(holders)
    )]
    Busy {
        /// The name given.
        name: String,
        /// The processes that have it open, as far as this system tells.
        holders: Vec<Holder>,
    },
    /// The operating system refused.
    #[error("cannot open port '{name}': {source}{hint}")]
    Io {
        /// The name given.
        name: String,
        /// The cause.
        #[source]
        source: io::Error,
        /// What to do about it ([`open_hint`]), led by "; ", or empty.
        hint: String,
    },
}

impl OpenError {
    /// The system's refusal to open `name`, with what to do about it.
    pub fn io(name: &str, source: io::Error) -> OpenError {
        let hint = open_hint(name, &source, &serial::list().unwrap_or_default());
        OpenError::Io {
            name: name.to_string(),
            source,
            hint,
        }
    }
}

/// The names a port name may be a slip of: the embedded simulator, the real controllers'
/// prefixes and the socket schemes.
const KNOWN: [&str; 6] = ["sim", "rapl:", "mars:", "c500c:", "socket://", "listen://"];

/// What to do when `name` could not be opened for `why`, given this machine's serial ports
/// (`ports`: name and description, as `trol ports` lists them): led by "; ", else empty.
/// A name that does not exist gets the nearest known name or device ("did you mean"), and
/// where to find the devices; a refusal, the group that gives access; a socket nobody
/// listens on, what to start.
pub fn open_hint(name: &str, why: &io::Error, ports: &[(String, String)]) -> String {
    match why.kind() {
        io::ErrorKind::NotFound if !name.contains("://") => {
            // A prefix's slip is the part before its `:` (`mars/dev/...` is no slip of ours).
            let head = name.split_inclusive(':').next().unwrap_or(name);
            let nearest = KNOWN
                .iter()
                .map(|k| {
                    (
                        strsim::levenshtein(&head.to_ascii_lowercase(), k),
                        k.to_string(),
                        *k,
                    )
                })
                .chain(
                    ports
                        .iter()
                        .map(|(p, _)| (strsim::levenshtein(name, p), p.clone(), "")),
                )
                .filter(|(d, _, _)| *d <= 2)
                .min_by_key(|(d, _, _)| *d);
            let guess = match nearest {
                Some((_, _, k)) if !k.is_empty() && k.ends_with(':') => {
                    format!(" did you mean `{k}{}`?", &name[head.len()..])
                }
                Some((_, p, "sim")) => format!(" did you mean `{p}` (the embedded simulator)?"),
                Some((_, p, _)) => format!(" did you mean `{p}`?"),
                None => String::new(),
            };
            let listed = if ports.is_empty() {
                "this machine shows no serial port (is the adapter plugged in?)".to_string()
            } else {
                format!(
                    "this machine's serial ports: {} (`trol ports` says more)",
                    ports
                        .iter()
                        .map(|(p, _)| p.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            };
            format!(";{guess} {listed}")
        }
        io::ErrorKind::PermissionDenied => format!(
            "; this user may not open it: add the user to the group that owns it (`ls -l \
             {name}`; usually dialout or uucp) and log in again"
        ),
        io::ErrorKind::ConnectionRefused => {
            "; nothing listens there: start the TROL server first (`trol sim --port \
             listen://HOST:PORT`, or `trol gateway --port listen://HOST:PORT`)"
                .to_string()
        }
        _ => String::new(),
    }
}

/// Open the port called `name`: `socket://HOST:PORT`, `listen://HOST:PORT`, or the path of a
/// serial device. The in-process names (`sim`, memory lines) are handled by the layers that
/// own them.
pub fn open(name: &str, settings: &PortSettings) -> Result<Box<dyn Port>, OpenError> {
    if let Some(addr) = name.strip_prefix("socket://") {
        return Ok(Box::new(
            tcp::TcpLine::connect(addr, settings.open_timeout)
                .map_err(|source| OpenError::io(name, source))?,
        ));
    }
    if let Some(addr) = name.strip_prefix("listen://") {
        return Ok(Box::new(
            tcp::TcpLine::listen(addr, settings.open_timeout)
                .map_err(|source| OpenError::io(name, source))?,
        ));
    }
    if name.contains("://") {
        return Err(OpenError::BadName {
            name: name.to_string(),
            why: "the known schemes are socket://HOST:PORT and listen://HOST:PORT".into(),
        });
    }
    if name.is_empty() {
        return Err(OpenError::BadName {
            name: name.to_string(),
            why: "empty; give a device path such as /dev/ttyUSB0, or socket://HOST:PORT".into(),
        });
    }
    let busy =
        |e: &io::Error| e.kind() == io::ErrorKind::ResourceBusy || e.raw_os_error() == Some(16);
    // A device held only for a moment is not busy: a process that forked from this one (to
    // run another program) holds a copy of a port just closed here until its exec closes it.
    let grace = std::time::Instant::now() + BUSY_GRACE;
    let opened = loop {
        match serial::SerialLine::open_with(name, settings.baud, settings.rts_cts) {
            Err(e) if busy(&e) && std::time::Instant::now() < grace => {
                std::thread::sleep(std::time::Duration::from_millis(20));
            }
            other => break other,
        }
    };
    Ok(Box::new(opened.map_err(|source| {
        // EBUSY: the device was opened for exclusive use by another process.
        if busy(&source) {
            OpenError::Busy {
                name: name.to_string(),
                holders: holders(name),
            }
        } else {
            OpenError::io(name, source)
        }
    })?))
}

/// How long a device opened for exclusive use elsewhere is tried again before it counts as
/// busy ([`OpenError::Busy`]): long enough for a process forked from this one to exec (and
/// so close its copy of a port just closed here) on a loaded machine.
pub const BUSY_GRACE: std::time::Duration = std::time::Duration::from_millis(1000);

/// A process that has a port open.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Holder {
    /// Its process id.
    pub pid: u32,
    /// Its command name.
    pub command: String,
}

impl std::fmt::Display for Holder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "process {} ({})", self.pid, self.command)
    }
}

/// ` by process 12 (trol)` for a message, or nothing when no holder is known.
pub fn held_by(holders: &[Holder]) -> String {
    if holders.is_empty() {
        return String::new();
    }
    let list: Vec<String> = holders.iter().map(|h| h.to_string()).collect();
    format!(" by {}", list.join(", "))
}

/// The other processes that have the device `path` open (Linux: from /proc; elsewhere, and
/// for names that are not device paths, none). For a pseudo-terminal, the process that made
/// it (it has that pty's master open too: a `trol sim` serving on it) is the other end, not a
/// rival, and is left out. A process that holds the masters of other ptys only (a test
/// program with several lines open) is not the maker of this one.
pub fn holders(path: &str) -> Vec<Holder> {
    let Ok(target) = std::fs::canonicalize(path) else {
        return Vec::new();
    };
    // /dev/pts/N: N, the index a master of this pty shows in its fdinfo.
    let pty_index: Option<u32> = target
        .strip_prefix("/dev/pts")
        .ok()
        .and_then(|n| n.to_str()?.parse().ok());
    let me = std::process::id();
    let Ok(procs) = std::fs::read_dir("/proc") else {
        return Vec::new();
    };
    let mut found = Vec::new();
    for entry in procs.flatten() {
        let Some(pid) = entry
            .file_name()
            .to_str()
            .and_then(|n| n.parse::<u32>().ok())
        else {
            continue;
        };
        if pid == me {
            continue;
        }
        let Ok(fds) = std::fs::read_dir(entry.path().join("fd")) else {
            continue;
        };
        let links: Vec<(std::ffi::OsString, PathBuf)> = fds
            .flatten()
            .filter_map(|fd| Some((fd.file_name(), std::fs::read_link(fd.path()).ok()?)))
            .collect();
        let holds = links.iter().any(|(_, l)| *l == target);
        let pty_maker = pty_index.is_some_and(|index| {
            links.iter().any(|(fd, l)| {
                (l == Path::new("/dev/ptmx") || l == Path::new("/dev/pts/ptmx"))
                    && master_of(&entry.path().join("fdinfo").join(fd), index)
            })
        });
        if holds && !pty_maker {
            let command = std::fs::read_to_string(entry.path().join("comm"))
                .map(|c| c.trim().to_string())
                .unwrap_or_else(|_| "?".into());
            found.push(Holder { pid, command });
        }
    }
    found.sort_by_key(|h| h.pid);
    found
}

/// Whether the pty master whose fdinfo is at `fdinfo` is the master of /dev/pts/`index`
/// (Linux gives `tty-index:`; a kernel that does not is taken at its word that it may be).
fn master_of(fdinfo: &Path, index: u32) -> bool {
    let Ok(info) = std::fs::read_to_string(fdinfo) else {
        return true;
    };
    match info
        .lines()
        .find_map(|l| l.strip_prefix("tty-index:"))
        .map(|v| v.trim().parse::<u32>())
    {
        Some(Ok(i)) => i == index,
        _ => true,
    }
}

/// Time left until `deadline`, zero when it has passed.
pub(crate) fn remaining(deadline: Instant) -> Duration {
    deadline.saturating_duration_since(Instant::now())
}

#[cfg(test)]
mod hint_tests {
    use super::*;

    fn not_found() -> io::Error {
        io::Error::from(io::ErrorKind::NotFound)
    }

    #[test]
    fn a_name_that_does_not_exist_gets_the_nearest_known_one_and_the_ports() {
        let ports = vec![("/dev/ttyUSB0".to_string(), "USB serial".to_string())];
        let h = open_hint("Sim", &not_found(), &ports);
        assert!(
            h.contains("did you mean `sim` (the embedded simulator)?"),
            "{h}"
        );
        assert!(
            h.contains("this machine's serial ports: /dev/ttyUSB0"),
            "{h}"
        );
        let h = open_hint("/dev/ttyUSB7", &not_found(), &ports);
        assert!(h.contains("did you mean `/dev/ttyUSB0`?"), "{h}");
        let h = open_hint("marz:/dev/ttyUSB0", &not_found(), &ports);
        assert!(h.contains("did you mean `mars:/dev/ttyUSB0`?"), "{h}");
        let h = open_hint("/dev/somewhere/else", &not_found(), &[]);
        assert!(!h.contains("did you mean"), "{h}");
        assert!(h.contains("shows no serial port"), "{h}");
    }

    #[test]
    fn a_refusal_names_the_group_and_a_refused_socket_what_to_start() {
        let h = open_hint(
            "/dev/ttyS0",
            &io::Error::from(io::ErrorKind::PermissionDenied),
            &[],
        );
        assert!(h.contains("dialout"), "{h}");
        let h = open_hint(
            "socket://127.0.0.1:9",
            &io::Error::from(io::ErrorKind::ConnectionRefused),
            &[],
        );
        assert!(h.contains("nothing listens there"), "{h}");
        assert_eq!(open_hint("x", &io::Error::other("odd"), &[]), "");
    }
}

//! TCP lines: `socket://HOST:PORT` connects to a server, `listen://HOST:PORT` waits for one
//! client. A listening line that loses its client accepts the next one, so a relay or a
//! simulated controller survives a client reconnecting.
//!
//! `listen://PORT` and `listen://:PORT` bind the loopback interface only: whoever reaches a
//! listening line drives the arm, and there is no authentication. Naming an address that
//! is reachable from elsewhere (`listen://0.0.0.0:7000`) is allowed and logged as a warning.
//! While a client is connected, a second one is told at once that the line is busy
//! ([`BUSY`]) and closed; its `socket://` end reports that as an error.

use std::io::{self, Read, Write};
use std::net::{Shutdown, TcpListener, TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};

use crate::{Port, remaining};

/// What a listening line sends a second client before closing it. A TROL controller never
/// sends `T` first, so the connecting end recognises it.
pub const BUSY: &[u8] = b"TROL busy: another client is connected\r\n";

/// One end of a TCP connection carrying the byte line.
#[derive(Debug)]
pub struct TcpLine {
    stream: Option<TcpStream>,
    listener: Option<TcpListener>,
    name: String,
    /// A connecting line that has received nothing yet (it checks for [`BUSY`]).
    fresh: bool,
}

/// `PORT` or `:PORT` means the loopback interface.
fn listen_address(addr: &str) -> String {
    let port = addr.strip_prefix(':').unwrap_or(addr);
    if !port.is_empty() && port.bytes().all(|b| b.is_ascii_digit()) {
        format!("127.0.0.1:{port}")
    } else {
        addr.to_string()
    }
}

impl TcpLine {
    /// Connect to `addr` (`HOST:PORT`).
    pub fn connect(addr: &str, timeout: Duration) -> io::Result<TcpLine> {
        let mut last = io::Error::new(io::ErrorKind::NotFound, format!("no address for {addr}"));
        for a in addr.to_socket_addrs()? {
            match TcpStream::connect_timeout(&a, timeout) {
                Ok(stream) => {
                    stream.set_nodelay(true)?;
                    return Ok(TcpLine {
                        stream: Some(stream),
                        listener: None,
                        name: format!("socket://{addr}"),
                        fresh: true,
                    });
                }
                Err(e) => last = e,
            }
        }
        Err(last)
    }

    /// Listen on `addr` (`HOST:PORT`, or `PORT` / `:PORT` for the loopback interface; port
    /// 0 picks a free port, see [`TcpLine::local_addr`]). The first client is accepted
    /// lazily, on the first send or receive.
    pub fn listen(addr: &str, _timeout: Duration) -> io::Result<TcpLine> {
        let listener = TcpListener::bind(listen_address(addr))?;
        listener.set_nonblocking(true)?;
        let local = listener.local_addr()?;
        if !local.ip().is_loopback() {
            tracing::warn!(
                "listening on {local}: anyone who can reach this machine on port {} can drive \
                 the arm (there is no authentication); listen://{} keeps it to this machine",
                local.port(),
                local.port()
            );
        }
        Ok(TcpLine {
            stream: None,
            listener: Some(listener),
            name: format!("listen://{local}"),
            fresh: false,
        })
    }

    /// The local address of a listening line.
    pub fn local_addr(&self) -> Option<std::net::SocketAddr> {
        self.listener.as_ref().and_then(|l| l.local_addr().ok())
    }

    /// Whether a peer is connected.
    pub fn is_connected(&self) -> bool {
        self.stream.is_some()
    }

    fn try_accept(&mut self) -> io::Result<()> {
        if self.stream.is_some() {
            self.turn_away();
            return Ok(());
        }
        if let Some(listener) = &self.listener {
            match listener.accept() {
                Ok((stream, _)) => {
                    stream.set_nonblocking(false)?;
                    stream.set_nodelay(true)?;
                    self.stream = Some(stream);
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => {}
                Err(e) => return Err(e),
            }
        }
        Ok(())
    }

    /// A connecting line whose connection is gone stays gone (open it again).
    fn connected(&self) -> io::Result<()> {
        if self.stream.is_none() && self.listener.is_none() {
            return Err(io::Error::new(
                io::ErrorKind::NotConnected,
                format!("{}: the connection is closed", self.name),
            ));
        }
        Ok(())
    }

    /// Tell clients that connect while one is served that the line is busy.
    fn turn_away(&mut self) {
        let Some(listener) = &self.listener else {
            return;
        };
        while let Ok((mut other, peer)) = listener.accept() {
            tracing::warn!(
                "{}: turned {peer} away: another client is connected",
                self.name
            );
            let _ = other.set_nonblocking(false);
            let _ = other.write_all(BUSY);
            let _ = other.shutdown(Shutdown::Both);
        }
    }

    /// A connecting line's first bytes: the listening end's busy notice is an error.
    fn check_busy(&mut self, got: &[u8]) -> io::Result<()> {
        if !self.fresh || got.is_empty() {
            return Ok(());
        }
        self.fresh = false;
        if got[0] == BUSY[0] && BUSY.starts_with(&got[..got.len().min(BUSY.len())]) {
            self.lost();
            return Err(io::Error::new(
                io::ErrorKind::ConnectionRefused,
                format!(
                    "{}: the controller is busy: another client is connected to it (close \
                     that one first)",
                    self.name
                ),
            ));
        }
        Ok(())
    }

    fn lost(&mut self) {
        if let Some(s) = self.stream.take() {
            let _ = s.shutdown(Shutdown::Both);
        }
    }
}

impl Port for TcpLine {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.try_accept()?;
        self.connected()?;
        let Some(stream) = self.stream.as_mut() else {
            // A listening line with no client: the bytes fall off the line, as on a
            // disconnected serial cable.
            return Ok(());
        };
        match stream.write_all(bytes) {
            Ok(()) => Ok(()),
            Err(e) if self.listener.is_some() => {
                let _ = e;
                self.lost();
                Ok(())
            }
            Err(e) => Err(e),
        }
    }

    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        loop {
            self.try_accept()?;
            self.connected()?;
            let left = remaining(deadline);
            let Some(stream) = self.stream.as_mut() else {
                if left.is_zero() {
                    return Ok(0);
                }
                std::thread::sleep(left.min(Duration::from_millis(10)));
                continue;
            };
            stream.set_read_timeout(Some(left.max(Duration::from_micros(1))))?;
            match stream.read(buf) {
                Ok(0) => {
                    if self.listener.is_some() {
                        self.lost();
                        continue;
                    }
                    return Err(io::Error::new(
                        io::ErrorKind::ConnectionAborted,
                        format!("{}: the peer closed the connection", self.name),
                    ));
                }
                Ok(n) => {
                    if self.fresh {
                        let got = buf[..n].to_vec();
                        self.check_busy(&got)?;
                    }
                    return Ok(n);
                }
                Err(e)
                    if matches!(
                        e.kind(),
                        io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut
                    ) =>
                {
                    return Ok(0);
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) if self.listener.is_some() => {
                    let _ = e;
                    self.lost();
                }
                Err(e) => return Err(e),
            }
        }
    }

    fn available(&mut self) -> io::Result<usize> {
        self.try_accept()?;
        let Some(stream) = self.stream.as_mut() else {
            return Ok(0);
        };
        stream.set_nonblocking(true)?;
        let mut tmp = [0u8; 4096];
        let r = stream.peek(&mut tmp);
        stream.set_nonblocking(false)?;
        match r {
            Ok(n) => Ok(n),
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => Ok(0),
            Err(e) => Err(e),
        }
    }

    fn flush_input(&mut self) -> io::Result<()> {
        let mut tmp = [0u8; 4096];
        loop {
            let n = self.available()?;
            if n == 0 {
                return Ok(());
            }
            let got = self.recv(&mut tmp, Instant::now())?;
            if got == 0 {
                return Ok(());
            }
        }
    }

    fn name(&self) -> String {
        self.name.clone()
    }

    fn offers_beacon(&self) -> bool {
        true
    }

    fn beacon(&mut self) -> Option<crate::Beacon> {
        let mut stream = self.stream.as_ref()?.try_clone().ok()?;
        Some(Box::new(move |bytes: &[u8]| stream.write_all(bytes)))
    }
}

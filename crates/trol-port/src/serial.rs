//! Serial devices and pseudo-terminals, through the `serialport` crate: 8 data bits, no
//! parity, 1 stop bit, no flow control, raw mode.
//!
//! Writes go straight to the device's descriptor (Unix): one write(2) where the kernel takes
//! the bytes, without the crate's poll before each write and its tcdrain after it. The link
//! times its answers from when the bytes were handed over plus their line time
//! (`LinkConfig::line_time`), and the EOT confirms delivery as the manual says; a drain per
//! write only cost two system calls and the line's idle time (docs/performance.md, "System
//! calls"). Reads keep the crate's one poll per read.

use std::io::{self, Read, Write};
use std::time::{Duration, Instant};

use serialport::{ClearBuffer, DataBits, FlowControl, Parity, SerialPort, StopBits};

use crate::{Port, remaining};

/// A serial device (USB adapters and pseudo-terminals included).
pub struct SerialLine {
    port: Box<dyn SerialPort>,
    /// The device's descriptor, written directly (Unix; `None` for a port opened elsewhere).
    fd: Option<RawFd>,
    name: String,
    /// The second handle the keep-alive writes through ([`Port::beacon`]), made once.
    second: Option<std::sync::Arc<std::sync::Mutex<Box<dyn SerialPort>>>>,
}

#[cfg(unix)]
type RawFd = std::os::fd::RawFd;
#[cfg(not(unix))]
type RawFd = i32;

impl std::fmt::Debug for SerialLine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SerialLine")
            .field("name", &self.name)
            .finish()
    }
}

impl SerialLine {
    /// Open the device at `path` at `baud`, 8N1, raw.
    pub fn open(path: &str, baud: u32) -> io::Result<SerialLine> {
        SerialLine::open_with(path, baud, false)
    }

    /// Like [`SerialLine::open`], with RTS/CTS hardware flow control if `rts_cts`.
    pub fn open_with(path: &str, baud: u32, rts_cts: bool) -> io::Result<SerialLine> {
        let builder = serialport::new(path, baud)
            .data_bits(DataBits::Eight)
            .parity(Parity::None)
            .stop_bits(StopBits::One)
            .flow_control(if rts_cts {
                FlowControl::Hardware
            } else {
                FlowControl::None
            })
            .timeout(Duration::from_millis(100));
        #[cfg(unix)]
        {
            use std::os::fd::AsRawFd;
            let port = builder.open_native().map_err(open_error)?;
            let fd = Some(port.as_raw_fd());
            Ok(SerialLine {
                port: Box::new(port),
                fd,
                name: path.to_string(),
                second: None,
            })
        }
        #[cfg(not(unix))]
        Ok(SerialLine {
            port: builder.open().map_err(open_error)?,
            fd: None,
            name: path.to_string(),
            second: None,
        })
    }

    /// Wrap a port opened elsewhere.
    pub fn from_port(port: Box<dyn SerialPort>) -> SerialLine {
        let name = port.name().unwrap_or_else(|| "serial".into());
        SerialLine {
            port,
            fd: None,
            name,
            second: None,
        }
    }

    /// A new pseudo-terminal pair: `(controlling end, other end)`. The other end has a path
    /// (`/dev/pts/N`) that a second process can open by name.
    #[cfg(unix)]
    pub fn pty_pair() -> io::Result<(SerialLine, SerialLine, String)> {
        use std::os::fd::AsRawFd;
        let (master, slave) = serialport::TTYPort::pair().map_err(io::Error::from)?;
        let path = slave
            .name()
            .ok_or_else(|| io::Error::other("the pty has no path"))?;
        let (master_fd, slave_fd) = (master.as_raw_fd(), slave.as_raw_fd());
        Ok((
            SerialLine {
                port: Box::new(master),
                fd: Some(master_fd),
                name: "pty-master".into(),
                second: None,
            },
            SerialLine {
                port: Box::new(slave),
                fd: Some(slave_fd),
                name: path.clone(),
                second: None,
            },
            path,
        ))
    }
}

/// The crate's error on opening, as an I/O error: its failed flock (another program has the
/// device open through the crate, as TROL does) is the device being busy, as EBUSY is.
fn open_error(e: serialport::Error) -> io::Error {
    if e.kind == serialport::ErrorKind::NoDevice && e.description.contains("lock") {
        io::Error::new(io::ErrorKind::ResourceBusy, e.description)
    } else {
        io::Error::from(e)
    }
}

impl Port for SerialLine {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        #[cfg(unix)]
        if let Some(fd) = self.fd {
            use std::os::fd::FromRawFd;
            // SAFETY: `fd` is the open descriptor `self.port` owns and keeps open for as long
            // as `self` lives; ManuallyDrop never closes it. (The crate's one unsafe block:
            // std has no safe way to write to a descriptor another value owns.)
            #[allow(unsafe_code)]
            let mut device = std::mem::ManuallyDrop::new(unsafe { std::fs::File::from_raw_fd(fd) });
            let mut rest = bytes;
            while !rest.is_empty() {
                match device.write(rest) {
                    Ok(0) => return Err(io::ErrorKind::WriteZero.into()),
                    Ok(n) => rest = &rest[n..],
                    Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                    // A descriptor without blocking (a pty pair's end) whose buffer is full:
                    // the crate's write waits until it takes the rest, at most a second.
                    Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                        self.port
                            .set_timeout(Duration::from_secs(1))
                            .map_err(io::Error::from)?;
                        return self.port.write_all(rest);
                    }
                    Err(e) => return Err(e),
                }
            }
            return Ok(());
        }
        self.port.write_all(bytes)?;
        self.port.flush()
    }

    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        if buf.is_empty() {
            return Ok(0);
        }
        loop {
            let left = remaining(deadline);
            // serialport treats a zero timeout as "poll once".
            self.port
                .set_timeout(left.max(Duration::from_micros(1)))
                .map_err(io::Error::from)?;
            match self.port.read(buf) {
                Ok(n) => return Ok(n),
                Err(e) if e.kind() == io::ErrorKind::TimedOut => return Ok(0),
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => return Ok(0),
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {
                    if left.is_zero() {
                        return Ok(0);
                    }
                }
                Err(e) => return Err(e),
            }
        }
    }

    fn available(&mut self) -> io::Result<usize> {
        Ok(self.port.bytes_to_read().map_err(io::Error::from)? as usize)
    }

    fn flush_input(&mut self) -> io::Result<()> {
        self.port.clear(ClearBuffer::Input).map_err(io::Error::from)
    }

    fn name(&self) -> String {
        self.name.clone()
    }

    fn offers_beacon(&self) -> bool {
        true
    }

    fn beacon(&mut self) -> Option<crate::Beacon> {
        // One second handle for the line's life, shared by every beacon: a request's
        // keep-alive then costs no system call before the request runs (a handle made per
        // request cost three: dup, TIOCNXCL, close).
        if self.second.is_none() {
            let device = self.port.try_clone().ok()?;
            self.second = Some(std::sync::Arc::new(std::sync::Mutex::new(device)));
        }
        let device = self.second.clone()?;
        Some(Box::new(move |bytes: &[u8]| {
            let mut device = device.lock().unwrap_or_else(|e| e.into_inner());
            match device.write(bytes) {
                Ok(_) => Ok(()),
                // A full buffer (a pty nobody reads): this keep-alive is not needed either.
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => Ok(()),
                Err(e) if e.kind() == io::ErrorKind::TimedOut => Ok(()),
                Err(e) => Err(e),
            }
        }))
    }
}

/// Serial ports of this machine, as `(name, description)`.
pub fn list() -> io::Result<Vec<(String, String)>> {
    let ports = serialport::available_ports().map_err(io::Error::from)?;
    Ok(ports
        .into_iter()
        .map(|p| {
            let what = match p.port_type {
                serialport::SerialPortType::UsbPort(u) => format!(
                    "USB {:04x}:{:04x}{}",
                    u.vid,
                    u.pid,
                    u.product.map(|s| format!(" {s}")).unwrap_or_default()
                ),
                serialport::SerialPortType::PciPort => "PCI".into(),
                serialport::SerialPortType::BluetoothPort => "Bluetooth".into(),
                serialport::SerialPortType::Unknown => "serial".into(),
            };
            (p.port_name, what)
        })
        .collect())
}

//! `trol trace`: the traffic layer by layer. Layer 2's control codes, headers and frames with
//! their checks; layer 3's transaction numbers; layer 4's records decoded into commands and
//! replies with their return codes; with times. Either as a spy between an application and
//! the controller (a relay like `trol link` that also decodes), or from a capture file.
//!
//! The capture format is text, one chunk of bytes per line:
//! `SECONDS DIRECTION HEX`, for example `0.012345 pc 99` (DIRECTION is `pc` for bytes from
//! the application, `ctl` for bytes from the controller).

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use clap::{Args, Subcommand};
use trol_proto::link::BlockCheck;
use trol_proto::link::codes::NakCode;
use trol_proto::link::control;
use trol_proto::link::frame;
use trol_proto::link::monitor::{FrameEnd, Message, Monitor, Seen};

use trol_proto::application::Catalog;

use crate::link::{Side, open_side, relay};

#[derive(Subcommand, Debug)]
pub enum Trace {
    /// Relay between the controller's port and the application's, and show what passes.
    ///
    /// Example: trol trace spy /dev/pts/4 listen://127.0.0.1:7001 --capture run.cap
    /// (the application then uses --port socket://127.0.0.1:7001)
    Spy(SpyArgs),
    /// Decode a capture written by `trol trace spy --capture`.
    ///
    /// Example: trol trace read run.cap
    Read {
        /// The capture file.
        file: PathBuf,
        /// Commands an application added, described in FILE (docs/extending.md), shown by
        /// their names and arguments.
        #[arg(long, value_name = "FILE")]
        commands: Option<PathBuf>,
    },
}

#[derive(Args, Debug)]
pub struct SpyArgs {
    /// The controller's port: a serial device, a pty, or socket://HOST:PORT.
    controller: String,
    /// The application's side: `pty` (a new pseudo-terminal), a serial device, or
    /// listen://HOST:PORT.
    application: String,
    /// Baud rate of serial devices.
    #[arg(long, default_value_t = 9600)]
    baud: u32,
    /// Also write the raw traffic to this capture file.
    #[arg(long, value_name = "FILE")]
    capture: Option<PathBuf>,
    /// Commands an application added, described in FILE (docs/extending.md), shown by their
    /// names and arguments.
    #[arg(long, value_name = "FILE")]
    commands: Option<PathBuf>,
}

/// Who sent the bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dir {
    /// The application (the PC).
    Pc,
    /// The controller.
    Ctl,
}

impl Dir {
    fn label(self) -> &'static str {
        match self {
            Dir::Pc => "PC  -> CTL",
            Dir::Ctl => "CTL -> PC ",
        }
    }
    fn word(self) -> &'static str {
        match self {
            Dir::Pc => "pc",
            Dir::Ctl => "ctl",
        }
    }
}

/// Decodes both directions and writes lines to `out`: layer 2 through the protocol core's
/// passive reader ([`Monitor`]), layer 4 through the catalog.
pub struct Decoder<W: Write> {
    out: W,
    catalog: Catalog,
    pc: Monitor,
    ctl: Monitor,
    last_request: Option<(Vec<u8>, f64)>,
    /// The controller's BIOS codes: the default until a GetCodes reply goes by, then the
    /// controller's own (docs/protocol.md, "Codes").
    codes: &'static trol::CodeTable,
}

impl<W: Write> Decoder<W> {
    /// A decoder that names records from `catalog`.
    pub fn new(out: W, catalog: Catalog) -> Self {
        Decoder {
            out,
            catalog,
            pc: Monitor::new(),
            ctl: Monitor::new(),
            last_request: None,
            codes: trol::default_codes(),
        }
    }

    fn line(&mut self, t: f64, dir: Dir, what: String) {
        let _ = writeln!(self.out, "{:>10.3} ms  {}  {what}", t * 1e3, dir.label());
    }

    /// Bytes from `dir` at `t` seconds.
    pub fn feed(&mut self, t: f64, dir: Dir, bytes: &[u8]) {
        let seen = match dir {
            Dir::Pc => self.pc.feed(bytes),
            Dir::Ctl => self.ctl.feed(bytes),
        };
        for s in seen {
            self.show(t, dir, s);
        }
    }

    fn show(&mut self, t: f64, dir: Dir, seen: Seen) {
        let what = match seen {
            Seen::Text(text) => format!(
                "terminal text \"{}\"",
                String::from_utf8_lossy(&text).escape_debug()
            ),
            Seen::Control(c) => control::name_of(c).unwrap_or("control").to_string(),
            Seen::Nak(code) => format!(
                "NAK {}",
                NakCode::from_byte(code)
                    .map(|c| c.name().to_string())
                    .unwrap_or_else(|| format!("{code:#04x}"))
            ),
            Seen::Stray(b) => control::name_of(b)
                .map(|n| format!("{n} out of place"))
                .unwrap_or_else(|| format!("byte {b:#04x} outside a block")),
            Seen::Header {
                len,
                pci,
                first_word,
                bcc,
                check,
            } => {
                // In CRC-16 mode the PCI's bits 9..15 are the check of the whole message.
                let shown = match check {
                    Some(BlockCheck::Crc16) => format!(
                        "PCI {:#06x} (transaction {}), message check {:#04x}",
                        pci & frame::PCI_LAYER3_BITS,
                        pci & 0xFF,
                        pci >> 9
                    ),
                    _ => format!("PCI {pci:#06x} (transaction {})", pci & 0xFF),
                };
                format!(
                    "HEADER #bytes {len}, {shown}, first word {first_word:02x?}, BCC {bcc:#06x} {}",
                    verdict(check)
                )
            }
            Seen::Frame {
                index,
                data,
                bcc,
                check,
                end,
            } => format!(
                "FRAME id {index}, {} data bytes, BCC {bcc:#06x} {}, {}",
                data.len(),
                verdict(check),
                match end {
                    FrameEnd::Etx => "ETX",
                    FrameEnd::Etb => "ETB",
                    FrameEnd::Bad => "bad terminator",
                }
            ),
            Seen::Message(Message::Incomplete { got, len }) => {
                format!("message incomplete: {got} of {len} bytes")
            }
            Seen::Message(Message::CheckWrong) => "message check WRONG: not delivered".into(),
            Seen::Message(Message::Delivered { pci, bytes }) => {
                return self.message(t, dir, pci, bytes);
            }
            // A kind of sight the core adds later: its form, unformatted.
            other => format!("{other:?}"),
        };
        self.line(t, dir, what);
    }

    fn message(&mut self, t: f64, dir: Dir, pci: u16, bytes: Vec<u8>) {
        let n = pci & 0xFF;
        match dir {
            Dir::Pc => {
                let text = self.catalog.request_text(&bytes);
                self.line(t, dir, format!("REQUEST #{n}: {text}"));
                self.last_request = Some((bytes, t));
            }
            Dir::Ctl => {
                if let Some((req, _)) = &self.last_request
                    && req.first() == Some(&trol::table::GET_CODES.code)
                    && let Ok(trol::Reply::Codes(codes)) =
                        trol::Reply::decode(&trol::table::GET_CODES, &bytes)
                {
                    // The controller told its codes: name them its way from now on.
                    self.codes = trol::codes::intern(&codes);
                }
                let (text, after) = match &self.last_request {
                    Some((req, t0)) => (
                        self.catalog.reply_text(req, &bytes, self.codes),
                        format!(" ({:.1} ms after the request)", (t - t0) * 1e3),
                    ),
                    None => (format!("{bytes:02x?}"), String::new()),
                };
                self.line(t, dir, format!("REPLY   #{n}: {text}{after}"));
            }
        }
    }
}

fn verdict(check: Option<BlockCheck>) -> &'static str {
    match check {
        Some(BlockCheck::Crc16) => "ok (CRC16)",
        Some(BlockCheck::Lrc) => "ok (LRC)",
        None => "WRONG",
    }
}

/// Read a capture file into the decoder.
fn read(file: &PathBuf, catalog: Catalog) -> Result<(), String> {
    let text = std::fs::read_to_string(file)
        .map_err(|e| format!("cannot read {}: {e}", file.display()))?;
    let stdout = std::io::stdout();
    let mut d = Decoder::new(stdout.lock(), catalog);
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let bad = |why: &str| {
            format!(
                "{}:{}: {why}; expected `SECONDS pc|ctl HEX`, like `0.0125 pc 99`",
                file.display(),
                n + 1
            )
        };
        let mut parts = line.split_whitespace();
        let t: f64 = parts
            .next()
            .and_then(|s| s.parse().ok())
            .ok_or_else(|| bad("no time"))?;
        let dir = match parts.next() {
            Some("pc") => Dir::Pc,
            Some("ctl") => Dir::Ctl,
            _ => return Err(bad("no direction")),
        };
        let hex: String = parts.collect();
        if hex.len() % 2 != 0 {
            return Err(bad("an odd number of hex digits"));
        }
        let bytes = (0..hex.len())
            .step_by(2)
            .map(|i| u8::from_str_radix(&hex[i..i + 2], 16))
            .collect::<Result<Vec<u8>, _>>()
            .map_err(|_| bad("not hex"))?;
        d.feed(t, dir, &bytes);
    }
    Ok(())
}

pub fn run(t: Trace) -> Result<(), String> {
    match t {
        Trace::Read { file, commands } => {
            read(&file, trol::described::catalog(commands.as_deref())?)
        }
        Trace::Spy(a) => {
            let catalog = trol::described::catalog(a.commands.as_deref())?;
            let mut ctl = open_side(&a.controller, a.baud, Side::Controller)?;
            let mut app = open_side(&a.application, a.baud, Side::Application)?;
            say!("trol trace: application on {}", app.name);
            let mut capture = match &a.capture {
                Some(p) => Some(std::io::BufWriter::new(
                    std::fs::File::create(p)
                        .map_err(|e| format!("cannot create {}: {e}", p.display()))?,
                )),
                None => None,
            };
            let start = Instant::now();
            let stdout = std::io::stdout();
            let mut d = Decoder::new(stdout.lock(), catalog);
            relay(&mut ctl.port, &mut app.port, &mut |from_app, bytes| {
                let t = start.elapsed().as_secs_f64();
                let dir = if from_app { Dir::Pc } else { Dir::Ctl };
                if let Some(c) = capture.as_mut() {
                    let hex: String = bytes.iter().map(|b| format!("{b:02x}")).collect();
                    let _ = writeln!(c, "{t:.6} {} {hex}", dir.word());
                    let _ = c.flush();
                }
                d.feed(t, dir, bytes);
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use trol_proto::link::control::{ACK, ENQ, EOT, NAK};
    use trol_proto::link::frame::{Header, encode_frame};

    #[test]
    fn a_transaction_decodes_layer_by_layer() {
        let mut out = Vec::new();
        let mut d = Decoder::new(&mut out, Catalog::builtin());
        // TROLHome(0) as a 2-byte message, travelling in the header alone.
        let req = [7u8, 0];
        d.feed(0.0, Dir::Pc, &[ENQ]);
        d.feed(0.001, Dir::Ctl, &[ACK]);
        d.feed(
            0.002,
            Dir::Pc,
            &Header::for_message(&req, 1).encode(BlockCheck::Lrc),
        );
        d.feed(0.003, Dir::Ctl, &[ACK]);
        d.feed(0.004, Dir::Pc, &[EOT]);
        // The reply: -1 as a 2-byte message, in pieces.
        let reply = (-1i16).to_le_bytes();
        let pci = frame::line_pci(BlockCheck::Crc16, 1, &reply);
        let h = Header::for_message(&reply, pci).encode(BlockCheck::Crc16);
        d.feed(0.010, Dir::Ctl, &[ENQ]);
        d.feed(0.011, Dir::Pc, &[ACK]);
        d.feed(0.012, Dir::Ctl, &h[..4]);
        d.feed(0.013, Dir::Ctl, &h[4..]);
        d.feed(0.014, Dir::Pc, &[NAK, 0xF1]);
        d.feed(0.015, Dir::Ctl, &[EOT]);
        // A longer request with one frame: MoveII.
        let long: Vec<u8> = (0..40u8).collect();
        d.feed(
            0.02,
            Dir::Pc,
            &Header::for_message(&long, frame::line_pci(BlockCheck::Crc16, 2, &long))
                .encode(BlockCheck::Crc16),
        );
        let mut f = Vec::new();
        encode_frame(&long, 0, BlockCheck::Crc16, &mut f);
        d.feed(0.021, Dir::Pc, &f);
        let text = String::from_utf8(out).unwrap();
        assert!(text.contains("PC  -> CTL  ENQ"), "{text}");
        assert!(
            text.contains("HEADER #bytes 2, PCI 0x0001 (transaction 1)"),
            "{text}"
        );
        assert!(text.contains("REQUEST #1: TROLHome 0"), "{text}");
        assert!(text.contains("NAK ERR_BCC"), "{text}");
        assert!(text.contains("REPLY   #1: -1 (BIOS_NOT_HOMED)"), "{text}");
        assert!(text.contains("FRAME id 0, 38 data bytes, BCC"), "{text}");
        assert!(text.contains("ok (CRC16), ETX"), "{text}");
        assert!(text.contains("ok (LRC)"), "{text}");
    }

    #[test]
    fn terminal_text_and_a_damaged_header_are_shown() {
        let mut out = Vec::new();
        let mut d = Decoder::new(&mut out, Catalog::builtin());
        d.feed(0.0, Dir::Pc, b"PCP TROL\r");
        d.feed(0.05, Dir::Ctl, b"\r\n>>");
        d.feed(0.06, Dir::Pc, &[ENQ]);
        let mut h = Header::for_message(&[7, 0], 1).encode(BlockCheck::Crc16);
        h[2] ^= 0x10;
        d.feed(0.1, Dir::Pc, &h);
        let text = String::from_utf8(out).unwrap();
        assert!(text.contains("terminal text \"PCP TROL\\r\""), "{text}");
        assert!(text.contains("CTL -> PC   terminal text \"\\r\""), "{text}");
        assert!(text.contains("WRONG"), "{text}");
    }
}

//! Terminal mode: what the controller does when it is not serving TROL (where a real C500
//! speaks RAPL to a terminal), and the activation sequence that starts server mode
//! (docs/protocol.md, "The controller's modes").

pub use trol_proto::activation::{
    ACTIVATE, ACTIVATED, Activation, activated_line, activation_line,
};

/// The prompt.
pub const PROMPT: &str = "\r\n>>";

/// The terminal's line discipline, sans-IO: bytes in, echo and answers out.
#[derive(Debug, Default)]
pub struct Terminal {
    line: Vec<u8>,
    /// Know only the manual's bare `PCP TROL` (a 1998 controller, simulated).
    manual_only: bool,
}

impl Terminal {
    /// A terminal that knows only the manual's bare activation line, as a controller with
    /// the 1998 PCP server would: a line with a block check's word is an unknown line.
    pub fn manual_only() -> Terminal {
        Terminal {
            line: Vec::new(),
            manual_only: true,
        }
    }

    /// Take bytes from the line; append what to send back to `out`. Returns the activation,
    /// when its line arrived (the rest of `input` is dropped).
    pub fn feed(&mut self, input: &[u8], out: &mut Vec<u8>) -> Option<Activation> {
        for &b in input {
            match b {
                0x03 => {
                    self.line.clear();
                    out.extend_from_slice(PROMPT.as_bytes());
                }
                b'\r' | b'\n' => {
                    let line = String::from_utf8_lossy(&self.line)
                        .trim()
                        .to_ascii_uppercase();
                    self.line.clear();
                    let activation = Activation::of_line(&line)
                        .filter(|a| !self.manual_only || *a == Activation::Manual);
                    if let Some(activation) = activation {
                        out.extend_from_slice(b"\r\n");
                        out.extend_from_slice(activation.answer().as_bytes());
                        out.extend_from_slice(b"\r\n");
                        return Some(activation);
                    }
                    if b == b'\r' {
                        if line.is_empty() {
                            out.extend_from_slice(PROMPT.as_bytes());
                        } else {
                            out.extend_from_slice(b"\r\n012-COMMAND ERROR.");
                            out.extend_from_slice(PROMPT.as_bytes());
                        }
                    }
                }
                0x20..=0x7E if self.line.len() < 256 => {
                    self.line.push(b);
                    out.push(b);
                }
                _ => {}
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use trol_proto::link::BlockCheck;

    #[test]
    fn activation_and_other_lines() {
        let mut t = Terminal::default();
        let mut out = Vec::new();
        assert_eq!(t.feed(b"HELP\r", &mut out), None);
        assert!(String::from_utf8_lossy(&out).contains("012-COMMAND ERROR."));
        out.clear();
        // Protocol bytes (ENQ) are not echoed and do not activate.
        assert_eq!(t.feed(&[0x99, 0x1E], &mut out), None);
        assert!(out.is_empty());
        // The bare line is a 1998 host's: the manual's LRC and sizes, and the bare answer.
        assert_eq!(
            t.feed(b"\x03\rpcp trol\r", &mut out),
            Some(Activation::Manual)
        );
        assert!(String::from_utf8_lossy(&out).ends_with("pcp trol\r\nPCP TROL ACTIVE\r\n"));
        out.clear();
        assert_eq!(
            t.feed(b"PCP TROL LRC\r", &mut out),
            Some(Activation::Trol(BlockCheck::Lrc))
        );
        assert!(String::from_utf8_lossy(&out).ends_with("PCP TROL ACTIVE LRC\r\n"));
        out.clear();
        assert_eq!(
            t.feed(b"PCP TROL CRC16\r", &mut out),
            Some(Activation::Trol(BlockCheck::Crc16))
        );
        assert!(String::from_utf8_lossy(&out).ends_with("PCP TROL ACTIVE CRC16\r\n"));
        out.clear();
        // An unknown check is an unknown line.
        assert_eq!(t.feed(b"PCP TROL MD5\r", &mut out), None);
        assert!(String::from_utf8_lossy(&out).contains("012-COMMAND ERROR."));
    }

    #[test]
    fn a_1998_controller_knows_only_the_bare_line() {
        let mut t = Terminal::manual_only();
        let mut out = Vec::new();
        assert_eq!(t.feed(b"\x03\rPCP TROL CRC16\r", &mut out), None);
        assert!(String::from_utf8_lossy(&out).ends_with("012-COMMAND ERROR.\r\n>>"));
        out.clear();
        assert_eq!(t.feed(b"PCP TROL LRC\r", &mut out), None);
        assert_eq!(t.feed(b"PCP TROL\r", &mut out), Some(Activation::Manual));
        assert!(String::from_utf8_lossy(&out).ends_with("PCP TROL ACTIVE\r\n"));
    }
}

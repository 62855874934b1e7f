//! Terminal mode: what the controller does when it is not serving TROL (where a real C500
//! speaks RAPL to a terminal), and the activation sequence that starts server mode
//! (docs/protocol.md, "The controller's modes").

use trol_proto::link::BlockCheck;

pub use trol_proto::activation::{ACTIVATE, ACTIVATED, activated_line, activation_line};

/// The prompt.
pub const PROMPT: &str = "\r\n>>";

/// The terminal's line discipline, sans-IO: bytes in, echo and answers out.
#[derive(Debug, Default)]
pub struct Terminal {
    line: Vec<u8>,
}

impl Terminal {
    /// Take bytes from the line; append what to send back to `out`. Returns the block check
    /// the activation line asked for, when it arrived (the rest of `input` is dropped).
    pub fn feed(&mut self, input: &[u8], out: &mut Vec<u8>) -> Option<BlockCheck> {
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
                    let check = match line.strip_prefix(ACTIVATE).map(str::trim) {
                        Some("") => Some(BlockCheck::Lrc),
                        Some(word) => BlockCheck::from_word(word),
                        None => None,
                    };
                    if let Some(check) = check {
                        out.extend_from_slice(b"\r\n");
                        out.extend_from_slice(activated_line(check).as_bytes());
                        out.extend_from_slice(b"\r\n");
                        return Some(check);
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
        assert_eq!(t.feed(b"\x03\rpcp trol\r", &mut out), Some(BlockCheck::Lrc));
        assert!(String::from_utf8_lossy(&out).ends_with("PCP TROL ACTIVE LRC\r\n"));
        out.clear();
        assert_eq!(
            t.feed(b"PCP TROL CRC16\r", &mut out),
            Some(BlockCheck::Crc16)
        );
        assert!(String::from_utf8_lossy(&out).ends_with("PCP TROL ACTIVE CRC16\r\n"));
        out.clear();
        // An unknown check is an unknown line.
        assert_eq!(t.feed(b"PCP TROL MD5\r", &mut out), None);
        assert!(String::from_utf8_lossy(&out).contains("012-COMMAND ERROR."));
    }
}

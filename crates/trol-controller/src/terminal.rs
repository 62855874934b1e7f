//! Terminal mode: what the controller does when it is not serving TROL (where a real C500
//! speaks RAPL to a terminal), and the activation sequence that starts server mode
//! (docs/protocol.md, "The controller's modes").

/// The line that starts server mode.
pub const ACTIVATE: &str = "PCP TROL";
/// The controller's answer to it.
pub const ACTIVATED: &str = "PCP TROL ACTIVE\r\n";
/// The prompt.
pub const PROMPT: &str = "\r\n>>";

/// The terminal's line discipline, sans-IO: bytes in, echo and answers out.
#[derive(Debug, Default)]
pub struct Terminal {
    line: Vec<u8>,
}

impl Terminal {
    /// Take bytes from the line; append what to send back to `out`. Returns true when the
    /// activation line arrived (the rest of `input` is dropped).
    pub fn feed(&mut self, input: &[u8], out: &mut Vec<u8>) -> bool {
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
                    if line == ACTIVATE {
                        out.extend_from_slice(b"\r\n");
                        out.extend_from_slice(ACTIVATED.as_bytes());
                        return true;
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
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn activation_and_other_lines() {
        let mut t = Terminal::default();
        let mut out = Vec::new();
        assert!(!t.feed(b"HELP\r", &mut out));
        assert!(String::from_utf8_lossy(&out).contains("012-COMMAND ERROR."));
        out.clear();
        // Protocol bytes (ENQ) are not echoed and do not activate.
        assert!(!t.feed(&[0x99, 0x1E], &mut out));
        assert!(out.is_empty());
        assert!(t.feed(b"\x03\rpcp trol\r", &mut out));
        assert!(String::from_utf8_lossy(&out).ends_with(ACTIVATED));
    }
}

//! The transcript of a session with a real controller: every byte both ways, in order (a
//! first contact, a session that failed), and the controller's bytes as text for logs.

/// Bytes as text: printable ASCII as is, anything else as `\xNN`.
pub fn printable(bytes: &[u8]) -> String {
    let mut s = String::new();
    for &b in bytes {
        if (0x20..0x7f).contains(&b) {
            s.push(b as char);
        } else {
            s.push_str(&format!("\\x{b:02x}"));
        }
    }
    s
}

/// Every byte both ways, in order.
#[derive(Clone, Debug, Default)]
pub struct Transcript {
    /// `(sent, bytes)` in order: `sent` for what TROL sent.
    pub chunks: Vec<(bool, Vec<u8>)>,
}

impl Transcript {
    /// The transcript as text: `> ` for what TROL sent, `< ` for what it read, a line per
    /// chunk, bytes as [`printable`] shows them.
    pub fn text(&self) -> String {
        let mut s = String::new();
        for (sent, b) in &self.chunks {
            s.push_str(if *sent { "> " } else { "< " });
            s.push_str(&printable(b));
            s.push('\n');
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_ways_in_order_and_every_byte_shown() {
        let t = Transcript {
            chunks: vec![(true, b"w2\r".to_vec()), (false, b"ok\r\n\xff".to_vec())],
        };
        assert_eq!(t.text(), "> w2\\x0d\n< ok\\x0d\\x0a\\xff\n");
    }
}

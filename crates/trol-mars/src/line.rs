//! The MARS 8 line, sans-IO: bytes in, lines and replies out (docs/mars.md, "The line").
//!
//! Commands are ASCII lines ending in `\n` (`COORDMV:1,2,3,4,5,6`); a query is `NAME?` and its
//! answer a line `NAME=value`; `STAMP:n` is answered by `STAMP=n` once everything before it
//! has been processed; `R:` by `R!` (ready) or `FAIL!`. Replies end in `\r\n` (the public
//! client also accepts `\n` and `\r`). Nothing else is known to be printed.

/// The longest line kept; a longer one is cut there (a noisy line cannot fill memory).
pub const MAX_LINE: usize = 512;

/// Splits what arrives into lines: `\r\n`, `\r` and `\n` end one; empty lines are dropped.
#[derive(Debug, Default)]
pub struct Lines {
    buf: Vec<u8>,
    cut: bool,
}

impl Lines {
    /// Feed bytes; returns the lines they complete (as text, bytes outside ASCII shown as
    /// `\xNN`).
    pub fn feed(&mut self, bytes: &[u8]) -> Vec<String> {
        let mut out = Vec::new();
        for &b in bytes {
            if b == b'\n' || b == b'\r' {
                if !self.buf.is_empty() {
                    out.push(text(&self.buf));
                }
                self.buf.clear();
                self.cut = false;
            } else if self.buf.len() < MAX_LINE {
                self.buf.push(b);
            } else {
                self.cut = true;
            }
        }
        out
    }

    /// Bytes received that no line end has closed yet.
    pub fn partial(&self) -> &[u8] {
        &self.buf
    }

    /// Forget a partial line.
    pub fn clear(&mut self) {
        self.buf.clear();
        self.cut = false;
    }
}

/// Bytes as text: printable ASCII as is, anything else as `\xNN` (the shared core's).
pub use trol_controller::real::printable as text;

/// A line from the unit.
#[derive(Clone, Debug, PartialEq)]
pub enum Reply {
    /// `NAME=value`, the answer to `NAME?` (STAMP included).
    Value {
        /// The name.
        name: String,
        /// The text after `=`.
        value: String,
    },
    /// `R!` or `R<axis>!`: ready.
    Ready(String),
    /// `FAIL!`.
    Fail,
    /// Anything else.
    Other(String),
}

/// What a line is.
pub fn parse(line: &str) -> Reply {
    let l = line.trim();
    if l == "FAIL!" {
        return Reply::Fail;
    }
    if let Some(axis) = l.strip_prefix('R').and_then(|r| r.strip_suffix('!')) {
        if axis.len() <= 1 && axis.chars().all(|c| c.is_ascii_uppercase()) {
            return Reply::Ready(axis.to_string());
        }
    }
    if let Some((name, value)) = l.split_once('=') {
        if !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric()) {
            return Reply::Value {
                name: name.to_string(),
                value: value.trim().to_string(),
            };
        }
    }
    Reply::Other(l.to_string())
}

/// A query's bytes: `\nNAME?\n` (the leading line end closes whatever came before, as the
/// public client does).
pub fn query(name: &str) -> Vec<u8> {
    format!("\n{name}?\n").into_bytes()
}

/// A command's bytes: `TEXT\n`.
pub fn command(text: &str) -> Vec<u8> {
    format!("{text}\n").into_bytes()
}

/// The status word's bits (`ST?`), as the public client reads them.
pub mod st {
    /// The unit reports an error.
    pub const ERROR: u32 = 0x8;
    /// An axis moves (not ready).
    pub const MOVING: u32 = 0x10;
    /// The coordinated-motion queue is full.
    pub const QUEUE_FULL: u32 = 0x80;
    /// Arm power is off.
    pub const POWER_OFF: u32 = 0x1_0000;
    /// Motion stop.
    pub const MOTION_STOP: u32 = 0x2_0000;
}

/// Parse `COORDAP`'s value: nine comma-separated integers, the last six the joint axes' IRC.
/// The public clients agree on nine only: ctu-crs takes the six from index 3 on, pyrocon
/// the last six; any other count is refused, since TROL could not tell which are the axes.
pub fn coordap(value: &str) -> Result<[f64; 6], String> {
    let v: Result<Vec<i64>, _> = value.split(',').map(|s| s.trim().parse::<i64>()).collect();
    match v {
        Ok(v) if v.len() == 9 => Ok(std::array::from_fn(|i| v[3 + i] as f64)),
        _ => Err(format!(
            "COORDAP={value}: expected nine whole numbers (three, then the six axes)"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_end_in_any_of_cr_lf_and_crlf_and_split_across_reads() {
        let mut l = Lines::default();
        assert_eq!(l.feed(b"ST=1"), Vec::<String>::new());
        assert_eq!(l.feed(b"6\r\nR!\rFAIL!\n\n"), vec!["ST=16", "R!", "FAIL!"]);
        assert_eq!(l.feed(b"\x00\xffx\n"), vec!["\\x00\\xffx"]);
        let long = vec![b'A'; 2 * MAX_LINE];
        assert_eq!(l.feed(&long), Vec::<String>::new());
        assert_eq!(l.feed(b"\n")[0].len(), MAX_LINE);
    }

    #[test]
    fn replies_are_told_apart() {
        assert_eq!(parse("R!"), Reply::Ready(String::new()));
        assert_eq!(parse("RG!"), Reply::Ready("G".into()));
        assert_eq!(parse("FAIL!"), Reply::Fail);
        assert_eq!(
            parse("COORDAP=1,0,0,1,2,3,4,5,6"),
            Reply::Value {
                name: "COORDAP".into(),
                value: "1,0,0,1,2,3,4,5,6".into()
            }
        );
        assert_eq!(parse("ERR 3"), Reply::Other("ERR 3".into()));
        assert_eq!(parse("RELEASE!x"), Reply::Other("RELEASE!x".into()));
        assert_eq!(
            coordap("7,0,0,1,-2,3,4,5,6").unwrap(),
            [1.0, -2.0, 3.0, 4.0, 5.0, 6.0]
        );
        assert!(coordap("1,-2,3,4,5,6").is_err());
        assert!(coordap("1,2,3").is_err());
        assert!(coordap("1,2,x,4,5,6").is_err());
        assert_eq!(query("ST"), b"\nST?\n");
    }
}

//! The C500C's front console, sans-IO: bytes in, what the console said out
//! (docs/c500c.md, "The line"; shared/reference/c500c.md).
//!
//! The console is a text terminal: typed characters are echoed, lines end CR LF, and a shell
//! waits for the next line with a prompt that no line end follows: `$ ` for the CROS system
//! shell, `<app>> ` or `<app>[<v3>]> ` for the application shell `ash`. Some commands ask a
//! question back and wait on the same line (`Are you sure you want to exit?`), and a few
//! lines come unasked, in brackets (`[test: Lost robot power]`). [`Console::feed`] turns
//! bytes into [`Said`] items; the partial line that waits is judged a prompt or a question
//! only when it matches one exactly, so a line cut by the serial driver is not taken for one.

/// The longest line kept; a longer one is cut there (a noisy line cannot fill memory).
pub const MAX_LINE: usize = 512;

/// The questions ash is known to ask (CRS's texts in the flash of a C500C): a partial line
/// ending in one of these waits for an answer.
pub const QUESTIONS: &[&str] = &[
    "Are you sure you want to exit?",
    "-- create it?",
    "Limp ALL robot axes?",
    "(y/n) ?",
    "Please answer 'yes' or 'no':",
    "and its value?",
    "Hit <space> or <q>",
];

/// What the console said.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Said {
    /// A whole line (its CR LF taken off).
    Line(String),
    /// A shell's prompt: `$` for the system shell, or the application's name for ash
    /// (`test` for `test> `).
    Prompt(String),
    /// A question that waits for an answer on its own line.
    Question(String),
}

impl std::fmt::Display for Said {
    /// In words for a message: ``the line `x` ``, ``the prompt of `test` ``.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Said::Line(l) if l.trim().is_empty() => write!(f, "an empty line"),
            Said::Line(l) => write!(f, "the line `{l}`"),
            Said::Prompt(p) => write!(f, "the prompt of `{p}`"),
            Said::Question(q) => write!(f, "the question `{q}`"),
        }
    }
}

/// What the console said, or that it said nothing in time, in words for a message.
pub fn heard(said: &Option<Said>) -> String {
    match said {
        Some(s) => s.to_string(),
        None => "nothing in time".into(),
    }
}

/// Lines in words for a message: each in backquotes, or "no line".
pub fn lines_said(lines: &[String]) -> String {
    if lines.is_empty() {
        return "no line".into();
    }
    lines
        .iter()
        .map(|l| format!("`{l}`"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Splits what the console prints into lines, prompts and questions.
#[derive(Debug, Default)]
pub struct Console {
    buf: Vec<u8>,
    /// The last byte was CR (a CR LF pair ends one line, not two).
    after_cr: bool,
    /// A question was just closed: the blank that ends it may come in a later read (the
    /// line paced byte by byte), and is not the start of what follows.
    after_question: bool,
}

impl Console {
    /// Feed bytes; returns what they complete.
    pub fn feed(&mut self, bytes: &[u8]) -> Vec<Said> {
        let mut out = Vec::new();
        for &b in bytes {
            match b {
                b'\n' if self.after_cr => {
                    self.after_cr = false;
                }
                b'\r' | b'\n' => {
                    self.after_cr = b == b'\r';
                    self.after_question = false;
                    // A prompt the console printed before the line (a shell that prompts
                    // and then prints, with no line end between) is a prompt of its own.
                    let mut line = text(&self.buf);
                    while let Some((app, len)) = leading_prompt(&line) {
                        out.push(Said::Prompt(app));
                        line.drain(..len);
                    }
                    out.push(Said::Line(line));
                    self.buf.clear();
                }
                b' ' if self.after_question && self.buf.is_empty() => {}
                _ => {
                    self.after_cr = false;
                    self.after_question = false;
                    if self.buf.len() < MAX_LINE {
                        self.buf.push(b);
                    }
                }
            }
        }
        let mut partial = text(&self.buf);
        // Prompts one after the other (a shell given empty lines, its echo off).
        let mut prompts = Vec::new();
        while let Some((app, len)) = leading_prompt(&partial) {
            prompts.push(app);
            partial.drain(..len);
        }
        if !prompts.is_empty() && partial.is_empty() {
            out.extend(prompts.into_iter().map(Said::Prompt));
            self.buf.clear();
        } else if QUESTIONS.iter().any(|q| partial.trim_end().ends_with(q)) {
            out.push(Said::Question(partial.trim_end().to_string()));
            self.buf.clear();
            self.after_question = true;
        }
        out
    }

    /// Bytes received that no line end, prompt or question has closed yet.
    pub fn partial(&self) -> String {
        text(&self.buf)
    }

    /// What was echoed of a line being typed: the bytes of the partial line, after any
    /// prompt that came before them (raw, to be compared byte for byte with what was typed).
    pub fn echo(&self) -> &[u8] {
        let mut at = 0;
        // A prompt is printable ASCII, so its length as text is its length in bytes.
        while let Some((_, len)) = leading_prompt(&text(&self.buf[at..])) {
            at += len;
        }
        &self.buf[at..]
    }

    /// Forget a partial line.
    pub fn clear(&mut self) {
        self.buf.clear();
        self.after_cr = false;
        self.after_question = false;
    }
}

/// The shell whose prompt `partial` is, if it is one exactly: `$ ` (the system shell, `$`),
/// `NAME> ` or `NAME[FILE]> ` (ash running application NAME).
pub fn prompt(partial: &str) -> Option<String> {
    if partial == "$ " {
        return Some("$".into());
    }
    let head = partial.strip_suffix("> ")?;
    let name = match head.split_once('[') {
        Some((name, rest)) => {
            let file = rest.strip_suffix(']')?;
            if file.is_empty() || file.contains(['[', ']']) {
                return None;
            }
            name
        }
        None => head,
    };
    let word = !name.is_empty()
        && name.len() <= 32
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    word.then(|| name.to_string())
}

/// A prompt at the start of `text` and its length.
fn leading_prompt(text: &str) -> Option<(String, usize)> {
    let end = text.find(' ')? + 1;
    prompt(&text[..end]).map(|app| (app, end))
}

/// Bytes as text: printable ASCII as is, anything else as `\xNN` (the shared core's).
pub use trol_controller::real::printable as text;

/// An unasked line: `[<app>: <text>]` (ash's asynchronous lines, such as `[test: Lost robot
/// power]`) or `[pendant done.]`.
pub fn bracketed(line: &str) -> Option<&str> {
    line.trim()
        .strip_prefix('[')
        .and_then(|l| l.strip_suffix(']'))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn all(c: &mut Console, chunks: &[&[u8]]) -> Vec<Said> {
        chunks.iter().flat_map(|b| c.feed(b)).collect()
    }

    #[test]
    fn lines_prompts_and_questions_in_any_cut() {
        let bytes = b"robotver\r\nVersion string: 'A465 v2.1'\r\ntest> ";
        let whole = all(&mut Console::default(), &[bytes]);
        assert_eq!(
            whole,
            vec![
                Said::Line("robotver".into()),
                Said::Line("Version string: 'A465 v2.1'".into()),
                Said::Prompt("test".into()),
            ]
        );
        // Byte by byte: the same, and no prompt taken from a line cut short (`test>` before
        // its space).
        let mut c = Console::default();
        let single: Vec<&[u8]> = bytes.chunks(1).collect();
        assert_eq!(all(&mut c, &single), whole);
        let asked = all(
            &mut Console::default(),
            &[b"exit\r\nAre you sure you want to exit? "],
        );
        assert_eq!(
            asked.last(),
            Some(&Said::Question("Are you sure you want to exit?".into()))
        );
        // Byte by byte, its blank after it is read: with the echo off, the prompt that
        // follows the answer is still a prompt, and with it on, the echo is the answer.
        let quiet = b"Erase variable 'p1' and its value? test> ";
        let single: Vec<&[u8]> = quiet.chunks(1).collect();
        assert_eq!(
            all(&mut Console::default(), &single),
            vec![
                Said::Question("Erase variable 'p1' and its value?".into()),
                Said::Prompt("test".into()),
            ]
        );
        let echoed = b"Erase variable 'p1' and its value? y\r\ntest> ";
        let single: Vec<&[u8]> = echoed.chunks(1).collect();
        assert_eq!(
            all(&mut Console::default(), &single)[1..],
            [Said::Line("y".into()), Said::Prompt("test".into())]
        );
    }

    #[test]
    fn the_echo_of_a_line_being_typed_is_what_follows_the_prompt() {
        let mut c = Console::default();
        assert!(c.feed(b"test> joi").is_empty());
        assert_eq!(c.echo(), b"joi");
        c.feed(b"nt 3,\xb0");
        assert_eq!(c.echo(), b"joint 3,\xb0");
        let mut c = Console::default();
        assert_eq!(c.feed(b"test> "), vec![Said::Prompt("test".into())]);
        assert_eq!(c.echo(), b"");
        c.feed(b"w2");
        assert_eq!(c.echo(), b"w2");
    }

    #[test]
    fn only_exact_prompts_count() {
        assert_eq!(prompt("$ "), Some("$".into()));
        assert_eq!(prompt("test> "), Some("test".into()));
        assert_eq!(prompt("test[test.v3]> "), Some("test".into()));
        for not in ["test>", "a b> ", "> ", "Joint 1 > ", "x[]> ", "x[a]b> "] {
            assert_eq!(prompt(not), None, "{not}");
        }
    }

    #[test]
    fn lf_alone_and_cr_alone_end_lines_and_noise_is_shown() {
        let mut c = Console::default();
        let said = c.feed(b"a\nb\rc\r\n\x00\xffd\n");
        assert_eq!(
            said,
            vec![
                Said::Line("a".into()),
                Said::Line("b".into()),
                Said::Line("c".into()),
                Said::Line("\\x00\\xffd".into()),
            ]
        );
        assert_eq!(
            bracketed("[test: Lost robot power]"),
            Some("test: Lost robot power")
        );
        // Echo off: prompts one after the other, and a prompt before a line.
        let said = Console::default().feed(b"$ $ $ ");
        assert_eq!(said, vec![Said::Prompt("$".into()); 3]);
        let said = Console::default().feed(b"test> Current speed is 5\r\ntest> ");
        assert_eq!(
            said,
            vec![
                Said::Prompt("test".into()),
                Said::Line("Current speed is 5".into()),
                Said::Prompt("test".into())
            ]
        );
    }
}

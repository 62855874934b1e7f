//! The terminal session, sans-IO: one command line at a time, typed byte by byte with each
//! echo checked, and the reply read up to the prompt (c500-rapl.md §1.3).
//!
//! Bytes in ([`Session::feed`]), bytes out ([`Session::poll_transmit`]), time passed in;
//! no I/O, no clock. The reader takes what the two public drivers saw: an ACK or none, the
//! prompts `>>` and `O>`, up to `extra_after_digit` bytes after the first character of a
//! number, XON/XOFF anywhere (an XOFF that no XON follows within [`XOFF_LIMIT`] is given up,
//! and an urgent line, Halt, is typed through it). What a reply means, success or refusal,
//! the backend decides from the profile ([`crate::backend`]). Anything else is a surprise:
//! the session types Ctrl-C and waits for the prompt and a quiet line before it reports the
//! failure, so no stale byte is ever taken for the next reply. A surprise before the
//! terminator was typed cancels the line: the command did not run.

use std::collections::VecDeque;
use std::time::Duration;

use trol_proto::time::Instant;

use crate::profile::{Flow, Profile};

/// Acknowledge: a command succeeded.
pub const ACK: u8 = 0x06;
/// Flow control: resume sending.
pub const XON: u8 = 0x11;
/// Flow control: stop sending.
pub const XOFF: u8 = 0x13;
/// Ctrl-C: cancel the line, answer with the prompt.
pub const CTRL_C: u8 = 0x03;
/// Ctrl-Z: two of them switch the port back to ACI mode.
pub const CTRL_Z: u8 = 0x1A;

/// How long the line must stay quiet after the prompt that ends a resynchronisation.
pub const SETTLE: Duration = Duration::from_millis(60);
/// How long one Ctrl-C may wait for the prompt (three are tried).
pub const RESYNC_WAIT: Duration = Duration::from_millis(1000);
/// How long an XOFF holds the typing before it is taken for a stray byte and the typing goes
/// on (the controller's XON was lost, or the byte was noise).
pub const XOFF_LIMIT: Duration = Duration::from_millis(1000);

/// The settings the session takes from the profile.
#[derive(Clone, Debug)]
pub struct SessionConfig {
    /// The line terminator.
    pub terminator: u8,
    /// Bytes tolerated after the echo of a number's first character.
    pub extra_after_digit: u8,
    /// Honour XON/XOFF.
    pub flow: Flow,
    /// How long one echo may take.
    pub echo_timeout: Duration,
    /// How long typing waits after a number's first character for the controller's extra
    /// bytes (they may be spaces, which the next typed space would be taken for).
    pub extra_wait: Duration,
}

impl From<&Profile> for SessionConfig {
    fn from(p: &Profile) -> Self {
        SessionConfig {
            terminator: p.terminator.byte(),
            extra_after_digit: p.extra_after_digit,
            flow: p.flow,
            echo_timeout: Duration::from_millis(p.echo_timeout_ms),
            extra_wait: (p.char_time() * 10).max(Duration::from_millis(20)),
        }
    }
}

/// A command's answer.
#[derive(Clone, Debug, PartialEq)]
pub struct Reply {
    /// What the controller printed between the echo and the prompt (ACK bytes removed).
    pub text: String,
    /// Whether an ACK came.
    pub ack: bool,
    /// Bytes the controller sent while the line was typed besides its echo (HELP-mode
    /// completion, the extra bytes after numbers).
    pub extra: Vec<u8>,
}

/// A typed character as a person reads it: the line's end by its name.
fn shown(c: char) -> String {
    match c {
        '\r' => "CR".into(),
        '\n' => "LF".into(),
        c => format!("`{c}`"),
    }
}

/// Where in a line a character was typed (`at` counts from 0; the line's terminator comes
/// after its last character).
fn place(line: &str, at: usize) -> String {
    if at >= line.chars().count() {
        format!("the end of `{line}`")
    } else {
        format!("character {} of `{line}`", at + 1)
    }
}

/// What became of a line whose echo went wrong: cancelled before its end, or, once its end
/// was typed, perhaps taken by the controller.
fn fate(cancelled_before_its_end: bool) -> &'static str {
    if cancelled_before_its_end {
        "the line was cancelled and did not run"
    } else {
        "the controller may have taken the line, so whether it ran is not known"
    }
}

/// Why a command has no answer.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SessionError {
    /// The echo differed from what was typed; the line was cancelled before it ran.
    #[error(
        "the controller echoed {got:#04x} where {} was typed ({}); {}{hint}",
        shown(*.want),
        place(.line, *.at),
        fate(*.at < .line.chars().count() && *.got != b'\r' && *.got != b'\n')
    )]
    Echo {
        /// The line.
        line: String,
        /// Where.
        at: usize,
        /// What was typed.
        want: char,
        /// What came back.
        got: u8,
        /// What to set, when a profile setting explains it.
        hint: String,
    },
    /// No echo in time; the line was cancelled before it ran.
    #[error(
        "no echo of {} within {ms} ms; {}",
        place(.line, *.at),
        fate(*.at < .line.chars().count())
    )]
    EchoTimeout {
        /// The line.
        line: String,
        /// Where.
        at: usize,
        /// The wait.
        ms: u128,
    },
    /// The line was typed but no prompt came in time: whether it ran is not known.
    #[error(
        "`{line}` got no prompt within {ms} ms (received {got:?}); whether it ran is not known"
    )]
    ReplyTimeout {
        /// The line.
        line: String,
        /// The wait.
        ms: u128,
        /// What came.
        got: String,
    },
    /// The controller did not answer Ctrl-C with its prompt: the session is lost.
    #[error(
        "the controller did not answer Ctrl-C with its prompt (after: {cause}); the session is lost"
    )]
    Lost {
        /// What happened before.
        cause: String,
    },
    /// A command was given while another was under way.
    #[error("the session is busy with another command")]
    Busy,
}

impl SessionError {
    /// Whether the command surely did not run (it was cancelled before its terminator). An
    /// echo that came back as a line end is not sure: the controller may have taken a
    /// damaged byte for the terminator and run the line so far.
    pub fn surely_not_run(&self) -> bool {
        match self {
            SessionError::Echo { line, at, got, .. } => {
                *at < line.len() && *got != b'\r' && *got != b'\n'
            }
            // The terminator's echo lost: the controller may have the line.
            SessionError::EchoTimeout { line, at, .. } => *at < line.len(),
            SessionError::Busy => true,
            _ => false,
        }
    }
}

#[derive(Debug)]
enum State {
    Idle,
    Typing {
        line: Vec<u8>,
        next: usize,
        awaiting: Option<Instant>,
        extras: u8,
        in_number: bool,
        reply_timeout: Duration,
        /// A pause before the terminator, in which the controller may complete the word.
        pause: Option<Duration>,
        /// Typed through an XOFF (Halt).
        urgent: bool,
        /// Typing waits for the extra bytes after a number's first character until then.
        hold_until: Option<Instant>,
        pause_until: Option<Instant>,
        extra: Vec<u8>,
        deadline: Instant,
    },
    Reading {
        line: Vec<u8>,
        buf: Vec<u8>,
        extra: Vec<u8>,
        deadline: Instant,
        timeout: Duration,
    },
    Resync {
        buf: Vec<u8>,
        deadline: Instant,
        prompt_at: Option<Instant>,
        cause: Option<SessionError>,
        tries: u8,
    },
    Lost,
}

/// The terminal session.
#[derive(Debug)]
pub struct Session {
    cfg: SessionConfig,
    state: State,
    xoff: bool,
    xoff_since: Option<Instant>,
    xoff_expired: u32,
    tx: VecDeque<u8>,
    events: VecDeque<Result<Reply, SessionError>>,
    stray: Vec<u8>,
    resync_text: Vec<u8>,
}

fn is_numeric(b: u8) -> bool {
    b.is_ascii_digit() || b == b'.' || b == b'-'
}

fn ends_with_prompt(buf: &[u8]) -> bool {
    buf.ends_with(b"\r\n>>") || buf.ends_with(b"\r\nO>")
}

impl Session {
    /// A session at the prompt.
    pub fn new(cfg: SessionConfig) -> Session {
        Session {
            cfg,
            state: State::Idle,
            xoff: false,
            xoff_since: None,
            xoff_expired: 0,
            tx: VecDeque::new(),
            events: VecDeque::new(),
            stray: Vec::new(),
            resync_text: Vec::new(),
        }
    }

    /// Whether no command is under way.
    pub fn is_idle(&self) -> bool {
        matches!(self.state, State::Idle)
    }

    /// Whether a typed line's reply is being read (its terminator was echoed).
    pub fn is_reading(&self) -> bool {
        matches!(self.state, State::Reading { .. })
    }

    /// Whether Ctrl-C found no prompt: nothing more can be sent until [`Session::resync`]
    /// succeeds.
    pub fn is_lost(&self) -> bool {
        matches!(self.state, State::Lost)
    }

    /// Whether the controller has said XOFF.
    pub fn paused(&self) -> bool {
        self.xoff
    }

    /// How many XOFFs were given up since the last call (no XON within [`XOFF_LIMIT`]).
    pub fn take_xoff_expired(&mut self) -> u32 {
        std::mem::take(&mut self.xoff_expired)
    }

    /// Bytes that arrived while no command was under way (dropped; their presence means
    /// the next command must resynchronise first).
    pub fn take_stray(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.stray)
    }

    /// What came from the controller between a surprise and the prompt that ended the
    /// resynchronisation after it (a line it printed unasked may be there).
    pub fn take_resync_text(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.resync_text)
    }

    /// Type `line` (its terminator is added) and read its reply, which may take
    /// `reply_timeout` after the terminator's echo.
    pub fn send_line(
        &mut self,
        line: &str,
        reply_timeout: Duration,
        now: Instant,
    ) -> Result<(), SessionError> {
        self.start(line, reply_timeout, None, false, now)
    }

    /// Like [`Session::send_line`], typed even while the controller says XOFF (Halt: a
    /// controller whose XON was lost must still hear it).
    pub fn send_urgent(
        &mut self,
        line: &str,
        reply_timeout: Duration,
        now: Instant,
    ) -> Result<(), SessionError> {
        self.start(line, reply_timeout, None, true, now)
    }

    /// Like [`Session::send_line`], pausing `pause` before the terminator and taking what
    /// the controller sends meanwhile as its completion of the word (HELP mode: `NOH`).
    pub fn send_completing(
        &mut self,
        prefix: &str,
        pause: Duration,
        reply_timeout: Duration,
        now: Instant,
    ) -> Result<(), SessionError> {
        self.start(prefix, reply_timeout, Some(pause), false, now)
    }

    fn start(
        &mut self,
        line: &str,
        reply_timeout: Duration,
        pause: Option<Duration>,
        urgent: bool,
        now: Instant,
    ) -> Result<(), SessionError> {
        if !self.is_idle() {
            return Err(SessionError::Busy);
        }
        let mut bytes = line.as_bytes().to_vec();
        bytes.push(self.cfg.terminator);
        let per_byte = self.cfg.echo_timeout + Duration::from_millis(20);
        let deadline = now + per_byte * (bytes.len() as u32 + 1) + pause.unwrap_or_default();
        self.state = State::Typing {
            line: bytes,
            next: 0,
            awaiting: None,
            extras: 0,
            in_number: false,
            reply_timeout,
            pause,
            urgent,
            hold_until: None,
            pause_until: None,
            extra: Vec::new(),
            deadline,
        };
        Ok(())
    }

    /// Type Ctrl-C and wait for the prompt and a quiet line (after a surprise, or to find
    /// out whether a controller in terminal mode is there). Its event is an empty reply,
    /// or [`SessionError::Lost`].
    pub fn resync(&mut self, now: Instant) {
        self.enter_resync(None, now);
    }

    fn enter_resync(&mut self, cause: Option<SessionError>, now: Instant) {
        self.tx.clear();
        self.tx.push_back(CTRL_C);
        self.state = State::Resync {
            buf: Vec::new(),
            deadline: now + RESYNC_WAIT,
            prompt_at: None,
            cause,
            tries: 1,
        };
    }

    /// The next byte to put on the line, if one may go now.
    pub fn poll_transmit(&mut self, now: Instant) -> Option<u8> {
        if let Some(b) = self.tx.pop_front() {
            // Ctrl-C goes even when paused: it is how a stuck line is recovered.
            return Some(b);
        }
        if self.xoff && self.xoff_since.is_some_and(|t| now >= t + XOFF_LIMIT) {
            self.xoff = false;
            self.xoff_since = None;
            self.xoff_expired += 1;
        }
        let echo_timeout = self.cfg.echo_timeout;
        if let State::Typing {
            line,
            next,
            awaiting,
            pause_until,
            urgent,
            hold_until,
            extras,
            ..
        } = &mut self.state
        {
            if self.xoff && !*urgent {
                return None;
            }
            if let Some(h) = *hold_until {
                if now < h && *extras > 0 {
                    return None;
                }
                // Extras that come later than this are not taken for echoes of what follows.
                *hold_until = None;
                *extras = 0;
            }
            if awaiting.is_none() && *next < line.len() {
                if let Some(t) = pause_until {
                    if now < *t {
                        return None;
                    }
                }
                *awaiting = Some(now + echo_timeout);
                return Some(line[*next]);
            }
        }
        None
    }

    /// Take bytes from the line.
    pub fn feed(&mut self, bytes: &[u8], now: Instant) {
        for &b in bytes {
            if self.cfg.flow == Flow::Xonxoff && (b == XON || b == XOFF) {
                self.xoff = b == XOFF;
                self.xoff_since = self.xoff.then_some(now);
                continue;
            }
            self.feed_byte(b, now);
        }
    }

    fn feed_byte(&mut self, b: u8, now: Instant) {
        let extra_allowed = self.cfg.extra_after_digit;
        let extra_wait = self.cfg.extra_wait;
        let terminator = self.cfg.terminator;
        let failure = match &mut self.state {
            State::Idle => {
                self.stray.push(b);
                None
            }
            State::Lost => None,
            State::Typing {
                line,
                next,
                awaiting,
                extras,
                in_number,
                reply_timeout,
                pause,
                pause_until,
                extra,
                hold_until,
                ..
            } => {
                let want = line.get(*next).copied();
                let in_pause = pause_until.is_some_and(|t| now < t || awaiting.is_none());
                if awaiting.is_some() && Some(b) == want {
                    *awaiting = None;
                    *next += 1;
                    let numeric = is_numeric(b);
                    *extras = if numeric && !*in_number {
                        extra_allowed
                    } else {
                        0
                    };
                    *hold_until = (*extras > 0).then(|| now + extra_wait);
                    *in_number = numeric;
                    if b == terminator {
                        let line = std::mem::take(line);
                        let extra = std::mem::take(extra);
                        let timeout = *reply_timeout;
                        self.state = State::Reading {
                            line,
                            buf: Vec::new(),
                            extra,
                            deadline: now + timeout,
                            timeout,
                        };
                    } else if *next + 1 == line.len() {
                        if let Some(p) = pause {
                            *pause_until = Some(now + *p);
                        }
                    }
                    None
                } else if *extras > 0 || in_pause {
                    *extras = extras.saturating_sub(1);
                    if *extras == 0 {
                        *hold_until = None;
                    }
                    extra.push(b);
                    None
                } else {
                    let hint = if is_numeric(line.get(next.saturating_sub(1)).copied().unwrap_or(0))
                        && extra_allowed < 4
                    {
                        format!(
                            "; this controller sends bytes after a number's first character: \
                             raise extra_after_digit (now {extra_allowed}) in the profile"
                        )
                    } else {
                        String::new()
                    };
                    Some(SessionError::Echo {
                        line: String::from_utf8_lossy(&line[..line.len() - 1]).into_owned(),
                        at: *next,
                        want: want.map(char::from).unwrap_or('?'),
                        got: b,
                        hint,
                    })
                }
            }
            State::Reading {
                line, buf, extra, ..
            } => {
                buf.push(b);
                if ends_with_prompt(buf) {
                    let body = &buf[..buf.len() - 2];
                    let ack = body.contains(&ACK);
                    let text: String = String::from_utf8_lossy(
                        &body
                            .iter()
                            .copied()
                            .filter(|c| *c != ACK)
                            .collect::<Vec<_>>(),
                    )
                    .into_owned();
                    let _ = line;
                    self.events.push_back(Ok(Reply {
                        text,
                        ack,
                        extra: std::mem::take(extra),
                    }));
                    self.state = State::Idle;
                }
                None
            }
            State::Resync { buf, prompt_at, .. } => {
                buf.push(b);
                *prompt_at = if ends_with_prompt(buf) {
                    Some(now)
                } else {
                    None
                };
                None
            }
        };
        if let Some(e) = failure {
            self.enter_resync(Some(e), now);
        }
    }

    /// When [`Session::handle_timeout`] must next be called.
    pub fn next_timeout(&self) -> Option<Instant> {
        let xoff = self
            .xoff_since
            .filter(|_| self.xoff)
            .map(|t| t + XOFF_LIMIT);
        let t = self.state_timeout();
        match (t, xoff) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b.filter(|_| !self.is_idle())),
        }
    }

    fn state_timeout(&self) -> Option<Instant> {
        match &self.state {
            State::Typing {
                awaiting,
                deadline,
                pause_until,
                hold_until,
                ..
            } => {
                let mut t = *deadline;
                if let Some(a) = awaiting {
                    t = t.min(*a);
                }
                if let Some(h) = hold_until {
                    t = t.min(*h);
                }
                if let Some(p) = pause_until {
                    t = t.min(*p);
                }
                Some(t)
            }
            State::Reading { deadline, .. } => Some(*deadline),
            State::Resync {
                deadline,
                prompt_at,
                ..
            } => Some(match prompt_at {
                Some(p) => (*p + SETTLE).min(*deadline),
                None => *deadline,
            }),
            State::Idle | State::Lost => None,
        }
    }

    /// Let time pass.
    pub fn handle_timeout(&mut self, now: Instant) {
        let echo_ms = self.cfg.echo_timeout.as_millis();
        let failure = match &mut self.state {
            State::Typing {
                line,
                next,
                awaiting,
                deadline,
                ..
            } => {
                if awaiting.is_some_and(|a| now >= a) || now >= *deadline {
                    Some(SessionError::EchoTimeout {
                        line: String::from_utf8_lossy(&line[..line.len() - 1]).into_owned(),
                        at: *next,
                        ms: echo_ms,
                    })
                } else {
                    None
                }
            }
            State::Reading {
                line,
                buf,
                deadline,
                timeout,
                ..
            } => {
                if now >= *deadline {
                    Some(SessionError::ReplyTimeout {
                        line: String::from_utf8_lossy(&line[..line.len() - 1]).into_owned(),
                        ms: timeout.as_millis(),
                        got: String::from_utf8_lossy(buf).into_owned(),
                    })
                } else {
                    None
                }
            }
            State::Resync {
                buf,
                deadline,
                prompt_at,
                cause,
                tries,
            } => {
                if prompt_at.is_some_and(|p| now >= p + SETTLE) {
                    // Only before the terminator went out is what came not the line's answer.
                    if cause.as_ref().is_some_and(|c| {
                        matches!(c, SessionError::Echo { .. }) && c.surely_not_run()
                    }) {
                        self.resync_text.extend_from_slice(buf);
                    }
                    let ev = match cause.take() {
                        Some(e) => Err(e),
                        None => Ok(Reply {
                            text: String::from_utf8_lossy(buf).into_owned(),
                            ack: false,
                            extra: Vec::new(),
                        }),
                    };
                    self.events.push_back(ev);
                    self.state = State::Idle;
                } else if now >= *deadline {
                    if *tries < 3 {
                        *tries += 1;
                        buf.clear();
                        *prompt_at = None;
                        *deadline = now + RESYNC_WAIT;
                        self.tx.push_back(CTRL_C);
                    } else {
                        let cause = cause
                            .take()
                            .map(|c| c.to_string())
                            .unwrap_or_else(|| "opening the session".into());
                        self.events.push_back(Err(SessionError::Lost { cause }));
                        self.state = State::Lost;
                    }
                }
                None
            }
            State::Idle | State::Lost => None,
        };
        if let Some(e) = failure {
            self.enter_resync(Some(e), now);
        }
    }

    /// The next answer: a reply, or why there is none.
    pub fn poll_event(&mut self) -> Option<Result<Reply, SessionError>> {
        self.events.pop_front()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cfg(extra: u8) -> SessionConfig {
        SessionConfig {
            terminator: b'\r',
            extra_after_digit: extra,
            flow: Flow::Xonxoff,
            echo_timeout: Duration::from_millis(500),
            extra_wait: Duration::from_millis(20),
        }
    }

    /// A scripted controller: echoes each byte (plus `extras` NULs after a number's first
    /// character) and answers the terminator with `answer`.
    fn run(
        s: &mut Session,
        extras: usize,
        answer: &[u8],
        start: Instant,
    ) -> (Result<Reply, SessionError>, Vec<u8>, Instant) {
        let mut now = start;
        let mut sent = Vec::new();
        let mut prev_numeric = false;
        for _ in 0..10_000 {
            if let Some(ev) = s.poll_event() {
                return (ev, sent, now);
            }
            if let Some(b) = s.poll_transmit(now) {
                sent.push(b);
                if b == CTRL_C {
                    s.feed(b"\r\n>>", now);
                    continue;
                }
                let mut echo = vec![b];
                let numeric = is_numeric(b);
                if numeric && !prev_numeric {
                    echo.extend(std::iter::repeat_n(0u8, extras));
                }
                prev_numeric = numeric;
                if b == b'\r' {
                    echo.extend_from_slice(answer);
                }
                s.feed(&echo, now);
                continue;
            }
            now = s.next_timeout().unwrap_or(now + Duration::from_millis(1));
            s.handle_timeout(now);
        }
        panic!("no event");
    }

    #[test]
    fn an_echo_failure_names_the_place_and_whether_the_line_may_have_run() {
        let e = SessionError::EchoTimeout {
            line: "NOH".into(),
            at: 3,
            ms: 2000,
        };
        assert_eq!(
            e.to_string(),
            "no echo of the end of `NOH` within 2000 ms; the controller may have taken the \
             line, so whether it ran is not known"
        );
        assert!(!e.surely_not_run());
        let e = SessionError::EchoTimeout {
            line: "NOH".into(),
            at: 0,
            ms: 2000,
        };
        assert_eq!(
            e.to_string(),
            "no echo of character 1 of `NOH` within 2000 ms; the line was cancelled and did not run"
        );
        assert!(e.surely_not_run());
        let e = SessionError::Echo {
            line: "W2".into(),
            at: 2,
            want: '\r',
            got: b' ',
            hint: String::new(),
        };
        assert_eq!(
            e.to_string(),
            "the controller echoed 0x20 where CR was typed (the end of `W2`); the controller may \
             have taken the line, so whether it ran is not known"
        );
    }

    #[test]
    fn a_reply_with_ack_and_four_extras() {
        let mut s = Session::new(cfg(4));
        s.send_line("SPEED 50", Duration::from_secs(3), Instant::ZERO)
            .unwrap();
        let (r, sent, _) = run(&mut s, 4, b"\x06\r\n>>", Instant::ZERO);
        let r = r.unwrap();
        assert!(r.ack && r.text.trim().is_empty());
        assert_eq!(r.extra, vec![0; 4]);
        assert_eq!(sent, b"SPEED 50\r");
    }

    #[test]
    fn spaces_after_a_digit_are_not_taken_for_the_echo_of_a_typed_space() {
        // `T1 380`: four spaces after `1`, then the typed space's own echo.
        let mut s = Session::new(cfg(4));
        s.send_line("POINT T1 380", Duration::from_secs(3), Instant::ZERO)
            .unwrap();
        let mut now = Instant::ZERO;
        let mut prev_numeric = false;
        let mut sent = Vec::new();
        while s.poll_event().is_none() {
            if let Some(b) = s.poll_transmit(now) {
                sent.push(b);
                let mut echo = vec![b];
                if is_numeric(b) && !prev_numeric {
                    echo.extend_from_slice(b"    ");
                }
                prev_numeric = is_numeric(b);
                if b == b'\r' {
                    echo.extend_from_slice(b"\x06\r\n>>");
                }
                // The extras trickle in a byte at a time.
                for e in echo {
                    s.feed(&[e], now);
                    now = now + Duration::from_millis(1);
                }
                continue;
            }
            now = s.next_timeout().unwrap();
            s.handle_timeout(now);
        }
        assert_eq!(sent, b"POINT T1 380\r");
    }

    #[test]
    fn tolerant_of_fewer_extras_and_of_no_ack() {
        let mut s = Session::new(cfg(4));
        s.send_line("JOINT 1,-5", Duration::from_secs(3), Instant::ZERO)
            .unwrap();
        let (r, _, _) = run(&mut s, 0, b"\r\n>>", Instant::ZERO);
        assert!(!r.unwrap().ack);
    }

    #[test]
    fn extras_not_expected_cancel_the_line_before_it_runs() {
        let mut s = Session::new(cfg(0));
        s.send_line("SPEED 50", Duration::from_secs(3), Instant::ZERO)
            .unwrap();
        let (r, sent, _) = run(&mut s, 4, b"\x06\r\n>>", Instant::ZERO);
        let e = r.unwrap_err();
        assert!(e.surely_not_run(), "{e}");
        assert!(e.to_string().contains("raise extra_after_digit"), "{e}");
        // The terminator never went out; Ctrl-C did.
        assert!(!sent.contains(&b'\r'));
        assert_eq!(sent.last(), Some(&CTRL_C));
        assert!(s.is_idle());
    }

    #[test]
    fn an_error_line_is_the_reply_s_text_without_ack() {
        let mut s = Session::new(cfg(4));
        s.send_line("MOVE XX", Duration::from_secs(3), Instant::ZERO)
            .unwrap();
        let (r, _, _) = run(
            &mut s,
            0,
            b"\r\n035-LOCATION NOT DEFINED.\r\n>>",
            Instant::ZERO,
        );
        let r = r.unwrap();
        assert_eq!(r.text.trim(), "035-LOCATION NOT DEFINED.");
        assert!(!r.ack);
    }

    #[test]
    fn a_silent_controller_times_out_and_is_lost() {
        let mut s = Session::new(cfg(4));
        s.send_line("W2", Duration::from_secs(3), Instant::ZERO)
            .unwrap();
        let mut now = Instant::ZERO;
        let b = s.poll_transmit(now).unwrap();
        assert_eq!(b, b'W');
        let mut events = Vec::new();
        while let Some(t) = s.next_timeout() {
            now = t;
            s.handle_timeout(now);
            while s.poll_transmit(now).is_some() {}
            events.extend(std::iter::from_fn(|| s.poll_event()));
        }
        assert!(matches!(
            events.last(),
            Some(Err(SessionError::Lost { .. }))
        ));
        assert!(s.is_lost());
        // Bounded: one echo wait and three Ctrl-C waits.
        assert!(now.since_epoch() < Duration::from_secs(5));
    }

    #[test]
    fn an_xoff_without_xon_is_given_up_and_halt_is_typed_through_it() {
        let mut s = Session::new(cfg(4));
        s.feed(&[XOFF], Instant::ZERO);
        s.send_line("W2", Duration::from_secs(3), Instant::ZERO)
            .unwrap();
        assert_eq!(s.poll_transmit(Instant::ZERO), None);
        assert_eq!(s.next_timeout(), Some(Instant::ZERO + XOFF_LIMIT));
        assert_eq!(s.poll_transmit(Instant::ZERO + XOFF_LIMIT), Some(b'W'));
        assert_eq!(s.take_xoff_expired(), 1);

        let mut s = Session::new(cfg(4));
        s.feed(&[XOFF], Instant::ZERO);
        s.send_urgent("HALT", Duration::from_secs(3), Instant::ZERO)
            .unwrap();
        assert_eq!(s.poll_transmit(Instant::ZERO), Some(b'H'));
    }

    #[test]
    fn xoff_pauses_typing() {
        let mut s = Session::new(cfg(4));
        s.send_line("HERE A", Duration::from_secs(3), Instant::ZERO)
            .unwrap();
        s.feed(&[XOFF], Instant::ZERO);
        assert_eq!(s.poll_transmit(Instant::ZERO), None);
        s.feed(&[XON], Instant::ZERO);
        assert_eq!(s.poll_transmit(Instant::ZERO), Some(b'H'));
    }

    #[test]
    fn late_bytes_after_a_timeout_are_swallowed_by_the_resync() {
        let mut s = Session::new(cfg(4));
        s.send_line("READY", Duration::from_millis(100), Instant::ZERO)
            .unwrap();
        let mut now = Instant::ZERO;
        for &b in b"READY\r" {
            assert_eq!(s.poll_transmit(now), Some(b));
            s.feed(&[b], now);
        }
        now = s.next_timeout().unwrap();
        s.handle_timeout(now);
        assert_eq!(s.poll_transmit(now), Some(CTRL_C));
        // The late answer and the prompt for Ctrl-C.
        s.feed(b"\x06\r\n>>", now);
        s.feed(b"\r\n>>", now);
        now = s.next_timeout().unwrap();
        s.handle_timeout(now);
        let e = s.poll_event().unwrap().unwrap_err();
        assert!(!e.surely_not_run());
        assert!(s.is_idle());
        assert!(s.take_stray().is_empty());
    }
}

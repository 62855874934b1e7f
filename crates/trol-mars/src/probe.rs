//! First contact with a MARS 8 that only reads (`trol mars probe`): `VER?`, `ST?` and
//! `COORDAP?`, each sent once, every byte both ways recorded. Not even `ECHO:0` is sent, so
//! the unit is left as it was found; an echo of each query is expected and shown.

use std::time::{Duration, Instant};

use trol_port::Port;

use crate::backend::Transcript;
use crate::line::{self, Lines, Reply, st};

/// The queries first contact sends, in order.
pub const QUERIES: [&str; 3] = ["VER", "ST", "COORDAP"];

/// What first contact found.
#[derive(Debug, Default)]
pub struct Contact {
    /// Per query: its answer's value, or why there is none.
    pub answers: Vec<(String, Result<String, String>)>,
    /// Every byte both ways.
    pub transcript: Transcript,
}

impl Contact {
    /// The status word's bits in words, if `ST?` was answered.
    pub fn status_words(&self) -> Option<String> {
        let v = self
            .answers
            .iter()
            .find(|(q, _)| q == "ST")?
            .1
            .as_ref()
            .ok()?;
        let s: u32 = v.parse().ok()?;
        let mut w = Vec::new();
        for (bit, name) in [
            (st::ERROR, "error"),
            (st::MOVING, "moving"),
            (st::QUEUE_FULL, "queue full"),
            (st::POWER_OFF, "arm power off"),
            (st::MOTION_STOP, "motion stop"),
        ] {
            if s & bit != 0 {
                w.push(name);
            }
        }
        Some(if w.is_empty() {
            "ready, no fault".into()
        } else {
            w.join(", ")
        })
    }
}

/// Send each query and wait up to `wait` for its answer.
pub fn first_contact(port: &mut dyn Port, wait: Duration) -> Contact {
    let mut c = Contact::default();
    let mut lines = Lines::default();
    let mut buf = [0u8; 256];
    // What the unit printed before we asked.
    let until = Instant::now() + Duration::from_millis(200);
    while let Ok(n) = port.recv(&mut buf, until) {
        if n == 0 {
            break;
        }
        c.transcript.chunks.push((false, buf[..n].to_vec()));
    }
    for q in QUERIES {
        let bytes = line::query(q);
        c.transcript.chunks.push((true, bytes.clone()));
        if let Err(e) = port.send(&bytes) {
            c.answers
                .push((q.into(), Err(format!("the line failed: {e}"))));
            break;
        }
        let deadline = Instant::now() + wait;
        let mut answer = Err(format!("no answer within {wait:?}"));
        'read: loop {
            match port.recv(&mut buf, deadline) {
                Ok(0) => break,
                Ok(n) => {
                    c.transcript.chunks.push((false, buf[..n].to_vec()));
                    for l in lines.feed(&buf[..n]) {
                        if let Reply::Value { name, value } = line::parse(&l) {
                            if name == q {
                                answer = Ok(value);
                                break 'read;
                            }
                        }
                    }
                }
                Err(e) => {
                    answer = Err(format!("the line failed: {e}"));
                    break;
                }
            }
        }
        c.answers.push((q.into(), answer));
    }
    c
}

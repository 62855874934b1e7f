//! The controller's journal of its last call (issue 67): what the manual's GetStatus and
//! layer 3's exactly-once memory know, kept in a file, so that a controller program that is
//! killed and started again (`trol gateway --journal FILE`) still knows whether the last
//! CAT1/CAT2 request ran, and a host's recovery never sends a move again that ran.
//!
//! One record, rewritten in place before a request runs (`run`: it may run from here on)
//! and once its reply is settled (`done`: it ran, with this reply). After a restart:
//! - `done`: the memory is back: the same epoch, GetStatus's record, and the reply a
//!   repeat of that request is answered with;
//! - `run`: the program died while the request ran, so whether the arm got it cannot be
//!   told: its status and its repeat's answer are TROL_ERR_ROBOT_UNSURE (called);
//! - no file, or a record that does not read whole (its check fails): a fresh start, a new
//!   epoch, as without a journal (the host then answers UNSURE for a call in doubt itself).
//!
//! Each record is one write of [`RECORD`] bytes at the start of the file: a program that is
//! killed loses none of it (the kernel holds it); a power loss of the PC may, since nothing
//! is synced (docs/reliability.md).

use std::fs::File;
use std::io;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

use trol_proto::application::Reply;
use trol_proto::application::code::{Code, TROL_ERR_ROBOT_UNSURE};
use trol_proto::link::frame::crc16;

use crate::pcp::Status;

/// The size of a record on disk.
const RECORD: usize = 256;
/// The longest reply a record keeps (a CAT1 reply is 2 bytes).
const MAX_REPLY: usize = 64;
const MAGIC: &str = "TROL-JOURNAL 1";

/// What a journal held when the controller started.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Restored {
    /// The epoch of the controller that wrote it (kept: the memory goes on).
    pub epoch: u16,
    /// GetStatus's record of the last CAT1/CAT2 request.
    pub status: Status,
    /// Its transaction number and the reply a repeat of it gets.
    pub memory: (u8, Vec<u8>),
    /// Whether that request's reply was settled (`false`: it was running when the
    /// controller stopped, and its fate is TROL_ERR_ROBOT_UNSURE).
    pub settled: bool,
}

impl std::fmt::Display for Restored {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.settled {
            write!(
                f,
                "transaction {} ran (called {}, value {}), epoch {} kept",
                self.memory.0,
                u8::from(self.status.bios_called),
                self.status.last_error_code.0,
                self.epoch
            )
        } else {
            write!(
                f,
                "transaction {} was running when the controller stopped: it may have run \
                 (TROL_ERR_ROBOT_UNSURE), epoch {} kept",
                self.memory.0, self.epoch
            )
        }
    }
}

/// The journal file.
#[derive(Debug)]
pub struct Journal {
    file: File,
    path: PathBuf,
}

impl Journal {
    /// Open (or make) the journal at `path`, and what it held: `Ok((journal, None))` for a
    /// new file or one whose record does not read whole.
    pub fn open(path: &Path) -> io::Result<(Journal, Option<Restored>)> {
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(path)?;
        let mut buf = vec![0u8; RECORD];
        let n = file.read_at(&mut buf, 0)?;
        let restored = parse(&buf[..n]);
        Ok((
            Journal {
                file,
                path: path.to_path_buf(),
            },
            restored,
        ))
    }

    /// Where it is.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Before a request runs: from here on it may have run.
    pub fn running(&mut self, epoch: u16, transaction: u8) -> io::Result<()> {
        self.write(&format!("run epoch={epoch} txn={transaction}"))
    }

    /// Once its reply is settled: it ran, with this status and reply.
    pub fn done(&mut self, epoch: u16, status: Status, reply: &[u8]) -> io::Result<()> {
        let reply = if reply.len() <= MAX_REPLY {
            hex(reply)
        } else {
            // Too long to keep: a repeat of it is answered UNSURE (no CAT1 reply is).
            hex(&Reply::Code(TROL_ERR_ROBOT_UNSURE).encode())
        };
        self.write(&format!(
            "done epoch={epoch} txn={} called={} last={} reply={reply}",
            status.transaction,
            u8::from(status.bios_called),
            status.last_error_code.0
        ))
    }

    fn write(&mut self, body: &str) -> io::Result<()> {
        let text = format!("{MAGIC} {body}");
        let line = format!("{text} crc={:04x}\n", crc16(text.as_bytes()));
        let mut buf = vec![b' '; RECORD];
        buf[RECORD - 1] = b'\n';
        let n = line.len().min(RECORD - 1);
        buf[..n].copy_from_slice(&line.as_bytes()[..n]);
        self.file.write_all_at(&buf, 0)
    }
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

fn unhex(s: &str) -> Option<Vec<u8>> {
    if s.len() % 2 != 0 {
        return None;
    }
    (0..s.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(s.get(i..i + 2)?, 16).ok())
        .collect()
}

/// A record, if it reads whole.
fn parse(buf: &[u8]) -> Option<Restored> {
    let text = std::str::from_utf8(buf).ok()?;
    let line = text.lines().next()?.trim_end();
    let (body, crc) = line.rsplit_once(" crc=")?;
    if u16::from_str_radix(crc, 16).ok()? != crc16(body.as_bytes()) {
        return None;
    }
    let rest = body.strip_prefix(MAGIC)?.trim_start();
    let mut words = rest.split(' ');
    let state = words.next()?;
    let mut field = |name: &str| -> Option<String> {
        let w = words.next()?;
        w.strip_prefix(name)?.strip_prefix('=').map(str::to_string)
    };
    let epoch: u16 = field("epoch")?.parse().ok()?;
    let transaction: u8 = field("txn")?.parse().ok()?;
    match state {
        "run" => {
            let unsure = Reply::Code(TROL_ERR_ROBOT_UNSURE).encode();
            Some(Restored {
                epoch,
                status: Status {
                    bios_called: true,
                    last_error_code: TROL_ERR_ROBOT_UNSURE,
                    transaction,
                    current: transaction,
                },
                memory: (transaction, unsure),
                settled: false,
            })
        }
        "done" => {
            let called = match field("called")?.as_str() {
                "0" => false,
                "1" => true,
                _ => return None,
            };
            let last: i16 = field("last")?.parse().ok()?;
            let reply = unhex(&field("reply")?)?;
            Some(Restored {
                epoch,
                status: Status {
                    bios_called: called,
                    last_error_code: Code(last),
                    transaction,
                    current: transaction,
                },
                memory: (transaction, reply),
                settled: true,
            })
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("trol-journal-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        let _ = std::fs::remove_file(&p);
        p
    }

    #[test]
    fn a_record_reads_back_as_written_and_a_damaged_one_not_at_all() {
        let path = temp("a");
        let (mut j, none) = Journal::open(&path).unwrap();
        assert_eq!(none, None, "a new file holds nothing");
        j.running(77, 5).unwrap();
        let (_, r) = Journal::open(&path).unwrap();
        let r = r.unwrap();
        assert!(!r.settled);
        assert_eq!(r.epoch, 77);
        assert_eq!(r.status.transaction, 5);
        assert_eq!(r.status.last_error_code, TROL_ERR_ROBOT_UNSURE);
        assert!(r.status.bios_called);
        assert_eq!(r.memory, (5, Reply::Code(TROL_ERR_ROBOT_UNSURE).encode()));
        let status = Status {
            bios_called: true,
            last_error_code: Code(-3),
            transaction: 5,
            current: 5,
        };
        j.done(77, status, &[0xfd, 0xff]).unwrap();
        let (_, r) = Journal::open(&path).unwrap();
        let r = r.unwrap();
        assert!(r.settled);
        assert_eq!(r.status, status);
        assert_eq!(r.memory, (5, vec![0xfd, 0xff]));
        // One byte changed anywhere in the record: it does not read at all.
        let good = std::fs::read(&path).unwrap();
        for i in 0..good.iter().position(|b| *b == b'\n').unwrap() {
            let mut bad = good.clone();
            bad[i] ^= 0x04;
            std::fs::write(&path, &bad).unwrap();
            assert_eq!(Journal::open(&path).unwrap().1, None, "byte {i} changed");
        }
        // Half a record (cut short) neither.
        std::fs::write(&path, &good[..40]).unwrap();
        assert_eq!(Journal::open(&path).unwrap().1, None);
    }
}

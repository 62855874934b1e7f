//! The ACI steps that leave ACI mode (c500-rapl.md §1.2): the host (master) asks the
//! controller (slave) for the special transfer 0x48, after which the port speaks RAPL-II in
//! terminal mode. Both entry variants of the public drivers: [`Entry::Aci`] (CRS's sample
//! code as RobWork uses it: one data byte, source id 0xFF) and [`Entry::AciEmpty`] (the
//! G3000 driver: no data, source id 0x21).
//!
//! Sans-IO: [`Master`] and [`Slave`] take bytes and time and say what to send.

use std::time::Duration;

use trol_proto::time::Instant;

use crate::profile::Entry;

/// Start of header.
pub const SOH: u8 = 0x01;
/// Start of text.
pub const STX: u8 = 0x02;
/// End of text.
pub const ETX: u8 = 0x03;
/// End of transmission.
pub const EOT: u8 = 0x04;
/// Enquiry.
pub const ENQ: u8 = 0x05;
/// Acknowledge.
pub const ACK: u8 = 0x06;
/// Negative acknowledge.
pub const NAK: u8 = 0x15;
/// The memory type that switches to terminal mode.
pub const TO_TERMINAL: u8 = 0x48;

/// How long each step waits for the slave.
pub const STEP_WAIT: Duration = Duration::from_millis(300);
/// Enquiries before giving up (RW tries 32 times; a controller already in terminal mode
/// never answers, so the session falls back to Ctrl-C sooner).
pub const ENQ_TRIES: u8 = 3;

/// The header of the 0x48 transfer for `entry` and slave `slave`.
pub fn header(entry: Entry, slave: u8) -> [u8; 13] {
    let addr = slave + 0x20;
    let (src, last) = match entry {
        Entry::AciEmpty => (0x21, 0),
        _ => (0xFF, 1),
    };
    let mut h = [
        SOH,
        addr,
        src,
        0x00,
        TO_TERMINAL,
        0,
        last,
        0,
        0,
        0,
        0,
        ETX,
        0,
    ];
    h[12] = h[1..11].iter().fold(0u8, |a, b| a.wrapping_add(*b));
    h
}

/// Why the ACI steps failed: the ACI error numbers of CRS's sample code.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum AciError {
    /// 04: the enquiry was not answered.
    #[error(
        "ACI error 04: the controller did not answer the enquiry (is it in ACI mode, on slave number {0}?)"
    )]
    Enquiry(u8),
    /// 12: the header was refused (NAK) each time.
    #[error("ACI error 12: the controller refused the 0x48 header")]
    HeaderRefused,
    /// 16: neither ACK nor NAK to the header.
    #[error("ACI error 16: the controller answered the header with neither ACK nor NAK")]
    HeaderAnswer,
    /// 20: the data block's check failed each time.
    #[error("ACI error 20: the data block's check failed")]
    Data,
    /// 28: no data block.
    #[error("ACI error 28: no data block after the header")]
    NoData,
    /// 27: no EOT.
    #[error("ACI error 27: no EOT at the end of the transfer")]
    NoEot,
}

#[derive(Debug, PartialEq)]
enum Step {
    Enq { tries: u8 },
    Header { tries: u8 },
    Data { tries: u8 },
    Eot,
    Done,
    Failed(AciError),
}

/// The master's side of the 0x48 transfer.
#[derive(Debug)]
pub struct Master {
    entry: Entry,
    slave: u8,
    step: Step,
    rx: Vec<u8>,
    tx: Vec<u8>,
    deadline: Instant,
}

impl Master {
    /// Start: the first enquiry is ready to send.
    pub fn new(entry: Entry, slave: u8, now: Instant) -> Master {
        let mut m = Master {
            entry,
            slave,
            step: Step::Enq { tries: 1 },
            rx: Vec::new(),
            tx: Vec::new(),
            deadline: now + STEP_WAIT,
        };
        m.tx.extend_from_slice(&[b'R', slave + 0x20, ENQ]);
        m
    }

    /// Bytes to send now.
    pub fn take_transmit(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.tx)
    }

    /// Done (Ok), failed (Err), or under way (None).
    pub fn result(&self) -> Option<Result<(), AciError>> {
        match self.step {
            Step::Done => Some(Ok(())),
            Step::Failed(e) => Some(Err(e)),
            _ => None,
        }
    }

    /// When [`Master::handle_timeout`] must be called.
    pub fn next_timeout(&self) -> Option<Instant> {
        self.result().is_none().then_some(self.deadline)
    }

    fn data_len(&self) -> usize {
        if self.entry == Entry::AciEmpty { 0 } else { 1 }
    }

    /// Take bytes from the line.
    pub fn feed(&mut self, bytes: &[u8], now: Instant) {
        self.rx.extend_from_slice(bytes);
        loop {
            let before = self.rx.len();
            self.step_once(now);
            if self.rx.len() == before || self.result().is_some() {
                break;
            }
        }
    }

    fn step_once(&mut self, now: Instant) {
        let addr = self.slave + 0x20;
        match self.step {
            Step::Enq { .. } => {
                if let Some(i) = self.rx.windows(3).position(|w| w == [b'R', addr, ACK]) {
                    self.rx.drain(..i + 3);
                    self.tx.extend_from_slice(&header(self.entry, self.slave));
                    self.step = Step::Header { tries: 1 };
                    self.deadline = now + STEP_WAIT;
                }
            }
            Step::Header { tries } => {
                let Some(&b) = self.rx.first() else { return };
                self.rx.remove(0);
                match b {
                    ACK => {
                        self.step = Step::Data { tries: 1 };
                        self.deadline = now + STEP_WAIT;
                    }
                    NAK if tries < 4 => {
                        self.tx.extend_from_slice(&header(self.entry, self.slave));
                        self.step = Step::Header { tries: tries + 1 };
                        self.deadline = now + STEP_WAIT;
                    }
                    NAK => self.step = Step::Failed(AciError::HeaderRefused),
                    _ => self.step = Step::Failed(AciError::HeaderAnswer),
                }
            }
            Step::Data { tries } => {
                let n = self.data_len();
                if self.rx.first().is_some_and(|b| *b != STX) {
                    self.step = Step::Failed(AciError::NoData);
                    return;
                }
                if self.rx.len() < n + 3 {
                    return;
                }
                let block: Vec<u8> = self.rx.drain(..n + 3).collect();
                let sum = block[1..=n].iter().fold(0u8, |a, b| a.wrapping_add(*b));
                if block[n + 1] == ETX && block[n + 2] == sum {
                    self.tx.push(ACK);
                    self.step = Step::Eot;
                } else if tries < 4 {
                    self.tx.push(NAK);
                    self.step = Step::Data { tries: tries + 1 };
                } else {
                    self.step = Step::Failed(AciError::Data);
                }
                self.deadline = now + STEP_WAIT;
            }
            Step::Eot => {
                let Some(&b) = self.rx.first() else { return };
                self.rx.remove(0);
                if b == EOT {
                    self.tx.push(EOT);
                    self.step = Step::Done;
                } else {
                    self.step = Step::Failed(AciError::NoEot);
                }
            }
            Step::Done | Step::Failed(_) => {}
        }
    }

    /// Let time pass.
    pub fn handle_timeout(&mut self, now: Instant) {
        if now < self.deadline {
            return;
        }
        match self.step {
            Step::Enq { tries } if tries < ENQ_TRIES => {
                self.rx.clear();
                self.tx.extend_from_slice(&[b'R', self.slave + 0x20, ENQ]);
                self.step = Step::Enq { tries: tries + 1 };
                self.deadline = now + STEP_WAIT;
            }
            Step::Enq { .. } => self.step = Step::Failed(AciError::Enquiry(self.slave)),
            Step::Header { .. } => self.step = Step::Failed(AciError::HeaderAnswer),
            Step::Data { .. } => self.step = Step::Failed(AciError::NoData),
            Step::Eot => self.step = Step::Failed(AciError::NoEot),
            Step::Done | Step::Failed(_) => {}
        }
    }
}

#[derive(Debug)]
enum SlaveStep {
    Idle,
    Header,
    Sent { block: Vec<u8> },
    AwaitEot,
}

/// The controller's side: answers the 0x48 transfer (either variant) and says when the port
/// switches to terminal mode. Other memory types are refused with NAK (the simulated C500
/// has no memory map to serve).
#[derive(Debug)]
pub struct Slave {
    slave: u8,
    step: SlaveStep,
    buf: Vec<u8>,
}

impl Slave {
    /// A slave with number `slave`.
    pub fn new(slave: u8) -> Slave {
        Slave {
            slave,
            step: SlaveStep::Idle,
            buf: Vec::new(),
        }
    }

    /// Take one byte; append the answer to `out`. True when the transfer ended and the port
    /// is now in terminal mode.
    pub fn feed(&mut self, b: u8, out: &mut Vec<u8>) -> bool {
        let addr = self.slave + 0x20;
        // An enquiry restarts from any step.
        self.buf.push(b);
        if self.buf.ends_with(&[b'R', addr, ENQ]) {
            out.extend_from_slice(&[b'R', addr, ACK]);
            self.step = SlaveStep::Header;
            self.buf.clear();
            return false;
        }
        match &self.step {
            SlaveStep::Idle => {
                if self.buf.len() > 3 {
                    self.buf.remove(0);
                }
            }
            SlaveStep::Header => {
                if self.buf[0] != SOH {
                    self.buf.clear();
                } else if self.buf.len() == 13 {
                    let h = std::mem::take(&mut self.buf);
                    let lrc = h[1..11].iter().fold(0u8, |a, b| a.wrapping_add(*b));
                    let ok = h[1] == addr && h[11] == ETX && h[12] == lrc;
                    if ok && h[3] == 0x00 && h[4] == TO_TERMINAL {
                        let n = usize::from(h[5]) * 128 + usize::from(h[6]);
                        let data = vec![0u8; n.min(128)];
                        let mut block = vec![STX];
                        block.extend_from_slice(&data);
                        block.push(ETX);
                        block.push(data.iter().fold(0u8, |a, b| a.wrapping_add(*b)));
                        out.push(ACK);
                        out.extend_from_slice(&block);
                        self.step = SlaveStep::Sent { block };
                    } else {
                        out.push(NAK);
                    }
                }
            }
            SlaveStep::Sent { block } => {
                let block = block.clone();
                self.buf.clear();
                match b {
                    ACK => {
                        out.push(EOT);
                        self.step = SlaveStep::AwaitEot;
                    }
                    NAK => out.extend_from_slice(&block),
                    _ => {}
                }
            }
            SlaveStep::AwaitEot => {
                self.buf.clear();
                if b == EOT {
                    self.step = SlaveStep::Idle;
                    return true;
                }
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_headers_of_both_drivers() {
        // c500-rapl.md §1.2: the LRC bytes 0x69 (RW) and 0x8A (G3K).
        assert_eq!(
            header(Entry::Aci, 1),
            [
                0x01, 0x21, 0xFF, 0x00, 0x48, 0x00, 0x01, 0, 0, 0, 0, 0x03, 0x69
            ]
        );
        assert_eq!(
            header(Entry::AciEmpty, 1),
            [
                0x01, 0x21, 0x21, 0x00, 0x48, 0x00, 0x00, 0, 0, 0, 0, 0x03, 0x8A
            ]
        );
    }

    #[test]
    fn master_and_slave_agree_in_both_variants() {
        for entry in [Entry::Aci, Entry::AciEmpty] {
            let now = Instant::ZERO;
            let mut m = Master::new(entry, 1, now);
            let mut s = Slave::new(1);
            let mut switched = false;
            for _ in 0..20 {
                let tx = m.take_transmit();
                let mut back = Vec::new();
                for b in tx {
                    switched |= s.feed(b, &mut back);
                }
                m.feed(&back, now);
                if m.result().is_some() {
                    let tx = m.take_transmit();
                    for b in tx {
                        switched |= s.feed(b, &mut back);
                    }
                    break;
                }
            }
            assert_eq!(m.result(), Some(Ok(())), "{entry:?}");
            assert!(switched, "{entry:?}");
        }
    }

    #[test]
    fn a_silent_port_fails_with_error_04_in_bounded_time() {
        let mut m = Master::new(Entry::Aci, 1, Instant::ZERO);
        let mut now = Instant::ZERO;
        while m.result().is_none() {
            now = m.next_timeout().unwrap();
            m.handle_timeout(now);
        }
        assert_eq!(m.result(), Some(Err(AciError::Enquiry(1))));
        assert!(now.since_epoch() <= STEP_WAIT * u32::from(ENQ_TRIES));
    }
}

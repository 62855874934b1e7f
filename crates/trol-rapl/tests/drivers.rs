//! The two public host drivers, as their code is written, against the simulated C500: their
//! byte sequences replayed step by step (RobWork's crs_aci.cpp `ACI::OpenSession`,
//! `SetSpeed`, `GetJointConfig`, `Move`, `CloseSession`; the G3000 driver's `ACI_to_Term`,
//! `connect`, `sendCommand`, `block`), with the bytes of c500-rapl.md §1.2 as golden
//! transcripts.

use trol_a465::arm::{Arm, ArmSettings, Stored};
use trol_rapl::{C500, Profile};

/// A host that talks to the simulated C500 with simulated time.
struct Host {
    c: C500,
    t: f64,
    sent: Vec<u8>,
    got: Vec<u8>,
    pending: std::collections::VecDeque<u8>,
}

impl Host {
    fn new() -> Host {
        let arm = Arm::new(ArmSettings {
            homed: true,
            ..Default::default()
        });
        let loc = vec![(
            "TEST_001".to_string(),
            Stored::Cart([400.0, 0.0, 150.0, 0.0, std::f64::consts::FRAC_PI_2, 0.0]),
        )];
        Host {
            c: C500::new(Profile::simulator(), arm, loc),
            t: 0.0,
            sent: Vec::new(),
            got: Vec::new(),
            pending: Default::default(),
        }
    }

    fn send(&mut self, bytes: &[u8]) {
        self.sent.extend_from_slice(bytes);
        self.c.feed(bytes, self.t);
        self.collect();
    }

    fn collect(&mut self) {
        let out = self.c.take_output(usize::MAX);
        self.got.extend_from_slice(&out);
        self.pending.extend(out);
    }

    /// RW's `get_aci`: the next byte, waiting (simulated) up to `limit` seconds.
    fn get_raw(&mut self, limit: f64) -> Option<u8> {
        let end = self.t + limit;
        while self.pending.is_empty() && self.t < end {
            self.t += 0.01;
            self.c.tick(self.t);
            self.collect();
        }
        self.pending.pop_front()
    }

    /// RW's `ACI::get`: XON and XOFF skipped.
    fn get(&mut self) -> u8 {
        loop {
            let c = self.get_raw(2.0).expect("a byte within RW's 2 s");
            if c != 0x11 && c != 0x13 {
                return c;
            }
        }
    }

    /// RW's `garble`: CR LF `>>`, or return at the first byte that differs.
    fn garble(&mut self) -> bool {
        b"\r\n>>".iter().all(|&b| self.get() == b)
    }

    /// RW's `sendstr`: each byte echoed, four bytes read after a number's first character.
    fn sendstr(&mut self, s: &str) -> bool {
        let mut num = false;
        for &b in s.as_bytes() {
            self.send(&[b]);
            if self.get() != b {
                return false;
            }
            if b.is_ascii_digit() || b == b'.' || b == b'-' {
                if !num {
                    for _ in 0..4 {
                        self.get();
                    }
                    num = true;
                }
            } else {
                num = false;
            }
        }
        true
    }

    /// G3K's `block`: read until the buffer ends with a prompt (120 s).
    fn block(&mut self) -> Vec<u8> {
        let mut buf = Vec::new();
        while !(buf.ends_with(b"\r\n>>") || buf.ends_with(b"\r\nO>")) {
            buf.push(self.get_raw(120.0).expect("a prompt within G3K's 120 s"));
        }
        buf
    }
}

#[test]
fn robworks_driver_opens_runs_and_closes_a_session() {
    let mut h = Host::new();
    // ACI::OpenSession: aci_xfr(slave 1, 0x48, 0, 0, 'W', 1).
    h.send(&[0x52, 0x21, 0x05]);
    assert_eq!([h.get(), h.get(), h.get()], [0x52, 0x21, 0x06]);
    let header = [
        0x01, 0x21, 0xFF, 0x00, 0x48, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00, 0x03, 0x69,
    ];
    h.send(&header);
    assert_eq!(h.get(), 0x06);
    let block = [h.get(), h.get(), h.get(), h.get()];
    assert_eq!(block[0], 0x02);
    assert_eq!(block[2], 0x03);
    assert_eq!(block[3], block[1], "LRC of one byte");
    h.send(&[0x06]);
    assert_eq!(h.get(), 0x04);
    h.send(&[0x04]);
    // usleep(100000); send(3); garble();
    h.t += 0.1;
    h.send(&[0x03]);
    assert!(h.garble());
    assert!(h.sendstr("NOH"));
    let completion: Vec<u8> = (0..5).map(|_| h.get()).collect();
    assert_eq!(completion, b"ELP  ");
    h.send(b"\r");
    h.get();
    assert_eq!(h.get(), 0x06, "ACK: session open");
    assert!(h.garble());
    // SetSpeed(50).
    assert!(h.sendstr("SPEED 50\r"));
    assert_eq!(h.get(), 0x06);
    assert!(h.garble());
    // GetJointConfig: W2, read to ">>", parse JOINTS.
    assert!(h.sendstr("W2\r"));
    let mut buf = Vec::new();
    while !buf.ends_with(b">>") {
        buf.push(h.get());
    }
    let text = String::from_utf8_lossy(&buf);
    let joints = trol_rapl::text::row(&text, "JOINTS").unwrap();
    assert!(joints.iter().all(|j| j.abs() < 0.01), "{joints:?}");
    // Move: MOVE, ACK; the same MOVE again, whose ACK waits for the first to end.
    assert!(h.sendstr("MOVE TEST_001\r"));
    assert_eq!(h.get(), 0x06);
    assert!(h.garble());
    let started = h.t;
    assert!(h.sendstr("MOVE TEST_001\r"));
    let c = loop {
        if let Some(c) = h.get_raw(0.01) {
            break c;
        }
    };
    assert_eq!(c, 0x06);
    assert!(
        h.t > started + 0.3,
        "the second MOVE answered only at the end of the first"
    );
    assert!(h.garble());
    // CloseSession.
    assert!(h.sendstr("HELP\r"));
    assert_eq!(h.get(), 0x06);
    assert!(h.garble());
    h.send(&[0x1A, 0x1A]);
    assert!(!h.c.in_terminal_mode());
    // The opening's bytes, host side, as c500-rapl.md §1.2 lists them.
    let golden: Vec<u8> = [
        &[0x52, 0x21, 0x05][..],
        &header,
        &[0x06, 0x04, 0x03],
        b"NOH\r",
    ]
    .concat();
    assert_eq!(&h.sent[..golden.len()], &golden[..]);
}

#[test]
fn the_g3000_driver_opens_and_runs_its_test() {
    let mut h = Host::new();
    // ACI_to_Term: CRS_send / CRS_expect, byte for byte.
    h.send(&[0x52, 0x21, 0x05]);
    assert_eq!(h.block_n(3), [0x52, 0x21, 0x06]);
    h.send(&[0x01, 0x21, 0x21, 0x00, 0x48, 0, 0, 0, 0, 0, 0, 0x03, 0x8a]);
    assert_eq!(h.block_n(4), [0x06, 0x02, 0x03, 0x00]);
    h.send(&[0x06]);
    assert_eq!(h.block_n(1), [0x04]);
    h.send(&[0x04]);
    // CRS_receive(&dummy, 1): nothing comes, which is fine for it.
    assert_eq!(h.get_raw(0.5), None);
    // connect(): sendCommand("NOHELP"): the whole line at once, then expect(command).
    h.send(b"NOHELP\r");
    let echo = h.block();
    assert!(
        echo.starts_with(b"NOHELP"),
        "{:?}",
        String::from_utf8_lossy(&echo)
    );
    // The test: r << "JOINT 6 +90" << finish << "JOINT 6 -90" << block;
    h.send(b"JOINT 6 +90\r");
    let r = h.block();
    assert!(!String::from_utf8_lossy(&r).contains("ERROR"));
    h.send(b"JOINT 6 -90\r");
    let r = h.block();
    assert!(!String::from_utf8_lossy(&r).contains("ERROR"));
    // The second motion began when its prompt came; look once it has had time to end.
    h.t += 5.0;
    h.send(b"W0\r");
    let w0 = h.block();
    let joints = trol_rapl::text::row(&String::from_utf8_lossy(&w0), "JOINTS").unwrap();
    assert!(joints[5].abs() < 0.01, "joint 6 back at 0: {joints:?}");
    // disconnect(): two Ctrl-Z.
    h.send(&[0x1a, 0x1a]);
    assert!(!h.c.in_terminal_mode());
}

impl Host {
    /// G3K's `CRS_expect`: the next `n` bytes.
    fn block_n(&mut self, n: usize) -> Vec<u8> {
        (0..n).map(|_| self.get_raw(1.0).expect("a byte")).collect()
    }
}

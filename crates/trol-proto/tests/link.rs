//! Layer 2 against scripted peers and between two ends, with injected time.

mod common;

use std::time::Duration;

use common::{Dir, End, Script, Wire, hex};
use trol_proto::Instant;
use trol_proto::link::control::{self, ACK, ENQ, EOT, ETB, ETX, NAK, SOH, STX};
use trol_proto::link::frame::{self, FRAME_SIZE, Header, MAX_RETRIES, lrc};
use trol_proto::link::{
    Link, LinkConfig, LinkError, NakClass, NakCode, Outcome, ReceiveError, SendError, Timeouts,
};

const T: Duration = Duration::from_millis(1000);

fn cfg() -> LinkConfig {
    LinkConfig::default()
}

/// Run until the link reports an outcome (or nothing more can happen).
fn outcome_of<B: End>(wire: &mut Wire, link: &mut Link, peer: &mut B) -> Option<Outcome> {
    let mut got = None;
    wire.run(link, peer, Duration::from_secs(60), |l, _| {
        if got.is_none() {
            got = l.poll_outcome();
        }
        got.is_some()
    });
    got
}

fn receiving() -> (Wire, Link, Script) {
    let mut link = Link::new(cfg());
    link.receive(Instant::ZERO).unwrap();
    (Wire::new(), link, Script::default())
}

fn sending(message: &[u8]) -> (Wire, Link, Script) {
    let mut link = Link::new(cfg());
    link.send(message, 0x0001, Instant::ZERO).unwrap();
    (Wire::new(), link, Script::default())
}

/// A header as the sender writes it for a message of `len` bytes starting with `first` (in
/// CRC-16 mode the PCI carries the message check: right for messages of up to 2 bytes).
fn header_bytes(len: u16, pci: u16, first: [u8; 2]) -> Vec<u8> {
    let shown = &first[..usize::from(len).min(2)];
    Header {
        len,
        pci: frame::line_pci(cfg().check, pci, shown),
        first_word: first,
    }
    .encode(cfg().check)
    .to_vec()
}

/// The header of `message` as the sender writes it.
fn header_for(message: &[u8], pci: u16) -> Vec<u8> {
    Header::for_message(message, frame::line_pci(cfg().check, pci, message))
        .encode(cfg().check)
        .to_vec()
}

fn frame_bytes(message: &[u8], index: usize) -> Vec<u8> {
    let mut v = Vec::new();
    frame::encode_frame(message, index, cfg().check, &mut v);
    v
}

fn fail_recv(o: Option<Outcome>) -> ReceiveError {
    match o {
        Some(Outcome::Failed(LinkError::Receive(e))) => e,
        other => panic!("expected a receive failure, got {other:?}"),
    }
}

fn fail_send(o: Option<Outcome>) -> SendError {
    match o {
        Some(Outcome::Failed(LinkError::Send(e))) => e,
        other => panic!("expected a send failure, got {other:?}"),
    }
}

// ---------------------------------------------------------------- control codes

#[test]
fn control_codes_differ_pairwise_in_at_least_three_bits() {
    for (i, (na, a)) in control::ALL.iter().enumerate() {
        for (nb, b) in &control::ALL[i + 1..] {
            let d = control::distance(*a, *b);
            assert!(
                d >= 3,
                "{na} 0x{a:02X} and {nb} 0x{b:02X} differ in {d} bits"
            );
        }
        assert!(control::distance(*a, 0x00) >= 3, "{na} too close to 0x00");
        assert!(control::distance(*a, 0xFF) >= 3, "{na} too close to 0xFF");
    }
}

#[test]
fn a_byte_within_one_bit_is_accepted_as_the_expected_code_and_no_other() {
    for (name, code) in control::ALL {
        assert!(control::accepts(code, code));
        for bit in 0..8 {
            let near = code ^ (1 << bit);
            assert!(
                control::accepts(near, code),
                "{name} with bit {bit} flipped"
            );
            assert_eq!(control::name_of(near), Some(name));
            for (other_name, other) in control::ALL {
                if other != code {
                    assert!(
                        !control::accepts(near, other),
                        "{name}~ taken as {other_name}"
                    );
                }
            }
        }
        for bits in [0b11u8, 0b101, 0b1001_0000] {
            assert!(
                !control::accepts(code ^ bits, code),
                "2-bit error accepted for {name}"
            );
        }
    }
}

#[test]
fn nak_codes_keep_the_manuals_distances() {
    let fatal: Vec<_> = NakCode::ALL.iter().filter(|c| c.is_fatal()).collect();
    let retry: Vec<_> = NakCode::ALL.iter().filter(|c| !c.is_fatal()).collect();
    assert_eq!(fatal.len(), 3);
    assert_eq!(retry.len(), 4);
    for group in [&fatal, &retry] {
        for (i, a) in group.iter().enumerate() {
            for b in &group[i + 1..] {
                assert!(control::distance(a.byte(), b.byte()) >= 2, "{a} {b}");
            }
        }
    }
    for a in &fatal {
        for b in &retry {
            assert!(control::distance(a.byte(), b.byte()) >= 4, "{a} {b}");
        }
    }
    // A fatal code with one bit flipped is still fatal; a retry code with one bit flipped
    // still asks for a retry.
    for code in NakCode::ALL {
        for bit in 0..8 {
            let got = NakCode::classify(code.byte() ^ (1 << bit));
            if code.is_fatal() {
                // Fatal codes differ in 2 bits among themselves, so which one is meant can be
                // ambiguous; that it is fatal is not.
                assert!(
                    matches!(got, NakClass::Fatal(_)),
                    "{code} bit {bit}: {got:?}"
                );
            } else {
                assert_eq!(got, NakClass::Retry);
            }
        }
    }
}

#[test]
fn return_values_carry_the_manuals_numbers() {
    assert_eq!(SendError::WrongCchar.code(), 0x01);
    assert_eq!(SendError::Nak(NakCode::Fid).code(), 0x0102);
    assert_eq!(SendError::TimeoutEnq.code(), 0x03);
    assert_eq!(SendError::TimeoutNak.code(), 0x04);
    assert_eq!(SendError::TimeoutEtx.code(), 0x05);
    assert_eq!(SendError::LimitExceeded.code(), 0x07);
    assert_eq!(ReceiveError::Abort(NakCode::TooLarge).code(), 0x0480);
    assert_eq!(ReceiveError::TimeoutSoh.code(), 0x81);
    assert_eq!(ReceiveError::TimeoutStx.code(), 0x82);
    assert_eq!(ReceiveError::TimeoutTermc.code(), 0x83);
    assert_eq!(ReceiveError::TimeoutEot.code(), 0x84);
    assert_eq!(ReceiveError::BadEnq.code(), 0x85);
    assert_eq!(ReceiveError::BadEot.code(), 0x86);
    assert_eq!(ReceiveError::LimitExceeded.code(), 0x07);
    // Masking with 0xff gives the code, as the manual says.
    assert_eq!(SendError::Nak(NakCode::Etb).code() & 0xff, 0x02);
    assert_eq!(SendError::Nak(NakCode::Etb).code() >> 8, 0x02);
}

#[test]
fn frame_count_follows_the_manuals_formula() {
    assert_eq!(frame::frame_count(0), 0);
    assert_eq!(frame::frame_count(2), 0);
    assert_eq!(frame::frame_count(3), 1);
    assert_eq!(frame::frame_count(2 + FRAME_SIZE), 1);
    assert_eq!(frame::frame_count(3 + FRAME_SIZE), 2);
    assert_eq!(frame::frame_count(65535), (65533usize).div_ceil(FRAME_SIZE));
    assert_eq!(lrc(&[0xFF; 300]), (300u32 * 255 % 65536) as u16);
}

// ---------------------------------------------------------------- receiver codes

#[test]
fn receiver_rejects_a_byte_that_is_not_enq() {
    let (mut w, mut link, mut peer) = receiving();
    peer.to_send = vec![0x00];
    assert_eq!(
        fail_recv(outcome_of(&mut w, &mut link, &mut peer)),
        ReceiveError::BadEnq
    );
    assert!(peer.received.is_empty(), "nothing is answered to a bad ENQ");
}

#[test]
fn receiver_accepts_enq_with_one_bit_flipped() {
    let (mut w, mut link, mut peer) = receiving();
    peer.to_send = vec![ENQ ^ 0x10];
    w.run(&mut link, &mut peer, T, |_, p| !p.received.is_empty());
    assert_eq!(peer.received, vec![ACK]);
}

#[test]
fn receiver_times_out_waiting_for_soh() {
    let (mut w, mut link, mut peer) = receiving();
    peer.to_send = vec![ENQ];
    let o = outcome_of(&mut w, &mut link, &mut peer);
    assert_eq!(fail_recv(o), ReceiveError::TimeoutSoh);
    assert_eq!(
        w.now,
        Instant::ZERO + T,
        "fails exactly when the start timeout runs out"
    );
}

#[test]
fn receiver_times_out_inside_a_block() {
    let (mut w, mut link, mut peer) = receiving();
    peer.to_send = vec![ENQ, SOH, 0x05, 0x00];
    assert_eq!(
        fail_recv(outcome_of(&mut w, &mut link, &mut peer)),
        ReceiveError::TimeoutTermc
    );
}

fn nak_after_header(mut header: Vec<u8>, cfg: LinkConfig) -> (Vec<u8>, Option<Outcome>, Link) {
    let mut link = Link::new(cfg);
    link.receive(Instant::ZERO).unwrap();
    let mut w = Wire::new();
    let mut peer = Script::default();
    let mut first = vec![ENQ];
    first.append(&mut header);
    peer.to_send = first;
    w.run(&mut link, &mut peer, T / 2, |_, p| p.received.len() >= 3);
    let o = link.poll_outcome();
    (peer.received.clone(), o, link)
}

#[test]
fn receiver_naks_a_header_without_soh_and_takes_it_again() {
    let mut h = header_bytes(2, 1, [0x41, 0x42]);
    h[0] = 0x00;
    let (got, o, mut link) = nak_after_header(h, cfg());
    assert_eq!(got, vec![ACK, NAK, NakCode::Soh.byte()]);
    assert_eq!(o, None, "a retry code does not end the transfer");
    // The good header then goes through.
    let mut w = Wire::new();
    let mut peer = Script {
        to_send: [header_bytes(2, 1, [0x41, 0x42]), vec![EOT]].concat(),
        ..Script::default()
    };
    assert_eq!(
        outcome_of(&mut w, &mut link, &mut peer),
        Some(Outcome::Received)
    );
    assert_eq!(link.take_received(), Some((1, b"AB".to_vec())));
}

#[test]
fn receiver_naks_a_header_whose_last_byte_is_not_etx() {
    let mut h = header_bytes(2, 1, [1, 2]);
    h[9] = 0x00;
    let (got, o, _) = nak_after_header(h, cfg());
    assert_eq!(got, vec![ACK, NAK, NakCode::Etx.byte()]);
    assert_eq!(o, None);
}

#[test]
fn receiver_aborts_on_etb_where_etx_belongs() {
    let mut h = header_bytes(2, 1, [1, 2]);
    h[9] = ETB;
    let (got, o, _) = nak_after_header(h, cfg());
    assert_eq!(got, vec![ACK, NAK, NakCode::Etb.byte()]);
    assert_eq!(fail_recv(o), ReceiveError::Abort(NakCode::Etb));
}

#[test]
fn receiver_naks_a_bad_bcc() {
    let mut h = header_bytes(2, 1, [1, 2]);
    h[5] ^= 0x01;
    let (got, o, _) = nak_after_header(h, cfg());
    assert_eq!(got, vec![ACK, NAK, NakCode::Bcc.byte()]);
    assert_eq!(o, None);
}

#[test]
fn receiver_aborts_a_message_larger_than_its_limit() {
    let cfg = LinkConfig {
        max_message: 10,
        ..cfg()
    };
    let (got, o, _) = nak_after_header(header_bytes(11, 1, [1, 2]), cfg);
    assert_eq!(got, vec![ACK, NAK, NakCode::TooLarge.byte()]);
    assert_eq!(fail_recv(o), ReceiveError::Abort(NakCode::TooLarge));
    assert_eq!(fail_recv(o).code(), 0x0480);
}

#[test]
fn receiver_gives_up_after_max_retries_bad_headers() {
    let mut link = Link::new(cfg());
    link.receive(Instant::ZERO).unwrap();
    let mut w = Wire::new();
    let mut peer = Script {
        to_send: vec![ENQ],
        ..Script::default()
    };
    let mut bad = header_bytes(2, 1, [1, 2]);
    bad[7] ^= 0x40;
    let mut outcome = None;
    for attempt in 0..=MAX_RETRIES {
        peer.to_send.extend_from_slice(&bad);
        w.run(&mut link, &mut peer, T / 2, |l, p| {
            outcome = outcome.or(l.poll_outcome());
            p.received.len() > 2 * (usize::from(attempt) + 1)
        });
    }
    assert_eq!(fail_recv(outcome), ReceiveError::LimitExceeded);
    let naks = peer.received.iter().filter(|b| **b == NAK).count();
    assert_eq!(naks, usize::from(MAX_RETRIES) + 1);
}

fn receiver_after_header(message: &[u8]) -> (Wire, Link, Script) {
    let mut link = Link::new(cfg());
    link.receive(Instant::ZERO).unwrap();
    let mut w = Wire::new();
    let mut peer = Script {
        to_send: [vec![ENQ], header_for(message, 7)].concat(),
        ..Script::default()
    };
    w.run(&mut link, &mut peer, T / 2, |_, p| p.received.len() >= 2);
    assert_eq!(peer.received, vec![ACK, ACK]);
    peer.received.clear();
    (w, link, peer)
}

#[test]
fn receiver_naks_a_frame_without_stx() {
    let msg = b"hello";
    let (mut w, mut link, mut peer) = receiver_after_header(msg);
    let mut f = frame_bytes(msg, 0);
    f[0] = 0x00;
    peer.to_send = f;
    w.run(&mut link, &mut peer, T / 2, |_, p| p.received.len() >= 2);
    assert_eq!(peer.received, vec![NAK, NakCode::Stx.byte()]);
}

#[test]
fn receiver_aborts_on_a_wrong_frame_id() {
    let msg = b"hello";
    let (mut w, mut link, mut peer) = receiver_after_header(msg);
    // A well-formed frame with ID 1 where 0 is expected (BCC computed over the wrong ID).
    let data = &msg[2..];
    let fid = frame::frame_id_field(cfg().check, 1, data).to_le_bytes();
    let bcc = frame::frame_bcc(cfg().check, data, fid).to_le_bytes();
    peer.to_send = [
        vec![STX],
        data.to_vec(),
        fid.to_vec(),
        bcc.to_vec(),
        vec![ETX],
    ]
    .concat();
    let mut o = None;
    w.run(&mut link, &mut peer, T / 2, |l, p| {
        o = o.or(l.poll_outcome());
        p.received.len() >= 2
    });
    assert_eq!(peer.received, vec![NAK, NakCode::Fid.byte()]);
    assert_eq!(fail_recv(o), ReceiveError::Abort(NakCode::Fid));
}

#[test]
fn receiver_times_out_waiting_for_stx() {
    let (mut w, mut link, mut peer) = receiver_after_header(b"hello");
    assert_eq!(
        fail_recv(outcome_of(&mut w, &mut link, &mut peer)),
        ReceiveError::TimeoutStx
    );
}

#[test]
fn receiver_times_out_waiting_for_eot() {
    let (mut w, mut link, mut peer) = receiver_after_header(b"hi");
    assert_eq!(
        fail_recv(outcome_of(&mut w, &mut link, &mut peer)),
        ReceiveError::TimeoutEot
    );
}

#[test]
fn receiver_rejects_a_byte_that_is_not_eot() {
    let (mut w, mut link, mut peer) = receiver_after_header(b"hi");
    peer.to_send = vec![ENQ];
    assert_eq!(
        fail_recv(outcome_of(&mut w, &mut link, &mut peer)),
        ReceiveError::BadEot
    );
}

// ---------------------------------------------------------------- sender codes

#[test]
fn sender_times_out_when_enq_is_not_answered() {
    let (mut w, mut link, mut peer) = sending(b"abc");
    assert_eq!(
        fail_send(outcome_of(&mut w, &mut link, &mut peer)),
        SendError::TimeoutEnq
    );
    assert_eq!(peer.received, vec![ENQ]);
}

#[test]
fn sender_fails_on_a_byte_that_is_neither_ack_nor_nak() {
    let (mut w, mut link, mut peer) = sending(b"abc");
    peer.to_send = vec![0x00];
    assert_eq!(
        fail_send(outcome_of(&mut w, &mut link, &mut peer)),
        SendError::WrongCchar
    );
}

#[test]
fn sender_times_out_waiting_for_the_ack_of_a_block() {
    let (mut w, mut link, mut peer) = sending(b"abc");
    peer.to_send = vec![ACK];
    assert_eq!(
        fail_send(outcome_of(&mut w, &mut link, &mut peer)),
        SendError::TimeoutEtx
    );
    assert_eq!(peer.received.len(), 1 + 10, "ENQ and the header went out");
}

#[test]
fn sender_times_out_waiting_for_the_nak_code() {
    let (mut w, mut link, mut peer) = sending(b"abc");
    peer.to_send = vec![ACK];
    w.run(&mut link, &mut peer, T / 2, |_, p| p.received.len() >= 11);
    peer.to_send = vec![NAK];
    assert_eq!(
        fail_send(outcome_of(&mut w, &mut link, &mut peer)),
        SendError::TimeoutNak
    );
}

#[test]
fn sender_stops_on_a_fatal_nak_code_and_reports_it_in_the_high_byte() {
    let (mut w, mut link, mut peer) = sending(b"abc");
    peer.to_send = vec![ACK];
    w.run(&mut link, &mut peer, T / 2, |_, p| p.received.len() >= 11);
    peer.to_send = vec![NAK, NakCode::TooLarge.byte() ^ 0x80];
    let e = fail_send(outcome_of(&mut w, &mut link, &mut peer));
    assert_eq!(e, SendError::Nak(NakCode::TooLarge));
    assert_eq!(e.code(), 0x0402);
}

#[test]
fn sender_repeats_a_block_after_a_retry_nak_then_gives_up() {
    let (mut w, mut link, mut peer) = sending(b"abc");
    peer.to_send = vec![ACK];
    w.run(&mut link, &mut peer, T / 2, |_, p| p.received.len() >= 11);
    let header = peer.received[1..].to_vec();
    let mut outcome = None;
    for attempt in 1..=u32::from(MAX_RETRIES) + 1 {
        peer.received.clear();
        peer.to_send = vec![NAK, NakCode::Bcc.byte()];
        w.run(&mut link, &mut peer, T / 2, |l, p| {
            outcome = outcome.or(l.poll_outcome());
            outcome.is_some() || p.received.len() >= 10
        });
        if attempt <= u32::from(MAX_RETRIES) {
            assert_eq!(
                peer.received, header,
                "attempt {attempt} repeats the header"
            );
        }
    }
    assert_eq!(fail_send(outcome), SendError::LimitExceeded);
}

// ---------------------------------------------------------------- whole transfers

/// Send `message` from one link to another; returns (sender outcome, receiver outcome,
/// received message).
pub fn transfer(
    wire: &mut Wire,
    message: &[u8],
) -> (Option<Outcome>, Option<Outcome>, Option<Vec<u8>>) {
    let mut s = Link::new(LinkConfig {
        char_time: wire.char_time,
        ..cfg()
    });
    let mut r = Link::new(LinkConfig {
        char_time: wire.char_time,
        ..cfg()
    });
    r.receive(wire.now).unwrap();
    // In CRC-16 mode layer 3 has the PCI's bits 0..8 (the rest carries the message check).
    s.send(message, 0x0134, wire.now).unwrap();
    let (mut so, mut ro) = (None, None);
    wire.run(&mut s, &mut r, Duration::from_secs(600), |s, r| {
        so = so.or(s.poll_outcome());
        ro = ro.or(r.poll_outcome());
        so.is_some() && ro.is_some()
    });
    let data = r.take_received().map(|(pci, d)| {
        assert_eq!(pci, 0x0134);
        d
    });
    (so, ro, data)
}

#[test]
fn messages_of_every_boundary_size_arrive_exactly() {
    for len in [
        0,
        1,
        2,
        3,
        4,
        FRAME_SIZE + 1,
        FRAME_SIZE + 2,
        FRAME_SIZE + 3,
        3 * FRAME_SIZE,
        65535,
    ] {
        let message: Vec<u8> = (0..len).map(|i| (i * 7 + 3) as u8).collect();
        let mut w = Wire::new();
        let (so, ro, data) = transfer(&mut w, &message);
        assert_eq!(so, Some(Outcome::Sent), "len {len}");
        assert_eq!(ro, Some(Outcome::Received), "len {len}");
        assert_eq!(data.as_deref(), Some(&message[..]), "len {len}");
        assert_eq!(
            w.carried as usize,
            frame::wire_bytes_for(len),
            "wire bytes for len {len}"
        );
    }
}

#[test]
fn a_paced_transfer_takes_the_line_time_of_its_bytes() {
    let ct = trol_proto::link::config::char_time(38400);
    let mut w = Wire::paced(ct);
    let message = vec![0x5A; 1000];
    let (_, ro, _) = transfer(&mut w, &message);
    assert_eq!(ro, Some(Outcome::Received));
    let expected = ct * frame::wire_bytes_for(1000) as u32;
    let took = w.now.since_epoch();
    assert!(
        took >= expected && took <= expected + ct * 4,
        "took {took:?}, line time {expected:?}"
    );
}

#[test]
fn a_bad_frame_is_sent_again_and_the_message_arrives() {
    // Flip one bit in the first frame's data on the way: the receiver NAKs ERR_BCC, the
    // sender repeats the frame.
    let message: Vec<u8> = (0..600u32).map(|i| i as u8).collect();
    let mut s = Link::new(cfg());
    let mut r = Link::new(cfg());
    r.receive(Instant::ZERO).unwrap();
    s.send(&message, 9, Instant::ZERO).unwrap();
    let mut w = Wire::new();
    // Let ENQ/ACK/header/ACK pass untouched.
    let mut tx = Vec::new();
    s.drain_transmit(&mut tx); // ENQ
    r.handle_input(&tx, w.now);
    tx.clear();
    r.drain_transmit(&mut tx); // ACK
    s.handle_input(&tx, w.now);
    tx.clear();
    s.drain_transmit(&mut tx); // header
    r.handle_input(&tx, w.now);
    tx.clear();
    r.drain_transmit(&mut tx); // ACK
    s.handle_input(&tx, w.now);
    tx.clear();
    s.drain_transmit(&mut tx); // frame 0
    tx[10] ^= 0x04;
    r.handle_input(&tx, w.now);
    tx.clear();
    r.drain_transmit(&mut tx);
    assert_eq!(tx, vec![NAK, NakCode::Bcc.byte()]);
    s.handle_input(&tx, w.now);
    let (mut so, mut ro) = (None, None);
    w.run(&mut s, &mut r, T * 10, |s, r| {
        so = so.or(s.poll_outcome());
        ro = ro.or(r.poll_outcome());
        so.is_some() && ro.is_some()
    });
    assert_eq!(ro, Some(Outcome::Received));
    assert_eq!(r.take_received().unwrap().1, message);
}

// ---------------------------------------------------------------- the reset

#[test]
fn after_a_failure_stale_bytes_are_dropped_and_the_next_message_arrives_clean() {
    // The receiver fails inside a header; the rest of that header arrives late, during the
    // reset. The next transfer must not take any of it.
    let mut r = Link::new(cfg());
    r.receive(Instant::ZERO).unwrap();
    let mut w = Wire::new();
    let stale_header = header_bytes(2, 5, [0xEE, 0xEE]);
    let mut peer = Script {
        to_send: [vec![ENQ], stale_header[..4].to_vec()].concat(),
        ..Script::default()
    };
    assert_eq!(
        fail_recv(outcome_of(&mut w, &mut r, &mut peer)),
        ReceiveError::TimeoutTermc
    );
    assert!(r.is_resetting());
    // Stale rest of the header, and a stale EOT, arrive during the reset.
    peer.to_send = [stale_header[4..].to_vec(), vec![EOT]].concat();
    r.receive(w.now).unwrap();
    w.run(&mut r, &mut peer, T * 3, |r, _| !r.is_resetting());
    assert!(!r.is_resetting());
    assert!(r.stats().bytes_dropped >= 7, "the stale bytes were dropped");
    // Now a clean transfer from a fresh sender.
    let mut s = Link::new(cfg());
    s.send(b"new", 6, w.now).unwrap();
    let (mut so, mut ro) = (None, None);
    w.run(&mut s, &mut r, T * 10, |s, r| {
        so = so.or(s.poll_outcome());
        ro = ro.or(r.poll_outcome());
        so.is_some() && ro.is_some()
    });
    assert_eq!(
        w.flushes, 1,
        "the end of the reset asked for a flush of layer 1"
    );
    assert_eq!(ro, Some(Outcome::Received));
    assert_eq!(r.take_received(), Some((6, b"new".to_vec())));
}

#[test]
fn a_sender_waits_two_reset_periods_a_receiver_one() {
    let timeouts = Timeouts {
        reset: Duration::from_millis(300),
        ..Timeouts::default()
    };
    let c = LinkConfig { timeouts, ..cfg() };
    let mut s = Link::new(c);
    s.send(b"x", 0, Instant::ZERO).unwrap();
    let mut w = Wire::new();
    let mut peer = Script::default();
    let o = outcome_of(&mut w, &mut s, &mut peer);
    assert_eq!(fail_send(o), SendError::TimeoutEnq);
    let failed_at = w.now;
    // A new send asked for now starts only after two reset periods.
    s.send(b"y", 0, w.now).unwrap();
    peer.received.clear();
    w.run(&mut s, &mut peer, Duration::from_secs(5), |_, p| {
        !p.received.is_empty()
    });
    assert_eq!(peer.received, vec![ENQ]);
    assert_eq!(w.now - failed_at, Duration::from_millis(600));

    let mut r = Link::new(c);
    r.receive(Instant::ZERO).unwrap();
    let mut w = Wire::new();
    let mut peer = Script {
        to_send: vec![0x00],
        ..Script::default()
    };
    assert_eq!(
        fail_recv(outcome_of(&mut w, &mut r, &mut peer)),
        ReceiveError::BadEnq
    );
    let failed_at = w.now;
    w.run(&mut r, &mut peer, Duration::from_secs(5), |r, _| {
        !r.is_resetting()
    });
    assert_eq!(w.now - failed_at, Duration::from_millis(300));
}

#[test]
fn the_transcript_of_a_two_frame_message() {
    // ENQ, ACK, header, ACK, frame 0 (ETB), ACK, frame 1 (ETX), ACK, EOT.
    let message: Vec<u8> = (0..(2 + FRAME_SIZE + 1)).map(|i| i as u8).collect();
    let mut w = Wire::new();
    let (_, ro, _) = transfer(&mut w, &message);
    assert_eq!(ro, Some(Outcome::Received));
    let dirs: Vec<(Dir, usize)> = w.transcript.iter().map(|(d, v)| (*d, v.len())).collect();
    assert_eq!(
        dirs,
        vec![
            (Dir::AtoB, 1),
            (Dir::BtoA, 1),
            (Dir::AtoB, 10),
            (Dir::BtoA, 1),
            (Dir::AtoB, FRAME_SIZE + 6),
            (Dir::BtoA, 1),
            (Dir::AtoB, 7),
            (Dir::BtoA, 1),
            (Dir::AtoB, 1),
        ]
    );
    assert_eq!(*w.transcript[4].1.last().unwrap(), ETB);
    assert_eq!(*w.transcript[6].1.last().unwrap(), ETX);
    assert_eq!(w.transcript[8].1, vec![EOT]);
    assert_eq!(hex("1E"), vec![SOH]);
}

#[test]
fn in_crc16_mode_damage_that_passes_a_blocks_crc_is_caught_by_the_two_more_checks() {
    use trol_proto::link::BlockCheck::Crc16;
    assert_eq!(cfg().check, Crc16);
    // A header-only message whose BCC holds (as if the damage had matched the CRC-16) but
    // whose message check in the PCI does not: asked for again, not delivered.
    let msg = [0x11u8, 0x96];
    let good = Header::for_message(&msg, frame::line_pci(Crc16, 5, &msg));
    let damaged = Header {
        first_word: [0x11, 0x97],
        ..good
    }
    .encode(Crc16)
    .to_vec();
    let (got, o, _) = nak_after_header(damaged, cfg());
    assert_eq!(got, vec![ACK, NAK, NakCode::Bcc.byte()]);
    assert_eq!(o, None);

    // A frame whose BCC holds but whose frame-ID field's second CRC does not.
    let msg = b"hello";
    let (mut w, mut link, mut peer) = receiver_after_header(msg);
    let data = b"llp";
    let fid = frame::frame_id_field(Crc16, 0, &msg[2..]).to_le_bytes();
    let bcc = frame::frame_bcc(Crc16, data, fid).to_le_bytes();
    peer.to_send = [
        vec![STX],
        data.to_vec(),
        fid.to_vec(),
        bcc.to_vec(),
        vec![ETX],
    ]
    .concat();
    w.run(&mut link, &mut peer, T / 2, |_, p| p.received.len() >= 2);
    assert_eq!(peer.received, vec![NAK, NakCode::Bcc.byte()]);

    // Damage in an earlier frame that passed both of its checks is still caught by the
    // message check on the last frame: a header that announces other bytes than the frames
    // carry (its check was made over "hellp").
    let (mut w, mut link, mut peer) = {
        let mut link = Link::new(cfg());
        link.receive(Instant::ZERO).unwrap();
        let mut w = Wire::new();
        let other = b"hellp";
        let header = Header::for_message(b"hello", frame::line_pci(Crc16, 7, other))
            .encode(Crc16)
            .to_vec();
        let mut peer = Script {
            to_send: [vec![ENQ], header].concat(),
            ..Script::default()
        };
        w.run(&mut link, &mut peer, T / 2, |_, p| p.received.len() >= 2);
        assert_eq!(peer.received, vec![ACK, ACK]);
        peer.received.clear();
        (w, link, peer)
    };
    peer.to_send = frame_bytes(b"hello", 0);
    w.run(&mut link, &mut peer, T / 2, |_, p| p.received.len() >= 2);
    assert_eq!(peer.received, vec![NAK, NakCode::Bcc.byte()]);
}

#[test]
fn a_receiver_that_does_not_know_the_senders_set_delay_still_takes_its_long_message() {
    // The PC pauses 5 ms between bytes (the manual's SetDelay default); the controller's end
    // knows only the baud rate. A 600-byte message's 256-byte frames then take 1.4 s each,
    // longer than the block timeout: the receiver's timer restarts with each byte.
    let delay = Duration::from_millis(5);
    let ct = trol_proto::link::config::char_time(38400);
    let mut w = Wire::paced(ct + delay);
    let mut s = Link::new(LinkConfig::for_line(38400, delay));
    let mut r = Link::new(LinkConfig::for_line(38400, Duration::ZERO));
    r.receive(w.now).unwrap();
    let message: Vec<u8> = (0..600u32).map(|i| (i * 7) as u8).collect();
    s.send(&message, 3, w.now).unwrap();
    let (mut so, mut ro) = (None, None);
    w.run(&mut s, &mut r, Duration::from_secs(60), |s, r| {
        so = so.or(s.poll_outcome());
        ro = ro.or(r.poll_outcome());
        so.is_some() && ro.is_some()
    });
    assert_eq!(ro, Some(Outcome::Received));
    assert_eq!(so, Some(Outcome::Sent));
    assert_eq!(r.take_received().map(|(_, d)| d), Some(message));
}

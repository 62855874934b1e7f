//! Property tests: random payloads over a clean and a faulty simulated line.

mod common;

use std::time::Duration;

use common::Wire;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use trol_port::faulty::{FaultConfig, FaultInjector};
use trol_proto::Instant;
use trol_proto::link::control::{ACK, ENQ};
use trol_proto::link::frame::{self, FRAME_SIZE, Header};
use trol_proto::link::{BlockCheck, Link, LinkConfig, Outcome, Receiver};

fn transfer(
    wire: &mut Wire,
    message: &[u8],
) -> (Option<Outcome>, Option<Outcome>, Option<Vec<u8>>) {
    let mut s = Link::new(LinkConfig::default());
    let mut r = Link::new(LinkConfig::default());
    r.receive(wire.now).unwrap();
    s.send(message, 3, wire.now).unwrap();
    let (mut so, mut ro) = (None, None);
    let settled = wire.run(&mut s, &mut r, Duration::from_secs(3600), |s, r| {
        so = so.or(s.poll_outcome());
        ro = ro.or(r.poll_outcome());
        so.is_some() && ro.is_some()
    });
    assert!(settled, "both ends must come to an outcome");
    (so, ro, r.take_received().map(|(_, d)| d))
}

fn fixed(cases: u32) -> Config {
    Config {
        cases,
        rng_seed: RngSeed::Fixed(0x7201_1998),
        failure_persistence: None,
        ..Config::default()
    }
}

proptest! {
    #![proptest_config(fixed(48))]

    #[test]
    fn any_payload_arrives_exactly_over_a_clean_line(
        message in prop_oneof![
            proptest::collection::vec(any::<u8>(), 0..=600),
            proptest::collection::vec(any::<u8>(), 0..=65535),
        ]
    ) {
        let mut w = Wire::new();
        let (so, ro, data) = transfer(&mut w, &message);
        prop_assert_eq!(so, Some(Outcome::Sent));
        prop_assert_eq!(ro, Some(Outcome::Received));
        prop_assert_eq!(data, Some(message));
    }
}

proptest! {
    #![proptest_config(fixed(160))]

    /// Over a noisy line every transfer ends: the message arrives exactly, or both ends
    /// report one of the manual's codes. (At these rates two compensating errors in one
    /// block, which the LRC cannot see, do not occur in the fixed seeds; see
    /// `the_lrc_misses_some_multi_bit_errors` for how often they do at a high rate.)
    #[test]
    fn any_payload_arrives_exactly_or_fails_with_a_code_over_a_faulty_line(
        message in proptest::collection::vec(any::<u8>(), 0..=3000),
        seed in any::<u64>(),
        kind in 0u8..5,
    ) {
        let rate = |k: u8, r: f64| if kind == k || kind == 4 { r } else { 0.0 };
        let faults = |seed: u64| FaultConfig {
            seed,
            bit_error_rate: rate(0, 2e-5),
            drop_rate: rate(1, 2e-4),
            insert_rate: rate(2, 2e-4),
            duplicate_rate: rate(3, 2e-4),
            ..FaultConfig::default()
        };
        let mut w = Wire::paced(Duration::from_micros(260)).with_faults(faults(seed), faults(!seed));
        let (so, ro, data) = transfer(&mut w, &message);
        match ro {
            Some(Outcome::Received) => prop_assert_eq!(data, Some(message)),
            Some(Outcome::Failed(e)) => prop_assert!(e.code() != 0),
            other => prop_assert!(false, "receiver ended with {:?}", other),
        }
        prop_assert!(matches!(so, Some(Outcome::Sent | Outcome::Failed(_))));
    }
}

/// Feed one block (after ENQ) to a fresh receiver and report whether it was acknowledged.
fn receiver_acks(check: BlockCheck, before: &[u8], block: &[u8]) -> bool {
    let mut r = Receiver::new(LinkConfig {
        check,
        ..LinkConfig::default()
    });
    r.start();
    let now = Instant::ZERO;
    r.handle_input(&[ENQ], now);
    r.handle_input(before, now);
    let mut out = Vec::new();
    r.drain_transmit(&mut out);
    r.handle_input(block, now);
    let mut reply = Vec::new();
    r.drain_transmit(&mut reply);
    reply.first() == Some(&ACK)
}

/// Corrupted headers and frames a receiver accepts on a noisy line, with one block check.
fn missed(check: BlockCheck, ber: f64, blocks: u32) -> (u32, u32, u32, u32) {
    let mut noise = FaultInjector::new(FaultConfig {
        seed: 465,
        bit_error_rate: ber,
        ..FaultConfig::default()
    });
    let message: Vec<u8> = (0..(2 + FRAME_SIZE)).map(|i| (i * 31 + 7) as u8).collect();
    let header = Header::for_message(&message, 0).encode(check);
    let mut frame0 = Vec::new();
    frame::encode_frame(&message, 0, check, &mut frame0);
    let (mut hdr_corrupt, mut hdr_missed, mut frm_corrupt, mut frm_missed) =
        (0u32, 0u32, 0u32, 0u32);
    for _ in 0..blocks {
        let mut h = Vec::new();
        noise.apply(&header, &mut h);
        // Control codes with one bit flipped are accepted by design; a miss is an accepted
        // block whose other bytes differ.
        let inner = |b: &[u8]| b[1..b.len() - 1].to_vec();
        if h.len() == header.len() && inner(&h) != inner(&header) {
            hdr_corrupt += 1;
            if receiver_acks(check, &[], &h) {
                hdr_missed += 1;
            }
        }
        let mut f = Vec::new();
        noise.apply(&frame0, &mut f);
        if f.len() == frame0.len() && inner(&f) != inner(&frame0) {
            frm_corrupt += 1;
            if receiver_acks(check, &header, &f) {
                frm_missed += 1;
            }
        }
    }
    println!(
        "{check:?} at BER {ber}: {blocks} headers, {hdr_corrupt} corrupted, {hdr_missed} accepted; \
         {blocks} frames of {FRAME_SIZE} bytes, {frm_corrupt} corrupted, {frm_missed} accepted"
    );
    (hdr_corrupt, hdr_missed, frm_corrupt, frm_missed)
}

/// The manual's LRC is a plain sum: two errors that cancel in the sum pass. CRC-16 catches
/// every error of up to 3 bits: on the same noise it accepts no corrupted block. The counts
/// are written in docs/protocol.md ("Block check").
#[test]
fn the_lrc_misses_some_multi_bit_errors_and_crc16_none() {
    let blocks: u32 = std::env::var("TROL_LRC_BLOCKS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(5_000);
    let (_, _, frm_corrupt, frm_missed) = missed(BlockCheck::Lrc, 1e-3, blocks);
    assert!(frm_corrupt > blocks / 2, "the noise must reach most frames");
    assert!(
        frm_missed > 0,
        "a plain sum cannot catch every multi-bit error"
    );
    assert!(
        frm_missed < frm_corrupt / 20,
        "but it catches the great majority"
    );
    let (hdr_corrupt, hdr_missed, frm_corrupt, frm_missed) =
        missed(BlockCheck::Crc16, 1e-3, blocks);
    assert!(hdr_corrupt > 0 && frm_corrupt > blocks / 2);
    assert_eq!((hdr_missed, frm_missed), (0, 0));
}

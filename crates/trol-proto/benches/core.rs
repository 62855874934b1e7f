//! Cost of the sans-IO state machines alone: no line, no threads, no clock.
//! Run: cargo bench -p trol-proto --bench core

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use trol_proto::Instant;
use trol_proto::link::LinkConfig;
use trol_proto::transaction::{Initiator, InitiatorEvent, Responder, ResponderEvent};

/// One transaction: a 3-byte request (a CAT1 command's size) and a 2-byte reply (its return
/// value), both carried in the header alone, through Initiator and Responder.
fn one_transaction(
    i: &mut Initiator,
    r: &mut Responder,
    buf: &mut Vec<u8>,
    request: &[u8],
) -> Vec<u8> {
    let now = Instant::ZERO;
    i.start(request, now).expect("idle");
    loop {
        buf.clear();
        i.drain_transmit(buf);
        if !buf.is_empty() {
            r.handle_input(buf, now);
        }
        if r.poll_event() == Some(ResponderEvent::Request) {
            r.respond(&[0, 0], now);
        }
        buf.clear();
        r.drain_transmit(buf);
        if !buf.is_empty() {
            i.handle_input(buf, now);
        }
        if let Some(ev) = i.poll_event() {
            assert_eq!(ev, InitiatorEvent::Reply);
            return i.take_reply().expect("reply");
        }
    }
}

fn transactions(c: &mut Criterion) {
    let cfg = LinkConfig::default();
    let mut i = Initiator::new(cfg);
    let mut r = Responder::new(cfg);
    r.listen(Instant::ZERO);
    let mut buf = Vec::with_capacity(64);
    c.bench_function("transaction_3_byte_request_2_byte_reply", |b| {
        b.iter(|| one_transaction(&mut i, &mut r, &mut buf, black_box(&[7, 1, 0])))
    });
    let big: Vec<u8> = (0..1000u32).map(|x| x as u8).collect();
    c.bench_function("transaction_1000_byte_request_2_byte_reply", |b| {
        b.iter(|| one_transaction(&mut i, &mut r, &mut buf, black_box(&big)))
    });
}

criterion_group!(benches, transactions);
criterion_main!(benches);

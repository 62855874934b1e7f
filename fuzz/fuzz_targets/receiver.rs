#![no_main]
//! Fuzz the receiving side of layer 2 with arbitrary line input.
//! Run: cargo +nightly fuzz run receiver fuzz/seeds/receiver

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    trol_proto::fuzzing::receive(data);
});

//! The fuzz target's body on the stable toolchain: its seeds (taken from the vectors of
//! docs/protocol.md) and random inputs must not panic.

use proptest::prelude::*;

#[test]
fn the_fuzz_seeds_run_clean() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fuzz/seeds/receiver");
    let mut n = 0;
    for entry in std::fs::read_dir(dir).expect("fuzz/seeds/receiver") {
        let data = std::fs::read(entry.unwrap().path()).unwrap();
        trol_proto::fuzzing::receive(&data);
        n += 1;
    }
    assert!(n >= 7, "{n} seeds");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, failure_persistence: None, ..ProptestConfig::default() })]
    #[test]
    fn random_line_input_never_panics(data in proptest::collection::vec(any::<u8>(), 0..2000)) {
        trol_proto::fuzzing::receive(&data);
    }
}

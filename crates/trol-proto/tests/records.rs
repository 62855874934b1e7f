//! Layer 4: every request and reply record, encoded and decoded from the command table; the
//! refusals with the manual's codes; the `trol-record` vectors of docs/protocol.md.

use proptest::prelude::*;
use trol_proto::application::code::*;
use trol_proto::application::record::{self, Value};
use trol_proto::application::table::*;
use trol_proto::application::*;

fn name(s: &str) -> Value {
    Value::Name(LocName::new(s).unwrap())
}

fn cart(v: &[f64]) -> Value {
    Value::Loc(Location::Cart(v.to_vec()))
}

fn joints(v: &[f64]) -> Value {
    Value::Loc(Location::Joint(v.to_vec()))
}

/// One request of every built-in command.
fn one_of_each() -> Vec<(&'static CommandDef, Vec<Value>)> {
    use Value::*;
    vec![
        (&APPRO, vec![name("test_001"), cart(&[-90.0]), Flag(true)]),
        (
            &APPRO_II,
            vec![
                Loc(Location::Prec(vec![1000, -2000, 3000, 0, 5, -6])),
                cart(&[-50.0, 0.0, 10.0]),
                Flag(false),
            ],
        ),
        (&CLOSE, vec![Int(60)]),
        (&DEPART, vec![cart(&[-90.0]), Flag(true)]),
        (&FINISH, vec![Int(FINISH_WAIT)]),
        (&GRIP, vec![Int(25)]),
        (&HALT, vec![]),
        (&HOME, vec![Int(0)]),
        (&JOG, vec![cart(&[10.0, 0.0, -5.0]), Flag(true)]),
        (&JOINT, vec![Int(1), Real(0.5)]),
        (&MA, vec![joints(&[0.0, 0.5, 1.0, 0.0, 0.5, 0.0])]),
        (&MI, vec![joints(&[0.1f32 as f64])]),
        (&MOVE, vec![name("p1"), Flag(false)]),
        (
            &MOVE_II,
            vec![cart(&[400.0, 0.0, 300.0, 0.0, 1.5, 0.0]), Flag(true)],
        ),
        (&OPEN, vec![Int(100)]),
        (&READY, vec![]),
        (
            &SET_TOOL_TRANSFORM,
            vec![cart(&[0.0, 0.0, 120.0, 0.0, 0.0, 0.0])],
        ),
        (&SPEED, vec![Int(150)]),
        (&GET_POSITION, vec![Int(Tag::Cart as u8), Int(POS_ACT)]),
        (&TERMINATE_PCP, vec![]),
        (&GET_STATUS, vec![]),
        (&GET_VERSION, vec![]),
        (&SET_WATCHDOG, vec![Int(50)]),
        (&GET_CODES, vec![]),
        (&GET_REPLY_TIME, vec![]),
        (&GET_GRIPPER, vec![]),
        (&LIST_LOCATIONS, vec![]),
        (&HERE, vec![name("p1"), Int(Tag::Cart as u8)]),
        (
            &DEFINE,
            vec![
                name("#park"),
                Loc(Location::Prec(vec![0, 100, -200, 0, 5, 0])),
            ],
        ),
        (&DELETE_LOCATION, vec![name("p1")]),
        (&SAVE_LOCATIONS, vec![]),
        (
            &TRAJECTORY,
            vec![Path(vec![
                Waypoint {
                    time: 0.5,
                    joints: [0.0, 0.25, 0.5, 0.0, 0.25, 0.0],
                },
                Waypoint {
                    time: 1.5,
                    joints: [0.5, 0.5, 1.0, 0.0, 0.5, -0.5],
                },
            ])],
        ),
    ]
}

/// A trajectory's count and waypoints (docs/protocol.md, "Trajectory"): the size follows
/// the count; no waypoints, times that do not increase, a time out of 0..3600 s or a value
/// that is not finite is TROL_ERR_ARG_RANGE on both sides.
#[test]
fn a_trajectory_carries_its_count_and_increasing_times() {
    let at = |time: f64| Waypoint {
        time,
        joints: [0.0, 0.125, 0.25, -0.5, 1.0, 2.0],
    };
    let ok = vec![Value::Path(vec![at(0.0), at(0.25), at(2.0)])];
    let bytes = record::encode(&TRAJECTORY, &ok).unwrap();
    // Code, count (2 bytes), a pad to an even offset, then 28 bytes per waypoint.
    assert_eq!(&bytes[..4], &[TROL_TRAJECTORY, 3, 0, 0]);
    assert_eq!(bytes.len(), 4 + 3 * 28);
    assert_eq!(record::decode(&TRAJECTORY, &bytes).unwrap(), ok);
    // One waypoint more or fewer than the count says: the size is wrong.
    let mut long = bytes.clone();
    long.extend_from_slice(&[0; 28]);
    assert_eq!(
        record::decode(&TRAJECTORY, &long).unwrap_err().code(),
        TROL_ERR_BAD_CSIZE
    );
    assert_eq!(
        record::decode(&TRAJECTORY, &bytes[..bytes.len() - 28])
            .unwrap_err()
            .code(),
        TROL_ERR_BAD_CSIZE
    );
    let refused = |points: Vec<Waypoint>| {
        let e = record::encode(&TRAJECTORY, &[Value::Path(points)]).unwrap_err();
        assert_eq!(e.code(), TROL_ERR_ARG_RANGE, "{e}");
        e.to_string()
    };
    assert!(refused(vec![]).contains("0 waypoints"));
    assert!(refused(vec![at(1.0), at(1.0)]).contains("times must increase"));
    assert!(refused(vec![at(2.0), at(1.0)]).contains("times must increase"));
    assert!(refused(vec![at(-0.5)]).contains("outside"));
    assert!(refused(vec![at(3601.0)]).contains("outside"));
    let mut nan = at(1.0);
    nan.joints[3] = f64::NAN;
    assert!(refused(vec![nan]).contains("finite"));
    assert!(refused(vec![at(1.0); usize::from(MAX_WAYPOINTS) + 1]).contains("waypoints"));
    // Its 1 is named as the command means it, not as the BIOS table's 1 (moving).
    let untimed = Reply::Code(Code(TRAJECTORY_UNTIMED));
    assert!(
        untimed
            .text_for(&TRAJECTORY, &[])
            .starts_with("1 (TRAJECTORY_UNTIMED")
    );
    assert_eq!(untimed.text_for(&FINISH, &[]), untimed.text(&[]));
    // The controller checks the same: decreasing times put on the line by hand.
    let mut back = record::encode(&TRAJECTORY, &[Value::Path(vec![at(1.0), at(2.0)])]).unwrap();
    back[4..8].copy_from_slice(&3.0f32.to_le_bytes());
    assert_eq!(
        record::decode(&TRAJECTORY, &back).unwrap_err().code(),
        TROL_ERR_ARG_RANGE
    );
}

/// ListLocations' reply (docs/protocol.md, "Locations"): names with their locations
/// round-trip; a cut entry, a bad name or tag, a value that is not 0, is TROL_ERR_BAD_RSIZE.
#[test]
fn a_locations_reply_holds_only_what_the_rules_allow() {
    use trol_proto::application::LocName;
    let def = &table::LIST_LOCATIONS;
    let all = vec![
        (
            LocName::new("#park").unwrap(),
            Location::Prec(vec![0, 100, -200, 0, 5, 0]),
        ),
        (
            LocName::new("p1").unwrap(),
            Location::Cart(vec![400.0, 0.0, 300.0, 0.0, 1.5, 0.0]),
        ),
        (
            LocName::new("pj").unwrap(),
            Location::Joint(vec![0.0, 0.5, 1.0, 0.0, 0.25, 0.0]),
        ),
    ];
    for list in [vec![], all.clone()] {
        let bytes = Reply::Locations(list.clone()).encode();
        assert_eq!(Reply::decode(def, &bytes).unwrap(), Reply::Locations(list));
    }
    let good = Reply::Locations(all).encode();
    assert_eq!(good.len(), 2 + 3 * 33);
    let mut bad_name = good.clone();
    bad_name[2] = b'9';
    let mut bad_tag = good.clone();
    bad_tag[2 + 8] = 7;
    for bad in [
        good[..good.len() - 1].to_vec(),
        [&[1u8, 0][..], &good[2..]].concat(),
        bad_name,
        bad_tag,
    ] {
        assert_eq!(
            Reply::decode(def, &bad).unwrap_err().code(),
            trol_proto::application::code::TROL_ERR_BAD_RSIZE,
            "{bad:02x?}"
        );
    }
}

#[test]
fn a_version_reply_is_accepted_only_in_its_form() {
    let good = Reply::Version {
        protocol: PROTOCOL_VERSION,
        kind: "simulated A465".into(),
    };
    let bytes = good.encode();
    assert_eq!(Reply::decode(&GET_VERSION, &bytes).unwrap(), good);
    let mut long = vec![0, 0, 3, 0];
    long.extend(std::iter::repeat_n(b'x', 33));
    for bad in [
        vec![0, 0, 3, 0],                   // no kind
        vec![1, 0, 3, 0, b'x'],             // a value that is not 0
        vec![0, 0, 3],                      // cut in the version
        vec![0, 0, 3, 0, b'x', 0x07, b'y'], // not printable
        long,                               // too long
    ] {
        assert!(Reply::decode(&GET_VERSION, &bad).is_err(), "{bad:02x?}");
    }
    // A refusal is a refusal, as for every command.
    assert_eq!(
        Reply::decode(
            &GET_VERSION,
            &trol_proto::application::code::TROL_ERR_UNKNOWN
                .0
                .to_le_bytes()
        )
        .unwrap(),
        Reply::Code(trol_proto::application::code::TROL_ERR_UNKNOWN)
    );
}

#[test]
fn every_builtin_request_round_trips_and_starts_with_its_code() {
    let all = one_of_each();
    assert_eq!(all.len(), BUILTIN.len());
    let catalog = Catalog::builtin();
    for (def, values) in all {
        let bytes = record::encode(def, &values).unwrap();
        assert_eq!(bytes[0], def.code);
        let (back_def, back) = catalog.decode(&bytes).unwrap();
        assert_eq!(back_def, def);
        assert_eq!(back, values);
    }
}

#[test]
fn depart_packs_num_dims_and_straight_into_one_byte_as_the_manual_does() {
    let bytes = record::encode(&DEPART, &[cart(&[-90.0]), Value::Flag(true)]).unwrap();
    // code, numDims 1 / tag POS_CART / straight, then one little-endian float.
    assert_eq!(bytes, [TROL_DEPART, 0x15, 0x00, 0x00, 0xB4, 0xC2]);
}

#[test]
fn a_request_of_the_wrong_size_is_bad_csize() {
    let catalog = Catalog::builtin();
    for (def, values) in one_of_each() {
        let bytes = record::encode(def, &values).unwrap();
        let mut longer = bytes.clone();
        longer.push(0);
        assert_eq!(
            catalog.decode(&longer).unwrap_err().code(),
            TROL_ERR_BAD_CSIZE,
            "{}",
            def.name
        );
        if bytes.len() > 1 {
            let shorter = &bytes[..bytes.len() - 1];
            assert_eq!(
                catalog.decode(shorter).unwrap_err().code(),
                TROL_ERR_BAD_CSIZE,
                "{}",
                def.name
            );
        }
    }
}

#[test]
fn unknown_codes_are_refused_with_trol_err_unknown() {
    let catalog = Catalog::builtin();
    assert_eq!(catalog.decode(&[]).unwrap_err().code(), TROL_ERR_UNKNOWN);
    for code in [
        LAST_CAT1_CODE + 1,
        63,
        64,
        100,
        LAST_CAT3_CODE + 1,
        LAST_CAT4_CODE + 1,
        255,
    ] {
        let e = catalog.decode(&[code, 0, 0]).unwrap_err();
        assert_eq!(e, RequestError::Unknown(Some(code)));
        assert_eq!(e.code(), TROL_ERR_UNKNOWN);
    }
}

#[test]
fn out_of_range_fields_are_arg_range_on_both_sides() {
    use Value::*;
    let bad: Vec<(&CommandDef, Vec<Value>)> = vec![
        (&CLOSE, vec![Int(0)]),
        (&OPEN, vec![Int(101)]),
        (&GRIP, vec![Int(51)]),
        (&SPEED, vec![Int(0)]),
        (&SPEED, vec![Int(151)]),
        (&HOME, vec![Int(7)]),
        (&JOINT, vec![Int(0), Real(0.1)]),
        (&JOINT, vec![Int(7), Real(0.1)]),
        (&JOINT, vec![Int(1), Real(f64::NAN)]),
        (&JOINT, vec![Int(1), Real(1e39)]),
        (&JOG, vec![cart(&[1.0; 4]), Flag(false)]),
        (&DEPART, vec![cart(&[]), Flag(false)]),
        (&MA, vec![joints(&[0.0; 7])]),
        (&MOVE_II, vec![joints(&[0.0; 6]), Flag(false)]),
        (
            &APPRO_II,
            vec![cart(&[f64::INFINITY]), cart(&[1.0]), Flag(false)],
        ),
        (&FINISH, vec![Int(2)]),
        (&GET_POSITION, vec![Int(3), Int(0)]),
        // A reserved name (docs/teach.md, "Names"), in any case.
        (&MOVE, vec![name("T1"), Flag(false)]),
        (&APPRO, vec![name("#t18"), cart(&[-90.0]), Flag(false)]),
        // Wrong kinds and counts.
        (&HOME, vec![Flag(true)]),
        (&HOME, vec![]),
    ];
    for (def, values) in &bad {
        let e = record::encode(def, values).unwrap_err();
        assert_eq!(e.code(), TROL_ERR_ARG_RANGE, "{}: {e}", def.name);
    }
    // The controller checks the same after decoding: build the bytes by hand.
    let cases: Vec<Vec<u8>> = vec![
        vec![TROL_CLOSE, 0],
        vec![TROL_SPEED, 151],
        vec![TROL_FINISH, 2],
        vec![TROL_GET_POSITION, 3, 0],
        vec![TROL_GET_POSITION, 2, 2],
        vec![TROL_MOVE, 2, b'p', b'1', b' ', b' ', b' ', b' ', b' ', b' '],
        vec![TROL_MOVE, 0, b'1', b'p', b' ', b' ', b' ', b' ', b' ', b' '],
        vec![TROL_MOVE, 0, b'p', b'1', 0, b' ', b' ', b' ', b' ', b' '],
        // A reserved name, sent by a host that does not check it.
        vec![TROL_MOVE, 0, b't', b'7', b' ', b' ', b' ', b' ', b' ', b' '],
        // MA with the cartesian tag.
        vec![TROL_MA, 0x14, 0, 0, 0, 0],
        // MA with the straight bit.
        vec![TROL_MA, 0x13, 0, 0, 0, 0],
        // MA with numDims 0 and 7.
        vec![TROL_MA, 0x02],
        // Joint with a NaN.
        vec![TROL_JOINT, 1, 0, 0, 0xC0, 0x7F],
        // ApproII with a non-zero reserved byte.
        vec![TROL_APPRO_II, 0x14, 0x14, 1, 0, 0, 0, 0, 0, 0, 0, 0],
        // ApproII with the straight bit on the second location.
        vec![TROL_APPRO_II, 0x14, 0x15, 0, 0, 0, 0, 0, 0, 0, 0, 0],
    ];
    let catalog = Catalog::builtin();
    for bytes in cases {
        assert_eq!(
            catalog.decode(&bytes).unwrap_err().code(),
            TROL_ERR_ARG_RANGE,
            "{bytes:02X?}"
        );
    }
}

#[test]
fn replies_round_trip_and_bad_sizes_are_bad_rsize() {
    let cases = vec![
        (&MOVE, Reply::Code(Code(0))),
        (&FINISH, Reply::Code(Code(1))),
        (&JOINT, Reply::Code(Code(-3))),
        (&MOVE, Reply::Code(TROL_ERR_LOCATION)),
        (
            &GET_POSITION,
            Reply::Position(Location::Cart(vec![1.0, 2.0, 3.0, 0.5, 0.25, 0.125])),
        ),
        (
            &GET_POSITION,
            Reply::Position(Location::Prec(vec![1, -2, 3, 4, 5, 6])),
        ),
        (&GET_POSITION, Reply::Code(TROL_ERR_BAD_CSIZE)),
        (
            &GET_STATUS,
            Reply::Status {
                bios_called: true,
                last: Code(-32700),
                transaction: 7,
                epoch: 0xBEEF,
            },
        ),
        (&TERMINATE_PCP, Reply::Code(Code(0))),
    ];
    for (def, reply) in cases {
        let bytes = reply.encode();
        assert_eq!(Reply::decode(def, &bytes).unwrap(), reply);
        let mut longer = bytes.clone();
        longer.push(0);
        assert_eq!(
            Reply::decode(def, &longer).unwrap_err().code(),
            TROL_ERR_BAD_RSIZE
        );
        assert_eq!(
            Reply::decode(def, &bytes[..1]).unwrap_err().code(),
            TROL_ERR_BAD_RSIZE
        );
    }
    // A CAT1 reply is one word; a GetStatus value other than 0/1 is not a status; a position
    // has six values, no more and no fewer.
    assert!(Reply::decode(&MOVE, &[0, 0, 0, 0]).is_err());
    assert!(Reply::decode(&GET_STATUS, &[2, 0, 0, 0, 0, 0, 0, 0]).is_err());
    // The manual's 4-byte status (a 1998 controller's: no transaction, no epoch) is read as
    // epoch 0, which no controller of this protocol draws, and written back the same; an
    // 8-byte status with epoch 0 is neither.
    let manual = Reply::decode(&GET_STATUS, &[1, 0, 0xF6, 0xFF]).unwrap();
    assert_eq!(
        manual,
        Reply::Status {
            bios_called: true,
            last: Code(-10),
            transaction: 0,
            epoch: 0,
        }
    );
    assert_eq!(manual.encode(), [1, 0, 0xF6, 0xFF]);
    assert!(Reply::decode(&GET_STATUS, &[1, 0, 0, 0, 7, 0, 0, 0]).is_err());
    assert!(Reply::decode(&GET_STATUS, &[1, 0, 0, 0, 0, 0]).is_err());
    for n in 0..=8u8 {
        let mut bytes = vec![0, 0, Tag::Cart as u8, n];
        bytes.resize(4 + 4 * n as usize, 0);
        assert_eq!(Reply::decode(&GET_POSITION, &bytes).is_ok(), n == 6, "{n}");
    }
}

fn arb_reals(max: usize) -> impl Strategy<Value = Vec<f64>> {
    prop::collection::vec((-1.0e4f32..1.0e4).prop_map(f64::from), 1..=max)
}

fn arb_target() -> impl Strategy<Value = Location> {
    prop_oneof![
        prop::collection::vec(any::<i32>(), 1..=6).prop_map(Location::Prec),
        arb_reals(6).prop_map(|v| Location::Cart(within_a_turn(v))),
    ]
}

/// A cartesian location's angles (values 3..6) kept within a full turn, as every surface
/// requires (f32 exact, so the round trip stays exact).
fn within_a_turn(v: Vec<f64>) -> Vec<f64> {
    v.into_iter()
        .enumerate()
        .map(|(i, x)| {
            if i < 3 {
                x
            } else {
                f64::from((x as f32) % 6.0)
            }
        })
        .collect()
}

fn arb_request() -> impl Strategy<Value = (&'static CommandDef, Vec<Value>)> {
    use Value::*;
    let name = "[a-zA-Z#][a-zA-Z0-9_]{0,7}"
        .prop_map(|s| LocName::new(&s).unwrap())
        .prop_filter("a reserved name is refused", |n| !n.reserved())
        .prop_map(Name);
    let c = |v: Vec<f64>| Loc(Location::Cart(within_a_turn(v)));
    let j = |v: Vec<f64>| Loc(Location::Joint(v));
    prop_oneof![
        (name.clone(), arb_reals(6), any::<bool>())
            .prop_map(move |(n, d, s)| (&APPRO, vec![n, c(d), Flag(s)])),
        (arb_target(), arb_reals(6), any::<bool>())
            .prop_map(move |(t, d, s)| (&APPRO_II, vec![Loc(t), c(d), Flag(s)])),
        (1u8..=100).prop_map(|f| (&CLOSE, vec![Int(f)])),
        (arb_reals(6), any::<bool>()).prop_map(move |(d, s)| (&DEPART, vec![c(d), Flag(s)])),
        (arb_reals(3), any::<bool>()).prop_map(move |(d, s)| (&JOG, vec![c(d), Flag(s)])),
        (1u8..=6, -10.0f32..10.0).prop_map(|(n, r)| (&JOINT, vec![Int(n), Real(r.into())])),
        arb_reals(6).prop_map(move |q| (&MA, vec![j(q)])),
        arb_reals(6).prop_map(move |q| (&MI, vec![j(q)])),
        (name, any::<bool>()).prop_map(|(n, s)| (&MOVE, vec![n, Flag(s)])),
        (arb_target(), any::<bool>()).prop_map(|(t, s)| (&MOVE_II, vec![Loc(t), Flag(s)])),
        arb_reals(6).prop_map(move |t| (&SET_TOOL_TRANSFORM, vec![c(t)])),
        (1u8..=150).prop_map(|p| (&SPEED, vec![Int(p)])),
        (0u8..=50).prop_map(|d| (&GRIP, vec![Int(d)])),
        (0u8..=6).prop_map(|a| (&HOME, vec![Int(a)])),
        prop::collection::vec((0.001f32..10.0, prop::array::uniform6(-3.0f32..3.0)), 1..20)
            .prop_map(|steps| {
                let mut t = 0.0f32;
                let path = steps
                    .into_iter()
                    .map(|(dt, q)| {
                        t += dt;
                        Waypoint {
                            time: t.into(),
                            joints: q.map(f64::from),
                        }
                    })
                    .collect();
                (&TRAJECTORY, vec![Path(path)])
            }),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn valid_requests_round_trip((def, values) in arb_request()) {
        let bytes = record::encode(def, &values).unwrap();
        prop_assert_eq!(record::decode(def, &bytes).unwrap(), values);
    }

    #[test]
    fn any_bytes_decode_to_a_request_or_a_code(bytes in prop::collection::vec(any::<u8>(), 0..64)) {
        let catalog = Catalog::builtin();
        match catalog.decode(&bytes) {
            Ok((def, values)) => prop_assert_eq!(record::encode(def, &values).unwrap(), bytes.clone()),
            Err(e) => prop_assert!([TROL_ERR_UNKNOWN, TROL_ERR_BAD_CSIZE, TROL_ERR_ARG_RANGE].contains(&e.code())),
        }
        for def in BUILTIN {
            let _ = Reply::decode(def, &bytes);
        }
    }
}

fn hex(s: &str) -> Vec<u8> {
    s.split_whitespace()
        .map(|t| u8::from_str_radix(t, 16).unwrap_or_else(|_| panic!("bad byte {t}")))
        .collect()
}

/// The `trol-record` blocks of docs/protocol.md: `request:` or `reply-to:`/`reply:` bytes and
/// the text they stand for (the form the interpreter reads, the trace and the logs print).
/// Each is decoded and compared, then encoded again and compared byte for byte.
#[test]
fn the_record_vectors_of_the_spec_hold() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/protocol.md");
    let doc = std::fs::read_to_string(path).expect("docs/protocol.md");
    let catalog = Catalog::builtin();
    let mut seen = std::collections::HashSet::new();
    let mut count = 0;
    for block in doc.split("```trol-record").skip(1) {
        let body = block.split("```").next().unwrap();
        let field = |key: &str| {
            body.lines()
                .find_map(|l| l.trim().strip_prefix(key).map(|v| v.trim().to_string()))
        };
        let decoded = field("decoded:").expect("decoded:");
        if let Some(req) = field("request:") {
            let bytes = hex(&req);
            let (def, values) = catalog
                .decode(&bytes)
                .unwrap_or_else(|e| panic!("{req}: {e}"));
            assert_eq!(record::format_call(def, &values), decoded);
            assert_eq!(record::encode(def, &values).unwrap(), bytes);
            seen.insert(def.code);
        } else {
            let def = catalog
                .find(&field("reply-to:").expect("reply-to:"))
                .unwrap();
            let bytes = hex(&field("reply:").expect("reply:"));
            let r = Reply::decode(def, &bytes).unwrap();
            assert_eq!(r.text(&[]), decoded);
            assert_eq!(r.encode(), bytes);
        }
        count += 1;
    }
    assert!(count > 0);
    let missing: Vec<_> = BUILTIN
        .iter()
        .filter(|d| !seen.contains(&d.code))
        .map(|d| d.name)
        .collect();
    assert!(
        missing.is_empty(),
        "commands without a request vector: {missing:?}"
    );
}

#[test]
#[ignore = "prints the record vectors for docs/protocol.md"]
fn print_record_vectors() {
    let hexs = |b: &[u8]| {
        b.iter()
            .map(|x| format!("{x:02X}"))
            .collect::<Vec<_>>()
            .join(" ")
    };
    for (def, values) in one_of_each() {
        println!(
            "```trol-record\nrequest: {}\ndecoded: {}\n```\n",
            hexs(&record::encode(def, &values).unwrap()),
            record::format_call(def, &values)
        );
    }
}

/// GetCodes' reply (docs/protocol.md, "Codes"): what the rules allow round-trips; anything
/// else is TROL_ERR_BAD_RSIZE, never a table with a wrong name in it.
#[test]
fn a_codes_reply_holds_only_what_the_rules_allow() {
    use trol_proto::application::CodeEntry;
    use trol_proto::application::reply::{MAX_CODE_MEANING, MAX_CODE_NAME, MAX_CODES};
    let def = &table::GET_CODES;
    let entry = |v: i16, name: &str, meaning: &str| CodeEntry {
        value: v,
        name: name.into(),
        meaning: meaning.into(),
    };
    let most: Vec<CodeEntry> = (1..=MAX_CODES as i16)
        .map(|i| {
            entry(
                -i,
                &"N".repeat(MAX_CODE_NAME),
                &"m".repeat(MAX_CODE_MEANING),
            )
        })
        .collect();
    for codes in [vec![], vec![entry(-1, "BIOS_A", "")], most.clone()] {
        let bytes = Reply::Codes(codes.clone()).encode();
        assert_eq!(Reply::decode(def, &bytes).unwrap(), Reply::Codes(codes));
    }
    let good = Reply::Codes(vec![entry(-1, "BIOS_A", "a"), entry(5, "BIOS_B", "b")]).encode();
    let mut bad: Vec<Vec<u8>> = vec![
        // Cut anywhere inside an entry.
        good[..good.len() - 1].to_vec(),
        good[..3].to_vec(),
        // A return value other than 0.
        [&[1u8, 0][..], &good[2..]].concat(),
        // One code too many (the encoder never writes more than the most).
        [
            Reply::Codes(most.clone()).encode(),
            Reply::Codes(vec![entry(-99, "X", "")]).encode()[2..].to_vec(),
        ]
        .concat(),
    ];
    // Success or a TROL code in the table; an empty name; a name too long; a byte that is
    // not printable.
    for v in [0i16, -32001] {
        let mut b = good.clone();
        b[2..4].copy_from_slice(&v.to_le_bytes());
        bad.push(b);
    }
    let mut b = good.clone();
    b[4] = 0;
    bad.push(b);
    let mut b = vec![0, 0, 0xFF, 0xFF, MAX_CODE_NAME as u8 + 1];
    b.extend(std::iter::repeat_n(b'N', MAX_CODE_NAME + 1));
    b.push(0);
    bad.push(b);
    let mut b = good.clone();
    b[5] = 0x07;
    bad.push(b);
    for b in bad {
        let e = Reply::decode(def, &b).unwrap_err();
        assert_eq!(
            e.code(),
            trol_proto::application::code::TROL_ERR_BAD_RSIZE,
            "{b:02x?}"
        );
    }
}

/// GetGripper's reply (docs/protocol.md, "Gripper"): its three forms round-trip; a held byte
/// out of range, a name where none belongs, or an opening that is not a length is
/// TROL_ERR_BAD_RSIZE.
#[test]
fn a_gripper_reply_holds_only_what_the_rules_allow() {
    let def = &table::GET_GRIPPER;
    for held in [
        Held::Nothing,
        Held::Unknown,
        Held::Object("cube".into()),
        Held::Object(String::new()),
    ] {
        let r = Reply::Gripper(Gripper {
            opening_mm: 12.5,
            held,
        });
        assert_eq!(Reply::decode(def, &r.encode()).unwrap(), r);
    }
    let opening = 12.5f32.to_le_bytes();
    let with = |held: &[u8]| [&[0u8, 0][..], &opening, held].concat();
    for bad in [
        with(&[3]),
        with(&[0, b'x']),
        with(&[2, b'x']),
        with(&[1, 0x07]),
        [&[0u8, 0][..], &f32::NAN.to_le_bytes(), &[0]].concat(),
        [&[0u8, 0][..], &(-1.0f32).to_le_bytes(), &[0]].concat(),
        [&[1u8, 0][..], &opening, &[0]].concat(),
        with(&[]),
    ] {
        let e = Reply::decode(def, &bad).unwrap_err();
        assert_eq!(e.code(), TROL_ERR_BAD_RSIZE, "{bad:02x?}");
    }
}

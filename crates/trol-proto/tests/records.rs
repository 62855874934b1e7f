//! Layer 4: every request and reply record, encoded and decoded; the refusals with the
//! manual's codes; the `trol-record` vectors of docs/protocol.md.

use proptest::prelude::*;
use trol_proto::application::codes::*;
use trol_proto::application::errors::*;
use trol_proto::application::*;

fn name(s: &str) -> LocName {
    LocName::new(s).unwrap()
}

/// One request of every built-in command.
fn one_of_each() -> Vec<Request> {
    vec![
        Request::Appro {
            name: name("test_001"),
            disp: vec![-90.0],
            straight: true,
        },
        Request::ApproII {
            target: Location::Prec(vec![1000, -2000, 3000, 0, 5, -6]),
            disp: vec![-50.0, 0.0, 10.0],
            straight: false,
        },
        Request::Close { force: 60 },
        Request::Depart {
            disp: vec![-90.0],
            straight: true,
        },
        Request::Finish {
            mode: FinishMode::Wait,
        },
        Request::Grip { dist: 25 },
        Request::Halt,
        Request::Home { axis: 0 },
        Request::Jog {
            disp: vec![10.0, 0.0, -5.0],
            straight: true,
        },
        Request::Joint {
            joint: 1,
            radians: 0.5,
        },
        Request::Ma {
            joints: vec![0.0, 0.5, 1.0, 0.0, 0.5, 0.0],
        },
        Request::Mi { joints: vec![0.1] },
        Request::Move {
            name: name("p1"),
            straight: false,
        },
        Request::MoveII {
            target: Location::Cart(vec![400.0, 0.0, 300.0, 0.0, 1.5, 0.0]),
            straight: true,
        },
        Request::Open { force: 100 },
        Request::Ready,
        Request::SetToolTransform {
            tool: vec![0.0, 0.0, 120.0, 0.0, 0.0, 0.0],
        },
        Request::Speed { percent: 150 },
        Request::GetPosition {
            tag: Tag::Cart,
            mode: PosMode::Actual,
        },
        Request::TerminatePcp,
        Request::GetStatus,
    ]
}

#[test]
fn every_builtin_request_round_trips_and_starts_with_its_code() {
    let all = one_of_each();
    assert_eq!(all.len(), Command::ALL.len());
    for req in all {
        let bytes = req.encode();
        assert_eq!(bytes[0], req.command().code());
        assert_eq!(Request::decode(&bytes).unwrap(), req);
    }
}

#[test]
fn depart_packs_num_dims_and_straight_into_one_byte_as_the_manual_does() {
    let bytes = Request::Depart {
        disp: vec![-90.0],
        straight: true,
    }
    .encode();
    // code, numDims 1 / tag POS_CART / straight, then one little-endian float.
    assert_eq!(bytes, [TROL_DEPART, 0x15, 0x00, 0x00, 0xB4, 0xC2]);
}

#[test]
fn a_request_of_the_wrong_size_is_bad_csize() {
    for req in one_of_each() {
        let bytes = req.encode();
        let mut longer = bytes.clone();
        longer.push(0);
        assert_eq!(
            Request::decode(&longer).unwrap_err().code(),
            TROL_ERR_BAD_CSIZE,
            "{req:?}"
        );
        if bytes.len() > 1 {
            let shorter = &bytes[..bytes.len() - 1];
            assert_eq!(
                Request::decode(shorter).unwrap_err().code(),
                TROL_ERR_BAD_CSIZE,
                "{req:?}"
            );
        }
    }
}

#[test]
fn unknown_codes_are_refused_with_trol_err_unknown() {
    assert_eq!(Request::decode(&[]).unwrap_err().code(), TROL_ERR_UNKNOWN);
    for code in [
        LAST_CAT1_CODE + 1,
        63,
        64,
        100,
        LAST_CAT3_CODE + 1,
        LAST_CAT4_CODE + 1,
        255,
    ] {
        let e = Request::decode(&[code, 0, 0]).unwrap_err();
        assert_eq!(e, RequestError::Unknown(Some(code)));
        assert_eq!(e.code(), TROL_ERR_UNKNOWN);
    }
}

#[test]
fn out_of_range_fields_are_arg_range_on_both_sides() {
    let bad = vec![
        Request::Close { force: 0 },
        Request::Open { force: 101 },
        Request::Grip { dist: 51 },
        Request::Speed { percent: 0 },
        Request::Speed { percent: 151 },
        Request::Home { axis: 7 },
        Request::Joint {
            joint: 0,
            radians: 0.1,
        },
        Request::Joint {
            joint: 7,
            radians: 0.1,
        },
        Request::Joint {
            joint: 1,
            radians: f32::NAN,
        },
        Request::Jog {
            disp: vec![1.0; 4],
            straight: false,
        },
        Request::Depart {
            disp: vec![],
            straight: false,
        },
        Request::Ma {
            joints: vec![0.0; 7],
        },
        Request::MoveII {
            target: Location::Joint(vec![0.0; 6]),
            straight: false,
        },
        Request::ApproII {
            target: Location::Cart(vec![f32::INFINITY]),
            disp: vec![1.0],
            straight: false,
        },
    ];
    for req in bad {
        assert_eq!(
            req.validate().unwrap_err().code(),
            TROL_ERR_ARG_RANGE,
            "{req:?}"
        );
        // The controller checks the same after decoding.
        let e = Request::decode(&req.encode()).unwrap_err();
        assert_eq!(e.code(), TROL_ERR_ARG_RANGE, "{req:?}: {e}");
    }
    // Fields only the wire can get wrong.
    let cases: Vec<Vec<u8>> = vec![
        vec![TROL_FINISH, 2],
        vec![TROL_GET_POSITION, 3, 0],
        vec![TROL_GET_POSITION, 2, 2],
        vec![TROL_MOVE, 2, b'p', b'1', b' ', b' ', b' ', b' ', b' ', b' '],
        vec![TROL_MOVE, 0, b'1', b'p', b' ', b' ', b' ', b' ', b' ', b' '],
        // MA with the cartesian tag.
        vec![TROL_MA, 0x14, 0, 0, 0, 0],
        // MA with the straight bit.
        vec![TROL_MA, 0x13, 0, 0, 0, 0],
        // ApproII with a non-zero reserved byte.
        vec![TROL_APPRO_II, 0x14, 0x10, 1, 0, 0, 0, 0, 0, 0, 0, 0],
    ];
    for bytes in cases {
        assert_eq!(
            Request::decode(&bytes).unwrap_err().code(),
            TROL_ERR_ARG_RANGE,
            "{bytes:02X?}"
        );
    }
}

#[test]
fn replies_round_trip_and_bad_sizes_are_bad_rsize() {
    let cases = vec![
        (Command::Move, Reply::Code(0)),
        (Command::Finish, Reply::Code(1)),
        (Command::Joint, Reply::Code(-3)),
        (Command::Move, Reply::Code(TROL_ERR_LOCATION)),
        (
            Command::GetPosition,
            Reply::Position(Location::Cart(vec![1.0, 2.0, 3.0, 0.1, 0.2, 0.3])),
        ),
        (
            Command::GetPosition,
            Reply::Position(Location::Prec(vec![1, -2, 3, 4, 5, 6])),
        ),
        (Command::GetPosition, Reply::Code(TROL_ERR_BAD_CSIZE)),
        (
            Command::GetStatus,
            Reply::Status {
                bios_called: true,
                last: -32700,
            },
        ),
        (Command::TerminatePcp, Reply::Code(0)),
    ];
    for (cmd, reply) in cases {
        let bytes = reply.encode();
        assert_eq!(Reply::decode(cmd, &bytes).unwrap(), reply);
        let mut longer = bytes.clone();
        longer.push(0);
        assert_eq!(
            Reply::decode(cmd, &longer).unwrap_err().code(),
            TROL_ERR_BAD_RSIZE
        );
        assert_eq!(
            Reply::decode(cmd, &bytes[..1]).unwrap_err().code(),
            TROL_ERR_BAD_RSIZE
        );
    }
    // A CAT1 reply is one word; a GetStatus value other than 0/1 is not a status.
    assert!(Reply::decode(Command::Move, &[0, 0, 0, 0]).is_err());
    assert!(Reply::decode(Command::GetStatus, &[2, 0, 0, 0]).is_err());
}

fn arb_f32s(max: usize) -> impl Strategy<Value = Vec<f32>> {
    prop::collection::vec(-1.0e4f32..1.0e4, 1..=max)
}

fn arb_target() -> impl Strategy<Value = Location> {
    prop_oneof![
        prop::collection::vec(any::<i32>(), 1..=6).prop_map(Location::Prec),
        arb_f32s(6).prop_map(Location::Cart),
    ]
}

fn arb_request() -> impl Strategy<Value = Request> {
    let name = "[a-zA-Z#][a-zA-Z0-9_]{0,7}".prop_map(|s| LocName::new(&s).unwrap());
    prop_oneof![
        (name.clone(), arb_f32s(6), any::<bool>()).prop_map(|(name, disp, straight)| {
            Request::Appro {
                name,
                disp,
                straight,
            }
        }),
        (arb_target(), arb_f32s(6), any::<bool>()).prop_map(|(target, disp, straight)| {
            Request::ApproII {
                target,
                disp,
                straight,
            }
        }),
        (1u8..=100).prop_map(|force| Request::Close { force }),
        (arb_f32s(6), any::<bool>())
            .prop_map(|(disp, straight)| Request::Depart { disp, straight }),
        (arb_f32s(3), any::<bool>()).prop_map(|(disp, straight)| Request::Jog { disp, straight }),
        (1u8..=6, -10.0f32..10.0).prop_map(|(joint, radians)| Request::Joint { joint, radians }),
        arb_f32s(6).prop_map(|joints| Request::Ma { joints }),
        arb_f32s(6).prop_map(|joints| Request::Mi { joints }),
        (name, any::<bool>()).prop_map(|(name, straight)| Request::Move { name, straight }),
        (arb_target(), any::<bool>())
            .prop_map(|(target, straight)| Request::MoveII { target, straight }),
        arb_f32s(6).prop_map(|tool| Request::SetToolTransform { tool }),
        (1u8..=150).prop_map(|percent| Request::Speed { percent }),
        (0u8..=50).prop_map(|dist| Request::Grip { dist }),
        (0u8..=6).prop_map(|axis| Request::Home { axis }),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn valid_requests_round_trip(req in arb_request()) {
        prop_assert!(req.validate().is_ok());
        let bytes = req.encode();
        prop_assert_eq!(Request::decode(&bytes).unwrap(), req);
    }

    #[test]
    fn any_bytes_decode_to_a_request_or_a_code(bytes in prop::collection::vec(any::<u8>(), 0..64)) {
        match Request::decode(&bytes) {
            Ok(req) => prop_assert_eq!(req.encode(), bytes.clone()),
            Err(e) => prop_assert!([TROL_ERR_UNKNOWN, TROL_ERR_BAD_CSIZE, TROL_ERR_ARG_RANGE].contains(&e.code())),
        }
        for &c in Command::ALL {
            let _ = Reply::decode(c, &bytes);
        }
    }
}

fn hex(s: &str) -> Vec<u8> {
    s.split_whitespace()
        .map(|t| u8::from_str_radix(t, 16).unwrap_or_else(|_| panic!("bad byte {t}")))
        .collect()
}

/// The `trol-record` blocks of docs/protocol.md: `request:` or `reply-to:`/`reply:` bytes and
/// the `decoded:` value they stand for. Each is decoded and compared, then encoded again and
/// compared byte for byte.
#[test]
fn the_record_vectors_of_the_spec_hold() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/protocol.md");
    let doc = std::fs::read_to_string(path).expect("docs/protocol.md");
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
            let r = Request::decode(&bytes).unwrap_or_else(|e| panic!("{req}: {e}"));
            assert_eq!(format!("{r:?}"), decoded);
            assert_eq!(r.encode(), bytes);
            seen.insert(r.command());
        } else {
            let cmd = Command::from_name(&field("reply-to:").expect("reply-to:")).unwrap();
            let bytes = hex(&field("reply:").expect("reply:"));
            let r = Reply::decode(cmd, &bytes).unwrap();
            assert_eq!(format!("{r:?}"), decoded);
            assert_eq!(r.encode(), bytes);
        }
        count += 1;
    }
    assert!(count > 0);
    let missing: Vec<_> = Command::ALL.iter().filter(|c| !seen.contains(c)).collect();
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
    for r in one_of_each() {
        println!(
            "```trol-record\nrequest: {}\ndecoded: {r:?}\n```\n",
            hexs(&r.encode())
        );
    }
}

//! The test vectors of docs/protocol.md, replayed against the sender and the receiver.

use trol_proto::Instant;
use trol_proto::link::{BlockCheck, LinkConfig, Receiver, Sender};

struct Vector {
    name: String,
    message: Vec<u8>,
    pci: u16,
    receiver_only: bool,
    /// The block check: the manual's LRC unless the vector says `bcc: crc16`.
    bcc: BlockCheck,
    result: Option<u16>,
    lines: Vec<(char, Vec<u8>)>,
}

fn bytes(s: &str, message: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    for tok in s.split_whitespace() {
        if let Some(range) = tok.strip_prefix("msg[").and_then(|t| t.strip_suffix(']')) {
            let (a, b) = range.split_once("..").expect("msg[a..b]");
            out.extend_from_slice(
                &message[a.parse::<usize>().unwrap()..b.parse::<usize>().unwrap()],
            );
        } else {
            out.push(u8::from_str_radix(tok, 16).unwrap_or_else(|_| panic!("bad byte {tok}")));
        }
    }
    out
}

fn vectors() -> Vec<Vector> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/protocol.md");
    let doc = std::fs::read_to_string(path).expect("docs/protocol.md");
    let mut out = Vec::new();
    for block in doc.split("```trol-vector").skip(1) {
        let body = block.split("```").next().unwrap();
        let mut v = Vector {
            name: String::new(),
            message: Vec::new(),
            pci: 0,
            receiver_only: false,
            bcc: BlockCheck::Lrc,
            result: None,
            lines: Vec::new(),
        };
        for line in body.lines().map(str::trim).filter(|l| !l.is_empty()) {
            let (key, val) = line.split_once(':').expect("key: value");
            let val = val.trim();
            match key {
                "name" => v.name = val.to_string(),
                "message" if val == "(empty)" => v.message.clear(),
                "message" if val.starts_with("seq ") => {
                    let n: usize = val[4..].parse().unwrap();
                    v.message = (0..n).map(|i| i as u8).collect();
                }
                "message" => v.message = bytes(val, &[]),
                "pci" => v.pci = u16::from_str_radix(val, 16).unwrap(),
                "check" => v.receiver_only = val == "receiver",
                "bcc" => v.bcc = BlockCheck::from_word(val).expect("bcc: lrc or crc16"),
                "result" => {
                    let hex = val
                        .split_whitespace()
                        .last()
                        .unwrap()
                        .trim_start_matches("0x");
                    v.result = Some(u16::from_str_radix(hex, 16).unwrap());
                }
                "S" | "R" => {
                    let b = bytes(val, &v.message);
                    v.lines.push((key.chars().next().unwrap(), b));
                }
                other => panic!("unknown key {other} in vector {}", v.name),
            }
        }
        out.push(v);
    }
    out
}

#[test]
fn the_document_holds_the_vectors() {
    let v = vectors();
    assert!(v.len() >= 7, "found {} vectors", v.len());
    assert!(v.iter().any(|v| v.message.is_empty()));
    assert!(v.iter().any(|v| v.message.len() > 258));
}

#[test]
fn the_receiver_answers_every_vector_byte_for_byte() {
    for v in vectors() {
        let mut r = Receiver::new(LinkConfig {
            check: v.bcc,
            ..LinkConfig::default()
        });
        r.start();
        let now = Instant::ZERO;
        for (who, b) in &v.lines {
            let mut out = Vec::new();
            match who {
                'S' => {
                    r.handle_input(b, now);
                }
                _ => {
                    r.drain_transmit(&mut out);
                    assert_eq!(&out, b, "vector '{}': receiver's answer", v.name);
                }
            }
        }
        let mut rest = Vec::new();
        r.drain_transmit(&mut rest);
        assert!(
            rest.is_empty(),
            "vector '{}': receiver sent more: {rest:02X?}",
            v.name
        );
        match v.result {
            None => {
                let got = r
                    .outcome()
                    .unwrap_or_else(|| panic!("vector '{}' did not end", v.name));
                let got = got.unwrap_or_else(|e| panic!("vector '{}': {e}", v.name));
                assert_eq!(got.data, &v.message[..], "vector '{}'", v.name);
                assert_eq!(got.pci, v.pci, "vector '{}'", v.name);
            }
            Some(code) => {
                let err = r.outcome().and_then(|o| o.err()).expect("a failure");
                assert_eq!(err.code(), code, "vector '{}'", v.name);
            }
        }
    }
}

#[test]
fn the_sender_produces_every_vector_byte_for_byte() {
    for v in vectors().into_iter().filter(|v| !v.receiver_only) {
        let mut s = Sender::new(LinkConfig {
            check: v.bcc,
            ..LinkConfig::default()
        });
        let now = Instant::ZERO;
        s.start(&v.message, v.pci, now).unwrap();
        for (who, b) in &v.lines {
            match who {
                'S' => {
                    let mut out = Vec::new();
                    s.drain_transmit(&mut out);
                    assert_eq!(&out, b, "vector '{}': sender's bytes", v.name);
                }
                _ => {
                    s.handle_input(b, now);
                }
            }
        }
        assert_eq!(s.outcome(), Some(Ok(())), "vector '{}'", v.name);
    }
}

//! include/trol.h agrees with the command table and the code table: a C program compiled
//! against it prints every command code, LAST_CATx_CODE, every TROL code and the constants
//! the table fixes, and the test compares them with the Rust side.

mod common;

use common::cbuild::{Link, compile, program};
use trol_client::code::TROL_CODES;
use trol_client::table::{self, BUILTIN};

/// The header's constant of a command: TROLApproII -> TROL_APPRO_II.
fn constant(name: &str) -> String {
    let bare = name.strip_prefix("TROL").unwrap();
    let mut out = String::from("TROL");
    let mut prev_lower = false;
    for c in bare.chars() {
        if c.is_ascii_uppercase() && prev_lower || out.len() == 4 {
            out.push('_');
        }
        out.push(c.to_ascii_uppercase());
        prev_lower = c.is_ascii_lowercase();
    }
    out
}

#[test]
fn the_header_agrees_with_the_table() {
    let mut expected: Vec<(String, i64)> = Vec::new();
    for def in BUILTIN {
        expected.push((constant(def.name), def.code.into()));
    }
    expected.extend([
        ("LAST_CAT1_CODE".into(), table::LAST_CAT1_CODE.into()),
        ("LAST_CAT2_CODE".into(), table::LAST_CAT2_CODE.into()),
        ("LAST_CAT3_CODE".into(), table::LAST_CAT3_CODE.into()),
        ("LAST_CAT4_CODE".into(), table::LAST_CAT4_CODE.into()),
        ("FINISH_STATUS".into(), table::FINISH_STATUS.into()),
        ("FINISH_WAIT".into(), table::FINISH_WAIT.into()),
        ("POS_COMMANDED".into(), table::POS_COMMANDED.into()),
        ("POS_ACT".into(), table::POS_ACT.into()),
        ("POS_PREC".into(), trol_client::Tag::Prec as i64),
        ("POS_JOINT".into(), trol_client::Tag::Joint as i64),
        ("POS_CART".into(), trol_client::Tag::Cart as i64),
    ]);
    for c in TROL_CODES {
        expected.push((c.name.into(), c.value.into()));
    }
    let mut c = String::from("#include <stdio.h>\n#include \"trol.h\"\nint main(void) {\n");
    for (name, _) in &expected {
        c.push_str(&format!("    printf(\"{name} %ld\\n\", (long)({name}));\n"));
    }
    c.push_str("    return 0;\n}\n");
    let dir = std::env::temp_dir().join(format!("trol-header-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let src = dir.join("codes.c");
    std::fs::write(&src, c).unwrap();
    let exe = compile(&src, "codes", Link::Static);
    let o = program(&exe).output().unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{out}");
    for (name, value) in &expected {
        assert!(
            out.lines().any(|l| l == format!("{name} {value}")),
            "trol.h's {name} is not {value}:\n{out}"
        );
    }
    assert_eq!(constant("TROLApproII"), "TROL_APPRO_II");
    assert_eq!(constant("TROLTerminatePCP"), "TROL_TERMINATE_PCP");
    assert_eq!(constant("TROLMA"), "TROL_MA");
}

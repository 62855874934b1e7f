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
        ("MAX_WAYPOINTS".into(), trol_client::MAX_WAYPOINTS.into()),
        (
            "TRAJECTORY_UNTIMED".into(),
            table::TRAJECTORY_UNTIMED.into(),
        ),
        ("POS_PREC".into(), trol_client::Tag::Prec as i64),
        ("POS_JOINT".into(), trol_client::Tag::Joint as i64),
        ("POS_CART".into(), trol_client::Tag::Cart as i64),
        (
            "TROL_PROTOCOL_VERSION".into(),
            table::PROTOCOL_VERSION.into(),
        ),
    ]);
    for c in TROL_CODES {
        expected.push((c.name.into(), c.value.into()));
    }
    let mut c = String::from("#include <stdio.h>\n#include \"trol.h\"\nint main(void) {\n");
    for (name, _) in &expected {
        c.push_str(&format!("    printf(\"{name} %ld\\n\", (long)({name}));\n"));
    }
    c.push_str("    return 0;\n}\n");
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("trol-header");
    let _ = std::fs::remove_dir_all(&dir);
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

/// The prototype of `name` in trol.h (the line that declares it).
fn prototype(header: &str, name: &str) -> String {
    header
        .lines()
        .find(|l| l.contains(&format!(" {name}(")) && l.trim_end().ends_with(';'))
        .unwrap_or_else(|| panic!("trol.h declares no {name}"))
        .split(';')
        .next()
        .unwrap()
        .trim()
        .to_string()
}

fn tags(tags: &[trol_client::Tag]) -> String {
    let names: Vec<&str> = tags
        .iter()
        .map(|t| match t {
            trol_client::Tag::Cart => "POS_CART",
            trol_client::Tag::Joint => "POS_JOINT",
            trol_client::Tag::Prec => "POS_PREC",
        })
        .collect();
    names.join(" or ")
}

/// One argument in words, with its range, from the command table.
fn argument(a: &trol_client::Arg) -> String {
    use trol_client::ArgKind;
    let what = match a.kind {
        ArgKind::Int { min, max } => format!("a whole number {min}..{max}"),
        ArgKind::Choice(choices) => {
            let c: Vec<String> = choices
                .iter()
                .map(|c| format!("{} ({})", c.constant, c.value))
                .collect();
            format!("one of {}", c.join(", "))
        }
        ArgKind::Straight => "0: joint-interpolated, 1: a straight line".into(),
        ArgKind::Name => "a location name of the controller's table (TLocName)".into(),
        ArgKind::Real => "a real number".into(),
        ArgKind::Loc { tags: t, min, max } => {
            let n = if min == max {
                format!("{min}")
            } else {
                format!("{min}..{max}")
            };
            format!("an SLocData of tag {}, numDims {n}", tags(t))
        }
        ArgKind::Path { max } => format!(
            "1..{max} STrajPoint (a time in seconds from the start, increasing, and six joint \
             angles in radians), with their count"
        ),
    };
    format!("`{}`: {what}", a.name)
}

fn returns(def: &trol_client::CommandDef) -> &'static str {
    use trol_client::ReplyKind;
    match def.reply {
        ReplyKind::Code => {
            "the firmware's return value (0: success; a BIOS code of the controller's \
             table), or a TROL code"
        }
        ReplyKind::Reals { .. } => "0 and the values, or a TROL code",
        ReplyKind::Position => {
            "0 with the position in `*pos` (in the form `pos->tag` asked for), or a \
             TROL code (TROL_ERR_BAD_RSIZE: a reply in another form, `*pos` untouched)"
        }
        ReplyKind::Status => {
            "BIOSCalled (1: the last CAT1/CAT2 command called the firmware, 0: it did not), \
             with lastErrorCode in `*lastBIOSRetVal` (the firmware's value, or the TROL code \
             that kept it from being called), or a TROL code"
        }
        ReplyKind::Version | ReplyKind::Codes | ReplyKind::Gripper => {
            "0 with the reply in the out parameters, or a TROL code (TROL_ERR_UNKNOWN: a \
             controller that does not know the command)"
        }
        ReplyKind::Locations => {
            "0 with up to `max` names and locations in `names` and `locs`, how many there \
             are in `*count`, or a TROL code (TROL_ERR_UNKNOWN: a controller that does not \
             know the command)"
        }
        ReplyKind::Bytes => "the reply's first word; its bytes are the application's",
        _ => "a return value, or a TROL code",
    }
}

/// The generated part of docs/c-api.md: one entry per command of the table, and the TROL
/// codes.
fn c_api_reference(header: &str) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    for def in BUILTIN {
        let added = table::ADDED.contains(&def.code);
        let _ = writeln!(s, "### {}\n", def.name);
        let _ = writeln!(s, "```c\n{};", prototype(header, def.name));
        let per = constant(def.name).to_ascii_lowercase();
        let _ = writeln!(s, "{};\n```\n", prototype(header, &per));
        let _ = writeln!(
            s,
            "{} ({}, code {}{}).\n",
            upper_first(def.help),
            def.class(),
            def.code,
            if added { ", added to the manual's" } else { "" }
        );
        if !def.args.is_empty() {
            for a in def.args {
                let _ = writeln!(s, "- {}", argument(a));
            }
            s.push('\n');
        }
        let _ = writeln!(s, "Returns {}.\n", returns(def));
    }
    let _ = writeln!(s, "### TROL's codes\n");
    let _ = writeln!(s, "| code | value | meaning |\n|---|---|---|");
    for c in TROL_CODES {
        let _ = writeln!(s, "| {} | {} | {} |", c.name, c.value, c.meaning);
    }
    s
}

fn upper_first(text: &str) -> String {
    let mut c = text.chars();
    match c.next() {
        Some(f) => f.to_uppercase().collect::<String>() + c.as_str(),
        None => String::new(),
    }
}

/// docs/c-api.md's reference of the commands is generated from the command table and
/// trol.h's prototypes, so it cannot drift: this test compares it (TROL_BLESS=1 writes it).
#[test]
fn the_c_reference_is_the_tables() {
    let root = common::cbuild::root();
    let header = std::fs::read_to_string(root.join("include/trol.h")).unwrap();
    let path = root.join("docs/c-api.md");
    let doc = std::fs::read_to_string(&path).unwrap();
    let (begin, end) = ("<!-- generated: commands -->\n", "<!-- /generated -->");
    let at = doc.find(begin).expect("docs/c-api.md's generated part") + begin.len();
    let stop = doc[at..].find(end).expect("its end") + at;
    let want = c_api_reference(&header);
    if std::env::var_os("TROL_BLESS").is_some() {
        let new = format!("{}\n{want}\n{}", &doc[..at], &doc[stop..]);
        std::fs::write(&path, new.replace(&format!("{begin}\n"), begin)).unwrap();
        return;
    }
    assert_eq!(
        doc[at..stop].trim(),
        want.trim(),
        "docs/c-api.md's reference is not the table's: run TROL_BLESS=1 cargo test -p \
         trol-c --test header"
    );
}

/// The README's C example compiles as a reader pastes it into a `main`, with every warning
/// an error (`-Wall -Wextra -Werror`; it warned with -Wpointer-sign before the cast), so the
/// README cannot show C that a careful compiler refuses (issue 44, item 4).
#[test]
fn the_readme_c_example_compiles_without_a_warning() {
    let root = common::cbuild::root();
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let start = readme.find("```c\n").expect("a C block in the README") + 5;
    let len = readme[start..].find("```").unwrap();
    let body = &readme[start..start + len];
    assert!(body.contains("trol_connect"), "{body}");
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("trol-readme-c");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let source = dir.join("readme.c");
    std::fs::write(
        &source,
        format!(
            "#include <stdio.h>\n#include \"trol.h\"\n\nint main(void)\n{{\n{body}return 0;\n}}\n"
        ),
    )
    .unwrap();
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let out = std::process::Command::new(&cc)
        .arg("-c")
        .arg(&source)
        .arg("-I")
        .arg(root.join("include"))
        .args(["-std=c99", "-Wall", "-Wextra", "-Werror", "-o"])
        .arg(dir.join("readme.o"))
        .output()
        .expect("run the C compiler (cc)");
    assert!(
        out.status.success(),
        "the README's C example does not compile cleanly:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Every C example (examples/*.c) compiles with every warning an error (`-Wall -Wextra
/// -Werror`): pick.c passed its location's name as a string to the manual's unsigned char
/// name and warned (issue 68, item 4).
#[test]
fn the_c_examples_compile_without_a_warning() {
    let root = common::cbuild::root();
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("trol-examples-c");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let mut seen = 0;
    for entry in std::fs::read_dir(root.join("examples")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "c") {
            continue;
        }
        seen += 1;
        let out = std::process::Command::new(&cc)
            .arg("-c")
            .arg(&path)
            .arg("-I")
            .arg(root.join("include"))
            .args(["-Wall", "-Wextra", "-Werror", "-o"])
            .arg(dir.join("example.o"))
            .output()
            .expect("run the C compiler (cc)");
        assert!(
            out.status.success(),
            "{} does not compile cleanly:\n{}",
            path.display(),
            String::from_utf8_lossy(&out.stderr)
        );
    }
    assert!(seen >= 3, "only {seen} C examples found");
}

//! Command descriptions from a file (`--commands FILE` of the utilities, `add_commands` in
//! Python), so that every surface knows the commands an application added
//! (docs/extending.md).
//!
//! The file is TOML, one `[[command]]` table per command, with the fields of a
//! `CommandDef`:
//!
//! ```toml
//! [[command]]
//! code = 64
//! name = "TROLGetJointSpeeds"
//! help = "the joints' speeds now, rad/s"
//! args = [{ name = "axis", kind = "int", min = 0, max = 6 }]
//! reply = { kind = "reals", min = 1, max = 6 }
//! ```
//!
//! Argument kinds: `int` (min, max), `real`, `name`, `straight`, `loc` (tags: any of
//! "cart", "joint", "prec"; min, max), `path` (max waypoints, 255 at most here), `choice`
//! (choices: word, constant, value). Replies:
//! `code`, `reals` (min, max), `bytes`. `success` lists values besides 0 that count as
//! success; `wait` is `"reply"` (default), `"unlimited"` or a number of seconds more.
//! Descriptions live as long as the process.

use std::path::Path;

use serde::Deserialize;
use trol_proto::application::{Arg, ArgKind, Catalog, Choice, CommandDef, ReplyKind, Tag, Wait};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    command: Vec<Entry>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Entry {
    code: u8,
    name: String,
    #[serde(default)]
    help: String,
    #[serde(default)]
    args: Vec<ArgEntry>,
    #[serde(default)]
    reply: Option<ReplyEntry>,
    #[serde(default)]
    success: Vec<i16>,
    #[serde(default)]
    wait: Option<WaitEntry>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ArgEntry {
    name: String,
    kind: String,
    min: Option<u8>,
    max: Option<u8>,
    #[serde(default)]
    tags: Vec<String>,
    #[serde(default)]
    choices: Vec<ChoiceEntry>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ChoiceEntry {
    word: String,
    constant: String,
    value: u8,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ReplyEntry {
    kind: String,
    min: Option<u8>,
    max: Option<u8>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum WaitEntry {
    Word(String),
    Seconds(u16),
}

fn leak(s: String) -> &'static str {
    Box::leak(s.into_boxed_str())
}

fn arg(e: ArgEntry) -> Result<Arg, String> {
    let range = |what: &str| -> Result<(u8, u8), String> {
        match (e.min, e.max) {
            (Some(a), Some(b)) if a <= b => Ok((a, b)),
            _ => Err(format!("argument `{}`: a {what} needs min <= max", e.name)),
        }
    };
    let kind = match e.kind.as_str() {
        "int" => {
            let (min, max) = range("int")?;
            ArgKind::Int { min, max }
        }
        "real" => ArgKind::Real,
        "name" => ArgKind::Name,
        "straight" => ArgKind::Straight,
        "loc" => {
            let (min, max) = range("loc")?;
            if !(1..=6).contains(&min) || max > 6 {
                return Err(format!("argument `{}`: a loc has 1..6 values", e.name));
            }
            let tags = e
                .tags
                .iter()
                .map(|t| match t.as_str() {
                    "cart" => Ok(Tag::Cart),
                    "joint" => Ok(Tag::Joint),
                    "prec" => Ok(Tag::Prec),
                    other => Err(format!(
                        "argument `{}`: tag `{other}` is none of cart, joint, prec",
                        e.name
                    )),
                })
                .collect::<Result<Vec<Tag>, String>>()?;
            if tags.is_empty() {
                return Err(format!("argument `{}`: a loc needs tags", e.name));
            }
            ArgKind::Loc {
                tags: Box::leak(tags.into_boxed_slice()),
                min,
                max,
            }
        }
        "path" => {
            // A trajectory: `max` waypoints at most (the table's MAX_WAYPOINTS without one).
            let max = e
                .max
                .map_or(trol_proto::application::MAX_WAYPOINTS, u16::from);
            if max == 0 {
                return Err(format!("argument `{}`: a path needs max >= 1", e.name));
            }
            ArgKind::Path { max }
        }
        "choice" => {
            if e.choices.is_empty() {
                return Err(format!("argument `{}`: a choice needs choices", e.name));
            }
            let choices: Vec<Choice> = e
                .choices
                .into_iter()
                .map(|c| Choice {
                    word: leak(c.word),
                    constant: leak(c.constant),
                    value: c.value,
                })
                .collect();
            ArgKind::Choice(Box::leak(choices.into_boxed_slice()))
        }
        other => {
            return Err(format!(
                "argument `{}`: kind `{other}` is none of int, real, name, straight, loc, path, \
                 choice",
                e.name
            ));
        }
    };
    Ok(Arg {
        name: leak(e.name),
        kind,
    })
}

fn def(e: Entry) -> Result<CommandDef, String> {
    let name = e.name.clone();
    let reply = match e.reply {
        None => ReplyKind::Code,
        Some(r) => match r.kind.as_str() {
            "code" => ReplyKind::Code,
            "bytes" => ReplyKind::Bytes,
            "reals" => ReplyKind::Reals {
                min: r.min.unwrap_or(0),
                max: r.max.unwrap_or(u8::MAX),
            },
            other => {
                return Err(format!(
                    "reply kind `{other}` is none of code, reals, bytes"
                ));
            }
        },
    };
    let wait = match e.wait {
        None => Wait::Reply,
        Some(WaitEntry::Word(w)) if w == "reply" => Wait::Reply,
        Some(WaitEntry::Word(w)) if w == "unlimited" => Wait::Unlimited,
        Some(WaitEntry::Word(w)) => {
            return Err(format!(
                "wait `{w}` is none of \"reply\", \"unlimited\" or a number of seconds"
            ));
        }
        Some(WaitEntry::Seconds(s)) => Wait::Extra(s),
    };
    let args = e.args.into_iter().map(arg).collect::<Result<Vec<_>, _>>()?;
    if !name.starts_with("TROL") || name.len() < 5 {
        return Err(format!(
            "name `{name}` must start with TROL, as the API's names do"
        ));
    }
    Ok(CommandDef {
        code: e.code,
        name: leak(e.name),
        args: Box::leak(args.into_boxed_slice()),
        reply,
        success: Box::leak(e.success.into_boxed_slice()),
        wait,
        help: leak(e.help),
    })
}

/// The descriptions in `path`.
pub fn load(path: &Path) -> Result<Vec<CommandDef>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    parse(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// The descriptions in a file's text.
pub fn parse(text: &str) -> Result<Vec<CommandDef>, String> {
    let file: File = toml::from_str(text).map_err(|e| e.to_string())?;
    file.command
        .into_iter()
        .map(|e| {
            let name = e.name.clone();
            def(e).map_err(|why| format!("command {name}: {why}"))
        })
        .collect()
}

/// The built-in catalog with the commands of `path` (if given) added.
pub fn catalog(path: Option<&Path>) -> Result<Catalog, String> {
    let mut c = Catalog::builtin();
    if let Some(p) = path {
        for d in load(p)? {
            let name = d.name;
            c.add(d)
                .map_err(|e| format!("{}: {name}: {e}", p.display()))?;
        }
    }
    Ok(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_described_command_joins_the_catalog_and_bad_files_say_why() {
        let defs = parse(
            r#"
[[command]]
code = 64
name = "TROLGetJointSpeeds"
help = "the joints' speeds"
args = [{ name = "axis", kind = "int", min = 0, max = 6 },
        { name = "pTarget", kind = "loc", tags = ["cart", "prec"], min = 1, max = 6 },
        { name = "mode", kind = "choice", choices = [{ word = "fast", constant = "FAST", value = 1 }] }]
reply = { kind = "reals", min = 1, max = 6 }
wait = 10
"#,
        )
        .unwrap();
        assert_eq!(defs[0].code, 64);
        assert_eq!(defs[0].args.len(), 3);
        assert_eq!(defs[0].reply, ReplyKind::Reals { min: 1, max: 6 });
        assert_eq!(defs[0].wait, Wait::Extra(10));
        for (bad, says) in [
            (
                "[[command]]\ncode = 64\nname = \"X\"",
                "must start with TROL",
            ),
            ("[[command]]\ncode = 300\nname = \"TROLX\"", "300"),
            (
                "[[command]]\ncode = 64\nname = \"TROLX\"\nargs = [{ name = \"a\", kind = \"float\" }]",
                "kind `float`",
            ),
            (
                "[[command]]\ncode = 64\nname = \"TROLX\"\ncolour = 1",
                "colour",
            ),
        ] {
            let e = parse(bad).unwrap_err();
            assert!(e.contains(says), "{bad}: {e}");
        }
    }
}

//! The interpreter's commands: every command of the catalog (the built-in table and any
//! described in a `--commands` file), named as in the manual (with or without the TROL
//! prefix, any case), with the arguments and ranges of its description; and the parser from
//! tokens to a call. Nothing here is written per command.

use trol::code::TROL_ERR_ARG_RANGE;
use trol_proto::application::record::literal_prefix;
use trol_proto::application::{ArgKind, Catalog, CommandDef, LocName, Location, Tag, Value};

use super::scanner::{Kind, SyntaxError, Token};

/// How `help` writes an argument.
pub fn arg_usage(name: &str, kind: &ArgKind) -> String {
    match kind {
        ArgKind::Int { min, max } => format!("{name}:{min}..{max}"),
        ArgKind::Real => format!("{name}:real"),
        ArgKind::Name => format!("{name}:NAME"),
        ArgKind::Loc { tags, min, max } => {
            let kinds: Vec<&str> = tags.iter().map(|t| literal_prefix(*t)).collect();
            let n = if min == max {
                format!("{min}")
            } else {
                format!("{min}..{max}")
            };
            format!("{name}:{}({n} values)", kinds.join("|"))
        }
        ArgKind::Straight => "[straight:0|1]".into(),
        ArgKind::Path { max } => format!("{name}:w(t, 6 joints) ... (1..{max} waypoints)"),
        ArgKind::Choice(options) => {
            let words: Vec<&str> = options.iter().map(|c| c.word).collect();
            format!("[{name}:{}]", words.join("|"))
        }
    }
}

/// The words one argument takes (its choices, the straight flag; a location's literal
/// forms), for completion.
pub fn words_for(kind: &ArgKind) -> Vec<&'static str> {
    match kind {
        ArgKind::Choice(options) => options.iter().map(|c| c.word).collect(),
        ArgKind::Straight => vec!["straight", "interpolated"],
        ArgKind::Loc { tags, .. } => tags
            .iter()
            .map(|t| match t {
                Tag::Cart => "c(",
                Tag::Joint => "j(",
                Tag::Prec => "p(",
            })
            .collect(),
        ArgKind::Path { .. } => vec!["w("],
        _ => Vec::new(),
    }
}

/// The interpreter's own commands.
pub const OWN: &[(&str, &str, &str)] = &[
    ("help", "[COMMAND]", "list the commands, or explain one"),
    (
        "delay",
        "ms:0..600000",
        "wait (the manual's delay(), e.g. for the gripper)",
    ),
    (
        "init",
        "",
        "activate the controller's TROL server (as trol init), with trol.cfg's tool",
    ),
    (
        "reconnect",
        "",
        "open the port again and check the server (after the controller restarted)",
    ),
    ("quit", "", "leave the interpreter (also exit, or Ctrl-D)"),
];

/// What a line asks for.
#[derive(Debug, PartialEq)]
pub enum Action {
    /// Nothing (a blank or comment line).
    Nothing,
    /// An API call: the command and its arguments.
    Call(CommandDef, Vec<Value>),
    /// help [command].
    Help(Option<String>),
    /// delay ms.
    Delay(u64),
    /// quit.
    Quit,
    /// init: activate the controller.
    Init,
    /// reconnect: open the port again.
    Reconnect,
}

fn kind_word(tag: Tag) -> &'static str {
    match tag {
        Tag::Cart => "cartesian",
        Tag::Joint => "joint",
        Tag::Prec => "precision-point",
    }
}

fn literal_tag(word: &str) -> Option<Tag> {
    match word.to_ascii_lowercase().as_str() {
        "c" | "cart" => Some(Tag::Cart),
        "j" | "joint" => Some(Tag::Joint),
        "p" | "prec" => Some(Tag::Prec),
        _ => None,
    }
}

/// The usage line of a command.
pub fn usage(def: &CommandDef) -> String {
    let mut s = def.short_name().to_string();
    for a in def.args {
        s.push(' ');
        s.push_str(&arg_usage(a.name, &a.kind));
    }
    s
}

/// Parse one line against the commands of `catalog`.
pub fn parse(tokens: &[Token], line_len: usize, catalog: &Catalog) -> Result<Action, SyntaxError> {
    let Some(first) = tokens.first() else {
        return Ok(Action::Nothing);
    };
    let Kind::Word(word) = &first.kind else {
        return Err(SyntaxError::at(
            first,
            "expected a command name at the start of the line (`help` lists them)",
        ));
    };
    let mut cur = Cursor {
        tokens,
        pos: 1,
        end_col: line_len + 1,
    };
    let lower = word.to_ascii_lowercase();
    match lower.as_str() {
        "help" | "?" => {
            let topic = match cur.next() {
                Some(Token {
                    kind: Kind::Word(w),
                    ..
                }) => Some(w.clone()),
                Some(t) => return Err(SyntaxError::at(t, "expected a command name after help")),
                None => None,
            };
            cur.finish("help")?;
            return Ok(Action::Help(topic));
        }
        "quit" | "exit" => {
            cur.finish(&lower)?;
            return Ok(Action::Quit);
        }
        "init" => {
            cur.finish("init")?;
            return Ok(Action::Init);
        }
        "reconnect" => {
            cur.finish("reconnect")?;
            return Ok(Action::Reconnect);
        }
        "delay" => {
            let ms = cur.int("ms", 0, 600_000, "delay")?;
            cur.finish("delay")?;
            return Ok(Action::Delay(ms as u64));
        }
        _ => {}
    }
    let Some(def) = catalog.find(word).copied() else {
        let hint = did_you_mean(catalog, &lower);
        return Err(SyntaxError::at(
            first,
            format!("unknown command `{word}`{hint} (`help` lists the commands)"),
        ));
    };
    let name = def.short_name();
    let mut values = Vec::new();
    for a in def.args {
        values.push(cur.arg(a.name, &a.kind, name)?);
    }
    cur.finish(name)?;
    Ok(Action::Call(def, values))
}

/// "; did you mean `Home`?" for a command name `word` (lower case, with or without `trol`)
/// within two edits of one of the catalog's or the interpreter's own, else nothing.
pub fn did_you_mean(catalog: &Catalog, word: &str) -> String {
    let mut names: Vec<&str> = catalog.iter().map(|d| d.short_name()).collect();
    names.extend(OWN.iter().map(|o| o.0));
    let bare = word.strip_prefix("trol").unwrap_or(word);
    names
        .iter()
        .map(|n| (strsim::levenshtein(&n.to_ascii_lowercase(), bare), n))
        .filter(|(d, _)| *d <= 2)
        .min_by_key(|(d, _)| *d)
        .map(|(_, n)| format!("; did you mean `{n}`?"))
        .unwrap_or_default()
}

struct Cursor<'a> {
    tokens: &'a [Token],
    pos: usize,
    end_col: usize,
}

impl<'a> Cursor<'a> {
    fn next(&mut self) -> Option<&'a Token> {
        let t = self.tokens.get(self.pos);
        if t.is_some() {
            self.pos += 1;
        }
        t
    }

    fn peek(&self) -> Option<&'a Token> {
        self.tokens.get(self.pos)
    }

    fn missing(&self, what: String) -> SyntaxError {
        SyntaxError {
            col: self.end_col,
            width: 1,
            message: what,
        }
    }

    fn finish(&self, command: &str) -> Result<(), SyntaxError> {
        match self.peek() {
            None => Ok(()),
            Some(t) => Err(SyntaxError::at(
                t,
                format!(
                    "unexpected `{}`: {command} takes no more arguments (`help {command}`)",
                    t.text
                ),
            )),
        }
    }

    fn int(&mut self, name: &str, min: i64, max: i64, command: &str) -> Result<i64, SyntaxError> {
        let want = format!("`{name}`, a whole number {min}..{max}");
        let Some(t) = self.next() else {
            return Err(self.missing(format!("expected {want} after `{command}`")));
        };
        match t.kind {
            Kind::Number(v) if v.fract() == 0.0 => {
                if (min as f64..=max as f64).contains(&v) {
                    Ok(v as i64)
                } else {
                    Err(SyntaxError::at(
                        t,
                        format!(
                            "`{name}` {} is out of range {min}..{max} (TROL_ERR_ARG_RANGE, {})",
                            t.text, TROL_ERR_ARG_RANGE.0
                        ),
                    ))
                }
            }
            _ => Err(SyntaxError::at(
                t,
                format!("expected {want}, found `{}`", t.text),
            )),
        }
    }

    fn arg(&mut self, name: &str, kind: &ArgKind, command: &str) -> Result<Value, SyntaxError> {
        match *kind {
            ArgKind::Int { min, max } => self
                .int(name, min.into(), max.into(), command)
                .map(|v| Value::Int(v as u8)),
            ArgKind::Real => match self.next() {
                Some(Token {
                    kind: Kind::Number(v),
                    ..
                }) => Ok(Value::Real(*v)),
                Some(t) => Err(SyntaxError::at(
                    t,
                    format!("expected `{name}`, a number, found `{}`", t.text),
                )),
                None => Err(self.missing(format!("expected `{name}`, a number"))),
            },
            ArgKind::Name => match self.next() {
                Some(
                    t @ Token {
                        kind: Kind::Word(w),
                        ..
                    },
                ) => {
                    if literal_tag(w).is_some()
                        && matches!(self.peek().map(|t| &t.kind), Some(Kind::Open))
                    {
                        return Err(SyntaxError::at(
                            t,
                            format!(
                                "{command} takes a location name; for a location given by its \
                                 values use {command}II"
                            ),
                        ));
                    }
                    LocName::new(w).map(Value::Name).map_err(|e| {
                        SyntaxError::at(
                            t,
                            format!(
                                "`{w}` is not a location name ({e}): up to 8 characters, the \
                                 first a letter or '#', the rest letters, digits or '_'"
                            ),
                        )
                    })
                }
                Some(t) => Err(SyntaxError::at(
                    t,
                    format!("expected a location name, found `{}`", t.text),
                )),
                None => Err(self.missing(format!("expected a location name after `{command}`"))),
            },
            ArgKind::Loc { tags, min, max } => {
                let bare = tags.first().copied().unwrap_or(Tag::Cart);
                self.location(name, tags, bare, min.into(), max.into(), command)
            }
            ArgKind::Path { max } => self.path(name, usize::from(max), command),
            ArgKind::Straight => match self.peek() {
                None => Ok(Value::Flag(false)),
                Some(t) => {
                    let v = match &t.kind {
                        Kind::Number(v) if *v == 0.0 => false,
                        Kind::Number(v) if *v == 1.0 => true,
                        Kind::Word(w) if w.eq_ignore_ascii_case("straight") => true,
                        Kind::Word(w) if w.eq_ignore_ascii_case("interpolated") => false,
                        _ => {
                            return Err(SyntaxError::at(
                                t,
                                format!(
                                    "expected the straight flag (0 or interpolated, 1 or \
                                     straight), found `{}`",
                                    t.text
                                ),
                            ));
                        }
                    };
                    self.pos += 1;
                    Ok(Value::Flag(v))
                }
            },
            ArgKind::Choice(options) => match (self.peek(), options.first()) {
                (None, Some(default)) => Ok(Value::Int(default.value)),
                (None, None) => Err(self.missing(format!("`{name}` has no words to choose"))),
                (Some(t), _) => {
                    let found = match &t.kind {
                        Kind::Word(w) => options.iter().find(|c| {
                            w.eq_ignore_ascii_case(c.word) || w.eq_ignore_ascii_case(c.constant)
                        }),
                        _ => None,
                    };
                    match found {
                        Some(c) => {
                            self.pos += 1;
                            Ok(Value::Int(c.value))
                        }
                        None => {
                            let words: Vec<String> = options
                                .iter()
                                .map(|c| format!("{} ({})", c.word, c.constant))
                                .collect();
                            Err(SyntaxError::at(
                                t,
                                format!(
                                    "expected `{name}`: one of {}, found `{}`",
                                    words.join(", "),
                                    t.text
                                ),
                            ))
                        }
                    }
                }
            },
        }
    }

    /// A trajectory: one or more `w(t, q1, q2, q3, q4, q5, q6)`, up to the end of the line.
    fn path(&mut self, name: &str, max: usize, command: &str) -> Result<Value, SyntaxError> {
        let want = format!(
            "`{name}`: waypoints w(t, q1, q2, q3, q4, q5, q6), seconds from the start and \
             six joint angles in radians"
        );
        let mut points = Vec::new();
        while let Some(start) = self.next() {
            match &start.kind {
                Kind::Word(w) if w.eq_ignore_ascii_case("w") => {}
                _ => {
                    return Err(SyntaxError::at(
                        start,
                        format!("expected {want}, found `{}`", start.text),
                    ));
                }
            }
            match self.next() {
                Some(Token {
                    kind: Kind::Open, ..
                }) => {}
                Some(t) => return Err(SyntaxError::at(t, "expected `(` after `w`")),
                None => return Err(self.missing("expected `(` after `w`".into())),
            }
            let values = self.numbers(
                start,
                "waypoint",
                7,
                "too many values: a waypoint is its time and six joint angles",
                |_| None,
            )?;
            if values.len() != 7 {
                return Err(SyntaxError::at(
                    start,
                    format!(
                        "a waypoint is its time and six joint angles: {} values given",
                        values.len()
                    ),
                ));
            }
            if points.len() == max {
                return Err(SyntaxError::at(
                    start,
                    format!("too many waypoints: `{name}` takes at most {max}"),
                ));
            }
            points.push(trol_proto::application::Waypoint {
                time: values[0],
                joints: std::array::from_fn(|j| values[j + 1]),
            });
        }
        if points.is_empty() {
            return Err(self.missing(format!("expected {want} after `{command}`")));
        }
        Ok(Value::Path(points))
    }

    /// The numbers of a literal whose `(` has been read (at `start`), up to its `)`: at most
    /// `max` (`too_many` says so at the first beyond), each checked by `bad` at its token;
    /// `what` names the literal where its `)` is missing.
    fn numbers(
        &mut self,
        start: &Token,
        what: &str,
        max: usize,
        too_many: &str,
        bad: impl Fn(f64) -> Option<&'static str>,
    ) -> Result<Vec<f64>, SyntaxError> {
        let mut values = Vec::new();
        let mut want_value = true;
        loop {
            let Some(t) = self.next() else {
                return Err(self.missing(format!(
                    "expected `)` to close the {what} begun at column {}",
                    start.col
                )));
            };
            match &t.kind {
                Kind::Close => return Ok(values),
                Kind::Comma if !want_value => want_value = true,
                Kind::Number(v) => {
                    if values.len() == max {
                        return Err(SyntaxError::at(t, too_many));
                    }
                    if let Some(why) = bad(*v) {
                        return Err(SyntaxError::at(t, why));
                    }
                    values.push(*v);
                    want_value = false;
                }
                _ => {
                    return Err(SyntaxError::at(
                        t,
                        format!("expected a number or `)`, found `{}`", t.text),
                    ));
                }
            }
        }
    }

    fn location(
        &mut self,
        name: &str,
        tags: &[Tag],
        bare: Tag,
        min: usize,
        max: usize,
        command: &str,
    ) -> Result<Value, SyntaxError> {
        let kinds: Vec<String> = tags
            .iter()
            .map(|t| format!("{}(...)", literal_prefix(*t)))
            .collect();
        let want = format!(
            "`{name}`: a location literal {} with {} values, or ( ... )",
            kinds.join(" or "),
            if min == max {
                format!("{min}")
            } else {
                format!("{min}..{max}")
            }
        );
        let Some(start) = self.next() else {
            return Err(self.missing(format!("expected {want} after `{command}`")));
        };
        let tag = match &start.kind {
            Kind::Open => bare,
            Kind::Word(w) => {
                let Some(tag) = literal_tag(w) else {
                    return Err(SyntaxError::at(
                        start,
                        format!("expected {want}, found `{}`", start.text),
                    ));
                };
                match self.next() {
                    Some(Token {
                        kind: Kind::Open, ..
                    }) => {}
                    Some(t) => {
                        return Err(SyntaxError::at(
                            t,
                            format!("expected `(` after `{}`", start.text),
                        ));
                    }
                    None => {
                        return Err(self.missing(format!("expected `(` after `{}`", start.text)));
                    }
                }
                if !tags.contains(&tag) {
                    return Err(SyntaxError::at(
                        start,
                        format!(
                            "{command} takes {} here, not a {} location",
                            kinds.join(" or "),
                            kind_word(tag)
                        ),
                    ));
                }
                tag
            }
            _ => {
                return Err(SyntaxError::at(
                    start,
                    format!("expected {want}, found `{}`", start.text),
                ));
            }
        };
        let too_many = format!("too many values: `{name}` takes at most {max}");
        let values = self.numbers(start, "location", max, &too_many, |v| {
            (tag == Tag::Prec && v.fract() != 0.0)
                .then_some("a precision point holds whole encoder counts")
        })?;
        if values.len() < min {
            let last = &self.tokens[self.pos - 1];
            return Err(SyntaxError::at(
                last,
                format!(
                    "`{name}` needs {min}{} values, {} given",
                    if max > min {
                        format!("..{max}")
                    } else {
                        String::new()
                    },
                    values.len()
                ),
            ));
        }
        let loc = match tag {
            Tag::Cart => Location::Cart(values),
            Tag::Joint => Location::Joint(values),
            Tag::Prec => {
                let mut counts = Vec::new();
                for (v, t) in values.iter().zip(&self.tokens[self.pos - values.len()..]) {
                    if *v < i32::MIN as f64 || *v > i32::MAX as f64 {
                        return Err(SyntaxError::at(t, "an encoder count out of 32-bit range"));
                    }
                    counts.push(*v as i32);
                }
                Location::Prec(counts)
            }
        };
        Ok(Value::Loc(loc))
    }
}

#[cfg(test)]
mod tests {
    use super::super::scanner::scan;
    use super::*;
    use trol_proto::application::record::{format_call, format_location};
    use trol_proto::application::table::*;

    fn p(line: &str) -> Result<Action, SyntaxError> {
        parse(
            &scan(line).unwrap(),
            line.chars().count(),
            &Catalog::builtin(),
        )
    }

    fn call(def: CommandDef, values: Vec<Value>) -> Action {
        Action::Call(def, values)
    }

    #[test]
    fn every_command_parses_with_or_without_the_prefix() {
        assert_eq!(p("TROLHome 0").unwrap(), call(HOME, vec![Value::Int(0)]));
        assert_eq!(p("home 3").unwrap(), p("trolHOME 3").unwrap());
        assert_eq!(
            p("appro test_001 c(-90) straight").unwrap(),
            call(
                APPRO,
                vec![
                    Value::Name(LocName::new("test_001").unwrap()),
                    Value::Loc(Location::Cart(vec![-90.0])),
                    Value::Flag(true)
                ]
            )
        );
        assert_eq!(
            p("moveii p(1, 2, 3, 4, 5, 6)").unwrap(),
            call(
                MOVE_II,
                vec![
                    Value::Loc(Location::Prec(vec![1, 2, 3, 4, 5, 6])),
                    Value::Flag(false)
                ]
            )
        );
        assert_eq!(
            p("ma (0.1 0.2)").unwrap(),
            call(MA, vec![Value::Loc(Location::Joint(vec![0.1, 0.2]))])
        );
        assert_eq!(
            p("getposition joint actual").unwrap(),
            call(
                GET_POSITION,
                vec![Value::Int(Tag::Joint as u8), Value::Int(POS_ACT)]
            )
        );
        assert_eq!(
            p("finish").unwrap(),
            call(FINISH, vec![Value::Int(FINISH_WAIT)])
        );
        assert_eq!(
            p("finish FINISH_STATUS").unwrap(),
            call(FINISH, vec![Value::Int(FINISH_STATUS)])
        );
        assert_eq!(p("; only a comment").unwrap(), Action::Nothing);
    }

    #[test]
    fn what_the_trace_prints_parses_back_to_the_same_call() {
        for line in [
            "TROLAppro test_001 c(-90) straight",
            "TROLApproII p(1000, -2000, 3000, 0, 5, -6) c(-50, 0, 10)",
            "TROLJoint 1 0.5",
            "TROLGetPosition prec commanded",
            "TROLMoveII c(400.123, 0, 300, 0, 1.5, 0) straight",
        ] {
            let Action::Call(def, values) = p(line).unwrap() else {
                panic!("{line}")
            };
            assert_eq!(format_call(&def, &values), line);
        }
    }

    #[test]
    fn errors_point_at_the_column_and_say_what_was_expected() {
        let e = p("close 200").unwrap_err();
        assert_eq!(e.col, 7);
        assert!(e.message.contains("out of range 1..100"), "{}", e.message);
        assert!(e.message.contains("TROL_ERR_ARG_RANGE"), "{}", e.message);
        let e = p("home").unwrap_err();
        assert_eq!(e.col, 5);
        assert!(e.message.contains("`axis`"), "{}", e.message);
        let e = p("fly 3").unwrap_err();
        assert_eq!(e.col, 1);
        assert!(e.message.contains("unknown command `fly`"));
        let e = p("jog c(1, 2, 3, 4) 1").unwrap_err();
        assert!(e.message.contains("at most 3"), "{}", e.message);
        let e = p("moveii c(1, 2, 3").unwrap_err();
        assert!(e.message.contains("expected `)`"), "{}", e.message);
        assert_eq!(e.col, 17);
        let e = p("moveii c(1, 2, 3, 4, 5, 6 1").unwrap_err();
        assert!(e.message.contains("at most 6"), "{}", e.message);
        let e = p("ma c(1)").unwrap_err();
        assert!(
            e.message.contains("not a cartesian location"),
            "{}",
            e.message
        );
        let e = p("halt now").unwrap_err();
        assert_eq!(e.col, 6);
        let e = p("move toolongname").unwrap_err();
        assert!(e.message.contains("not a location name"), "{}", e.message);
        let e = p("moveii p(1.5, 0, 0, 0, 0, 0)").unwrap_err();
        assert_eq!(e.col, 10);
        let e = p("finish later").unwrap_err();
        assert!(e.message.contains("wait (FINISH_WAIT)"), "{}", e.message);
    }

    #[test]
    fn locations_print_as_literals_that_parse_back() {
        let loc = Location::Cart(vec![400.0, 0.0, 150.0, 0.0, 1.25, 0.0]);
        let line = format!("moveii {}", format_location(&loc));
        match p(&line).unwrap() {
            Action::Call(_, values) => assert_eq!(values[0], Value::Loc(loc)),
            other => panic!("{other:?}"),
        }
    }
}

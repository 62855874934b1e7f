//! The interpreter's commands: one per API function (named as in the manual, with or without
//! the TROL prefix, any case), their arguments with ranges, and the parser from tokens to a
//! request.

use trol::Command;
use trol::errors::TROL_ERR_ARG_RANGE;
use trol_proto::application::request::Request;
use trol_proto::application::{FinishMode, LocName, Location, PosMode, Tag};

use super::scanner::{Kind, SyntaxError, Token};

/// One argument of a command.
#[derive(Clone, Copy, Debug)]
pub enum Param {
    /// A whole number in a range.
    Int {
        name: &'static str,
        min: i64,
        max: i64,
    },
    /// A real number.
    Real { name: &'static str },
    /// A location name in the controller's table.
    Name,
    /// A location literal of one of `tags` with `min..=max` values; a bare `( ... )` is
    /// `bare`.
    Loc {
        name: &'static str,
        tags: &'static [Tag],
        bare: Tag,
        min: usize,
        max: usize,
    },
    /// The optional straight flag: 0/1, `straight` or `interpolated` (default 0).
    Straight,
    /// One word of a list (optional; the first is the default).
    Choice {
        name: &'static str,
        options: &'static [(&'static str, &'static str)],
    },
}

impl Param {
    /// How `help` writes it.
    pub fn usage(&self) -> String {
        match self {
            Param::Int { name, min, max } => format!("{name}:{min}..{max}"),
            Param::Real { name } => format!("{name}:real"),
            Param::Name => "NAME".into(),
            Param::Loc {
                name,
                tags,
                min,
                max,
                ..
            } => {
                let kinds: Vec<&str> = tags.iter().map(|t| literal_prefix(*t)).collect();
                let n = if min == max {
                    format!("{min}")
                } else {
                    format!("{min}..{max}")
                };
                format!("{name}:{}({n} values)", kinds.join("|"))
            }
            Param::Straight => "[straight:0|1]".into(),
            Param::Choice { name, options } => {
                let words: Vec<&str> = options.iter().map(|(w, _)| *w).collect();
                format!("[{name}:{}]", words.join("|"))
            }
        }
    }
}

/// A command of the interpreter.
#[derive(Clone, Copy, Debug)]
pub struct Spec {
    pub command: Command,
    pub params: &'static [Param],
    pub summary: &'static str,
}

const CART: &[Tag] = &[Tag::Cart];
const JOINT: &[Tag] = &[Tag::Joint];
const TARGET: &[Tag] = &[Tag::Cart, Tag::Prec];
const DISP: Param = Param::Loc {
    name: "disp",
    tags: CART,
    bare: Tag::Cart,
    min: 1,
    max: 6,
};
const FORCE: Param = Param::Int {
    name: "force",
    min: 1,
    max: 100,
};

/// Every API command, in code order.
pub const SPECS: &[Spec] = &[
    Spec {
        command: Command::Appro,
        params: &[Param::Name, DISP, Param::Straight],
        summary: "approach a named location, displaced in its tool frame (mm, rad)",
    },
    Spec {
        command: Command::ApproII,
        params: &[
            Param::Loc {
                name: "target",
                tags: TARGET,
                bare: Tag::Cart,
                min: 6,
                max: 6,
            },
            DISP,
            Param::Straight,
        ],
        summary: "approach a given location (cartesian or precision point)",
    },
    Spec {
        command: Command::Close,
        params: &[FORCE],
        summary: "close the gripper with a percentage of the maximum force",
    },
    Spec {
        command: Command::Depart,
        params: &[DISP, Param::Straight],
        summary: "move away from here, displaced in the tool frame",
    },
    Spec {
        command: Command::Finish,
        params: &[Param::Choice {
            name: "mode",
            options: &[("wait", "FINISH_WAIT"), ("status", "FINISH_STATUS")],
        }],
        summary: "wait until the arm and gripper stop (wait), or ask (status: 1 moving, 0 done)",
    },
    Spec {
        command: Command::Grip,
        params: &[Param::Int {
            name: "dist",
            min: 0,
            max: 50,
        }],
        summary: "set the finger distance in mm, at full force",
    },
    Spec {
        command: Command::Halt,
        params: &[],
        summary: "stop all motion",
    },
    Spec {
        command: Command::Home,
        params: &[Param::Int {
            name: "axis",
            min: 0,
            max: 6,
        }],
        summary: "home one axis (1..6) or all (0); needed before any motion",
    },
    Spec {
        command: Command::Jog,
        params: &[
            Param::Loc {
                name: "delta",
                tags: CART,
                bare: Tag::Cart,
                min: 1,
                max: 3,
            },
            Param::Straight,
        ],
        summary: "move the tool by dx [dy [dz]] mm in the world frame, orientation kept",
    },
    Spec {
        command: Command::Joint,
        params: &[
            Param::Int {
                name: "joint",
                min: 1,
                max: 6,
            },
            Param::Real { name: "radians" },
        ],
        summary: "move one joint by an increment in radians",
    },
    Spec {
        command: Command::Ma,
        params: &[Param::Loc {
            name: "joints",
            tags: JOINT,
            bare: Tag::Joint,
            min: 1,
            max: 6,
        }],
        summary: "move all joints to absolute angles (radians)",
    },
    Spec {
        command: Command::Mi,
        params: &[Param::Loc {
            name: "joints",
            tags: JOINT,
            bare: Tag::Joint,
            min: 1,
            max: 6,
        }],
        summary: "move all joints by increments (radians)",
    },
    Spec {
        command: Command::Move,
        params: &[Param::Name, Param::Straight],
        summary: "move to a named location of the controller's table",
    },
    Spec {
        command: Command::MoveII,
        params: &[
            Param::Loc {
                name: "target",
                tags: TARGET,
                bare: Tag::Cart,
                min: 6,
                max: 6,
            },
            Param::Straight,
        ],
        summary: "move to a given location (cartesian or precision point)",
    },
    Spec {
        command: Command::Open,
        params: &[FORCE],
        summary: "open the gripper with a percentage of the maximum force",
    },
    Spec {
        command: Command::Ready,
        params: &[],
        summary: "move to the READY pose",
    },
    Spec {
        command: Command::SetToolTransform,
        params: &[Param::Loc {
            name: "tool",
            tags: CART,
            bare: Tag::Cart,
            min: 1,
            max: 6,
        }],
        summary: "set where the tool tip is in the tool frame (x y z mm, yaw pitch roll rad)",
    },
    Spec {
        command: Command::Speed,
        params: &[Param::Int {
            name: "percent",
            min: 1,
            max: 150,
        }],
        summary: "set the speed of the following motions, percent of the maximum",
    },
    Spec {
        command: Command::GetPosition,
        params: &[
            Param::Choice {
                name: "form",
                options: &[
                    ("cart", "POS_CART"),
                    ("joint", "POS_JOINT"),
                    ("prec", "POS_PREC"),
                ],
            },
            Param::Choice {
                name: "mode",
                options: &[("commanded", "POS_COMMANDED"), ("actual", "POS_ACT")],
            },
        ],
        summary: "read the position: cartesian, joint or precision point; commanded or actual",
    },
    Spec {
        command: Command::TerminatePcp,
        params: &[],
        summary: "end the controller's TROL server (back to terminal mode)",
    },
    Spec {
        command: Command::GetStatus,
        params: &[],
        summary: "whether the last command called the BIOS, and its return value",
    },
];

/// The interpreter's own commands.
pub const OWN: &[(&str, &str, &str)] = &[
    ("help", "[COMMAND]", "list the commands, or explain one"),
    (
        "delay",
        "ms:0..600000",
        "wait (the manual's delay(), e.g. for the gripper)",
    ),
    ("quit", "", "leave the interpreter (also exit, or Ctrl-D)"),
];

/// What a line asks for.
#[derive(Debug, PartialEq)]
pub enum Action {
    /// Nothing (a blank or comment line).
    Nothing,
    /// An API call.
    Call(Request),
    /// help [command].
    Help(Option<String>),
    /// delay ms.
    Delay(u64),
    /// quit.
    Quit,
}

/// The spec of a command name (any case, with or without TROL).
pub fn find(name: &str) -> Option<&'static Spec> {
    let c = Command::from_name(name)?;
    SPECS.iter().find(|s| s.command == c)
}

fn literal_prefix(tag: Tag) -> &'static str {
    match tag {
        Tag::Cart => "c",
        Tag::Joint => "j",
        Tag::Prec => "p",
    }
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
pub fn usage(spec: &Spec) -> String {
    let mut s = spec.command.short_name().to_string();
    for p in spec.params {
        s.push(' ');
        s.push_str(&p.usage());
    }
    s
}

/// Parse one line.
pub fn parse(tokens: &[Token], line_len: usize) -> Result<Action, SyntaxError> {
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
        "delay" => {
            let ms = cur.int("ms", 0, 600_000, "delay")?;
            cur.finish("delay")?;
            return Ok(Action::Delay(ms as u64));
        }
        _ => {}
    }
    let Some(spec) = find(word) else {
        let mut names: Vec<&str> = SPECS.iter().map(|s| s.command.short_name()).collect();
        names.extend(OWN.iter().map(|o| o.0));
        let bare = lower.strip_prefix("trol").unwrap_or(&lower);
        let hint = names
            .iter()
            .map(|n| (edit_distance(&n.to_ascii_lowercase(), bare), n))
            .filter(|(d, _)| *d <= 2)
            .min_by_key(|(d, _)| *d)
            .map(|(_, n)| format!("; did you mean `{n}`?"))
            .unwrap_or_default();
        return Err(SyntaxError::at(
            first,
            format!("unknown command `{word}`{hint} (`help` lists the commands)"),
        ));
    };
    let name = spec.command.short_name();
    let mut values = Vec::new();
    for p in spec.params {
        values.push(cur.param(p, spec)?);
    }
    cur.finish(name)?;
    build(spec, values).map(Action::Call)
}

/// Levenshtein distance, for "did you mean".
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for j in 0..b.len() {
            let cur = row[j + 1];
            row[j + 1] = (prev + usize::from(ca != b[j]))
                .min(row[j] + 1)
                .min(cur + 1);
            prev = cur;
        }
    }
    row[b.len()]
}

/// A parsed argument.
#[derive(Debug)]
enum Value {
    Int(i64),
    Real(f64),
    Name(LocName),
    Loc(Location),
    Flag(bool),
    Choice(usize),
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
                            t.text, TROL_ERR_ARG_RANGE
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

    fn param(&mut self, p: &Param, spec: &Spec) -> Result<Value, SyntaxError> {
        let command = spec.command.short_name();
        match *p {
            Param::Int { name, min, max } => self.int(name, min, max, command).map(Value::Int),
            Param::Real { name } => match self.next() {
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
            Param::Name => match self.next() {
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
            Param::Loc {
                name,
                tags,
                bare,
                min,
                max,
            } => self.location(name, tags, bare, min, max, command),
            Param::Straight => match self.peek() {
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
            Param::Choice { name, options } => match self.peek() {
                None => Ok(Value::Choice(0)),
                Some(t) => {
                    let found = match &t.kind {
                        Kind::Word(w) => options.iter().position(|(word, konst)| {
                            w.eq_ignore_ascii_case(word) || w.eq_ignore_ascii_case(konst)
                        }),
                        _ => None,
                    };
                    match found {
                        Some(i) => {
                            self.pos += 1;
                            Ok(Value::Choice(i))
                        }
                        None => {
                            let words: Vec<String> =
                                options.iter().map(|(w, k)| format!("{w} ({k})")).collect();
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
        let mut values = Vec::new();
        let mut want_value = true;
        loop {
            let Some(t) = self.next() else {
                return Err(SyntaxError {
                    col: self.end_col,
                    width: 1,
                    message: format!(
                        "expected `)` to close the location begun at column {}",
                        start.col
                    ),
                });
            };
            match &t.kind {
                Kind::Close => break,
                Kind::Comma if !want_value => want_value = true,
                Kind::Number(v) => {
                    if values.len() == max {
                        return Err(SyntaxError::at(
                            t,
                            format!("too many values: `{name}` takes at most {max}"),
                        ));
                    }
                    if tag == Tag::Prec && v.fract() != 0.0 {
                        return Err(SyntaxError::at(
                            t,
                            "a precision point holds whole encoder counts",
                        ));
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
            Tag::Cart => Location::Cart(values.iter().map(|v| *v as f32).collect()),
            Tag::Joint => Location::Joint(values.iter().map(|v| *v as f32).collect()),
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

fn build(spec: &Spec, values: Vec<Value>) -> Result<Request, SyntaxError> {
    use Value::*;
    let floats = |l: &Location| -> Vec<f32> {
        l.to_array6()[..l.num_dims()]
            .iter()
            .map(|v| *v as f32)
            .collect()
    };
    let mut v = values.into_iter();
    let mut take = || v.next().expect("one value per parameter");
    let req = match spec.command {
        Command::Appro => {
            let (Name(name), Loc(d), Flag(straight)) = (take(), take(), take()) else {
                unreachable!()
            };
            Request::Appro {
                name,
                disp: floats(&d),
                straight,
            }
        }
        Command::ApproII => {
            let (Loc(target), Loc(d), Flag(straight)) = (take(), take(), take()) else {
                unreachable!()
            };
            Request::ApproII {
                target,
                disp: floats(&d),
                straight,
            }
        }
        Command::Close => {
            let Int(f) = take() else { unreachable!() };
            Request::Close { force: f as u8 }
        }
        Command::Depart => {
            let (Loc(d), Flag(straight)) = (take(), take()) else {
                unreachable!()
            };
            Request::Depart {
                disp: floats(&d),
                straight,
            }
        }
        Command::Finish => {
            let Choice(i) = take() else { unreachable!() };
            Request::Finish {
                mode: if i == 0 {
                    FinishMode::Wait
                } else {
                    FinishMode::Status
                },
            }
        }
        Command::Grip => {
            let Int(d) = take() else { unreachable!() };
            Request::Grip { dist: d as u8 }
        }
        Command::Halt => Request::Halt,
        Command::Home => {
            let Int(a) = take() else { unreachable!() };
            Request::Home { axis: a as u8 }
        }
        Command::Jog => {
            let (Loc(d), Flag(straight)) = (take(), take()) else {
                unreachable!()
            };
            Request::Jog {
                disp: floats(&d),
                straight,
            }
        }
        Command::Joint => {
            let (Int(j), Real(r)) = (take(), take()) else {
                unreachable!()
            };
            Request::Joint {
                joint: j as u8,
                radians: r as f32,
            }
        }
        Command::Ma | Command::Mi => {
            let Loc(q) = take() else { unreachable!() };
            if spec.command == Command::Ma {
                Request::Ma { joints: floats(&q) }
            } else {
                Request::Mi { joints: floats(&q) }
            }
        }
        Command::Move => {
            let (Name(name), Flag(straight)) = (take(), take()) else {
                unreachable!()
            };
            Request::Move { name, straight }
        }
        Command::MoveII => {
            let (Loc(target), Flag(straight)) = (take(), take()) else {
                unreachable!()
            };
            Request::MoveII { target, straight }
        }
        Command::Open => {
            let Int(f) = take() else { unreachable!() };
            Request::Open { force: f as u8 }
        }
        Command::Ready => Request::Ready,
        Command::SetToolTransform => {
            let Loc(t) = take() else { unreachable!() };
            Request::SetToolTransform { tool: floats(&t) }
        }
        Command::Speed => {
            let Int(p) = take() else { unreachable!() };
            Request::Speed { percent: p as u8 }
        }
        Command::GetPosition => {
            let (Choice(form), Choice(mode)) = (take(), take()) else {
                unreachable!()
            };
            Request::GetPosition {
                tag: [Tag::Cart, Tag::Joint, Tag::Prec][form],
                mode: [PosMode::Commanded, PosMode::Actual][mode],
            }
        }
        Command::TerminatePcp => Request::TerminatePcp,
        Command::GetStatus => Request::GetStatus,
    };
    Ok(req)
}

/// A location written the way the interpreter reads it: `c(400, 0, 150, 0, 1.5708, 0)`.
pub fn format_location(loc: &Location) -> String {
    let values: Vec<String> = match loc {
        Location::Prec(c) => c.iter().map(|v| v.to_string()).collect(),
        Location::Cart(v) => v
            .iter()
            .enumerate()
            .map(|(i, x)| {
                if i < 3 {
                    format!("{x:.3}")
                } else {
                    format!("{x:.5}")
                }
            })
            .collect(),
        Location::Joint(v) => v.iter().map(|x| format!("{x:.5}")).collect(),
    };
    format!("{}({})", literal_prefix(loc.tag()), values.join(", "))
}

#[cfg(test)]
mod tests {
    use super::super::scanner::scan;
    use super::*;

    fn p(line: &str) -> Result<Action, SyntaxError> {
        parse(&scan(line).unwrap(), line.chars().count())
    }

    #[test]
    fn every_command_parses_with_or_without_the_prefix() {
        assert_eq!(
            p("TROLHome 0").unwrap(),
            Action::Call(Request::Home { axis: 0 })
        );
        assert_eq!(p("home 3").unwrap(), p("trolHOME 3").unwrap());
        assert_eq!(
            p("appro test_001 c(-90) straight").unwrap(),
            Action::Call(Request::Appro {
                name: LocName::new("test_001").unwrap(),
                disp: vec![-90.0],
                straight: true
            })
        );
        assert_eq!(
            p("moveii p(1, 2, 3, 4, 5, 6)").unwrap(),
            Action::Call(Request::MoveII {
                target: Location::Prec(vec![1, 2, 3, 4, 5, 6]),
                straight: false
            })
        );
        assert_eq!(
            p("ma (0.1 0.2)").unwrap(),
            Action::Call(Request::Ma {
                joints: vec![0.1, 0.2]
            })
        );
        assert_eq!(
            p("getposition joint actual").unwrap(),
            Action::Call(Request::GetPosition {
                tag: Tag::Joint,
                mode: PosMode::Actual
            })
        );
        assert_eq!(
            p("finish").unwrap(),
            Action::Call(Request::Finish {
                mode: FinishMode::Wait
            })
        );
        assert_eq!(
            p("finish FINISH_STATUS").unwrap(),
            Action::Call(Request::Finish {
                mode: FinishMode::Status
            })
        );
        assert_eq!(p("; only a comment").unwrap(), Action::Nothing);
        for spec in SPECS {
            // Every command is reachable by its manual name.
            assert!(find(spec.command.api_name()).is_some());
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
        let e = p("moveii c(1, 2, 3) 1").unwrap_err();
        assert!(
            e.message.contains("needs 6 values, 3 given"),
            "{}",
            e.message
        );
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
            Action::Call(Request::MoveII { target, .. }) => {
                assert_eq!(target.to_array6()[..3], loc.to_array6()[..3]);
            }
            other => panic!("{other:?}"),
        }
    }
}

//! The simulated C500C's variables: ash's `new`, `here`, `print`, `set`, `setvalid`,
//! `erase`, `list` and `save`, and the application's variables loaded or read by the tests
//! and the CLI (`trol sim --c500c --locations`).

use super::*;

/// An ash variable's base type (`help list`: int, float, string, cloc, ploc, gloc) and, for
/// a location, its value once taught.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Var {
    Int,
    Float,
    Str,
    /// A cartesian location: x, y, z (mm), then the three angles (degrees) as ash prints
    /// them (taught by `here`, or `set`), and whether it is valid to move to (`here`, or
    /// `setvalid` after `set`).
    Cloc(Option<[f64; 6]>, bool),
    /// A precision point: the pulses of axes 1 to 6.
    Ploc(Option<[i64; 6]>),
}

impl Var {
    pub(super) fn base(&self) -> &'static str {
        match self {
            Var::Int => "int",
            Var::Float => "float",
            Var::Str => "string",
            Var::Cloc(..) => "cloc",
            Var::Ploc(_) => "ploc",
        }
    }
    pub(super) fn taught(&self) -> bool {
        match self {
            Var::Cloc(v, valid) => v.is_some() && *valid,
            Var::Ploc(v) => v.is_some(),
            _ => true,
        }
    }
}

/// Whether `name` is a variable name ash takes: 1 to 28 letters, digits and `_`, a letter
/// first (assumed: RAPL-3's identifiers; ash's own `Names must consist of 1 to 28
/// alphanumeric characters (no '/''s)` reads as its applications' names).
pub(super) fn ash_name(name: &str) -> bool {
    (1..=28).contains(&name.len())
        && name.as_bytes()[0].is_ascii_alphabetic()
        && name.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_')
}

impl C500c {
    /// `new <sigil><name>`: a variable of the sigil's type (none int, `%` float, `$`
    /// string, `_` cloc, `#` ploc), untaught.
    pub(super) fn new_var(&mut self, args: &str) {
        let (var, name) = match args.as_bytes().first() {
            Some(b'#') => (Var::Ploc(None), &args[1..]),
            Some(b'_') => (Var::Cloc(None, false), &args[1..]),
            Some(b'%') => (Var::Float, &args[1..]),
            Some(b'$') => (Var::Str, &args[1..]),
            _ => (Var::Int, args),
        };
        if name.is_empty() {
            self.line("Missing <variable_name>");
        } else if !ash_name(name) {
            self.line("Names must consist of 1 to 28 alphanumeric characters (no '/''s)");
        } else if self.vars.contains_key(name) {
            self.line("error: variable already exists.");
        } else {
            self.vars.insert(name.to_string(), var);
        }
    }

    /// A variable named in a command: printed `error: ...` where there is none. A sigil
    /// belongs only to `new` and `set` (`help setvalid`: `setvalid testloc`).
    pub(super) fn var(&mut self, args: &str) -> Option<String> {
        if args.is_empty() {
            self.line("Missing <variable_name>");
            return None;
        }
        if !ash_name(args) {
            self.line("error: no valid variable found.");
            return None;
        }
        if !self.vars.contains_key(args) {
            self.line("error: variable not found.");
            return None;
        }
        Some(args.to_string())
    }

    /// `here NAME`: where the arm is, into a location variable (its pulses for a ploc).
    /// True when a question waits (none: TROL's reading is that `here` asks only for a
    /// variable that does not exist, `-- create it?`).
    pub(super) fn here(&mut self, args: &str) -> bool {
        if ash_name(args) && !self.vars.contains_key(args) {
            self.out
                .extend_from_slice(format!("Variable '{args}' not found.").as_bytes());
            let eol = self.eol();
            self.out.extend_from_slice(eol);
            self.out.extend_from_slice(b"  -- create it? ");
            self.asking = Some(Ask::Create(args.to_string()));
            return true;
        }
        let Some(name) = self.var(args) else {
            return false;
        };
        let t = self.now();
        let q = self.arm.position(t, Which::Actual);
        let value = match self.vars[&name] {
            Var::Ploc(_) => Var::Ploc(Some(self.sw.pulses.pulses(&q.map(f64::to_degrees)))),
            Var::Cloc(..) => Var::Cloc(Some(self.cloc_of_world(self.world(&q))), true),
            _ => {
                self.line("Not a location variable.");
                return false;
            }
        };
        self.vars.insert(name, value);
        false
    }

    /// `print NAME`: its value (a ploc in the switch's form).
    pub(super) fn print_var(&mut self, args: &str) {
        let Some(name) = self.var(args) else {
            return;
        };
        match self.vars[&name].clone() {
            Var::Ploc(None) | Var::Cloc(None, _) => self.line("Location has not been taught"),
            Var::Ploc(Some(p)) => {
                let text = match self.sw.loc_print {
                    LocPrint::Row => format!(
                        "        {:+10} {:+10} {:+10} {:+10} {:+10} {:+10}",
                        p[0], p[1], p[2], p[3], p[4], p[5]
                    ),
                    LocPrint::Braced => {
                        format!("{name} = {{{}}}", p.map(|v| v.to_string()).join(", "))
                    }
                };
                self.line(&text);
            }
            Var::Cloc(Some(w), _) => {
                let text = match self.sw.loc_print {
                    LocPrint::Row => format!(
                        "        {:+10.3} {:+10.3} {:+10.3} {:+10.3} {:+10.3} {:+10.3}",
                        w[0], w[1], w[2], w[3], w[4], w[5]
                    ),
                    LocPrint::Braced => {
                        format!("{name} = {{{}}}", w.map(|v| format!("{v:.3}")).join(", "))
                    }
                };
                self.line(&text);
            }
            Var::Int | Var::Float => self.line(&format!("{name} = 0")),
            Var::Str => self.line(&format!("{name} = \"\"")),
        }
    }

    /// `set _NAME = {x, y, z, a, b, c[, e1, e2]}`: a cartesian location's values, not valid
    /// until `setvalid` (`help setvalid`). Other constants are not played.
    pub(super) fn set_var(&mut self, args: &str) {
        let Some((lhs, rhs)) = args.split_once('=') else {
            self.line("Missing '='");
            return;
        };
        let Some(name) = lhs.trim().strip_prefix('_') else {
            self.line("error: unimplemented.");
            return;
        };
        let Some(inner) = rhs
            .trim()
            .strip_prefix('{')
            .and_then(|r| r.strip_suffix('}'))
        else {
            self.line("error: missing value(s).");
            return;
        };
        let v: Result<Vec<f64>, _> = inner.split(',').map(|w| w.trim().parse::<f64>()).collect();
        let v = match v {
            Ok(v) if (v.len() == 6 || v.len() == 8) && v.iter().all(|x| x.is_finite()) => v,
            _ => {
                self.line("error: missing value(s).");
                return;
            }
        };
        match self.vars.get(name) {
            Some(Var::Cloc(..)) => {
                let w = [v[0], v[1], v[2], v[3], v[4], v[5]];
                self.vars
                    .insert(name.to_string(), Var::Cloc(Some(w), false));
            }
            Some(_) => self.line("error: type mismatch."),
            // Assumed: ash asks to create it (`Variable '...' not found. -- create it?`);
            // played as not found.
            None => self.line("error: variable not found."),
        }
    }

    /// `setvalid NAME`: asks first (`help setvalid`: USE EXTREME CAUTION). True when the
    /// question waits.
    pub(super) fn set_valid(&mut self, args: &str) -> bool {
        let Some(name) = self.var(args) else {
            return false;
        };
        if !matches!(self.vars[&name], Var::Cloc(Some(_), _)) {
            self.line("Not a location variable.");
            return false;
        }
        if !self.sw.setvalid_asks {
            // Sets the flag at once, with nothing said.
            if let Some(Var::Cloc(v, _)) = self.vars.get(&name).cloned() {
                self.vars.insert(name, Var::Cloc(v, true));
            }
            return false;
        }
        self.line("WARNING: moving to an incorrect location can damage the robot.");
        self.out
            .extend_from_slice(b"Set the valid flag anyway (y/n) ? ");
        self.asking = Some(Ask::Valid(name));
        true
    }

    /// A cartesian location's constant of the WORLD row's values (the angles reversed on
    /// [`Switches::cloc_reversed`]).
    pub(super) fn cloc_of_world(&self, w: [f64; 6]) -> [f64; 6] {
        if self.sw.cloc_reversed {
            [w[0], w[1], w[2], w[5], w[4], w[3]]
        } else {
            w
        }
    }

    /// The WORLD row's values of a cartesian location's constant.
    pub(super) fn world_of_cloc(&self, c: [f64; 6]) -> [f64; 6] {
        // Reversing is its own inverse.
        self.cloc_of_world(c)
    }

    /// Where the tool is, as the WORLD row prints it (ash's tool transform is the null one).
    pub(super) fn world(&self, q: &[f64; 6]) -> [f64; 6] {
        world::to_ash(&self.arm.kinematics().fk(q), self.sw.reading())
    }

    /// `erase NAME`: asks first. True when the question waits.
    pub(super) fn erase(&mut self, args: &str) -> bool {
        if args.is_empty() {
            self.line("Missing <variable_name>");
            return false;
        }
        if !self.vars.contains_key(args) {
            self.line("Variable not found");
            return false;
        }
        self.out
            .extend_from_slice(format!("Erase variable '{args}' and its value? ").as_bytes());
        self.asking = Some(Ask::Erase(args.to_string()));
        true
    }

    /// `list [basetype]`: the variables, a pager's question after each [`PAGE_ROWS`] rows.
    /// True when the prompt is the pager's to give.
    pub(super) fn list(&mut self, args: &str) -> bool {
        if !matches!(
            args,
            "" | "int" | "float" | "string" | "cloc" | "ploc" | "gloc"
        ) {
            self.line("Illegal basetype: must be int|float|string|cloc|ploc|gloc");
            return false;
        }
        let rows: Vec<String> = self
            .vars
            .iter()
            .filter(|(_, v)| args.is_empty() || v.base() == args)
            .map(|(n, v)| {
                format!(
                    "  {:<16} {}{:<32}",
                    v.base(),
                    if v.taught() { "" } else { "* " },
                    n
                )
            })
            .collect();
        if rows.is_empty() {
            self.line("< no variables >");
            return false;
        }
        self.line("Variables: (* indicates not yet taught)");
        self.asking = Some(Ask::Page(rows));
        // The pager prompts once the last page is out.
        self.page();
        true
    }

    /// The application's variables as `save` last wrote them (its `.v3` file): each name,
    /// and a precision point's pulses.
    pub fn saved_plocs(&self) -> Vec<(String, Option<[i64; 6]>)> {
        self.saved
            .iter()
            .filter_map(|(n, v)| match v {
                Var::Ploc(p) => Some((n.clone(), *p)),
                _ => None,
            })
            .collect()
    }

    /// The backup battery died: every variable is gone, and the `.v3` file with them.
    pub fn forget_variables(&mut self) {
        self.vars.clear();
        self.saved.clear();
    }

    /// The cartesian locations as ash holds them now: each name, its values as the WORLD
    /// row prints them, and whether it is valid.
    pub fn clocs(&self) -> Vec<(String, Option<[f64; 6]>, bool)> {
        self.vars
            .iter()
            .filter_map(|(n, v)| match v {
                Var::Cloc(w, valid) => Some((n.clone(), *w, *valid)),
                _ => None,
            })
            .collect()
    }

    /// The precision points as ash holds them now.
    pub fn plocs(&self) -> Vec<(String, Option<[i64; 6]>)> {
        self.vars
            .iter()
            .filter_map(|(n, v)| match v {
                Var::Ploc(p) => Some((n.clone(), *p)),
                _ => None,
            })
            .collect()
    }

    /// Teach a precision point as the pendant would, whatever TROL does: `pulses`, or
    /// untaught.
    pub fn set_ploc(&mut self, name: &str, pulses: Option<[i64; 6]>) {
        self.vars.insert(name.to_string(), Var::Ploc(pulses));
    }

    /// Teach a cartesian location as the pendant would: the flange at `pose` (TROL's x y z
    /// yaw pitch roll), or untaught.
    pub fn set_cloc(&mut self, name: &str, pose: Option<[f64; 6]>) {
        let v = pose.map(|p| {
            self.cloc_of_world(world::to_ash(
                &trol_a465::kinematics::Pose::from_xyzypr(p),
                self.sw.reading(),
            ))
        });
        self.vars
            .insert(name.to_string(), Var::Cloc(v, v.is_some()));
    }

    /// The application's variables from a TROL locations file's entries (the lab's `.v3`
    /// file): a cartesian location as a `cloc`, a precision point (`#NAME`) as a `ploc`;
    /// joint locations have no ash form. Names in lower case.
    pub fn load_variables(
        &mut self,
        entries: &[(String, trol_a465::arm::Stored)],
    ) -> Result<usize, String> {
        use trol_a465::arm::Stored;
        for (name, loc) in entries {
            let var = name.trim_start_matches('#').to_ascii_lowercase();
            if !ash_name(&var) {
                return Err(format!("{name}: not a name ash takes"));
            }
            match loc {
                Stored::Cart(v) => self.set_cloc(&var, Some(*v)),
                // The file's counts are the A465 model's: as this controller counts them.
                Stored::Prec(c) => {
                    let q = trol_a465::model::counts_to_joints(&c.map(f64::from));
                    let p = self.sw.pulses.pulses(&q.map(f64::to_degrees));
                    self.set_ploc(&var, Some(p))
                }
                Stored::Joints(_) => {
                    return Err(format!(
                        "{name}: a joint location, which ash has no form for"
                    ));
                }
            }
        }
        self.saved = self.vars.clone();
        Ok(entries.len())
    }
}

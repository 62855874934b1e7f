//! `trol c500c backup` and `restore` (docs/c500c.md, "Backup and restore"): the
//! application's location variables as ash prints them, to a text file on the PC and back.
//!
//! The file holds ash's own values (pulses; x, y, z and the angles as the WORLD row prints
//! them), so neither needs the profile's reading of the angles. Restore writes back only
//! what ash can be given from values: a cartesian location (`set`, `setvalid`, each read
//! back). A precision point has no such form (`set` takes cartesian constants only): where
//! the controller's differs from the file's or is missing, restore creates the name where it
//! is missing and lists each to teach again on the arm; it never moves the arm.

use super::*;
use crate::backend::cartesian::Cloc;
use crate::backend::teach::Ploc;

/// One location variable as ash holds it.
#[derive(Clone, Debug, PartialEq)]
pub enum Saved {
    /// A precision point: its pulses, or not taught.
    Ploc(Option<[i64; 6]>),
    /// A cartesian location: x, y, z (mm) and the angles (degrees) as ash prints them, or
    /// not taught (or not valid).
    Cloc(Option<[f64; 6]>),
}

/// The application's location variables, by name.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Backup {
    /// The application.
    pub app: String,
    /// Each variable, sorted by name.
    pub vars: Vec<(String, Saved)>,
}

/// The first line of a backup file.
pub const HEADER: &str = "; trol c500c backup";

impl Backup {
    /// The file's text: a header, then one variable per line: `NAME ploc P1 .. P6`, `NAME
    /// cloc X Y Z A B C`, or `NAME ploc untaught` / `NAME cloc untaught`.
    pub fn to_text(&self) -> String {
        let mut out = format!(
            "{HEADER} of the application {}: ash's own values (pulses; mm and degrees as the \
             WORLD row prints them)\n",
            self.app
        );
        for (name, v) in &self.vars {
            let line = match v {
                Saved::Ploc(Some(p)) => {
                    format!("{name} ploc {}", p.map(|x| x.to_string()).join(" "))
                }
                Saved::Cloc(Some(w)) => {
                    format!("{name} cloc {}", w.map(fmt3).join(" "))
                }
                Saved::Ploc(None) => format!("{name} ploc untaught"),
                Saved::Cloc(None) => format!("{name} cloc untaught"),
            };
            out.push_str(&line);
            out.push('\n');
        }
        out
    }

    /// Read a backup file's text; the line and what is wrong with it where it is not one.
    pub fn parse(text: &str) -> Result<Backup, String> {
        let mut lines = text.lines();
        let head = lines.next().unwrap_or("");
        let Some(rest) = head.strip_prefix(HEADER) else {
            return Err(format!(
                "line 1: not a backup of `trol c500c backup` (it starts `{HEADER}`)"
            ));
        };
        let app = rest
            .strip_prefix(" of the application ")
            .and_then(|r| r.split(':').next())
            .unwrap_or("")
            .to_string();
        let mut b = Backup {
            app,
            vars: Vec::new(),
        };
        for (i, l) in lines.enumerate() {
            let n = i + 2;
            let l = l.trim();
            if l.is_empty() || l.starts_with(';') {
                continue;
            }
            let w: Vec<&str> = l.split_whitespace().collect();
            let bad = |why: &str| format!("line {n}: {why}: `{l}`");
            let name = w[0];
            let named = name.as_bytes()[0].is_ascii_alphabetic()
                && name.len() <= 28
                && name.bytes().all(|c| c.is_ascii_alphanumeric() || c == b'_');
            if !named {
                return Err(bad("not an ash variable name"));
            }
            if b.vars.iter().any(|(v, _)| v == name) {
                return Err(bad("a name given twice"));
            }
            let saved = match (w.get(1).copied(), &w[2..]) {
                (Some("ploc"), ["untaught"]) => Saved::Ploc(None),
                (Some("cloc"), ["untaught"]) => Saved::Cloc(None),
                (Some("ploc"), v) if v.len() == 6 => {
                    let p: Result<Vec<i64>, _> = v.iter().map(|x| x.parse::<i64>()).collect();
                    let p = p.map_err(|_| bad("six whole pulses"))?;
                    Saved::Ploc(Some(p.try_into().map_err(|_| bad("six pulses"))?))
                }
                (Some("cloc"), v) if v.len() == 6 => {
                    let c: Result<Vec<f64>, _> = v.iter().map(|x| x.parse::<f64>()).collect();
                    let c = c.map_err(|_| bad("six numbers"))?;
                    if c.iter().any(|x| !x.is_finite() || x.abs() > 1e5) {
                        return Err(bad("a value out of range"));
                    }
                    Saved::Cloc(Some(c.try_into().map_err(|_| bad("six numbers"))?))
                }
                _ => {
                    return Err(bad(
                        "expected `NAME ploc P1 .. P6` or `NAME cloc X Y Z A B C`",
                    ));
                }
            };
            b.vars.push((name.to_string(), saved));
        }
        Ok(b)
    }
}

/// What restore did, or would do.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Restored {
    /// Cartesian locations written (or to write), each read back.
    pub written: Vec<String>,
    /// Variables already as the file has them.
    pub same: Vec<String>,
    /// Names created untaught (a precision point or an untaught one missing on the
    /// controller).
    pub created: Vec<String>,
    /// Precision points whose value differs from the file's: each to teach again on the
    /// arm, with the file's pulses.
    pub to_teach: Vec<(String, [i64; 6])>,
}

impl C500cBackend {
    /// The application's location variables as ash holds them (`list ploc`, `list cloc`,
    /// `print` of each taught one); TROL's own `trolgo` left out. Reads only.
    pub fn backup(&mut self) -> Result<Backup, BackendError> {
        self.clean()?;
        if self.console_busy() {
            return Err(BackendError::Refused(BUSY));
        }
        let mut vars = Vec::new();
        for base in ["ploc", "cloc"] {
            for (var, taught) in self.list_vars(base)? {
                if var == cartesian::SCRATCH {
                    continue;
                }
                let saved = match (base, taught) {
                    ("ploc", false) => Saved::Ploc(None),
                    (_, false) => Saved::Cloc(None),
                    ("ploc", true) => match self.print_ploc(&var)? {
                        Ploc::At(p) => Saved::Ploc(Some(p)),
                        other => return Err(self.misread(base, &var, &other)),
                    },
                    (_, true) => match self.print_cloc(&var)? {
                        Cloc::At(w) => Saved::Cloc(Some(w)),
                        other => return Err(self.misread(base, &var, &other)),
                    },
                };
                vars.push((var, saved));
            }
        }
        vars.sort_by(|a, b| a.0.cmp(&b.0));
        Ok(Backup {
            app: self.profile.app.clone(),
            vars,
        })
    }

    /// Restore `b`: compare with what ash holds now; with `write`, set each cartesian
    /// location that differs or is missing (`new _name`, `set`, `setvalid` answered y, read
    /// back), create each missing name untaught, and `save`. Precision points that differ
    /// are listed to teach again. Without `write`, only says what it would do. Never moves
    /// the arm.
    pub fn restore(&mut self, b: &Backup, write: bool) -> Result<Restored, BackendError> {
        let now = self.backup()?;
        let held = |name: &str| now.vars.iter().find(|(n, _)| n == name).map(|(_, v)| v);
        // A name of another type on the controller stops the restore before anything is
        // written.
        for (name, want) in &b.vars {
            if let Some(other) = held(name)
                && std::mem::discriminant(other) != std::mem::discriminant(want)
            {
                return Err(BackendError::Explained(
                    code::BAD_ARGUMENT,
                    format!(
                        "{name}: the file has a {}, the controller a {}: nothing restored",
                        kind_of(want),
                        kind_of(other)
                    ),
                ));
            }
        }
        let mut r = Restored::default();
        for (name, want) in &b.vars {
            let have = held(name);
            match (want, have) {
                (Saved::Cloc(Some(w)), Some(Saved::Cloc(Some(h))))
                    if (0..6).all(|j| (w[j] - h[j]).abs() <= 0.0015) =>
                {
                    r.same.push(name.clone())
                }
                (Saved::Ploc(Some(w)), Some(Saved::Ploc(Some(h)))) if w == h => {
                    r.same.push(name.clone())
                }
                // Untaught in the file, and the name there (of the same type, above).
                (Saved::Cloc(None) | Saved::Ploc(None), Some(_)) => r.same.push(name.clone()),
                (Saved::Cloc(Some(w)), have) => {
                    if write {
                        if have.is_none() {
                            self.new_var('_', name)?;
                        }
                        self.write_cloc(name, w)?;
                    }
                    r.written.push(name.clone());
                }
                (Saved::Ploc(p), have) => {
                    if have.is_none() {
                        if write {
                            self.new_var('#', name)?;
                        }
                        r.created.push(name.clone());
                    }
                    if let Some(p) = p {
                        r.to_teach.push((name.clone(), *p));
                    }
                }
                (Saved::Cloc(None), None) => {
                    if write {
                        self.new_var('_', name)?;
                    }
                    r.created.push(name.clone());
                }
            }
        }
        if write && !(r.written.is_empty() && r.created.is_empty()) {
            let lines = self.exchange("save").map_err(|e| self.fail(e))?;
            match said(&lines)[..] {
                [l] if l.starts_with("Saving '") && l.ends_with("done.") => {}
                _ => return Err(self.refusal("save", &lines)),
            }
        }
        Ok(r)
    }

    /// `list BASE` said `var` is taught, and `print` says otherwise: UNSURE.
    pub(super) fn misread(
        &mut self,
        base: &str,
        var: &str,
        got: &dyn std::fmt::Display,
    ) -> BackendError {
        self.unsure(format!(
            "`list {base}` has {var} taught, and `print {var}` reads {got}"
        ))
    }

    /// `new #name` or `new _name`: nothing printed.
    fn new_var(&mut self, sign: char, name: &str) -> Result<(), BackendError> {
        let cmd = format!("new {sign}{name}");
        let lines = self.exchange(&cmd).map_err(|e| self.fail(e))?;
        if lines.is_empty() {
            Ok(())
        } else {
            Err(self.refusal(&cmd, &lines))
        }
    }

    /// Set a cartesian location to `w` (ash's values), make it valid, and read it back.
    pub(super) fn write_cloc(&mut self, name: &str, w: &[f64; 6]) -> Result<(), BackendError> {
        let values: Vec<String> = w.iter().copied().map(fmt3).collect();
        let cmd = format!("set _{name} = {{{}, 0, 0}}", values.join(", "));
        let lines = self.exchange(&cmd).map_err(|e| self.fail(e))?;
        if !lines.is_empty() {
            return Err(self.refusal(&cmd, &lines));
        }
        // Read back before it is made valid (issue 62: `setvalid` came first).
        match self.print_cloc(name)? {
            Cloc::At(got) if (0..6).all(|j| (got[j] - w[j]).abs() <= 0.0015) => {}
            other => {
                return Err(self.unsure(format!(
                    "`set _{name}` taken, and `print {name}` then reads {other}, not the values \
                     set ({}); not made valid",
                    values.join(", ")
                )));
            }
        }
        let cmd = format!("setvalid {name}");
        let lines = self.converse(&cmd, &[("Set the valid flag anyway (y/n) ?", "y\r")])?;
        let warned = "WARNING: moving to an incorrect location can damage the robot.";
        if said(&lines).iter().any(|l| *l != warned) {
            return Err(self.refusal(&cmd, &lines));
        }
        Ok(())
    }
}

fn kind_of(s: &Saved) -> &'static str {
    match s {
        Saved::Ploc(_) => "precision point",
        Saved::Cloc(_) => "cartesian location",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_backup_reads_back_and_bad_files_are_refused_with_the_line() {
        let b = Backup {
            app: "test".into(),
            vars: vec![
                ("a".into(), Saved::Ploc(Some([1, -2, 3, 4, 5, 6]))),
                (
                    "b".into(),
                    Saved::Cloc(Some([400.0, 0.0, 150.0, 0.0, 90.0, 0.0])),
                ),
                ("c".into(), Saved::Ploc(None)),
                ("d_1".into(), Saved::Cloc(None)),
            ],
        };
        assert_eq!(Backup::parse(&b.to_text()).unwrap(), b);
        for (text, why) in [
            ("hello\n", "line 1"),
            (
                "; trol c500c backup of the application test: x\na ploc 1 2 3\n",
                "line 2",
            ),
            (
                "; trol c500c backup of the application test: x\na cloc 1 2 3 4 5 nan\n",
                "line 2",
            ),
            (
                "; trol c500c backup of the application test: x\n1a ploc untaught\n",
                "line 2",
            ),
            (
                "; trol c500c backup of the application test: x\na ploc untaught\na cloc untaught\n",
                "line 3",
            ),
            (
                "; trol c500c backup of the application test: x\na joint 1 2 3 4 5 6\n",
                "line 2",
            ),
        ] {
            let e = Backup::parse(text).unwrap_err();
            assert!(e.starts_with(why), "{text}: {e}");
        }
    }
}

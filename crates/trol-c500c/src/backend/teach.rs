//! Locations as ash's own variables (docs/c500c.md, "Locations"): a precision point `#NAME`
//! of TROL's is the `ploc` variable `name` of the application, so what TROL teaches is in
//! the application's `.v3` file after `save`, and what the pendant taught TROL can move to.
//!
//! Every value is read back (`print`) before it is trusted: after `here`, where it must
//! equal the pulses `w2` reads; and before `move`, whose end is the arm seen at those
//! pulses. A cartesian location needs the WORLD row's angle order, which no public source
//! settles: refused before sending, as cartesian motions are.

use super::*;

/// How far (pulses) the arm may stand from a precision point and be at it (assumed: about
/// 0.05 degrees at an A465's 561 to 1,111 pulses per degree, which a C500C's are not known
/// to differ from).
pub const ARRIVE_PULSES: i64 = 25;

/// What `print NAME` said of a precision point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Ploc {
    /// ash has no variable of that name.
    Missing,
    /// It exists, not yet taught.
    Untaught,
    /// Its pulses, axes 1 to 6.
    At([i64; 6]),
}

/// The lines ash prints for a name it does not have (`print`, `erase`; CRS's texts).
fn not_found(line: &str) -> bool {
    let l = line.trim();
    l == "error: variable not found."
        || l == "Variable not found"
        || (l.starts_with("Variable '") && l.ends_with("' not found."))
}

/// `print`'s lines of a precision point: one row of six signed integers (axes 7 and 8 may
/// follow on a second row, ignored).
pub(super) fn read_ploc(lines: &[String]) -> Option<Ploc> {
    let lines: Vec<&str> = lines
        .iter()
        .map(|l| l.trim())
        .filter(|l| !l.is_empty())
        .collect();
    match lines[..] {
        [l] if not_found(l) => Some(Ploc::Missing),
        ["Location has not been taught"] => Some(Ploc::Untaught),
        [row] | [row, _] => {
            let v: Vec<i64> = row
                .split_whitespace()
                .map(|w| w.parse::<i64>())
                .collect::<Result<_, _>>()
                .ok()?;
            if lines.len() == 2 {
                // Axes 7 and 8: two more integers, nothing else.
                let extra = lines[1]
                    .split_whitespace()
                    .map(|w| w.parse::<i64>().is_ok())
                    .collect::<Vec<_>>();
                if extra.len() != 2 || extra.contains(&false) {
                    return None;
                }
            }
            Some(Ploc::At(v.try_into().ok()?))
        }
        _ => None,
    }
}

/// `list ploc`'s rows: each name, and whether it is taught. `None`: a row of another form.
pub(super) fn read_list(lines: &[String]) -> Option<Vec<(String, bool)>> {
    let mut out = Vec::new();
    for l in lines.iter().map(|l| l.trim()).filter(|l| !l.is_empty()) {
        if l == "Variables: (* indicates not yet taught)" || l == "< no variables >" {
            continue;
        }
        let words: Vec<&str> = l.split_whitespace().collect();
        match words[..] {
            ["ploc", "*", name] => out.push((name.to_string(), false)),
            ["ploc", name] => out.push((name.to_string(), true)),
            _ => return None,
        }
    }
    Some(out)
}

/// The ash variable of a TROL precision point: the name without `#`, in lower case (TROL
/// tells no two names apart by case; whether ash does is not public). `None`: not a name
/// ash takes (letters and digits only: `Names must consist of 1 to 28 alphanumeric
/// characters`).
pub(super) fn ash_var(name: &LocName) -> Option<String> {
    let v = name.as_str().strip_prefix('#')?.to_ascii_lowercase();
    (!v.is_empty() && v.bytes().all(|b| b.is_ascii_alphanumeric())).then_some(v)
}

impl C500cBackend {
    /// The ash variable for `name`, or the refusal to give (before anything is sent).
    fn variable(&mut self, name: &LocName, what: &str) -> Result<String, BiosResult> {
        if !name.is_precision() {
            return Err(self.unsettled(&format!(
                "{what} {}: a cartesian location on a C500C is an ash `cloc`, whose angles need \
                 the WORLD row's order (not settled); use a precision point (#NAME)",
                name.as_str()
            )));
        }
        match ash_var(name) {
            Some(v) => Ok(v),
            None => {
                self.note(format!(
                    "refused before sending: {what} {}: ash's variable names are letters and \
                     digits only",
                    name.as_str()
                ));
                Err(Ok(code::BAD_ARGUMENT))
            }
        }
    }

    /// The arm must stand, with nothing of TROL's under way or queued, for a call that reads
    /// or teaches where it is.
    fn standing_only(&mut self, what: &str) -> Option<BiosResult> {
        if let Err(e) = self.clean() {
            return Some(Err(e));
        }
        if self.outstanding.is_some() || !self.queue.is_empty() {
            self.note(format!(
                "refused: {what} while a motion has not ended: call TROLFinish(FINISH_WAIT) \
                 first"
            ));
            return Some(Ok(BUSY));
        }
        None
    }

    /// `print VAR`, read as a precision point; any other form is UNSURE.
    pub(super) fn print_ploc(&mut self, var: &str) -> Result<Ploc, BackendError> {
        let cmd = format!("print {var}");
        let lines = match self.exchange(&cmd) {
            Ok(l) => l,
            Err(e) => return Err(self.fail(e)),
        };
        match read_ploc(&lines) {
            Some(p) => Ok(p),
            None => Err(self.unsure(format!(
                "`{cmd}`: ash printed `{}`, not a precision point in the form TROL reads (a \
                 row of six pulses): TROL moves to no variable it cannot read",
                lines.join(" | ")
            ))),
        }
    }

    /// A command ash asks `question` back on, answered `answer` (TROL asked for it on
    /// purpose); the lines to the prompt after it. A prompt with no question: its lines (a
    /// refusal). Any other question: Ctrl-C, and UNSURE.
    fn exchange_asked(
        &mut self,
        cmd: &str,
        question: &str,
        answer: &str,
    ) -> Result<Vec<String>, BackendError> {
        if let Err(e) = self.send(format!("{cmd}\r").as_bytes()) {
            return Err(self.unsure(format!("`{cmd}`: the console failed: {e}")));
        }
        let app = self.profile.app.clone();
        let deadline = Instant::now() + REPLY_LIMIT;
        let mut lines = Vec::new();
        loop {
            let said = match self.next(deadline) {
                Ok(s) => s,
                Err(e) => return Err(self.unsure(format!("`{cmd}`: the console failed: {e}"))),
            };
            match said {
                Some(Said::Line(l)) if l.trim_end() == cmd || l.trim().is_empty() => {}
                Some(Said::Line(l)) => lines.push(l),
                Some(Said::Prompt(p)) if p == app => return Ok(lines),
                Some(Said::Question(q)) if q.ends_with(question) => {
                    if let Err(e) = self.send(format!("{answer}\r").as_bytes()) {
                        return Err(self.unsure(format!("`{cmd}`: the console failed: {e}")));
                    }
                    return match self.read_to_prompt(answer, Instant::now() + REPLY_LIMIT) {
                        Ok(Some(l)) => Ok(l),
                        Ok(None) => Err(self.unsure(format!(
                            "`{cmd}`, answered `{answer}`: no prompt within {REPLY_LIMIT:?}"
                        ))),
                        Err(e) => Err(self.fail(e)),
                    };
                }
                Some(Said::Question(q)) => {
                    let _ = self.send(b"\x03");
                    return Err(self.unsure(format!(
                        "after `{cmd}` ash asked `{q}`: not answered (Ctrl-C sent)"
                    )));
                }
                Some(Said::Prompt(p)) => {
                    return Err(self.unsure(format!(
                        "after `{cmd}` the console gave the prompt of `{p}`, not ash's: ash \
                         ended"
                    )));
                }
                None => {
                    return Err(self.unsure(format!("`{cmd}`: no prompt within {REPLY_LIMIT:?}")));
                }
            }
        }
    }

    /// Here: `new #var` where ash has no such variable, `here var`, then `w2` and `print
    /// var`, which must agree.
    pub(super) fn teach_here(&mut self, name: LocName, tag: Tag) -> BiosResult {
        if let Some(r) = self.standing_only("Here") {
            return r;
        }
        if tag != Tag::Prec && name.is_precision() {
            return Ok(code::BAD_ARGUMENT);
        }
        let var = match self.variable(&name, "Here") {
            Ok(v) => v,
            Err(r) => return r,
        };
        if self.print_ploc(&var)? == Ploc::Missing {
            let cmd = format!("new #{var}");
            let lines = match self.exchange(&cmd) {
                Ok(l) => l,
                Err(e) => return Err(self.fail(e)),
            };
            if !lines.is_empty() {
                return Err(self.refusal(&cmd, &lines));
            }
        }
        let cmd = format!("here {var}");
        let lines = match self.exchange(&cmd) {
            Ok(l) => l,
            Err(e) => return Err(self.fail(e)),
        };
        if !lines.is_empty() {
            return Err(self.refusal(&cmd, &lines));
        }
        let p = self.read_position(true)?;
        match self.print_ploc(&var)? {
            Ploc::At(v) if (0..6).all(|j| (v[j] - p.pulses[j]).abs() <= ARRIVE_PULSES) => {
                self.rests_at(p.joints_deg);
                Ok(code::OK)
            }
            other => Err(self.unsure(format!(
                "`{cmd}` taken, and then `print {var}` reads {other:?} with the arm at pulses \
                 {:?} (w2): what ash holds under {var} is not known",
                p.pulses
            ))),
        }
    }

    /// Define: ash sets a precision point only with `here` (`set` takes cartesian
    /// constants only, `help constants`).
    pub(super) fn teach_define(&mut self, name: LocName) -> BiosResult {
        if !name.is_precision() {
            return match self.variable(&name, "Define") {
                Ok(_) => Ok(UNSETTLED),
                Err(r) => r,
            };
        }
        self.note(format!(
            "refused before sending: Define {}: ash sets a precision point only with `here` \
             (its `set` takes cartesian constants only): move the arm there and use TROLHere",
            name.as_str()
        ));
        Ok(UNSUPPORTED)
    }

    /// DeleteLocation: `erase var`, its question answered `y`, then `print var` must find
    /// none.
    pub(super) fn teach_delete(&mut self, name: LocName) -> BiosResult {
        if let Some(r) = self.standing_only("DeleteLocation") {
            return r;
        }
        let var = match self.variable(&name, "DeleteLocation") {
            Ok(v) => v,
            Err(r) => return r,
        };
        if self.print_ploc(&var)? == Ploc::Missing {
            return Err(BackendError::UnknownLocation(name));
        }
        let cmd = format!("erase {var}");
        let lines = self.exchange_asked(&cmd, "and its value?", "y")?;
        if !lines.is_empty() {
            return Err(self.refusal(&cmd, &lines));
        }
        match self.print_ploc(&var)? {
            Ploc::Missing => Ok(code::OK),
            other => Err(self.unsure(format!(
                "`{cmd}` answered y, and `print {var}` still reads {other:?}"
            ))),
        }
    }

    /// ListLocations: `list ploc` (its pager answered with a space: TROL asked for the whole
    /// list), then `print` of each taught one. Untaught ones, and names TROL cannot hold
    /// (over 7 characters), are left out and named in the log.
    pub(super) fn teach_list(&mut self) -> Result<Vec<(LocName, Location)>, BackendError> {
        if let Some(r) = self.standing_only("ListLocations") {
            return match r {
                Err(e) => Err(e),
                Ok(c) => Err(BackendError::Refused(c)),
            };
        }
        let cmd = "list ploc";
        if let Err(e) = self.send(format!("{cmd}\r").as_bytes()) {
            return Err(self.unsure(format!("`{cmd}`: the console failed: {e}")));
        }
        let app = self.profile.app.clone();
        let mut lines = Vec::new();
        let mut deadline = Instant::now() + REPLY_LIMIT;
        loop {
            let said = match self.next(deadline) {
                Ok(s) => s,
                Err(e) => return Err(self.unsure(format!("`{cmd}`: the console failed: {e}"))),
            };
            match said {
                Some(Said::Line(l)) if l.trim_end() == cmd => {}
                Some(Said::Line(l)) => lines.push(l),
                Some(Said::Prompt(p)) if p == app => break,
                Some(Said::Question(q)) if q.ends_with("Hit <space> or <q>") => {
                    if let Err(e) = self.send(b" ") {
                        return Err(self.unsure(format!("`{cmd}`: the console failed: {e}")));
                    }
                    deadline = Instant::now() + REPLY_LIMIT;
                }
                Some(Said::Question(q)) => {
                    let _ = self.send(b"\x03");
                    return Err(self.unsure(format!(
                        "after `{cmd}` ash asked `{q}`: not answered (Ctrl-C sent)"
                    )));
                }
                Some(Said::Prompt(p)) => {
                    return Err(self.unsure(format!(
                        "after `{cmd}` the console gave the prompt of `{p}`, not ash's"
                    )));
                }
                None => {
                    return Err(self.unsure(format!("`{cmd}`: no prompt within {REPLY_LIMIT:?}")));
                }
            }
        }
        let Some(rows) = read_list(&lines) else {
            return Err(self.unsure(format!(
                "`{cmd}`: ash printed `{}`, not the list form TROL reads",
                lines.join(" | ")
            )));
        };
        let mut out = Vec::new();
        let mut left = Vec::new();
        for (var, taught) in rows {
            let name = LocName::new(&format!("#{var}"));
            match (name, taught) {
                (Ok(name), true) if ash_var(&name).is_some() => match self.print_ploc(&var)? {
                    Ploc::At(p) => {
                        let counts: Option<Vec<i32>> =
                            p.iter().map(|&v| i32::try_from(v).ok()).collect();
                        match counts {
                            Some(c) => out.push((name, Location::Prec(c))),
                            None => left.push(format!("{var} (pulses out of range)")),
                        }
                    }
                    other => {
                        return Err(self.unsure(format!(
                            "`list ploc` names {var} taught, and `print {var}` reads {other:?}"
                        )));
                    }
                },
                (_, false) => left.push(format!("{var} (not taught)")),
                _ => left.push(format!("{var} (no TROL name: over 7 characters)")),
            }
        }
        if !left.is_empty() {
            self.note(format!(
                "ash's precision points left out: {}",
                left.join(", ")
            ));
        }
        out.sort_by(|a, b| a.0.as_str().cmp(b.0.as_str()));
        Ok(out)
    }

    /// SaveLocations: `save`, which writes the application's `.v3` file: `Saving
    /// '<file>'...done.`
    pub(super) fn teach_save(&mut self) -> BiosResult {
        if let Some(r) = self.standing_only("SaveLocations") {
            return r;
        }
        let lines = match self.exchange("save") {
            Ok(l) => l,
            Err(e) => return Err(self.fail(e)),
        };
        let said: Vec<&str> = lines
            .iter()
            .map(|l| l.trim())
            .filter(|l| !l.is_empty())
            .collect();
        match said[..] {
            [l] if l.starts_with("Saving '") && l.ends_with("done.") => Ok(code::OK),
            _ => Err(self.refusal("save", &lines)),
        }
    }

    /// TROLMove to a precision point of ash's: read back (`print`), then `move var` through
    /// the gate; its end is the arm seen at those pulses. Joint-interpolated only.
    pub(super) fn move_named(&mut self, name: LocName, straight: bool) -> BiosResult {
        if let Some(r) = self.standing_only("a move to a named location") {
            return r;
        }
        if !name.is_precision() {
            // A name ash does not have is TROL_ERR_LOCATION, as on every controller; one it
            // has is a `cloc`, which TROL cannot move to yet.
            let var = name.as_str().to_ascii_lowercase();
            if var.bytes().all(|b| b.is_ascii_alphanumeric()) {
                let cmd = format!("print {var}");
                let lines = match self.exchange(&cmd) {
                    Ok(l) => l,
                    Err(e) => return Err(self.fail(e)),
                };
                if let [l] = &lines[..]
                    && not_found(l)
                {
                    return Err(BackendError::UnknownLocation(name));
                }
            }
        }
        let var = match self.variable(&name, "Move to") {
            Ok(v) => v,
            Err(r) => return r,
        };
        if straight {
            return self.unsettled(
                "a straight-line move needs the WORLD row's angle order (not settled): move to \
                 a precision point joint-interpolated (straight = 0)",
            );
        }
        match self.print_ploc(&var)? {
            Ploc::At(p) => self.motion(Motion {
                line: format!("move {var}"),
                kind: Kind::Named(p),
            }),
            Ploc::Missing => Err(BackendError::UnknownLocation(name)),
            Ploc::Untaught => Err(BackendError::Explained(
                trol_proto::application::code::TROL_ERR_LOCATION.0,
                format!(
                    "{}: ash has the variable {var}, not yet taught: teach it (TROLHere) first",
                    name.as_str()
                ),
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn l(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn print_is_read_exactly() {
        assert_eq!(
            read_ploc(&l(&["        +1000       -20 +3 +4 +5 +6"])),
            Some(Ploc::At([1000, -20, 3, 4, 5, 6]))
        );
        assert_eq!(
            read_ploc(&l(&["Location has not been taught"])),
            Some(Ploc::Untaught)
        );
        assert_eq!(
            read_ploc(&l(&["error: variable not found."])),
            Some(Ploc::Missing)
        );
        assert_eq!(read_ploc(&l(&["p = {1, 2, 3, 4, 5, 6}"])), None);
        assert_eq!(read_ploc(&l(&["1 2 3 4 5"])), None);
        assert_eq!(read_ploc(&l(&["1 2 3 4 5 6", "7 x"])), None);
        assert_eq!(
            read_ploc(&l(&["1 2 3 4 5 6", "7 8"])),
            Some(Ploc::At([1, 2, 3, 4, 5, 6]))
        );
        assert_eq!(read_ploc(&l(&["1.5 2 3 4 5 6"])), None);
    }

    #[test]
    fn list_rows_are_read_exactly() {
        assert_eq!(
            read_list(&l(&[
                "Variables: (* indicates not yet taught)",
                "  ploc             p1",
                "  ploc             * p2",
            ])),
            Some(vec![("p1".into(), true), ("p2".into(), false)])
        );
        assert_eq!(read_list(&l(&["< no variables >"])), Some(vec![]));
        assert_eq!(read_list(&l(&["  cloc             p1"])), None);
    }

    #[test]
    fn names_map_to_ash_variables() {
        let n = |s: &str| LocName::new(s).unwrap();
        assert_eq!(ash_var(&n("#Pick1")), Some("pick1".into()));
        assert_eq!(ash_var(&n("#a_b")), None);
        assert_eq!(ash_var(&n("pick")), None);
    }
}

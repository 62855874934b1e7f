//! Locations as ash's own variables (docs/c500c.md, "Locations"): a precision point `#NAME`
//! of TROL's is the `ploc` variable `name` of the application, so what TROL teaches is in
//! the application's `.v3` file after `save`, and what the pendant taught TROL can move to.
//!
//! Every value is read back (`print`) before it is trusted: after `here`, where it must
//! equal the pulses `w2` reads; and before `move`, whose end is the arm seen at those
//! pulses. A cartesian location needs the WORLD row's angle order, which no public source
//! settles: refused before sending, as cartesian motions are.

use super::*;
use crate::backend::backup::Saved;

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

impl std::fmt::Display for Ploc {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Ploc::Missing => write!(f, "no such variable"),
            Ploc::Untaught => write!(f, "a point not yet taught"),
            Ploc::At(p) => write!(f, "pulses {}", p.map(|v| v.to_string()).join(" ")),
        }
    }
}

/// The lines ash prints for a name it does not have (`print`, `erase`; CRS's texts).
pub(super) fn not_found(line: &str) -> bool {
    let l = line.trim();
    l == "error: variable not found."
        || l == "Variable not found"
        || (l.starts_with("Variable '") && l.ends_with("' not found."))
}

/// `print`'s lines of a precision point: one row of six signed integers (axes 7 and 8 may
/// follow on a second row, ignored).
pub(super) fn read_ploc(lines: &[String]) -> Option<Ploc> {
    let lines = said(lines);
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

/// `list BASE`'s rows: each name, and whether it is taught. `None`: a row of another form.
pub(super) fn read_list(lines: &[String], base: &str) -> Option<Vec<(String, bool)>> {
    let mut out = Vec::new();
    for l in lines.iter().map(|l| l.trim()).filter(|l| !l.is_empty()) {
        if l == "Variables: (* indicates not yet taught)" || l == "< no variables >" {
            continue;
        }
        let words: Vec<&str> = l.split_whitespace().collect();
        match words[..] {
            [b, "*", name] if b == base => out.push((name.to_string(), false)),
            [b, name] if b == base => out.push((name.to_string(), true)),
            _ => return None,
        }
    }
    Some(out)
}

/// The ash variable of a TROL location: the name without `#`, in lower case (TROL
/// tells no two names apart by case; whether ash does is not public). `None`: not a name
/// ash takes (assumed: RAPL-3's identifiers, a letter, then letters, digits and `_`).
pub(super) fn ash_var(name: &LocName) -> Option<String> {
    let n = name.as_str();
    let v = n.strip_prefix('#').unwrap_or(n).to_ascii_lowercase();
    let ok = v.as_bytes().first().is_some_and(u8::is_ascii_alphabetic)
        && v.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_');
    ok.then_some(v)
}

impl C500cBackend {
    /// The ash variable for `name` and its base type (`ploc` for `#NAME`, else `cloc`), or
    /// the refusal to give (before anything is sent).
    fn variable(
        &mut self,
        name: &LocName,
        what: &str,
    ) -> Result<(String, &'static str), BiosResult> {
        match ash_var(name) {
            Some(v) if name.is_precision() => Ok((v, "ploc")),
            Some(v) => Ok((v, "cloc")),
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
    pub(super) fn standing_only(&mut self, what: &str) -> Option<BiosResult> {
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

    /// A command whose questions TROL asked for on purpose, each answered as `answers`
    /// says (the bytes sent when ash asks a question ending so; a question may come again,
    /// as a pager's); the lines to ash's prompt, the echoes taken off. A prompt with no
    /// question: its lines (a refusal). Any other question: Ctrl-C, and UNSURE.
    pub(super) fn converse(
        &mut self,
        cmd: &str,
        answers: &[(&str, &str)],
    ) -> Result<Vec<String>, BackendError> {
        if let Err(e) = self.type_line(cmd) {
            return Err(self.fail(e));
        }
        let app = self.profile.app.clone();
        let mut deadline = Instant::now() + REPLY_LIMIT;
        let mut lines = Vec::new();
        let mut answered: Vec<&str> = Vec::new();
        loop {
            let said = match self.next(deadline) {
                Ok(s) => s,
                Err(e) => return Err(self.unsure(format!("`{cmd}`: the console failed: {e}"))),
            };
            match said {
                Some(Said::Line(l))
                    if l.trim() == cmd
                        || l.trim().is_empty()
                        || answered.iter().any(|a| l.trim() == a.trim()) => {}
                Some(Said::Line(l)) => lines.push(l),
                Some(Said::Prompt(p)) if p == app => return Ok(lines),
                Some(Said::Question(q)) => {
                    let Some((_, answer)) = answers.iter().find(|(end, _)| q.ends_with(end)) else {
                        let _ = self.send(b"\x03");
                        return Err(self.unsure(format!(
                            "after `{cmd}` ash asked `{q}`: not answered (Ctrl-C sent)"
                        )));
                    };
                    // A line's answer is typed as a line (its echo seen first); a key alone
                    // (the pager's) as it is.
                    let sent = match answer.strip_suffix('\r') {
                        Some(line) => self.type_line(line),
                        None => self.send(answer.as_bytes()).map_err(Fail::Io),
                    };
                    if let Err(e) = sent {
                        return Err(self.fail(e));
                    }
                    answered.push(answer);
                    deadline = Instant::now() + REPLY_LIMIT;
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

    /// Here: `new #var` (a precision point) or `new _var` (a cartesian location) where ash
    /// lists none, `here var`, then `w2` and `print var`, which must agree: the pulses with
    /// its PULSES row, a cartesian location with its WORLD row (both as ash prints them, so
    /// no reading of the angles is needed).
    pub(super) fn teach_here(&mut self, name: LocName, tag: Tag) -> BiosResult {
        if let Some(r) = self.standing_only("Here") {
            return r;
        }
        if tag != Tag::Prec && name.is_precision() {
            return Ok(code::BAD_ARGUMENT);
        }
        if tag == Tag::Joint {
            self.note(format!(
                "refused before sending: Here {} in joints: ash keeps no joint locations; use a \
                 precision point (#NAME) or a cartesian location",
                name.as_str()
            ));
            return Ok(UNSUPPORTED);
        }
        let (var, base) = match self.variable(&name, "Here") {
            Ok(v) => v,
            Err(r) => return r,
        };
        if !self.list_vars(base)?.iter().any(|(n, _)| *n == var) {
            let sign = if base == "ploc" { '#' } else { '_' };
            let cmd = format!("new {sign}{var}");
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
        let (agrees, read) = if base == "ploc" {
            let got = self.print_ploc(&var)?;
            let ok = matches!(got, Ploc::At(v)
                if (0..6).all(|j| (v[j] - p.pulses[j]).abs() <= ARRIVE_PULSES));
            (
                ok,
                format!(
                    "{got} with the arm at pulses {}",
                    p.pulses.map(|v| v.to_string()).join(" ")
                ),
            )
        } else {
            let got = self.print_cloc(&var)?;
            // The same place as the WORLD row read just after (the arm's dither apart), in
            // either reading of the angles.
            let ok = matches!(got, cartesian::Cloc::At(w)
            if crate::world::Angles::ALL.iter().any(|&a| {
                let (mm, deg) = crate::world::gap(
                    &crate::world::from_ash(&w, a),
                    &crate::world::from_ash(&p.world, a),
                );
                mm <= cartesian::ARRIVE_MM && deg <= cartesian::ARRIVE_TURN_DEG
            }));
            (
                ok,
                format!("{got} with the WORLD row at {}", join(&p.world)),
            )
        };
        if !agrees {
            return Err(self.unsure(format!(
                "`{cmd}` taken, and then `print {var}` reads {read} (w2): what ash holds under \
                 {var} is not known"
            )));
        }
        self.rests_at(p.joints_deg);
        Ok(code::OK)
    }

    /// Define: ash sets a precision point only with `here` (`set` takes cartesian
    /// constants only, `help constants`), and a cartesian location's values would need the
    /// WORLD row's reading and the tool of the moment: taught with Here instead.
    pub(super) fn teach_define(&mut self, name: LocName) -> BiosResult {
        self.note(format!(
            "refused before sending: Define {}: on a C500C a location is taught where the arm \
             is (TROLHere); ash's `set` takes no precision point, and TROL writes no cartesian \
             location of ash's from values",
            name.as_str()
        ));
        Ok(UNSUPPORTED)
    }

    /// DeleteLocation: `erase var`, its question answered `y`, then ash must list it no
    /// more.
    pub(super) fn teach_delete(&mut self, name: LocName) -> BiosResult {
        if let Some(r) = self.standing_only("DeleteLocation") {
            return r;
        }
        let (var, base) = match self.variable(&name, "DeleteLocation") {
            Ok(v) => v,
            Err(r) => return r,
        };
        if !self.list_vars(base)?.iter().any(|(n, _)| *n == var) {
            return Err(BackendError::UnknownLocation(name));
        }
        let cmd = format!("erase {var}");
        let lines = self.converse(&cmd, &[("and its value?", "y\r")])?;
        if !lines.is_empty() {
            return Err(self.refusal(&cmd, &lines));
        }
        if self.list_vars(base)?.iter().any(|(n, _)| *n == var) {
            return Err(self.unsure(format!(
                "`{cmd}` answered y, and `list {base}` still has {var}"
            )));
        }
        Ok(code::OK)
    }

    /// `list BASE` (its pager answered with a space: TROL asked for the whole list): each
    /// variable of that base type, and whether it is taught.
    pub(super) fn list_vars(&mut self, base: &str) -> Result<Vec<(String, bool)>, BackendError> {
        let cmd = format!("list {base}");
        let lines = self.converse(&cmd, &[("Hit <space> or <q>", " ")])?;
        let Some(rows) = read_list(&lines, base) else {
            return Err(self.unsure(format!(
                "`{cmd}`: ash printed `{}`, not the list form TROL reads",
                lines.join(" | ")
            )));
        };
        Ok(rows)
    }

    /// ListLocations: `list ploc` and `list cloc` (their pager answered with a space: TROL
    /// asked for the whole list), then `print` of each taught one. Untaught ones, names TROL
    /// cannot hold (over 7 or 8 characters), and cartesian ones where the profile has no
    /// `world-angles`, are left out and named in the log.
    pub(super) fn teach_list(&mut self) -> Result<Vec<(LocName, Location)>, BackendError> {
        if let Some(r) = self.standing_only("ListLocations") {
            return match r {
                Err(e) => Err(e),
                Ok(c) => Err(BackendError::Refused(c)),
            };
        }
        // What ash holds, as `trol c500c backup` reads it; then in TROL's forms.
        let held = self.backup()?;
        let mut out = Vec::new();
        let mut left = Vec::new();
        for (var, saved) in held.vars {
            let sign = if matches!(saved, Saved::Ploc(_)) {
                "#"
            } else {
                ""
            };
            let name = LocName::new(&format!("{sign}{var}"))
                .ok()
                .filter(|n| ash_var(n).is_some());
            let Some(name) = name else {
                left.push(format!("{var} (no TROL name: over 8 characters)"));
                continue;
            };
            match saved {
                Saved::Ploc(Some(p)) => {
                    let counts: Option<Vec<i32>> =
                        p.iter().map(|&v| i32::try_from(v).ok()).collect();
                    match counts {
                        Some(c) => out.push((name, Location::Prec(c))),
                        None => left.push(format!("{var} (pulses out of range)")),
                    }
                }
                // The flange as ash keeps it; TROL's tool centre point there, in TROL's
                // angles (which needs the profile's reading of ash's).
                Saved::Cloc(Some(w)) => match self.profile.reading() {
                    Some(angles) => {
                        let tcp = crate::world::from_ash(&w, angles)
                            .then(&trol_a465::kinematics::Pose::from_xyzypr(self.tool))
                            .to_xyzypr();
                        out.push((name, Location::Cart(tcp.to_vec())));
                    }
                    None => left.push(format!(
                        "{var} (cartesian: needs `world-angles` in the profile)"
                    )),
                },
                Saved::Ploc(None) | Saved::Cloc(None) => {
                    left.push(format!("{var} (not taught or not valid)"))
                }
            }
        }
        if !left.is_empty() {
            self.note(format!("ash's locations left out: {}", left.join(", ")));
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
        let said = said(&lines);
        match said[..] {
            [l] if l.starts_with("Saving '") && l.ends_with("done.") => Ok(code::OK),
            _ => Err(self.refusal("save", &lines)),
        }
    }

    /// TROLMove by name: a precision point or a cartesian location of ash's, through the
    /// gate and the queue ([`Self::named_motion`]).
    pub(super) fn move_named(&mut self, name: LocName, straight: bool) -> BiosResult {
        self.named_motion(name, None, straight)
    }

    /// `var` is listed by ash (`list BASE`) and taught; else TROL_ERR_LOCATION.
    pub(super) fn taught_in(
        &mut self,
        base: &str,
        var: &str,
        name: LocName,
    ) -> Result<(), BackendError> {
        match self.list_vars(base)?.iter().find(|(n, _)| n == var) {
            None => Err(BackendError::UnknownLocation(name)),
            Some((_, false)) => Err(BackendError::Explained(
                trol_proto::application::code::TROL_ERR_LOCATION.0,
                format!(
                    "{}: ash has the {base} {var}, not yet taught (or not valid): teach it \
                     (TROLHere) first",
                    name.as_str()
                ),
            )),
            Some((_, true)) => Ok(()),
        }
    }

    /// A move to a precision point of ash's as it goes: listed (its base type as ash lists
    /// it: a variable of another type is not a precision point, whatever `print` shows),
    /// read back (`print`), then `move var` or `moves var`; its end is the arm seen at those
    /// pulses.
    pub(super) fn resolve_ploc(
        &mut self,
        name: LocName,
        straight: bool,
    ) -> Result<Motion, BackendError> {
        let var = ash_var(&name).ok_or(BackendError::UnknownLocation(name))?;
        self.taught_in("ploc", &var, name)?;
        match self.print_ploc(&var)? {
            Ploc::At(p) => Ok(Motion {
                line: format!("{} {var}", if straight { "moves" } else { "move" }),
                kind: Kind::Named(p),
            }),
            other => Err(self.misread("ploc", &var, &other)),
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
            read_list(
                &l(&[
                    "Variables: (* indicates not yet taught)",
                    "  ploc             p1",
                    "  ploc             * p2",
                ]),
                "ploc"
            ),
            Some(vec![("p1".into(), true), ("p2".into(), false)])
        );
        assert_eq!(read_list(&l(&["< no variables >"]), "ploc"), Some(vec![]));
        assert_eq!(read_list(&l(&["  cloc             p1"]), "ploc"), None);
        assert_eq!(
            read_list(&l(&["  cloc             p1"]), "cloc"),
            Some(vec![("p1".into(), true)])
        );
    }

    #[test]
    fn names_map_to_ash_variables() {
        let n = |s: &str| LocName::new(s).unwrap();
        assert_eq!(ash_var(&n("#Pick1")), Some("pick1".into()));
        assert_eq!(ash_var(&n("#a_b")), Some("a_b".into()));
        assert_eq!(ash_var(&n("#1a")), None);
        assert_eq!(ash_var(&n("Pick")), Some("pick".into()));
    }
}

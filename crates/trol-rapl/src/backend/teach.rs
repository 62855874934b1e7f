//! Locations: scratch points read back before a motion names them, the controller's own
//! table (LISTL), the units and conventions the profile has not settled.

use super::*;

impl RaplBackend {
    pub(super) fn unsettled(&mut self, u: Unsettled) -> i16 {
        self.note(format!("refused before sending: {u}"));
        match u {
            Unsettled::Units => NO_UNITS,
            Unsettled::Angles => NO_ANGLES,
            Unsettled::Pulses => NO_PULSES,
        }
    }

    /// A scratch name not used by a motion under way or queued.
    /// Why a teaching command cannot go to the C500 (said in the log), before anything is
    /// sent: a joint location (RAPL-II keeps cartesian locations and precision points), or a
    /// scratch location's name.
    pub(super) fn teach_refusal(&mut self, name: &LocName, tag: Tag) -> Option<i16> {
        if tag == Tag::Joint {
            self.note(
                "refused before sending: RAPL-II keeps cartesian locations and precision \
                 points (#NAME), not joint angles"
                    .into(),
            );
            return Some(UNSUPPORTED);
        }
        if Self::is_scratch(name.as_str()) {
            self.note(format!(
                "refused before sending: {name} is a scratch location of this backend (T1 to \
                 T{}, for MoveII and Appro); choose another name",
                QUEUE + 2
            ));
            return Some(code_of("BIOS_BAD_ARGUMENT"));
        }
        None
    }

    pub(super) fn scratch_name(&mut self) -> String {
        self.scratch = (self.scratch % (QUEUE + 2)) + 1;
        format!("T{}", self.scratch)
    }

    /// Define a scratch location for a TROL target and read it back; the motion line's
    /// target name and what the motion must end at, or the code that refused it.
    pub(super) fn point(
        &mut self,
        loc: &Location,
    ) -> Result<Result<(String, Expect), i16>, BackendError> {
        let name = self.scratch_name();
        self.point_named(name, loc)
    }

    /// Whether `name` (any case) is one of the scratch locations this backend defines for
    /// MoveII and Appro: a program's location of that name would be overwritten.
    pub(super) fn is_scratch(name: &str) -> bool {
        let upper = name.to_ascii_uppercase();
        upper
            .strip_prefix('T')
            .and_then(|n| n.parse::<usize>().ok())
            .is_some_and(|n| (1..=QUEUE + 2).contains(&n))
    }

    /// POINT `name` (upper case; `#` added for a precision point) with `loc`, read back with
    /// LISTL: the RAPL name and what a motion to it must end at, or the code that refused it.
    pub(super) fn point_named(
        &mut self,
        name: String,
        loc: &Location,
    ) -> Result<Result<(String, Expect), i16>, BackendError> {
        let name = name.trim_start_matches('#').to_ascii_uppercase();
        let (name, values, expect) = match loc {
            Location::Cart(_) => match self.frames.to_rapl(loc.to_array6()) {
                Ok(v) => (name, v, Expect::World(v)),
                Err(u) => return Ok(Err(self.unsettled(u))),
            },
            Location::Prec(_) => {
                if self.frames.pulses.is_none() {
                    return Ok(Err(self.unsettled(Unsettled::Pulses)));
                }
                let c = loc.to_array6().map(|x| x.round() as i64);
                (format!("#{name}"), c.map(|x| x as f64), Expect::Pulses(c))
            }
            Location::Joint(_) => {
                let deg = loc.to_array6().map(f64::to_degrees);
                match self.frames.joints_to_pulses(deg) {
                    Ok(c) => (format!("#{name}"), c.map(|x| x as f64), Expect::Joints(deg)),
                    Err(u) => return Ok(Err(self.unsettled(u))),
                }
            }
        };
        let line = if name.starts_with('#') {
            format!("POINT {name} {}", join_int(&values.map(|x| x as i64)))
        } else {
            format!("POINT {name} {}", join(&values))
        };
        // POINT changes a scratch location only: whatever happened to it, no motion was sent.
        match self.command(&line).map_err(not_run)? {
            0 => {}
            c => return Ok(Err(c)),
        }
        // Read it back: the motion names it only if it holds what was sent.
        let back = self.output(&format!("LISTL {name}"))?;
        let rows = text::read_listl(&back.text).map_err(BackendError::Link)?;
        let held = rows.into_iter().find(|(n, _)| *n == name).map(|(_, l)| l);
        let same = match (&held, &expect) {
            (Some(Listed::Cart(v)), Expect::World(w)) => {
                v.iter().zip(w).all(|(a, b)| (a - b).abs() <= 0.002)
            }
            (Some(Listed::Prec(p)), _) => p.iter().zip(&values).all(|(a, b)| *a as f64 == *b),
            _ => false,
        };
        if !same {
            let e = format!(
                "`{line}` was answered with success, but LISTL {name} reads {held:?}: the \
                 scratch location does not hold the target, so no motion was sent"
            );
            self.note(e.clone());
            return Err(BackendError::Link(e));
        }
        Ok(Ok((name, expect)))
    }

    pub(super) fn move_pose(&mut self, pose: &Pose, straight: bool, busy: bool) -> BiosResult {
        let loc = Location::from_array6(Tag::Cart, pose.to_xyzypr());
        match self.point(&loc)? {
            Ok((n, expect)) => self.submit(
                Motion {
                    line: format!("{} {n}", mv(straight)),
                    expect,
                },
                busy,
            ),
            Err(c) => Ok(c),
        }
    }

    /// A location of the controller's table, or None when it has none of the name.
    pub(super) fn listed(&mut self, name: &LocName) -> Result<Option<Listed>, BackendError> {
        let upper = name.as_str().to_ascii_uppercase();
        let line = format!("LISTL {upper}");
        let t = self.reply_timeout();
        let r = self.exchange(&line, t)?;
        let r = match self.answer(&line, r, true)? {
            Answer::Refused(..) => return Ok(None),
            Answer::Done(r) => r,
        };
        let rows = text::read_listl(&r.text).map_err(BackendError::Link)?;
        Ok(rows.into_iter().find(|(n, _)| *n == upper).map(|(_, l)| l))
    }

    /// The pose of a listed location (a cartesian one needs the profile's conventions, a
    /// precision point its pulses).
    pub(super) fn pose_of(&mut self, l: Listed) -> Result<Pose, i16> {
        Ok(match l {
            Listed::Cart(v) => match self.frames.from_rapl(v) {
                Ok(t) => Pose::from_xyzypr(t),
                Err(u) => return Err(self.unsettled(u)),
            },
            Listed::Prec(p) => match self.frames.pulses_to_joints(p) {
                Ok(deg) => self.kin().fk(&deg.map(f64::to_radians)),
                Err(u) => return Err(self.unsettled(u)),
            },
        })
    }
}

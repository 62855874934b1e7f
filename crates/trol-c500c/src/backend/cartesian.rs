//! Cartesian motions through ash's cartesian locations (docs/c500c.md, "Cartesian motions"):
//! TROL plans the motion on the A465 model from where the arm rests (reach, joint limits, the
//! table, the time), writes the flange's end into its own `cloc` variable `trolgo` (`set
//! _trolgo = {x, y, z, a, b, c, 0, 0}`, `setvalid trolgo`), reads it back (`print trolgo`)
//! and sends `move trolgo` or `moves trolgo`. A cartesian location of ash's own, by name, is
//! read back and moved to as it is.
//!
//! What the profile states is checked against the arm before each motion: `w2`'s WORLD row,
//! read in the profile's `world-angles`, must put the flange where TROL's kinematics put it
//! from the JOINTS row (within [`AGREE_MM`] and [`AGREE_DEG`]); a tool or base transform set
//! in ash, other units or another reading of the angles make them disagree, and nothing is
//! sent. The end is the flange read (from `w2`'s JOINTS) at the planned end.

use trol_a465::kinematics::Pose;

use super::*;
use crate::world::{self, Angles, Reading};

/// TROL's own cartesian location in the application (a `cloc`).
pub const SCRATCH: &str = "trolgo";
/// How far apart the WORLD row and TROL's kinematics may put the flange and agree, mm.
pub const AGREE_MM: f64 = 0.5;
/// ... and degrees.
pub const AGREE_DEG: f64 = 0.1;
/// How far the flange may stand from a cartesian motion's end and be at it, mm (assumed).
pub const ARRIVE_MM: f64 = 0.5;
/// ... and degrees.
pub const ARRIVE_TURN_DEG: f64 = 0.1;
/// How far apart the two readings of the angles must put a pose for the WORLD row there to
/// tell them apart, degrees.
pub const TELLS_APART_DEG: f64 = 1.0;
/// How far apart the WORLD row's first and last angle must be for `print` of a location
/// `here` set to tell their order, degrees.
const CLOC_APART_DEG: f64 = 1.0;
/// How far apart a motion's end's first and last angle may be for their order not to matter,
/// degrees (the rows' three decimals).
const CLOC_SAME: f64 = 0.05;
/// How far a location `here` set just now may read from the WORLD row read just before, mm
/// and degrees: the resting arm's dither between the two reads (a CI run under load saw
/// 0.051 degrees). Well below [`CLOC_APART_DEG`], so that angles in another order (at least
/// that far apart) never pass for the same.
const CLOC_DITHER: f64 = 0.3;

/// An angle's difference as a turn, -180 to 180 degrees (ash may print -180 or 180 for the
/// same angle).
fn turn_deg(d: f64) -> f64 {
    (d + 180.0).rem_euclid(360.0) - 180.0
}

/// Whether a location `here` set where the arm rests tells the order of its angles: the
/// WORLD row's first and last angle apart, and its middle one away from ±90 degrees (where
/// the first and last are not one pose's alone, and the encoders' dither moves them).
pub(crate) fn cloc_order_tells(world: &[f64; 6]) -> bool {
    turn_deg(world[3] - world[5]).abs() > CLOC_APART_DEG && world[4].abs() < 80.0
}

/// Whether two rows of values as ash prints them are one pose's, as read a moment apart.
pub(crate) fn same_values(a: &[f64; 6], b: &[f64; 6]) -> bool {
    (0..3).all(|j| (a[j] - b[j]).abs() <= CLOC_DITHER)
        && (3..6).all(|j| turn_deg(a[j] - b[j]).abs() <= CLOC_DITHER)
}

/// How far apart the two readings put values as ash prints them, degrees.
fn readings_differ(v: &[f64; 6]) -> f64 {
    world::gap(
        &world::from_ash(v, Angles::Zyx),
        &world::from_ash(v, Angles::Xyz),
    )
    .1
}

/// What `print NAME` said of a cartesian location.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Cloc {
    Missing,
    Untaught,
    /// x, y, z (mm), the three angles (degrees), as ash prints them.
    At([f64; 6]),
}

impl std::fmt::Display for Cloc {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Cloc::Missing => write!(f, "no such variable"),
            Cloc::Untaught => write!(f, "a location not yet taught"),
            Cloc::At(w) => write!(f, "{}", join(w)),
        }
    }
}

/// `print`'s lines of a cartesian location: one row of six numbers (two more, the extra
/// axes, may follow on a second row).
pub(crate) fn read_cloc(lines: &[String]) -> Option<Cloc> {
    let said = said(lines);
    let nums = |l: &str| -> Option<Vec<f64>> {
        let v: Vec<f64> = l
            .split_whitespace()
            .map(|w| w.parse::<f64>())
            .collect::<Result<_, _>>()
            .ok()?;
        v.iter().all(|x| x.is_finite()).then_some(v)
    };
    match said[..] {
        [l] if teach::not_found(l) => Some(Cloc::Missing),
        ["Location has not been taught"] => Some(Cloc::Untaught),
        [row] => Some(Cloc::At(nums(row)?.try_into().ok()?)),
        [row, extra] if nums(extra)?.len() == 2 => Some(Cloc::At(nums(row)?.try_into().ok()?)),
        _ => None,
    }
}

/// The flange where TROL's kinematics put it for joints in degrees.
pub(super) fn flange(joints_deg: &[f64; 6]) -> Pose {
    Kinematics::new([0.0; 6]).fk(&joints_deg.map(f64::to_radians))
}

/// Whether the flange read at `joints_deg` stands at `target`.
pub(super) fn at_pose(joints_deg: &[f64; 6], target: &Pose) -> bool {
    let (mm, deg) = world::gap(&flange(joints_deg), target);
    mm <= ARRIVE_MM && deg <= ARRIVE_TURN_DEG
}

/// A cartesian call: where it goes.
#[derive(Clone, Copy, Debug)]
pub(super) enum CartCall {
    /// MoveII (the tool centre point, TROL's x y z yaw pitch roll).
    Move([f64; 6]),
    /// ApproII, or Appro of a location already read: the location, the displacement.
    Appro([f64; 6], [f64; 6]),
    /// Depart by a displacement in the tool frame.
    Depart([f64; 6]),
    /// Jog by dx dy dz in the world frame.
    Jog([f64; 3]),
}

/// A motion worked out as it goes (when TROL sends it, after the motions before it have
/// ended): its locations read, and planned from where the arm rests then.
#[derive(Clone, Copy, Debug)]
pub(super) enum Pending {
    /// A cartesian motion of TROL's, straight or not.
    Cart(CartCall, bool),
    /// To a location of ash's by name (an approach to it where there is a displacement).
    Named(LocName, Option<[f64; 6]>, bool),
}

/// A refusal noted, as the error it is.
fn refused(c: i16) -> BackendError {
    BackendError::Refused(c)
}

impl C500cBackend {
    /// What the profile must state for a cartesian motion, and metric units. `Err`: refused
    /// before sending (noted).
    fn cart_keys(&mut self) -> Result<Reading, BackendError> {
        if self.profile.motion_return.is_none() {
            self.unsettled(
                "a motion needs to know when ash gives its prompt back: set `motion-return` in \
                 the C500C profile",
            )?;
            return Err(refused(UNSETTLED));
        }
        let Some(angles) = self.profile.reading() else {
            self.unsettled(
                "a cartesian motion needs how the WORLD row's Z-Rot, Y-Rot and X-Rot compose: \
                 set `world-angles = \"zyx\"` or `\"xyz\"` in the C500C profile (`trol c500c \
                 step world-angles` reads it off the arm)",
            )?;
            return Err(refused(UNSETTLED));
        };
        if !self.stat.metric {
            self.unsettled(
                "ash's units are imperial (armstat): TROL plans in millimetres; set `units` to \
                 metric at the controller",
            )?;
            return Err(refused(UNSETTLED));
        }
        Ok(angles)
    }

    /// Where the arm rests (`w2`): its WORLD row, read in the profile's reading, must put the
    /// flange where TROL's kinematics put it from the JOINTS row.
    fn world_check(&mut self, angles: Reading) -> Result<[f64; 6], BackendError> {
        let p = self.read_position(true)?;
        self.rests_at(p.joints_deg);
        let (mm, deg) = world::gap(&world::from_ash(&p.world, angles), &flange(&p.joints_deg));
        if mm > AGREE_MM || deg > AGREE_DEG {
            self.unsettled(&format!(
                "ash's WORLD row ({}) read as `{}` is {mm:.2} mm and {deg:.2} degrees from \
                 where TROL's A465 kinematics put the flange for the JOINTS row ({}): a tool \
                 or base transform set in ash (`tool`, `base`), or a `world-angles` or \
                 `tool-rotation` that is not the arm's (`trol c500c step world-angles` reads \
                 both)",
                join(&p.world),
                angles.words(),
                join(&p.joints_deg)
            ))?;
            return Err(refused(UNSETTLED));
        }
        if readings_differ(&p.world) > TELLS_APART_DEG {
            // A pose where the other reading would be off by more than a degree, and the
            // profile's agrees: it is the arm's.
            self.angles_seen = true;
        }
        Ok(p.world)
    }

    /// A cartesian location's constant holds the WORLD row's values in the row's order (not
    /// public: `help constants` names `{x, y, z, yaw, pitch, roll, e1, e2}`, the WORLD row
    /// heads its angles Z-Rot Y-Rot X-Rot). Seen once a session, reading only what TROL's own
    /// `trolgo` holds: where the arm rests with its first and last angle apart, `here
    /// trolgo`, then `print trolgo` must read the WORLD row just read (`world`) in its order.
    /// In the reverse order (the twin's variant `cloc-reversed`), or any other, every
    /// location TROL would write or read is refused (BIOS_UNSETTLED), nothing moved. Until
    /// seen, a motion whose end (`v`, in the WORLD row's order) has its first and last angle
    /// apart is refused too, with what to do.
    fn cloc_order(&mut self, world: &[f64; 6], v: &[f64; 6]) -> Result<(), BackendError> {
        if self.cloc_order_seen {
            return Ok(());
        }
        if cloc_order_tells(world) {
            if self.print_cloc(SCRATCH)? == Cloc::Missing {
                let cmd = format!("new _{SCRATCH}");
                let lines = self.exchange(&cmd).map_err(|e| self.fail(e))?;
                if !lines.is_empty() {
                    return Err(self.refusal(&cmd, &lines));
                }
            }
            let cmd = format!("here {SCRATCH}");
            let lines = self.exchange(&cmd).map_err(|e| self.fail(e))?;
            if !lines.is_empty() {
                return Err(self.refusal(&cmd, &lines));
            }
            let got = match self.print_cloc(SCRATCH)? {
                Cloc::At(w) => w,
                other => return Err(self.misread("cloc", SCRATCH, &other)),
            };
            if same_values(&got, world) {
                self.cloc_order_seen = true;
                return Ok(());
            }
            self.unsettled(&format!(
                "`here {SCRATCH}` then `print {SCRATCH}` reads {} where the WORLD row read {}: \
                 ash's cartesian locations do not hold the WORLD row's values in its order, \
                 and TROL writes and reads none there (cartesian motions and named cartesian \
                 locations stay refused; joint motions and precision points work)",
                join(&got),
                join(world)
            ))?;
            return Err(refused(UNSETTLED));
        }
        if turn_deg(v[3] - v[5]).abs() <= CLOC_SAME || self.profile.cloc_world_order {
            // Its order does not matter for this end, or the step saw it on this arm.
            return Ok(());
        }
        self.unsettled(&format!(
            "this motion's end ({}) depends on the order of a cartesian location's angles, \
             which TROL has not yet seen on this controller: turn a wrist joint by 0.3 rad \
             (TROLJoint 4) so that the WORLD row's first and last angles differ, and try again \
             (`trol c500c step world-angles` sees it once and writes `cloc-world-order`)",
            join(v)
        ))?;
        Err(refused(UNSETTLED))
    }

    /// A motion's end, as ash will read it: where the two readings of the angles differ,
    /// the profile's must have been seen to be the arm's in this session.
    fn reading_settled(&mut self, v: &[f64; 6]) -> Result<(), BackendError> {
        if self.angles_seen || readings_differ(v) <= AGREE_DEG {
            return Ok(());
        }
        self.unsettled(&format!(
            "this motion's end ({}) reads differently in the two readings of the WORLD row's \
             angles, and TROL has not yet seen the arm agree with the profile's `world-angles` \
             at a pose where they differ: turn a wrist joint first (TROLJoint 4 by 0.3 rad) \
             and try again, or check the profile with `trol c500c step world-angles`",
            join(v)
        ))?;
        Err(refused(UNSETTLED))
    }

    /// Plan a cartesian motion from where the arm rests on the A465 model with TROL's tool:
    /// the flange's end and the time, or the model's refusal.
    fn cart_plan(&self, call: CartCall, straight: bool) -> Result<(Pose, Duration), i16> {
        let mut arm = Arm::new(ArmSettings {
            homed: true,
            ..ArmSettings::default()
        });
        arm.place(self.rest.map(f64::to_radians));
        arm.set_speed(f64::from(self.speed.max(1)));
        arm.set_tool(self.tool);
        let c = match call {
            CartCall::Move(v) => arm.move_to(trol_a465::arm::Target::Cart(v), straight, 0.0),
            CartCall::Appro(v, d) => arm.appro(trol_a465::arm::Target::Cart(v), d, straight, 0.0),
            CartCall::Depart(d) => arm.depart(d, straight, 0.0),
            CartCall::Jog(d) => arm.jog(d, straight, 0.0),
        };
        if c != code::OK {
            return Err(c);
        }
        let end = arm.planned_end();
        let secs = arm.done_at(0.0).clamp(0.0, 600.0);
        Ok((
            Kinematics::new([0.0; 6]).fk(&end),
            Duration::from_secs_f64(secs),
        ))
    }

    /// `print VAR` read as a cartesian location; any other form is UNSURE.
    pub(super) fn print_cloc(&mut self, var: &str) -> Result<Cloc, BackendError> {
        let cmd = format!("print {var}");
        let lines = match self.exchange(&cmd) {
            Ok(l) => l,
            Err(e) => return Err(self.fail(e)),
        };
        read_cloc(&lines).ok_or_else(|| {
            self.unsure(format!(
                "`{cmd}`: ash printed `{}`, not a cartesian location in the form TROL reads (a \
                 row of six values): TROL moves to no location it cannot read",
                lines.join(" | ")
            ))
        })
    }

    /// A cartesian motion of TROL's (MoveII, ApproII, Depart, Jog): through the gate and the
    /// queue; worked out as it goes ([`Self::resolve`]).
    pub(super) fn cart_motion(&mut self, call: CartCall, straight: bool) -> BiosResult {
        self.clean()?;
        self.cart_keys()?;
        self.motion(Motion {
            line: format!("{call:?}"),
            kind: Kind::Pending(Pending::Cart(call, straight)),
        })
    }

    /// To a location of ash's by name (Move, or Appro with `disp`): through the gate and
    /// the queue; its values read as it goes.
    pub(super) fn named_motion(
        &mut self,
        name: LocName,
        disp: Option<[f64; 6]>,
        straight: bool,
    ) -> BiosResult {
        self.clean()?;
        let Some(var) = teach::ash_var(&name) else {
            return Err(BackendError::UnknownLocation(name));
        };
        // A name ash does not have is TROL_ERR_LOCATION whatever the arm's state (issue 62:
        // with the power off it was BIOS_ARM_POWER): looked up before the gate, where the
        // motion would go now (one queued is looked up when its turn comes).
        if self.outstanding.is_none() && self.queue.is_empty() && !self.console_busy() {
            let base = if name.is_precision() { "ploc" } else { "cloc" };
            self.taught_in(base, &var, name)?;
        }
        if !name.is_precision() || disp.is_some() {
            self.cart_keys()?;
        }
        if name.is_precision() && disp.is_some() {
            self.pulses_keys()?;
        }
        self.motion(Motion {
            line: format!(
                "{} {}",
                if disp.is_some() { "Appro" } else { "Move" },
                name.as_str()
            ),
            kind: Kind::Pending(Pending::Named(name, disp, straight)),
        })
    }

    /// Work out a motion as it goes: the ash line to send and what its end is.
    pub(super) fn resolve(&mut self, p: Pending) -> Result<Motion, BackendError> {
        match p {
            Pending::Cart(call, straight) => self.resolve_cart(call, straight),
            Pending::Named(name, None, straight) if name.is_precision() => {
                self.resolve_ploc(name, straight)
            }
            Pending::Named(name, Some(disp), straight) if name.is_precision() => {
                self.resolve_ploc_appro(name, disp, straight)
            }
            Pending::Named(name, disp, straight) => {
                let var = teach::ash_var(&name).ok_or(BackendError::UnknownLocation(name))?;
                self.taught_in("cloc", &var, name)?;
                let angles = self.cart_keys()?;
                let world = self.world_check(angles)?;
                let w = match self.print_cloc(&var)? {
                    Cloc::At(w) => w,
                    other => return Err(self.misread("cloc", &var, &other)),
                };
                self.reading_settled(&w)?;
                self.cloc_order(&world, &w)?;
                // The location is the flange (ash's tool is the null one: the check saw
                // it); TROL's tool centre point there.
                let tcp = world::from_ash(&w, angles)
                    .then(&Pose::from_xyzypr(self.tool))
                    .to_xyzypr();
                if let Some(d) = disp {
                    return self.resolve_cart(CartCall::Appro(tcp, d), straight);
                }
                let (end, planned) =
                    self.cart_plan(CartCall::Move(tcp), straight).map_err(|c| {
                        self.note(format!(
                        "refused before sending: the A465 model refuses the motion to {var} ({c})"
                    ));
                        refused(c)
                    })?;
                Ok(Motion {
                    line: format!("{} {var}", if straight { "moves" } else { "move" }),
                    kind: Kind::Pose(end, planned.as_secs_f64()),
                })
            }
        }
    }

    /// A cartesian motion of TROL's as it goes: the WORLD row checked, the plan, `trolgo`
    /// set, made valid and read back; then `move trolgo` or `moves trolgo`.
    pub(super) fn resolve_cart(
        &mut self,
        call: CartCall,
        straight: bool,
    ) -> Result<Motion, BackendError> {
        let angles = self.cart_keys()?;
        let world = self.world_check(angles)?;
        let (end, planned) = self.cart_plan(call, straight).map_err(|c| {
            self.note(format!(
                "refused before sending: the A465 model refuses the motion ({c})"
            ));
            refused(c)
        })?;
        let v = world::to_ash(&end, angles);
        self.reading_settled(&v)?;
        self.cloc_order(&world, &v)?;
        if self.print_cloc(SCRATCH)? == Cloc::Missing {
            let cmd = format!("new _{SCRATCH}");
            let lines = self.exchange(&cmd).map_err(|e| self.fail(e))?;
            if !lines.is_empty() {
                return Err(self.refusal(&cmd, &lines));
            }
        }
        let values: Vec<String> = v.iter().copied().map(fmt3).collect();
        let cmd = format!("set _{SCRATCH} = {{{}, 0, 0}}", values.join(", "));
        let lines = self.exchange(&cmd).map_err(|e| self.fail(e))?;
        if !lines.is_empty() {
            return Err(self.refusal(&cmd, &lines));
        }
        // What was set is read back before it is made valid (issue 62: `setvalid` came first);
        // TROL asked for the flag: it has planned the motion on the arm's model.
        match self.print_cloc(SCRATCH)? {
            Cloc::At(got) if (0..6).all(|j| (got[j] - v[j]).abs() <= 0.0015) => {}
            other => {
                return Err(self.unsure(format!(
                    "`{cmd}` taken, and `print {SCRATCH}` then reads {other}, not the values \
                     set ({}): nothing moved",
                    values.join(", ")
                )));
            }
        }
        let cmd = format!("setvalid {SCRATCH}");
        let lines = self.converse(&cmd, &[("Set the valid flag anyway (y/n) ?", "y\r")])?;
        let warned = "WARNING: moving to an incorrect location can damage the robot.";
        if lines
            .iter()
            .any(|l| !l.trim().is_empty() && l.trim() != warned)
        {
            return Err(self.refusal(&cmd, &lines));
        }
        Ok(Motion {
            line: format!("{} {SCRATCH}", if straight { "moves" } else { "move" }),
            kind: Kind::Pose(end, planned.as_secs_f64()),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_location_read_with_the_arm_s_dither_is_the_same_and_one_in_another_order_is_not() {
        // As a CI run under load read them: `print trolgo` after `here`, and the WORLD row.
        let got = [419.999, -30.012, 200.007, 22.645, 73.920, -18.781];
        let world = [419.991, -29.985, 199.982, 22.696, 73.924, -18.832];
        assert!(cloc_order_tells(&world));
        assert!(same_values(&got, &world));
        // The first and last angle the other way round: at least CLOC_APART_DEG apart.
        let reversed = [got[0], got[1], got[2], got[5], got[4], got[3]];
        assert!(!same_values(&reversed, &world));
        let barely = [
            420.0,
            -30.0,
            200.0,
            10.0,
            45.0,
            10.0 + CLOC_APART_DEG + 0.01,
        ];
        let swapped = [420.0, -30.0, 200.0, barely[5], 45.0, barely[3]];
        assert!(cloc_order_tells(&barely) && !same_values(&swapped, &barely));
    }

    fn l(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn print_of_a_cartesian_location_is_read_exactly() {
        assert_eq!(
            read_cloc(&l(&["  +400.000 +0.000 +150.000 +0.000 +90.000 +0.000"])),
            Some(Cloc::At([400.0, 0.0, 150.0, 0.0, 90.0, 0.0]))
        );
        assert_eq!(
            read_cloc(&l(&["1 2 3 4 5 6", "0 0"])),
            Some(Cloc::At([1.0, 2.0, 3.0, 4.0, 5.0, 6.0]))
        );
        assert_eq!(read_cloc(&l(&["p = {1, 2, 3, 4, 5, 6}"])), None);
        assert_eq!(read_cloc(&l(&["1 2 3 4 5"])), None);
        assert_eq!(read_cloc(&l(&["1 2 3 4 5 nan"])), None);
        assert_eq!(
            read_cloc(&l(&["Location has not been taught"])),
            Some(Cloc::Untaught)
        );
        assert_eq!(
            read_cloc(&l(&["error: variable not found."])),
            Some(Cloc::Missing)
        );
    }
}

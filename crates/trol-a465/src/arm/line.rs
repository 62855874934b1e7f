//! Straight lines (MOVES, APPRO and DEPART straight, a straight Jog): the line in joint
//! space within the arm's limits, its timing, and why a line is refused (docs/a465.md,
//! "Straight lines").

use super::*;

/// The largest change of any joint between two neighbouring samples of a straight line,
/// radians (1°): where the inverse kinematics needs a bigger step however close the samples,
/// the line jumps (a singularity), and it is refused.
pub(super) const LINE_STEP: f64 = std::f64::consts::PI / 180.0;

/// Samples of a straight line closer than this in s are not split further.
pub(super) const LINE_MIN_H: f64 = 1e-7;

/// How far the executed joint path may leave the straight line between samples: mm, and
/// radians of orientation.
pub(super) const LINE_TOLERANCE_MM: f64 = 0.01;

pub(super) const LINE_TOLERANCE_RAD: f64 = 1e-4;

/// Most samples a straight line may need.
pub(super) const LINE_MAX_SAMPLES: usize = 200_000;

/// Stretches of the time grid per segment of a straight line's spline ([`Profile::along`]).
pub(super) const LINE_PIECES: usize = 4;

/// What to do about a straight line the arm cannot follow.
pub(super) const LINE_ADVICE: &str = "go through a point off the line first (a joint move to it), or move there in joints \
     (straight 0)";

/// Points of a refused straight line checked for a configuration within the limits.
pub(super) const LINE_CHECKS: usize = 200;

/// Beyond this many segments, one stretch each.
pub(super) const LINE_MANY_SEGMENTS: usize = 5_000;

/// The longest a straight line may take, as a multiple of the least time it needs (its
/// joints' joint-interpolated move between the same ends, or its length at the linear
/// limits, whichever is longer): a line that needs more passes too near a singular pose,
/// where the wrist would have to turn far faster than the tool moves, and is refused with
/// SINGULAR_PATH before anything moves (docs/a465.md, "Straight lines").
pub const LINE_MAX_FACTOR: f64 = 20.0;

/// Where along a line its leaving direction is read (s; a turn of the free joints at a
/// singular pose aims there): near enough that the free joints are as at the start, far
/// enough that the wrist is clear of J5 = 0 by more than the inverse kinematics' band.
pub(super) const LINE_PROBE: f64 = 1e-5;

/// The probe's distance along a line, and farther: multiples of it.
pub(super) const LINE_PROBE_FARTHER: [f64; 3] = [1.0, 10.0, 100.0];

/// Starts nearer than this in every joint (rad) are one: the line read a little farther on
/// gives the same way with the free joints a little on.
pub(super) const LINE_SAME_START: f64 = 3e-3;

/// The same in the eased parameter σ of a line from the stretched elbow ([`Ease`]), where
/// the joints go as σ.
pub(super) const LINE_PROBE_EASED: f64 = 1e-4;

/// And a line is refused for its time only when it would take this much longer still, s: a
/// line whose ends are (nearly) the same pose needs no time, and its few stretches a little.
pub const LINE_SLACK: f64 = 0.1;

/// The joints in words, for the planner's messages.
pub(super) const JOINT_NAMES: [&str; 6] = [
    "the waist (J1)",
    "the shoulder (J2)",
    "the elbow (J3)",
    "the forearm's roll (J4)",
    "the wrist (J5)",
    "the flange (J6)",
];

/// Where along a line (s) its leaving direction is read: [`LINE_PROBE`], or
/// [`LINE_PROBE_EASED`] in σ from the stretched elbow.
pub(super) fn line_probe(ease: Ease) -> f64 {
    match ease {
        Ease::None | Ease::Out => LINE_PROBE,
        Ease::In | Ease::Both => ease.at(LINE_PROBE_EASED).0,
    }
}

pub(super) fn line_pose(from: &Pose, to: &Pose, q_from: &DQuat, q_to: &DQuat, s: f64) -> Pose {
    Pose {
        pos: from.pos.lerp(to.pos, s),
        rot: glam::DMat3::from_quat(q_from.slerp(*q_to, s)),
    }
}

/// How a straight line's path parameter maps to the distance along it: s(σ). Where the
/// line starts or ends with the elbow stretched (J3 = 0: READY), the elbow and shoulder
/// joints go as the square root of the distance (the law of cosines at its edge), which no
/// spline in the distance follows; in σ with s = σ² (or its mirror at the end) they go as σ,
/// smoothly, and the time profile keeps the tool's linear limits through ds/dσ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Ease {
    /// s = σ.
    None,
    /// s = σ²: the elbow stretched at the start.
    In,
    /// s = 2σ - σ²: the elbow stretched at the end.
    Out,
    /// s = 3σ² - 2σ³: at both ends.
    Both,
}

impl Ease {
    /// The easing for a line whose elbow starts at `j3_start` and ends at `j3_end` (radians
    /// from stretched).
    fn for_elbow(j3_start: f64, j3_end: f64) -> Ease {
        match (
            j3_start.abs() < STRETCHED_ELBOW,
            j3_end.abs() < STRETCHED_ELBOW,
        ) {
            (false, false) => Ease::None,
            (true, false) => Ease::In,
            (false, true) => Ease::Out,
            (true, true) => Ease::Both,
        }
    }

    /// s(σ), ds/dσ, d²s/dσ².
    fn at(self, x: f64) -> (f64, f64, f64) {
        match self {
            Ease::None => (x, 1.0, 0.0),
            Ease::In => (x * x, 2.0 * x, 2.0),
            Ease::Out => (2.0 * x - x * x, 2.0 - 2.0 * x, -2.0),
            Ease::Both => (
                3.0 * x * x - 2.0 * x * x * x,
                6.0 * x - 6.0 * x * x,
                6.0 - 12.0 * x,
            ),
        }
    }

    /// The largest |ds/dσ| and |d²s/dσ²| on [a, b].
    fn bounds(self, a: f64, b: f64) -> (f64, f64) {
        let d1 = |x: f64| self.at(x).1.abs();
        let d2 = |x: f64| self.at(x).2.abs();
        let mut m1 = d1(a).max(d1(b));
        if self == Ease::Both && a < 0.5 && b > 0.5 {
            m1 = m1.max(d1(0.5));
        }
        (m1, d2(a).max(d2(b)))
    }
}

/// The straight line of the tool from one pose to another.
pub(super) struct Line {
    pub(super) from: Pose,
    pub(super) to: Pose,
    pub(super) q_from: DQuat,
    pub(super) q_to: DQuat,
}

impl Line {
    fn new(from: Pose, to: Pose) -> Line {
        let (q_from, mut q_to) = (DQuat::from_mat3(&from.rot), DQuat::from_mat3(&to.rot));
        // The shorter way round.
        if q_from.dot(q_to) < 0.0 {
            q_to = -q_to;
        }
        Line {
            from,
            to,
            q_from,
            q_to,
        }
    }

    fn at(&self, s: f64) -> Pose {
        line_pose(&self.from, &self.to, &self.q_from, &self.q_to, s)
    }
}

/// How far a pose is from another: mm, and radians of orientation.
pub(super) fn pose_error(a: &Pose, b: &Pose) -> (f64, f64) {
    let dp = (a.pos - b.pos).length();
    let dq = DQuat::from_mat3(&a.rot).angle_between(DQuat::from_mat3(&b.rot));
    (dp, dq)
}

/// [`max_step`] with each joint's difference taken the short way round.
pub(super) fn wrapped_step(a: &Joints, b: &Joints) -> f64 {
    (0..6).map(|i| wrap(a[i] - b[i]).abs()).fold(0.0, f64::max)
}

/// What the planner found for a straight line (the survey's and the tests' view of it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LineOutcome {
    /// Accepted.
    Accepted {
        /// The least time any arm within the A465's limits needs for this line from where
        /// it stood, s: the turn of the free joints the way along it needs first (none off
        /// a singular pose), then the longer of the joint-interpolated move between the
        /// line's ends and its length at the tool's linear limits; the fastest way counts.
        least: f64,
    },
    /// Refused, and no arm follows it: every way along the line from where the arm stands
    /// meets a joint limit, or a point of it has no configuration within the limits.
    Blocked,
    /// Refused: the line meets a singular pose where the joints would jump, or it would take
    /// too long near one.
    Singular,
}

/// Where planning a straight line failed: its code, how far along the line (0..1), and the
/// joints there.
#[derive(Clone, Copy, Debug)]
pub(super) struct LineFail {
    pub(super) code: i16,
    pub(super) at: f64,
    pub(super) q: Joints,
}

impl Arm {
    pub(super) fn linear_limits(&self) -> (f64, f64) {
        let f = self.speed.clamp(1.0, 100.0) / 100.0;
        (MAX_LINEAR_SPEED * f, MAX_LINEAR_ACCEL * f)
    }

    /// A straight line's path of `length` mm timed along it ([`Profile::along`]) from
    /// `start`, within the joint limits at the speed setting and the tool's linear limits.
    pub(super) fn line_profile(&self, path: &Path, length: f64, start: f64, ease: Ease) -> Profile {
        let (speeds, accels) = self.joint_limits_at(self.speed);
        let lin = self.linear_limits();
        // A line with very many samples (near a singular pose) gets one stretch per segment:
        // its grid is fine already, and the memory stays bounded.
        let per = if path.segments() > LINE_MANY_SEGMENTS {
            1
        } else {
            LINE_PIECES
        };
        let stretches = path
            .pieces(per)
            .iter()
            .map(|(s0, s1, b)| {
                let (e1, e2) = ease.bounds(*s0, *s1);
                let linear = Some((length * e1, length * e2, lin));
                Stretch::new(*s0, *s1, b, &speeds, &accels, linear)
            })
            .collect();
        Profile::along(start, stretches)
    }

    /// The least time a straight line from `from` to `to` (joints) of `length` mm needs: the
    /// joint-interpolated move between its ends at the speed setting, or its length at the
    /// tool's linear limits, whichever takes longer.
    pub fn line_least_time(&self, from: Joints, to: Joints, length: f64) -> f64 {
        let (speeds, accels) = self.joint_limits_at(self.speed);
        let (v, a) = Path::Joint { from, to }.bounds().limits(&speeds, &accels);
        let joints = Profile::trapezoid(0.0, v, a, 0.0).end();
        let (lv, la) = self.linear_limits();
        let linear = if length > 0.0 {
            Profile::trapezoid(0.0, lv / length, la / length, 0.0).end()
        } else {
            0.0
        };
        joints.max(linear)
    }

    /// Accept a straight-line motion of the tool centre point to `to`, orientation
    /// interpolated, after checking the whole path (docs/a465.md, "Straight lines"). From a
    /// singular pose (J5 = 0; READY, the wrist centre on the base axis) the joints the pose
    /// leaves free may first turn, the tool standing still, to where the line leaves it
    /// ([`Arm::line_starts`]); the turn is a motion of its own before the line, and its time
    /// counts in the line's.
    pub(super) fn move_line(&mut self, to: Pose, now: f64) -> i16 {
        // Set below once the planner has a verdict; refused before it (not homed, out of
        // reach, below the table), the line has none.
        self.last_line = None;
        if let Err(c) = self.need_homed(now) {
            return c;
        }
        let q0 = self.planned_end();
        // The target first: out of reach is the clearer answer than whatever fails on the
        // way there.
        if self.kin.ik_all(&to, &q0).is_empty() {
            return code::OUT_OF_REACH;
        }
        let from = self.kin.fk(&q0);
        // The line is straight, so its ends bound its height.
        if self.lowest_z(&from).min(self.lowest_z(&to)) < self.settings.table_z - 1e-9 {
            return code::BELOW_TABLE;
        }
        let line = Line::new(from, to);
        let length = (to.pos - from.pos).length();
        let start = self.planned_start_time(now);
        let (speeds, accels) = self.joint_limits_at(self.speed);
        // The line from where the arm is; if it is slow or refused, from each place the free
        // joints can turn to first: the fastest wins.
        let mut best: Option<(f64, Option<Path>, Path, Profile)> = None;
        let mut farthest: Option<LineFail> = None;
        let mut least = f64::INFINITY;
        // Whether every start that leaves the way the line does later meets a joint limit
        // (a start that cannot even reach the probe point smoothly is not aimed along the
        // line: its free joints point elsewhere).
        let mut limits_everywhere = true;
        let mut any_limit = false;
        // |J3| at the target: the same in every configuration (the wrist centre's distance
        // from the shoulder fixes it).
        let j3_end = self
            .kin
            .ik_all(&to, &q0)
            .as_slice()
            .first()
            .map_or(1.0, |s| s.q[2].abs());
        let starts = self.line_starts(&line, q0, Ease::for_elbow(q0[2], j3_end));
        for (k, q_start) in starts.iter().enumerate() {
            // Before trying the turns: a line with a point no configuration reaches is
            // refused at once (from READY most lines to the table are such).
            if k == 1 && best.is_none() {
                if let Some((code, why)) = self.unreachable_point(&line) {
                    self.refusal = Some(why);
                    self.last_line = Some(LineOutcome::Blocked);
                    return code;
                }
            }
            let turn = (k > 0).then_some(Path::Joint {
                from: q0,
                to: *q_start,
            });
            let turn_time = match &turn {
                Some(p) => {
                    let (v, a) = p.bounds().limits(&speeds, &accels);
                    Profile::trapezoid(0.0, v, a, 0.0).end()
                }
                None => 0.0,
            };
            // A start whose turn alone takes as long as the least time of a way already
            // found neither wins nor lowers that least time.
            if turn_time >= least {
                continue;
            }
            let ease = Ease::for_elbow(q_start[2], j3_end);
            let path = match self.plan_line(&line, *q_start, ease) {
                Ok(p) => p,
                Err(f) => {
                    if f.code == code::JOINT_LIMIT {
                        any_limit = true;
                    } else if f.at > line_probe(ease) {
                        limits_everywhere = false;
                    }
                    // The start that got farthest says best where the line cannot go on.
                    if farthest.is_none_or(|g| f.at > g.at) {
                        farthest = Some(f);
                    }
                    continue;
                }
            };
            let (lo, hi) = path.range();
            if first_outside_limits(&lo).is_some() || first_outside_limits(&hi).is_some() {
                continue;
            }
            let profile = self.line_profile(&path, length, start + turn_time, ease);
            let total = profile.end() - start;
            least = least.min(turn_time + self.line_least_time(*q_start, path.at(1.0), length));
            if best.as_ref().is_none_or(|b| total < b.0) {
                best = Some((total, turn, path, profile));
            }
        }
        let Some((total, turn, path, profile)) = best else {
            let blocked = limits_everywhere && any_limit;
            let (code, why) = self.why_no_line(&line, farthest, blocked);
            self.refusal = Some(why);
            self.last_line = Some(if blocked {
                LineOutcome::Blocked
            } else {
                LineOutcome::Singular
            });
            return code;
        };
        if total > LINE_MAX_FACTOR * least + LINE_SLACK {
            self.refusal = Some(format!(
                "the straight line passes so near a singular pose that it would take {total:.1} \
                 s, more than {LINE_MAX_FACTOR} times the {least:.1} s it needs: go through a \
                 point off the line first, or move there in joints (straight 0)"
            ));
            self.last_line = Some(LineOutcome::Singular);
            return code::SINGULAR_PATH;
        }
        if let Some(turn) = turn {
            if self.motions.len() + 2 > MOTION_QUEUE {
                return code::QUEUE_FULL;
            }
            self.push(turn, now);
        }
        self.push_timed(path, profile);
        self.last_line = Some(LineOutcome::Accepted { least });
        code::OK
    }

    /// What the planner found for the last straight line asked for (accepted with its least
    /// time, or why it was refused); None when it was refused before planning (not homed,
    /// the target out of reach or below the table).
    pub fn last_line(&self) -> Option<LineOutcome> {
        self.last_line
    }

    /// The code and the words for a straight line no start could follow: a point of it that
    /// no configuration reaches within the limits (JOINT_LIMIT, or OUT_OF_REACH), every way
    /// along it meeting a joint limit (`blocked`: JOINT_LIMIT), or else the singular pose
    /// where the line from where the arm is had to jump (`fail`, the start that got
    /// farthest).
    pub(super) fn why_no_line(
        &self,
        line: &Line,
        fail: Option<LineFail>,
        blocked: bool,
    ) -> (i16, String) {
        if let Some(why) = self.unreachable_point(line) {
            return why;
        }
        let do_this = LINE_ADVICE;
        let Some(f) = fail else {
            return (
                code::SINGULAR_PATH,
                format!("the straight line cannot be followed smoothly: {do_this}"),
            );
        };
        if f.code != code::SINGULAR_PATH || blocked {
            let p = line.at(f.at).pos;
            let joint = first_outside_limits(&f.q).map_or_else(String::new, |j| {
                format!(
                    " ({} would pass its ±{:.0} deg)",
                    JOINT_NAMES[j],
                    crate::model::limits()[j].to_degrees()
                )
            });
            let every = if blocked {
                "every way the arm can follow the straight line from where it stands meets a \
                 joint limit: the farthest reaches"
            } else {
                "the straight line meets a joint limit in the arm's configuration at"
            };
            return (
                if blocked { code::JOINT_LIMIT } else { f.code },
                format!(
                    "{every} {:.0} % of its length ({:.1}, {:.1}, {:.1}){joint}: {do_this}",
                    100.0 * f.at,
                    p.x,
                    p.y,
                    p.z
                ),
            );
        }
        let flange = crate::kinematics::flange_dh(&f.q);
        let wrist = flange.pos - flange.rot.z_axis * crate::model::D6;
        let kind = if (wrist.x * wrist.x + wrist.y * wrist.y).sqrt() < 1.0 {
            "the shoulder's singular pose (the wrist centre on the base axis, where J1 is free)"
        } else if f.q[4].abs() < 0.02 {
            "the wrist's singular pose (J5 = 0, where J4 and J6 turn about one axis)"
        } else if f.q[2].abs() < 0.02 {
            "the elbow's singular pose (stretched, J3 = 0)"
        } else {
            "a change of the arm's configuration (its elbow or wrist would have to flip)"
        };
        let p = line.at(f.at).pos;
        (
            code::SINGULAR_PATH,
            format!(
                "the straight line meets {kind} at {:.0} % of its length ({:.1}, {:.1}, {:.1}), \
                 where the joints would have to jump: {do_this}",
                100.0 * f.at,
                p.x,
                p.y,
                p.z
            ),
        )
    }

    /// The first point of `line` that no configuration reaches within the joint limits (or
    /// at all), with its code and the words: no arm follows such a line.
    pub(super) fn unreachable_point(&self, line: &Line) -> Option<(i16, String)> {
        let lim = crate::model::limits();
        let do_this = LINE_ADVICE;
        for i in 0..=LINE_CHECKS {
            let s = i as f64 / LINE_CHECKS as f64;
            let pose = line.at(s);
            let all = self.kin.ik_all_exact(&pose, &self.planned_end());
            let p = pose.pos;
            if all.is_empty() {
                return Some((
                    code::OUT_OF_REACH,
                    format!(
                        "the straight line leaves the arm's reach at {:.0} % of its length \
                         ({:.1}, {:.1}, {:.1}): {do_this}",
                        100.0 * s,
                        p.x,
                        p.y,
                        p.z
                    ),
                ));
            }
            if all.as_slice().iter().any(|x| x.within_limits) {
                continue;
            }
            // The joint the solutions least beyond their limits still pass.
            let worst = all
                .as_slice()
                .iter()
                .map(|x| {
                    (0..6)
                        .filter(|&j| x.q[j].abs() > lim[j] + 1e-9)
                        .map(|j| (x.q[j].abs() - lim[j], j))
                        .fold((0.0, 0), |a, b| if b.0 > a.0 { b } else { a })
                })
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .map_or(2, |w| w.1);
            return Some((
                code::JOINT_LIMIT,
                format!(
                    "no configuration of the arm reaches the point at {:.0} % of the straight \
                     line ({:.1}, {:.1}, {:.1}) within its limits ({} would pass its ±{:.0} \
                     deg): {do_this}",
                    100.0 * s,
                    p.x,
                    p.y,
                    p.z,
                    JOINT_NAMES[worst],
                    lim[worst].to_degrees()
                ),
            ));
        }
        None
    }

    /// Where a straight line from `q0` may start: `q0` itself first, then each place the
    /// joints can turn to without moving the tool, toward the way the line leaves. At J5 = 0
    /// only J4 + J6 fixes the tool, and on READY's vertical line J1 turns about the same
    /// axis too; the inverse kinematics keeps the current J4 (and J1) there, which is
    /// seldom the one the line needs: the arm would have to jump. So the line's pose a
    /// little way along is solved in each configuration, and the start pose solved again
    /// from each solution: the free joints as the line needs them, J2, J3 and J5 as they are.
    /// A start is taken only where the whole turn is in the null space (the tool pose the
    /// same at both ends, and J2, J3, J5 unchanged) and within the limits.
    pub(super) fn line_starts(&self, line: &Line, q0: Joints, ease: Ease) -> Vec<Joints> {
        let mut starts = vec![q0];
        // Where the free joints must be as the line leaves: its pose a very little way
        // along (in the eased parameter, where the joints go linearly).
        // A line whose wrist leaves J5 = 0 slowly is still within the inverse kinematics'
        // band a very little way along (J4 kept there): it is read farther on as well.
        let probe_s = line_probe(ease);
        let mut probes = Vec::new();
        for far in LINE_PROBE_FARTHER {
            probes.extend_from_slice(
                self.kin
                    .ik_all_exact(&line.at((probe_s * far).min(1.0)), &q0)
                    .as_slice(),
            );
        }
        let mut found: Vec<(f64, Joints)> = Vec::new();
        for sol in &probes {
            let qp: Joints = std::array::from_fn(|i| q0[i] + wrap(sol.q[i] - q0[i]));
            let again = self.kin.ik_all(&line.from, &qp);
            let Some(at) = again
                .as_slice()
                .iter()
                .min_by(|a, b| wrapped_step(&a.q, &qp).total_cmp(&wrapped_step(&b.q, &qp)))
            else {
                continue;
            };
            let mut q: Joints = std::array::from_fn(|i| qp[i] + wrap(at.q[i] - qp[i]));
            // A free joint continued past its limit may be within it a turn the other way.
            let lim = crate::model::limits();
            for i in [0, 3, 5] {
                for turn in [std::f64::consts::TAU, -std::f64::consts::TAU] {
                    if q[i].abs() > lim[i] && (q[i] + turn).abs() <= lim[i] {
                        q[i] += turn;
                    }
                }
            }
            // At J5 = 0 the wrist may leave the same way turned half round (J5 the other
            // sign): J4 and J6 each a half turn on.
            let mut half = q;
            let pi = std::f64::consts::PI;
            half[3] += if half[3] > 0.0 { -pi } else { pi };
            half[5] += if half[5] > 0.0 { -pi } else { pi };
            for q in [q, half] {
                let still = [1, 2, 4].iter().all(|&i| (q[i] - q0[i]).abs() < 1e-6);
                let (dp, da) = pose_error(&self.kin.fk(&q), &line.from);
                let moved = max_step(&q, &q0);
                if !still
                    || dp > 1e-6
                    || da > 1e-6
                    || moved < 1e-9
                    || first_outside_limits(&q).is_some()
                {
                    continue;
                }
                // The same way read at a farther probe: the nearer reading is kept.
                if found.iter().all(|(_, f)| max_step(f, &q) > LINE_SAME_START) {
                    found.push((moved, q));
                }
            }
        }
        found.sort_by(|a, b| a.0.total_cmp(&b.0));
        starts.extend(found.into_iter().map(|(_, q)| q));
        starts
    }

    /// The joints along `line` from `q0`: samples of the inverse kinematics, each the
    /// solution nearest the one before (so the arm keeps its configuration), split until
    /// neighbours differ by at most LINE_STEP in every joint, and until the spline through
    /// them stays within LINE_TOLERANCE of the line between samples. A step that stays large
    /// however close the samples is a jump: SINGULAR_PATH. A point out of reach:
    /// OUT_OF_REACH.
    pub(super) fn plan_line(&self, line: &Line, q0: Joints, ease: Ease) -> Result<Path, LineFail> {
        let on_line = |s: f64| line.at(ease.at(s).0);
        let fail = |code: i16, s: f64, q: Joints| LineFail {
            code,
            at: ease.at(s).0,
            q,
        };
        let solve = |s: f64, near: &Joints| -> Result<Joints, LineFail> {
            let all = self.kin.ik_all_exact(&on_line(s), near);
            // Nearest as the joints turn: a joint past ±180° comes back as its other end,
            // and is the same place continued (then past its limit: JOINT_LIMIT, not a jump).
            let best = all
                .as_slice()
                .iter()
                .min_by(|a, b| wrapped_step(&a.q, near).total_cmp(&wrapped_step(&b.q, near)))
                .ok_or(fail(code::OUT_OF_REACH, s, *near))?;
            // Continue each joint from the previous one, without a wrap.
            Ok(std::array::from_fn(|i| near[i] + wrap(best.q[i] - near[i])))
        };
        let mut s = vec![0.0];
        let mut q = vec![q0];
        // Walk the line, halving the step where the joints move too far.
        let mut h: f64 = 1.0 / 32.0;
        while *s.last().expect("a sample") < 1.0 {
            let (s0, q_prev) = (*s.last().expect("a sample"), *q.last().expect("a sample"));
            let s1 = (s0 + h).min(1.0);
            let q1 = solve(s1, &q_prev)?;
            if max_step(&q1, &q_prev) <= LINE_STEP && first_outside_limits(&q1).is_some() {
                return Err(fail(code::JOINT_LIMIT, s1, q1));
            }
            if max_step(&q1, &q_prev) > LINE_STEP {
                h /= 2.0;
                if h < LINE_MIN_H {
                    return Err(fail(code::SINGULAR_PATH, s0, q_prev));
                }
                continue;
            }
            s.push(s1);
            q.push(q1);
            if s.len() > LINE_MAX_SAMPLES {
                return Err(fail(code::SINGULAR_PATH, s1, q1));
            }
            h = (h * 2.0).min(1.0 / 32.0);
        }
        // Between samples the spline must stay on the line: split where it does not.
        loop {
            let path = Path::spline(s.clone(), q.clone());
            let mut split = Vec::new();
            for k in 0..s.len() - 1 {
                let mid = 0.5 * (s[k] + s[k + 1]);
                let (dp, da) = pose_error(&self.kin.fk(&path.at(mid)), &on_line(mid));
                if dp > LINE_TOLERANCE_MM || da > LINE_TOLERANCE_RAD {
                    split.push(k);
                }
            }
            if split.is_empty() {
                return Ok(path);
            }
            for &k in split.iter().rev() {
                let mid = 0.5 * (s[k] + s[k + 1]);
                if s[k + 1] - s[k] < LINE_MIN_H {
                    return Err(fail(code::SINGULAR_PATH, mid, q[k]));
                }
                let qm = solve(mid, &q[k])?;
                if max_step(&qm, &q[k]) > LINE_STEP || max_step(&qm, &q[k + 1]) > LINE_STEP {
                    return Err(fail(code::SINGULAR_PATH, mid, q[k]));
                }
                s.insert(k + 1, mid);
                q.insert(k + 1, qm);
            }
            if s.len() > LINE_MAX_SAMPLES {
                return Err(fail(code::SINGULAR_PATH, 0.5, q0));
            }
        }
    }
}

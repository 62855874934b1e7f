//! FollowJointTrajectory's rules, apart from DDS and the arm, so that they are tested alone:
//! a goal becomes TROL waypoints (or is refused with the action's error code), and each look
//! at the arm gives the feedback and, at the end, the result.
//!
//! - **Validation**: the six joints by the URDF's names, each once, in any order; at least one
//!   point, six finite positions each, times from start 0 or more and increasing; no
//!   multi-DOF part; tolerances only for known joints. Otherwise INVALID_JOINTS or
//!   INVALID_GOAL, with the reason.
//! - **Desired**: where the arm should be at a time, as the simulated A465 and a MARS 8 run the
//!   trajectory (trol-a465's timed spline through the start and the waypoints, at rest at
//!   both ends).
//! - **Path tolerance** (a position per joint; 0 leaves the default, none here; -1 none):
//!   checked while the trajectory runs timed; beyond it, the arm is halted and the goal
//!   aborts with PATH_TOLERANCE_VIOLATED.
//! - **Goal tolerance** (default [`DEFAULT_GOAL_TOLERANCE`]) and **goal time tolerance**
//!   (0: not checked): at the end, every joint within its tolerance of the last point, and
//!   (timed) the end no later than the trajectory's time and the tolerance; otherwise
//!   GOAL_TOLERANCE_VIOLATED.

use trol::Waypoint;
use trol_a465::motion::Path;

use crate::msgs::{FollowGoal, JointTolerance, follow_code};

/// How far (rad) a joint may end from the last point when the goal gives no tolerance
/// (assumption: about half a degree, well above TROL's arrival rule on every controller).
pub const DEFAULT_GOAL_TOLERANCE: f64 = 0.01;

/// The latest time a point may have, s (TROLTrajectory's limit, docs/protocol.md).
const MAX_TIME_S: f64 = 3600.0;

/// A goal refused: the action's error code and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Refused {
    /// One of [`follow_code`].
    pub code: i32,
    /// Why, in words.
    pub why: String,
}

fn refused(code: i32, why: impl Into<String>) -> Refused {
    Refused {
        code,
        why: why.into(),
    }
}

/// An accepted goal, ready to run.
#[derive(Debug, Clone)]
pub struct Plan {
    /// TROLTrajectory's waypoints (joint_1 .. joint_6 order).
    pub waypoints: Vec<Waypoint>,
    /// For each URDF joint, its index in the goal's joint names.
    pub order: [usize; 6],
    /// The goal's joint names, for feedback.
    pub names: Vec<String>,
    /// The arm's joint names, in the URDF's order.
    pub joints: [String; 6],
    /// The path from the start, for the desired position.
    path: Path,
    /// The trajectory's time, s.
    pub total: f64,
    /// Path tolerance per joint (`None`: not checked).
    pub path_tolerance: [Option<f64>; 6],
    /// Goal tolerance per joint (`None`: not checked).
    pub goal_tolerance: [Option<f64>; 6],
    /// How late the end may be, s (`None`: not checked).
    pub goal_time_tolerance: Option<f64>,
}

/// Tolerances per URDF joint from a goal's list: 0 leaves `default`, a negative value means
/// none, a positive one is the tolerance.
fn tolerances(
    list: &[JointTolerance],
    default: Option<f64>,
    what: &str,
    joints: &[String; 6],
) -> Result<[Option<f64>; 6], Refused> {
    let mut out = [default; 6];
    for t in list {
        let Some(i) = joints.iter().position(|j| *j == t.name) else {
            return Err(refused(
                follow_code::INVALID_JOINTS,
                format!("{what} names `{}`, which this arm does not have", t.name),
            ));
        };
        if !t.position.is_finite() {
            return Err(refused(
                follow_code::INVALID_GOAL,
                format!("{what} of {} is not a number", t.name),
            ));
        }
        out[i] = if t.position > 0.0 {
            Some(t.position)
        } else if t.position < 0.0 {
            None
        } else {
            default
        };
    }
    Ok(out)
}

/// Check `goal` and make its plan from `start` (the arm's commanded joints); `joints`: the
/// arm's joint names, as the node gives them (`--prefix`).
pub fn plan(goal: &FollowGoal, start: [f64; 6], joints: &[String; 6]) -> Result<Plan, Refused> {
    let t = &goal.trajectory;
    let mut order = [usize::MAX; 6];
    for (k, name) in t.joint_names.iter().enumerate() {
        let Some(i) = joints.iter().position(|j| j == name) else {
            return Err(refused(
                follow_code::INVALID_JOINTS,
                format!(
                    "joint `{name}` is not one of this arm's ({})",
                    joints.join(", ")
                ),
            ));
        };
        if order[i] != usize::MAX {
            return Err(refused(
                follow_code::INVALID_JOINTS,
                format!("joint `{name}` is named twice"),
            ));
        }
        order[i] = k;
    }
    if let Some(i) = order.iter().position(|k| *k == usize::MAX) {
        return Err(refused(
            follow_code::INVALID_JOINTS,
            format!(
                "joint `{}` is missing: a trajectory names all six",
                joints[i]
            ),
        ));
    }
    if !goal.multi_dof_trajectory.points.is_empty()
        || !goal.component_path_tolerance.is_empty()
        || !goal.component_goal_tolerance.is_empty()
    {
        return Err(refused(
            follow_code::INVALID_GOAL,
            "this arm has no multi-DOF joints: the multi-DOF trajectory and component \
             tolerances must be empty",
        ));
    }
    if t.points.is_empty() {
        return Err(refused(
            follow_code::INVALID_GOAL,
            "the trajectory has no points",
        ));
    }
    if t.points.len() > usize::from(trol::MAX_WAYPOINTS) {
        return Err(refused(
            follow_code::INVALID_GOAL,
            format!(
                "{} points: at most {} (resample the trajectory)",
                t.points.len(),
                trol::MAX_WAYPOINTS
            ),
        ));
    }
    let mut waypoints = Vec::with_capacity(t.points.len());
    let mut last = -1.0;
    for (k, p) in t.points.iter().enumerate() {
        let time = p.time_from_start.seconds();
        if p.positions.len() != 6 || p.positions.iter().any(|x| !x.is_finite()) {
            return Err(refused(
                follow_code::INVALID_GOAL,
                format!(
                    "point {}: {} positions, six finite ones expected",
                    k + 1,
                    p.positions.len()
                ),
            ));
        }
        if time <= last || time > MAX_TIME_S {
            return Err(refused(
                follow_code::INVALID_GOAL,
                format!(
                    "point {}: time_from_start {time} s does not come after {last} s",
                    k + 1
                ),
            ));
        }
        last = time;
        waypoints.push(Waypoint {
            time,
            joints: std::array::from_fn(|i| p.positions[order[i]]),
        });
    }
    let path_tolerance = tolerances(&goal.path_tolerance, None, "a path tolerance", joints)?;
    let goal_tolerance = tolerances(
        &goal.goal_tolerance,
        Some(DEFAULT_GOAL_TOLERANCE),
        "a goal tolerance",
        joints,
    )?;
    let gt = goal.goal_time_tolerance.seconds();
    let total = last.max(0.0);
    // The desired path as the timed controllers run it: from the start through every
    // waypoint (a point at 0 is the start itself).
    let (mut ts, mut qs) = (vec![0.0], vec![start]);
    for w in &waypoints {
        if w.time > 0.0 {
            ts.push(w.time);
            qs.push(w.joints);
        }
    }
    let path = if total > 0.0 {
        Path::timed(ts.iter().map(|t| t / total).collect(), qs)
    } else {
        Path::Joint {
            from: start,
            to: start,
        }
    };
    Ok(Plan {
        waypoints,
        order,
        names: t.joint_names.clone(),
        joints: joints.clone(),
        path,
        total,
        path_tolerance,
        goal_tolerance,
        goal_time_tolerance: (gt > 0.0).then_some(gt),
    })
}

impl Plan {
    /// Where the arm should be `t` s after the start (URDF order).
    pub fn desired(&self, t: f64) -> [f64; 6] {
        if self.total <= 0.0 {
            return self.path.at(1.0);
        }
        self.path.at((t / self.total).clamp(0.0, 1.0))
    }

    /// The last point (URDF order).
    pub fn end(&self) -> [f64; 6] {
        self.waypoints
            .last()
            .map_or(self.desired(0.0), |w| w.joints)
    }

    /// Values in URDF order, put in the goal's order.
    pub fn in_goal_order(&self, q: &[f64; 6]) -> Vec<f64> {
        let mut out = vec![0.0; 6];
        for (i, k) in self.order.iter().enumerate() {
            out[*k] = q[i];
        }
        out
    }

    /// The first joint beyond its path tolerance at `t` with the arm at `actual`: (joint
    /// index, error).
    pub fn off_path(&self, t: f64, actual: &[f64; 6]) -> Option<(usize, f64)> {
        let want = self.desired(t);
        (0..6).find_map(|i| {
            let e = actual[i] - want[i];
            self.path_tolerance[i]
                .filter(|tol| e.abs() > *tol)
                .map(|_| (i, e))
        })
    }

    /// The plan thinned to at most `n` waypoints for a controller that runs no more (a C500:
    /// one joint move per point), or why it cannot be: the last point always kept, then
    /// greedily the point farthest from the path the kept ones make (linear between them in
    /// time), until `n`. Returns the thinned waypoints and how far (rad) the dropped points
    /// lie from their path at most; a path tolerance smaller than that refuses it.
    pub fn thinned(&self, n: usize) -> Result<(Vec<Waypoint>, f64), Refused> {
        let w = &self.waypoints;
        if w.len() <= n {
            return Ok((w.clone(), 0.0));
        }
        if n < 2 {
            return Err(refused(
                follow_code::INVALID_GOAL,
                format!("{} points for a controller that takes {n}", w.len()),
            ));
        }
        // The start (where the arm stands, time 0) anchors the first segment.
        let start = Waypoint {
            time: 0.0,
            joints: self.desired(0.0),
        };
        let mut kept = vec![w.len() - 1];
        let deviation = |kept: &[usize], k: usize| -> [f64; 6] {
            let before = kept
                .iter()
                .copied()
                .filter(|&j| j < k)
                .max()
                .map_or(&start, |j| &w[j]);
            let after = &w[kept.iter().copied().filter(|&j| j > k).min().unwrap_or(k)];
            let span = after.time - before.time;
            let f = if span > 0.0 {
                (w[k].time - before.time) / span
            } else {
                0.0
            };
            std::array::from_fn(|i| {
                let on_path = before.joints[i] + f * (after.joints[i] - before.joints[i]);
                (w[k].joints[i] - on_path).abs()
            })
        };
        let worst = |kept: &[usize]| -> Option<(usize, f64)> {
            (0..w.len())
                .filter(|k| !kept.contains(k))
                .map(|k| (k, deviation(kept, k).into_iter().fold(0.0, f64::max)))
                .max_by(|a, b| a.1.total_cmp(&b.1))
        };
        while kept.len() < n {
            let Some((k, _)) = worst(&kept) else { break };
            kept.push(k);
        }
        kept.sort_unstable();
        // How far the dropped points lie from the thinned path, per joint.
        let mut off = [0.0f64; 6];
        for k in (0..w.len()).filter(|k| !kept.contains(k)) {
            let d = deviation(&kept, k);
            for i in 0..6 {
                off[i] = off[i].max(d[i]);
            }
        }
        for (i, (off_i, tol)) in off.iter().zip(self.path_tolerance).enumerate() {
            if let Some(tol) = tol
                && *off_i > tol
            {
                return Err(refused(
                    follow_code::INVALID_GOAL,
                    format!(
                        "{} points, and this controller runs at most {n}: thinned, {} would \
                         leave the path by {:.4} rad, beyond its path tolerance {tol}; send \
                         fewer points or a wider tolerance",
                        w.len(),
                        self.joints[i],
                        off_i
                    ),
                ));
            }
        }
        Ok((
            kept.iter().map(|&k| w[k]).collect(),
            off.into_iter().fold(0.0, f64::max),
        ))
    }

    /// The goal's point in use `elapsed` s after the start: the first not yet due (the last
    /// once all are).
    pub fn point_in_use(&self, elapsed: f64) -> i32 {
        let k = self
            .waypoints
            .iter()
            .position(|w| w.time >= elapsed)
            .unwrap_or(self.waypoints.len().saturating_sub(1));
        i32::try_from(k).unwrap_or(i32::MAX)
    }

    /// The result once the arm stands at `actual`, `elapsed` s after the start (`timed`: the
    /// controller kept the times).
    pub fn result(&self, actual: &[f64; 6], elapsed: f64, timed: bool) -> (i32, String) {
        let end = self.end();
        for i in 0..6 {
            if let Some(tol) = self.goal_tolerance[i] {
                let e = actual[i] - end[i];
                if e.abs() > tol {
                    return (
                        follow_code::GOAL_TOLERANCE_VIOLATED,
                        format!(
                            "{} ended {e:.4} rad from the last point (tolerance {tol})",
                            self.joints[i]
                        ),
                    );
                }
            }
        }
        if let (true, Some(late)) = (timed, self.goal_time_tolerance)
            && elapsed > self.total + late
        {
            return (
                follow_code::GOAL_TOLERANCE_VIOLATED,
                format!(
                    "the arm arrived {:.3} s after the trajectory's end (goal time tolerance \
                     {late} s)",
                    elapsed - self.total
                ),
            );
        }
        (
            follow_code::SUCCESSFUL,
            if timed {
                "the arm is at the last point".into()
            } else {
                "the arm is at the last point (this controller ran it without its times, one \
                 joint move per point)"
                    .into()
            },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msgs::{Duration, JointTrajectoryPoint};

    fn point(t: f64, q: [f64; 6]) -> JointTrajectoryPoint {
        JointTrajectoryPoint {
            positions: q.to_vec(),
            time_from_start: Duration::from_seconds(t),
            ..Default::default()
        }
    }

    /// The URDF's joint names, no prefix.
    fn urdf() -> [String; 6] {
        crate::joint_names("")
    }

    #[test]
    fn a_dense_plan_is_thinned_to_the_controller_s_count_keeping_its_end_and_its_corners() {
        let joints = urdf();
        let names: Vec<&str> = joints.iter().map(String::as_str).collect();
        // 40 points: joint 1 up to 1 rad at 2 s, then back to 0.5 at 4 s (a corner at 2 s).
        let points: Vec<_> = (1..=40)
            .map(|k| {
                let t = k as f64 * 0.1;
                let q1 = if t <= 2.0 {
                    t / 2.0
                } else {
                    1.0 - (t - 2.0) / 4.0
                };
                point(t, [q1, 0.0, 0.0, 0.0, 0.0, 0.0])
            })
            .collect();
        let p = plan(&goal(&names, points), [0.0; 6], &joints).unwrap();
        let (thin, off) = p.thinned(16).unwrap();
        assert!(thin.len() <= 16);
        assert_eq!(thin.last().unwrap().joints, p.end(), "the end is kept");
        assert!(
            thin.iter().any(|w| (w.time - 2.0).abs() < 1e-9),
            "the corner is kept"
        );
        assert!(thin.windows(2).all(|w| w[0].time < w[1].time));
        assert!(off < 1e-9, "straight pieces lose nothing: {off}");
        // A tolerance tighter than what thinning costs refuses it.
        let wavy: Vec<_> = (1..=40)
            .map(|k| {
                let t = k as f64 * 0.1;
                point(t, [0.1 * (k % 2) as f64, 0.0, 0.0, 0.0, 0.0, 0.0])
            })
            .collect();
        let mut g = goal(&names, wavy);
        g.path_tolerance.push(JointTolerance {
            name: joints[0].clone(),
            position: 0.01,
            ..Default::default()
        });
        let p = plan(&g, [0.0; 6], &joints).unwrap();
        let e = p.thinned(16).unwrap_err();
        assert_eq!(e.code, follow_code::INVALID_GOAL);
        assert!(e.why.contains("path tolerance"), "{e:?}");
    }

    #[test]
    fn a_prefixed_arm_takes_only_its_prefixed_names() {
        let joints = crate::joint_names("arm2_");
        let names: Vec<&str> = joints.iter().map(String::as_str).collect();
        let g = goal(&names, vec![point(1.0, [0.1; 6])]);
        assert!(plan(&g, [0.0; 6], &joints).is_ok());
        // The bare names belong to no arm of this node.
        let bare = urdf();
        let names: Vec<&str> = bare.iter().map(String::as_str).collect();
        let e = plan(&goal(&names, vec![point(1.0, [0.1; 6])]), [0.0; 6], &joints).unwrap_err();
        assert_eq!(e.code, follow_code::INVALID_JOINTS);
        assert!(e.why.contains("arm2_joint_1"), "{e:?}");
    }

    fn goal(names: &[&str], points: Vec<JointTrajectoryPoint>) -> FollowGoal {
        let mut g = FollowGoal::default();
        g.trajectory.joint_names = names.iter().map(|s| s.to_string()).collect();
        g.trajectory.points = points;
        g
    }

    #[test]
    fn a_goal_in_any_joint_order_becomes_waypoints_in_the_urdf_order() {
        let names = [
            "joint_6", "joint_5", "joint_4", "joint_3", "joint_2", "joint_1",
        ];
        let g = goal(&names, vec![point(1.0, [6.0, 5.0, 4.0, 3.0, 2.0, 1.0])]);
        let p = plan(&g, [0.0; 6], &urdf()).unwrap();
        assert_eq!(p.waypoints[0].joints, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        assert_eq!(
            p.in_goal_order(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]),
            vec![6.0, 5.0, 4.0, 3.0, 2.0, 1.0]
        );
        // The desired path starts where the arm is and ends at the point, at its time.
        assert_eq!(p.desired(0.0), [0.0; 6]);
        let end = p.desired(1.0);
        assert!((end[0] - 1.0).abs() < 1e-12 && (end[5] - 6.0).abs() < 1e-12);
    }

    #[test]
    fn bad_goals_are_refused_with_the_action_s_codes() {
        let joints = urdf();
        let ok: Vec<&str> = joints.iter().map(String::as_str).collect();
        let p = |t: f64| point(t, [0.1; 6]);
        let cases = [
            (
                goal(&ok[..5], vec![p(1.0)]),
                follow_code::INVALID_JOINTS,
                "missing",
            ),
            (
                goal(
                    &[
                        "joint_1", "joint_1", "joint_3", "joint_4", "joint_5", "joint_6",
                    ],
                    vec![p(1.0)],
                ),
                follow_code::INVALID_JOINTS,
                "twice",
            ),
            (
                goal(
                    &[
                        "elbow", "joint_2", "joint_3", "joint_4", "joint_5", "joint_6",
                    ],
                    vec![p(1.0)],
                ),
                follow_code::INVALID_JOINTS,
                "not one of",
            ),
            (goal(&ok, vec![]), follow_code::INVALID_GOAL, "no points"),
            (
                goal(&ok, vec![p(2.0), p(1.0)]),
                follow_code::INVALID_GOAL,
                "does not come after",
            ),
            (
                goal(
                    &ok,
                    vec![JointTrajectoryPoint {
                        positions: vec![0.0; 5],
                        ..p(1.0)
                    }],
                ),
                follow_code::INVALID_GOAL,
                "positions",
            ),
        ];
        for (g, code, words) in cases {
            let e = plan(&g, [0.0; 6], &urdf()).unwrap_err();
            assert_eq!(e.code, code, "{e:?}");
            assert!(e.why.contains(words), "{e:?}");
        }
        let mut tol = goal(&ok, vec![p(1.0)]);
        tol.goal_tolerance.push(JointTolerance {
            name: "gripper".into(),
            position: 0.1,
            ..Default::default()
        });
        assert_eq!(
            plan(&tol, [0.0; 6], &urdf()).unwrap_err().code,
            follow_code::INVALID_JOINTS
        );
    }

    #[test]
    fn the_result_checks_the_goal_tolerance_and_the_goal_time() {
        let joints = urdf();
        let names: Vec<&str> = joints.iter().map(String::as_str).collect();
        let mut g = goal(&names, vec![point(2.0, [0.5; 6])]);
        g.goal_time_tolerance = Duration::from_seconds(0.5);
        g.path_tolerance.push(JointTolerance {
            name: "joint_2".into(),
            position: 0.05,
            ..Default::default()
        });
        let p = plan(&g, [0.0; 6], &urdf()).unwrap();
        assert_eq!(p.result(&[0.5; 6], 2.1, true).0, follow_code::SUCCESSFUL);
        let (c, why) = p.result(&[0.5, 0.5, 0.5, 0.5, 0.5, 0.53], 2.1, true);
        assert_eq!(c, follow_code::GOAL_TOLERANCE_VIOLATED);
        assert!(why.contains("joint_6"), "{why}");
        assert_eq!(
            p.result(&[0.5; 6], 2.6, true).0,
            follow_code::GOAL_TOLERANCE_VIOLATED
        );
        // Untimed, lateness is not the arm's fault.
        assert_eq!(p.result(&[0.5; 6], 9.0, false).0, follow_code::SUCCESSFUL);
        // The path tolerance: joint 2 only.
        let mid = p.desired(1.0);
        assert_eq!(p.off_path(1.0, &mid), None);
        let mut off = mid;
        off[1] += 0.06;
        assert_eq!(p.off_path(1.0, &off).map(|(i, _)| i), Some(1));
        off = mid;
        off[0] += 0.5;
        assert_eq!(p.off_path(1.0, &off), None, "joint 1 has no path tolerance");
    }
}

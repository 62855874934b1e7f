//! Straight lines from where people start (issue 42): the survey behind docs/a465.md's
//! figures, and an independent check of the planner's verdicts. A line refused as blocked
//! (every way along it meets a joint limit) must have no continuous joint path within the
//! limits, and an accepted line must have one, as a search over every joint solution along
//! the line finds them.

use trol_a465::arm::{Arm, ArmSettings, LineOutcome, Target, code};
use trol_a465::model::limits;
use trol_a465::survey::{everyday_lines, survey};
use trol_a465::{Kinematics, Pose};

/// The survey behind docs/a465.md's figures (`trol bench lines`): of the everyday lines an
/// arm can follow at all, from READY and from J5 = 0, at least 95 % are taken (issue 42's
/// goal), each within 2.5 times its least time, none leaving the limits or the line.
#[test]
fn the_line_survey_takes_the_lines_an_arm_can_follow() {
    let sets = survey(120, 7, false);
    for s in &sets {
        assert!(s.tried - s.impossible - s.blocked >= 20, "{s:?}");
        assert!(s.accepted_percent >= 95.0, "{s:?}");
        assert!(s.ratio_max <= 2.5, "{s:?}");
        assert_eq!(s.limit_excursions, 0, "{s:?}");
        assert!(s.max_off_line_mm < 0.02, "{s:?}");
    }
}

/// Samples of the line for the search (closer near the start), and the largest step of a joint between two
/// neighbours that still counts as continuous (200 rad over the whole line: generous, so
/// that the search finds a way wherever one could be).
const SAMPLES: usize = 4000;
const STEP: f64 = 0.05;
/// Below this |J5| J4 and J6 count as free (rad).
const WRIST_FREE: f64 = 1e-3;
/// How far past a limit a solution of the exact line may be and still count: where the line
/// grazes a limit, the planned path (within 0.01 mm of the line) keeps inside it while the
/// exact line's solution is a few 1e-8 rad past.
const GRAZE: f64 = 1e-6;

/// Every joint solution within the limits at `pose`, J4 and J6 also a turn on where that
/// is within their limits too.
fn solutions_within_limits(kin: &Kinematics, pose: &Pose, near: &[f64; 6]) -> Vec<[f64; 6]> {
    let lim = limits();
    let mut out = Vec::new();
    for s in kin.ik_all_exact(pose, near).as_slice() {
        let mut variants = vec![s.q];
        for j in [3, 5] {
            for turn in [std::f64::consts::TAU, -std::f64::consts::TAU] {
                let more: Vec<[f64; 6]> = variants
                    .iter()
                    .map(|q| {
                        let mut v = *q;
                        v[j] += turn;
                        v
                    })
                    .collect();
                variants.extend(more);
            }
        }
        out.extend(
            variants
                .into_iter()
                .filter(|q| (0..6).all(|i| q[i].abs() <= lim[i] + GRAZE)),
        );
    }
    out
}

/// Whether some continuous joint path within the limits follows the straight line from
/// `q0` to `target` (orientation by the shorter slerp, as the arm interpolates it): a search
/// from every solution near the start (J2, J3 and J5 as at the start; J1, J4 and J6 free,
/// as a singular start leaves them) through the solutions at each sample.
fn some_way_along(q0: [f64; 6], target: [f64; 6]) -> bool {
    let kin = Kinematics::default();
    let (a, b) = (kin.fk(&q0), Pose::from_xyzypr(target));
    let (ra, mut rb) = (
        glam::DQuat::from_mat3(&a.rot),
        glam::DQuat::from_mat3(&b.rot),
    );
    if ra.dot(rb) < 0.0 {
        rb = -rb;
    }
    // Sampled in σ, s = σ²: from a stretched elbow (READY) J2 and J3 go as √s.
    let at = |i: usize| {
        let s = (i as f64 / SAMPLES as f64).powi(2);
        Pose {
            pos: a.pos.lerp(b.pos, s),
            rot: glam::DMat3::from_quat(ra.slerp(rb, s)),
        }
    };
    // Near J5 = 0 only J4 + J6 is fixed, and J4 and J6 may turn (in place, at the singular
    // pose) to whatever the line needs as it leaves: there they count as free.
    let near = |x: &[f64; 6], y: &[f64; 6]| {
        let free = x[4].abs() < WRIST_FREE && y[4].abs() < WRIST_FREE;
        (0..6).all(|i| (x[i] - y[i]).abs() <= STEP || (free && (i == 3 || i == 5)))
    };
    let mut live: Vec<[f64; 6]> = solutions_within_limits(&kin, &at(1), &q0)
        .into_iter()
        .filter(|q| [1, 2, 4].iter().all(|&i| (q[i] - q0[i]).abs() <= STEP))
        .collect();
    for i in 2..=SAMPLES {
        let next = solutions_within_limits(&kin, &at(i), &q0);
        live = next
            .into_iter()
            .filter(|q| live.iter().any(|p| near(p, q)))
            .collect();
        if live.is_empty() {
            return false;
        }
    }
    true
}

#[test]
fn a_blocked_line_has_no_way_within_the_limits_and_an_accepted_one_has() {
    let [ready, wrist] = everyday_lines(300, 3);
    let (mut blocked, mut every_way, mut accepted) = (0, 0, 0);
    for (q0, target) in ready.into_iter().chain(wrist) {
        let mut arm = Arm::new(ArmSettings {
            homed: true,
            ..ArmSettings::default()
        });
        arm.place(q0);
        let c = arm.move_to(Target::Cart(target), true, 0.0);
        match arm.last_line() {
            Some(LineOutcome::Blocked) => {
                assert_eq!(c, code::JOINT_LIMIT);
                let why = arm.take_refusal().expect("a reason");
                assert!(why.contains("would pass its ±"), "{why}");
                // A point with no solution at all is blocked too; the search agrees.
                assert!(
                    !some_way_along(q0, target),
                    "from {q0:?} to {target:?}: refused as blocked, but the search found a \
                     way: {why}"
                );
                blocked += 1;
                // Blocked along the way, not at a point no configuration reaches.
                if why.contains("every way the arm can follow") {
                    every_way += 1;
                }
            }
            Some(LineOutcome::Accepted { .. }) => {
                assert_eq!(c, code::OK);
                // Every fourth: the search is the slow part.
                if accepted % 4 == 0 {
                    assert!(
                        some_way_along(q0, target),
                        "from {q0:?} to {target:?}: accepted, but the search found no way"
                    );
                }
                accepted += 1;
            }
            other => panic!("from {q0:?} to {target:?}: {other:?} ({c})"),
        }
    }
    assert!(
        every_way >= 3,
        "lines blocked along every way to check: {every_way} (of {blocked} blocked)"
    );
    assert!(accepted >= 50, "accepted lines: {accepted}");
}

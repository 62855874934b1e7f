//! A survey of straight lines (`trol bench lines`, and the tests of docs/a465.md's figures):
//! lines from where people start (READY, after Home) and from poses with the wrist at
//! J5 = 0 (issue 42) to everyday targets (the table's working volume, the tool down or
//! level, reachable by a joint move), each tried on the model in its own time: the share
//! accepted, each line's duration against its least time, the joint limits along it, and how
//! far it leaves the line. Lines no arm within the limits can follow are counted apart: a
//! point of them that no configuration reaches, or every way along them from the start
//! meeting a joint limit.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::arm::{Arm, ArmSettings, LineOutcome, Target, code};
use crate::model::limits;
use crate::{Kinematics, Pose};

/// One set's figures.
#[derive(Clone, Debug, PartialEq)]
pub struct SetReport {
    /// What the set is.
    pub set: &'static str,
    /// Lines tried: targets a joint move reaches.
    pub tried: usize,
    /// Lines with a point that no configuration reaches within the joint limits: no arm
    /// can follow them (refused, and not counted in the share).
    pub impossible: usize,
    /// Lines whose every way from the start (in each configuration the arm can leave in)
    /// meets a joint limit: no arm within the limits follows them (refused with
    /// JOINT_LIMIT, not counted in the share).
    pub blocked: usize,
    /// Lines accepted as straight lines.
    pub accepted: usize,
    /// Share accepted of the lines an arm can follow (tried, less impossible and blocked),
    /// percent.
    pub accepted_percent: f64,
    /// Share accepted of all the lines tried (every target reachable by a joint move),
    /// percent.
    pub accepted_of_tried_percent: f64,
    /// Refusals by code.
    pub refused: Vec<(i16, usize)>,
    /// Duration over least time: the median.
    pub ratio_median: f64,
    /// Duration over least time: the 99th percentile.
    pub ratio_p99: f64,
    /// Duration over least time: the largest.
    pub ratio_max: f64,
    /// Duration over the joint-interpolated move from where the arm stood to the line's end
    /// (or its length at the linear limits), a turn of the free joints first not counted in
    /// it: the largest.
    pub plain_ratio_max: f64,
    /// Samples outside a joint limit (should be 0).
    pub limit_excursions: usize,
    /// Largest distance of the tool centre point from the line, mm.
    pub max_off_line_mm: f64,
    /// The refused lines, each in words (when asked for).
    pub refusals: Vec<String>,
}

/// Everyday targets: in the table's working volume, the tool down or level.
fn everyday_target(rng: &mut ChaCha8Rng) -> [f64; 6] {
    let x = rng.random_range(250.0..550.0);
    let y = rng.random_range(-350.0..350.0);
    let z = rng.random_range(30.0..450.0);
    if rng.random_bool(0.5) {
        // Tool down, turned about the vertical.
        let yaw = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
        [x, y, z, yaw, std::f64::consts::FRAC_PI_2, 0.0]
    } else {
        // Level, pointing away from the base within 45 degrees.
        let yaw = f64::atan2(y, x) + rng.random_range(-0.8..0.8);
        [x, y, z, yaw, 0.0, 0.0]
    }
}

fn arm_at(q: [f64; 6]) -> Arm {
    let mut arm = Arm::new(ArmSettings {
        homed: true,
        ..ArmSettings::default()
    });
    arm.place(q);
    arm
}

/// Distance of `p` from the segment a-b.
fn off_segment(p: glam::DVec3, a: glam::DVec3, b: glam::DVec3) -> f64 {
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 {
        ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * t)).length()
}

struct Tally {
    shown: Vec<String>,
    tried: usize,
    /// Lines with a point no configuration reaches within the limits.
    impossible: usize,
    /// Lines whose every way meets a joint limit.
    blocked: usize,
    plain_max: f64,
    accepted: usize,
    refused: std::collections::BTreeMap<i16, usize>,
    ratios: Vec<f64>,
    limit_excursions: usize,
    max_off: f64,
}

/// Whether every point of the straight line from `a` to `b` (orientation by the shorter
/// slerp, as the arm interpolates it) has a joint solution within the limits: where one
/// has none, no arm follows the line, in any configuration.
fn feasible(kin: &Kinematics, a: &Pose, b: &Pose) -> bool {
    let (qa, mut qb) = (
        glam::DQuat::from_mat3(&a.rot),
        glam::DQuat::from_mat3(&b.rot),
    );
    if qa.dot(qb) < 0.0 {
        qb = -qb;
    }
    (0..=200).all(|i| {
        let s = i as f64 / 200.0;
        let p = Pose {
            pos: a.pos.lerp(b.pos, s),
            rot: glam::DMat3::from_quat(qa.slerp(qb, s)),
        };
        kin.ik_all_exact(&p, &[0.0; 6])
            .as_slice()
            .iter()
            .any(|s| s.within_limits)
    })
}

/// Whether a joint move from `q0` reaches `target` (the survey's lines all do).
fn joint_move_reaches(q0: [f64; 6], target: [f64; 6]) -> bool {
    arm_at(q0).move_to(Target::Cart(target), false, 0.0) == code::OK
}

/// Try the straight line from `q0` to `target` (a joint move reaches it).
fn try_line(q0: [f64; 6], target: [f64; 6], t: &mut Tally, show: bool) {
    let kin = Kinematics::default();
    t.tried += 1;
    let mut arm = arm_at(q0);
    let c = arm.move_to(Target::Cart(target), true, 0.0);
    if c != code::OK {
        if !feasible(&kin, &kin.fk(&q0), &Pose::from_xyzypr(target)) {
            t.impossible += 1;
            return;
        }
        if arm.last_line() == Some(LineOutcome::Blocked) {
            t.blocked += 1;
            if show {
                let why = arm.take_refusal().unwrap_or_default();
                t.shown
                    .push(format!("blocked {c}: from {q0:.4?} to {target:.3?}: {why}"));
            }
            return;
        }
        *t.refused.entry(c).or_default() += 1;
        if show {
            let why = arm.take_refusal().unwrap_or_default();
            t.shown
                .push(format!("refused {c}: from {q0:.4?} to {target:.3?}: {why}"));
        }
        return;
    }
    t.accepted += 1;
    // From the call (time 0), so that a turn of the free joints first counts.
    let (_, end, _) = arm.last_motion().expect("a motion");
    let start = 0.0;
    let from = kin.fk(&q0);
    let to = Pose::from_xyzypr(target);
    let length = (to.pos - from.pos).length();
    let Some(LineOutcome::Accepted { least }) = arm.last_line() else {
        unreachable!("an accepted line has its least time");
    };
    let ratio = (end - start) / least.max(1e-9);
    t.ratios.push(ratio);
    let plain = arm.line_least_time(q0, arm.planned_end(), length);
    t.plain_max = t.plain_max.max((end - start) / plain.max(1e-9));
    if show && ratio > 2.5 {
        t.shown.push(format!(
            "slow {ratio:.2}: from {q0:.4?} to {target:.3?}: {:.3} s for least {least:.3} s",
            end - start
        ));
    }
    let lim = limits();
    let n = 400;
    for i in 0..=n {
        let time = start + (end - start) * i as f64 / n as f64;
        let q = arm.planned_at(time);
        if q.iter().zip(lim).any(|(v, l)| v.abs() > l + 1e-9) {
            t.limit_excursions += 1;
        }
        let p = kin.fk(&q).pos;
        t.max_off = t.max_off.max(off_segment(p, from.pos, to.pos));
    }
}

fn report(set: &'static str, mut t: Tally) -> SetReport {
    t.ratios.sort_by(f64::total_cmp);
    let pick = |p: f64| -> f64 {
        if t.ratios.is_empty() {
            return f64::NAN;
        }
        let i = ((t.ratios.len() - 1) as f64 * p).round() as usize;
        t.ratios[i]
    };
    SetReport {
        refusals: t.shown,
        set,
        tried: t.tried,
        impossible: t.impossible,
        blocked: t.blocked,
        accepted: t.accepted,
        accepted_percent: 100.0 * t.accepted as f64
            / (t.tried - t.impossible - t.blocked).max(1) as f64,
        accepted_of_tried_percent: 100.0 * t.accepted as f64 / t.tried.max(1) as f64,
        refused: t.refused.into_iter().collect(),
        ratio_median: pick(0.5),
        ratio_p99: pick(0.99),
        ratio_max: pick(1.0),
        plain_ratio_max: t.plain_max,
        limit_excursions: t.limit_excursions,
        max_off_line_mm: t.max_off,
    }
}

fn tally() -> Tally {
    Tally {
        shown: Vec::new(),
        tried: 0,
        impossible: 0,
        blocked: 0,
        plain_max: 0.0,
        accepted: 0,
        refused: Default::default(),
        ratios: Vec::new(),
        limit_excursions: 0,
        max_off: 0.0,
    }
}

/// The survey's lines, `count` of each set (from READY, from J5 = 0): each its start (the
/// joints) and its target (x y z mm, yaw pitch roll rad), a target a joint move reaches. The
/// same seed draws the same lines.
pub fn everyday_lines(count: u32, seed: u64) -> [Vec<([f64; 6], [f64; 6])>; 2] {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut ready = Vec::new();
    let mut guard = 0;
    while ready.len() < count as usize && guard < 100 * count {
        guard += 1;
        let target = everyday_target(&mut rng);
        if joint_move_reaches([0.0; 6], target) {
            ready.push(([0.0; 6], target));
        }
    }
    let lim = limits();
    let mut wrist = Vec::new();
    let mut guard = 0;
    while wrist.len() < count as usize && guard < 100 * count {
        guard += 1;
        // A random pose with J5 = 0, the arm over the table.
        let mut q: [f64; 6] = std::array::from_fn(|i| rng.random_range(-lim[i]..lim[i]) * 0.8);
        q[4] = 0.0;
        q[1] = rng.random_range(-0.2..1.0);
        q[2] = rng.random_range(0.2..1.6);
        let p = Kinematics::default().fk(&q);
        if p.pos.z < 30.0 {
            continue;
        }
        let target = everyday_target(&mut rng);
        if joint_move_reaches(q, target) {
            wrist.push((q, target));
        }
    }
    [ready, wrist]
}

/// The sets of lines, `count` each.
pub fn survey(count: u32, seed: u64, show: bool) -> Vec<SetReport> {
    let [ready_lines, wrist_lines] = everyday_lines(count, seed);
    let mut ready = tally();
    for (q0, target) in ready_lines {
        try_line(q0, target, &mut ready, show);
    }
    let mut wrist = tally();
    for (q0, target) in wrist_lines {
        try_line(q0, target, &mut wrist, show);
    }
    vec![report("from READY", ready), report("from J5 = 0", wrist)]
}

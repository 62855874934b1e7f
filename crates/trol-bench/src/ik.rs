//! `trol bench ik`: the inverse kinematics against EAIK's, in the same run.

use super::*;

#[derive(Serialize)]
pub(super) struct IkReport {
    pub(super) poses: usize,
    pub(super) solutions: usize,
    pub(super) solutions_per_pose: f64,
    pub(super) max_position_error_mm: f64,
    pub(super) seconds: f64,
    pub(super) ns_per_pose: f64,
    /// EAIK in the same run (`--eaik`): its figures, and how many times faster TROL's is than
    /// its batched call.
    pub(super) eaik: Option<serde_json::Value>,
    pub(super) times_faster_than_eaik: Option<f64>,
}

/// The EAIK anchor's script (`--eaik`).
pub(super) const EAIK_SCRIPT: &str = include_str!("anchors/eaik.py");

/// Run EAIK on `n` poses with `python`: its report.
pub(super) fn eaik_anchor(python: &str, n: usize, seed: u64) -> Result<serde_json::Value, String> {
    let out = std::process::Command::new(python)
        .arg("-c")
        .arg(EAIK_SCRIPT)
        .arg(n.to_string())
        .arg(seed.to_string())
        .output()
        .map_err(|e| format!("cannot run {python}: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "EAIK did not run with {python} (install it: {python} -m pip install eaik): {}",
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    serde_json::from_slice(&out.stdout).map_err(|e| format!("EAIK's report is not JSON: {e}"))
}

pub(super) fn ik(a: IkArgs) -> Result<(), String> {
    use rand::{Rng, SeedableRng};
    use trol_a465::Kinematics;
    use trol_a465::model::limits;
    // Seeded, so that a run can be repeated.
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(a.seed);
    let mut uniform = move || rng.random::<f64>();
    let kin = Kinematics::new([0.0, 0.0, 120.0, 0.0, 0.0, 0.0]);
    let lim = limits();
    let n = a.poses as usize;
    let mut joints = Vec::with_capacity(n);
    let mut poses = Vec::with_capacity(n);
    for _ in 0..n {
        let q: [f64; 6] = std::array::from_fn(|i| (uniform() * 2.0 - 1.0) * lim[i]);
        poses.push(kin.fk(&q));
        joints.push(q);
    }
    // Check once, untimed: every solution reproduces its pose, and the joints that made the
    // pose are among them.
    let mut solutions = 0;
    let mut max_err: f64 = 0.0;
    for (pose, q) in poses.iter().zip(&joints) {
        let all = kin.ik_all(pose, q);
        if all.is_empty() {
            return Err(format!("no solution for the pose of joints {q:?}"));
        }
        solutions += all.len();
        for s in all.as_slice() {
            max_err = max_err.max((kin.fk(&s.q).pos - pose.pos).length());
        }
    }
    if max_err > 1e-6 {
        return Err(format!("a solution misses its pose by {max_err} mm"));
    }
    let mut best = f64::INFINITY;
    for _ in 0..a.repeat {
        let started = Instant::now();
        let mut count = 0usize;
        for (pose, q) in poses.iter().zip(&joints) {
            count += std::hint::black_box(kin.ik_all(std::hint::black_box(pose), q)).len();
        }
        let seconds = started.elapsed().as_secs_f64();
        std::hint::black_box(count);
        best = best.min(seconds);
    }
    let ns_per_pose = best * 1e9 / n as f64;
    // EAIK is slower: a fifth of the poses does for its figure.
    let eaik = match &a.eaik {
        Some(python) => {
            if !a.json {
                eprintln!("timing EAIK on {} poses with {python} ...", (n / 5).max(1));
            }
            Some(eaik_anchor(python, (n / 5).max(1), a.seed)?)
        }
        None => None,
    };
    let times_faster_than_eaik = eaik
        .as_ref()
        .and_then(|e| e["ns_per_pose_batched"].as_f64())
        .map(|e| e / ns_per_pose);
    let r = IkReport {
        poses: n,
        solutions,
        solutions_per_pose: solutions as f64 / n as f64,
        max_position_error_mm: max_err,
        seconds: best,
        ns_per_pose,
        eaik,
        times_faster_than_eaik,
    };
    print_report(&r, a.json, |r| {
        let mut t = format!(
            "{} poses, {:.2} solutions each (largest position error {:.1e} mm): {:.1} ns per pose",
            r.poses, r.solutions_per_pose, r.max_position_error_mm, r.ns_per_pose
        );
        if let (Some(e), Some(x)) = (&r.eaik, r.times_faster_than_eaik) {
            t += &format!(
                "\nEAIK in the same run ({} poses): {:.0} ns per pose batched, {:.0} ns one call \
                 each; TROL's is {x:.1} times faster than the batched call",
                e["poses"],
                e["ns_per_pose_batched"].as_f64().unwrap_or(f64::NAN),
                e["ns_per_pose_one_call_each"].as_f64().unwrap_or(f64::NAN),
            );
        }
        t
    })
}

//! The A465's published figures and the conventions this simulation fixes.
//!
//! Sources are in `../shared/reference/a465.md`; each constant says whether it is a published
//! fact (two or more independent sources) or an assumption of ours.

use std::f64::consts::PI;

/// Base mounting surface to the shoulder (J2) axis, mm (13 in). Published.
pub const D1: f64 = 330.2;
/// Shoulder to elbow (upper arm), mm (12 in). Published.
pub const A2: f64 = 304.8;
/// Elbow to wrist centre (forearm), mm (13 in). Published.
pub const D4: f64 = 330.2;
/// Wrist centre to the tool flange, mm (3 in). Published.
pub const D6: f64 = 76.2;

/// Joint limits, degrees (±). Published.
pub const LIMITS_DEG: [f64; 6] = [175.0, 90.0, 110.0, 180.0, 105.0, 180.0];
/// Maximum joint speeds, degrees per second. Published.
pub const MAX_SPEED_DEG: [f64; 6] = [180.0, 180.0, 180.0, 171.0, 173.0, 171.0];
/// Joint accelerations, degrees per second squared. From one source (ReaK's planner limits),
/// so an assumption as far as the C500 is concerned.
pub const MAX_ACCEL_DEG: [f64; 6] = [720.0, 720.0, 720.0, 1430.0, 1430.0, 1430.0];
/// Motor encoder lines per revolution. Published.
pub const ENCODER_LINES: [f64; 6] = [1000.0, 1000.0, 1000.0, 500.0, 500.0, 500.0];
/// Gear ratios (harmonic drives). Published.
pub const GEAR_RATIOS: [f64; 6] = [100.0, 100.0, 100.0, 101.0, 100.0, 101.0];

/// Joint limits in radians.
pub const LIMITS_RAD: [f64; 6] = {
    let mut out = [0.0; 6];
    let mut i = 0;
    while i < 6 {
        out[i] = LIMITS_DEG[i] * (PI / 180.0);
        i += 1;
    }
    out
};

/// Joint limits in radians.
pub fn limits() -> [f64; 6] {
    LIMITS_RAD
}

/// Maximum joint speeds in radians per second.
pub fn max_speeds() -> [f64; 6] {
    MAX_SPEED_DEG.map(f64::to_radians)
}

/// Joint accelerations in radians per second squared (assumed).
pub fn max_accels() -> [f64; 6] {
    MAX_ACCEL_DEG.map(f64::to_radians)
}

/// Encoder counts per radian of each joint: lines × 4 (quadrature) × gear ratio per turn.
/// That the C500's precision points count these quadrature counts is an assumption.
pub fn counts_per_radian() -> [f64; 6] {
    let mut out = [0.0; 6];
    for i in 0..6 {
        out[i] = ENCODER_LINES[i] * 4.0 * GEAR_RATIOS[i] / (2.0 * PI);
    }
    out
}

/// Joint angles (radians) to precision-point counts, rounded. Counts are 0 at joint zero
/// (assumption).
pub fn joints_to_counts(q: &[f64; 6]) -> [i32; 6] {
    let c = counts_per_radian();
    let mut out = [0; 6];
    for i in 0..6 {
        out[i] = (q[i] * c[i]).round() as i32;
    }
    out
}

/// Precision-point counts to joint angles (radians).
pub fn counts_to_joints(counts: &[f64; 6]) -> [f64; 6] {
    let c = counts_per_radian();
    let mut out = [0.0; 6];
    for i in 0..6 {
        out[i] = counts[i] / c[i];
    }
    out
}

/// The READY pose: all joints 0, the arm straight up. Assumption: no public text gives the
/// A465's READY joint values; every model's zero pose is this upright one.
pub const READY: [f64; 6] = [0.0; 6];

/// Whether joint values lie within the limits (with a hair of tolerance for rounding).
pub fn within_limits(q: &[f64; 6]) -> bool {
    q.iter().zip(LIMITS_RAD).all(|(x, l)| x.abs() <= l + 1e-9)
}

/// How far past a limit a joint value may come and still mean the limit, rad: a value sent as
/// a C `float` (the manual's SLocData) rounds up to 1.2e-7 past it (175 deg as f32 is
/// 3.05432630, the limit 3.05432619).
pub const LIMIT_SLACK: f64 = 1e-6;

/// The joint values with each one within [`LIMIT_SLACK`] past its limit set to the limit
/// (the rest unchanged, so a value truly beyond is still refused).
pub fn snap_to_limits(q: &[f64; 6]) -> [f64; 6] {
    std::array::from_fn(|i| {
        let l = LIMITS_RAD[i];
        if q[i].abs() > l && q[i].abs() <= l + LIMIT_SLACK {
            l.copysign(q[i])
        } else {
            q[i]
        }
    })
}

/// Index of the first joint outside its limit.
pub fn first_outside_limits(q: &[f64; 6]) -> Option<usize> {
    let lim = limits();
    (0..6).find(|&i| q[i].abs() > lim[i] + 1e-9)
}

//! Motion in time: a path in joint space, parametrised by s in 0..1, and a profile s(t) that
//! keeps every joint within its speed and acceleration limits (and the tool within its
//! Cartesian limits) all along the path (docs/a465.md, "Motion").
//!
//! A path is either a joint-interpolated straight segment in joint space, or a C1 cubic
//! Hermite spline through inverse-kinematics samples of a straight line of the tool. For
//! either, the first and second derivatives of every joint with respect to s are bounded
//! exactly, segment by segment, and a profile whose s' stays within V and whose s'' stays
//! within A keeps joint i within
//!
//! ```text
//! |dq_i/dt|   = |q_i'(s)| s'                 <= max|q_i'| V
//! |d2q_i/dt2| = |q_i''(s) s'^2 + q_i'(s) s''| <= max|q_i''| V^2 + max|q_i'| A
//! ```
//!
//! so choosing V and A from these bounds keeps every joint within its limits at every
//! instant, not only at the samples. A joint path is timed by one trapezoid within V and A
//! ([`Profile::trapezoid`]); a straight line's spline by the same bounds taken stretch by
//! stretch, each stretch as fast as its own bounds allow ([`Profile::along`]).

use std::sync::Arc;

use crate::kinematics::Joints;

/// One phase of a profile: constant acceleration from a start.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Phase {
    /// When it starts, s (absolute time).
    t: f64,
    /// s at its start.
    s: f64,
    /// s' at its start.
    v: f64,
    /// s'' during it.
    a: f64,
}

/// s(t): phases of constant acceleration, from s = 0 at rest to the end at rest.
#[derive(Clone, Debug, PartialEq)]
pub struct Profile {
    /// Shared, so that copies of an arm (a view's, a test's) cost little.
    phases: Arc<Vec<Phase>>,
    end: f64,
    s_end: f64,
    /// How a stop may decelerate.
    brake: Brake,
}

/// How a stop decelerates along the path.
#[derive(Clone, Debug, PartialEq)]
enum Brake {
    /// At one rate |s''| the limits allow anywhere on the path below the cruise speed.
    Rate(f64),
    /// As hard as each stretch of the path allows at the speed it goes (a profile timed
    /// along the path, [`Profile::along`]).
    Stretches(Arc<Vec<Stretch>>),
}

/// One constraint on a stretch of path: |s''| d1 + s'^2 d2 <= a (a joint's acceleration, with
/// d1 and d2 the largest |q'(s)| and |q''(s)| on the stretch; or the tool's linear
/// acceleration, with d1 the line's length and d2 0).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Limit {
    a: f64,
    d1: f64,
    d2: f64,
}

/// The largest s'^2 of any stretch.
const X_CEILING: f64 = 1e12;

/// A stretch [s0, s1] of a path with what limits s' and s'' on it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stretch {
    s0: f64,
    s1: f64,
    /// The largest s'^2 on it (joint speeds, the linear speed, and s'' = 0 being possible).
    x_max: f64,
    limits: [Limit; 7],
}

impl Stretch {
    /// A stretch with its derivative bounds `b`, under joint `speeds` and `accels`, and a
    /// linear limit if it is a line: `linear` = (d1, d2, (mm/s, mm/s^2)), with d1 and d2 the
    /// largest |dx/ds| and |d2x/ds2| of the tool's distance x along the line on the stretch
    /// (its length and 0 where x is linear in s).
    pub fn new(
        s0: f64,
        s1: f64,
        b: &Bounds,
        speeds: &[f64; 6],
        accels: &[f64; 6],
        linear: Option<(f64, f64, (f64, f64))>,
    ) -> Stretch {
        let mut limits = [Limit::default(); 7];
        let mut x_max = f64::INFINITY;
        for i in 0..6 {
            limits[i] = Limit {
                a: accels[i],
                d1: b.d1[i],
                d2: b.d2[i],
            };
            if b.d1[i] > 0.0 {
                x_max = x_max.min((speeds[i] / b.d1[i]).powi(2));
            }
            if b.d2[i] > 0.0 {
                x_max = x_max.min(accels[i] / b.d2[i]);
            }
        }
        if let Some((d1, d2, (v, a))) = linear.filter(|(d1, d2, _)| *d1 > 0.0 || *d2 > 0.0) {
            limits[6] = Limit { a, d1, d2 };
            if d1 > 0.0 {
                x_max = x_max.min((v / d1).powi(2));
            }
            if d2 > 0.0 {
                x_max = x_max.min(a / d2);
            }
        }
        Stretch {
            s0,
            s1,
            // Where nothing moves nothing limits s': a bound all the same, so that every
            // figure stays finite (s' of 10^6 per second crosses any stretch at once).
            x_max: x_max.min(X_CEILING),
            limits,
        }
    }

    /// The largest |s''| allowed at s'^2 = `x` (at most `x_max`).
    fn accel(&self, x: f64) -> f64 {
        self.limits
            .iter()
            .filter(|l| l.d1 > 0.0)
            .map(|l| (l.a - l.d2 * x) / l.d1)
            .fold(f64::INFINITY, f64::min)
            .max(0.0)
    }

    /// The largest s'^2 at one end of `len` of this stretch from which s'^2 = `x` at the
    /// other end can be reached (accelerating from `x`, or braking down to it), the
    /// acceleration taken at the faster end: the largest y with y - 2 len accel(y) <= x, at
    /// most `x_max`.
    fn reach(&self, x: f64, len: f64) -> f64 {
        self.limits
            .iter()
            .filter(|l| l.d1 > 0.0)
            .map(|l| (x + 2.0 * len * l.a / l.d1) / (1.0 + 2.0 * len * l.d2 / l.d1))
            .fold(self.x_max, f64::min)
    }
}

/// How long a motion along a path of no length takes to stop (s): it moves nothing.
const NO_LENGTH_STOP: f64 = 1e-3;

impl Profile {
    /// The fastest trapezoid from s = 0 to 1 with |s'| <= `v` and |s''| <= `a`, starting at
    /// `start`, lasting at least `min_duration`.
    pub fn trapezoid(start: f64, v: f64, a: f64, min_duration: f64) -> Profile {
        // A path of no length: nothing limits it but the minimum duration. Nothing moves on
        // it either, so a Halt stops it at once (its own rate would take half the duration:
        // Ctrl-C during a Home at the home pose waited up to 3 s).
        let no_length = !(v.is_finite() && a.is_finite());
        let (v, a) = if !no_length {
            (v, a)
        } else if min_duration > 0.0 {
            (2.0 / min_duration, 4.0 / (min_duration * min_duration))
        } else {
            return Profile::still(start);
        };
        let (mut v, a) = (v.max(1e-12), a.max(1e-12));
        // At least min_duration: lower the cruise speed (T = 1/v + v/a, the smaller root).
        let fastest = if v * v / a >= 1.0 {
            2.0 / a.sqrt()
        } else {
            1.0 / v + v / a
        };
        if min_duration > fastest && min_duration * min_duration >= 4.0 / a {
            let t = min_duration;
            v = (t - (t * t - 4.0 / a).sqrt()) * a / 2.0;
        }
        let (ta, cruise) = if v * v / a >= 1.0 {
            ((1.0 / a).sqrt(), 0.0)
        } else {
            (v / a, 1.0 / v - v / a)
        };
        let vp = a * ta;
        let s1 = 0.5 * a * ta * ta;
        let phases = vec![
            Phase {
                t: start,
                s: 0.0,
                v: 0.0,
                a,
            },
            Phase {
                t: start + ta,
                s: s1,
                v: vp,
                a: 0.0,
            },
            Phase {
                t: start + ta + cruise,
                s: s1 + vp * cruise,
                v: vp,
                a: -a,
            },
        ];
        Profile {
            phases: Arc::new(phases),
            end: start + 2.0 * ta + cruise,
            s_end: 1.0,
            brake: Brake::Rate(if no_length { vp / NO_LENGTH_STOP } else { a }),
        }
    }

    /// The fastest s(t) from s = 0 at rest to 1 at rest within the limits of each of
    /// `stretches` (consecutive, covering 0..1), starting at `start`: time-optimal path
    /// parameterization by reachability analysis (H. Pham, Q.-C. Pham, "A New Approach to
    /// Time-Optimal Path Parameterization Based on Reachability Analysis", IEEE Transactions
    /// on Robotics 34(3), 2018), on the stretches as its grid, with s'' constant on each. A
    /// backward pass finds the fastest s'^2 at each grid point from which the end can still be
    /// reached at rest; a forward pass accelerates as hard as allowed under it. Each
    /// stretch's constraint uses the largest |q'| and |q''| on it and the larger s'^2 of its
    /// ends, so the limits hold at every instant, not only at the grid points.
    pub fn along(start: f64, stretches: Vec<Stretch>) -> Profile {
        let n = stretches.len();
        if n == 0 {
            return Profile::still(start);
        }
        // Backward: the fastest s'^2 at each grid point that can still stop at s = 1.
        let mut back = vec![0.0; n + 1];
        for k in (0..n).rev() {
            let st = &stretches[k];
            let mut x = st.reach(back[k + 1], st.s1 - st.s0);
            if k > 0 {
                x = x.min(stretches[k - 1].x_max);
            }
            back[k] = x.max(0.0);
        }
        back[0] = 0.0;
        // Forward: as fast as allowed under the backward pass.
        let mut phases = Vec::with_capacity(n);
        let (mut t, mut x) = (start, 0.0f64);
        for (k, st) in stretches.iter().enumerate() {
            let len = st.s1 - st.s0;
            let next = st.reach(x, len).min(back[k + 1]).max(0.0);
            let (v0, v1) = (x.sqrt(), next.sqrt());
            let dt = if v0 + v1 > 0.0 {
                2.0 * len / (v0 + v1)
            } else {
                0.0
            };
            if dt > 0.0 {
                phases.push(Phase {
                    t,
                    s: st.s0,
                    v: v0,
                    a: (next - x) / (2.0 * len),
                });
            }
            t += dt;
            x = next;
        }
        if phases.is_empty() {
            return Profile::still(start);
        }
        Profile {
            phases: Arc::new(phases),
            end: t,
            s_end: 1.0,
            brake: Brake::Stretches(Arc::new(stretches)),
        }
    }

    /// s = (t - start) / `duration`: the path at one speed from start to end (a timed
    /// trajectory, whose path carries the times: it starts and ends at rest because its
    /// tangents are 0 there, [`Path::timed`]). A stop decelerates at `brake` (s'').
    pub fn steady(start: f64, duration: f64, brake: f64) -> Profile {
        if !(duration.is_finite() && duration > 0.0) {
            return Profile::still(start);
        }
        Profile {
            phases: Arc::new(vec![Phase {
                t: start,
                s: 0.0,
                v: 1.0 / duration,
                a: 0.0,
            }]),
            end: start + duration,
            s_end: 1.0,
            brake: Brake::Rate(brake.max(1e-12)),
        }
    }

    /// A profile that stays at s = 0 (an empty motion).
    pub fn still(start: f64) -> Profile {
        Profile {
            phases: Arc::new(vec![Phase {
                t: start,
                s: 0.0,
                v: 0.0,
                a: 0.0,
            }]),
            end: start,
            s_end: 0.0,
            brake: Brake::Rate(1.0),
        }
    }

    /// When it starts.
    pub fn start(&self) -> f64 {
        self.phases[0].t
    }

    /// When it ends (at rest).
    pub fn end(&self) -> f64 {
        self.end
    }

    /// s where it ends: 1, or less for a motion stopped early.
    pub fn s_end(&self) -> f64 {
        self.s_end
    }

    fn phase(&self, t: f64) -> &Phase {
        let i = self.phases.partition_point(|p| p.t <= t);
        &self.phases[i.saturating_sub(1)]
    }

    /// (s, s') at `t`.
    pub fn at(&self, t: f64) -> (f64, f64) {
        if t <= self.start() {
            return (0.0, 0.0);
        }
        if t >= self.end {
            return (self.s_end, 0.0);
        }
        let p = self.phase(t);
        let dt = t - p.t;
        let s = (p.s + p.v * dt + 0.5 * p.a * dt * dt).clamp(0.0, self.s_end);
        (s, (p.v + p.a * dt).max(0.0))
    }

    /// Stop as soon as the limits allow, from `t` on: decelerate as hard as the limits allow
    /// until at rest, along the same path. Returns the s where it comes to rest.
    pub fn stop_at(&mut self, t: f64) -> f64 {
        if t >= self.end {
            return self.s_end;
        }
        let t = t.max(self.start());
        let (s, v) = self.at(t);
        let keep = self.phases.partition_point(|p| p.t <= t).max(1);
        let phases = Arc::make_mut(&mut self.phases);
        phases.truncate(keep);
        if t <= phases[0].t {
            // Not started yet: it never will.
            phases[0].a = 0.0;
            self.end = t;
            self.s_end = 0.0;
            return 0.0;
        }
        match &self.brake {
            Brake::Rate(brake) => {
                phases.push(Phase { t, s, v, a: -brake });
                let stop = v / brake;
                self.end = t + stop;
                self.s_end = (s + 0.5 * v * stop).min(self.s_end);
            }
            Brake::Stretches(stretches) => {
                // Stretch by stretch, as hard as each allows at the speed it is entered
                // with (the fastest on it, as the speed only falls).
                let (mut t, mut s, mut v) = (t, s, v);
                let mut k = stretches.partition_point(|st| st.s1 <= s);
                while v > 0.0 && k < stretches.len() {
                    let st = &stretches[k];
                    let brake = st.accel(v * v);
                    phases.push(Phase { t, s, v, a: -brake });
                    let left = st.s1 - s;
                    if brake > 0.0 && v * v <= 2.0 * brake * left {
                        // At rest within this stretch.
                        t += v / brake;
                        s += 0.5 * v * v / brake;
                        v = 0.0;
                    } else {
                        let v1 = (v * v - 2.0 * brake * left).max(0.0).sqrt();
                        t += 2.0 * left / (v + v1);
                        s = st.s1;
                        v = v1;
                        k += 1;
                    }
                }
                self.end = t;
                self.s_end = s.min(self.s_end);
            }
        }
        self.s_end
    }
}

/// Bounds of a path's derivatives with respect to s, per joint.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Bounds {
    /// max |q_i'(s)|.
    pub d1: [f64; 6],
    /// max |q_i''(s)|.
    pub d2: [f64; 6],
}

impl Bounds {
    /// The largest s' and s'' that keep every joint within `speeds` and `accels`: the speed
    /// bound first, lowered where curvature would use more than half of an acceleration
    /// limit at that speed; the acceleration bound from what is left.
    pub fn limits(&self, speeds: &[f64; 6], accels: &[f64; 6]) -> (f64, f64) {
        let mut v = f64::INFINITY;
        for i in 0..6 {
            if self.d1[i] > 0.0 {
                v = v.min(speeds[i] / self.d1[i]);
            }
            if self.d2[i] > 0.0 {
                v = v.min((accels[i] / (2.0 * self.d2[i])).sqrt());
            }
        }
        let a = (0..6)
            .filter(|i| self.d1[*i] > 0.0)
            .map(|i| (accels[i] - self.d2[i] * v * v) / self.d1[i])
            .fold(f64::INFINITY, f64::min);
        (v, a)
    }
}

/// A path in joint space over s in 0..1.
#[derive(Clone, Debug, PartialEq)]
pub enum Path {
    /// Every joint linear in s (joint-interpolated motion).
    Joint {
        /// At s = 0.
        from: Joints,
        /// At s = 1.
        to: Joints,
    },
    /// A C1 cubic Hermite spline through `q` at the increasing parameters `s` (from 0 to 1),
    /// with tangents `m` (dq/ds).
    Spline {
        /// The parameters.
        s: Vec<f64>,
        /// The joints there.
        q: Vec<Joints>,
        /// dq/ds there.
        m: Vec<Joints>,
    },
}

/// The cubic Hermite basis on one segment of length `h` at t in 0..1: (value, d/ds, d2/ds2).
fn hermite(p0: f64, p1: f64, m0: f64, m1: f64, h: f64, t: f64) -> (f64, f64, f64) {
    let (t2, t3) = (t * t, t * t * t);
    let value = (2.0 * t3 - 3.0 * t2 + 1.0) * p0
        + (t3 - 2.0 * t2 + t) * h * m0
        + (-2.0 * t3 + 3.0 * t2) * p1
        + (t3 - t2) * h * m1;
    let d1 = ((6.0 * t2 - 6.0 * t) * p0
        + (3.0 * t2 - 4.0 * t + 1.0) * h * m0
        + (-6.0 * t2 + 6.0 * t) * p1
        + (3.0 * t2 - 2.0 * t) * h * m1)
        / h;
    let d2 = ((12.0 * t - 6.0) * p0
        + (6.0 * t - 4.0) * h * m0
        + (-12.0 * t + 6.0) * p1
        + (6.0 * t - 2.0) * h * m1)
        / (h * h);
    (value, d1, d2)
}

impl Path {
    /// A spline through `q` at `s`, tangents by finite differences (three-point, for uneven
    /// spacing; one-sided at the ends).
    pub fn spline(s: Vec<f64>, q: Vec<Joints>) -> Path {
        let n = s.len();
        let m = (0..n)
            .map(|k| {
                std::array::from_fn(|i| {
                    if n < 2 {
                        0.0
                    } else if k == 0 {
                        (q[1][i] - q[0][i]) / (s[1] - s[0])
                    } else if k == n - 1 {
                        (q[n - 1][i] - q[n - 2][i]) / (s[n - 1] - s[n - 2])
                    } else {
                        let (h0, h1) = (s[k] - s[k - 1], s[k + 1] - s[k]);
                        let d0 = (q[k][i] - q[k - 1][i]) / h0;
                        let d1 = (q[k + 1][i] - q[k][i]) / h1;
                        (h1 * d0 + h0 * d1) / (h0 + h1)
                    }
                })
            })
            .collect();
        Path::Spline { s, q, m }
    }

    /// A timed path through `q` at `s` (a trajectory's times over its duration, from 0 to
    /// 1): tangents as [`Path::spline`] has them inside, 0 at both ends, so that a steady
    /// profile over it ([`Profile::steady`]) starts and ends at rest and passes each point
    /// at its time.
    pub fn timed(s: Vec<f64>, q: Vec<Joints>) -> Path {
        let Path::Spline { s, q, mut m } = Path::spline(s, q) else {
            unreachable!("Path::spline makes a spline")
        };
        if let Some(first) = m.first_mut() {
            *first = [0.0; 6];
        }
        if let Some(last) = m.last_mut() {
            *last = [0.0; 6];
        }
        Path::Spline { s, q, m }
    }

    /// The joints at parameter `s`.
    pub fn at(&self, s: f64) -> Joints {
        match self {
            Path::Joint { from, to } if s >= 1.0 => *to,
            Path::Joint { from, to } => std::array::from_fn(|i| from[i] + (to[i] - from[i]) * s),
            Path::Spline { s: ss, q, m } => {
                if s <= ss[0] {
                    return q[0];
                }
                let last = ss.len() - 1;
                if s >= ss[last] {
                    return q[last];
                }
                let k = ss.partition_point(|x| *x <= s).clamp(1, last) - 1;
                let h = ss[k + 1] - ss[k];
                let t = (s - ss[k]) / h;
                std::array::from_fn(|i| hermite(q[k][i], q[k + 1][i], m[k][i], m[k + 1][i], h, t).0)
            }
        }
    }

    /// The exact bounds of the first and second derivatives over the whole path.
    pub fn bounds(&self) -> Bounds {
        let mut b = Bounds::default();
        match self {
            Path::Joint { from, to } => {
                for i in 0..6 {
                    b.d1[i] = (to[i] - from[i]).abs();
                }
            }
            Path::Spline { s, q, m } => {
                for k in 0..s.len().saturating_sub(1) {
                    let h = s[k + 1] - s[k];
                    for i in 0..6 {
                        let at = |t: f64| hermite(q[k][i], q[k + 1][i], m[k][i], m[k + 1][i], h, t);
                        // q'' is linear in t: its extremes are at the ends. q' is quadratic:
                        // the ends and its vertex (where q'' = 0).
                        let (_, d1a, d2a) = at(0.0);
                        let (_, d1b, d2b) = at(1.0);
                        let mut d1 = d1a.abs().max(d1b.abs());
                        if d2a * d2b < 0.0 {
                            let t = d2a / (d2a - d2b);
                            d1 = d1.max(at(t).1.abs());
                        }
                        b.d1[i] = b.d1[i].max(d1);
                        b.d2[i] = b.d2[i].max(d2a.abs()).max(d2b.abs());
                    }
                }
            }
        }
        b
    }

    /// How many segments: a spline's between its samples, 1 for a joint path.
    pub fn segments(&self) -> usize {
        match self {
            Path::Joint { .. } => 1,
            Path::Spline { s, .. } => s.len().saturating_sub(1),
        }
    }

    /// The path cut into stretches, `per_segment` to each segment of a spline (one for a
    /// joint path), each with the exact bounds of the derivatives on it: the grid of
    /// [`Profile::along`].
    pub fn pieces(&self, per_segment: usize) -> Vec<(f64, f64, Bounds)> {
        let per = per_segment.max(1);
        match self {
            Path::Joint { .. } => vec![(0.0, 1.0, self.bounds())],
            Path::Spline { s, q, m } => {
                let mut out = Vec::with_capacity(s.len().saturating_sub(1) * per);
                for k in 0..s.len().saturating_sub(1) {
                    let h = s[k + 1] - s[k];
                    for j in 0..per {
                        let (ta, tb) = (j as f64 / per as f64, (j + 1) as f64 / per as f64);
                        let mut b = Bounds::default();
                        for i in 0..6 {
                            let at =
                                |t: f64| hermite(q[k][i], q[k + 1][i], m[k][i], m[k + 1][i], h, t);
                            let (_, d1a, d2a) = at(ta);
                            let (_, d1b, d2b) = at(tb);
                            let mut d1 = d1a.abs().max(d1b.abs());
                            // q' peaks inside where q'' (linear) crosses 0.
                            if d2a * d2b < 0.0 {
                                let t = ta + (tb - ta) * d2a / (d2a - d2b);
                                d1 = d1.max(at(t).1.abs());
                            }
                            b.d1[i] = d1;
                            b.d2[i] = d2a.abs().max(d2b.abs());
                        }
                        out.push((s[k] + h * ta, s[k] + h * tb, b));
                    }
                }
                out
            }
        }
    }

    /// The smallest and largest value of each joint over the whole path.
    pub fn range(&self) -> ([f64; 6], [f64; 6]) {
        let mut lo = [f64::INFINITY; 6];
        let mut hi = [f64::NEG_INFINITY; 6];
        let mut take = |q: &Joints| {
            for i in 0..6 {
                lo[i] = lo[i].min(q[i]);
                hi[i] = hi[i].max(q[i]);
            }
        };
        match self {
            Path::Joint { from, to } => {
                take(from);
                take(to);
            }
            Path::Spline { s, q, m } => {
                q.iter().for_each(&mut take);
                // Inside a segment a joint peaks where q' = 0: the roots of a quadratic.
                for k in 0..s.len().saturating_sub(1) {
                    let h = s[k + 1] - s[k];
                    for i in 0..6 {
                        let (p0, p1, m0, m1) = (q[k][i], q[k + 1][i], m[k][i] * h, m[k + 1][i] * h);
                        // d/dt of the cubic: 3c t^2 + 2b t + m0.
                        let c = 2.0 * p0 + m0 - 2.0 * p1 + m1;
                        let bq = -3.0 * p0 - 2.0 * m0 + 3.0 * p1 - m1;
                        let roots: Vec<f64> = if c.abs() < 1e-15 {
                            if bq.abs() < 1e-15 {
                                vec![]
                            } else {
                                vec![-m0 / (2.0 * bq)]
                            }
                        } else {
                            let disc = 4.0 * bq * bq - 12.0 * c * m0;
                            if disc < 0.0 {
                                vec![]
                            } else {
                                let r = disc.sqrt();
                                vec![(-2.0 * bq + r) / (6.0 * c), (-2.0 * bq - r) / (6.0 * c)]
                            }
                        };
                        for t in roots.into_iter().filter(|t| *t > 0.0 && *t < 1.0) {
                            let v = hermite(q[k][i], q[k + 1][i], m[k][i], m[k + 1][i], h, t).0;
                            lo[i] = lo[i].min(v);
                            hi[i] = hi[i].max(v);
                        }
                    }
                }
            }
        }
        (lo, hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_trapezoid_reaches_one_at_rest_within_its_limits() {
        for (v, a) in [(2.0, 10.0), (0.5, 0.7), (10.0, 1.0)] {
            let p = Profile::trapezoid(1.0, v, a, 0.0);
            assert_eq!(p.at(1.0), (0.0, 0.0));
            let (s, sv) = p.at(p.end());
            assert_eq!((s, sv), (1.0, 0.0));
            let mut prev = p.at(1.0);
            let dt = 1e-4;
            let mut t = 1.0;
            while t < p.end() {
                t += dt;
                let now = p.at(t);
                assert!(now.1 <= v + 1e-9, "s' {} > {v}", now.1);
                assert!((now.1 - prev.1).abs() / dt <= a * 1.0001 + 1e-6);
                assert!((now.0 - prev.0) >= -1e-12);
                prev = now;
            }
        }
        let slow = Profile::trapezoid(0.0, 2.0, 10.0, 5.0);
        assert!((slow.end() - 5.0).abs() < 1e-9, "{}", slow.end());
        let dwell = Profile::trapezoid(0.0, f64::INFINITY, f64::INFINITY, 2.0);
        assert!((dwell.end() - 2.0).abs() < 1e-9, "{}", dwell.end());
        assert_eq!(Profile::trapezoid(3.0, f64::INFINITY, 1.0, 0.0).end(), 3.0);
    }

    #[test]
    fn a_stop_decelerates_at_the_brake_rate_and_stays_on_the_path() {
        let mut p = Profile::trapezoid(0.0, 1.0, 2.0, 0.0);
        let (s0, v0) = p.at(0.7);
        let s_stop = p.stop_at(0.7);
        assert!((s_stop - (s0 + v0 * v0 / 4.0)).abs() < 1e-12);
        assert!((p.end() - (0.7 + v0 / 2.0)).abs() < 1e-12);
        assert_eq!(p.at(p.end() + 1.0), (s_stop, 0.0));
        let (s_mid, _) = p.at(0.7 + v0 / 4.0);
        assert!(s_mid > s0 && s_mid < s_stop);
    }

    fn uniform(path: &Path, n: usize, speeds: &[f64; 6], accels: &[f64; 6]) -> Vec<Stretch> {
        let b = path.bounds();
        (0..n)
            .map(|k| {
                let (s0, s1) = (k as f64 / n as f64, (k + 1) as f64 / n as f64);
                Stretch::new(s0, s1, &b, speeds, accels, None)
            })
            .collect()
    }

    #[test]
    fn timed_along_a_straight_joint_path_it_comes_close_to_the_trapezoid() {
        let path = Path::Joint {
            from: [0.0; 6],
            to: [1.0, -0.5, 0.2, 0.0, 0.0, 0.3],
        };
        let (speeds, accels) = ([1.0; 6], [2.0; 6]);
        let (v, a) = path.bounds().limits(&speeds, &accels);
        let best = Profile::trapezoid(0.0, v, a, 0.0).end();
        let p = Profile::along(0.0, uniform(&path, 400, &speeds, &accels));
        assert!(p.end() >= best - 1e-9, "{} faster than {best}", p.end());
        assert!(p.end() < best * 1.02, "{} against {best}", p.end());
        assert_eq!(p.at(p.end()), (1.0, 0.0));
        // Its speed and acceleration stay within the limits.
        let dt = 1e-4;
        let (mut t, mut prev) = (0.0, p.at(0.0));
        while t < p.end() {
            t += dt;
            let now = p.at(t);
            assert!(now.1 <= v * (1.0 + 1e-9), "s' {} > {v}", now.1);
            assert!((now.1 - prev.1).abs() / dt <= a * 1.0001 + 1e-6);
            prev = now;
        }
    }

    #[test]
    fn a_path_that_does_not_move_takes_no_time_and_stays_finite() {
        let path = Path::Joint {
            from: [0.3; 6],
            to: [0.3; 6],
        };
        let mut p = Profile::along(2.0, uniform(&path, 8, &[1.0; 6], &[2.0; 6]));
        assert!(p.end().is_finite() && p.end() - 2.0 < 1e-3, "{}", p.end());
        let (s, v) = p.at(2.0 + 1e-9);
        assert!(s.is_finite() && v.is_finite());
        assert_eq!(p.at(p.end()), (1.0, 0.0));
        assert!(p.stop_at(2.0 + 1e-9).is_finite());
    }

    #[test]
    fn a_stop_along_stretches_brakes_within_each_stretchs_limit() {
        let path = Path::Joint {
            from: [0.0; 6],
            to: [2.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        };
        let (speeds, accels) = ([1.0; 6], [2.0; 6]);
        let mut p = Profile::along(0.0, uniform(&path, 100, &speeds, &accels));
        let t = p.end() / 2.0;
        let (s0, v0) = p.at(t);
        let s_stop = p.stop_at(t);
        // Joint 1 moves 2 rad per unit of s: s'' of at most 1 brakes it.
        assert!((s_stop - (s0 + v0 * v0 / 2.0)).abs() < 1e-9, "{s_stop}");
        assert!((p.end() - (t + v0)).abs() < 1e-9);
        assert_eq!(p.at(p.end() + 1.0), (s_stop, 0.0));
    }

    #[test]
    fn spline_bounds_hold_between_the_samples() {
        let s: Vec<f64> = (0..=10).map(|k| k as f64 / 10.0).collect();
        let q: Vec<Joints> = s
            .iter()
            .map(|x| [x.sin(), x * x, -x, 0.0, (3.0 * x).cos(), 0.5])
            .collect();
        let path = Path::spline(s, q);
        let b = path.bounds();
        let (lo, hi) = path.range();
        let h = 1e-4;
        let mut x = h;
        while x < 1.0 - h {
            let (a, c, d) = (path.at(x - h), path.at(x), path.at(x + h));
            for i in 0..6 {
                let d1 = (d[i] - a[i]) / (2.0 * h);
                let d2 = (d[i] - 2.0 * c[i] + a[i]) / (h * h);
                assert!(
                    d1.abs() <= b.d1[i] + 1e-6,
                    "joint {i} d1 {d1} > {}",
                    b.d1[i]
                );
                assert!(
                    d2.abs() <= b.d2[i] + 1e-3,
                    "joint {i} d2 {d2} > {}",
                    b.d2[i]
                );
                assert!(c[i] >= lo[i] - 1e-12 && c[i] <= hi[i] + 1e-12);
            }
            x += 0.0037;
        }
    }
}

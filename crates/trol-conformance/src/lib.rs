//! One conformance suite for every simulated controller (issue 39, item 2): the simulated
//! A465, every simulated C500 variant (RAPL-II), every simulated MARS 8 variant and every
//! simulated C500C variant (RAPL-3), each
//! driven through TROL's API ([`trol::Robot`]) and checked against the twin's own arm, not
//! against what TROL says.
//!
//! What every controller must do ([`run`]):
//!
//! - **the manual's API semantics**: TROLHome, then a motion and TROLFinish, leaves the arm
//!   where the motion asked, and TROLGetPosition says so; motions sent back to back without
//!   a Finish between them (a 1998 program) run one after the other; a motion out of the
//!   arm's range is refused and moves nothing;
//! - **the rule for real controllers**: no call reports success for a motion the arm did not
//!   make (no false success); nothing moves that was not asked for (a refused call, a line
//!   the controller printed unasked); a Halt reports success only with the arm standing;
//!   after a failure the next call works;
//! - **a Home is a home** (issue 62, item 1): a Home halted at several instants, on a homed
//!   and on an unhomed arm, or cut by a power loss (announced, silent, in each form the
//!   controller has), is never reported done unless the arm stands at the home pose; a power
//!   loss is named as such; the next Home works.
//!
//! Where a controller may differ, the difference is named once, in [`Differences`], with
//! the reason; [`subjects`] builds each controller with its differences.

#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod subjects;

use std::time::{Duration, Instant};

use trol::{PosMode, Robot, Tag};
use trol_proto::application::code::{TROL_ERR_NOT_STOPPED, TROL_ERR_ROBOT_UNSURE};
use trol_proto::application::record::Value;
use trol_proto::application::{Reply, table};

/// The twin's own arm: the truth the suite checks TROL's answers against.
pub trait Twin: Send {
    /// Where the arm is, TROL's joints (radians).
    fn joints(&self) -> [f64; 6];
    /// Whether the arm (or the gripper) moves.
    fn moving(&self) -> bool;
    /// Make the controller print a line nobody asked for; `false` where this controller
    /// has no line to print on (the simulated A465).
    fn say_unasked(&self, text: &str) -> bool;
    /// Whether this controller's arm can lose its power in this form: `announced`, the
    /// controller tells of it on its own (a line it prints, a status bit, the embedded
    /// simulator's own arm); otherwise it says nothing, and only what TROL reads of the arm
    /// can show it.
    fn can_lose_power(&self, announced: bool) -> bool;
    /// Cut the arm's power now in that form (an e-stop, a power failure): the axes stop
    /// where they are. Only where [`Twin::can_lose_power`] says so.
    fn cut_power(&self, announced: bool);
    /// Give the arm its power back.
    fn power_on(&self);
}

/// How a controller may differ from the others, each with its reason.
#[derive(Debug, Clone, PartialEq)]
pub struct Differences {
    /// The arm starts not homed: a motion before TROLHome is refused (a real controller's
    /// encoders mean nothing before homing; the simulated A465 starts homed).
    pub starts_unhomed: bool,
    /// No stop this controller has stops its arm (a fault the twin simulates): Halt must
    /// say TROL_ERR_NOT_STOPPED, never success.
    pub unstoppable: bool,
    /// How far (radians, every joint) the arm may end from a motion's target and still be
    /// there: the controller's own arrival tolerance and its encoder resolution.
    pub arrive_rad: f64,
    /// It runs a trajectory (TROLTrajectory) without its times, one joint move per
    /// waypoint (a C500: RAPL-II has no timed path); the others keep the times.
    pub untimed_trajectory: bool,
    /// A motion of several joints at once is refused as unsettled (a C500C: it needs a
    /// joint-space location, which needs the A465's pulses per degree there, not public;
    /// a series of `joint` commands would not be one motion). The suite's motions then
    /// move joint 1 alone, from where TROLHome left the arm.
    pub one_joint_at_a_time: bool,
    /// A motion sent while one runs is refused (BIOS_BUSY), not queued (a C500C: MA goes as
    /// a motion relative to where the arm rests, which is known only once it rests). A 1998
    /// program's back-to-back motions then need TROLFinish between them; the second is
    /// refused and moves nothing.
    pub one_motion_at_a_time: bool,
    /// A trajectory has one waypoint at most (a C500C, for the same reason).
    pub one_waypoint: bool,
    /// After a call it answered UNSURE (a line the controller printed unasked, say), it
    /// sends nothing further until the application connects again, and every call is UNSURE
    /// until then (a C500C: its console may be mid-question or mid-motion, which TROL cannot
    /// tell; docs/c500c.md). Elsewhere the call after the UNSURE one works.
    pub unsure_until_reconnect: bool,
}

impl Default for Differences {
    fn default() -> Self {
        Differences {
            starts_unhomed: false,
            unstoppable: false,
            arrive_rad: 2e-3,
            untimed_trajectory: false,
            one_joint_at_a_time: false,
            one_motion_at_a_time: false,
            one_waypoint: false,
            unsure_until_reconnect: false,
        }
    }
}

/// The positions the suite moves to on one subject: [`Q1`], [`Q2`], [`FAR`] and
/// [`OUT_OF_RANGE`], or, where only one joint may move at a time, the same moves of joint 1
/// alone from where TROLHome left the arm.
#[derive(Clone, Copy, Debug)]
struct Targets {
    q1: [f64; 6],
    q2: [f64; 6],
    far: [f64; 6],
    out_of_range: [f64; 6],
}

impl Targets {
    fn for_subject(s: &Subject) -> Targets {
        if !s.differences.one_joint_at_a_time {
            return Targets {
                q1: Q1,
                q2: Q2,
                far: FAR,
                out_of_range: OUT_OF_RANGE,
            };
        }
        let home = s.twin.joints();
        let j1 = |v: f64| {
            let mut q = home;
            q[0] = v;
            q
        };
        Targets {
            q1: j1(Q1[0]),
            q2: j1(Q2[0]),
            far: j1(FAR[0]),
            out_of_range: j1(OUT_OF_RANGE[0]),
        }
    }
}

/// A controller under test: TROL's API on it, its twin's arm, and how it may differ.
pub struct Subject {
    /// Its name in messages (`C500 default`, `MARS 8 moving-lag`).
    pub label: String,
    /// TROL's API on it.
    pub robot: Robot,
    /// Its arm.
    pub twin: Box<dyn Twin>,
    /// How it may differ.
    pub differences: Differences,
}

/// A joint position every controller reaches from home (radians).
pub const Q1: [f64; 6] = [0.3, 0.2, 0.9, -0.4, 0.6, 0.5];
/// A second one.
pub const Q2: [f64; 6] = [0.2, 0.1, 0.8, -0.3, 0.5, 0.4];
/// A far one, for a motion long enough to halt.
pub const FAR: [f64; 6] = [-1.2, 0.5, 1.6, 1.0, 1.2, -1.0];
/// Joint 1 beyond every A465's range.
pub const OUT_OF_RANGE: [f64; 6] = [4.0, 0.2, 0.9, -0.4, 0.6, 0.5];

/// The longest any step may take on a loaded machine.
const STEP: Duration = Duration::from_secs(30);

fn code(r: trol::Result<()>) -> i16 {
    match r {
        Ok(()) => 0,
        Err(e) => e.code().0,
    }
}

fn near(a: &[f64; 6], b: &[f64; 6], tol: f64) -> bool {
    (0..6).all(|i| (a[i] - b[i]).abs() <= tol)
}

fn fmt(q: &[f64; 6]) -> String {
    format!(
        "[{}]",
        q.iter()
            .map(|x| format!("{x:.4}"))
            .collect::<Vec<_>>()
            .join(", ")
    )
}

/// What one run found.
#[derive(Debug, Default)]
pub struct Findings {
    /// Rule broken: the test fails on any.
    pub broken: Vec<String>,
    /// What happened, step by step (shown when something broke).
    pub steps: Vec<String>,
}

impl Findings {
    fn step(&mut self, s: String) {
        self.steps.push(s);
    }
    fn broke(&mut self, s: String) {
        self.steps.push(format!("BROKEN: {s}"));
        self.broken.push(s);
    }
}

/// Whether the twin's arm stands: two readings 250 ms apart that agree, the twin saying
/// nothing moves.
fn stands(twin: &dyn Twin) -> Result<(), String> {
    let a = twin.joints();
    std::thread::sleep(Duration::from_millis(250));
    let b = twin.joints();
    if twin.moving() {
        return Err(format!("the twin says its arm moves (at {})", fmt(&b)));
    }
    if !near(&a, &b, STILL_RAD) {
        return Err(format!(
            "the arm went from {} to {} in 250 ms",
            fmt(&a),
            fmt(&b)
        ));
    }
    Ok(())
}

/// How far two readings of a standing arm may differ (encoder dither), radians: the
/// backends' own [`trol_controller::real::STILL_DEG`].
const STILL_RAD: f64 = trol_controller::real::STILL_DEG * std::f64::consts::PI / 180.0;

/// Whether the arm is still at `before` and stands.
fn unmoved(twin: &dyn Twin, before: &[f64; 6]) -> Result<(), String> {
    let now = twin.joints();
    if twin.moving() {
        return Err(format!("the twin says its arm moves (at {})", fmt(&now)));
    }
    if !near(before, &now, STILL_RAD) {
        return Err(format!("from {} to {}", fmt(before), fmt(&now)));
    }
    Ok(())
}

/// Wait for the twin's arm to start moving (bounded); whether it did.
fn wait_moving(twin: &dyn Twin, within: Duration) -> bool {
    let until = Instant::now() + within;
    while Instant::now() < until {
        if twin.moving() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    false
}

/// A motion and its Finish: success only with the arm at `q`.
fn motion(s: &mut Subject, f: &mut Findings, what: &str, q: [f64; 6]) -> bool {
    let tol = s.differences.arrive_rad;
    let sent = code(s.robot.ma(&q));
    let done = if sent == 0 {
        code(s.robot.finish())
    } else {
        sent
    };
    let at = s.twin.joints();
    f.step(format!(
        "{what}: MA {} -> {sent}, Finish -> {done}, arm at {}",
        fmt(&q),
        fmt(&at)
    ));
    if done == 0 && !near(&at, &q, tol) {
        f.broke(format!(
            "{what}: success, but the arm is at {} for {}",
            fmt(&at),
            fmt(&q)
        ));
    }
    done == 0
}

/// A trajectory (TROLTrajectory) from Q1 through Q2 back to Q1: timed or untimed as the
/// controller says it runs it (and as its differences say it must), and after Finish the arm
/// at the last waypoint. One too fast for the speed setting is refused and moves nothing;
/// so is one of too many waypoints for a controller that runs them untimed.
fn trajectory(s: &mut Subject, f: &mut Findings, t: &Targets) {
    let wp = |time: f64, joints: [f64; 6]| trol::Waypoint { time, joints };
    // From Q1 (where the motions before left the arm) through Q2 back to Q1; where a
    // trajectory has one waypoint, to Q2 and back in two.
    let paths: Vec<Vec<trol::Waypoint>> = if s.differences.one_waypoint {
        vec![vec![wp(1.0, t.q2)], vec![wp(1.0, t.q1)]]
    } else {
        vec![vec![wp(1.0, t.q2), wp(2.0, t.q1)]]
    };
    let mut r = Ok(trol::Timing::Timed);
    let mut done = 0;
    for path in &paths {
        r = s.robot.trajectory(path);
        done = match &r {
            Ok(_) => code(s.robot.finish()),
            Err(e) => e.code().0,
        };
        if done != 0 {
            break;
        }
    }
    let at = s.twin.joints();
    f.step(format!(
        "Trajectory Q2 at 1 s, Q1 at 2 s ({} call(s)) -> {r:?}, Finish -> {done}, arm at {}",
        paths.len(),
        fmt(&at)
    ));
    let want = if s.differences.untimed_trajectory {
        trol::Timing::Untimed
    } else {
        trol::Timing::Timed
    };
    match r {
        Ok(t) if t != want => f.broke(format!("the trajectory ran {t:?}, expected {want:?}")),
        Ok(_) if done == 0 && !near(&at, &t.q1, s.differences.arrive_rad) => f.broke(format!(
            "the trajectory succeeded, but the arm is at {} for {}",
            fmt(&at),
            fmt(&t.q1)
        )),
        Ok(_) if done != 0 => f.broke(format!("the trajectory's Finish failed ({done})")),
        Ok(_) => {}
        Err(e) => f.broke(format!("a trajectory within the arm's range failed: {e}")),
    }
    // Too fast for the speed setting: refused by every controller (a timed one cannot keep
    // the times; an untimed one would need more than the user's speed setting).
    let mut refusals: Vec<(&str, Vec<trol::Waypoint>)> = vec![("too fast", vec![wp(0.05, t.far)])];
    if s.differences.untimed_trajectory {
        let most = if s.differences.one_waypoint {
            1
        } else {
            trol_controller::UNTIMED_WAYPOINTS
        };
        let many = (1..=most + 1)
            .map(|k| wp(k as f64, if k % 2 == 0 { t.q1 } else { t.q2 }))
            .collect();
        refusals.push(("too many waypoints", many));
    }
    for (what, path) in refusals {
        let before = s.twin.joints();
        let refused = s.robot.trajectory(&path);
        std::thread::sleep(Duration::from_millis(200));
        f.step(format!("a trajectory {what} -> {refused:?}"));
        if refused.is_ok() {
            let cf = code(s.robot.finish());
            f.broke(format!("a trajectory {what} was accepted (Finish {cf})"));
        } else if let Err(e) = unmoved(s.twin.as_ref(), &before) {
            f.broke(format!("a refused trajectory ({what}) moved the arm: {e}"));
        }
    }
}

/// When, after the arm is seen homing, the suite halts it (issue 62, item 2: every instant of
/// a Home on a homed arm was reported a success).
const HOME_HALTS: [Duration; 2] = [Duration::from_millis(0), Duration::from_millis(300)];

/// Send TROLHome(0) alone (not waiting for its end, as a 1998 program's TROLHome then its
/// TROLFinish) and see the arm start: whether it did (the step says why not).
fn start_home(s: &mut Subject, f: &mut Findings, what: &str) -> bool {
    let h = match s.robot.call(&table::HOME, &[Value::Int(0)]) {
        Ok(Reply::Code(c)) => c.0,
        Ok(other) => {
            f.broke(format!("{what}: TROLHome answered {other:?}"));
            return false;
        }
        Err(e) => e.code().0,
    };
    if h != 0 || !wait_moving(s.twin.as_ref(), STEP) {
        f.step(format!(
            "{what}: TROLHome(0) -> {h}, the arm not seen moving"
        ));
        let _ = s.robot.finish();
        return false;
    }
    true
}

/// Wait (bounded) for the twin's arm to stand.
fn wait_standing(twin: &dyn Twin) {
    let until = Instant::now() + STEP;
    while twin.moving() && Instant::now() < until {
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// A Home halted `after` it was seen to start, on an arm `was` (homed, not homed): TROLHome
/// and the Finish after it may report success only with the arm seen at the home pose.
/// Whether the Home was halted (false: it was not seen to start).
fn halt_a_home(
    s: &mut Subject,
    f: &mut Findings,
    home_pose: &[f64; 6],
    after: Duration,
    was: &str,
) -> bool {
    let what = format!("a Home on an arm {was}, halted after {after:?}");
    if near(&s.twin.joints(), home_pose, s.differences.arrive_rad) {
        f.step(format!("{what}: the arm is at the home pose, not checked"));
        return false;
    }
    if !start_home(s, f, &what) {
        return false;
    }
    std::thread::sleep(after);
    let stop = code(s.robot.halt());
    wait_standing(s.twin.as_ref());
    let hf = code(s.robot.finish());
    let at = s.twin.joints();
    f.step(format!(
        "{what}: Halt -> {stop}, Finish -> {hf}, the arm at {}",
        fmt(&at)
    ));
    if hf == 0 && !near(&at, home_pose, s.differences.arrive_rad) {
        f.broke(format!(
            "{what}: reported done with the arm at {}, not at the home pose {}",
            fmt(&at),
            fmt(home_pose)
        ));
    }
    true
}

/// A whole Home: success, and the arm at the home pose. Whether both.
fn home_again(s: &mut Subject, f: &mut Findings, home_pose: &[f64; 6], after: &str) -> bool {
    let again = code(s.robot.home(0));
    let again_f = if again == 0 {
        code(s.robot.finish())
    } else {
        again
    };
    f.step(format!("TROLHome(0) after {after} -> {again_f}"));
    if again_f != 0 {
        f.broke(format!("the Home after {after} failed ({again_f})"));
        return false;
    }
    if !near(&s.twin.joints(), home_pose, s.differences.arrive_rad) {
        f.broke(format!(
            "the Home after {after} was reported done with the arm at {}",
            fmt(&s.twin.joints())
        ));
        return false;
    }
    true
}

/// Homes halted on their way at each of [`HOME_HALTS`], first on an arm that was homed and
/// stands away from the home pose, then (the halt having left it unhomed) on the same arm
/// not homed; then a whole Home works, and a motion takes the arm away for the next instant.
fn halted_home(s: &mut Subject, f: &mut Findings, home_pose: &[f64; 6]) {
    for after in HOME_HALTS {
        if !halt_a_home(s, f, home_pose, after, "homed") {
            continue;
        }
        halt_a_home(s, f, home_pose, after, "not homed (the Home before halted)");
        if !home_again(s, f, home_pose, "a halted Home") {
            return;
        }
        // Away from the home pose again, for the next instant.
        let away = Targets::for_subject(s).q1;
        if !motion(s, f, "a motion after a halted Home", away) {
            f.broke("a motion after a halted Home and a Home failed".into());
            return;
        }
    }
}

/// The arm's power lost during a Home, in each form this controller has (announced,
/// silent), on a homed arm away from the home pose: TROLHome's Finish is never success and
/// names the power (BIOS_ARM_POWER), or says TROL cannot tell (UNSURE); with the power off
/// a motion is refused and nothing moves; with the power back a Home works. Whether the
/// controller still takes calls (false: it sends nothing further until reconnect).
fn power_lost_home(s: &mut Subject, f: &mut Findings, home_pose: &[f64; 6]) -> bool {
    for announced in [true, false] {
        if !s.twin.can_lose_power(announced) {
            continue;
        }
        let form = if announced { "announced" } else { "silent" };
        let what = format!("a power loss ({form}) during Home");
        if near(&s.twin.joints(), home_pose, s.differences.arrive_rad) {
            let away = Targets::for_subject(s).q1;
            if !motion(s, f, "a motion away from home", away) {
                f.broke(format!("{what}: the motion before it failed"));
                return true;
            }
        }
        if !start_home(s, f, &what) {
            continue;
        }
        std::thread::sleep(Duration::from_millis(100));
        s.twin.cut_power(announced);
        wait_standing(s.twin.as_ref());
        let hf = code(s.robot.finish());
        let name = trol::Code(hf).name(s.robot.codes()).unwrap_or("?");
        let at = s.twin.joints();
        f.step(format!(
            "{what}: Finish -> {hf} ({name}), the arm at {}",
            fmt(&at)
        ));
        let unsure = hf == TROL_ERR_ROBOT_UNSURE.0;
        if hf == 0 {
            f.broke(format!(
                "{what}: reported done with the power off, the arm at {}",
                fmt(&at)
            ));
        } else if name != "BIOS_ARM_POWER" && !unsure {
            f.broke(format!(
                "{what}: the Finish said {hf} ({name}), not the power (BIOS_ARM_POWER)"
            ));
        }
        // With the power off: a motion is refused, nothing moves.
        let before = s.twin.joints();
        let c = code(s.robot.ma(&Targets::for_subject(s).q2));
        std::thread::sleep(Duration::from_millis(200));
        f.step(format!("{what}: MA with the power off -> {c}"));
        if c == 0 {
            let cf = code(s.robot.finish());
            f.broke(format!(
                "{what}: a motion with the power off was accepted (Finish {cf})"
            ));
        }
        if let Err(e) = unmoved(s.twin.as_ref(), &before) {
            f.broke(format!("{what}: the arm moved with its power off: {e}"));
        }
        s.twin.power_on();
        if (unsure || c == TROL_ERR_ROBOT_UNSURE.0) && s.differences.unsure_until_reconnect {
            f.step(format!(
                "{what}: UNSURE, and this controller sends nothing further until reconnect"
            ));
            return false;
        }
        if !home_again(s, f, home_pose, &format!("{what} and the power back")) {
            return true;
        }
    }
    true
}

/// Run every check on `s`.
pub fn run(s: &mut Subject) -> Findings {
    let mut f = Findings::default();
    let label = s.label.clone();
    // Before TROLHome only a refusal is checked; the positions come from where it leaves
    // the arm.
    let t0 = Targets::for_subject(s);

    // Before TROLHome: a real controller's arm refuses every motion, and nothing moves.
    if s.differences.starts_unhomed {
        let before = s.twin.joints();
        let c = code(s.robot.ma(&t0.q1));
        std::thread::sleep(Duration::from_millis(200));
        f.step(format!("MA before TROLHome -> {c}"));
        if c == 0 {
            f.broke("a motion before TROLHome was accepted".into());
        }
        if let Err(e) = unmoved(s.twin.as_ref(), &before) {
            f.broke(format!("the arm moved before TROLHome: {e}"));
        }
    }
    let h = code(s.robot.home(0));
    let hf = if h == 0 { code(s.robot.finish()) } else { h };
    f.step(format!("TROLHome(0) -> {h}, Finish -> {hf}"));
    if hf != 0 {
        f.broke(format!(
            "TROLHome(0) failed ({hf}): nothing further can be checked"
        ));
        return f;
    }
    if let Err(e) = stands(s.twin.as_ref()) {
        f.broke(format!(
            "TROLHome and Finish succeeded with the arm still moving: {e}"
        ));
    }
    let home_pose = s.twin.joints();
    let t = Targets::for_subject(s);
    let (q1, q2) = (t.q1, t.q2);

    // A motion arrives, and GetPosition says where.
    if !motion(s, &mut f, "a joint motion", q1) {
        f.broke("a joint motion within range failed".into());
    }
    match s.robot.position(Tag::Joint, PosMode::Actual) {
        Ok(loc) => {
            let got = loc.to_array6();
            if !near(&got, &s.twin.joints(), s.differences.arrive_rad) {
                f.broke(format!(
                    "TROLGetPosition says {} where the arm is at {}",
                    fmt(&got),
                    fmt(&s.twin.joints())
                ));
            }
        }
        Err(e) => f.broke(format!("TROLGetPosition failed: {e}")),
    }

    // Back to back, without a Finish between (a 1998 program): one after the other; where
    // one motion runs at a time, the second is refused and the first ends where it should.
    let a = code(s.robot.ma(&q2));
    let b = code(s.robot.ma(&q1));
    let c = code(s.robot.finish());
    let at = s.twin.joints();
    f.step(format!(
        "MA Q2 -> {a}, MA Q1 -> {b} (no Finish between), Finish -> {c}, arm at {}",
        fmt(&at)
    ));
    if s.differences.one_motion_at_a_time {
        if a != 0 || c != 0 {
            f.broke(format!("a motion and its Finish failed: {a}, Finish {c}"));
        } else if b == 0 {
            f.broke("a second motion while one ran was accepted".into());
        } else if !near(&at, &q2, s.differences.arrive_rad) {
            f.broke(format!(
                "the second motion was refused, but the arm is at {} for the first's {}",
                fmt(&at),
                fmt(&q2)
            ));
        }
        // Then the second, after the Finish, as such a controller needs it.
        if !motion(s, &mut f, "the second motion after Finish", q1) {
            f.broke("the second motion after Finish failed".into());
        }
    } else if a != 0 || b != 0 || c != 0 {
        f.broke(format!(
            "two motions back to back failed: {a}, {b}, Finish {c}"
        ));
    } else if !near(&at, &q1, s.differences.arrive_rad) {
        f.broke(format!(
            "two motions back to back succeeded, but the arm is at {}",
            fmt(&at)
        ));
    }

    // Out of range: refused, nothing moves.
    let before = s.twin.joints();
    let c = code(s.robot.ma(&t.out_of_range));
    let cf = code(s.robot.finish());
    f.step(format!("MA out of range -> {c}, Finish -> {cf}"));
    if c == 0 && cf == 0 {
        f.broke("a motion out of the arm's range succeeded".into());
    }
    if !near(&before, &s.twin.joints(), s.differences.arrive_rad) {
        f.broke(format!(
            "a refused motion moved the arm from {} to {}",
            fmt(&before),
            fmt(&s.twin.joints())
        ));
    }

    trajectory(s, &mut f, &t);

    // Halt while a motion runs: success only with the arm standing.
    let far = t.far;
    let c = code(s.robot.ma(&far));
    if c != 0 {
        f.broke(format!("a far motion within range was refused ({c})"));
    } else if !wait_moving(s.twin.as_ref(), STEP) {
        f.step("the far motion was over before it was seen: Halt not checked".into());
        let _ = s.robot.finish();
    } else {
        let h = code(s.robot.halt());
        let standing = stands(s.twin.as_ref());
        f.step(format!(
            "Halt during the far motion -> {h}; the arm stands: {standing:?}"
        ));
        if let (0, Err(e)) = (h, &standing) {
            f.broke(format!(
                "Halt reported success while the arm still moved: {e}"
            ));
        }
        if s.differences.unstoppable {
            // Success only where the motion ran to its end within the Halt's time (the arm
            // was seen standing, at its target): no stop is claimed then.
            let ran_out = h == 0
                && standing.is_ok()
                && near(&s.twin.joints(), &far, s.differences.arrive_rad);
            if h != TROL_ERR_NOT_STOPPED.0 && !ran_out {
                f.broke(format!("nothing stops this arm, but Halt answered {h}"));
            }
        } else if h != 0 {
            f.broke(format!("Halt did not stop a stoppable arm ({h})"));
        }
        // Let anything that runs end, within a bound; the Finish's code may name the halt.
        let until = Instant::now() + STEP;
        while s.twin.moving() && Instant::now() < until {
            std::thread::sleep(Duration::from_millis(20));
        }
        let cf = code(s.robot.finish());
        f.step(format!("Finish after the Halt -> {cf}"));
        if cf == 0 && h == 0 && !near(&s.twin.joints(), &far, s.differences.arrive_rad) {
            // A halted motion ends short; a Finish may say so, or say nothing of a motion
            // it no longer follows. It must not say the arm reached FAR.
            let got = s.robot.position(Tag::Joint, PosMode::Actual);
            if let Ok(loc) = got {
                if near(&loc.to_array6(), &far, s.differences.arrive_rad) {
                    f.broke("after a Halt, GetPosition says the arm reached its target".into());
                }
            }
        }
    }
    // After a Halt (or a failed one), the next call works where the arm can move.
    if !s.differences.unstoppable {
        let h = code(s.robot.home(0));
        let hf = if h == 0 { code(s.robot.finish()) } else { h };
        if hf != 0 {
            f.step(format!("TROLHome after the Halt -> {hf}"));
        }
        // From where TROLHome leaves the arm, as the first motion went.
        let q2 = Targets::for_subject(s).q2;
        if !motion(s, &mut f, "the motion after the Halt", q2) {
            f.broke("the motion after a Halt did not work".into());
        }
        halted_home(s, &mut f, &home_pose);
        if !power_lost_home(s, &mut f, &home_pose) {
            f.steps.insert(0, format!("{label}:"));
            return f;
        }
    }
    // A line nobody asked for (last: a controller may send nothing further after it): the
    // next call is UNSURE and moves nothing; the one after works, or is UNSURE too where the
    // controller waits for a new connection.
    if s.twin.say_unasked("OVERCURRENT B") {
        std::thread::sleep(Duration::from_millis(100));
        let before = s.twin.joints();
        let c = code(s.robot.ma(&q2));
        std::thread::sleep(Duration::from_millis(200));
        f.step(format!("MA after an unasked line -> {c}"));
        if c == 0 {
            let cf = code(s.robot.finish());
            f.broke(format!(
                "a motion after an unasked line was reported sent (Finish {cf})"
            ));
        } else if c != TROL_ERR_ROBOT_UNSURE.0 {
            f.step(format!(
                "(not UNSURE but {c}: a refusal; allowed, as nothing moved)"
            ));
        }
        if c != 0 {
            if let Err(e) = unmoved(s.twin.as_ref(), &before) {
                f.broke(format!("the arm moved after an unasked line: {e}"));
            }
        }
        if s.differences.unsure_until_reconnect {
            // Nothing further until a new connection: the next call is UNSURE too, and
            // nothing moves.
            let before = s.twin.joints();
            let c2 = code(s.robot.ma(&q1));
            std::thread::sleep(Duration::from_millis(200));
            f.step(format!("the call after UNSURE -> {c2} (until reconnect)"));
            if c2 != TROL_ERR_ROBOT_UNSURE.0 {
                f.broke(format!(
                    "after UNSURE, a controller that sends nothing further until reconnect \
                     answered {c2}"
                ));
            }
            if let Err(e) = unmoved(s.twin.as_ref(), &before) {
                f.broke(format!("the arm moved after UNSURE: {e}"));
            }
        } else if !motion(s, &mut f, "the call after UNSURE", q1) {
            f.broke("the call after an unasked line did not work".into());
        }
    }

    f.steps.insert(0, format!("{label}:"));
    f
}

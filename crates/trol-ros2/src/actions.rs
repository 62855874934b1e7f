//! The node's two actions, on ros2-client's synchronous action server, turned once per tick of
//! the node's loop:
//!
//! - `follow_joint_trajectory` (control_msgs/FollowJointTrajectory): a goal becomes one
//!   TROLTrajectory ([`crate::follow`] checks it and gives the desired path), with feedback
//!   each tick, the path tolerance while it runs timed, and the result from what the arm did;
//! - `gripper_cmd` (control_msgs/GripperCommand): TROLGrip to the asked gap, and the result
//!   from TROLGetGripper: `reached_goal` when the fingers stand at the gap, `stalled` when they
//!   stopped on an object.
//!
//! What every action shares is in [`Book`]: one goal at a time (a goal while one runs is
//! rejected), a goal refused after acceptance so that its error code reaches the client, the
//! ended goals' results for a late `get_result`, result requests that wait for their goal,
//! the status array, and cancel: a cancel halts the arm, and is a success only with the arm
//! seen standing.

use std::collections::VecDeque;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use ros2_client::action::{ActionServer, ActionServerQosPolicies, GetResultResponse};
use ros2_client::action_msgs::{
    CancelGoalRequest, CancelGoalResponse, CancelGoalResponseEnum, GoalId, GoalInfo, GoalStatus,
    GoalStatusArray, GoalStatusEnum,
};
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{Message, QosProfile, RmwRequestId};
use trol::{PosMode, Robot, Tag};

use crate::msgs::{
    self, FollowFeedback, FollowGoal, FollowResult, GripperFeedback, GripperGoal, GripperResult,
    Header, JointTrajectoryPoint, Time, follow_code,
};
use crate::{JOINTS, follow, words};

/// The QoS of an action's parts, as ROS 2's defaults have them: its services and feedback
/// reliable and volatile, its status transient local (a late client still learns it).
pub fn action_qos() -> ActionServerQosPolicies {
    let service = QosProfile::publisher_default()
        .reliability_reliable(WhenFull::DEFAULT)
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 10 });
    ActionServerQosPolicies {
        goal_service: service.clone(),
        result_service: service.clone(),
        cancel_service: service.clone(),
        feedback_publisher: service,
        status_publisher: QosProfile::publisher_default()
            .reliability_reliable(WhenFull::DEFAULT)
            .durability(Durability::TransientLocal)
            .history(History::KeepLast { depth: 1 }),
    }
}

/// How many ended goals' results are kept for a late get_result.
const KEPT_RESULTS: usize = 32;
/// How often the goals' status is published when nothing changes.
const STATUS_EVERY: Duration = Duration::from_secs(1);

/// A cancel request's goal id (ros2-client keeps the request's field to itself; its
/// serialised form has it). `None`: the request could not be read, taken as "all".
fn cancel_goal_id(req: &CancelGoalRequest) -> Option<GoalId> {
    let v = serde_json::to_value(req).ok()?;
    serde_json::from_value(v.get("goal_info")?.get("goal_id")?.clone()).ok()
}

/// One action's goals, apart from what its goals do.
pub struct Book<R> {
    /// The goal under way.
    running: Option<GoalInfo>,
    ended: VecDeque<(GoalInfo, GoalStatusEnum, R)>,
    waiting: Vec<(RmwRequestId, GoalId)>,
    last_status: Option<Instant>,
}

impl<R: Message + Clone + Default + 'static> Book<R> {
    fn new() -> Book<R> {
        Book {
            running: None,
            ended: VecDeque::new(),
            waiting: Vec::new(),
            last_status: None,
        }
    }

    /// A new goal: rejected while one runs; otherwise accepted (its info returned), so that
    /// a refusal found afterwards reaches the client with its code.
    fn take_goal<G: Message + Clone + 'static, F: Message + 'static>(
        &mut self,
        server: &ActionServer<G, R, F>,
        req_id: RmwRequestId,
        goal_id: GoalId,
    ) -> Option<GoalInfo> {
        let info = GoalInfo {
            goal_id,
            stamp: ros2_client::builtin_interfaces::Time::now(),
        };
        let accepted = self.running.is_none();
        if !accepted {
            trol_cli::tell!(
                "trol-ros2: a goal of {} was rejected: one is under way",
                server.name()
            );
        }
        let resp = ros2_client::action::SendGoalResponse {
            accepted,
            stamp: info.stamp,
        };
        if let Err(e) = server.send_goal_response(req_id, resp) {
            tracing::warn!("send_goal's response: {e:?}");
        }
        accepted.then_some(info)
    }

    fn start(&mut self, info: GoalInfo) {
        self.running = Some(info);
        self.last_status = None;
    }

    /// The goal under way ends (or `info`, one that never ran).
    fn end(&mut self, info: GoalInfo, status: GoalStatusEnum, result: R) {
        if self
            .running
            .as_ref()
            .is_some_and(|r| r.goal_id == info.goal_id)
        {
            self.running = None;
        }
        self.ended.push_back((info, status, result));
        while self.ended.len() > KEPT_RESULTS {
            self.ended.pop_front();
        }
        self.last_status = None;
    }

    /// Cancel requests: `halt` stops the arm (success only with it seen standing); the
    /// running goal then ends canceled with `canceled`, or aborted with `failed(why)`.
    fn cancels<G: Message + Clone + 'static, F: Message + 'static>(
        &mut self,
        server: &ActionServer<G, R, F>,
        halt: &mut dyn FnMut() -> Result<(), String>,
        canceled: &dyn Fn() -> R,
        failed: &dyn Fn(String) -> R,
    ) {
        while let Ok(Some((req_id, req))) = server.receive_cancel_request() {
            let id = cancel_goal_id(&req);
            let answer = match self.running.clone() {
                Some(info) if id.is_none_or(|id| id == info.goal_id || id.uuid.is_nil()) => {
                    match halt() {
                        Ok(()) => {
                            self.end(info.clone(), GoalStatusEnum::Canceled, canceled());
                            CancelGoalResponse {
                                return_code: CancelGoalResponseEnum::None,
                                goals_canceling: vec![info],
                            }
                        }
                        Err(why) => {
                            self.end(
                                info,
                                GoalStatusEnum::Aborted,
                                failed(format!("cancel: the halt failed: {why}")),
                            );
                            CancelGoalResponse {
                                return_code: CancelGoalResponseEnum::Rejected,
                                goals_canceling: Vec::new(),
                            }
                        }
                    }
                }
                _ => {
                    let known =
                        id.is_some_and(|id| self.ended.iter().any(|(i, ..)| i.goal_id == id));
                    CancelGoalResponse {
                        return_code: if known {
                            CancelGoalResponseEnum::GoalTerminated
                        } else {
                            CancelGoalResponseEnum::UnknownGoal
                        },
                        goals_canceling: Vec::new(),
                    }
                }
            };
            if let Err(e) = server.send_cancel_response(req_id, answer) {
                tracing::warn!("cancel's response: {e:?}");
            }
        }
    }

    /// Result requests (answered once their goal has ended), and the status array.
    fn results_and_status<G: Message + Clone + 'static, F: Message + 'static>(
        &mut self,
        server: &ActionServer<G, R, F>,
    ) {
        while let Ok(Some((req_id, req))) = server.receive_result_request() {
            self.waiting.push((req_id, req.goal_id));
        }
        let mut still = Vec::new();
        for (req_id, id) in std::mem::take(&mut self.waiting) {
            let resp = if let Some((_, status, result)) =
                self.ended.iter().find(|(i, ..)| i.goal_id == id)
            {
                GetResultResponse {
                    status: *status,
                    result: result.clone(),
                }
            } else if self.running.as_ref().is_some_and(|r| r.goal_id == id) {
                still.push((req_id, id));
                continue;
            } else {
                GetResultResponse {
                    status: GoalStatusEnum::Unknown,
                    result: R::default(),
                }
            };
            if let Err(e) = server.send_result(req_id, resp) {
                tracing::warn!("get_result's response: {e:?}");
            }
        }
        self.waiting = still;
        if self.last_status.is_none_or(|t| t.elapsed() >= STATUS_EVERY) {
            let mut list: Vec<GoalStatus> = self
                .ended
                .iter()
                .map(|(info, status, _)| GoalStatus {
                    goal_info: info.clone(),
                    status: *status,
                })
                .collect();
            if let Some(info) = &self.running {
                list.push(GoalStatus {
                    goal_info: info.clone(),
                    status: GoalStatusEnum::Executing,
                });
            }
            if let Err(e) = server.send_goal_statuses(GoalStatusArray { status_list: list }) {
                tracing::warn!("status: {e:?}");
            }
            self.last_status = Some(Instant::now());
        }
    }
}

/// Halt the arm for a cancel: `Ok` only with it seen standing; counted, so that a Home under
/// way is not reported homed.
fn halt_for_cancel(robot: &Mutex<Robot>, halts: &AtomicU64) -> Result<(), String> {
    halts.fetch_add(1, Ordering::SeqCst);
    match robot.lock() {
        Ok(mut r) => r.halt().map_err(|e| words(&e)),
        Err(_) => Err("the arm's connection was poisoned".into()),
    }
}

/// The FollowJointTrajectory server.
pub type FollowServer = ActionServer<FollowGoal, FollowResult, FollowFeedback>;

struct FollowRun {
    info: GoalInfo,
    plan: follow::Plan,
    started: Instant,
    timed: bool,
    /// The count of halts (the `halt` service, a gripper's cancel) when it started: one
    /// since stopped it short.
    halts: u64,
}

/// FollowJointTrajectory's goals.
pub struct Follow {
    book: Book<FollowResult>,
    run: Option<FollowRun>,
    /// How much faster than real time the arm's clock runs (the embedded simulator's time
    /// scale; 1 for a real arm).
    clock: f64,
}

fn follow_result(code: i32, why: impl Into<String>) -> FollowResult {
    FollowResult {
        error_code: code,
        error_string: why.into(),
    }
}

impl Follow {
    /// No goal yet; the arm's clock runs `clock` times real time.
    pub fn new(clock: f64) -> Follow {
        Follow {
            book: Book::new(),
            run: None,
            clock,
        }
    }

    fn end(&mut self, status: GoalStatusEnum, code: i32, why: String) {
        if let Some(run) = self.run.take() {
            self.book.end(run.info, status, follow_result(code, why));
        }
    }

    /// One turn: new goals, cancels, results, the status; and at a `tick` (the arm just
    /// read, `actual`), the one under way.
    pub fn serve(
        &mut self,
        server: &FollowServer,
        robot: &Mutex<Robot>,
        actual: Option<[f64; 6]>,
        halts: &AtomicU64,
        tick: bool,
    ) {
        while let Ok(Some((req_id, req))) = server.receive_goal() {
            if let Some(info) = self.book.take_goal(server, req_id, req.goal_id) {
                self.start(robot, info, &req.goal, halts.load(Ordering::SeqCst));
            }
        }
        let run_before = self.run.is_some();
        self.book.cancels(
            server,
            &mut || halt_for_cancel(robot, halts),
            &|| {
                follow_result(
                    follow_code::SUCCESSFUL,
                    "canceled: the arm was halted and stands",
                )
            },
            &|why| follow_result(follow_code::PATH_TOLERANCE_VIOLATED, why),
        );
        if run_before && self.book.running.is_none() {
            self.run = None;
        }
        if tick {
            self.progress(server, robot, actual, halts);
        }
        self.book.results_and_status(server);
    }

    fn start(&mut self, robot: &Mutex<Robot>, info: GoalInfo, goal: &FollowGoal, halts: u64) {
        let refuse = |book: &mut Book<FollowResult>, info: GoalInfo, code: i32, why: String| {
            book.end(info, GoalStatusEnum::Aborted, follow_result(code, why));
        };
        let Ok(mut r) = robot.lock() else {
            refuse(
                &mut self.book,
                info,
                follow_code::INVALID_GOAL,
                "the arm's connection was poisoned".into(),
            );
            return;
        };
        let start = match r.position(Tag::Joint, PosMode::Commanded) {
            Ok(l) => l.to_array6(),
            Err(e) => {
                drop(r);
                refuse(&mut self.book, info, follow_code::INVALID_GOAL, words(&e));
                return;
            }
        };
        let plan = match follow::plan(goal, start) {
            Ok(p) => p,
            Err(no) => {
                drop(r);
                refuse(&mut self.book, info, no.code, no.why);
                return;
            }
        };
        let sent = r.trajectory(&plan.waypoints);
        drop(r);
        match sent {
            Ok(timing) => {
                self.book.start(info.clone());
                self.run = Some(FollowRun {
                    info,
                    plan,
                    started: Instant::now(),
                    timed: timing == trol::Timing::Timed,
                    halts,
                });
            }
            Err(e) => refuse(
                &mut self.book,
                info,
                follow_code::INVALID_GOAL,
                format!("the controller refused the trajectory: {}", words(&e)),
            ),
        }
    }

    /// The one under way: feedback, the path tolerance, and its end.
    fn progress(
        &mut self,
        server: &FollowServer,
        robot: &Mutex<Robot>,
        actual: Option<[f64; 6]>,
        halts: &AtomicU64,
    ) {
        let Some(run) = &self.run else {
            return;
        };
        if halts.load(Ordering::SeqCst) != run.halts {
            // Halted from outside the goal (the `halt` service): it ends here, whatever the
            // arm does next, and not as a success even if the arm stood at the end.
            self.end(
                GoalStatusEnum::Aborted,
                follow_code::GOAL_TOLERANCE_VIOLATED,
                "halted: a halt (the halt service, or a gripper goal's cancel) stopped the \
                 arm during the trajectory; send the goal again from where the arm stands"
                    .into(),
            );
            return;
        }
        let elapsed = run.started.elapsed().as_secs_f64() * self.clock;
        if let Some(q) = actual {
            let desired = run.plan.desired(elapsed);
            let point = |v: &[f64; 6]| JointTrajectoryPoint {
                positions: run.plan.in_goal_order(v),
                time_from_start: msgs::Duration::from_seconds(elapsed),
                ..Default::default()
            };
            let error: [f64; 6] = std::array::from_fn(|i| q[i] - desired[i]);
            let feedback = FollowFeedback {
                header: Header {
                    stamp: Time::now(),
                    frame_id: String::new(),
                },
                joint_names: run.plan.names.clone(),
                desired: point(&desired),
                actual: point(&q),
                error: point(&error),
                ..Default::default()
            };
            if let Err(e) = server.send_feedback(run.info.goal_id, feedback) {
                tracing::warn!("feedback: {e:?}");
            }
            if let Some((j, e)) = run.plan.off_path(elapsed, &q).filter(|_| run.timed) {
                let how = match robot.lock().map(|mut r| r.halt()) {
                    Ok(Ok(())) => "halted, the arm stands".to_string(),
                    Ok(Err(e)) => format!("the halt failed: {}", words(&e)),
                    Err(_) => "the arm's connection was poisoned".into(),
                };
                self.end(
                    GoalStatusEnum::Aborted,
                    follow_code::PATH_TOLERANCE_VIOLATED,
                    format!(
                        "{} was {e:.4} rad off the path at {elapsed:.3} s: {how}",
                        JOINTS[j]
                    ),
                );
                return;
            }
        }
        match robot.lock().map(|mut r| r.is_moving()) {
            Ok(Ok(true)) => {}
            Ok(Ok(false)) => {
                // Where the arm stands now, read after its end was seen: the tick's reading
                // may be older than the last motion (a C500 runs the next waypoint's MA
                // between two looks).
                let fresh = robot
                    .lock()
                    .map(|mut r| r.position(Tag::Joint, PosMode::Actual));
                let q = match fresh {
                    Ok(Ok(l)) => l.to_array6(),
                    Ok(Err(e)) => {
                        self.end(
                            GoalStatusEnum::Aborted,
                            follow_code::GOAL_TOLERANCE_VIOLATED,
                            format!("the arm could not be read at the end: {}", words(&e)),
                        );
                        return;
                    }
                    Err(_) => {
                        self.end(
                            GoalStatusEnum::Aborted,
                            follow_code::GOAL_TOLERANCE_VIOLATED,
                            "the arm's connection was poisoned".into(),
                        );
                        return;
                    }
                };
                let (code, why) = run.plan.result(&q, elapsed, run.timed);
                let status = if code == follow_code::SUCCESSFUL {
                    GoalStatusEnum::Succeeded
                } else {
                    GoalStatusEnum::Aborted
                };
                self.end(status, code, why);
            }
            Ok(Err(e)) => self.end(
                GoalStatusEnum::Aborted,
                follow_code::GOAL_TOLERANCE_VIOLATED,
                format!("the motion failed: {}", words(&e)),
            ),
            Err(_) => self.end(
                GoalStatusEnum::Aborted,
                follow_code::GOAL_TOLERANCE_VIOLATED,
                "the arm's connection was poisoned".into(),
            ),
        }
    }
}

/// The GripperCommand server.
pub type GripperServer = ActionServer<GripperGoal, GripperResult, GripperFeedback>;

/// How close (mm) the fingers must stand to the asked gap for `reached_goal` (assumption: the
/// gripper's own resolution is not public; 1 mm).
pub const GRIP_REACHED_MM: f64 = 1.0;
/// The widest gap TROLGrip takes, mm (the table's range of `dist`).
pub const GRIP_MAX_MM: f64 = 50.0;

/// GripperCommand's goals.
pub struct Gripper {
    book: Book<GripperResult>,
    run: Option<(GoalInfo, f64)>,
}

impl Gripper {
    /// No goal yet.
    pub fn new() -> Gripper {
        Gripper {
            book: Book::new(),
            run: None,
        }
    }

    /// One turn: new goals, cancels, results, the status; and at a `tick`, the one under
    /// way.
    pub fn serve(
        &mut self,
        server: &GripperServer,
        robot: &Mutex<Robot>,
        halts: &AtomicU64,
        tick: bool,
    ) {
        while let Ok(Some((req_id, req))) = server.receive_goal() {
            if let Some(info) = self.book.take_goal(server, req_id, req.goal_id) {
                self.start(robot, info, &req.goal);
            }
        }
        let run_before = self.run.is_some();
        self.book.cancels(
            server,
            &mut || halt_for_cancel(robot, halts),
            &GripperResult::default,
            &|_| GripperResult::default(),
        );
        if run_before && self.book.running.is_none() {
            self.run = None;
        }
        if tick {
            self.progress(server, robot);
        }
        self.book.results_and_status(server);
    }

    fn start(&mut self, robot: &Mutex<Robot>, info: GoalInfo, goal: &GripperGoal) {
        let mm = goal.command.position * 1000.0;
        if !(mm.is_finite() && (0.0..=GRIP_MAX_MM + 0.5).contains(&mm)) {
            trol_cli::tell!(
                "trol-ros2: gripper_cmd refused: a gap of {} m is outside 0 .. {} m",
                goal.command.position,
                GRIP_MAX_MM / 1000.0
            );
            self.book
                .end(info, GoalStatusEnum::Aborted, GripperResult::default());
            return;
        }
        let target = mm.round().min(GRIP_MAX_MM);
        let sent = robot.lock().map(|mut r| r.grip(target as u16));
        match sent {
            Ok(Ok(())) => {
                self.book.start(info.clone());
                self.run = Some((info, target));
            }
            Ok(Err(e)) => {
                trol_cli::tell!("trol-ros2: gripper_cmd: {}", words(&e));
                self.book
                    .end(info, GoalStatusEnum::Aborted, GripperResult::default());
            }
            Err(_) => self
                .book
                .end(info, GoalStatusEnum::Aborted, GripperResult::default()),
        }
    }

    /// The one under way: feedback of the fingers, and once they stand, the result.
    fn progress(&mut self, server: &GripperServer, robot: &Mutex<Robot>) {
        let Some((info, target)) = self.run.clone() else {
            return;
        };
        let read = robot.lock().map(|mut r| {
            let moving = r.is_moving();
            (moving, r.gripper())
        });
        let (moving, gripper) = match read {
            Ok(pair) => pair,
            Err(_) => {
                self.run = None;
                self.book
                    .end(info, GoalStatusEnum::Aborted, GripperResult::default());
                return;
            }
        };
        let g = match gripper {
            Ok(g) => g,
            Err(e) => {
                trol_cli::tell!("trol-ros2: gripper_cmd: {}", words(&e));
                self.run = None;
                self.book
                    .end(info, GoalStatusEnum::Aborted, GripperResult::default());
                return;
            }
        };
        let reached = (g.opening_mm - target).abs() <= GRIP_REACHED_MM;
        let stalled = !reached && matches!(g.held, trol::Held::Object(_));
        let state = GripperResult {
            position: g.opening_mm / 1000.0,
            effort: 0.0,
            stalled,
            reached_goal: reached,
        };
        if let Err(e) = server.send_feedback(info.goal_id, state) {
            tracing::warn!("gripper feedback: {e:?}");
        }
        match moving {
            Ok(true) => {}
            Ok(false) => {
                // Done: at the gap, or closed on an object (the grasp a close is for; as
                // ros2_controllers' gripper controller with stalling allowed). Anything
                // else did not do what was asked.
                let status = if reached || stalled {
                    GoalStatusEnum::Succeeded
                } else {
                    GoalStatusEnum::Aborted
                };
                self.run = None;
                self.book.end(info, status, state);
            }
            Err(e) => {
                trol_cli::tell!("trol-ros2: gripper_cmd: {}", words(&e));
                self.run = None;
                self.book.end(info, GoalStatusEnum::Aborted, state);
            }
        }
    }
}

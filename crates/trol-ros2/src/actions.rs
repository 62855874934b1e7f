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
//! Each action's goals are a [`Goals`] (start, progress, the result of a cancel); what every
//! action shares is [`Served`] and its [`Book`]: one goal at a time (a goal while one runs is
//! rejected), a goal refused after acceptance so that its error code reaches the client, the
//! ended goals' results for a late `get_result`, result requests that wait for their goal,
//! the status array, and cancel: a cancel halts the arm, and is a success only with the arm
//! seen standing. The answers of the action's three services wait until their client can
//! hear them ([`crate::replies`]).

use std::collections::VecDeque;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use ros2_client::action::{GetResultResponse, SendGoalResponse};
use ros2_client::action_msgs::{
    CancelGoalRequest, CancelGoalResponse, CancelGoalResponseEnum, GoalId, GoalInfo, GoalStatus,
    GoalStatusArray, GoalStatusEnum,
};
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{Message, QosProfile};
use trol::{PosMode, Robot, Tag};

use crate::action_server::{ActionQos, AnyActionServer};
use crate::mapping::Asker;
use crate::msgs::{
    self, FollowFeedback, FollowGoal, FollowResult, GripperFeedback, GripperGoal, GripperResult,
    Header, JointTrajectoryPoint, Time, follow_code,
};
use crate::replies::{Matches, Replies, Service};
use crate::{follow, words};

/// The QoS of an action's parts, as ROS 2's defaults have them: its services and feedback
/// reliable and volatile, its status transient local (a late client still learns it).
pub fn action_qos() -> ActionQos {
    let service = QosProfile::publisher_default()
        .reliability_reliable(WhenFull::DEFAULT)
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 10 });
    ActionQos {
        services: service.clone(),
        feedback: service,
        status: QosProfile::publisher_default()
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
    waiting: Vec<(Asker, GoalId)>,
    last_status: Option<Instant>,
    goal_replies: Replies<SendGoalResponse>,
    cancel_replies: Replies<CancelGoalResponse>,
    result_replies: Replies<GetResultResponse<R>>,
}

/// The DDS topics of an action's three services.
pub struct ActionServices {
    pub send_goal: Service,
    pub cancel_goal: Service,
    pub get_result: Service,
}

impl ActionServices {
    /// The action `<ns>/<action>`'s services, as ros2-client names them.
    pub fn new(
        ns: &str,
        action: &str,
        node: &ros2_client::NodeName,
    ) -> Result<ActionServices, String> {
        let part = |p: &str| Service::new(ns, &format!("{action}/_action/{p}"), node);
        Ok(ActionServices {
            send_goal: part("send_goal")?,
            cancel_goal: part("cancel_goal")?,
            get_result: part("get_result")?,
        })
    }
}

impl<R: Message + Clone + Default + 'static> Book<R> {
    fn new(services: ActionServices) -> Book<R> {
        Book {
            running: None,
            ended: VecDeque::new(),
            waiting: Vec::new(),
            last_status: None,
            goal_replies: Replies::new(services.send_goal),
            cancel_replies: Replies::new(services.cancel_goal),
            result_replies: Replies::new(services.get_result),
        }
    }

    /// Send the answers whose clients can hear them now (or that waited long enough).
    fn flush<G: Message + Clone + 'static, F: Message + 'static>(
        &mut self,
        server: &AnyActionServer<G, R, F>,
        matches: &Matches,
    ) {
        let now = Instant::now();
        self.goal_replies.flush(
            now,
            |s| matches.hear(s),
            |id, resp| {
                if let Err(e) = server.send_goal_response(id, resp) {
                    tracing::warn!("send_goal's response: {e}");
                }
            },
        );
        self.cancel_replies.flush(
            now,
            |s| matches.hear(s),
            |id, resp| {
                if let Err(e) = server.send_cancel_response(id, resp) {
                    tracing::warn!("cancel's response: {e}");
                }
            },
        );
        self.result_replies.flush(
            now,
            |s| matches.hear(s),
            |id, resp| {
                if let Err(e) = server.send_result(id, resp) {
                    tracing::warn!("get_result's response: {e}");
                }
            },
        );
    }

    /// A new goal: rejected while one runs; otherwise accepted (its info returned), so that
    /// a refusal found afterwards reaches the client with its code.
    fn take_goal<G: Message + Clone + 'static, F: Message + 'static>(
        &mut self,
        server: &AnyActionServer<G, R, F>,
        req_id: Asker,
        goal_id: GoalId,
        replacing: bool,
    ) -> Option<GoalInfo> {
        let info = GoalInfo {
            goal_id,
            stamp: ros2_client::builtin_interfaces::Time::now(),
        };
        let accepted = self.running.is_none() || replacing;
        if !accepted {
            crate::warn_ros!(
                "trol-ros2: a goal of {} was rejected: one is under way",
                server.name()
            );
        }
        let resp = SendGoalResponse {
            accepted,
            stamp: info.stamp,
        };
        self.goal_replies.push(req_id, resp, Instant::now());
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
        server: &AnyActionServer<G, R, F>,
        halt: &mut dyn FnMut() -> Result<(), String>,
        canceled: &dyn Fn() -> R,
        failed: &dyn Fn(String) -> R,
    ) {
        while let Some((req_id, req)) = crate::mapping::next(|| server.receive_cancel_request()) {
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
            self.cancel_replies.push(req_id, answer, Instant::now());
        }
    }

    /// Result requests (answered once their goal has ended), and the status array.
    fn results_and_status<G: Message + Clone + 'static, F: Message + 'static>(
        &mut self,
        server: &AnyActionServer<G, R, F>,
    ) {
        while let Some((req_id, req)) = crate::mapping::next(|| server.receive_result_request()) {
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
            self.result_replies.push(req_id, resp, Instant::now());
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
                tracing::warn!("status: {e}");
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

/// What the arm is, for an action's goals at one turn.
pub struct Arm<'a> {
    pub robot: &'a Mutex<Robot>,
    /// The joints as read at this tick (`None`: not read).
    pub actual: Option<[f64; 6]>,
    /// Halts served so far (the `halt` service, cancels).
    pub halts: &'a AtomicU64,
}

/// What one action's goals do; [`Served`] turns them with what every action shares
/// ([`Book`]: one goal at a time, cancel, results, status).
pub trait Goals {
    type Goal: Message + Clone + 'static;
    type Result: Message + Clone + Default + 'static;
    type Feedback: Message + std::fmt::Debug + 'static;
    /// A goal under way.
    type Run;
    /// Start a goal: its run, or the result of a goal refused (it ends aborted).
    fn start(&mut self, arm: &Arm<'_>, goal: &Self::Goal) -> Result<Self::Run, Self::Result>;
    /// At a tick, the goal under way: its feedback (`send`), and its end once it has ended.
    fn progress(
        &mut self,
        arm: &Arm<'_>,
        run: &Self::Run,
        send: &mut dyn FnMut(Self::Feedback),
    ) -> Option<(GoalStatusEnum, Self::Result)>;
    /// The result of a goal cancelled with the arm halted (`None`), or whose halt failed.
    fn canceled(&self, failed: Option<String>) -> Self::Result;
    /// Whether a new goal replaces the one under way (as ROS 2's joint_trajectory_controller
    /// does) rather than being rejected.
    fn replaces(&self) -> bool {
        false
    }
    /// What can be known of a goal before anything stops or moves: its refusal, if any (a
    /// new goal refused so leaves the one under way running).
    fn check(&self, _goal: &Self::Goal) -> Result<(), Self::Result> {
        Ok(())
    }
    /// The result of a goal replaced by a newer one, the arm halted for it.
    fn replaced(&self) -> Self::Result {
        self.canceled(None)
    }
}

/// One action's server side: its goals and their bookkeeping.
pub struct Served<A: Goals> {
    goals: A,
    book: Book<A::Result>,
    run: Option<(GoalInfo, A::Run)>,
}

impl<A: Goals> Served<A> {
    /// Whether a goal is under way.
    pub fn is_running(&self) -> bool {
        self.run.is_some()
    }

    /// No goal yet; `services`: the action's services on DDS.
    pub fn new(goals: A, services: ActionServices) -> Served<A> {
        Served {
            goals,
            book: Book::new(services),
            run: None,
        }
    }

    /// One turn: new goals, cancels, results, the status; and at a `tick` (the arm just
    /// read), the goal under way.
    pub fn serve(
        &mut self,
        server: &AnyActionServer<A::Goal, A::Result, A::Feedback>,
        arm: &Arm<'_>,
        tick: bool,
        matches: &Matches,
    ) {
        while let Some((req_id, req)) = crate::mapping::next(|| server.receive_goal()) {
            // A goal while one runs: replaced where this action replaces (the new one checked
            // first: one refused leaves the running goal alone), else rejected.
            let replacing = self.book.running.is_some()
                && self.goals.replaces()
                && self.goals.check(&req.goal).is_ok();
            if let Some(info) = self.book.take_goal(server, req_id, req.goal_id, replacing) {
                if replacing && let Some(old) = self.book.running.clone() {
                    let goals = &self.goals;
                    match halt_for_cancel(arm.robot, arm.halts) {
                        Ok(()) => self
                            .book
                            .end(old, GoalStatusEnum::Canceled, goals.replaced()),
                        Err(why) => {
                            // The arm was not seen standing: the old goal ends aborted, and
                            // the new one is not started on a moving arm.
                            self.book.end(
                                old,
                                GoalStatusEnum::Aborted,
                                goals.canceled(Some(format!(
                                    "replaced by a newer goal, but the halt failed: {why}"
                                ))),
                            );
                            self.run = None;
                            self.book.end(
                                info,
                                GoalStatusEnum::Aborted,
                                goals.canceled(Some(format!(
                                    "not started: the arm was not seen to stand after the \
                                     goal before it was halted: {why}"
                                ))),
                            );
                            continue;
                        }
                    }
                    self.run = None;
                }
                match self.goals.start(arm, &req.goal) {
                    Ok(run) => {
                        self.book.start(info.clone());
                        self.run = Some((info, run));
                    }
                    Err(result) => self.book.end(info, GoalStatusEnum::Aborted, result),
                }
            }
        }
        let goals = &self.goals;
        self.book.cancels(
            server,
            &mut || halt_for_cancel(arm.robot, arm.halts),
            &|| goals.canceled(None),
            &|why| goals.canceled(Some(why)),
        );
        if self.book.running.is_none() {
            self.run = None;
        }
        if tick && let Some((info, run)) = &self.run {
            let id = info.goal_id;
            let mut send = |f: A::Feedback| {
                if let Err(e) = server.send_feedback(id, f) {
                    tracing::warn!("feedback of {}: {e}", server.name());
                }
            };
            if let Some((status, result)) = self.goals.progress(arm, run, &mut send) {
                let (info, _) = self.run.take().expect("the goal under way");
                self.book.end(info, status, result);
            }
        }
        self.book.results_and_status(server);
        self.book.flush(server, matches);
    }
}

/// A trajectory goal under way.
pub struct FollowRun {
    plan: follow::Plan,
    started: Instant,
    timed: bool,
    /// The count of halts (the `halt` service, a gripper's cancel) when it started: one
    /// since stopped it short.
    halts: u64,
    /// Thinned for the controller: the goal's points, those sent, and how far (rad) the
    /// dropped ones lay from the path sent.
    thinned: Option<(usize, usize, f64)>,
}

/// FollowJointTrajectory's goals.
pub struct Follow {
    /// How much faster than real time the arm's clock runs (the embedded simulator's time
    /// scale; 1 for a real arm).
    clock: f64,
    /// The arm's joint names (`--prefix` and the URDF's), in the URDF's order.
    joints: [String; 6],
    /// Feedback in control_msgs 6.3's layout (Kilted, Rolling).
    kilted: bool,
    /// A new goal replaces the running one (false: it is rejected).
    replace: bool,
}

fn follow_result(code: i32, why: impl Into<String>) -> FollowResult {
    FollowResult {
        error_code: code,
        error_string: why.into(),
    }
}

fn aborted(code: i32, why: impl Into<String>) -> Option<(GoalStatusEnum, FollowResult)> {
    Some((GoalStatusEnum::Aborted, follow_result(code, why)))
}

impl Served<Follow> {
    /// FollowJointTrajectory, no goal yet; the arm's clock runs `clock` times real time;
    /// `joints`: the arm's joint names as the node gives them.
    pub fn follow(
        clock: f64,
        joints: [String; 6],
        distro: crate::Distro,
        replace: bool,
        services: ActionServices,
    ) -> Self {
        let kilted = distro.feedback_has_indices();
        Served::new(
            Follow {
                clock,
                joints,
                kilted,
                replace,
            },
            services,
        )
    }
}

impl Goals for Follow {
    type Goal = FollowGoal;
    type Result = FollowResult;
    type Feedback = FollowFeedback;
    type Run = FollowRun;

    fn start(&mut self, arm: &Arm<'_>, goal: &FollowGoal) -> Result<FollowRun, FollowResult> {
        let poisoned = || {
            follow_result(
                follow_code::INVALID_GOAL,
                "the arm's connection was poisoned",
            )
        };
        let halts = arm.halts.load(Ordering::SeqCst);
        let mut r = arm.robot.lock().map_err(|_| poisoned())?;
        let start = r
            .position(Tag::Joint, PosMode::Commanded)
            .map_err(|e| follow_result(follow_code::INVALID_GOAL, words(&e)))?
            .to_array6();
        let plan =
            follow::plan(goal, start, &self.joints).map_err(|no| follow_result(no.code, no.why))?;
        let mut sent = r.trajectory(&plan.waypoints);
        let mut thinned = None;
        // A controller that runs a trajectory as one joint move per point takes at most
        // UNTIMED_WAYPOINTS of them (a C500); MoveIt plans many more. Such a plan is thinned
        // to that many (its corners kept), where its path tolerance allows, and sent again:
        // nothing moved on the refusal.
        let limit = trol_controller::UNTIMED_WAYPOINTS;
        if let Err(e) = &sent
            && e.code() == trol::code::TROL_ERR_ARG_RANGE
            && plan.waypoints.len() > limit
        {
            let (fewer, off) = plan
                .thinned(limit)
                .map_err(|no| follow_result(no.code, no.why))?;
            thinned = Some((plan.waypoints.len(), fewer.len(), off));
            sent = r.trajectory(&fewer);
        }
        match sent {
            Ok(timing) => Ok(FollowRun {
                plan,
                started: Instant::now(),
                timed: timing == trol::Timing::Timed,
                halts,
                thinned,
            }),
            Err(e) => Err(follow_result(
                follow_code::INVALID_GOAL,
                format!("the controller refused the trajectory: {}", words(&e)),
            )),
        }
    }

    fn progress(
        &mut self,
        arm: &Arm<'_>,
        run: &FollowRun,
        send: &mut dyn FnMut(FollowFeedback),
    ) -> Option<(GoalStatusEnum, FollowResult)> {
        if arm.halts.load(Ordering::SeqCst) != run.halts {
            // Halted from outside the goal (the `halt` service): it ends here, whatever the
            // arm does next, and not as a success even if the arm stood at the end.
            return aborted(
                follow_code::GOAL_TOLERANCE_VIOLATED,
                "halted: a halt (the halt service, or a gripper goal's cancel) stopped the \
                 arm during the trajectory; send the goal again from where the arm stands",
            );
        }
        let elapsed = run.started.elapsed().as_secs_f64() * self.clock;
        if let Some(q) = arm.actual {
            let desired = run.plan.desired(elapsed);
            let point = |v: &[f64; 6]| JointTrajectoryPoint {
                positions: run.plan.in_goal_order(v),
                time_from_start: msgs::Duration::from_seconds(elapsed),
                ..Default::default()
            };
            let error: [f64; 6] = std::array::from_fn(|i| q[i] - desired[i]);
            send(FollowFeedback {
                header: Header {
                    stamp: Time::now(),
                    frame_id: String::new(),
                },
                joint_names: run.plan.names.clone(),
                desired: point(&desired),
                actual: point(&q),
                error: point(&error),
                index: run.plan.point_in_use(elapsed),
                kilted: self.kilted,
                ..Default::default()
            });
            if let Some((j, e)) = run.plan.off_path(elapsed, &q).filter(|_| run.timed) {
                let how = match arm.robot.lock().map(|mut r| r.halt()) {
                    Ok(Ok(())) => "halted, the arm stands".to_string(),
                    Ok(Err(e)) => format!("the halt failed: {}", words(&e)),
                    Err(_) => "the arm's connection was poisoned".into(),
                };
                return aborted(
                    follow_code::PATH_TOLERANCE_VIOLATED,
                    format!(
                        "{} was {e:.4} rad off the path at {elapsed:.3} s: {how}",
                        run.plan.joints[j]
                    ),
                );
            }
        }
        let poisoned = "the arm's connection was poisoned";
        match arm.robot.lock().map(|mut r| r.is_moving()) {
            Ok(Ok(true)) => None,
            Ok(Ok(false)) => {
                // Where the arm stands now, read after its end was seen: the tick's reading
                // may be older than the last motion (a C500 runs the next waypoint's MA
                // between two looks).
                let fresh = arm
                    .robot
                    .lock()
                    .map(|mut r| r.position(Tag::Joint, PosMode::Actual));
                let q = match fresh {
                    Ok(Ok(l)) => l.to_array6(),
                    Ok(Err(e)) => {
                        return aborted(
                            follow_code::GOAL_TOLERANCE_VIOLATED,
                            format!("the arm could not be read at the end: {}", words(&e)),
                        );
                    }
                    Err(_) => return aborted(follow_code::GOAL_TOLERANCE_VIOLATED, poisoned),
                };
                let (code, mut why) = run.plan.result(&q, elapsed, run.timed);
                if let Some((asked, sent, off)) = run.thinned {
                    why.push_str(&format!(
                        "; its {asked} points were thinned to {sent} for this controller, the \
                         dropped ones within {off:.4} rad of the path sent"
                    ));
                }
                let status = if code == follow_code::SUCCESSFUL {
                    GoalStatusEnum::Succeeded
                } else {
                    GoalStatusEnum::Aborted
                };
                Some((status, follow_result(code, why)))
            }
            Ok(Err(e)) => aborted(
                follow_code::GOAL_TOLERANCE_VIOLATED,
                format!("the motion failed: {}", words(&e)),
            ),
            Err(_) => aborted(follow_code::GOAL_TOLERANCE_VIOLATED, poisoned),
        }
    }

    fn canceled(&self, failed: Option<String>) -> FollowResult {
        match failed {
            None => follow_result(
                follow_code::SUCCESSFUL,
                "canceled: the arm was halted and stands",
            ),
            Some(why) => follow_result(follow_code::PATH_TOLERANCE_VIOLATED, why),
        }
    }

    fn replaces(&self) -> bool {
        self.replace
    }

    fn check(&self, goal: &FollowGoal) -> Result<(), FollowResult> {
        // Names, times, positions and tolerances: the start does not change them.
        follow::plan(goal, [0.0; 6], &self.joints)
            .map(drop)
            .map_err(|no| follow_result(no.code, no.why))
    }

    fn replaced(&self) -> FollowResult {
        follow_result(
            follow_code::SUCCESSFUL,
            "replaced by a newer goal: the arm was halted where it was and the new trajectory \
             starts there",
        )
    }
}

/// How close (mm) the fingers must stand to the asked gap for `reached_goal` (assumption: the
/// gripper's own resolution is not public; 1 mm).
pub const GRIP_REACHED_MM: f64 = 1.0;
/// The widest gap TROLGrip takes, mm (the table's range of `dist`; the URDF's gripper_joint
/// has it as its upper limit).
pub const GRIP_MAX_MM: f64 = trol_a465::urdf::GRIP_MAX_MM;

/// GripperCommand's goals; a run is the asked gap, mm.
pub struct Gripper;

impl Served<Gripper> {
    /// GripperCommand, no goal yet.
    pub fn gripper(services: ActionServices) -> Self {
        Served::new(Gripper, services)
    }
}

impl Goals for Gripper {
    type Goal = GripperGoal;
    type Result = GripperResult;
    type Feedback = GripperFeedback;
    type Run = f64;

    fn start(&mut self, arm: &Arm<'_>, goal: &GripperGoal) -> Result<f64, GripperResult> {
        let mm = goal.command.position * 1000.0;
        if !(mm.is_finite() && (0.0..=GRIP_MAX_MM + 0.5).contains(&mm)) {
            crate::warn_ros!(
                "trol-ros2: gripper_cmd refused: a gap of {} m is outside 0 .. {} m",
                goal.command.position,
                GRIP_MAX_MM / 1000.0
            );
            return Err(GripperResult::default());
        }
        let target = mm.round().min(GRIP_MAX_MM);
        match arm.robot.lock().map(|mut r| r.grip(target as u16)) {
            Ok(Ok(())) => Ok(target),
            Ok(Err(e)) => {
                crate::warn_ros!("trol-ros2: gripper_cmd: {}", words(&e));
                Err(GripperResult::default())
            }
            Err(_) => Err(GripperResult::default()),
        }
    }

    /// Feedback of the fingers, and once they stand, the result.
    fn progress(
        &mut self,
        arm: &Arm<'_>,
        target: &f64,
        send: &mut dyn FnMut(GripperFeedback),
    ) -> Option<(GoalStatusEnum, GripperResult)> {
        let failed = Some((GoalStatusEnum::Aborted, GripperResult::default()));
        let Ok((moving, gripper)) = arm.robot.lock().map(|mut r| {
            let moving = r.is_moving();
            (moving, r.gripper())
        }) else {
            return failed;
        };
        let g = match gripper {
            Ok(g) => g,
            Err(e) => {
                crate::warn_ros!("trol-ros2: gripper_cmd: {}", words(&e));
                return failed;
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
        send(state);
        match moving {
            Ok(true) => None,
            // Done: at the gap, or closed on an object (the grasp a close is for; as
            // ros2_controllers' gripper controller with stalling allowed). Anything else
            // did not do what was asked.
            Ok(false) if reached || stalled => Some((GoalStatusEnum::Succeeded, state)),
            Ok(false) => Some((GoalStatusEnum::Aborted, state)),
            Err(e) => {
                crate::warn_ros!("trol-ros2: gripper_cmd: {}", words(&e));
                Some((GoalStatusEnum::Aborted, state))
            }
        }
    }

    fn canceled(&self, _failed: Option<String>) -> GripperResult {
        GripperResult::default()
    }
}

"""`trol ros2` against a real DDS peer: Eclipse Cyclone DDS (PyPI `cyclonedds`, the library
under ROS 2's rmw_cyclonedds), on loopback only, speaking ROS 2's names and types.

The message types are written here from ROS 2's own definitions, not from TROL's code:
builtin_interfaces/msg/Time (`int32 sec`, `uint32 nanosec`), std_msgs/msg/Header
(`builtin_interfaces/Time stamp`, `string frame_id`), sensor_msgs/msg/JointState
(`std_msgs/Header header`, `string[] name`, `float64[] position`, `float64[] velocity`,
`float64[] effort`), std_msgs/msg/String (`string data`), std_srvs/srv/Trigger (an empty
request, which ROS 2's IDL gives `uint8 structure_needs_at_least_one_member`; a response of
`bool success`, `string message`). ROS 2 maps a topic `/ns/name` onto the DDS topic
`rt/ns/name`, a service onto `rq/ns/nameRequest` and `rr/ns/nameReply`, a type `pkg/msg/T`
onto `pkg::msg::dds_::T_`; rmw_cyclonedds puts a request header (the client's GUID, 8
bytes, and a sequence number, 8 bytes) before a request and its reply
(shared/reference/ros2.md)."""


import contextlib
import json
import os
import random
import subprocess
import sys
import threading
import time
import zlib
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

# Loopback only, no multicast: nothing leaves the machine (shared/reference/ros2.md).
os.environ["CYCLONEDDS_URI"] = (
    "<CycloneDDS><Domain id='any'><General><Interfaces><NetworkInterface name='lo'/>"
    "</Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery><Peers>"
    "<Peer address='127.0.0.1'/></Peers><ParticipantIndex>auto</ParticipantIndex>"
    "<MaxAutoParticipantIndex>40</MaxAutoParticipantIndex></Discovery></Domain></CycloneDDS>"
)

from cyclonedds.core import Qos, Policy  # noqa: E402
from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.idl import IdlStruct  # noqa: E402
from cyclonedds.idl.types import array, float64, int8, int32, int64, sequence, uint8, uint16, uint32, uint64  # noqa: E402
from cyclonedds.pub import DataWriter  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402
from cyclonedds.util import duration  # noqa: E402


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32
    nanosec: uint32


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time
    frame_id: str


@dataclass
class JointState(IdlStruct, typename="sensor_msgs::msg::dds_::JointState_"):
    header: Header
    name: sequence[str]
    position: sequence[float64]
    velocity: sequence[float64]
    effort: sequence[float64]


@dataclass
class String(IdlStruct, typename="std_msgs::msg::dds_::String_"):
    data: str


@dataclass
class TriggerRequest(IdlStruct, typename="std_srvs::srv::dds_::Trigger_Request_"):
    client_guid: uint64
    sequence_number: int64
    structure_needs_at_least_one_member: uint8


@dataclass
class TriggerResponse(IdlStruct, typename="std_srvs::srv::dds_::Trigger_Response_"):
    client_guid: uint64
    sequence_number: int64
    success: bool
    message: str


# control_msgs/action/FollowJointTrajectory (Humble, Jazzy) and what it is made of, field for
# field from trajectory_msgs, geometry_msgs, control_msgs, unique_identifier_msgs and
# action_msgs; the action's services carry rmw_cyclonedds's request header like Trigger's.

@dataclass
class UUID(IdlStruct, typename="unique_identifier_msgs::msg::dds_::UUID_"):
    uuid: array[uint8, 16]


@dataclass
class Duration(IdlStruct, typename="builtin_interfaces::msg::dds_::Duration_"):
    sec: int32
    nanosec: uint32


@dataclass
class JointTrajectoryPoint(IdlStruct, typename="trajectory_msgs::msg::dds_::JointTrajectoryPoint_"):
    positions: sequence[float64]
    velocities: sequence[float64]
    accelerations: sequence[float64]
    effort: sequence[float64]
    time_from_start: Duration


@dataclass
class JointTrajectory(IdlStruct, typename="trajectory_msgs::msg::dds_::JointTrajectory_"):
    header: Header
    joint_names: sequence[str]
    points: sequence[JointTrajectoryPoint]


@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: float64
    y: float64
    z: float64


@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    x: float64
    y: float64
    z: float64
    w: float64


@dataclass
class Transform(IdlStruct, typename="geometry_msgs::msg::dds_::Transform_"):
    translation: Vector3
    rotation: Quaternion


@dataclass
class Twist(IdlStruct, typename="geometry_msgs::msg::dds_::Twist_"):
    linear: Vector3
    angular: Vector3


@dataclass
class MultiDOFJointTrajectoryPoint(IdlStruct, typename="trajectory_msgs::msg::dds_::MultiDOFJointTrajectoryPoint_"):
    transforms: sequence[Transform]
    velocities: sequence[Twist]
    accelerations: sequence[Twist]
    time_from_start: Duration


@dataclass
class MultiDOFJointTrajectory(IdlStruct, typename="trajectory_msgs::msg::dds_::MultiDOFJointTrajectory_"):
    header: Header
    joint_names: sequence[str]
    points: sequence[MultiDOFJointTrajectoryPoint]


@dataclass
class JointTolerance(IdlStruct, typename="control_msgs::msg::dds_::JointTolerance_"):
    name: str
    position: float64
    velocity: float64
    acceleration: float64


@dataclass
class JointComponentTolerance(IdlStruct, typename="control_msgs::msg::dds_::JointComponentTolerance_"):
    joint_name: str
    component: uint16
    position: float64
    velocity: float64
    acceleration: float64


FJT = "control_msgs::action::dds_::FollowJointTrajectory_"


@dataclass
class FollowGoal(IdlStruct, typename=FJT + "Goal_"):
    trajectory: JointTrajectory
    multi_dof_trajectory: MultiDOFJointTrajectory
    path_tolerance: sequence[JointTolerance]
    component_path_tolerance: sequence[JointComponentTolerance]
    goal_tolerance: sequence[JointTolerance]
    component_goal_tolerance: sequence[JointComponentTolerance]
    goal_time_tolerance: Duration


@dataclass
class FollowResult(IdlStruct, typename=FJT + "Result_"):
    error_code: int32
    error_string: str


@dataclass
class FollowFeedback(IdlStruct, typename=FJT + "Feedback_"):
    header: Header
    joint_names: sequence[str]
    desired: JointTrajectoryPoint
    actual: JointTrajectoryPoint
    error: JointTrajectoryPoint
    multi_dof_joint_names: sequence[str]
    multi_dof_desired: MultiDOFJointTrajectoryPoint
    multi_dof_actual: MultiDOFJointTrajectoryPoint
    multi_dof_error: MultiDOFJointTrajectoryPoint


@dataclass
class SendGoalRequest(IdlStruct, typename=FJT + "SendGoal_Request_"):
    client_guid: uint64
    sequence_number: int64
    goal_id: UUID
    goal: FollowGoal


@dataclass
class SendGoalResponse(IdlStruct, typename=FJT + "SendGoal_Response_"):
    client_guid: uint64
    sequence_number: int64
    accepted: bool
    stamp: Time


@dataclass
class GetResultRequest(IdlStruct, typename=FJT + "GetResult_Request_"):
    client_guid: uint64
    sequence_number: int64
    goal_id: UUID


@dataclass
class GetResultResponse(IdlStruct, typename=FJT + "GetResult_Response_"):
    client_guid: uint64
    sequence_number: int64
    status: int8
    result: FollowResult


@dataclass
class FeedbackMessage(IdlStruct, typename=FJT + "FeedbackMessage_"):
    goal_id: UUID
    feedback: FollowFeedback


@dataclass
class GoalInfo(IdlStruct, typename="action_msgs::msg::dds_::GoalInfo_"):
    goal_id: UUID
    stamp: Time


@dataclass
class GoalStatus(IdlStruct, typename="action_msgs::msg::dds_::GoalStatus_"):
    goal_info: GoalInfo
    status: int8


@dataclass
class GoalStatusArray(IdlStruct, typename="action_msgs::msg::dds_::GoalStatusArray_"):
    status_list: sequence[GoalStatus]


@dataclass
class CancelGoalRequest(IdlStruct, typename="action_msgs::srv::dds_::CancelGoal_Request_"):
    client_guid: uint64
    sequence_number: int64
    goal_info: GoalInfo


@dataclass
class CancelGoalResponse(IdlStruct, typename="action_msgs::srv::dds_::CancelGoal_Response_"):
    client_guid: uint64
    sequence_number: int64
    return_code: int8
    goals_canceling: sequence[GoalInfo]


GC = "control_msgs::action::dds_::GripperCommand_"


@dataclass
class GripperCommand(IdlStruct, typename="control_msgs::msg::dds_::GripperCommand_"):
    position: float64
    max_effort: float64


@dataclass
class GripperGoal(IdlStruct, typename=GC + "Goal_"):
    command: GripperCommand


@dataclass
class GripperResult(IdlStruct, typename=GC + "Result_"):
    position: float64
    effort: float64
    stalled: bool
    reached_goal: bool


@dataclass
class GripperSendGoalRequest(IdlStruct, typename=GC + "SendGoal_Request_"):
    client_guid: uint64
    sequence_number: int64
    goal_id: UUID
    goal: GripperGoal


@dataclass
class GripperSendGoalResponse(IdlStruct, typename=GC + "SendGoal_Response_"):
    client_guid: uint64
    sequence_number: int64
    accepted: bool
    stamp: Time


@dataclass
class GripperGetResultRequest(IdlStruct, typename=GC + "GetResult_Request_"):
    client_guid: uint64
    sequence_number: int64
    goal_id: UUID


@dataclass
class GripperGetResultResponse(IdlStruct, typename=GC + "GetResult_Response_"):
    client_guid: uint64
    sequence_number: int64
    status: int8
    result: GripperResult


# action_msgs/GoalStatus's values.
SUCCEEDED, CANCELED, ABORTED = 4, 5, 6


def node_binary() -> Path:
    """`trol-ros2`: $TROL_ROS2_BIN, else target/debug/trol-ros2."""
    given = os.environ.get("TROL_ROS2_BIN")
    return Path(given) if given else ROOT / "target" / "debug" / "trol-ros2"


class Node:
    """A `trol-ros2` process on the embedded simulator, on its own domain."""

    def __init__(self, domain: int, namespace: str, time_scale: float = 10, extra: tuple[str, ...] = ()) -> None:
        env = dict(os.environ, ROS_LOCALHOST_ONLY="1", ROS_DOMAIN_ID=str(domain))
        env.pop("ROS_DISTRO", None)
        self.proc = subprocess.Popen(
            [str(node_binary()), "--port", "sim", "--time-scale", str(time_scale), "--namespace", namespace, *extra],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, text=True, env=env,
        )
        assert self.proc.stdout is not None
        self.first = self.proc.stdout.readline()
        self.rest: list[str] = []
        threading.Thread(target=self._drain, daemon=True).start()

    def _drain(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.rest.append(line)

    def stop(self) -> None:
        self.proc.terminate()
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


# The domains this process hands out: each test gets one of its own. With pytest-xdist
# (`pytest -n N`, scripts/test.sh where its lanes run side by side) worker k of N takes the
# domains k, k + N, k + 2N, ... from a start that all the run's workers share, so two tests
# running at once never meet; the start is the run's (xdist's run id) or, one at a time, a
# random one, so that two runs on one machine seldom do.
_DOMAINS = 200  # domains 1..200
_WORKERS = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1"))
_WORKER = int(os.environ.get("PYTEST_XDIST_WORKER", "gw0")[2:] or 0)
_RUN = os.environ.get("PYTEST_XDIST_TESTRUNUID")
_START = zlib.crc32(_RUN.encode()) if _RUN else random.randrange(_DOMAINS)
_handed_out = 0


@pytest.fixture
def domain() -> int:
    global _handed_out
    # A multiple of the workers, so that k, k + N, ... stay apart across the wrap.
    span = _DOMAINS - _DOMAINS % _WORKERS
    d = 1 + (_START + _WORKER + _WORKERS * _handed_out) % span
    _handed_out += 1
    return d


@pytest.fixture
def arm1(domain: int) -> Iterator[Node]:
    node = Node(domain, "arm1")
    try:
        assert "node /arm1/trol_a465 on ROS 2 domain" in node.first, node.first
        yield node
    finally:
        node.stop()


RELIABLE = Policy.Reliability.Reliable(max_blocking_time=duration(seconds=1))


def states_reader(dp: DomainParticipant, ns: str) -> DataReader:
    topic = Topic(dp, f"rt/{ns}/joint_states", JointState)
    return DataReader(dp, topic, qos=Qos(RELIABLE, Policy.History.KeepLast(50)))


# How often a wait looks again, s (tests/ros2/bench_ros2.py looks every millisecond).
POLL = 0.05


def wait_for(what: str, fn, limit: float = 30.0):  # type: ignore[no-untyped-def]
    """Call `fn` until it returns something other than None, within `limit` seconds."""
    until = time.monotonic() + limit
    while time.monotonic() < until:
        got = fn()
        if got is not None:
            return got
        time.sleep(POLL)
    raise AssertionError(f"no {what} within {limit} s")


def newest_state(states: DataReader) -> JointState:
    """The newest joint state the reader holds; if none has come yet (a new reader is still
    being matched, and a busy machine can take longer than any fixed pause), wait for one."""

    def newest():  # type: ignore[no-untyped-def]
        got = [s for s in states.take(N=50) if isinstance(s, JointState)]
        return got[-1] if got else None

    return wait_for("a joint state", newest)


class Service:
    """A ROS 2 service client as rmw_cyclonedds makes one: requests with its header on
    `rq/<name>Request`, replies with the same header on `rr/<name>Reply`."""

    def __init__(self, dp: DomainParticipant, name: str, req: type, resp: type) -> None:
        qos = Qos(RELIABLE, Policy.History.KeepLast(10))
        self.name, self.resp = name, resp
        self.writer = DataWriter(dp, Topic(dp, f"rq/{name}Request", req), qos=qos)
        self.reader = DataReader(dp, Topic(dp, f"rr/{name}Reply", resp), qos=qos)
        self.guid = random.getrandbits(63)
        self.seq = 0
        # Requests go once the service's reader and its reply writer are matched.
        wait_for(f"{name}'s server", lambda: True if self.writer.get_matched_subscriptions() else None)
        wait_for(f"{name}'s reply writer", lambda: True if self.reader.get_matched_publications() else None)

    def call(self, make, limit: float = 60.0):  # type: ignore[no-untyped-def]
        self.seq += 1
        seq = self.seq
        self.writer.write(make(self.guid, seq))

        def answer():  # type: ignore[no-untyped-def]
            for r in self.reader.take(N=10):
                if isinstance(r, self.resp) and r.client_guid == self.guid and r.sequence_number == seq:
                    return r
            return None

        return wait_for(f"{self.name}'s reply", answer, limit)


def call_trigger(dp: DomainParticipant, ns: str, service: str, seq: int, limit: float = 60.0) -> TriggerResponse:
    """A std_srvs/Trigger call."""
    s = Service(dp, f"{ns}/{service}", TriggerRequest, TriggerResponse)
    s.seq = seq - 1
    return s.call(lambda g, q: TriggerRequest(client_guid=g, sequence_number=q, structure_needs_at_least_one_member=0), limit)


@pytest.mark.timeout(180)
def test_joint_states_arrive_with_the_urdf_names_and_the_arm_s_values(arm1: Node, domain: int) -> None:
    dp = DomainParticipant(domain)
    reader = states_reader(dp, "arm1")
    samples: list[JointState] = []

    def some() -> bool | None:
        samples.extend(s for s in reader.take(N=50) if isinstance(s, JointState))
        return True if len(samples) >= 10 else None

    wait_for("10 joint states", some)
    first = samples[0]
    # The six joints, then the gripper's gap as one prismatic joint.
    assert list(first.name) == [f"joint_{i}" for i in range(1, 7)] + ["gripper_joint"]
    assert len(first.position) == 7 and len(first.velocity) == 7 and list(first.effort) == []
    # The simulator's arm stands at READY (every joint 0) before anything is asked; these
    # are its encoders, which dither by a few counts.
    assert list(first.position)[:6] == pytest.approx([0.0] * 6, abs=1e-3)
    stamps = [s.header.stamp.sec + s.header.stamp.nanosec * 1e-9 for s in samples]
    assert stamps == sorted(stamps) and stamps[-1] > stamps[0]
    assert abs(stamps[-1] - time.time()) < 60


@pytest.mark.timeout(180)
def test_the_description_reaches_a_late_subscriber(arm1: Node, domain: int) -> None:
    dp = DomainParticipant(domain)
    # Late: the node has published for a while when this subscriber starts.
    states = states_reader(dp, "arm1")
    wait_for("the node's joint states", lambda: True if states.take(N=1) else None)
    time.sleep(1.0)
    topic = Topic(dp, "rt/arm1/robot_description", String)
    reader = DataReader(dp, topic, qos=Qos(RELIABLE, Policy.Durability.TransientLocal, Policy.History.KeepLast(1)))
    got = wait_for("robot_description", lambda: next((s for s in reader.take(N=1) if isinstance(s, String)), None))
    urdf = subprocess.run([str(ROOT / "target" / "debug" / "trol"), "urdf"], check=True,
                          capture_output=True, text=True).stdout if (ROOT / "target" / "debug" / "trol").exists() else None
    assert "<robot" in got.data and 'name="joint_6"' in got.data
    if urdf is not None:
        # `trol urdf`'s, and the gripper as one prismatic joint on tool0 before its end.
        assert got.data.startswith(urdf.split("</robot>")[0]), got.data[:200]
        assert '<joint name="gripper_joint" type="prismatic">' in got.data
        assert got.data.rstrip().endswith("</robot>")


@pytest.mark.timeout(240)
def test_home_and_halt_are_ros2_services_that_say_what_the_arm_did(arm1: Node, domain: int) -> None:
    dp = DomainParticipant(domain)
    r = call_trigger(dp, "arm1", "home", 1)
    assert r.success, r.message
    assert "homed" in r.message
    r = call_trigger(dp, "arm1", "halt", 2)
    assert r.success, r.message
    assert "stands" in r.message


@pytest.mark.timeout(120)
def test_a_client_whose_reply_reader_comes_after_its_request_still_gets_the_reply(arm1: Node, domain: int) -> None:
    """DDS discovers each endpoint on its own: a request can reach the node before the node
    has matched the client's reply reader. The reply waits for it (not lost to nobody)."""
    dp = DomainParticipant(domain)
    qos = Qos(RELIABLE, Policy.History.KeepLast(10))
    writer = DataWriter(dp, Topic(dp, "rq/arm1/haltRequest", TriggerRequest), qos=qos)
    wait_for("the halt service", lambda: True if writer.get_matched_subscriptions() else None)
    writer.write(TriggerRequest(client_guid=7, sequence_number=1, structure_needs_at_least_one_member=0))
    # The node has the request (and has halted the arm) well before its client reads replies.
    time.sleep(1.0)
    reader = DataReader(dp, Topic(dp, "rr/arm1/haltReply", TriggerResponse), qos=qos)

    def answer():  # type: ignore[no-untyped-def]
        for r in reader.take(N=10):
            if isinstance(r, TriggerResponse) and r.client_guid == 7 and r.sequence_number == 1:
                return r
        return None

    r = wait_for("halt's reply", answer, 30.0)
    assert r.success, r.message
    assert "stands" in r.message


@pytest.mark.timeout(240)
def test_two_arms_in_two_namespaces_do_not_disturb_each_other(domain: int) -> None:
    one, two = Node(domain, "arm1"), Node(domain, "arm2")
    try:
        assert "/arm1/trol_a465" in one.first and "/arm2/trol_a465" in two.first
        dp = DomainParticipant(domain)
        r = call_trigger(dp, "arm2", "home", 7)
        assert r.success, r.message
        for ns in ["arm1", "arm2"]:
            reader = states_reader(dp, ns)
            s = wait_for(f"{ns}'s joint states", lambda: next(
                (x for x in reader.take(N=5) if isinstance(x, JointState)), None))
            assert list(s.name)[0] == "joint_1"
        # Each node answers for its own arm, on its own service names.
        r = call_trigger(dp, "arm1", "home", 8)
        assert r.success, r.message
    finally:
        one.stop()
        two.stop()


JOINTS = [f"joint_{i}" for i in range(1, 7)]


def trajectory_goal(names: list[str], points: list[tuple[float, list[float]]]) -> FollowGoal:
    return FollowGoal(
        trajectory=JointTrajectory(
            header=Header(stamp=Time(0, 0), frame_id=""),
            joint_names=names,
            points=[JointTrajectoryPoint(positions=q, velocities=[], accelerations=[], effort=[],
                                         time_from_start=Duration(int(t), int(round((t % 1) * 1e9))))
                    for t, q in points],
        ),
        multi_dof_trajectory=MultiDOFJointTrajectory(header=Header(stamp=Time(0, 0), frame_id=""),
                                                     joint_names=[], points=[]),
        path_tolerance=[], component_path_tolerance=[], goal_tolerance=[], component_goal_tolerance=[],
        goal_time_tolerance=Duration(0, 0),
    )


class Action:
    """A FollowJointTrajectory client on `<ns>/follow_joint_trajectory`."""

    def __init__(self, dp: DomainParticipant, ns: str) -> None:
        base = f"{ns}/follow_joint_trajectory/_action"
        self.send = Service(dp, f"{base}/send_goal", SendGoalRequest, SendGoalResponse)
        self.result = Service(dp, f"{base}/get_result", GetResultRequest, GetResultResponse)
        self.cancel = Service(dp, f"{base}/cancel_goal", CancelGoalRequest, CancelGoalResponse)
        self.feedback = DataReader(dp, Topic(dp, f"rt/{base}/feedback", FeedbackMessage),
                                   qos=Qos(RELIABLE, Policy.History.KeepLast(100)))
        self.status = DataReader(dp, Topic(dp, f"rt/{base}/status", GoalStatusArray),
                                 qos=Qos(RELIABLE, Policy.Durability.TransientLocal, Policy.History.KeepLast(1)))

    def goal(self, goal: FollowGoal) -> UUID:
        gid = UUID(uuid=list(random.randbytes(16)))
        r = self.send.call(lambda g, q: SendGoalRequest(client_guid=g, sequence_number=q, goal_id=gid, goal=goal))
        assert r.accepted
        return gid

    def outcome(self, gid: UUID, limit: float = 60.0) -> GetResultResponse:
        return self.result.call(lambda g, q: GetResultRequest(client_guid=g, sequence_number=q, goal_id=gid), limit)


@pytest.fixture
def arm_at_1x(domain: int) -> Iterator[Node]:
    """A node on the embedded simulator at real time (so a trajectory takes its own time)."""
    node = Node(domain, "arm1", time_scale=1)
    try:
        assert "/arm1/follow_joint_trajectory and /arm1/gripper_cmd" in node.first, node.first
        yield node
    finally:
        node.stop()


@pytest.mark.timeout(240)
def test_follow_joint_trajectory_runs_a_goal_with_feedback_and_its_result(arm_at_1x: Node, domain: int) -> None:
    dp = DomainParticipant(domain)
    assert call_trigger(dp, "arm1", "home", 1).success
    action = Action(dp, "arm1")
    states = states_reader(dp, "arm1")
    # The joints in another order than the URDF's: the goal's order is kept in the feedback.
    names = list(reversed(JOINTS))
    end = [0.2, 0.1, 0.3, 0.25, 0.2, 0.1]  # joint_6 .. joint_1
    gid = action.goal(trajectory_goal(names, [(0.8, [0.1, 0.05, 0.15, 0.1, 0.1, 0.05]), (1.6, end)]))
    r = action.outcome(gid)
    assert (r.status, r.result.error_code) == (SUCCEEDED, 0), r.result.error_string
    feedback = [m for m in action.feedback.take(N=100) if isinstance(m, FeedbackMessage) and list(m.goal_id.uuid) == list(gid.uuid)]
    assert feedback, "no feedback"
    f = feedback[-1].feedback
    assert list(f.joint_names) == names and len(f.desired.positions) == 6 and len(f.actual.positions) == 6
    # The arm tracked the trajectory: every feedback's error is the servo's lag and the
    # encoders' dither, far inside what MoveIt's default tolerances allow.
    worst = max(abs(e) for m in feedback for e in m.feedback.error.positions)
    assert worst < 0.02, worst
    # The arm is where the last point asked, as joint_states says.
    time.sleep(0.5)
    last = newest_state(states)
    assert list(last.position)[:6] == pytest.approx(list(reversed(end)), abs=2e-3)
    # The status says it too.
    st = wait_for("the goal's status", lambda: next(
        (g.status for a in action.status.take(N=5) if isinstance(a, GoalStatusArray)
         for g in a.status_list if list(g.goal_info.goal_id.uuid) == list(gid.uuid)), None))
    assert st == SUCCEEDED


@pytest.mark.timeout(240)
def test_follow_joint_trajectory_refuses_a_bad_goal_with_the_action_s_code_and_moves_nothing(
        arm_at_1x: Node, domain: int) -> None:
    dp = DomainParticipant(domain)
    assert call_trigger(dp, "arm1", "home", 1).success
    action = Action(dp, "arm1")
    # A joint missing.
    r = action.outcome(action.goal(trajectory_goal(JOINTS[:5], [(1.0, [0.1] * 5)])))
    assert (r.status, r.result.error_code) == (ABORTED, -2)
    assert "joint_6" in r.result.error_string
    # Faster than the arm: the controller's BIOS_TOO_FAST, with its name.
    r = action.outcome(action.goal(trajectory_goal(JOINTS, [(0.05, [1.0, 0, 0, 0, 0, 0])])))
    assert (r.status, r.result.error_code) == (ABORTED, -1)
    assert "BIOS_TOO_FAST" in r.result.error_string
    states = states_reader(dp, "arm1")
    time.sleep(0.5)
    last = newest_state(states)
    assert list(last.position)[:6] == pytest.approx([0.0] * 6, abs=2e-3)


FAR_TARGET = [1.2, 0.6, 1.0, 1.0, 0.8, 1.0]


def a_long_goal_under_way(dp: DomainParticipant) -> tuple[Action, UUID]:
    """The arm homed, and an 8 s trajectory goal to FAR_TARGET a second into its run."""
    assert call_trigger(dp, "arm1", "home", 1).success
    action = Action(dp, "arm1")
    gid = action.goal(trajectory_goal(JOINTS, [(8.0, FAR_TARGET)]))
    wait_for("feedback", lambda: True if action.feedback.take(N=10) else None)
    time.sleep(1.0)
    return action, gid


def standing_short_of_far_target(dp: DomainParticipant) -> None:
    """Two readings half a second apart agree, and the arm is not at FAR_TARGET."""
    states = states_reader(dp, "arm1")
    time.sleep(0.5)
    a = newest_state(states)
    time.sleep(0.5)
    b = newest_state(states)
    assert list(a.position) == pytest.approx(list(b.position), abs=1e-3)
    assert abs(b.position[0] - FAR_TARGET[0]) > 0.1, "the arm went on to the target"


@pytest.mark.timeout(240)
def test_cancelling_a_trajectory_halts_the_arm(arm_at_1x: Node, domain: int) -> None:
    dp = DomainParticipant(domain)
    action, gid = a_long_goal_under_way(dp)
    r = action.cancel.call(lambda g, q: CancelGoalRequest(client_guid=g, sequence_number=q,
                                                         goal_info=GoalInfo(goal_id=gid, stamp=Time(0, 0))))
    assert r.return_code == 0 and [list(x.goal_id.uuid) for x in r.goals_canceling] == [list(gid.uuid)]
    out = action.outcome(gid)
    assert out.status == CANCELED, out.result.error_string
    standing_short_of_far_target(dp)


@pytest.mark.timeout(240)
def test_the_halt_service_during_a_trajectory_stops_the_arm_and_aborts_the_goal(arm_at_1x: Node, domain: int) -> None:
    dp = DomainParticipant(domain)
    action, gid = a_long_goal_under_way(dp)
    r = call_trigger(dp, "arm1", "halt", 1)
    assert r.success, r.message
    # Not a success, not a cancel the client never sent: aborted, and it says why.
    out = action.outcome(gid)
    assert (out.status, out.result.error_code) == (ABORTED, -5), out.result.error_string
    assert "halted" in out.result.error_string, out.result.error_string
    standing_short_of_far_target(dp)


@pytest.mark.timeout(240)
def test_gripper_cmd_moves_the_fingers_and_says_whether_they_reached_the_gap(arm1: Node, domain: int) -> None:
    dp = DomainParticipant(domain)
    base = "arm1/gripper_cmd/_action"
    send = Service(dp, f"{base}/send_goal", GripperSendGoalRequest, GripperSendGoalResponse)
    result = Service(dp, f"{base}/get_result", GripperGetResultRequest, GripperGetResultResponse)

    def grip(gap_m: float) -> GripperGetResultResponse:
        gid = UUID(uuid=list(random.randbytes(16)))
        goal = GripperGoal(command=GripperCommand(position=gap_m, max_effort=10.0))
        r = send.call(lambda g, q: GripperSendGoalRequest(client_guid=g, sequence_number=q, goal_id=gid, goal=goal))
        assert r.accepted
        return result.call(lambda g, q: GripperGetResultRequest(client_guid=g, sequence_number=q, goal_id=gid))

    r = grip(0.02)
    assert r.status == SUCCEEDED
    assert r.result.reached_goal and not r.result.stalled
    assert r.result.position == pytest.approx(0.02, abs=1e-3)
    # A gap the fingers cannot make: aborted, nothing reached.
    r = grip(0.2)
    assert r.status == ABORTED and not r.result.reached_goal


def trol_binary() -> Path:
    given = os.environ.get("TROL_BIN")
    return Path(given) if given else ROOT / "target" / "debug" / "trol"


class Controller:
    """A simulated real controller as its own process (`trol sim --rapl` or `--mars`)."""

    def __init__(self, kind: str, tmp: Path) -> None:
        profile = subprocess.run([str(trol_binary()), "sim", kind, "--print-profile"],
                                 check=True, capture_output=True, text=True).stdout
        (tmp / "arm.toml").write_text(profile)
        self.proc = subprocess.Popen([str(trol_binary()), "sim", kind, "--time-scale", "5"],
                                     stdout=subprocess.PIPE, stdin=subprocess.DEVNULL, text=True)
        assert self.proc.stdout is not None
        line = self.proc.stdout.readline()
        assert "serving on " in line, line
        self.port = line.split("serving on ", 1)[1].split()[0]
        threading.Thread(target=self.proc.stdout.read, daemon=True).start()
        prefix, key = ("rapl", "rapl-profile") if kind == "--rapl" else ("mars", "mars-profile")
        (tmp / "trol.cfg").write_text(f"9600\n{prefix}:{self.port}\n0 0 0 0 0 0\n{key} = {tmp / 'arm.toml'}\n")
        self.cfg = tmp / "trol.cfg"

    def stop(self) -> None:
        self.proc.kill()
        self.proc.wait()


@contextlib.contextmanager
def node_on(controller: "Controller", domain: int) -> Iterator[tuple[str, list[str]]]:
    """`trol-ros2 --namespace cell -v` on `controller`'s port: its first line, and its log
    as it comes; the node and the controller ended after."""
    env = dict(os.environ, ROS_LOCALHOST_ONLY="1", ROS_DOMAIN_ID=str(domain))
    env.pop("ROS_DISTRO", None)
    node = subprocess.Popen([str(node_binary()), "--config", str(controller.cfg), "--namespace", "cell", "-v"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL,
                            text=True, env=env)
    log: list[str] = []
    threading.Thread(target=lambda: log.extend(node.stderr), daemon=True).start()  # type: ignore[arg-type]
    try:
        assert node.stdout is not None
        first = node.stdout.readline()
        assert "node /cell/trol_a465" in first and controller.port in first, first
        threading.Thread(target=node.stdout.read, daemon=True).start()
        yield first, log
    finally:
        node.terminate()
        try:
            node.wait(timeout=10)
        except subprocess.TimeoutExpired:
            node.kill()
        controller.stop()


@pytest.mark.timeout(300)
@pytest.mark.parametrize("kind,timed", [("--mars", True), ("--rapl", False)])
def test_trol_ros2_drives_the_simulated_real_controllers_through_their_ports(
        kind: str, timed: bool, tmp_path: Path, domain: int) -> None:
    with node_on(Controller(kind, tmp_path), domain) as (_, log):
        dp = DomainParticipant(domain)
        r = call_trigger(dp, "cell", "home", 1, limit=120)
        assert r.success, r.message
        action = Action(dp, "cell")
        end = [0.2, 0.1, 0.6, 0.1, 0.5, 0.1]
        gid = action.goal(trajectory_goal(JOINTS, [(3.0, [0.1, 0.05, 0.4, 0.05, 0.3, 0.05]), (6.0, end)]))
        out = action.outcome(gid, limit=120)
        assert (out.status, out.result.error_code) == (SUCCEEDED, 0), out.result.error_string + "".join(log[-40:])
        # A C500 has no timed path, and the result says so.
        assert ("without its times" in out.result.error_string) == (not timed), out.result.error_string
        states = states_reader(dp, "cell")
        s = wait_for("joint states", lambda: next(
            (x for x in reversed(states.take(N=50)) if isinstance(x, JointState)), None))
        assert list(s.position)[:6] == pytest.approx(end, abs=3e-3)


@pytest.mark.timeout(240)
def test_a_path_tolerance_the_arm_cannot_keep_aborts_the_goal_and_halts_the_arm(arm_at_1x: Node, domain: int) -> None:
    dp = DomainParticipant(domain)
    assert call_trigger(dp, "arm1", "home", 1).success
    action = Action(dp, "arm1")
    target = [1.0, 0.5, 0.8, 0.8, 0.6, 0.8]
    goal = trajectory_goal(JOINTS, [(6.0, target)])
    # A micro-radian along the way: the servo's lag alone breaks it.
    goal.path_tolerance = [JointTolerance(name="joint_1", position=1e-6, velocity=0.0, acceleration=0.0)]
    out = action.outcome(action.goal(goal))
    assert (out.status, out.result.error_code) == (ABORTED, -4), out.result.error_string
    assert "joint_1" in out.result.error_string and "halted" in out.result.error_string
    states = states_reader(dp, "arm1")
    time.sleep(0.5)
    last = newest_state(states)
    assert abs(last.position[0] - target[0]) > 0.5, "the arm was stopped early"


@pytest.mark.timeout(240)
def test_gripper_cmd_says_stalled_when_the_fingers_close_on_an_object(tmp_path: Path, domain: int) -> None:
    # trol.cfg's `object = 30`: a 30 mm object between the fingers at start.
    (tmp_path / "trol.cfg").write_text("9600\nsim\n0 0 0 0 0 0\ntime_scale = 10\nobject = 30\n")
    env = dict(os.environ, ROS_LOCALHOST_ONLY="1", ROS_DOMAIN_ID=str(domain))
    node = subprocess.Popen([str(node_binary()), "--config", str(tmp_path / "trol.cfg"), "--namespace", "hand"],
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, stdin=subprocess.DEVNULL,
                            text=True, env=env)
    try:
        assert node.stdout is not None
        first = node.stdout.readline()
        assert "/hand/gripper_cmd" in first, first
        threading.Thread(target=node.stdout.read, daemon=True).start()
        dp = DomainParticipant(domain)
        base = "hand/gripper_cmd/_action"
        send = Service(dp, f"{base}/send_goal", GripperSendGoalRequest, GripperSendGoalResponse)
        result = Service(dp, f"{base}/get_result", GripperGetResultRequest, GripperGetResultResponse)
        gid = UUID(uuid=list(random.randbytes(16)))
        goal = GripperGoal(command=GripperCommand(position=0.01, max_effort=10.0))
        r = send.call(lambda g, q: GripperSendGoalRequest(client_guid=g, sequence_number=q, goal_id=gid, goal=goal))
        assert r.accepted
        out = result.call(lambda g, q: GripperGetResultRequest(client_guid=g, sequence_number=q, goal_id=gid))
        # Closed on the object: stalled at its width, short of the asked gap; a grasp.
        assert out.status == SUCCEEDED
        assert out.result.stalled and not out.result.reached_goal
        assert out.result.position == pytest.approx(0.03, abs=1e-3)
    finally:
        node.terminate()
        try:
            node.wait(timeout=10)
        except subprocess.TimeoutExpired:
            node.kill()


@pytest.mark.timeout(240)
def test_a_kilted_peer_reads_the_discovery_message_and_the_trajectory_feedback_in_its_layouts(domain: int) -> None:
    # The Kilted peer in a process of its own (tests/ros2/kilted_peer.py): Cyclone DDS keeps
    # one definition of a type name per process, and this one's are Jazzy's.
    node = Node(domain, "arm1", time_scale=1, extra=("--distro", "kilted"))
    peer, lines = peer_process("kilted_peer.py", domain, 60)
    try:
        assert "/arm1/follow_joint_trajectory" in node.first, node.first
        # The discovery message in Kilted's layout (that of Jazzy, ros2-client's own).
        seen = wait_for("the node in Kilted's discovery layout", lambda: ours(lines) or None)
        assert seen[-1]["padded"], seen[-1]
        dp = DomainParticipant(domain)
        assert call_trigger(dp, "arm1", "home", 1).success
        action = Action(dp, "arm1")
        gid = action.goal(trajectory_goal(JOINTS, [(0.8, [0.1] * 6), (1.6, [0.2] * 6)]))
        r = action.outcome(gid)
        assert (r.status, r.result.error_code) == (SUCCEEDED, 0), r.result.error_string
        goal = bytes(gid.uuid).hex()
        got = wait_for("feedback read in Kilted's layout", lambda: [
            x for x in map(json.loads, list(lines)) if x.get("goal") == goal] or None)
        assert all(x["names"] == JOINTS and x["actual"] == 6 for x in got), got
        # The point in use goes from the first to the second; the multi-DOF index stays 0.
        wait_for("the second point in use", lambda: True if any(
            json.loads(x)["index"] == 1 for x in list(lines) if json.loads(x).get("goal") == goal) else None)
        assert {x["index"] for x in got} <= {0, 1}, got
        assert all(x["multi_dof_index"] == 0 for x in got), got
    finally:
        peer.kill()
        peer.wait()
        node.stop()


def peer_process(script: str, domain: int, seconds: float) -> tuple[subprocess.Popen, list[str]]:
    """A peer of another distribution's layouts (tests/ros2/`script`) on `domain`, for the
    namespace arm1, ready, its lines gathered as they come."""
    peer = subprocess.Popen([sys.executable, str(Path(__file__).with_name(script)), str(domain), "arm1",
                             str(seconds)], stdout=subprocess.PIPE, stdin=subprocess.DEVNULL, text=True,
                            cwd=Path(__file__).parent)
    assert peer.stdout is not None and peer.stdout.readline().strip() == "ready"
    lines: list[str] = []
    threading.Thread(target=lambda: lines.extend(peer.stdout), daemon=True).start()  # type: ignore[arg-type]
    return peer, lines


def ours(lines: list[str]) -> list[dict]:
    """The discovery messages a Humble peer decoded that name the node /arm1/trol_a465."""
    got = [json.loads(x) for x in list(lines)]
    return [x for x in got if "nodes" in x and any(n["ns"] == "/arm1" and n["name"] == "trol_a465"
                                                    for n in x["nodes"])]


@pytest.mark.timeout(300)
def test_a_humble_peer_sees_the_node_and_reads_its_feedback_with_distro_humble(domain: int) -> None:
    # Without --distro humble (Jazzy's layout, 16-byte ids) a Humble peer cannot read the
    # node's discovery message: `ros2 node list` on Humble would not show it.
    node = Node(domain, "arm1", time_scale=1)
    peer, lines = peer_process("humble_peer.py", domain, 8)
    try:
        peer.wait(timeout=60)
        assert not ours(lines), lines
    finally:
        peer.kill()
        node.stop()
    node = Node(domain, "arm1", time_scale=1, extra=("--distro", "humble"))
    peer, lines = peer_process("humble_peer.py", domain, 60)
    try:
        seen = wait_for("the node in Humble's discovery layout", lambda: ours(lines) or None)
        info = next(n for n in seen[-1]["nodes"] if n["name"] == "trol_a465")
        # Its readers (requests, goals) and writers (joint_states, replies' topics), each
        # id a DDS GUID padded to 24 bytes as Humble's rmw pads it.
        assert info["readers"] >= 8 and info["writers"] >= 5, info
        assert seen[-1]["padded"], seen[-1]
        dp = DomainParticipant(domain)
        assert call_trigger(dp, "arm1", "home", 1).success
        action = Action(dp, "arm1")
        gid = action.goal(trajectory_goal(JOINTS, [(0.8, [0.1] * 6)]))
        r = action.outcome(gid)
        assert (r.status, r.result.error_code) == (SUCCEEDED, 0), r.result.error_string
        goal = bytes(gid.uuid).hex()
        fed = wait_for("feedback read in Humble's layout", lambda: [
            x for x in map(json.loads, list(lines)) if x.get("goal") == goal] or None)
        assert all(x["names"] == JOINTS and x["actual"] == 6 for x in fed), fed
    finally:
        peer.kill()
        peer.wait()
        node.stop()


@pytest.mark.timeout(300)
def test_a_dense_plan_is_thinned_for_a_c500_and_reaches_its_end(tmp_path: Path, domain: int) -> None:
    # 40 points, as MoveIt plans them; a C500 runs at most 16 (one joint move each).
    with node_on(Controller("--rapl", tmp_path), domain) as (first, _):
        # A C500's position read is slow: joint_states says the rate it keeps, and why.
        assert "(asked 50 Hz: a position read takes" in first, first
        dp = DomainParticipant(domain)
        assert call_trigger(dp, "cell", "home", 1, limit=120).success
        action = Action(dp, "cell")
        end = [0.3, 0.1, 0.4, 0.1, 0.3, 0.2]
        points = [(0.1 * k, [x * k / 40 for x in end]) for k in range(1, 41)]
        out = action.outcome(action.goal(trajectory_goal(JOINTS, points)), limit=180)
        assert (out.status, out.result.error_code) == (SUCCEEDED, 0), out.result.error_string
        assert "40 points were thinned to 16" in out.result.error_string, out.result.error_string
        states = states_reader(dp, "cell")
        s = wait_for("joint states", lambda: next(
            (x for x in reversed(states.take(N=50)) if isinstance(x, JointState)), None))
        assert list(s.position)[:6] == pytest.approx(end, abs=3e-3)

"""`trol ros2` against ROS 2's own client library: rclpy from PyPI (ROS 2 Jazzy's
`ros-jazzy-rclpy`), on ROS 2's default middleware, Fast DDS (rmw_fastrtps_cpp), with the
message types ROS 2 generated (sensor_msgs, std_msgs, std_srvs), as a lab's program uses them.

Fast DDS answers a service the way RPC over DDS's enhanced mapping does, which `trol ros2` did
not speak until issue 61 (its calls went unanswered); tests/ros2/test_ros2.py checks the same
node against Cyclone DDS. Each test runs on a ROS 2 domain of its own, on loopback only.
"""

import os
import random
import signal
import subprocess
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node as RosNode
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import String
from std_srvs.srv import Trigger

ROOT = Path(__file__).resolve().parents[3]
JOINTS = [f"joint_{i}" for i in range(1, 7)]


def binary(var: str, name: str) -> Path:
    given = os.environ.get(var)
    return Path(given) if given else ROOT / "target" / "debug" / name


class TrolNode:
    """A `trol-ros2` process (its stdout's first line read), ended with `signal`."""

    def __init__(self, domain: int, *args: str) -> None:
        env = dict(os.environ, ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
        self.proc = subprocess.Popen(
            [str(binary("TROL_ROS2_BIN", "trol-ros2")), *args],
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

    def end(self, sig: int = signal.SIGTERM, limit: float = 30) -> int:
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
        try:
            return self.proc.wait(timeout=limit)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
            raise AssertionError(f"trol-ros2 did not end within {limit} s of signal {sig}")


class Ros:
    """An rclpy node of the test's own, in a context on the test's domain."""

    def __init__(self, domain: int) -> None:
        os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
        os.environ.pop("RMW_IMPLEMENTATION", None)
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain)
        self.node = RosNode(f"tester_{random.randrange(1 << 30)}", context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def spin_until(self, what: str, done, limit: float = 30.0):  # type: ignore[no-untyped-def]
        until = time.monotonic() + limit
        while time.monotonic() < until:
            got = done()
            if got:
                return got
            self.executor.spin_once(timeout_sec=0.05)
        raise AssertionError(f"no {what} within {limit} s")

    def call(self, service: str, limit: float = 60.0) -> Trigger.Response:
        client = self.node.create_client(Trigger, service)
        self.spin_until(f"server of {service}", lambda: client.service_is_ready())
        future = client.call_async(Trigger.Request())
        return self.spin_until(f"answer from {service}", lambda: future.result() if future.done() else None, limit)

    def states(self, ns: str) -> list[JointState]:
        got: list[JointState] = []
        self.node.create_subscription(JointState, f"/{ns}/joint_states", got.append, 10)
        return got

    def close(self) -> None:
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.shutdown(context=self.context)


# Domains 201..230 (tests/ros2/test_ros2.py's Cyclone tests use 1..200): with pytest-xdist
# worker k of N takes k, k + N, k + 2N, ... from a start all the run's workers share (its run
# id), so two tests running at once never share a domain; one at a time, a random start.
_SPAN = 30
_WORKERS = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1"))
_WORKER = int(os.environ.get("PYTEST_XDIST_WORKER", "gw0")[2:] or 0)
_RUN = os.environ.get("PYTEST_XDIST_TESTRUNUID")
_START = sum(_RUN.encode()) if _RUN else random.randrange(_SPAN)
_handed = 0


@pytest.fixture
def domain() -> int:
    global _handed
    span = _SPAN - _SPAN % _WORKERS
    d = 201 + (_START + _WORKER + _WORKERS * _handed) % span
    _handed += 1
    return d


@pytest.fixture
def ros(domain: int) -> Iterator[Ros]:
    r = Ros(domain)
    try:
        yield r
    finally:
        r.close()


@pytest.fixture
def arm1(domain: int) -> Iterator[TrolNode]:
    node = TrolNode(domain, "--port", "sim", "--time-scale", "10", "--namespace", "arm1")
    try:
        assert "node /arm1/trol_a465 on ROS 2 domain" in node.first, node.first
        yield node
    finally:
        node.end()


def test_the_middleware_is_ros_2_s_default_fast_dds(ros: Ros) -> None:
    assert rclpy.get_rmw_implementation_identifier() == "rmw_fastrtps_cpp"


def test_joint_states_arrive_with_the_urdf_s_names(arm1: TrolNode, ros: Ros) -> None:
    got = ros.states("arm1")
    ros.spin_until("five joint states", lambda: len(got) >= 5)
    # The six joints, then the gripper's gap as one prismatic joint.
    assert list(got[-1].name) == JOINTS + ["gripper_joint"]
    assert len(got[-1].position) == 7


def test_robot_description_reaches_a_subscriber_that_comes_late(arm1: TrolNode, ros: Ros) -> None:
    time.sleep(1.0)
    got: list[String] = []
    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
    ros.node.create_subscription(String, "/arm1/robot_description", got.append, latched)
    ros.spin_until("robot_description", lambda: got)
    assert "<robot" in got[0].data and 'name="joint_6"' in got[0].data


def test_home_and_halt_answer_a_fast_dds_client(arm1: TrolNode, ros: Ros) -> None:
    r = ros.call("/arm1/home")
    assert r.success, r.message
    assert "homed" in r.message
    r = ros.call("/arm1/halt")
    assert r.success, r.message
    assert "stands" in r.message


def test_the_node_is_listed_once_in_its_namespace(arm1: TrolNode, ros: Ros) -> None:
    def listed():  # type: ignore[no-untyped-def]
        names = ros.node.get_node_names_and_namespaces()
        return names if any(n == "trol_a465" for n, _ in names) else None

    names = ros.spin_until("trol_a465 in the node list", listed)
    time.sleep(1.0)
    names = ros.node.get_node_names_and_namespaces()
    ours = [(n, ns) for n, ns in names if n == "trol_a465"]
    assert ours == [("trol_a465", "/arm1")], names


def test_the_parameters_say_how_the_node_was_started_and_refuse_a_set(arm1: TrolNode, ros: Ros) -> None:
    # rclpy's own parameter client, as `ros2 param list/get/describe/set` use these services.
    from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
    from rclpy.parameter_client import AsyncParameterClient

    client = AsyncParameterClient(ros.node, "/arm1/trol_a465")
    ros.spin_until("the parameter services", lambda: client.services_are_ready())

    def wait(future):  # type: ignore[no-untyped-def]
        return ros.spin_until("a parameter service's answer", lambda: future.result() if future.done() else None)

    names = list(wait(client.list_parameters()).result.names)
    assert sorted(names) == sorted(["port", "rate", "prefix", "distro", "one_goal", "use_sim_time"]), names
    values = wait(client.get_parameters(["port", "rate", "one_goal", "nothing"])).values
    assert (values[0].type, values[0].string_value) == (ParameterType.PARAMETER_STRING, "sim")
    assert (values[1].type, values[1].double_value) == (ParameterType.PARAMETER_DOUBLE, 50.0)
    assert (values[2].type, values[2].bool_value) == (ParameterType.PARAMETER_BOOL, False)
    assert values[3].type == ParameterType.PARAMETER_NOT_SET
    described = wait(client.describe_parameters(["rate"])).descriptors
    assert described[0].read_only and "--rate" in described[0].additional_constraints
    # A set is refused, says what to do, and changes nothing.
    asked = Parameter(name="rate", value=ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=5.0))
    result = wait(client.set_parameters([asked])).results[0]
    assert not result.successful and "restart trol-ros2 with --rate" in result.reason, result.reason
    assert wait(client.get_parameters(["rate"])).values[0].double_value == 50.0


def moving(states: list[JointState], since: int) -> bool:
    """Whether the joint states after the `since`-th moved."""
    seen = [tuple(s.position) for s in states[since:]]
    return len(seen) >= 2 and max(abs(a - b) for a, b in zip(seen[0], seen[-1])) > 1e-3


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP, signal.SIGINT])
def test_a_signal_during_a_motion_halts_the_arm_before_the_node_ends(sig: int, tmp_path: Path, domain: int) -> None:
    # The arm is a simulated controller of its own (`trol sim`, in real time), so that what
    # it does after the node has ended can be seen by the next node.
    sim = subprocess.Popen([str(binary("TROL_BIN", "trol")), "sim", "--time-scale", "1", "--server"],
                           stdout=subprocess.PIPE, stdin=subprocess.DEVNULL, stderr=subprocess.DEVNULL, text=True)
    ros = Ros(domain)
    try:
        assert sim.stdout is not None
        line = sim.stdout.readline()
        assert "serving on " in line, line
        port = line.split("serving on ", 1)[1].split()[0]
        threading.Thread(target=sim.stdout.read, daemon=True).start()
        # The arm away from its home pose first, so that the node's Home has a way to go.
        away = subprocess.run([str(binary("TROL_BIN", "trol")), "interp", "--port", port],
                              input="home 0\njoint 1 1.5\nfinish\n", capture_output=True, text=True, timeout=120)
        assert away.returncode == 0, away.stdout + away.stderr
        node = TrolNode(domain, "--port", port, "--namespace", "cell")
        assert "node /cell/trol_a465" in node.first, node.first
        states = ros.states("cell")
        client = ros.node.create_client(Trigger, "/cell/home")
        ros.spin_until("the home service", lambda: client.service_is_ready())
        client.call_async(Trigger.Request())  # a Home, group by group: many seconds at 1x
        ros.spin_until("the arm moving", lambda: moving(states, max(0, len(states) - 25)), 60)
        code = node.end(sig)
        said = "".join(node.rest)
        assert "halted and stands" in said, said
        assert "ERROR" not in said, said
        assert code in (0, 130, 143, -sig), (code, said)
        # The next node on the same controller finds the arm standing.
        again = TrolNode(domain, "--port", port, "--namespace", "cell")
        try:
            if "node /cell/trol_a465" not in again.first:
                again.proc.wait(timeout=30)
                time.sleep(0.5)
            assert "node /cell/trol_a465" in again.first, again.first + "".join(again.rest)
            start = len(states)
            ros.spin_until("a second of joint states", lambda: len(states) >= start + 20)
            assert not moving(states, start), [s.position for s in states[start:start + 3]]
        finally:
            again.end()
    finally:
        ros.close()
        sim.kill()
        sim.wait()


# The actions, with control_msgs generated by rosidl (tests/ros2/rclpy/control_msgs.sh).
from builtin_interfaces.msg import Duration  # noqa: E402
from control_msgs.action import FollowJointTrajectory, GripperCommand  # noqa: E402
from rclpy.action import ActionClient  # noqa: E402
from trajectory_msgs.msg import JointTrajectoryPoint  # noqa: E402

# action_msgs/GoalStatus's values.
SUCCEEDED, CANCELED, ABORTED = 4, 5, 6
FAR_TARGET = [1.2, 0.6, 0.9, 0.9, 0.7, 0.9]


def trajectory(names: list[str], points: list[tuple[float, list[float]]]) -> FollowJointTrajectory.Goal:
    goal = FollowJointTrajectory.Goal()
    goal.trajectory.joint_names = names
    goal.trajectory.points = [
        JointTrajectoryPoint(positions=q, time_from_start=Duration(sec=int(t), nanosec=int(round((t % 1) * 1e9))))
        for t, q in points
    ]
    return goal


class Goals:
    """An rclpy ActionClient on `/<ns>/<action>`, with what came back."""

    def __init__(self, ros: Ros, ns: str, action: str = "follow_joint_trajectory", kind=FollowJointTrajectory) -> None:  # type: ignore[no-untyped-def]
        self.ros = ros
        self.client = ActionClient(ros.node, kind, f"/{ns}/{action}")
        self.feedback: list = []  # type: ignore[type-arg]
        ros.spin_until(f"the action server {ns}/{action}", lambda: self.client.server_is_ready())

    def send(self, goal):  # type: ignore[no-untyped-def]
        future = self.client.send_goal_async(goal, feedback_callback=self.feedback.append)
        return self.ros.spin_until("the goal's answer", lambda: future.result() if future.done() else None)

    def outcome(self, handle, limit: float = 120.0):  # type: ignore[no-untyped-def]
        future = handle.get_result_async()
        return self.ros.spin_until("the goal's result", lambda: future.result() if future.done() else None, limit)


def standing(ros: Ros, states: list[JointState]) -> list[float]:
    """The arm's joints once twenty readings in a row agree."""
    start = len(states)
    ros.spin_until("twenty joint states", lambda: len(states) >= start + 20)
    assert not moving(states, start), "the arm still moves"
    return list(states[-1].position)[:6]


def test_a_trajectory_goal_runs_to_its_end_with_feedback(arm1: TrolNode, ros: Ros) -> None:
    assert ros.call("/arm1/home").success
    states = ros.states("arm1")
    goals = Goals(ros, "arm1")
    end = [0.2, 0.1, 0.6, 0.1, 0.5, 0.1]
    handle = goals.send(trajectory(JOINTS, [(3.0, [0.1, 0.05, 0.4, 0.05, 0.3, 0.05]), (6.0, end)]))
    assert handle.accepted
    out = goals.outcome(handle)
    assert (out.status, out.result.error_code) == (SUCCEEDED, 0), out.result.error_string
    assert goals.feedback, "no feedback while the trajectory ran"
    assert list(goals.feedback[-1].feedback.joint_names) == JOINTS
    assert standing(ros, states) == pytest.approx(end, abs=3e-3)


def test_a_goal_with_unknown_joints_fails_and_moves_nothing(arm1: TrolNode, ros: Ros) -> None:
    assert ros.call("/arm1/home").success
    states = ros.states("arm1")
    before = standing(ros, states)
    goals = Goals(ros, "arm1")
    handle = goals.send(trajectory(["shoulder", "elbow"], [(2.0, [0.5, 0.5])]))
    if handle.accepted:
        out = goals.outcome(handle)
        assert out.status == ABORTED and out.result.error_code == -2, out.result.error_string
    assert standing(ros, states) == pytest.approx(before, abs=1e-3)


def test_a_cancel_halts_the_arm_short_of_its_target(domain: int, ros: Ros) -> None:
    node = TrolNode(domain, "--port", "sim", "--time-scale", "1", "--namespace", "arm1")
    try:
        assert ros.call("/arm1/home").success
        states = ros.states("arm1")
        goals = Goals(ros, "arm1")
        handle = goals.send(trajectory(JOINTS, [(8.0, FAR_TARGET)]))
        assert handle.accepted
        ros.spin_until("feedback", lambda: goals.feedback)
        ros.spin_until("the arm moving", lambda: moving(states, max(0, len(states) - 25)))
        cancel = handle.cancel_goal_async()
        answer = ros.spin_until("the cancel's answer", lambda: cancel.result() if cancel.done() else None)
        assert len(answer.goals_canceling) == 1
        out = goals.outcome(handle)
        assert out.status == CANCELED, out.result.error_string
        q = standing(ros, states)
        assert abs(q[0] - FAR_TARGET[0]) > 0.1, "the arm went on to its target"
    finally:
        node.end()


def test_the_gripper_action_reaches_its_gap(arm1: TrolNode, ros: Ros) -> None:
    goals = Goals(ros, "arm1", "gripper_cmd", GripperCommand)
    goal = GripperCommand.Goal()
    goal.command.position = 0.02
    goal.command.max_effort = 10.0
    handle = goals.send(goal)
    assert handle.accepted
    out = goals.outcome(handle)
    assert out.status == SUCCEEDED
    assert out.result.reached_goal and not out.result.stalled
    assert out.result.position == pytest.approx(0.02, abs=1e-3)
    # joint_states carries the gap as `gripper_joint`, in metres.
    states = ros.states("arm1")
    ros.spin_until("the gap in joint_states", lambda: [
        s for s in states if abs(s.position[list(s.name).index("gripper_joint")] - 0.02) < 1e-3])


def test_two_arms_in_two_namespaces_run_one_goal_each(domain: int, ros: Ros) -> None:
    left = TrolNode(domain, "--port", "sim", "--time-scale", "10", "--namespace", "left")
    right = TrolNode(domain, "--port", "sim", "--time-scale", "10", "--namespace", "right")
    try:
        for ns in ("left", "right"):
            assert ros.call(f"/{ns}/home").success
        left_states, right_states = ros.states("left"), ros.states("right")
        before = standing(ros, right_states)
        goals = Goals(ros, "left")
        end = [0.3, 0.2, 0.5, 0.1, 0.4, 0.2]
        handle = goals.send(trajectory(JOINTS, [(4.0, end)]))
        assert handle.accepted
        out = goals.outcome(handle)
        assert out.status == SUCCEEDED, out.result.error_string
        assert standing(ros, left_states) == pytest.approx(end, abs=3e-3)
        assert standing(ros, right_states) == pytest.approx(before, abs=1e-3), "the other arm moved"
    finally:
        left.end()
        right.end()


def test_a_second_node_for_the_same_names_refuses_to_start_and_says_who_serves_them(arm1: TrolNode, domain: int) -> None:
    second = TrolNode(domain, "--port", "sim", "--namespace", "arm1")
    code = second.proc.wait(timeout=60)
    said = second.first + "".join(second.rest)
    assert code == 1, said
    assert "another node already serves /arm1/" in said and "participant " in said, said
    assert "no arm was touched" in said, said


def test_a_prefix_names_the_joints_of_one_arm_of_a_cell(domain: int, ros: Ros) -> None:
    node = TrolNode(domain, "--port", "sim", "--time-scale", "10", "--namespace", "cell", "--prefix", "arm2_")
    try:
        assert "node /cell/trol_a465" in node.first, node.first
        names = [f"arm2_{j}" for j in JOINTS]
        states = ros.states("cell")
        ros.spin_until("joint states", lambda: states)
        assert list(states[-1].name) == names + ["arm2_gripper_joint"]
        got: list[String] = []
        latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
        ros.node.create_subscription(String, "/cell/robot_description", got.append, latched)
        ros.spin_until("robot_description", lambda: got)
        assert 'joint name="arm2_joint_1"' in got[0].data and 'link name="arm2_base_link"' in got[0].data
        assert ros.call("/cell/home").success
        goals = Goals(ros, "cell")
        # The bare names are not this arm's: refused, nothing moves.
        handle = goals.send(trajectory(JOINTS, [(2.0, [0.2] * 6)]))
        if handle.accepted:
            out = goals.outcome(handle)
            assert out.status == ABORTED and "arm2_joint_1" in out.result.error_string, out.result.error_string
        end = [0.2, 0.1, 0.3, 0.1, 0.2, 0.1]
        handle = goals.send(trajectory(names, [(3.0, end)]))
        out = goals.outcome(handle)
        assert out.status == SUCCEEDED, out.result.error_string
        assert list(goals.feedback[-1].feedback.joint_names) == names
        assert standing(ros, states) == pytest.approx(end, abs=3e-3)
    finally:
        node.end()


def test_a_new_goal_replaces_the_running_one_as_joint_trajectory_controller_does(domain: int, ros: Ros) -> None:
    node = TrolNode(domain, "--port", "sim", "--time-scale", "1", "--namespace", "arm1")
    try:
        assert ros.call("/arm1/home").success
        states = ros.states("arm1")
        goals = Goals(ros, "arm1")
        first = goals.send(trajectory(JOINTS, [(8.0, FAR_TARGET)]))
        assert first.accepted
        ros.spin_until("the arm moving", lambda: moving(states, max(0, len(states) - 25)))
        # A goal the arm cannot have (an unknown joint) is rejected and leaves the first running.
        bad = goals.send(trajectory(["elbow"] + JOINTS[1:], [(2.0, [0.1] * 6)]))
        assert not bad.accepted
        end = [0.1, 0.1, 0.2, 0.1, 0.1, 0.1]
        second = goals.send(trajectory(JOINTS, [(3.0, end)]))
        assert second.accepted
        out = goals.outcome(first)
        assert out.status == CANCELED and "replaced" in out.result.error_string, out.result.error_string
        out = goals.outcome(second)
        assert out.status == SUCCEEDED, out.result.error_string
        assert standing(ros, states) == pytest.approx(end, abs=3e-3)
    finally:
        node.end()


def test_with_one_goal_a_goal_while_one_runs_is_rejected_and_rosout_says_why(domain: int, ros: Ros) -> None:
    from rcl_interfaces.msg import Log

    node = TrolNode(domain, "--port", "sim", "--time-scale", "1", "--namespace", "arm1", "--one-goal")
    try:
        logs: list[Log] = []
        ros.node.create_subscription(Log, "/rosout", logs.append,
                                     QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))
        assert ros.call("/arm1/home").success
        goals = Goals(ros, "arm1")
        first = goals.send(trajectory(JOINTS, [(4.0, [0.3] * 6)]))
        assert first.accepted
        assert not goals.send(trajectory(JOINTS, [(2.0, [0.1] * 6)])).accepted
        said = ros.spin_until("the rejection on /rosout", lambda: [
            m for m in logs if m.name == "trol_a465" and "rejected" in m.msg])
        assert said[0].level == Log.WARN, said
        assert goals.outcome(first).status == SUCCEEDED
    finally:
        node.end()

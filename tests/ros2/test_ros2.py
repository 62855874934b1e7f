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


import os
import random
import subprocess
import threading
import time
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
from cyclonedds.idl.types import float64, int32, int64, sequence, uint8, uint32, uint64  # noqa: E402
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


def node_binary() -> Path:
    """`trol-ros2`: $TROL_ROS2_BIN, else target/debug/trol-ros2."""
    given = os.environ.get("TROL_ROS2_BIN")
    return Path(given) if given else ROOT / "target" / "debug" / "trol-ros2"


class Node:
    """A `trol-ros2` process on the embedded simulator, on its own domain."""

    def __init__(self, domain: int, namespace: str, *extra: str) -> None:
        env = dict(os.environ, ROS_LOCALHOST_ONLY="1", ROS_DOMAIN_ID=str(domain))
        self.proc = subprocess.Popen(
            [str(node_binary()), "--port", "sim", "--time-scale", "10", "--namespace", namespace, *extra],
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


@pytest.fixture
def domain() -> int:
    # A domain of its own, so that runs beside each other do not meet.
    return random.randint(1, 200)


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


def wait_for(what: str, fn, limit: float = 30.0):  # type: ignore[no-untyped-def]
    """Call `fn` until it returns something other than None, within `limit` seconds."""
    until = time.monotonic() + limit
    while time.monotonic() < until:
        got = fn()
        if got is not None:
            return got
        time.sleep(0.05)
    raise AssertionError(f"no {what} within {limit} s")


def call_trigger(dp: DomainParticipant, ns: str, service: str, seq: int, limit: float = 60.0) -> TriggerResponse:
    """A std_srvs/Trigger call as rmw_cyclonedds makes it: the request with its header on
    `rq/<ns>/<service>Request`, the reply with the same header on `rr/<ns>/<service>Reply`."""
    qos = Qos(RELIABLE, Policy.History.KeepLast(10))
    writer = DataWriter(dp, Topic(dp, f"rq/{ns}/{service}Request", TriggerRequest), qos=qos)
    reader = DataReader(dp, Topic(dp, f"rr/{ns}/{service}Reply", TriggerResponse), qos=qos)
    guid = random.getrandbits(63)
    # The request goes once the service's reader is matched (discovery takes a moment).
    wait_for(f"{service}'s server", lambda: True if writer.get_matched_subscriptions() else None)
    wait_for(f"{service}'s reply writer", lambda: True if reader.get_matched_publications() else None)
    writer.write(TriggerRequest(client_guid=guid, sequence_number=seq, structure_needs_at_least_one_member=0))

    def answer() -> TriggerResponse | None:
        for r in reader.take(N=10):
            if isinstance(r, TriggerResponse) and r.client_guid == guid and r.sequence_number == seq:
                return r
        return None

    return wait_for(f"{service}'s reply", answer, limit)


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
    assert list(first.name) == [f"joint_{i}" for i in range(1, 7)]
    assert len(first.position) == 6 and len(first.velocity) == 6 and list(first.effort) == []
    # The simulator's arm stands at READY (every joint 0) before anything is asked; these
    # are its encoders, which dither by a few counts.
    assert list(first.position) == pytest.approx([0.0] * 6, abs=1e-3)
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
        assert got.data == urdf


@pytest.mark.timeout(240)
def test_home_and_halt_are_ros2_services_that_say_what_the_arm_did(arm1: Node, domain: int) -> None:
    dp = DomainParticipant(domain)
    r = call_trigger(dp, "arm1", "home", 1)
    assert r.success, r.message
    assert "homed" in r.message
    r = call_trigger(dp, "arm1", "halt", 2)
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

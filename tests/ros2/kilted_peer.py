"""A Cyclone DDS peer of ROS 2 Kilted's layouts: FollowJointTrajectory's feedback (control_msgs
6.3: `int32 index` after `error`, `int32 multi_dof_index` at the end) and the discovery message
(16-byte ids, as since Iron), in a process of its own: Cyclone DDS keeps one definition of a
type name per process, and test_ros2.py's own peer uses Jazzy's. Reads the feedback on
`rt/<ns>/follow_joint_trajectory/_action/feedback` and `ros_discovery_info` in domain DOMAIN
for SECONDS and prints one JSON line per sample it could decode.

    python kilted_peer.py DOMAIN NS SECONDS
"""

import json
import sys
import time

import discovery_peer
import test_ros2 as base  # noqa: F401  (the loopback configuration, and the shared types)
from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import int32, sequence
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration
from dataclasses import dataclass


@dataclass
class FollowFeedbackKilted(IdlStruct, typename=base.FJT + "Feedback_"):
    header: base.Header
    joint_names: sequence[str]
    desired: base.JointTrajectoryPoint
    actual: base.JointTrajectoryPoint
    error: base.JointTrajectoryPoint
    index: int32
    multi_dof_joint_names: sequence[str]
    multi_dof_desired: base.MultiDOFJointTrajectoryPoint
    multi_dof_actual: base.MultiDOFJointTrajectoryPoint
    multi_dof_error: base.MultiDOFJointTrajectoryPoint
    multi_dof_index: int32


@dataclass
class FeedbackMessageKilted(IdlStruct, typename=base.FJT + "FeedbackMessage_"):
    goal_id: base.UUID
    feedback: FollowFeedbackKilted


def main() -> None:
    domain, ns, seconds = int(sys.argv[1]), sys.argv[2], float(sys.argv[3])
    dp = DomainParticipant(domain)
    reader = DataReader(dp, Topic(dp, f"rt/{ns}/follow_joint_trajectory/_action/feedback", FeedbackMessageKilted),
                        qos=Qos(Policy.Reliability.Reliable(max_blocking_time=duration(seconds=1)),
                                Policy.History.KeepLast(100)))
    discovery = discovery_peer.reader(dp, 16)
    print("ready", flush=True)
    until = time.monotonic() + seconds
    while time.monotonic() < until:
        for m in reader.take(N=100):
            if isinstance(m, FeedbackMessageKilted):
                f = m.feedback
                print(json.dumps({"goal": bytes(m.goal_id.uuid).hex(), "names": list(f.joint_names),
                                  "actual": len(f.actual.positions), "index": f.index,
                                  "multi_dof_index": f.multi_dof_index}), flush=True)
        for x in discovery_peer.decoded(discovery, 16):
            print(json.dumps(x), flush=True)
        time.sleep(0.02)


if __name__ == "__main__":
    main()

"""A Cyclone DDS peer of ROS 2 Humble's layouts, in a process of its own (Cyclone DDS keeps one
definition of a type name per process): the discovery message `ros_discovery_info`
(rmw_dds_common/ParticipantEntitiesInfo, whose Gid is 24 bytes in Humble, 16 since Iron) and
FollowJointTrajectory's feedback (control_msgs 4.x, the same as Jazzy's). Reads both in domain
DOMAIN for SECONDS and prints one JSON line per sample it could decode: each node a
discovery message names, and each feedback of the action under NS.

    python humble_peer.py DOMAIN NS SECONDS
"""

import json
import sys
import time

import discovery_peer
import test_ros2 as base  # noqa: F401  (the loopback configuration, and the shared types)
from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration


def main() -> None:
    domain, ns, seconds = int(sys.argv[1]), sys.argv[2], float(sys.argv[3])
    dp = DomainParticipant(domain)
    discovery = discovery_peer.reader(dp, 24)
    feedback = DataReader(dp, Topic(dp, f"rt/{ns}/follow_joint_trajectory/_action/feedback", base.FeedbackMessage),
                          qos=Qos(Policy.Reliability.Reliable(max_blocking_time=duration(seconds=1)),
                                  Policy.History.KeepLast(100)))
    print("ready", flush=True)
    until = time.monotonic() + seconds
    while time.monotonic() < until:
        for x in discovery_peer.decoded(discovery, 24):
            print(json.dumps(x), flush=True)
        for m in discovery_peer.take(feedback):
            if isinstance(m, base.FeedbackMessage):
                f = m.feedback
                print(json.dumps({"goal": bytes(m.goal_id.uuid).hex(), "names": list(f.joint_names),
                                  "actual": len(f.actual.positions)}), flush=True)
        time.sleep(0.05)


if __name__ == "__main__":
    main()

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
from dataclasses import dataclass

import test_ros2 as base  # noqa: F401  (the loopback configuration, and the shared types)
from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import array, sequence, uint8
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration


@dataclass
class Gid(IdlStruct, typename="rmw_dds_common::msg::dds_::Gid_"):
    data: array[uint8, 24]


@dataclass
class NodeEntitiesInfo(IdlStruct, typename="rmw_dds_common::msg::dds_::NodeEntitiesInfo_"):
    node_namespace: str
    node_name: str
    reader_gid_seq: sequence[Gid]
    writer_gid_seq: sequence[Gid]


@dataclass
class ParticipantEntitiesInfo(IdlStruct, typename="rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_"):
    gid: Gid
    node_entities_info_seq: sequence[NodeEntitiesInfo]


def take(reader: DataReader) -> list:
    """What `reader` holds, one sample at a time: a sample in another layout (ros2-client's
    own discovery message, in Jazzy's) cannot be decoded and is passed over."""
    got = []
    for _ in range(100):
        try:
            samples = reader.take(N=1)
        except Exception:  # noqa: BLE001  (a sample of another layout)
            continue
        if not samples:
            break
        got.extend(samples)
    return got


def main() -> None:
    domain, ns, seconds = int(sys.argv[1]), sys.argv[2], float(sys.argv[3])
    dp = DomainParticipant(domain)
    discovery = DataReader(dp, Topic(dp, "ros_discovery_info", ParticipantEntitiesInfo),
                           qos=Qos(Policy.Reliability.Reliable(max_blocking_time=duration(seconds=1)),
                                   Policy.Durability.TransientLocal, Policy.History.KeepLast(10)))
    feedback = DataReader(dp, Topic(dp, f"rt/{ns}/follow_joint_trajectory/_action/feedback", base.FeedbackMessage),
                          qos=Qos(Policy.Reliability.Reliable(max_blocking_time=duration(seconds=1)),
                                  Policy.History.KeepLast(100)))
    print("ready", flush=True)
    until = time.monotonic() + seconds
    while time.monotonic() < until:
        for m in take(discovery):
            if isinstance(m, ParticipantEntitiesInfo):
                gids = [bytes(g.data) for n in m.node_entities_info_seq for g in n.reader_gid_seq + n.writer_gid_seq]
                print(json.dumps({"participant": bytes(m.gid.data).hex(), "nodes": [
                    {"ns": n.node_namespace, "name": n.node_name, "readers": len(n.reader_gid_seq),
                     "writers": len(n.writer_gid_seq)} for n in m.node_entities_info_seq],
                    "padded": all(g[16:] == bytes(8) for g in gids + [bytes(m.gid.data)])}), flush=True)
        for m in take(feedback):
            if isinstance(m, base.FeedbackMessage):
                f = m.feedback
                print(json.dumps({"goal": bytes(m.goal_id.uuid).hex(), "names": list(f.joint_names),
                                  "actual": len(f.actual.positions)}), flush=True)
        time.sleep(0.05)


if __name__ == "__main__":
    main()

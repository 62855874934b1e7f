"""The discovery message of ROS 2 (`ros_discovery_info`, rmw_dds_common/ParticipantEntitiesInfo)
as a Cyclone DDS peer of one distribution reads it: each node a participant holds, with the
ids (Gid) of its readers and writers, 24 bytes each in Humble and 16 since Iron. Used by the
peers of tests/ros2 that run in processes of their own (humble_peer.py, kilted_peer.py):
Cyclone DDS keeps one definition of a type name per process."""

from dataclasses import dataclass

from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import array, sequence, uint8
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration


def reader(dp: DomainParticipant, gid_bytes: int) -> DataReader:
    """A reader of the discovery message in the layout whose ids are `gid_bytes` long."""

    @dataclass
    class Gid(IdlStruct, typename="rmw_dds_common::msg::dds_::Gid_"):
        data: array[uint8, gid_bytes]  # type: ignore[valid-type]

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

    return DataReader(dp, Topic(dp, "ros_discovery_info", ParticipantEntitiesInfo),
                      qos=Qos(Policy.Reliability.Reliable(max_blocking_time=duration(seconds=1)),
                              Policy.Durability.TransientLocal, Policy.History.KeepLast(10)))


def take(r: DataReader) -> list:
    """What `r` holds, one sample at a time: a sample of another layout cannot be decoded and
    is passed over."""
    got = []
    for _ in range(100):
        try:
            samples = r.take(N=1)
        except Exception:  # noqa: BLE001  (a sample of another layout)
            continue
        if not samples:
            break
        got.extend(samples)
    return got


def decoded(r: DataReader, gid_bytes: int) -> list[dict]:
    """Each discovery message `r` could decode: its participant's nodes, and whether every id
    in it is a 16-byte DDS GUID padded with zeros to `gid_bytes`."""
    out = []
    for m in take(r):
        if not hasattr(m, "node_entities_info_seq"):
            continue
        nodes = m.node_entities_info_seq
        gids = [bytes(g.data) for n in nodes for g in n.reader_gid_seq + n.writer_gid_seq] + [bytes(m.gid.data)]
        out.append({"participant": bytes(m.gid.data).hex(),
                    "nodes": [{"ns": n.node_namespace, "name": n.node_name, "readers": len(n.reader_gid_seq),
                               "writers": len(n.writer_gid_seq)} for n in nodes],
                    "ids": gid_bytes, "padded": all(len(g) == gid_bytes and g[16:] == bytes(gid_bytes - 16)
                                                    for g in gids)})
    return out

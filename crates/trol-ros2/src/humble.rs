//! ROS 2 Humble's layout of the discovery message, for `--distro humble`.
//!
//! Every ROS 2 participant says which nodes it holds on `ros_discovery_info`
//! (rmw_dds_common/ParticipantEntitiesInfo): each node's name and the ids (Gid) of its readers
//! and writers. `ros2 node list` and the graph of `ros2 topic info -v` come from it. A Gid is
//! 24 bytes in Humble (and Galactic) and 16 since Iron; ros2-client writes the layout it was
//! built for (here Jazzy's, 16), which a Humble peer cannot read, so the node was missing
//! from Humble's node list.
//!
//! With `--distro humble` the node also writes the message in Humble's layout, from a writer
//! of its own: ros2-client's message (the nodes, their readers and writers) read back and
//! written again with each id padded to 24 bytes, as Humble's rmw pads a DDS GUID. Humble's
//! middlewares cannot read ros2-client's own (its node count falls inside the longer id) and
//! drop it; a peer of a later distribution reads this one as a participant without nodes,
//! which is why the layout is chosen by `--distro` (or ROS_DISTRO), not written for all.

use ros2_client::entities_info::ParticipantEntitiesInfo;
use serde::{Deserialize, Serialize};

/// One node, in the layout of distribution whose ids are `N` bytes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Node<const N: usize>
where
    [u8; N]: Serialize + for<'a> Deserialize<'a>,
{
    namespace: String,
    name: String,
    readers: Vec<[u8; N]>,
    writers: Vec<[u8; N]>,
}

/// The message, ids of `N` bytes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Entities<const N: usize>
where
    [u8; N]: Serialize + for<'a> Deserialize<'a>,
{
    gid: [u8; N],
    nodes: Vec<Node<N>>,
}

/// Humble's layout of the message (ids of 24 bytes).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HumbleEntities(Entities<24>);

impl ros2_client::Message for HumbleEntities {}

/// A 16-byte id as Humble writes it: the DDS GUID, then 8 zero bytes.
fn pad(id: [u8; 16]) -> [u8; 24] {
    let mut out = [0u8; 24];
    out[..16].copy_from_slice(&id);
    out
}

/// ros2-client's message (the layout of Iron and later) in Humble's.
pub fn humble(info: &ParticipantEntitiesInfo) -> Result<HumbleEntities, String> {
    let bytes = rustdds::cdr_encoding::to_vec::<_, byteorder::LittleEndian>(info)
        .map_err(|e| format!("the discovery message could not be encoded: {e}"))?;
    let (later, _) =
        rustdds::cdr_encoding::from_bytes::<Entities<16>, byteorder::LittleEndian>(&bytes)
            .map_err(|e| {
                format!("the discovery message is not in the layout of Iron and later: {e}")
            })?;
    Ok(HumbleEntities(Entities {
        gid: pad(later.gid),
        nodes: later
            .nodes
            .into_iter()
            .map(|n| Node {
                namespace: n.namespace,
                name: n.name,
                readers: n.readers.into_iter().map(pad).collect(),
                writers: n.writers.into_iter().map(pad).collect(),
            })
            .collect(),
    }))
}

/// The writer of Humble's discovery message.
pub struct Discovery {
    writer: rustdds::no_key::DataWriterCdr<HumbleEntities>,
}

impl Discovery {
    /// A writer on `ros_discovery_info`, with the topic's own QoS (transient local, the last
    /// message kept for a peer that comes later).
    pub fn new(
        participant: &rustdds::DomainParticipant,
        writers: &rustdds::Publisher,
    ) -> Result<Discovery, String> {
        use ros2_client::builtin_topics::ros_discovery;
        let qos = ros_discovery::QOS_PUB.clone();
        let topic = participant
            .create_topic(
                ros_discovery::TOPIC_NAME.to_string(),
                ros_discovery::TYPE_NAME.to_string(),
                &qos,
                rustdds::TopicKind::NoKey,
            )
            .map_err(|e| format!("ros_discovery_info: {e:?}"))?;
        let writer = writers
            .create_datawriter_no_key::<HumbleEntities, rustdds::CDRSerializerAdapter<HumbleEntities>>(
                &topic,
                Some(qos),
            )
            .map_err(|e| format!("ros_discovery_info: {e:?}"))?;
        Ok(Discovery { writer })
    }

    /// Say the participant's nodes as `info` has them, in Humble's layout.
    pub fn publish(&self, info: &ParticipantEntitiesInfo) -> Result<(), String> {
        self.writer
            .write(humble(info)?, None)
            .map_err(|e| format!("ros_discovery_info: {e:?}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ros2_client::entities_info::NodeEntitiesInfo;
    use ros2_client::{Gid, NodeName};

    #[test]
    fn every_id_is_padded_to_humble_s_24_bytes_and_the_names_stay() {
        let mut node = NodeEntitiesInfo::new(NodeName::new("/arm1", "trol_a465").unwrap());
        node.add_reader(Gid::from([1u8; 16]));
        node.add_writer(Gid::from([2u8; 16]));
        node.add_writer(Gid::from([3u8; 16]));
        let info = ParticipantEntitiesInfo::new(Gid::from([9u8; 16]), vec![node]);
        let h = humble(&info).unwrap().0;
        assert_eq!(h.gid[..16], [9u8; 16]);
        assert_eq!(h.gid[16..], [0u8; 8]);
        assert_eq!(h.nodes.len(), 1);
        let n = &h.nodes[0];
        assert_eq!(
            (n.namespace.as_str(), n.name.as_str()),
            ("/arm1", "trol_a465")
        );
        assert_eq!(n.readers, vec![pad([1u8; 16])]);
        assert_eq!(n.writers, vec![pad([2u8; 16]), pad([3u8; 16])]);
        // On the wire: 24 bytes of id, then the node count (no length before a fixed array).
        let bytes = rustdds::cdr_encoding::to_vec::<_, byteorder::LittleEndian>(&HumbleEntities(h))
            .unwrap();
        assert_eq!(bytes[..16], [9u8; 16]);
        assert_eq!(bytes[24..28], 1u32.to_le_bytes());
    }
}

//! Services that answer each client in its own middleware's request/reply mapping.
//!
//! ROS 2's middlewares put a service call on DDS in different ways (shared/reference/ros2.md):
//! rmw_fastrtps_cpp, the default of Humble, Jazzy and Kilted, sends the bare request and
//! names it by the DDS sample's identity (the "enhanced" mapping of OMG's RPC over DDS): the
//! reply carries that identity as its related sample identity, in the sample's inline QoS.
//! rmw_cyclonedds_cpp puts a 16-byte header (the client's id and a sequence number) before
//! the request, and expects the same header before the reply. A server fixed to one mapping
//! answers the other middleware's clients with nothing they can match: `trol ros2` on
//! Cyclone's mapping alone left every rclpy call on Fast DDS unanswered.
//!
//! [`AnyServer`] reads each request's bytes as they came, tells the mapping by the DDS vendor
//! of the participant that wrote it ([`Vendors`]: from discovery, else the vendor id at the
//! head of the writer's GUID prefix, as the RTPS specification recommends and both vendors
//! do), and answers in that mapping: the header echoed before the reply for Cyclone DDS,
//! the bare reply with the request's identity for everyone else (Fast DDS, RTI Connext's
//! default, and rustdds's own clients as ros2-client makes them).

use std::collections::HashMap;
use std::marker::PhantomData;

use ros2_client::{Message, Node, QosProfile, RmwRequestId};

use crate::replies::Service;
use serde::de::{SeqAccess, Visitor};
use serde::ser::SerializeTuple;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// The DDS vendor ids (OMG's registry) that decide a mapping.
pub const CYCLONE_DDS: [u8; 2] = [0x01, 0x10];
/// eProsima Fast DDS.
#[cfg(test)]
pub const FAST_DDS: [u8; 2] = [0x01, 0x0f];

/// How a client put its request on DDS, and so how it is answered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mapping {
    /// rmw_cyclonedds: a 16-byte header before the request and before its reply.
    Cyclone,
    /// RPC over DDS's enhanced mapping (rmw_fastrtps, rmw_connextdds, ros2-client's
    /// default): bare bytes; the reply names the request by its related sample identity.
    Enhanced,
}

impl Mapping {
    /// The mapping of a client whose DDS says `vendor`.
    pub fn of_vendor(vendor: [u8; 2]) -> Mapping {
        if vendor == CYCLONE_DDS {
            Mapping::Cyclone
        } else {
            Mapping::Enhanced
        }
    }
}

/// Who asked, and how the answer must go to be heard.
#[derive(Clone, Debug, PartialEq)]
pub struct Asker {
    /// The request's identity (the reply's related sample identity).
    pub id: RmwRequestId,
    pub mapping: Mapping,
    /// Cyclone's header of the request, echoed before the reply.
    header: [u8; 16],
}

/// Cyclone's request header: the client's id and the request's number, 8 bytes each.
const CYCLONE_HEADER: usize = 16;

/// A request's bytes split into who asked and the request itself (CDR, little-endian, its
/// alignment counted from its own start). Err: bytes too short for the mapping's header.
pub fn split(id: RmwRequestId, vendor: [u8; 2], bytes: &[u8]) -> Result<(Asker, &[u8]), String> {
    let mapping = Mapping::of_vendor(vendor);
    let mut header = [0u8; CYCLONE_HEADER];
    let body = match mapping {
        Mapping::Cyclone => {
            if bytes.len() < CYCLONE_HEADER {
                return Err(format!(
                    "{} bytes, shorter than Cyclone DDS's 16-byte request header",
                    bytes.len()
                ));
            }
            header.copy_from_slice(&bytes[..CYCLONE_HEADER]);
            &bytes[CYCLONE_HEADER..]
        }
        Mapping::Enhanced => bytes,
    };
    Ok((
        Asker {
            id,
            mapping,
            header,
        },
        body,
    ))
}

/// The reply's bytes for `asker`: `reply` (CDR, little-endian) after the header it needs.
pub fn wrap(asker: &Asker, reply: &[u8]) -> Vec<u8> {
    match asker.mapping {
        Mapping::Cyclone => [&asker.header[..], reply].concat(),
        Mapping::Enhanced => reply.to_vec(),
    }
}

/// Bytes that travel as they are: read to the end of the sample, written without a length.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Raw(pub Vec<u8>);

impl Serialize for Raw {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut t = s.serialize_tuple(self.0.len())?;
        for b in &self.0 {
            t.serialize_element(b)?;
        }
        t.end()
    }
}

impl<'de> Deserialize<'de> for Raw {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Raw, D::Error> {
        struct Bytes;
        impl<'de> Visitor<'de> for Bytes {
            type Value = Raw;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a sample's bytes")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Raw, A::Error> {
                let mut v = Vec::new();
                // CDR has no length here: the sample ends where the bytes do (its reader
                // says so with an error, which is the end, not a failure).
                while let Ok(Some(b)) = seq.next_element::<u8>() {
                    v.push(b);
                }
                Ok(Raw(v))
            }
        }
        d.deserialize_tuple(usize::MAX, Bytes)
    }
}

impl Message for Raw {}

/// Each discovered participant's DDS vendor, by its GUID prefix.
#[derive(Default)]
pub struct Vendors {
    known: HashMap<[u8; 12], [u8; 2]>,
}

impl Vendors {
    /// A participant discovered (or updated).
    pub fn note(&mut self, prefix: [u8; 12], vendor: [u8; 2]) {
        self.known.insert(prefix, vendor);
    }

    /// A participant gone.
    pub fn forget(&mut self, prefix: &[u8; 12]) {
        self.known.remove(prefix);
    }

    /// The vendor of the participant whose entity has `guid`: as discovered, else the
    /// vendor id that leads its GUID prefix.
    pub fn of(&self, guid: &[u8; 16]) -> [u8; 2] {
        let mut prefix = [0u8; 12];
        prefix.copy_from_slice(&guid[..12]);
        self.known
            .get(&prefix)
            .copied()
            .unwrap_or([guid[0], guid[1]])
    }
}

/// A request taken, or None when none is waiting; one that could not be read is said on
/// stderr with its writer, and the next is taken (up to a bound per turn of the node's
/// loop, so a flood of garbage cannot hold the loop).
pub fn next<T>(mut take: impl FnMut() -> Result<Option<T>, String>) -> Option<T> {
    for _ in 0..UNREADABLE_PER_TURN {
        match take() {
            Ok(r) => return r,
            Err(e) => crate::warn_ros!("trol-ros2: {e}; not answered"),
        }
    }
    None
}

/// How many unreadable requests one turn takes before it goes on.
const UNREADABLE_PER_TURN: usize = 16;

/// The DDS vendors of the participants discovered, shared by the node's servers (the
/// participant's status events fill it: [`crate::replies::Matches`]).
pub type SharedVendors = std::sync::Arc<std::sync::Mutex<Vendors>>;

/// A service server that answers each client in its own mapping. Its request reader belongs
/// to the node (so the node lists it); its reply writer is the DDS's own, which can name the
/// request a reply answers (ros2-client's publishers cannot).
pub struct AnyServer<Req, Resp> {
    requests: ros2_client::Subscription<Raw>,
    replies: rustdds::no_key::DataWriterCdr<Raw>,
    vendors: SharedVendors,
    name: String,
    _types: PhantomData<(Req, Resp)>,
}

impl<Req: Message, Resp: Message> AnyServer<Req, Resp> {
    /// `participant`: the node's (its context's); `writers`: a DDS publisher in it, for the
    /// reply writers; `dds_type`: the DDS type without its `_Request_`/`_Response_`
    /// (`std_srvs::srv::dds_::Trigger`, `control_msgs::action::dds_::FollowJointTrajectory_SendGoal`).
    pub fn new(
        node: &mut Node,
        participant: &rustdds::DomainParticipant,
        writers: &rustdds::Publisher,
        topics: &Service,
        dds_type: &str,
        qos: &QosProfile,
        vendors: SharedVendors,
    ) -> Result<AnyServer<Req, Resp>, String> {
        let dds_qos = rustdds::QosPolicies::from(qos);
        let create = |e: &dyn std::fmt::Debug| {
            format!("cannot create the service {}: {e:?}", topics.request)
        };
        let request_topic = participant
            .create_topic(
                topics.request.clone(),
                format!("{dds_type}_Request_"),
                &dds_qos,
                rustdds::TopicKind::NoKey,
            )
            .map_err(|e| create(&e))?;
        let reply_topic = participant
            .create_topic(
                topics.reply.clone(),
                format!("{dds_type}_Response_"),
                &dds_qos,
                rustdds::TopicKind::NoKey,
            )
            .map_err(|e| create(&e))?;
        let requests = node
            .create_subscription::<Raw>(&request_topic, Some(qos.clone()))
            .map_err(|e| create(&e))?;
        let replies = writers
            .create_datawriter_no_key::<Raw, rustdds::CDRSerializerAdapter<Raw>>(
                &reply_topic,
                Some(dds_qos.clone()),
            )
            .map_err(|e| create(&e))?;
        Ok(AnyServer {
            requests,
            replies,
            vendors,
            name: topics.request.clone(),
            _types: PhantomData,
        })
    }

    /// The next request, if one came. Err: a request that could not be read, with its
    /// writer (it is not answered: nothing in it can be trusted).
    pub fn receive_request(&self) -> Result<Option<(Asker, Req)>, String> {
        let (raw, info) = match self.requests.take() {
            Ok(Some(r)) => r,
            Ok(None) => return Ok(None),
            Err(e) => return Err(format!("a request on {} was unreadable: {e:?}", self.name)),
        };
        let id = request_id(&info);
        let writer_guid = info.publisher_gid().to_bytes16();
        let vendor = self
            .vendors
            .lock()
            .map(|v| v.of(&writer_guid))
            .unwrap_or([writer_guid[0], writer_guid[1]]);
        let writer = || {
            format!(
                "writer {} (DDS vendor {:02x}.{:02x})",
                writer_guid
                    .iter()
                    .map(|b| format!("{b:02x}"))
                    .collect::<String>(),
                vendor[0],
                vendor[1]
            )
        };
        let (asker, body) = split(id, vendor, &raw.0)
            .map_err(|e| format!("a request on {} from {}: {e}", self.name, writer()))?;
        let (req, _) = rustdds::cdr_encoding::from_bytes::<Req, byteorder::LittleEndian>(body)
            .map_err(|e| {
                format!(
                    "a request on {} from {} could not be read in {:?} mapping: {e}",
                    self.name,
                    writer(),
                    asker.mapping
                )
            })?;
        Ok(Some((asker, req)))
    }

    /// Answer `asker` in its mapping, naming its request.
    pub fn send_response(&self, asker: &Asker, reply: Resp) -> Result<(), String> {
        let bytes = rustdds::cdr_encoding::to_vec::<Resp, byteorder::LittleEndian>(&reply)
            .map_err(|e| format!("the reply on {} could not be encoded: {e}", self.name))?;
        let options = rustdds::WriteOptionsBuilder::new()
            .source_timestamp(rustdds::Timestamp::now())
            .related_sample_identity(rustdds::SampleIdentity::from(asker.id))
            .build();
        self.replies
            .write_with_options(Raw(wrap(asker, &bytes)), options)
            .map(|_| ())
            .map_err(|e| format!("the reply on {}: {e:?}", self.name))
    }
}

/// A request's identity, as the enhanced mapping names it: the related sample identity the
/// client wrote (Fast DDS: its reply reader's GUID), else the sample's own; a sequence
/// number left unknown there is the sample's (Fast DDS leaves it so).
fn request_id(info: &ros2_client::MessageInfo) -> RmwRequestId {
    let mut id = info.related_request_id().unwrap_or(RmwRequestId {
        writer_gid: info.publisher_gid(),
        sequence_number: info.sequence_number(),
    });
    if id.sequence_number == i64::from(rustdds::SequenceNumber::UNKNOWN) {
        id.sequence_number = info.sequence_number();
    }
    id
}

#[cfg(test)]
mod tests {
    use super::*;

    fn id(seq: i64) -> RmwRequestId {
        RmwRequestId {
            sequence_number: seq,
            ..RmwRequestId::default()
        }
    }

    #[test]
    fn a_cyclone_request_keeps_its_header_for_the_reply_and_fast_dds_s_goes_bare() {
        // std_srvs/Trigger's request: one byte (structure_needs_at_least_one_member).
        let mut cyclone = vec![1, 2, 3, 4, 5, 6, 7, 8, 0, 0, 0, 0, 9, 0, 0, 0];
        cyclone.push(0);
        let (asker, body) = split(id(9), CYCLONE_DDS, &cyclone).unwrap();
        assert_eq!(asker.mapping, Mapping::Cyclone);
        assert_eq!(body, [0]);
        let reply = wrap(&asker, &[1, 0, 0, 0]);
        assert_eq!(
            &reply[..16],
            &cyclone[..16],
            "the header goes back as it came"
        );
        assert_eq!(&reply[16..], [1, 0, 0, 0]);

        let (asker, body) = split(id(3), FAST_DDS, &[0]).unwrap();
        assert_eq!(asker.mapping, Mapping::Enhanced);
        assert_eq!(asker.id, id(3));
        assert_eq!(body, [0]);
        assert_eq!(wrap(&asker, &[1, 0, 0, 0]), [1, 0, 0, 0]);
    }

    #[test]
    fn a_cyclone_request_too_short_for_its_header_is_an_error_that_says_so() {
        let e = split(id(1), CYCLONE_DDS, &[0; 5]).unwrap_err();
        assert!(e.contains("16-byte request header"), "{e}");
    }

    #[test]
    fn raw_bytes_go_through_cdr_unchanged_with_no_length() {
        let r = Raw(vec![7, 0, 255, 3, 1]);
        let bytes = rustdds::cdr_encoding::to_vec::<Raw, byteorder::LittleEndian>(&r).unwrap();
        assert_eq!(bytes, r.0);
        let (back, n) =
            rustdds::cdr_encoding::from_bytes::<Raw, byteorder::LittleEndian>(&bytes).unwrap();
        assert_eq!((back, n), (r, 5));
    }

    #[test]
    fn a_vendor_is_taken_from_discovery_before_the_guid_s_head() {
        let mut v = Vendors::default();
        let mut guid = [0u8; 16];
        guid[..2].copy_from_slice(&CYCLONE_DDS);
        assert_eq!(
            v.of(&guid),
            CYCLONE_DDS,
            "the GUID's head when not discovered"
        );
        let mut prefix = [0u8; 12];
        prefix.copy_from_slice(&guid[..12]);
        v.note(prefix, FAST_DDS);
        assert_eq!(v.of(&guid), FAST_DDS);
        v.forget(&prefix);
        assert_eq!(v.of(&guid), CYCLONE_DDS);
    }
}

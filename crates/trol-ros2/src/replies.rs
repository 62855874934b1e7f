//! Service replies held until the asker can hear them.
//!
//! A ROS 2 service is two DDS topics: the client writes `rq/<name>Request`, the server
//! answers on `rr/<name>Reply`. Each side discovers the other's endpoints on its own, so a
//! request can reach this node before the node has discovered the client's reply reader.
//! A reply written then goes to no reader, and a volatile reader that matches later never
//! gets it: the client waits for an answer that was lost (seen in tests/ros2: one
//! `send_goal` in nine loaded runs went unanswered for 60 s). ROS 2's own middlewares wait
//! on the server's side for the same reason (ros2/rmw_fastrtps#390, ros2/rmw_cyclonedds#187).
//!
//! Here a reply waits in a [`Replies`] queue until every participant that writes requests
//! to the service has a reader of its replies matched by this node's writer, as the
//! participant's status events ([`Matches`]) tell; or until [`READER_WAIT`] has passed (a
//! client that left, or one that never reads replies), when it goes anyway and the node
//! says so. Nothing else waits: what a request asks (a halt, a cancel) is done at once, and
//! the node's loop goes on.

use std::collections::{HashSet, VecDeque};
use std::time::{Duration, Instant};

use ros2_client::{Name, NodeName};
use rustdds::{DomainParticipant, DomainParticipantStatusEvent, GUID, StatusEvented};

use crate::mapping::{Asker, SharedVendors};

/// How long a reply waits for its asker's reader before it goes anyway.
pub const READER_WAIT: Duration = Duration::from_secs(5);

/// The DDS topics of one service.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Service {
    /// `rq/<name>Request`.
    pub request: String,
    /// `rr/<name>Reply`.
    pub reply: String,
}

impl Service {
    /// The service `<ns>/<path>` (`path`: `home`, or `follow_joint_trajectory/_action/send_goal`
    /// for an action's part), named as ros2-client names it on DDS.
    pub fn new(ns: &str, path: &str, node: &NodeName) -> Result<Service, String> {
        let (dir, base) = match path.rsplit_once('/') {
            Some((dir, base)) => (format!("{}/{dir}", ns.trim_end_matches('/')), base),
            None => (ns.to_string(), path),
        };
        let name = Name::new(&dir, base).map_err(|e| format!("{path}: {e:?}"))?;
        Ok(Service {
            request: name.to_dds_name("rq", node, "Request"),
            reply: name.to_dds_name("rr", node, "Reply"),
        })
    }
}

/// Whether every asker (the participant of a writer on a service's requests) has a reader
/// of the service's replies in the same participant that this node's writer has matched.
/// `readers`: the replies' readers, each with its participant. No asker: nobody to wait for.
pub fn askers_hear<P: PartialEq, R: Eq + std::hash::Hash>(
    askers: &[P],
    readers: &[(P, R)],
    matched: &HashSet<R>,
) -> bool {
    askers.iter().all(|asker| {
        readers
            .iter()
            .any(|(at, reader)| at == asker && matched.contains(reader))
    })
}

/// The remote readers this participant's writers have matched, from its status events (read
/// by nothing else: the node runs no ros2-client spinner).
/// The same events say each participant's DDS vendor, which decides how its service calls
/// are answered ([`crate::mapping`]).
pub struct Matches {
    participant: DomainParticipant,
    matched: HashSet<GUID>,
    vendors: SharedVendors,
}

/// The GUID prefix of an entity's GUID, as bytes.
fn prefix_bytes(guid: GUID) -> [u8; 12] {
    let mut p = [0u8; 12];
    p.copy_from_slice(&guid.to_bytes()[..12]);
    p
}

impl Matches {
    pub fn new(participant: DomainParticipant) -> Matches {
        Matches {
            participant,
            matched: HashSet::new(),
            vendors: SharedVendors::default(),
        }
    }

    /// The participants' vendors, for the node's servers.
    pub fn vendors(&self) -> SharedVendors {
        self.vendors.clone()
    }

    /// Take the status events that came since the last call.
    pub fn refresh(&mut self) {
        let listener = self.participant.status_listener();
        while let Some(event) = listener.try_recv_status() {
            match event {
                DomainParticipantStatusEvent::RemoteReaderMatched { remote_reader, .. } => {
                    self.matched.insert(remote_reader);
                }
                DomainParticipantStatusEvent::ReaderLost { guid, .. } => {
                    self.matched.remove(&guid);
                }
                DomainParticipantStatusEvent::ParticipantDiscovered { dpd } => {
                    if let Ok(mut v) = self.vendors.lock() {
                        v.note(prefix_bytes(dpd.guid), dpd.vendor_id.vendor_id);
                    }
                }
                DomainParticipantStatusEvent::ParticipantLost { id, .. } => {
                    // The prefix's type is rustdds's own; a GUID carries it out.
                    let mut guid = GUID::from_bytes([0; 16]);
                    guid.prefix = id;
                    if let Ok(mut v) = self.vendors.lock() {
                        v.forget(&prefix_bytes(guid));
                    }
                }
                _ => {}
            }
        }
    }

    /// Whether everyone who asks `service` can hear its replies now ([`askers_hear`]).
    pub fn hear(&self, service: &Service) -> bool {
        let askers: Vec<_> = self
            .participant
            .discovered_writers()
            .into_iter()
            .filter(|w| w.publication_topic_data.topic_name == service.request)
            .map(|w| w.writer_proxy.remote_writer_guid.prefix)
            .collect();
        let readers: Vec<_> = self
            .participant
            .discovered_readers()
            .into_iter()
            .filter(|r| r.subscription_topic_data.topic_name == service.reply)
            .map(|r| {
                let guid = r.reader_proxy.remote_reader_guid;
                (guid.prefix, guid)
            })
            .collect();
        askers_hear(&askers, &readers, &self.matched)
    }
}

/// One service's replies not yet sent, in the order they were made.
pub struct Replies<T> {
    service: Service,
    held: VecDeque<(Asker, T, Instant)>,
}

impl<T> Replies<T> {
    pub fn new(service: Service) -> Replies<T> {
        Replies {
            service,
            held: VecDeque::new(),
        }
    }

    /// A reply, made at `now`, to go as soon as its asker can hear it.
    pub fn push(&mut self, id: Asker, answer: T, now: Instant) {
        self.held.push_back((id, answer, now));
    }

    /// Replies waiting.
    #[cfg(test)]
    pub fn len(&self) -> usize {
        self.held.len()
    }

    /// Send what can go: everything once `hear()` says the askers can hear, else the replies
    /// that have waited [`READER_WAIT`] (said on stderr). `hear` is asked only with replies
    /// waiting.
    pub fn flush(
        &mut self,
        now: Instant,
        hear: impl FnOnce(&Service) -> bool,
        mut send: impl FnMut(&Asker, T),
    ) {
        if self.held.is_empty() {
            return;
        }
        let all = hear(&self.service);
        while let Some((_, _, made)) = self.held.front() {
            if !all && now.saturating_duration_since(*made) < READER_WAIT {
                break;
            }
            if !all {
                crate::warn_ros!(
                    "trol-ros2: a reply on {} waited {} s for its client's reader; sent anyway \
                     (the client may not hear it)",
                    self.service.reply,
                    READER_WAIT.as_secs()
                );
            }
            if let Some((id, answer, _)) = self.held.pop_front() {
                send(&id, answer);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn node(ns: &str) -> NodeName {
        NodeName::new(ns, "trol_a465").unwrap()
    }

    #[test]
    fn services_are_named_as_ros_2_names_them_on_dds() {
        let s = Service::new("/arm1", "home", &node("/arm1")).unwrap();
        assert_eq!(s.request, "rq/arm1/homeRequest");
        assert_eq!(s.reply, "rr/arm1/homeReply");
        let s = Service::new(
            "/cell/arm2",
            "follow_joint_trajectory/_action/send_goal",
            &node("/cell/arm2"),
        )
        .unwrap();
        assert_eq!(
            s.request,
            "rq/cell/arm2/follow_joint_trajectory/_action/send_goalRequest"
        );
        assert_eq!(
            s.reply,
            "rr/cell/arm2/follow_joint_trajectory/_action/send_goalReply"
        );
        let s = Service::new("/", "halt", &node("/")).unwrap();
        assert_eq!(
            (s.request.as_str(), s.reply.as_str()),
            ("rq/haltRequest", "rr/haltReply")
        );
    }

    #[test]
    fn an_asker_hears_only_with_a_reader_of_its_own_matched() {
        let matched: HashSet<u32> = [10, 20].into();
        // No asker: nobody to wait for.
        assert!(askers_hear::<u8, u32>(&[], &[], &matched));
        // Asker 1's reader 10 is matched.
        assert!(askers_hear(&[1u8], &[(1, 10)], &matched));
        // Its reader discovered but not yet matched: not yet.
        assert!(!askers_hear(&[1u8], &[(1, 11)], &matched));
        // Its reader not even discovered: not yet.
        assert!(!askers_hear(&[1u8], &[], &matched));
        // Another participant's matched reader does not stand in for it.
        assert!(!askers_hear(&[1u8], &[(2, 20)], &matched));
        // Two askers: both must hear.
        assert!(!askers_hear(&[1u8, 2], &[(1, 10)], &matched));
        assert!(askers_hear(&[1u8, 2], &[(1, 10), (2, 20)], &matched));
    }

    fn id(seq: i64) -> Asker {
        crate::mapping::split(
            ros2_client::RmwRequestId {
                sequence_number: seq,
                ..Default::default()
            },
            crate::mapping::FAST_DDS,
            &[],
        )
        .unwrap()
        .0
    }

    #[test]
    fn a_reply_waits_for_its_asker_and_goes_in_order_once_heard() {
        let t0 = Instant::now();
        let mut r = Replies::new(Service::new("/arm1", "halt", &node("/arm1")).unwrap());
        r.push(id(1), "one", t0);
        r.push(id(2), "two", t0 + Duration::from_millis(10));
        let mut sent = Vec::new();
        r.flush(t0 + Duration::from_secs(1), |_| false, |_, a| sent.push(a));
        assert!(sent.is_empty());
        assert_eq!(r.len(), 2);
        r.flush(t0 + Duration::from_secs(2), |_| true, |_, a| sent.push(a));
        assert_eq!(sent, ["one", "two"]);
        assert_eq!(r.len(), 0);
    }

    #[test]
    fn a_reply_nobody_can_hear_goes_anyway_after_the_wait_and_only_then() {
        let t0 = Instant::now();
        let mut r = Replies::new(Service::new("/arm1", "halt", &node("/arm1")).unwrap());
        r.push(id(1), "old", t0);
        r.push(id(2), "new", t0 + Duration::from_secs(2));
        let mut sent = Vec::new();
        r.flush(
            t0 + READER_WAIT - Duration::from_millis(1),
            |_| false,
            |_, a| sent.push(a),
        );
        assert!(sent.is_empty());
        r.flush(t0 + READER_WAIT, |_| false, |_, a| sent.push(a));
        assert_eq!(sent, ["old"], "the newer reply still has time");
        r.flush(
            t0 + READER_WAIT + Duration::from_secs(2),
            |_| false,
            |_, a| sent.push(a),
        );
        assert_eq!(sent, ["old", "new"]);
    }

    #[test]
    fn nothing_waiting_asks_nobody() {
        let mut r: Replies<&str> =
            Replies::new(Service::new("/arm1", "halt", &node("/arm1")).unwrap());
        r.flush(
            Instant::now(),
            |_| panic!("asked with nothing waiting"),
            |_, _| {},
        );
    }
}

//! The pendant's way to the controller: a request and the one made from its reply run in
//! one step (the pendant's turn: where the tool is, then the move there).

use std::sync::{Arc, Mutex};
use std::time::Duration;

use trol_controller::{Controller, Embedded, Mode, Pcp, Pendant};
use trol_proto::application::record::{self, Value};
use trol_proto::application::table;
use trol_proto::application::{Reply, Tag};
use trol_proto::link::LinkConfig;
use trol_sim::{SimBackend, SimSettings};

/// A simulated controller served on an in-memory line (its host end kept, as a cable left
/// plugged in), with a pendant.
fn controller() -> (Pendant, Embedded, trol_port::memory::MemoryLine) {
    let (host, line) = trol_port::memory::pair(None);
    let mut settings = SimSettings::default();
    settings.arm.homed = true;
    let mut c = Controller::new(
        line,
        LinkConfig::default(),
        Pcp::new(SimBackend::new(settings)),
        Mode::Server,
    );
    let pendant = c.pendant();
    (pendant, Embedded::spawn(c), host)
}

fn get_position() -> Vec<u8> {
    record::encode(
        &table::GET_POSITION,
        &[
            Value::Int(Tag::Cart as u8),
            Value::Int(table::POS_COMMANDED),
        ],
    )
    .unwrap()
}

#[test]
fn a_follow_up_runs_with_the_first_reply_and_answers_for_both() {
    let (pendant, _running, _host) = controller();
    let seen: Arc<Mutex<Option<Vec<u8>>>> = Arc::default();
    let sink = seen.clone();
    let speed = record::encode(&table::SPEED, &[Value::Int(40)]).unwrap();
    let (reply, followed) = pendant
        .call_then(
            get_position(),
            Some(Box::new(move |first: &[u8]| {
                *sink.lock().unwrap() = Some(first.to_vec());
                Some(speed)
            })),
            Duration::from_secs(30),
        )
        .unwrap();
    assert!(followed);
    // The follow-up saw where the tool is; the answer is the second request's.
    let first = seen.lock().unwrap().clone().expect("the follow-up ran");
    assert!(matches!(
        Reply::decode(&table::GET_POSITION, &first).unwrap(),
        Reply::Position(_)
    ));
    assert_eq!(Reply::decode(&table::SPEED, &reply).unwrap().value().0, 0);
}

#[test]
fn a_follow_up_that_makes_nothing_leaves_the_first_reply() {
    let (pendant, _running, _host) = controller();
    let (reply, followed) = pendant
        .call_then(
            get_position(),
            Some(Box::new(|_| None)),
            Duration::from_secs(30),
        )
        .unwrap();
    assert!(!followed);
    assert!(matches!(
        Reply::decode(&table::GET_POSITION, &reply).unwrap(),
        Reply::Position(_)
    ));
    // And a plain call still works.
    let reply = pendant
        .call(get_position(), Duration::from_secs(30))
        .unwrap();
    assert!(matches!(
        Reply::decode(&table::GET_POSITION, &reply).unwrap(),
        Reply::Position(_)
    ));
}

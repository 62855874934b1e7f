//! The journal of the last call (`trol gateway --journal FILE`): a journal that cannot be
//! written stops the controller before the request runs, so that no record is left that
//! would mislead after the next restart, and the arm does not move.

use std::time::Duration;

use trol_comm::Transactor;
use trol_controller::{Controller, Handled, Mode, Pcp};
use trol_proto::application::record::{self, Value};
use trol_proto::application::table;
use trol_proto::application::{Location, Reply, Tag};
use trol_proto::link::{LinkConfig, Timeouts};
use trol_sim::{SimBackend, SimSettings};

fn joints(c: &mut Controller<trol_port::memory::MemoryLine, SimBackend>) -> Vec<f64> {
    let request = record::encode(
        &table::GET_POSITION,
        &[
            Value::Int(Tag::Joint as u8),
            Value::Int(table::POS_COMMANDED),
        ],
    )
    .unwrap();
    let Handled::Reply(bytes) = c.pcp_mut().handle(&request) else {
        panic!("GetPosition waits")
    };
    match Reply::decode(&table::GET_POSITION, &bytes).unwrap() {
        Reply::Position(loc) => loc.values().to_vec(),
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_journal_that_cannot_be_written_stops_serving_before_the_request_runs() {
    let full = std::path::Path::new("/dev/full");
    if !full.exists() {
        eprintln!("skipped: no /dev/full here (a file every write to fails)");
        return;
    }
    let cfg = LinkConfig {
        timeouts: Timeouts::uniform(Duration::from_millis(300)),
        ..LinkConfig::default()
    };
    let (host, line) = trol_port::memory::pair(None);
    let mut settings = SimSettings::default();
    settings.arm.homed = true;
    let mut c = Controller::new(line, cfg, Pcp::new(SimBackend::new(settings)), Mode::Server);
    // /dev/full reads as zeros (no record: a fresh start) and refuses every write.
    assert_eq!(c.set_journal(full).unwrap(), None);
    let before = joints(&mut c);
    let host = std::thread::spawn(move || {
        let mut t = Transactor::new(host, cfg);
        let request = record::encode(
            &table::MI,
            &[Value::Loc(Location::Joint(vec![0.1, 0.0, 0.0]))],
        )
        .unwrap();
        t.trans_sr(&request)
    });
    let e = loop {
        if let Err(e) = c.step(Duration::from_millis(50)) {
            break e;
        }
    };
    assert!(
        e.to_string()
            .contains("the journal /dev/full cannot be written"),
        "{e}"
    );
    let _ = host.join().unwrap();
    assert_eq!(joints(&mut c), before, "the MI ran with no journal of it");
}

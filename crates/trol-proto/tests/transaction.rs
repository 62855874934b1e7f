//! Layer 3 (TransSR / TransRS) between two ends, with injected time.

mod common;

use std::time::Duration;

use common::{Script, Wire};
use trol_proto::Instant;
use trol_proto::link::{LinkConfig, ReceiveError, SendError};
use trol_proto::transaction::{
    Decision, Failure, Initiator, InitiatorEvent, Responder, ResponderEvent, TransCode, pci_number,
};

fn pair() -> (Wire, Initiator, Responder) {
    let mut r = Responder::new(LinkConfig::default());
    r.listen(Instant::ZERO);
    (Wire::new(), Initiator::new(LinkConfig::default()), r)
}

/// Run one transaction; the responder answers every request with `reply(request)`.
/// `decide` answers the initiator's failures. Returns the initiator's final event and the
/// number of times the responder executed a request.
fn transact(
    w: &mut Wire,
    i: &mut Initiator,
    r: &mut Responder,
    request: &[u8],
    reply: impl Fn(&[u8]) -> Vec<u8>,
    mut decide: impl FnMut(Failure) -> Decision,
) -> (InitiatorEvent, u32) {
    i.start(request, w.now).unwrap();
    let mut executed = 0;
    loop {
        let mut ev = None;
        let mut rev = None;
        w.run(i, r, Duration::from_secs(3600), |i, r| {
            ev = i.poll_event();
            rev = r.poll_event();
            ev.is_some() || rev == Some(ResponderEvent::Request)
        });
        if rev == Some(ResponderEvent::Request) {
            executed += 1;
            let answer = reply(r.request());
            r.respond(&answer, w.now);
        }
        match ev {
            Some(InitiatorEvent::NeedDecision(f)) => i.decide(decide(f), w.now),
            Some(e) => return (e, executed),
            None if rev.is_some() => {}
            None => panic!("stalled"),
        }
    }
}

/// Run until the initiator has something to say; the responder's events are ignored (it
/// plays a controller that never answers unless the test makes it).
fn next_event<B: common::End>(
    w: &mut Wire,
    i: &mut Initiator,
    peer: &mut B,
) -> Option<InitiatorEvent> {
    let mut ev = None;
    w.run(i, peer, Duration::from_secs(100), |i, _| {
        ev = i.poll_event();
        ev.is_some()
    });
    ev
}

#[test]
fn a_transaction_returns_the_reply_to_its_request() {
    let (mut w, mut i, mut r) = pair();
    let (ev, n) = transact(
        &mut w,
        &mut i,
        &mut r,
        &[7, 1, 2],
        |q| q.iter().rev().copied().collect(),
        |_| Decision::GiveUp,
    );
    assert_eq!(ev, InitiatorEvent::Reply);
    assert_eq!(n, 1);
    assert_eq!(i.take_reply(), Some(vec![2, 1, 7]));
    // And a second one, numbered on.
    let (ev, _) = transact(
        &mut w,
        &mut i,
        &mut r,
        &[8],
        |_| vec![0, 0],
        |_| Decision::GiveUp,
    );
    assert_eq!(ev, InitiatorEvent::Reply);
    assert_eq!(pci_number(r.request_pci()), 2);
}

#[test]
fn a_silent_controller_gives_trans_err_send() {
    let mut i = Initiator::new(LinkConfig::default());
    let mut peer = Script::default();
    let mut w = Wire::new();
    i.start(&[1], w.now).unwrap();
    let mut failures = Vec::new();
    let ev = next_event(&mut w, &mut i, &mut peer);
    if let Some(InitiatorEvent::NeedDecision(f)) = ev {
        failures.push(f);
        i.decide(Decision::GiveUp, w.now);
    }
    assert_eq!(failures, vec![Failure::Send(SendError::TimeoutEnq)]);
    assert_eq!(
        i.poll_event(),
        Some(InitiatorEvent::Failed(TransCode::ErrSend))
    );
    assert_eq!(i.last_comm_error().map(|e| e.code()), Some(0x03));
}

#[test]
fn no_reply_in_time_gives_trans_timeout_after_the_reply_timeout() {
    let (mut w, mut i, mut r) = pair();
    i.set_reply_timeout(Duration::from_secs(15));
    i.start(&[42], w.now).unwrap();
    // The controller receives the request but never answers.
    let ev = next_event(&mut w, &mut i, &mut r);
    let Some(InitiatorEvent::NeedDecision(Failure::Timeout { waited })) = ev else {
        panic!("{ev:?}")
    };
    assert_eq!(waited, Duration::from_secs(15));
    i.decide(Decision::GiveUp, w.now);
    assert_eq!(
        i.poll_event(),
        Some(InitiatorEvent::Failed(TransCode::Timeout))
    );
}

#[test]
fn wait_more_after_a_timeout_still_gets_a_late_reply() {
    let (mut w, mut i, mut r) = pair();
    i.start(&[42], w.now).unwrap();
    let ev = next_event(&mut w, &mut i, &mut r);
    assert!(matches!(
        ev,
        Some(InitiatorEvent::NeedDecision(Failure::Timeout { .. }))
    ));
    i.decide(Decision::WaitMore(Duration::from_secs(90)), w.now);
    w.advance(Duration::from_secs(30));
    r.respond(&[0, 0], w.now);
    let ev = next_event(&mut w, &mut i, &mut r);
    assert_eq!(ev, Some(InitiatorEvent::Reply));
    assert_eq!(i.take_reply(), Some(vec![0, 0]));
}

#[test]
fn a_reply_that_breaks_off_gives_trans_err_receive() {
    let mut i = Initiator::new(LinkConfig::default());
    let mut peer = Script::default();
    let mut w = Wire::new();
    i.start(&[1], w.now).unwrap();
    // Play the controller by hand: take the request, then start a reply and stop.
    use trol_proto::link::control::{ACK, ENQ};
    let mut ev = None;
    peer.to_send = vec![ACK];
    w.run(&mut i, &mut peer, Duration::from_secs(1), |_, p| {
        p.received.len() >= 11
    });
    peer.to_send = vec![ACK];
    w.run(&mut i, &mut peer, Duration::from_secs(1), |_, p| {
        p.received.len() >= 12
    });
    peer.to_send = vec![ENQ];
    w.run(&mut i, &mut peer, Duration::from_secs(60), |i, _| {
        ev = i.poll_event();
        ev.is_some()
    });
    assert_eq!(
        ev,
        Some(InitiatorEvent::NeedDecision(Failure::Receive(
            ReceiveError::TimeoutSoh
        )))
    );
    i.decide(Decision::GiveUp, w.now);
    assert_eq!(
        i.poll_event(),
        Some(InitiatorEvent::Failed(TransCode::ErrReceive))
    );
}

#[test]
fn a_stale_reply_is_never_taken_for_the_answer_to_a_newer_request() {
    use trol_proto::link::{Link, Outcome};
    // The controller's side is played by a bare link, so that it can send a late reply to
    // an earlier transaction right before the right one.
    let mut i = Initiator::new(LinkConfig::default());
    let mut c = Link::new(LinkConfig::default());
    let mut w = Wire::new();
    c.receive(w.now).unwrap();
    i.start(b"second", w.now).unwrap();
    let mut got = None;
    w.run(&mut i, &mut c, Duration::from_secs(10), |_, c| {
        got = got.or(c.poll_outcome());
        got.is_some()
    });
    assert_eq!(got, Some(Outcome::Received));
    let (req_pci, req) = c.take_received().unwrap();
    assert_eq!(req, b"second");
    // The number before this one: requests count 1, ..., 255, 1, ... (never 0).
    let before = match pci_number(req_pci) {
        1 => 255,
        n => n - 1,
    };
    let stale = trol_proto::transaction::pci(before);
    c.send(b"late answer to the first", stale, w.now).unwrap();
    let mut sent = 0;
    let mut ev = None;
    w.run_t(&mut i, &mut c, Duration::from_secs(10), |i, c, now| {
        if c.poll_outcome() == Some(Outcome::Sent) {
            sent += 1;
            if sent == 1 {
                c.send(b"answer to the second", req_pci, now).unwrap();
            }
        }
        ev = i.poll_event();
        ev.is_some()
    });
    assert_eq!(ev, Some(InitiatorEvent::Reply));
    assert_eq!(
        i.take_reply().as_deref(),
        Some(&b"answer to the second"[..])
    );
    assert_eq!(i.stale_replies(), 1);
}

#[test]
fn a_send_retried_after_err_on_send_reaches_the_controller_once() {
    // The first ENQ is lost (the controller is deaf for a moment); the handler asks for a
    // retry and the request is executed exactly once.
    let (mut w, mut i, mut r) = pair();
    r.stop();
    i.start(b"move", w.now).unwrap();
    let ev = next_event(&mut w, &mut i, &mut r);
    assert_eq!(
        ev,
        Some(InitiatorEvent::NeedDecision(Failure::Send(
            SendError::TimeoutEnq
        )))
    );
    r.listen(w.now);
    i.decide(Decision::Retry, w.now);
    let mut executed = 0;
    let mut ev = None;
    w.run_t(&mut i, &mut r, Duration::from_secs(30), |i, r, now| {
        if r.poll_event() == Some(ResponderEvent::Request) {
            executed += 1;
            r.respond(&[0, 0], now);
        }
        ev = i.poll_event();
        ev.is_some()
    });
    assert_eq!(ev, Some(InitiatorEvent::Reply));
    assert_eq!(executed, 1);
}

/// Exactly once: the reply to an executed request is lost; the request goes out again with
/// its number and the REPEAT bit, and the controller answers from memory without executing
/// it again. A new request with a REPEAT bit but another number executes.
#[test]
fn a_repeated_request_is_answered_from_memory_and_not_executed_again() {
    let (mut w, mut i, mut r) = pair();
    i.set_reply_timeout(Duration::from_millis(500));
    let mut executed = 0;
    // The controller as a server: executes requests (answering "done" the first time), and
    // gives up when its reply cannot be sent (the default ErrOnSend).
    let serve = |r: &mut Responder, now: Instant, executed: &mut u32| match r.poll_event() {
        Some(ResponderEvent::Request) => {
            *executed += 1;
            let answer: &[u8] = if *executed == 1 {
                b"done"
            } else {
                b"done again"
            };
            r.respond(answer, now);
        }
        Some(ResponderEvent::NeedDecision(_)) => r.decide(Decision::GiveUp, now),
        _ => {}
    };
    // First transaction: executed, its reply lost on the way (the PC hears nothing).
    i.start(b"move", w.now).unwrap();
    let mut ev = None;
    w.run(&mut i, &mut r, Duration::from_secs(60), |_, r| {
        serve(r, Instant::ZERO, &mut executed);
        executed == 1
    });
    w.deaf_b_to_a = true;
    w.run(&mut i, &mut r, Duration::from_secs(60), |i, r| {
        serve(r, Instant::ZERO, &mut executed);
        ev = i.poll_event();
        ev.is_some()
    });
    assert_eq!(executed, 1);
    assert!(matches!(
        ev,
        Some(InitiatorEvent::NeedDecision(Failure::Timeout { .. }))
    ));
    i.decide(Decision::GiveUp, w.now);
    assert_eq!(
        i.poll_event(),
        Some(InitiatorEvent::Failed(TransCode::Timeout))
    );
    // The line heals; the PC sends the request again, as a repeat of the same number.
    w.deaf_b_to_a = false;
    w.run(&mut i, &mut r, Duration::from_secs(10), |_, r| {
        serve(r, Instant::ZERO, &mut executed);
        false
    });
    let number = i.number();
    assert!(i.repeat(w.now));
    assert_eq!(i.current_pci() & 0x00FF, u16::from(number));
    assert_ne!(i.current_pci() & 0x0100, 0, "the REPEAT bit");
    w.run(&mut i, &mut r, Duration::from_secs(60), |i, r| {
        serve(r, Instant::ZERO, &mut executed);
        ev = i.poll_event();
        ev.is_some()
    });
    assert_eq!(ev, Some(InitiatorEvent::Reply));
    assert_eq!(
        i.take_reply().unwrap(),
        b"done",
        "the first reply, from memory"
    );
    assert_eq!(executed, 1, "executed once");
    assert_eq!(r.repeats_answered(), 1);
    // The next request is a new one and executes.
    let (e, n) = transact(
        &mut w,
        &mut i,
        &mut r,
        b"next",
        |_| b"ok".to_vec(),
        |_| Decision::GiveUp,
    );
    assert_eq!((e, n), (InitiatorEvent::Reply, 1));
}

#[test]
fn requests_are_never_numbered_zero_and_a_reply_numbered_zero_is_taken() {
    use trol_proto::link::{Link, Outcome};
    // A controller that speaks only the manual's protocol sends PCI 0 (the manual: "not
    // needed"); no request carries 0, so such a reply can be no stale one of this host's.
    let mut i = Initiator::new(LinkConfig::default());
    let mut c = Link::new(LinkConfig::default());
    let mut w = Wire::new();
    for round in 0..300u32 {
        c.receive(w.now).unwrap();
        i.start(b"req", w.now).unwrap();
        let mut got = None;
        w.run(&mut i, &mut c, Duration::from_secs(10), |_, c| {
            got = got.or(c.poll_outcome());
            got.is_some()
        });
        assert_eq!(got, Some(Outcome::Received));
        let (req_pci, _) = c.take_received().unwrap();
        assert_ne!(pci_number(req_pci), 0, "round {round}");
        c.send(b"ok", 0, w.now).unwrap();
        let mut ev = None;
        w.run_t(&mut i, &mut c, Duration::from_secs(10), |i, _, _| {
            ev = i.poll_event();
            ev.is_some()
        });
        assert_eq!(ev, Some(InitiatorEvent::Reply), "round {round}");
        assert_eq!(i.take_reply().as_deref(), Some(&b"ok"[..]));
    }
    assert_eq!(i.stale_replies(), 0);
}

/// One request from a host that is a bare layer 2 (a host written from the manual): sends
/// `request` under `pci`, lets the responder run it (counted in `ran`) and takes the reply.
fn manual_host_request(
    w: &mut Wire,
    host: &mut trol_proto::Link,
    r: &mut Responder,
    request: &[u8],
    pci: u16,
    ran: &mut u32,
) -> Vec<u8> {
    use trol_proto::link::Outcome;
    host.send(request, pci, w.now).unwrap();
    let mut sent = false;
    loop {
        let mut outcome = None;
        let mut rev = None;
        w.run(host, r, Duration::from_secs(60), |h, r| {
            outcome = h.poll_outcome();
            rev = r.poll_event();
            outcome.is_some() || rev == Some(ResponderEvent::Request)
        });
        if rev == Some(ResponderEvent::Request) {
            // The server's rule (trol-comm's Server): a suspect duplicate is answered
            // ROBOT_UNSURE and not run; anything else runs (a CAT1 reply: 0, success).
            if r.request_is_suspect_duplicate() {
                let unsure = trol_proto::application::Reply::Code(
                    trol_proto::application::code::TROL_ERR_ROBOT_UNSURE,
                )
                .encode();
                r.respond(&unsure, w.now);
            } else {
                *ran += 1;
                r.respond(&[0, 0], w.now);
            }
        }
        match outcome {
            Some(Outcome::Sent) if !sent => {
                sent = true;
                host.receive(w.now).unwrap();
            }
            Some(Outcome::Received) => return host.take_received().unwrap().1,
            Some(other) => panic!("the manual's host failed: {other:?}"),
            None => {}
        }
    }
}

/// A host written from the manual alone leaves the PCI as it is ("not needed"): every
/// request carries the same number, never the REPEAT bit. With the LRC, a controller that
/// took a number seen twice for a repeat whose bit noise cleared refused every motion such
/// a host sent (issue 38): each request runs, as the manual's controller ran them. A host
/// that numbers its requests (three different numbers seen, or TROL's worded activation
/// line) is still held to the rule.
#[test]
fn a_host_that_does_not_number_its_requests_has_each_one_run_with_the_lrc() {
    use trol_proto::link::BlockCheck;
    let cfg = LinkConfig {
        check: BlockCheck::Lrc,
        ..LinkConfig::default()
    };
    let joint = [9u8, 2, 0, 0, 0x80, 0x3e]; // Joint(2, 0.25)
    for pci in [0u16, 0x0007] {
        let mut w = Wire::new();
        let mut host = trol_proto::Link::new(cfg);
        let mut r = Responder::new(cfg);
        r.listen(w.now);
        let mut ran = 0;
        for _ in 0..5 {
            let reply = manual_host_request(&mut w, &mut host, &mut r, &joint, pci, &mut ran);
            assert_eq!(reply, [0, 0], "PCI {pci:#x}: success, not ROBOT_UNSURE");
        }
        assert_eq!(ran, 5, "PCI {pci:#x}: every request ran");
        assert!(!r.host_numbers_requests());
    }
    // A host that numbers: 1, 2, 3 run; 3 again without REPEAT is the same request.
    let unsure =
        trol_proto::application::Reply::Code(trol_proto::application::code::TROL_ERR_ROBOT_UNSURE)
            .encode();
    let mut w = Wire::new();
    let mut host = trol_proto::Link::new(cfg);
    let mut r = Responder::new(cfg);
    r.listen(w.now);
    let mut ran = 0;
    for n in 1..=3u16 {
        manual_host_request(&mut w, &mut host, &mut r, &joint, n, &mut ran);
    }
    assert!(r.host_numbers_requests());
    let reply = manual_host_request(&mut w, &mut host, &mut r, &joint, 3, &mut ran);
    assert_eq!(reply, unsure);
    assert_eq!(ran, 3, "the same request again did not run");
    // After TROL's worded activation line the rule holds from the first request.
    let mut w = Wire::new();
    let mut host = trol_proto::Link::new(cfg);
    let mut r = Responder::new(cfg);
    r.set_numbered_host(true);
    r.listen(w.now);
    let mut ran = 0;
    manual_host_request(&mut w, &mut host, &mut r, &joint, 1, &mut ran);
    let reply = manual_host_request(&mut w, &mut host, &mut r, &joint, 1, &mut ran);
    assert_eq!((reply, ran), (unsure, 1));
}

/// A header built by hand with the manual's LRC over whatever bytes it carries (so that a
/// damaged field whose sum noise made up for passes the block check).
fn lrc_header(len: u16, pci: u16, first: [u8; 2]) -> Vec<u8> {
    use trol_proto::link::control::{ETX, SOH};
    let mut body = Vec::new();
    body.extend_from_slice(&len.to_le_bytes());
    body.extend_from_slice(&pci.to_le_bytes());
    body.extend_from_slice(&first);
    let mut h = vec![SOH];
    h.extend_from_slice(&body);
    h.extend_from_slice(&trol_proto::link::frame::lrc(&body).to_le_bytes());
    h.push(ETX);
    h
}

/// With the manual's LRC, a request whose damage the sum missed is asked for again when it
/// does not fit what the controller knows (issue 38, item 4): a Finish whose mode noise made
/// 2, or a request whose transaction number is nowhere near the host's, is NAKed ERR_BCC
/// and the clean header that comes again runs; the same bytes twice are taken (a peer that
/// means them gets the layer above's answer). Deterministic: the damaged header is built by
/// hand with a sum that holds.
#[test]
fn with_the_lrc_an_implausible_request_is_asked_for_again() {
    use trol_proto::link::control::{ACK, ENQ, EOT, NAK};
    use trol_proto::link::{BlockCheck, NakCode, Plausible};
    let cfg = LinkConfig {
        check: BlockCheck::Lrc,
        ..LinkConfig::default()
    };
    let mut w = Wire::new();
    let mut r = Responder::new(cfg);
    // The controller's layer 4: Finish takes mode 0 or 1.
    r.set_request_check(Some(Plausible::new(|_, req| {
        !(req.first() == Some(&4) && req.get(1).is_some_and(|m| *m > 1))
    })));
    r.set_numbered_host(true);
    r.listen(w.now);
    let mut peer = Script::default();
    // Send bytes that the responder answers; what it answered.
    fn send(w: &mut Wire, r: &mut Responder, peer: &mut Script, bytes: &[u8]) -> Vec<u8> {
        peer.received.clear();
        peer.to_send.extend_from_slice(bytes);
        w.run(peer, r, Duration::from_secs(5), |p, _| {
            !p.received.is_empty()
        });
        std::mem::take(&mut peer.received)
    }
    // A request: ENQ, the headers in turn (each answered), EOT; the responder's event.
    fn request(
        w: &mut Wire,
        r: &mut Responder,
        peer: &mut Script,
        headers: &[Vec<u8>],
    ) -> (Vec<Vec<u8>>, Option<ResponderEvent>) {
        assert_eq!(send(w, r, peer, &[ENQ]), [ACK]);
        let answers = headers.iter().map(|h| send(w, r, peer, h)).collect();
        peer.to_send.push(EOT);
        let mut ev = None;
        w.run(peer, r, Duration::from_secs(5), |_, r| {
            ev = r.poll_event();
            ev.is_some()
        });
        (answers, ev)
    }
    // Answer [0, 0]; the host takes the reply (ENQ, header, EOT).
    fn answer(w: &mut Wire, r: &mut Responder, peer: &mut Script) {
        r.respond(&[0, 0], w.now);
        peer.received.clear();
        w.run(peer, r, Duration::from_secs(5), |p, _| p.received == [ENQ]);
        assert_eq!(send(w, r, peer, &[ACK]).len(), 10, "the reply's header");
        assert_eq!(send(w, r, peer, &[ACK]), [EOT]);
        let mut ev = None;
        w.run(peer, r, Duration::from_secs(5), |_, r| {
            ev = r.poll_event();
            ev.is_some()
        });
        assert_eq!(ev, Some(ResponderEvent::Done));
    }
    // Transaction 1, Finish(STATUS), clean: it runs.
    let (a, ev) = request(&mut w, &mut r, &mut peer, &[lrc_header(2, 1, [4, 0])]);
    assert_eq!((a, ev), (vec![vec![ACK]], Some(ResponderEvent::Request)));
    answer(&mut w, &mut r, &mut peer);
    // Transaction 2: its mode byte 0 -> 2 and its number 2 -> 0 (the sum holds): NAK, then
    // the clean header is taken and runs as sent.
    let damaged = lrc_header(2, 0, [4, 2]);
    let (a, ev) = request(
        &mut w,
        &mut r,
        &mut peer,
        &[damaged, lrc_header(2, 2, [4, 0])],
    );
    assert_eq!(a, vec![vec![NAK, NakCode::Bcc.byte()], vec![ACK]]);
    assert_eq!(ev, Some(ResponderEvent::Request));
    assert_eq!(r.request(), [4, 0]);
    assert_eq!(pci_number(r.request_pci()), 2);
    answer(&mut w, &mut r, &mut peer);
    // Transaction 3 under a number far from the host's (noise in the PCI): asked again.
    let (a, _) = request(
        &mut w,
        &mut r,
        &mut peer,
        &[lrc_header(2, 0x83, [17, 50]), lrc_header(2, 3, [17, 50])],
    );
    assert_eq!(a, vec![vec![NAK, NakCode::Bcc.byte()], vec![ACK]]);
    assert_eq!(pci_number(r.request_pci()), 3);
    answer(&mut w, &mut r, &mut peer);
    // The same implausible bytes twice (a host that means them): taken the second time.
    let odd = lrc_header(2, 4, [4, 7]);
    let (a, ev) = request(&mut w, &mut r, &mut peer, &[odd.clone(), odd]);
    assert_eq!(a, vec![vec![NAK, NakCode::Bcc.byte()], vec![ACK]]);
    assert_eq!(ev, Some(ResponderEvent::Request));
    assert_eq!(r.request(), [4, 7]);
}

// ---------------------------------------------------------------- keep-alive

/// The controller while it executes: its responder, and SYN every `every` until `until`.
struct Working<'a> {
    r: &'a mut Responder,
    next: Option<Instant>,
    every: Duration,
    until: Instant,
    out: Vec<u8>,
}

impl common::End for Working<'_> {
    fn feed(&mut self, bytes: &[u8], now: Instant) {
        self.r.feed(bytes, now);
    }
    fn tick(&mut self, now: Instant) {
        self.r.tick(now);
        if let Some(t) = self.next
            && now >= t
        {
            self.out.push(trol_proto::link::control::SYN);
            self.next = Some(t + self.every).filter(|n| *n <= self.until);
        }
    }
    fn next_deadline(&self) -> Option<Instant> {
        [self.r.next_deadline(), self.next]
            .into_iter()
            .flatten()
            .min()
    }
    fn transmit(&mut self, out: &mut Vec<u8>) {
        self.r.transmit(out);
        out.append(&mut self.out);
    }
    fn wants_flush(&mut self) -> bool {
        self.r.wants_flush()
    }
}

/// The controller `r` working from `t0`, saying "still working" every 250 ms until `until`.
fn working(r: &mut Responder, t0: Instant, until: Duration) -> Working<'_> {
    Working {
        r,
        next: Some(t0 + Duration::from_millis(250)),
        every: Duration::from_millis(250),
        until: t0 + until,
        out: Vec::new(),
    }
}

/// Start `request` and run until the controller has it; returns when it did.
fn deliver(w: &mut Wire, i: &mut Initiator, r: &mut Responder, request: &[u8]) -> Instant {
    i.start(request, w.now).unwrap();
    let mut got = false;
    w.run(i, r, Duration::from_secs(10), |_, r| {
        got |= r.poll_event() == Some(ResponderEvent::Request);
        got
    });
    assert!(got, "the request did not arrive");
    w.now
}

#[test]
fn a_controller_that_says_still_working_is_waited_for_past_the_silence() {
    let (mut w, mut i, mut r) = pair();
    i.set_reply_timeout(Duration::from_secs(10));
    i.set_silence(Some(Duration::from_millis(1500)));
    let t0 = deliver(&mut w, &mut i, &mut r, &[42]);
    // 5 s of work, SYN every 250 ms, then the reply.
    let mut working = working(&mut r, t0, Duration::from_secs(5));
    let mut ev = None;
    w.run_t(&mut i, &mut working, Duration::from_secs(5), |i, _, now| {
        ev = i.poll_event();
        ev.is_some() || now >= t0 + Duration::from_secs(5)
    });
    assert_eq!(ev, None, "gave up while the controller said it works");
    r.respond(&[0, 0], w.now);
    assert_eq!(
        next_event(&mut w, &mut i, &mut r),
        Some(InitiatorEvent::Reply)
    );
    assert_eq!(i.take_reply(), Some(vec![0, 0]));
}

#[test]
fn a_controller_that_falls_silent_is_given_up_after_the_silence() {
    let (mut w, mut i, mut r) = pair();
    i.set_reply_timeout(Duration::from_secs(10));
    i.set_silence(Some(Duration::from_millis(1500)));
    let t0 = deliver(&mut w, &mut i, &mut r, &[42]);
    // It says "still working" for 2 s, then dies.
    let mut working = working(&mut r, t0, Duration::from_secs(2));
    let ev = next_event(&mut w, &mut i, &mut working);
    assert!(
        matches!(
            ev,
            Some(InitiatorEvent::NeedDecision(Failure::Timeout { .. }))
        ),
        "{ev:?}"
    );
    // The last SYN came 2 s after the request; 1.5 s of silence later the wait ends.
    assert_eq!(w.now.saturating_since(t0), Duration::from_millis(3500));
}

#[test]
fn without_a_silence_set_syn_is_taken_and_the_reply_timeout_alone_counts() {
    let (mut w, mut i, mut r) = pair();
    i.set_reply_timeout(Duration::from_secs(4));
    let t0 = deliver(&mut w, &mut i, &mut r, &[42]);
    let mut working = working(&mut r, t0, Duration::from_millis(500));
    let ev = next_event(&mut w, &mut i, &mut working);
    let Some(InitiatorEvent::NeedDecision(Failure::Timeout { waited })) = ev else {
        panic!("{ev:?}")
    };
    assert_eq!(waited, Duration::from_secs(4));
}

#[test]
fn only_a_host_of_this_protocol_is_sent_syn() {
    use trol_proto::link::{BlockCheck, LinkConfig};
    let crc = LinkConfig {
        check: BlockCheck::Crc16,
        ..LinkConfig::default()
    };
    let lrc = LinkConfig {
        check: BlockCheck::Lrc,
        ..LinkConfig::default()
    };
    // CRC-16: no 1998 host can have agreed on it.
    assert!(Responder::new(crc).host_takes_keepalive());
    // The LRC from a host not known yet: a 1998 host's layer 2 fails on any byte but ENQ.
    let mut r = Responder::new(lrc);
    assert!(!r.host_takes_keepalive());
    r.set_numbered_host(true);
    assert!(r.host_takes_keepalive());
    r.set_numbered_host(false);
    assert!(!r.host_takes_keepalive());
    // The manual's layer 3 (a 1998 controller, simulated) never sends it.
    let mut r = Responder::new(crc);
    r.set_manual(Some(trol_proto::transaction::ManualLayer3::EchoPci));
    assert!(!r.host_takes_keepalive());
}

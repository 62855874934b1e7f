//! Layers 1-3 over real ports: the in-memory line, TCP, the fault injector, and a
//! pseudo-terminal pair between two processes.

use std::time::{Duration, Instant};

use trol_comm::{
    AppTimeoutContext, DefaultHandlers, ErrorHandlers, ExtraWait, FailureContext, Recovery, Server,
    ServerEvent, TimeoutAction, TransError, Transactor,
};
use trol_port::Port;
use trol_port::faulty::{FaultConfig, Faulty};
use trol_port::memory;
use trol_proto::link::{LinkConfig, Timeouts};
use trol_proto::transaction::TransCode;

/// Requests understood by the test controller: "echo" returns the request reversed,
/// "quit" ends the server, "big N" returns N bytes.
fn execute(request: &[u8]) -> Vec<u8> {
    if let Some(n) = request.strip_prefix(b"big ") {
        let n: usize = std::str::from_utf8(n).unwrap().parse().unwrap();
        return (0..n).map(|i| (i % 251) as u8).collect();
    }
    request.iter().rev().copied().collect()
}

fn serve<P: Port>(server: Server<P>, max_idle: Duration) -> u32 {
    serve_telling(server, max_idle, None)
}

/// [`serve`], telling `events` each transaction's end as the controller saw it (all but
/// [`ServerEvent::Idle`]): a test waits for the controller's side to be over, not for a
/// fixed time.
fn serve_telling<P: Port>(
    mut server: Server<P>,
    max_idle: Duration,
    events: Option<std::sync::mpsc::Sender<ServerEvent>>,
) -> u32 {
    let mut executed = 0;
    let mut quit = false;
    let started = Instant::now();
    while !quit && started.elapsed() < max_idle {
        let ev = server
            .serve(Duration::from_millis(100), &mut |req| {
                quit = req == b"quit";
                execute(req)
            })
            .unwrap();
        if ev == ServerEvent::Executed {
            executed += 1;
        }
        if ev != ServerEvent::Idle
            && let Some(tx) = &events
        {
            // After a failed transfer the link stays deaf for its reset (the manual's), then
            // flushes its input: told once it listens again, so that the next request is
            // not dropped by the reset.
            while server.responder().link().is_resetting() {
                server.wait(Duration::from_millis(5)).unwrap();
            }
            let _ = tx.send(ev);
        }
    }
    executed
}

/// A server on `port` in a thread of its own (30 s at most), with [`quick_link`], telling
/// each transaction's end ([`serve_telling`]).
fn telling_server<P: Port + Send + 'static>(
    port: P,
) -> (
    std::thread::JoinHandle<u32>,
    std::sync::mpsc::Receiver<ServerEvent>,
) {
    let (tx, events) = std::sync::mpsc::channel();
    let server = std::thread::spawn(move || {
        serve_telling(
            Server::new(port, quick_link()),
            Duration::from_secs(30),
            Some(tx),
        )
    });
    (server, events)
}

/// The next transaction's end on the controller's side, its link listening again, within a
/// bound a loaded machine keeps (the link's own timeouts are a fraction of it).
fn controller_done(events: &std::sync::mpsc::Receiver<ServerEvent>) -> ServerEvent {
    events
        .recv_timeout(Duration::from_secs(30))
        .expect("the controller's side ends its transaction")
}

fn quick_link() -> LinkConfig {
    LinkConfig {
        timeouts: Timeouts::uniform(Duration::from_millis(200)),
        ..LinkConfig::default()
    }
}

#[test]
fn transactions_over_the_in_memory_line() {
    let (a, b) = memory::pair(None);
    let server = std::thread::spawn(move || {
        serve(
            Server::new(b, LinkConfig::default()),
            Duration::from_secs(30),
        )
    });
    let mut t = Transactor::new(a, LinkConfig::default());
    for len in [0usize, 1, 2, 3, 300, 4000, 65000] {
        let req: Vec<u8> = (0..len).map(|i| (i * 13) as u8).collect();
        let reply = t.trans_sr(&req).unwrap();
        assert_eq!(
            reply,
            req.iter().rev().copied().collect::<Vec<_>>(),
            "len {len}"
        );
    }
    assert_eq!(t.trans_sr(b"big 65535").unwrap().len(), 65535);
    t.trans_sr(b"quit").unwrap();
    assert_eq!(server.join().unwrap(), 9);
}

#[test]
fn a_reply_too_long_for_layer_2_is_reported_and_the_server_goes_on() {
    let (a, b) = memory::pair(None);
    let server = std::thread::spawn(move || {
        let mut s = Server::new(b, quick_link());
        let first = s.serve(Duration::from_secs(5), &mut |_| vec![0; 70_000]);
        let second = s.serve(Duration::from_secs(5), &mut |req| req.to_vec());
        (first.unwrap(), second.unwrap())
    });
    let mut t = Transactor::new(a, quick_link());
    t.set_reply_timeout_tenths(5);
    t.set_repeats(0);
    assert_eq!(t.trans_sr(b"huge").unwrap_err().code(), TransCode::Timeout);
    assert_eq!(t.trans_sr(b"ok").unwrap(), b"ok");
    let (first, second) = server.join().unwrap();
    assert_eq!(first, ServerEvent::ReplyTooLong { len: 70_000 });
    assert_eq!(second, ServerEvent::Executed);
}

#[test]
fn transactions_over_a_paced_line_take_the_line_time() {
    let (a, b) = memory::pair(Some(38400));
    let cfg = LinkConfig::for_line(38400, Duration::ZERO);
    let server = std::thread::spawn(move || serve(Server::new(b, cfg), Duration::from_secs(30)));
    let mut t = Transactor::new(a, cfg);
    let started = Instant::now();
    let reply = t.trans_sr(&[0x55; 3000]).unwrap();
    let took = started.elapsed();
    assert_eq!(reply.len(), 3000);
    // 2 x 3000 bytes plus framing at 3840 bytes/s is at least 1.6 s of line time.
    assert!(took >= Duration::from_millis(1600), "took {took:?}");
    t.trans_sr(b"quit").unwrap();
    server.join().unwrap();
}

#[test]
fn transactions_over_tcp() {
    let listen = trol_port::tcp::TcpLine::listen("127.0.0.1:0", Duration::from_secs(1)).unwrap();
    let addr = listen.local_addr().unwrap();
    let server = std::thread::spawn(move || {
        serve(
            Server::new(listen, LinkConfig::default()),
            Duration::from_secs(30),
        )
    });
    let port = trol_port::open(&format!("socket://{addr}"), &Default::default()).unwrap();
    let mut t = Transactor::new(port, LinkConfig::default());
    assert_eq!(t.trans_sr(b"abc").unwrap(), b"cba");
    t.trans_sr(b"quit").unwrap();
    assert_eq!(server.join().unwrap(), 2);
}

#[test]
fn a_noisy_line_still_carries_every_transaction() {
    let (a, b) = memory::pair(None);
    let noise = |seed| FaultConfig {
        seed,
        bit_error_rate: 1e-5,
        ..FaultConfig::default()
    };
    let b = Faulty::new(b, noise(2));
    let server =
        std::thread::spawn(move || serve(Server::new(b, quick_link()), Duration::from_secs(60)));
    let a = Faulty::new(a, noise(1));
    let mut t = Transactor::new(a, quick_link());
    for i in 0..20u32 {
        let req: Vec<u8> = (0..2000u32).map(|k| (k ^ i) as u8).collect();
        let reply = t.trans_sr(&req).unwrap();
        assert_eq!(reply, req.iter().rev().copied().collect::<Vec<_>>());
    }
    let flips = t.driver().port().stats().flipped_bits;
    assert!(flips > 0, "the line did flip bits ({flips})");
    t.trans_sr(b"quit").unwrap();
    server.join().unwrap();
}

#[test]
fn a_cut_line_ends_the_transaction_with_a_code_not_a_hang() {
    let (a, _b) = memory::pair(None);
    let a = Faulty::new(
        a,
        FaultConfig {
            cut_after: Some(0),
            ..FaultConfig::default()
        },
    );
    let mut t = Transactor::new(a, quick_link());
    let started = Instant::now();
    let err = t.trans_sr(b"hello").unwrap_err();
    assert!(started.elapsed() < Duration::from_secs(5));
    assert_eq!(err.code(), TransCode::ErrSend);
    assert_eq!(
        t.last_comm_error().map(|e| e.name()),
        Some("ERR_TIMEOUT_ENQ")
    );
    match err {
        TransError::Failed { code, .. } => assert_eq!(code, TransCode::ErrSend),
        other => panic!("{other}"),
    }
}

#[test]
fn a_controller_that_never_answers_gives_trans_timeout() {
    let (a, b) = memory::pair(None);
    // A controller that receives the request and then hangs.
    let hang = std::thread::spawn(move || {
        let mut s = Server::new(b, LinkConfig::default());
        let _ = s.serve(Duration::from_secs(2), &mut |_| {
            std::thread::sleep(Duration::from_millis(1500));
            vec![0, 0]
        });
    });
    let mut t = Transactor::new(a, LinkConfig::default());
    t.set_reply_timeout_tenths(5);
    let err = t.trans_sr(b"slow").unwrap_err();
    assert_eq!(err.code(), TransCode::Timeout);
    hang.join().unwrap();
}

struct Counting {
    sends: std::sync::Arc<std::sync::atomic::AtomicU32>,
}

impl ErrorHandlers for Counting {
    fn err_on_send(&mut self, ctx: &FailureContext<'_>) -> Recovery {
        self.sends.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
        assert_eq!(ctx.error.name(), "ERR_TIMEOUT_ENQ");
        assert_eq!(ctx.message, b"again");
        if ctx.attempts < 2 {
            Recovery::Success
        } else {
            Recovery::Fail
        }
    }
}

#[test]
fn a_replaced_err_on_send_is_asked_and_can_retry() {
    let (a, _b) = memory::pair(None);
    let mut t = Transactor::new(a, quick_link());
    // The manual's behaviour: no repeats, the handler alone decides.
    t.set_repeats(0);
    let sends = std::sync::Arc::new(std::sync::atomic::AtomicU32::new(0));
    t.set_handlers(Box::new(Counting {
        sends: sends.clone(),
    }));
    let err = t.trans_sr(b"again").unwrap_err();
    assert_eq!(err.code(), TransCode::ErrSend);
    // Asked three times: two retries, then it gave up.
    assert_eq!(sends.load(std::sync::atomic::Ordering::SeqCst), 3);
    // With TROL's repeats (the default) the request is not sent again into a peer that
    // said nothing at all: the request never left, and a repeat would only wait longer. The
    // handler alone decided, as above.
    t.set_repeats(2);
    let before = sends.load(std::sync::atomic::Ordering::SeqCst);
    assert_eq!(t.trans_sr(b"again").unwrap_err().code(), TransCode::ErrSend);
    assert_eq!(sends.load(std::sync::atomic::Ordering::SeqCst) - before, 3);
}

#[test]
fn the_default_err_app_timeout_waits_longer_only_for_what_the_policy_names() {
    fn policy(req: &[u8]) -> Option<ExtraWait> {
        match req.first() {
            Some(1) => Some(ExtraWait::Up(Duration::from_secs(90))),
            Some(2) => Some(ExtraWait::Unlimited),
            _ => None,
        }
    }
    let mut h = DefaultHandlers::with_policy(std::sync::Arc::new(policy));
    let ctx = |request: &'static [u8], waited: u64| AppTimeoutContext {
        request,
        waited: Duration::from_secs(waited),
        reply_timeout: Duration::from_secs(15),
        input_pending: false,
    };
    assert_eq!(h.err_app_timeout(&ctx(&[0], 15)), TimeoutAction::Fail);
    assert_eq!(
        h.err_app_timeout(&ctx(&[1], 15)),
        TimeoutAction::WaitMore(Duration::from_secs(90))
    );
    assert_eq!(h.err_app_timeout(&ctx(&[1], 105)), TimeoutAction::Fail);
    assert_eq!(
        h.err_app_timeout(&ctx(&[2], 10_000)),
        TimeoutAction::WaitMore(Duration::from_secs(15))
    );
    assert_eq!(
        DefaultHandlers::default().err_app_timeout(&ctx(&[1], 15)),
        TimeoutAction::Fail
    );
}

// ------------------------------------------------------------ two processes over a pty

const PEER_ENV: &str = "TROL_TEST_PTY_PEER";

/// The controller half of the pty test, run in a second process (this test binary started
/// again with only this test selected). Does nothing when run on its own.
#[test]
#[ignore = "runs as the peer process of transactions_between_two_processes_over_a_pty"]
fn pty_peer_process() {
    let Ok(path) = std::env::var(PEER_ENV) else {
        return;
    };
    let line = trol_port::serial::SerialLine::open(&path, 38400).expect("open pty");
    let n = serve(
        Server::new(line, LinkConfig::default()),
        Duration::from_secs(60),
    );
    println!("peer executed {n}");
}

#[cfg(unix)]
#[test]
fn transactions_between_two_processes_over_a_pty() {
    let (master, _slave, path) = trol_port::serial::SerialLine::pty_pair().unwrap();
    let child = std::process::Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "pty_peer_process",
            "--ignored",
            "--nocapture",
            "--test-threads=1",
        ])
        .env(PEER_ENV, &path)
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut t = Transactor::new(master, LinkConfig::default());
    // The peer needs a moment to start; the first transaction may time out on ENQ.
    let started = Instant::now();
    loop {
        match t.trans_sr(b"ping") {
            Ok(r) => {
                assert_eq!(r, b"gnip");
                break;
            }
            Err(e) if started.elapsed() < Duration::from_secs(20) => {
                let _ = e;
            }
            Err(e) => panic!("peer never answered: {e}"),
        }
    }
    for len in [0usize, 2, 3, 257, 5000, 65535] {
        let req: Vec<u8> = (0..len).map(|i| (i * 7 + 1) as u8).collect();
        let reply = t.trans_sr(&req).unwrap();
        assert_eq!(
            reply,
            req.iter().rev().copied().collect::<Vec<_>>(),
            "len {len}"
        );
    }
    t.trans_sr(b"quit").unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("peer executed 8"), "{text}");
}

/// A port that fails its `n`-th receive with an I/O error, once.
struct FailsOnce<P> {
    inner: P,
    recvs: u32,
    fail_at: u32,
}

impl<P: Port> Port for FailsOnce<P> {
    fn send(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.inner.send(bytes)
    }
    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> std::io::Result<usize> {
        self.recvs += 1;
        if self.recvs == self.fail_at {
            return Err(std::io::Error::other("the adapter was unplugged"));
        }
        self.inner.recv(buf, deadline)
    }
    fn available(&mut self) -> std::io::Result<usize> {
        self.inner.available()
    }
    fn flush_input(&mut self) -> std::io::Result<()> {
        self.inner.flush_input()
    }
    fn name(&self) -> String {
        "fails-once".into()
    }
}

#[test]
fn a_port_error_mid_transaction_is_reported_and_the_next_transaction_works() {
    let (a, b) = memory::pair(None);
    let (server, events) = telling_server(b);
    let port = FailsOnce {
        inner: a,
        recvs: 0,
        fail_at: 2,
    };
    let mut t = Transactor::new(port, quick_link());
    let err = t.trans_sr(b"first").unwrap_err();
    assert!(matches!(err, TransError::Io(_)), "{err}");
    // The controller may still be finishing its side: wait until its link has ended it.
    let ended = controller_done(&events);
    assert_ne!(
        ended,
        ServerEvent::Executed,
        "a reply nobody heard counted as sent"
    );
    let _ = t.driver_mut().port_mut().flush_input();
    let reply = t
        .trans_sr(b"second")
        .expect("the next transaction must start afresh");
    assert_eq!(reply, b"dnoces");
    t.trans_sr(b"quit").unwrap();
    server.join().unwrap();
}

/// A port that fails its first receive after a send that carried EOT (the request is out:
/// the failure hits the wait for the reply).
struct FailsAfterRequest<P> {
    inner: P,
    once: bool,
    armed: bool,
}

impl<P: Port> Port for FailsAfterRequest<P> {
    fn send(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        if bytes.contains(&trol_proto::link::control::EOT) && std::mem::take(&mut self.once) {
            self.armed = true;
        }
        self.inner.send(bytes)
    }
    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> std::io::Result<usize> {
        if std::mem::take(&mut self.armed) {
            return Err(std::io::Error::other("the controller's process is gone"));
        }
        self.inner.recv(buf, deadline)
    }
    fn available(&mut self) -> std::io::Result<usize> {
        self.inner.available()
    }
    fn flush_input(&mut self) -> std::io::Result<()> {
        self.inner.flush_input()
    }
    fn name(&self) -> String {
        "fails-after-request".into()
    }
}

/// Records which handler was told of which failure.
#[derive(Default, Clone)]
struct Told(std::sync::Arc<std::sync::Mutex<Vec<(&'static str, trol_proto::link::LinkError)>>>);

impl ErrorHandlers for Told {
    fn err_on_send(&mut self, ctx: &FailureContext<'_>) -> Recovery {
        self.0.lock().unwrap().push(("ErrOnSend", ctx.error));
        Recovery::Fail
    }
    fn err_on_receive(&mut self, ctx: &FailureContext<'_>) -> Recovery {
        self.0.lock().unwrap().push(("ErrOnReceive", ctx.error));
        Recovery::Fail
    }
}

#[test]
fn a_port_that_fails_is_told_to_the_handler_of_its_side_and_kept_for_get_last_comm_err() {
    use trol_proto::link::{LinkError, ReceiveError, SendError};
    // While the request goes out: SendData's ERR_PORT, ErrOnSend.
    let (a, _b) = memory::pair(None);
    let told = Told::default();
    let mut t = Transactor::new(
        FailsOnce {
            inner: a,
            recvs: 0,
            fail_at: 1,
        },
        quick_link(),
    );
    t.set_handlers(Box::new(told.clone()));
    assert!(matches!(t.trans_sr(b"first"), Err(TransError::Io(_))));
    let port_send = LinkError::Send(SendError::Port);
    assert_eq!(*told.0.lock().unwrap(), vec![("ErrOnSend", port_send)]);
    assert_eq!(t.last_comm_error(), Some(port_send));
    assert_eq!(port_send.code(), 0x08);

    // While the reply is awaited: ReceiveData's ERR_PORT, ErrOnReceive; then a transaction
    // that goes through leaves no stale failure behind.
    let (a, b) = memory::pair(None);
    let (server, events) = telling_server(b);
    let told = Told::default();
    let mut t = Transactor::new(
        FailsAfterRequest {
            inner: a,
            once: true,
            armed: false,
        },
        quick_link(),
    );
    t.set_handlers(Box::new(told.clone()));
    t.set_repeats(0);
    assert!(matches!(t.trans_sr(b"first"), Err(TransError::Io(_))));
    let port_receive = LinkError::Receive(ReceiveError::Port);
    assert_eq!(
        *told.0.lock().unwrap(),
        vec![("ErrOnReceive", port_receive)]
    );
    assert_eq!(t.last_comm_error(), Some(port_receive));
    assert_eq!(port_receive.code(), 0x88);
    // The controller's reply to "first" may still come: wait until its link has given up,
    // then drop what came.
    let ended = controller_done(&events);
    assert!(matches!(ended, ServerEvent::ReplyFailed(_)), "{ended:?}");
    let _ = t.driver_mut().port_mut().flush_input();
    t.set_repeats(2);
    assert_eq!(t.trans_sr(b"second").unwrap(), b"dnoces");
    assert_eq!(t.last_comm_error(), None, "a stale failure was kept");
    t.trans_sr(b"quit").unwrap();
    server.join().unwrap();
}

/// A port that, while `armed`, hears nothing from its own EOT until it sends ENQ again: the
/// requests arrive, every reply is lost.
struct DeafToReplies<P> {
    inner: P,
    armed: std::sync::Arc<std::sync::atomic::AtomicBool>,
    deaf: bool,
}

impl<P: Port> Port for DeafToReplies<P> {
    fn send(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        if self.armed.load(std::sync::atomic::Ordering::SeqCst) {
            if bytes.contains(&trol_proto::link::control::ENQ) {
                self.deaf = false;
            }
            if bytes.contains(&trol_proto::link::control::EOT) {
                self.deaf = true;
            }
        } else {
            self.deaf = false;
        }
        self.inner.send(bytes)
    }
    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> std::io::Result<usize> {
        let n = self.inner.recv(buf, deadline)?;
        Ok(if self.deaf { 0 } else { n })
    }
    fn available(&mut self) -> std::io::Result<usize> {
        self.inner.available()
    }
    fn flush_input(&mut self) -> std::io::Result<()> {
        self.inner.flush_input()
    }
    fn name(&self) -> String {
        "deaf-to-replies".into()
    }
}

#[test]
fn a_repeat_answered_from_memory_whose_reply_is_lost_again_is_not_reported_as_run() {
    // The host hears nothing: the request runs once, its reply is lost, the repeat is
    // answered from memory and that reply is lost too. The server's events say so: one
    // execution, then a repeat that ran nothing.
    let (a, b) = memory::pair(None);
    let events = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let seen = events.clone();
    let server = std::thread::spawn(move || {
        let mut server = Server::new(b, quick_link());
        let started = Instant::now();
        while started.elapsed() < Duration::from_secs(20) {
            let ev = server
                .serve(Duration::from_millis(100), &mut |req| execute(req))
                .unwrap();
            if ev != ServerEvent::Idle {
                // Told once the link listens again after its reset (see serve_telling).
                while server.responder().link().is_resetting() {
                    server.wait(Duration::from_millis(5)).unwrap();
                }
                seen.lock().unwrap().push(ev);
            }
            if seen.lock().unwrap().len() >= 3 {
                break;
            }
        }
    });
    let deaf = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(true));
    let mut t = Transactor::new(
        DeafToReplies {
            inner: a,
            armed: deaf.clone(),
            deaf: false,
        },
        quick_link(),
    );
    t.set_repeats(1);
    t.initiator_mut()
        .set_reply_timeout(Duration::from_millis(800));
    assert!(t.trans_sr(b"move").is_err());
    // Let the server give up on the second reply (its second event), then hear again: a
    // third request.
    let gave_up = Instant::now();
    while events.lock().unwrap().len() < 2 {
        assert!(
            gave_up.elapsed() < Duration::from_secs(30),
            "the server never gave up: {:?}",
            events.lock().unwrap()
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    deaf.store(false, std::sync::atomic::Ordering::SeqCst);
    let _ = t.driver_mut().port_mut().flush_input();
    assert_eq!(t.trans_sr(b"next").unwrap(), b"txen");
    server.join().unwrap();
    let events = events.lock().unwrap().clone();
    assert!(
        matches!(
            events.as_slice(),
            [
                ServerEvent::ReplyFailed(_),
                ServerEvent::RepeatReplyFailed(_),
                ServerEvent::Executed
            ]
        ),
        "{events:?}"
    );
}

#[test]
fn a_controller_that_restarted_never_runs_a_repeat_it_cannot_place() {
    // The controller executes a relative move, then restarts before its reply goes out (a
    // killed gateway started again). The host, hearing nothing, sends the request again
    // marked REPEAT. The new controller remembers nothing: whether its earlier run executed
    // the move cannot be told, so it must not run it (the move would run twice) and answers
    // TROL_ERR_ROBOT_UNSURE. A request after that is executed as usual.
    let (a, b) = memory::pair(None);
    let runs = std::sync::Arc::new(std::sync::atomic::AtomicU32::new(0));
    let counted = runs.clone();
    let controller = std::thread::spawn(move || {
        // The first run: executes, then dies with the reply unsent.
        let mut first = Server::new(b, quick_link());
        let ev = loop {
            let ev = first
                .serve_deferrable(Duration::from_millis(100), &mut |_req, _pci| {
                    counted.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                    None
                })
                .unwrap();
            if ev != ServerEvent::Idle {
                break ev;
            }
        };
        assert_eq!(ev, ServerEvent::Pending);
        // The restart: a new server on the same line, with no memory.
        let mut second = Server::new(first.into_port(), quick_link());
        let mut events = Vec::new();
        let started = Instant::now();
        while events.len() < 2 && started.elapsed() < Duration::from_secs(20) {
            let ev = second
                .serve(Duration::from_millis(100), &mut |req| {
                    counted.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                    execute(req)
                })
                .unwrap();
            if ev != ServerEvent::Idle {
                events.push(ev);
            }
        }
        events
    });
    let mut t = Transactor::new(a, quick_link());
    t.set_repeats(1);
    t.initiator_mut()
        .set_reply_timeout(Duration::from_millis(800));
    let reply = t.trans_sr(b"mi 0.5").expect("the repeat is answered");
    let unsure =
        trol_proto::application::Reply::Code(trol_proto::application::code::TROL_ERR_ROBOT_UNSURE)
            .encode();
    assert_eq!(reply, unsure);
    assert_eq!(t.trans_sr(b"next").unwrap(), b"txen");
    let events = controller.join().unwrap();
    assert_eq!(
        events,
        [ServerEvent::UnknownRepeat, ServerEvent::Executed],
        "{events:?}"
    );
    // The move ran once (before the restart), "next" once.
    assert_eq!(runs.load(std::sync::atomic::Ordering::SeqCst), 2);
}

/// With the manual's LRC the REPEAT bit can be lost to noise the check lets through; a
/// CAT1/CAT2 request without it under the number of the request last executed is then that
/// request again, and must not run twice: the controller answers TROL_ERR_ROBOT_UNSURE and
/// runs nothing (docs/reliability.md, "LRC"). Here a host that starts anew sends its first
/// request under the number the controller executed last, which is what such a request looks
/// like. With CRC-16, which protects the bit, the same request runs (a host that restarted is
/// never refused).
#[test]
fn with_the_lrc_a_lost_repeat_bit_never_runs_a_request_twice() {
    use trol_proto::link::BlockCheck;
    for check in [BlockCheck::Lrc, BlockCheck::Crc16] {
        let cfg = LinkConfig {
            check,
            ..quick_link()
        };
        let (a, b) = memory::pair(None);
        let runs = std::sync::Arc::new(std::sync::atomic::AtomicU32::new(0));
        let counted = runs.clone();
        let controller = std::thread::spawn(move || {
            let mut server = Server::new(b, cfg);
            // As after TROL's worded activation line: this host numbers its requests.
            server.responder_mut().set_numbered_host(true);
            let mut events = Vec::new();
            let started = Instant::now();
            while events.len() < 2 && started.elapsed() < Duration::from_secs(20) {
                let ev = server
                    .serve(Duration::from_millis(100), &mut |req| {
                        counted.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                        execute(req)
                    })
                    .unwrap();
                if ev != ServerEvent::Idle {
                    events.push(ev);
                }
            }
            events
        });
        let mut first = Transactor::new(a, cfg);
        assert_eq!(first.trans_sr(b"mi 0.5").unwrap(), b"5.0 im");
        // The same number (1) again, without the REPEAT bit.
        let mut again = Transactor::new(first.into_port(), cfg);
        let reply = again.trans_sr(b"mi 0.5").unwrap();
        let events = controller.join().unwrap();
        if check == BlockCheck::Lrc {
            let unsure = trol_proto::application::Reply::Code(
                trol_proto::application::code::TROL_ERR_ROBOT_UNSURE,
            )
            .encode();
            assert_eq!(reply, unsure);
            assert_eq!(
                events,
                [ServerEvent::Executed, ServerEvent::SuspectDuplicate]
            );
            assert_eq!(runs.load(std::sync::atomic::Ordering::SeqCst), 1);
        } else {
            assert_eq!(reply, b"5.0 im");
            assert_eq!(events, [ServerEvent::Executed, ServerEvent::Executed]);
            assert_eq!(runs.load(std::sync::atomic::Ordering::SeqCst), 2);
        }
    }
}

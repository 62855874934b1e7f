//! The controller's main loop: terminal mode and server mode over one port.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use trol_comm::{Server, ServerEvent};
use trol_port::Port;
use trol_proto::application::Catalog;
use trol_proto::link::{LinkConfig, LinkError, SendError};

use crate::backend::{Backend, SharedReport};
use crate::pcp::{Handled, Pcp};
use crate::terminal::{PROMPT, Terminal};

/// Which mode the controller is in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Not serving TROL (a C500 would speak RAPL); waits for the activation sequence.
    Terminal,
    /// Serving TROL requests (the PCP runs).
    Server,
}

/// A way to the controller besides its TROL line: the browser's pendant (`trol sim --view
/// --control`, docs/teach.md). Each request runs between two transactions of the line, as
/// the server's own, through the same checks; what GetStatus tells the line's host is kept.
/// Clone it for each thread.
#[derive(Clone, Debug)]
pub struct Pendant {
    tx: std::sync::mpsc::SyncSender<PendantCall>,
}

/// The request that follows a pendant request, made from its reply (the pendant's turn:
/// where the tool is, then the move there): both run in one step of the controller, with
/// nothing from the line between them. `None`: nothing follows (the first reply is the
/// answer).
pub type FollowUp = Box<dyn FnOnce(&[u8]) -> Option<Vec<u8>> + Send>;

/// A request from the pendant, what follows it, and where the reply goes (with whether the
/// follow-up ran).
type PendantCall = (
    Vec<u8>,
    Option<FollowUp>,
    std::sync::mpsc::SyncSender<(Vec<u8>, bool)>,
);

/// Why a pendant request got no reply.
#[derive(Debug, thiserror::Error)]
pub enum PendantError {
    /// The controller did not take it up in time (it is busy with a long call of the line,
    /// or too many pendant requests wait).
    #[error("the controller did not answer within {0:?}")]
    Timeout(Duration),
    /// The controller has stopped.
    #[error("the controller has stopped")]
    Gone,
}

/// The controller's end of a [`Pendant`] ([`Controller::set_pendant`]).
#[derive(Debug)]
pub struct PendantInbox(std::sync::mpsc::Receiver<PendantCall>);

impl Pendant {
    /// A pendant and the inbox a controller takes its requests from (for a view that must
    /// start before the controller exists).
    pub fn channel() -> (Pendant, PendantInbox) {
        let (tx, rx) = std::sync::mpsc::sync_channel(PENDANT_QUEUE);
        (Pendant { tx }, PendantInbox(rx))
    }

    /// Send `request` (a record) and wait at most `limit` for its reply.
    pub fn call(&self, request: Vec<u8>, limit: Duration) -> Result<Vec<u8>, PendantError> {
        self.call_then(request, None, limit).map(|(reply, _)| reply)
    }

    /// Send `request`, and the request `follow` makes of its reply right after it, in the
    /// same step of the controller (no transaction of the line between the two); wait at
    /// most `limit`. The reply is the second request's when one followed (`true`), else the
    /// first's.
    pub fn call_then(
        &self,
        request: Vec<u8>,
        follow: Option<FollowUp>,
        limit: Duration,
    ) -> Result<(Vec<u8>, bool), PendantError> {
        let (back, reply) = std::sync::mpsc::sync_channel(1);
        match self.tx.try_send((request, follow, back)) {
            Ok(()) => {}
            Err(std::sync::mpsc::TrySendError::Full(_)) => {
                return Err(PendantError::Timeout(Duration::ZERO));
            }
            Err(std::sync::mpsc::TrySendError::Disconnected(_)) => {
                return Err(PendantError::Gone);
            }
        }
        reply.recv_timeout(limit).map_err(|e| match e {
            std::sync::mpsc::RecvTimeoutError::Timeout => PendantError::Timeout(limit),
            std::sync::mpsc::RecvTimeoutError::Disconnected => PendantError::Gone,
        })
    }
}

/// How many pendant requests may wait for the controller at once.
const PENDANT_QUEUE: usize = 8;

/// What the log hook is told after each transaction.
#[derive(Debug)]
pub struct LogEntry<'a> {
    /// The server's commands (to put the request and reply in words, added ones included).
    pub catalog: &'a Catalog,
    /// The request's bytes.
    pub request: &'a [u8],
    /// The reply's bytes.
    pub reply: &'a [u8],
    /// How the transaction ended.
    pub event: ServerEvent,
    /// Whether the PCP server ran the request (answered it from its dispatch tables):
    /// true for every request it executed, whatever happened to the reply afterwards, so a
    /// log that counts these counts every execution.
    pub executed: bool,
    /// Whether it came from the pendant ([`Pendant`]), not the TROL line.
    pub from_pendant: bool,
    /// The backend's word on its world (a simulator's objects), if it has one.
    pub world: Option<String>,
    /// Why the request was refused, in words, where the reply's code alone cannot say it
    /// (a locations file that could not be written: which, and what the system said).
    pub note: Option<String>,
}

/// A log hook: called after each transaction.
pub type LogFn = Box<dyn FnMut(&LogEntry<'_>) + Send>;

/// The watchdog halted the arm: no transaction arrived for `after` (SetWatchdog).
#[derive(Clone, Debug, PartialEq)]
pub struct WatchdogTrip {
    /// The limit that ran out.
    pub after: Duration,
    /// What the backend's Halt answered (its BIOS value, or why it failed).
    pub halt: Result<i16, String>,
}

/// How often a deferred reply (Finish(FINISH_WAIT), Home) asks the backend whether the arm
/// is idle.
const POLL: Duration = Duration::from_millis(5);

/// The controller: a PCP server over a port.
pub struct Controller<P, B> {
    server: Server<P>,
    pcp: Pcp<B>,
    mode: Mode,
    terminal: Terminal,
    log: Option<LogFn>,
    /// The last request and its reply, for the log.
    last: (Vec<u8>, Vec<u8>),
    /// Whether the PCP server ran a request not yet logged.
    ran: bool,
    /// When the last transaction arrived (or a long one was still under way).
    last_seen: Instant,
    /// Whether the watchdog has halted the arm since the last transaction.
    tripped: bool,
    /// The watchdog's last trip, not yet taken.
    trip: Option<WatchdogTrip>,
    /// Where the backend's reports go, how often, and when the last was taken.
    reports: Option<(SharedReport, Duration, Instant)>,
    /// Requests from the pendant, if one was made.
    pendant: Option<PendantInbox>,
    /// How long the server takes to start after its activation line was answered
    /// ([`Controller::set_start_pause`]), and until when it is still starting.
    start_pause: Duration,
    starting_until: Option<Instant>,
    /// The journal of the last call ([`Controller::set_journal`]).
    journal: Option<crate::journal::Journal>,
    /// A CAT1/CAT2 request of the line runs, its `done` not yet journaled.
    journaling: bool,
}

impl<P: Port, B: Backend> Controller<P, B> {
    /// A controller on `port` in `mode`.
    pub fn new(port: P, cfg: LinkConfig, pcp: Pcp<B>, mode: Mode) -> Self {
        let mut c = Controller {
            server: Server::new(port, cfg),
            pcp,
            mode,
            terminal: Terminal::default(),
            log: None,
            last: (Vec::new(), Vec::new()),
            ran: false,
            last_seen: Instant::now(),
            tripped: false,
            trip: None,
            reports: None,
            pendant: None,
            start_pause: Duration::ZERO,
            starting_until: None,
            journal: None,
            journaling: false,
        };
        c.check_requests();
        // "Still working" while a request executes, to a host that takes it: without a
        // thread the keep-alive is not offered, and the host waits the reply time alone.
        let _ = c.server.set_keepalive(Some(trol_comm::KEEPALIVE_INTERVAL));
        c
    }

    /// With the manual's LRC, a request is taken only when it is one of the commands this
    /// server knows, its fields fitting its record (and its PCI the host's numbering):
    /// damage the sum let through is asked for again, never run as another command
    /// (`Responder::set_request_check`). Called again when a command is added.
    pub fn check_requests(&mut self) {
        let catalog = self.pcp.catalog().clone();
        let fits = trol_proto::link::Plausible::new(move |_pci, request| {
            request
                .first()
                .and_then(|code| catalog.get(*code))
                .is_some_and(|def| trol_proto::application::record::decode(def, request).is_ok())
        });
        self.server.responder_mut().set_request_check(Some(fits));
    }

    /// A pendant for this controller (docs/teach.md): requests sent through it run between
    /// the line's transactions.
    pub fn pendant(&mut self) -> Pendant {
        let (pendant, inbox) = Pendant::channel();
        self.set_pendant(inbox);
        pendant
    }

    /// Take requests from a pendant made before ([`Pendant::channel`]).
    pub fn set_pendant(&mut self, inbox: PendantInbox) {
        self.pendant = Some(inbox);
    }

    /// Run what the pendant asked for since the last step, each logged as from the pendant.
    fn serve_pendant(&mut self) {
        let Some(rx) = &self.pendant else {
            return;
        };
        let calls: Vec<PendantCall> = rx.0.try_iter().collect();
        for (request, follow, back) in calls {
            let mut reply = self.run_aside(&request);
            let mut followed = false;
            if let Some(next) = follow.and_then(|f| f(&reply)) {
                reply = self.run_aside(&next);
                followed = true;
            }
            let _ = back.try_send((reply, followed));
        }
    }

    /// Run one pendant request, logged as from the pendant.
    fn run_aside(&mut self, request: &[u8]) -> Vec<u8> {
        let reply = self.pcp.handle_aside(request);
        self.pcp.backend_mut().after_request();
        if let Some(log) = self.log.as_mut() {
            let world = self.pcp.backend_mut().world();
            let note = self.pcp.take_note();
            log(&LogEntry {
                catalog: self.pcp.catalog(),
                request,
                reply: &reply,
                event: ServerEvent::Executed,
                executed: true,
                from_pendant: true,
                world,
                note,
            });
        }
        reply
    }

    /// Have the backend report its arm ([`Backend::report`]) at most every `every`, between
    /// requests and during long waits, into the returned slot (a view reads it).
    pub fn share_reports(&mut self, every: Duration) -> SharedReport {
        let slot = SharedReport::default();
        self.report_into(slot.clone(), every);
        slot
    }

    /// Like [`Controller::share_reports`], into a slot made before (a view already
    /// serving it).
    pub fn report_into(&mut self, slot: SharedReport, every: Duration) {
        self.reports = Some((slot, every, Instant::now() - every));
        // A view served before the controller runs has the arm at once where that is free.
        if self.pcp.backend().report_is_free() {
            self.refresh_report_now();
        }
    }

    /// How long one [`Controller::step`] of a serving loop should wait on a quiet line: 50
    /// ms, and no longer than the interval of a view's reports, which are renewed while the
    /// line is quiet.
    pub fn slice(&self) -> Duration {
        let most = Duration::from_millis(50);
        match &self.reports {
            Some((_, every, _)) => (*every).clamp(POLL, most),
            None => most,
        }
    }

    fn refresh_report(&mut self) {
        let Some((slot, every, last)) = &self.reports else {
            return;
        };
        if last.elapsed() < *every || !slot.wanted() {
            return;
        }
        self.refresh_report_now();
    }

    /// Renew the report now, whenever it was renewed last.
    fn refresh_report_now(&mut self) {
        let Some((slot, _, last)) = &mut self.reports else {
            return;
        };
        *last = Instant::now();
        let slot = slot.clone();
        if let Some(r) = self.pcp.backend_mut().report() {
            slot.put(r);
        }
    }

    /// The watchdog's trip since the last call, if it halted the arm (for logs).
    pub fn take_watchdog_trip(&mut self) -> Option<WatchdogTrip> {
        self.trip.take()
    }

    /// The watchdog (SetWatchdog): once no transaction has arrived for its limit, halt the
    /// arm, once, until the next transaction.
    fn watch(&mut self) {
        let Some(limit) = self.pcp.watchdog() else {
            return;
        };
        if !self.tripped && self.last_seen.elapsed() >= limit {
            self.tripped = true;
            let halt = self.pcp.backend_mut().halt().map_err(|e| e.to_string());
            self.pcp.halted_by_someone_else();
            self.pcp.backend_mut().after_request();
            self.trip = Some(WatchdogTrip { after: limit, halt });
        }
    }

    /// Log each request.
    pub fn set_log(&mut self, log: LogFn) {
        self.log = Some(log);
    }

    /// Speak only the manual's protocol, as a controller with the 1998 PCP server does (the
    /// simulated 1998 controller, `trol sim --manual`): only the bare `PCP TROL` activates,
    /// the added commands are unknown, GetStatus has the manual's 4 bytes, and layer 3 has no
    /// memory (a repeated request runs again) and numbers its replies as `pci` says.
    pub fn speak_manual_only(&mut self, pci: trol_proto::transaction::ManualLayer3) {
        self.terminal = Terminal::manual_only();
        self.pcp.set_manual_only(true);
        self.server.responder_mut().set_manual(Some(pci));
        // The 1998 server said nothing while it worked.
        let _ = self.server.set_keepalive(None);
        // The 1998 server checked nothing beyond the sum.
        self.server.responder_mut().set_request_check(None);
    }

    /// Take `pause` to start the server after answering the activation line, as a 1998
    /// controller whose PCP takes a moment to come up may: whatever arrives meanwhile is
    /// lost, as it would be on a line nobody reads yet (issue 67: the host's first ENQ
    /// must be tried again). For the simulated 1998 controller; 0 (the default) serves at once.
    pub fn set_start_pause(&mut self, pause: Duration) {
        self.start_pause = pause;
    }

    /// Keep the last call in the journal at `path` (`trol gateway --journal FILE`), and go on
    /// from what it holds: the epoch, GetStatus's record and the exactly-once memory of a
    /// controller before this one on the same arm (docs/reliability.md, "Exactly once").
    /// Returns what was restored, for the log. Each CAT1/CAT2 request of the line is
    /// journaled before it runs and once its reply is settled; a journal that cannot be
    /// written then stops the controller's serving with that error (it would otherwise lie
    /// after the next restart).
    pub fn set_journal(&mut self, path: &std::path::Path) -> std::io::Result<Option<String>> {
        let (journal, restored) = crate::journal::Journal::open(path)?;
        let said = restored.map(|r| {
            self.pcp.restore(r.epoch, r.status);
            self.server
                .responder_mut()
                .remember(r.memory.0, r.memory.1.clone());
            r.to_string()
        });
        self.journal = Some(journal);
        Ok(said)
    }

    /// The reply of the request being journaled is settled: journal it as done.
    fn journal_done(&mut self, reply: &[u8]) -> std::io::Result<()> {
        if !std::mem::take(&mut self.journaling) {
            return Ok(());
        }
        match self.journal.as_mut() {
            Some(j) => j.done(self.pcp.epoch(), self.pcp.status(), reply),
            None => Ok(()),
        }
    }

    /// The mode.
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// The block check the link uses now (the activation line may have changed it).
    pub fn check(&mut self) -> trol_proto::link::BlockCheck {
        self.server.responder_mut().link_mut().config().check
    }

    /// The PCP server.
    pub fn pcp_mut(&mut self) -> &mut Pcp<B> {
        &mut self.pcp
    }

    /// Run one step: serve for at most `slice` in the current mode.
    pub fn step(&mut self, slice: Duration) -> std::io::Result<()> {
        self.serve_pendant();
        match self.mode {
            Mode::Terminal => {
                let port = self.server.driver_mut().port_mut();
                let mut buf = [0u8; 256];
                let n = port.recv(&mut buf, Instant::now() + slice)?;
                let mut out = Vec::new();
                let activated = self.terminal.feed(&buf[..n], &mut out);
                if !out.is_empty() {
                    port.send(&out)?;
                }
                if let Some(activation) = activated {
                    port.flush_input()?;
                    // The block check the activation line agreed on.
                    let link = self.server.responder_mut().link_mut();
                    let cfg = LinkConfig {
                        check: activation.check(),
                        ..*link.config()
                    };
                    link.set_config(cfg);
                    // TROL's worded line says the host numbers its requests (so a number
                    // seen twice is a repeat); a 1998 host's bare line says nothing of it.
                    self.server
                        .responder_mut()
                        .set_numbered_host(activation != crate::terminal::Activation::Manual);
                    self.check_requests();
                    // A 1998 host (the bare line) gets the manual's record sizes.
                    self.pcp
                        .set_manual_host(activation == crate::terminal::Activation::Manual);
                    self.mode = Mode::Server;
                    self.last_seen = Instant::now();
                    self.starting_until =
                        (!self.start_pause.is_zero()).then(|| Instant::now() + self.start_pause);
                } else if n == 0 {
                    // Quiet in terminal mode: a view still follows the arm.
                    self.refresh_report();
                }
            }
            Mode::Server if self.starting_until.is_some_and(|t| Instant::now() < t) => {
                // Still starting: nothing reads the line yet, so what arrives is lost.
                let until = self.starting_until.unwrap_or_else(Instant::now);
                let port = self.server.driver_mut().port_mut();
                let mut buf = [0u8; 256];
                let _ = port.recv(&mut buf, until.min(Instant::now() + slice))?;
            }
            Mode::Server => {
                if self.starting_until.take().is_some() {
                    self.server.driver_mut().port_mut().flush_input()?;
                }
                let ev = match self.serve_one(slice) {
                    Ok(Some(ev)) => ev,
                    Ok(None) => return Ok(()),
                    Err(e) => {
                        // The port failed under a request that ran: its log entry still
                        // comes, so that the log holds every execution.
                        if self.ran {
                            self.log_transaction(ServerEvent::ReplyFailed(LinkError::Send(
                                SendError::Port,
                            )));
                        }
                        return Err(e);
                    }
                };
                // A request refused unrun (a repeat this controller cannot place, or the
                // LRC's duplicate): the log names it and its answer, not the one before.
                if matches!(
                    ev,
                    ServerEvent::UnknownRepeat | ServerEvent::SuspectDuplicate
                ) {
                    self.last = (
                        self.server.request().to_vec(),
                        trol_proto::application::Reply::Code(
                            trol_proto::application::code::TROL_ERR_ROBOT_UNSURE,
                        )
                        .encode(),
                    );
                }
                // A request that arrived whole feeds the watchdog; noise on the line does not.
                if !matches!(ev, ServerEvent::Idle | ServerEvent::ReceiveFailed(_)) || self.ran {
                    self.last_seen = Instant::now();
                    self.tripped = false;
                }
                self.watch();
                if matches!(ev, ServerEvent::Idle) {
                    self.pcp.backend_mut().idle();
                    self.refresh_report();
                }
                if !matches!(ev, ServerEvent::Idle | ServerEvent::Pending) {
                    let watched = self.reports.as_ref().is_some_and(|(s, _, _)| s.wanted());
                    if watched && self.pcp.backend().report_is_free() {
                        self.refresh_report_now();
                    }
                    self.log_transaction(ev);
                }
                if self.pcp.take_terminate() {
                    self.mode = Mode::Terminal;
                    self.server
                        .driver_mut()
                        .port_mut()
                        .send(PROMPT.as_bytes())?;
                }
            }
        }
        Ok(())
    }

    /// Serve one transaction's worth in server mode: its event, or `None` while a long
    /// call is still under way.
    fn serve_one(&mut self, slice: Duration) -> std::io::Result<Option<ServerEvent>> {
        if self.pcp.is_pending() {
            // A long call: ask the backend between short waits on the line, so the thread
            // never sleeps inside the backend.
            let Some(reply) = self.pcp.poll() else {
                // A long call under way counts as a transaction for the watchdog.
                self.last_seen = Instant::now();
                self.refresh_report();
                self.server.wait(POLL.min(slice))?;
                return Ok(None);
            };
            // The deferred reply goes out; serving below ends its transaction (a request
            // that arrived meanwhile is run as any other, never answered blindly). What the
            // call changed is shared first: whoever reads the arm after the reply sees it.
            self.pcp.backend_mut().after_request();
            self.journal_done(&reply)?;
            self.server.respond(&reply);
            self.last.1 = reply;
        }
        self.pcp.set_keepalive(self.server.keepalive_for_host());
        let pcp = &mut self.pcp;
        let last = &mut self.last;
        let ran = &mut self.ran;
        let journal = &mut self.journal;
        let journaling = &mut self.journaling;
        let mut failed = None;
        let event = self.server.serve_deferrable(slice, &mut |req, pci| {
            last.0 = req.to_vec();
            last.1.clear();
            let number = trol_proto::transaction::pci_number(pci);
            // A CAT1/CAT2 request may run from here on: the journal says so first.
            if let Some(j) = journal
                .as_mut()
                .filter(|_| req.first().is_some_and(|c| *c < 128))
            {
                if let Err(e) = j.running(pcp.epoch(), number) {
                    failed = Some(e);
                    return Some(
                        trol_proto::application::Reply::Code(
                            trol_proto::application::code::TROL_ERR_ROBOT,
                        )
                        .encode(),
                    );
                }
                *journaling = true;
            }
            *ran = true;
            pcp.set_transaction(number);
            let handled = pcp.handle(req);
            // What the call changed is shared before its reply leaves: whoever reads the
            // arm after the reply (a test, a view) sees it.
            pcp.backend_mut().after_request();
            match handled {
                Handled::Reply(reply) => {
                    if std::mem::take(journaling) {
                        if let Some(j) = journal.as_mut() {
                            if let Err(e) = j.done(pcp.epoch(), pcp.status(), &reply) {
                                failed = Some(e);
                            }
                        }
                    }
                    last.1 = reply.clone();
                    Some(reply)
                }
                Handled::Pending => None,
            }
        });
        if let Some(e) = failed {
            let path = self
                .journal
                .as_ref()
                .map(|j| j.path().display().to_string());
            return Err(std::io::Error::new(
                e.kind(),
                format!(
                    "the journal {} cannot be written ({e}): serving stops, since after a \
                     restart it could not say whether the last call ran",
                    path.unwrap_or_default()
                ),
            ));
        }
        event.map(Some)
    }

    /// Tell the log hook how the transaction ended (whether its request ran included).
    fn log_transaction(&mut self, event: ServerEvent) {
        let executed = std::mem::take(&mut self.ran);
        if let Some(log) = self.log.as_mut() {
            let world = self.pcp.backend_mut().world();
            let note = self.pcp.take_note();
            log(&LogEntry {
                catalog: self.pcp.catalog(),
                request: &self.last.0,
                reply: &self.last.1,
                event,
                executed,
                from_pendant: false,
                world,
                note,
            });
        }
    }

    /// Run until `stop` is set.
    pub fn run(&mut self, stop: &AtomicBool) -> std::io::Result<()> {
        let slice = self.slice();
        while !stop.load(Ordering::Relaxed) {
            self.step(slice)?;
        }
        Ok(())
    }
}

/// An embedded controller on a thread; stops and joins when dropped.
pub struct Embedded {
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
    world: Arc<std::sync::Mutex<Option<String>>>,
}

impl Embedded {
    /// Run `controller` on a thread of its own. Its log hook is taken over to keep the
    /// backend's last word on its world ([`Embedded::world`]).
    pub fn spawn<P: Port + 'static, B: Backend + 'static>(
        mut controller: Controller<P, B>,
    ) -> Embedded {
        let world = Arc::new(std::sync::Mutex::new(None));
        let keep = world.clone();
        controller.set_log(Box::new(move |e| {
            if let Ok(mut w) = keep.lock() {
                w.clone_from(&e.world);
            }
        }));
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let thread = std::thread::Builder::new()
            .name("trol-controller".into())
            .spawn(move || {
                // A failing in-memory line means the host end is gone: stop quietly.
                let _ = controller.run(&flag);
            })
            .expect("spawn the controller thread");
        Embedded {
            stop,
            thread: Some(thread),
            world,
        }
    }

    /// Where the backend's world objects were after the last transaction (a simulator's).
    pub fn world(&self) -> Option<String> {
        self.world.lock().ok().and_then(|w| w.clone())
    }
}

impl Drop for Embedded {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl<P, B: Backend> std::fmt::Debug for Controller<P, B> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Controller")
            .field("server", &self.server)
            .field("pcp", &self.pcp)
            .field("mode", &self.mode)
            .finish_non_exhaustive()
    }
}

impl std::fmt::Debug for Embedded {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Embedded")
            .field("running", &self.thread.is_some())
            .finish_non_exhaustive()
    }
}

//! `trol bench transact` and `trol bench link`: transactions and the link over paced
//! lines, with the line's own limit as the anchor.

use super::*;

#[derive(Serialize)]
pub(super) struct TransactReport {
    pub(super) port: String,
    pub(super) transactions: u32,
    pub(super) seconds: f64,
    pub(super) us_per_transaction: f64,
    pub(super) transactions_per_second: f64,
    /// Over a paced line (`--paced`): its baud rate, the bytes of one transaction (both
    /// directions), the time those bytes take on the line, and that time's share of the
    /// measured one.
    pub(super) baud: Option<u32>,
    pub(super) bytes_per_transaction: Option<f64>,
    pub(super) line_limit_us: Option<f64>,
    pub(super) share_of_line_limit: Option<f64>,
}

/// A port that counts the bytes both ways.
pub(super) struct Counted<P> {
    pub(super) inner: P,
    pub(super) bytes: std::sync::Arc<std::sync::atomic::AtomicU64>,
}

impl<P: trol_port::Port> trol_port::Port for Counted<P> {
    fn send(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.bytes
            .fetch_add(bytes.len() as u64, std::sync::atomic::Ordering::Relaxed);
        self.inner.send(bytes)
    }
    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> std::io::Result<usize> {
        let n = self.inner.recv(buf, deadline)?;
        self.bytes
            .fetch_add(n as u64, std::sync::atomic::Ordering::Relaxed);
        Ok(n)
    }
    fn available(&mut self) -> std::io::Result<usize> {
        self.inner.available()
    }
    fn flush_input(&mut self) -> std::io::Result<()> {
        self.inner.flush_input()
    }
    fn name(&self) -> String {
        self.inner.name()
    }
}

/// The simulator over an in-memory line paced at `baud`, with the host's bytes counted.
pub(super) fn paced_robot(
    baud: u32,
) -> Result<(trol::Robot, std::sync::Arc<std::sync::atomic::AtomicU64>), String> {
    paced_robot_with(baud, trol_sim::SimSettings::default())
}

/// [`paced_robot`] with the simulator's `settings`.
pub(super) fn paced_robot_with(
    baud: u32,
    settings: trol_sim::SimSettings,
) -> Result<(trol::Robot, std::sync::Arc<std::sync::atomic::AtomicU64>), String> {
    use trol_controller::{Controller, Embedded, Mode, Pcp};
    let (host, ctl) = memory::pair(Some(baud));
    let cfg = LinkConfig::for_line(baud, Duration::ZERO);
    let controller = Controller::new(
        ctl,
        cfg,
        Pcp::new(trol_sim::SimBackend::new(settings)),
        Mode::Server,
    );
    let handle = Embedded::spawn(controller);
    let bytes = std::sync::Arc::new(std::sync::atomic::AtomicU64::new(0));
    let port = Counted {
        inner: host,
        bytes: bytes.clone(),
    };
    let mut robot = trol::Robot::over(Box::new(port), cfg, None);
    robot.keep(handle);
    trol::check_server(&mut robot).map_err(|e| e.to_string())?;
    Ok((robot, bytes))
}

pub(super) fn transact(a: TransactArgs) -> Result<(), String> {
    let (mut robot, port, counted) = match a.paced {
        Some(baud) => {
            let (robot, bytes) = paced_robot(baud)?;
            (
                robot,
                format!("sim over a line paced at {baud} baud"),
                Some(bytes),
            )
        }
        None => {
            let (robot, cfg) = a.conn.robot()?;
            (robot, cfg.port, None)
        }
    };
    // One to warm up (the first transaction on a line pays for its set-up).
    robot.speed(100).map_err(|e| e.to_string())?;
    let before = counted
        .as_ref()
        .map_or(0, |b| b.load(std::sync::atomic::Ordering::Relaxed));
    let started = Instant::now();
    for _ in 0..a.count {
        robot.speed(100).map_err(|e| e.to_string())?;
    }
    let seconds = started.elapsed().as_secs_f64();
    let us = seconds * 1e6 / f64::from(a.count);
    let bytes = counted.map(|b| {
        (b.load(std::sync::atomic::Ordering::Relaxed) - before) as f64 / f64::from(a.count)
    });
    let limit = a
        .paced
        .zip(bytes)
        .map(|(baud, n)| n * 10.0 / f64::from(baud) * 1e6);
    let r = TransactReport {
        port,
        transactions: a.count,
        seconds,
        us_per_transaction: us,
        transactions_per_second: f64::from(a.count) / seconds,
        baud: a.paced,
        bytes_per_transaction: bytes,
        line_limit_us: limit,
        share_of_line_limit: limit.map(|l| l / us),
    };
    print_report(&r, a.json, |r| {
        let mut t = format!(
            "{} transactions on {}: {:.1} us each, {:.0} per second",
            r.transactions, r.port, r.us_per_transaction, r.transactions_per_second
        );
        if let (Some(n), Some(l), Some(share)) = (
            r.bytes_per_transaction,
            r.line_limit_us,
            r.share_of_line_limit,
        ) {
            t += &format!(
                "\n{n:.1} bytes per transaction on the line: {l:.1} us of line time, {:.1} % \
                 of the line's limit",
                share * 100.0
            );
        }
        t
    })
}

#[derive(Serialize)]
pub(super) struct LinkReport {
    pub(super) baud: u32,
    pub(super) payload_bytes: usize,
    pub(super) wire_bytes: u64,
    pub(super) seconds: f64,
    pub(super) line_seconds: f64,
    pub(super) efficiency: f64,
    pub(super) format_efficiency: f64,
    pub(super) frame_size: usize,
    pub(super) payload_bytes_per_second: f64,
}

pub(super) fn link(a: LinkArgs) -> Result<(), String> {
    let len = a.bytes as usize;
    debug_assert!(len <= MAX_MESSAGE);
    let message: Vec<u8> = (0..len).map(|i| (i * 131 + 7) as u8).collect();
    let cfg = LinkConfig::for_line(a.baud, Duration::ZERO);
    let mut best: Option<LinkReport> = None;
    // What it does and how long it will take, before the silence of a paced line.
    let line_s = frame::wire_bytes_for(len) as f64 * 10.0 / f64::from(a.baud);
    eprintln!(
        "trol bench link: {len} bytes at {} baud, {} time(s): about {:.1} s of line time each",
        a.baud, a.repeat, line_s
    );
    for round in 0..a.repeat {
        if a.repeat > 1 {
            eprintln!("  round {} of {}", round + 1, a.repeat);
        }
        let (tx, rx) = memory::pair(Some(a.baud));
        let receiver = std::thread::spawn(move || {
            let mut driver = Driver::new(rx);
            let mut link = Link::new(cfg);
            receive_data(&mut driver, &mut link, Duration::from_secs(30))
                .map(|(_, data)| data)
                .map_err(|e| e.to_string())
        });
        let mut driver = Driver::new(tx);
        let mut link = Link::new(cfg);
        let started = Instant::now();
        send_data(&mut driver, &mut link, &message, 0).map_err(|e| e.to_string())?;
        let received = receiver.join().map_err(|_| "receiver thread failed")??;
        let seconds = started.elapsed().as_secs_f64();
        if received != message {
            return Err("the message arrived damaged".into());
        }
        let line = driver.port().stats();
        let wire = line.total();
        let report = LinkReport {
            baud: a.baud,
            payload_bytes: len,
            wire_bytes: wire,
            seconds,
            line_seconds: wire as f64 * 10.0 / f64::from(a.baud),
            efficiency: if wire == 0 {
                0.0
            } else {
                len as f64 / wire as f64
            },
            format_efficiency: len as f64 / frame::wire_bytes_for(len) as f64,
            frame_size: FRAME_SIZE,
            payload_bytes_per_second: len as f64 / seconds,
        };
        if best.as_ref().is_none_or(|b| report.seconds < b.seconds) {
            best = Some(report);
        }
    }
    let r = best.ok_or("no run")?;
    print_report(&r, a.json, |r| {
        format!(
            "{} payload bytes at {} baud: {} bytes on the line, {:.3} s ({:.3} s of line time), \
                 efficiency {:.2} % (frame format allows {:.2} %), {:.0} payload bytes/s",
            r.payload_bytes,
            r.baud,
            r.wire_bytes,
            r.seconds,
            r.line_seconds,
            r.efficiency * 100.0,
            r.format_efficiency * 100.0,
            r.payload_bytes_per_second
        )
    })
}

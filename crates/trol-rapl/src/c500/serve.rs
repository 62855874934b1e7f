//! The simulated C500 on a port, paced at its baud rate (`trol sim --rapl`).

use super::*;

/// Serve the simulated C500 on `port` until `stop` is set or the line fails: input is fed at
/// the simulation time (wall time × `time_scale`), output goes out paced at the profile's
/// baud rate (10 bits a byte). `log` gets each command line the controller ran.
pub fn serve(
    port: &mut dyn trol_port::Port,
    c: &mut C500,
    time_scale: f64,
    stop: &std::sync::atomic::AtomicBool,
    log: &mut dyn FnMut(&str),
) -> std::io::Result<()> {
    serve_with(port, c, time_scale, stop, log, &mut |_, _| {})
}

/// Like [`serve`], calling `each` with the controller and the simulation time on every turn
/// of the loop (at least every 2 ms): the teach pendant of `trol sim --rapl --pendant`, and
/// measurements that watch the arm.
pub fn serve_with(
    port: &mut dyn trol_port::Port,
    c: &mut C500,
    time_scale: f64,
    stop: &std::sync::atomic::AtomicBool,
    log: &mut dyn FnMut(&str),
    each: &mut dyn FnMut(&mut C500, f64),
) -> std::io::Result<()> {
    use std::time::{Duration, Instant};
    let epoch = Instant::now();
    let scale = time_scale.max(1e-3);
    let char_time = c.profile.char_time();
    let mut next_free = Instant::now();
    let mut buf = [0u8; 256];
    while !stop.load(std::sync::atomic::Ordering::Relaxed) {
        let wait = if c.has_output() {
            next_free.saturating_duration_since(Instant::now())
        } else {
            Duration::from_millis(2)
        };
        let n = port.recv(&mut buf, Instant::now() + wait)?;
        let now = epoch.elapsed().as_secs_f64() * scale;
        if n > 0 {
            c.feed(&buf[..n], now);
        }
        c.tick(now);
        each(c, now);
        for line in c.take_log() {
            log(&line);
        }
        let t = Instant::now();
        if next_free < t {
            next_free = t;
        }
        if c.has_output() && next_free <= t + char_time {
            // As many bytes as the line carries in a millisecond, at least one.
            let burst =
                (Duration::from_millis(1).as_nanos() / char_time.as_nanos().max(1)).max(1) as usize;
            let out = c.take_output(burst);
            port.send(&out)?;
            next_free += char_time * out.len() as u32;
        }
    }
    Ok(())
}

//! First contact with a C500C that only reads (`trol c500c probe`; docs/c500c.md): Ctrl-E and
//! two CR, `crosver` at the system shell, `ash <app>` where it does not run yet, then
//! `robotver`, `armstat`, `w0`, `w2` and `speed`, and `exit` (answered `y`) only where the
//! probe started ash itself, so the controller is left as it was found. Nothing that moves the
//! arm or changes a setting is sent, and every byte both ways is recorded.

use std::time::{Duration, Instant};

use trol_port::Port;

use crate::console::{Console, Said};
use crate::reports;

/// Every byte both ways, in order (the shared core's).
pub use trol_controller::real::Transcript;

/// What first contact found.
#[derive(Debug, Default)]
pub struct Contact {
    /// Per command: the lines it printed before the prompt, or why there are none.
    pub steps: Vec<(String, Result<Vec<String>, String>)>,
    /// Every byte both ways.
    pub transcript: Transcript,
    /// What the answers say, read exactly (each a line for the person at the console).
    pub findings: Vec<String>,
}

/// The reads first contact makes in ash, in order.
pub const READS: [&str; 5] = ["robotver", "armstat", "w0", "w2", "speed"];

struct Probe<'a> {
    port: &'a mut dyn Port,
    console: Console,
    contact: Contact,
    wait: Duration,
}

impl Probe<'_> {
    fn send(&mut self, bytes: &[u8]) -> Result<(), String> {
        self.contact.transcript.chunks.push((true, bytes.to_vec()));
        self.port
            .send(bytes)
            .map_err(|e| format!("the line failed: {e}"))
    }

    /// What the console says until a prompt (or a question), or `wait` passes.
    fn read(&mut self, quiet_after_prompt: bool) -> Result<(Vec<String>, Option<Said>), String> {
        let deadline = Instant::now() + self.wait;
        let mut lines = Vec::new();
        let mut last = None;
        let mut buf = [0u8; 512];
        loop {
            let until = match &last {
                // A quiet console after its prompt: one per CR sent.
                Some(_) if quiet_after_prompt => Instant::now() + crate::backend::CONNECT_QUIET,
                Some(_) => return Ok((lines, last)),
                None => deadline,
            };
            let n = self
                .port
                .recv(&mut buf, until.min(deadline.max(Instant::now())))
                .map_err(|e| format!("the line failed: {e}"))?;
            if n == 0 {
                return Ok((lines, last));
            }
            self.contact
                .transcript
                .chunks
                .push((false, buf[..n].to_vec()));
            for s in self.console.feed(&buf[..n]) {
                match s {
                    Said::Line(l) => lines.push(l),
                    other => last = Some(other),
                }
            }
        }
    }

    /// Type `cmd` and read to ash's (or the shell's) prompt; the echo taken off.
    fn step(&mut self, cmd: &str) -> Result<(Vec<String>, Option<Said>), String> {
        self.send(format!("{cmd}\r").as_bytes())?;
        let (mut lines, end) = self.read(false)?;
        if lines.first().is_some_and(|l| l.trim_end() == cmd) {
            lines.remove(0);
        }
        Ok((lines, end))
    }

    fn record(&mut self, cmd: &str, r: Result<Vec<String>, String>) {
        self.contact.steps.push((cmd.to_string(), r));
    }
}

/// First contact: read the controller, move nothing, change nothing. `app` is the ash
/// application to read through (`test`, the factory one); `wait` bounds each answer.
pub fn first_contact(port: &mut dyn Port, app: &str, wait: Duration) -> Contact {
    let mut p = Probe {
        port,
        console: Console::default(),
        contact: Contact::default(),
        wait,
    };
    let found = (|| -> Result<(), String> {
        p.send(b"\x05\r\r")?;
        let (before, end) = p.read(true)?;
        let shell = match end {
            Some(Said::Prompt(s)) => s,
            Some(Said::Question(q)) => {
                return Err(format!(
                    "the console waits for an answer to `{q}`: answer it at a terminal first"
                ));
            }
            _ => {
                return Err(format!(
                    "no prompt within {wait:?} after Ctrl-E and two CR: check the cable (the \
                     front console), the baud rate (57600, 8N1) and that the controller has \
                     booted{}",
                    if before.is_empty() {
                        String::new()
                    } else {
                        format!("; it printed {:?}", before)
                    }
                ));
            }
        };
        p.contact
            .findings
            .push(format!("at first contact the console runs `{shell}`"));
        let mut started = false;
        if shell == "$" {
            let (lines, _) = p.step("crosver")?;
            p.record("crosver", Ok(lines.clone()));
            if let Some(l) = lines.iter().find(|l| l.starts_with("System type:")) {
                p.contact.findings.push(l.clone());
            }
            let cmd = format!("ash {app}");
            let (mut lines, mut end) = p.step(&cmd)?;
            // A system shell's prompt still on its way (one per CR sent) comes before ash's.
            while end == Some(Said::Prompt("$".into())) {
                let (more, next) = p.read(false)?;
                lines.extend(more);
                end = next;
            }
            p.record(&cmd, Ok(lines.clone()));
            if lines.iter().any(|l| l.contains("shut down the pendant")) {
                p.contact.findings.push(
                    "the pendant holds the point of control: press <SHIFT><ESC> on the pendant \
                     keyboard before the first motion"
                        .into(),
                );
            }
            match end {
                Some(Said::Prompt(a)) if a == app => started = true,
                other => return Err(format!("`{cmd}` did not give ash's prompt: {other:?}")),
            }
        } else if shell != app {
            return Err(format!(
                "ash runs the application `{shell}`, not `{app}`: give --app {shell}"
            ));
        }
        for cmd in READS {
            let r = p.step(cmd).and_then(|(lines, end)| match end {
                Some(Said::Prompt(a)) if a == app => Ok(lines),
                other => Err(format!("no prompt after `{cmd}`: {other:?} ({lines:?})")),
            });
            if let Ok(lines) = &r {
                let finding = match cmd {
                    "robotver" => reports::robotver(lines).map(|v| format!("robot version {v}")),
                    "armstat" => reports::armstat(lines).map(|s| {
                        format!(
                            "an {} arm, power {}, {:?}, units {}, online {}",
                            s.arm,
                            if s.power { "on" } else { "off" },
                            s.homing,
                            if s.metric { "metric" } else { "imperial" },
                            if s.online { "on" } else { "off" }
                        )
                    }),
                    "w2" => reports::position(lines, true)
                        .map(|p| format!("the arm stands at joints {:?} degrees", p.joints_deg)),
                    "w0" => reports::position(lines, false)
                        .map(|p| format!("commanded joints {:?} degrees", p.joints_deg)),
                    _ => reports::speed(lines).map(|s| format!("speed {s} %")),
                };
                p.contact.findings.push(match finding {
                    Ok(f) => f,
                    Err(e) => format!("{e}: tell TROL's maintainers (the transcript has it)"),
                });
            }
            let failed = r.is_err();
            p.record(cmd, r);
            if failed {
                break;
            }
        }
        if started {
            // Leave the controller as it was found: back to the system shell.
            let (lines, end) = p.step("exit")?;
            match end {
                Some(Said::Question(q)) if q.contains("exit") => {
                    let (more, _) = p.step("y")?;
                    p.record("exit", Ok([lines, vec![q], more].concat()));
                }
                other => p.record("exit", Err(format!("no question after exit: {other:?}"))),
            }
        }
        Ok(())
    })();
    if let Err(e) = found {
        p.contact.findings.push(format!("stopped: {e}"));
    }
    p.contact
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::c500c::{C500c, Switches, serve};
    use std::sync::atomic::AtomicBool;
    use std::sync::{Arc, Mutex};

    #[test]
    fn it_reads_and_leaves_the_controller_in_the_system_shell() {
        let (mut host, ctl) = trol_port::memory::pair(None);
        let unit = Arc::new(Mutex::new(C500c::new(Switches::default(), false, 10.0)));
        let stop = Arc::new(AtomicBool::new(false));
        let t = {
            let (unit, stop) = (unit.clone(), stop.clone());
            std::thread::spawn(move || serve(Box::new(ctl), unit, stop))
        };
        let c = first_contact(&mut host, "test", Duration::from_secs(3));
        stop.store(true, std::sync::atomic::Ordering::Relaxed);
        let _ = t.join();
        let typed = unit.lock().unwrap().received().to_vec();
        let moving = [
            "joint", "home", "ready", "move", "speed ", "armpower", "limp",
        ];
        assert!(
            !typed
                .iter()
                .any(|l| moving.iter().any(|m| l.starts_with(m))),
            "{typed:?}"
        );
        assert_eq!(typed.last().map(String::as_str), Some("y"), "{typed:?}");
        let f = c.findings.join("\n");
        assert!(f.contains("an A465 arm, power on, NotHomed"), "{f}");
        assert!(f.contains("System type: 'CROS-104 on a C500C'"), "{f}");
        assert!(
            c.transcript.text().contains("> w2\\x0d"),
            "{}",
            c.transcript.text()
        );
        assert!(!f.contains("stopped"), "{f}");
    }

    #[test]
    fn a_silent_line_is_said_with_what_to_check_and_recorded() {
        let (mut host, _ctl) = trol_port::memory::pair(None);
        let c = first_contact(&mut host, "test", Duration::from_millis(300));
        assert!(
            c.findings.last().unwrap().contains("check the cable"),
            "{:?}",
            c.findings
        );
        assert!(c.transcript.text().starts_with("> \\x05\\x0d\\x0d"));
    }
}

//! Helpers of the tests of the built `trol` binary.

#![allow(dead_code)]

use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

pub const TROL: &str = env!("CARGO_BIN_EXE_trol");

/// A scratch folder of this call's own, without a trol.cfg (so the port is `sim`). Each call
/// gets a new folder: tests run in parallel, and two that asked for the same name must not
/// remove each other's folder (a program started in a folder that was just removed fails).
pub fn scratch(name: &str) -> PathBuf {
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir =
        std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("trol-cli-{name}-{n}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

pub fn trol(dir: &Path, args: &[&str], stdin: &str) -> Output {
    let mut child = Command::new(TROL)
        .args(args)
        .current_dir(dir)
        .env_remove("TROL_CONFIG")
        .env_remove("RUST_LOG")
        // Messages whole, as to a pipe, whatever the shell exports (COLUMNS wraps them).
        .env_remove("COLUMNS")
        // Every notice at every start: the output does not depend on the cache folder.
        .env("TROL_VERBOSE", "1")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start trol");
    // A program that stops before reading its input (a bad trol.cfg) closes the pipe: what
    // it did not read does not matter, and the test reads its output and status.
    if let Err(e) = child.stdin.take().unwrap().write_all(stdin.as_bytes()) {
        assert_eq!(e.kind(), std::io::ErrorKind::BrokenPipe, "{e}");
    }
    child.wait_with_output().unwrap()
}

pub fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// A background `trol` process, killed when dropped; its first line of output names where
/// it serves (`... serving on NAME` / `... applications use NAME`).
pub struct Background {
    child: Child,
    pub name: String,
    lines: std::sync::mpsc::Receiver<String>,
    input: Option<std::process::ChildStdin>,
}

/// `trol gateway` in front of the simulated C500 on `controller`, with the profile in
/// `dir`/c500.toml and `extra` flags (`--server`, `--view`, ...).
#[allow(dead_code)]
pub fn c500_gateway(dir: &Path, controller: &str, extra: &[&str]) -> Background {
    let mut args = vec![
        "gateway",
        "--controller",
        controller,
        "--profile",
        "c500.toml",
    ];
    args.extend_from_slice(extra);
    Background::start(dir, &args, "serving on ")
}

impl Background {
    pub fn start(dir: &Path, args: &[&str], marker: &str) -> Background {
        Background::start_program(TROL, dir, args, marker)
    }

    /// Like [`Background::start`], for any program.
    pub fn start_program(
        program: impl AsRef<std::ffi::OsStr>,
        dir: &Path,
        args: &[&str],
        marker: &str,
    ) -> Background {
        Background::start_program_within(program, dir, args, marker, 20)
    }

    /// Like [`Background::start_program`], waiting up to `secs` seconds for `marker`.
    pub fn start_program_within(
        program: impl AsRef<std::ffi::OsStr>,
        dir: &Path,
        args: &[&str],
        marker: &str,
        secs: u64,
    ) -> Background {
        let mut child = Command::new(program)
            .args(args)
            .current_dir(dir)
            .env_remove("TROL_CONFIG")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("start the program");
        let input = child.stdin.take();
        let out = BufReader::new(child.stdout.take().unwrap());
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            for line in out.lines() {
                let Ok(line) = line else { break };
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        let deadline = Instant::now() + Duration::from_secs(secs);
        let name = loop {
            let left = deadline.saturating_duration_since(Instant::now());
            let Ok(line) = rx.recv_timeout(left) else {
                break None;
            };
            if let Some(i) = line.find(marker) {
                break line[i + marker.len()..]
                    .split_whitespace()
                    .next()
                    .map(|n| n.trim_end_matches(')').to_string());
            }
        };
        let Some(name) = name else {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{args:?} did not say `{marker}` within {secs} s");
        };
        Background {
            child,
            name,
            lines: rx,
            input,
        }
    }

    /// The process's id (to freeze it with SIGSTOP, as a hung controller).
    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// The output lines so far.
    pub fn output(&self) -> Vec<String> {
        self.lines.try_iter().collect()
    }

    /// The output lines not taken yet, waiting (up to `secs`) until `count` of them contain
    /// `marker`: a process logs after it answered, so a log is read for what it must hold,
    /// not after a guessed pause.
    pub fn output_until(&self, marker: &str, count: usize, secs: u64) -> Vec<String> {
        let deadline = Instant::now() + Duration::from_secs(secs);
        let mut seen: Vec<String> = self.lines.try_iter().collect();
        while seen.iter().filter(|l| l.contains(marker)).count() < count {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(line) => seen.push(line),
                Err(_) => break,
            }
        }
        seen
    }

    /// Write `line` to the program's standard input.
    pub fn type_line(&mut self, line: &str) {
        let input = self.input.as_mut().expect("standard input open");
        writeln!(input, "{line}").expect("write to the program");
        input.flush().unwrap();
    }

    /// The output lines up to and including the first that contains `marker` (panics after
    /// `secs` seconds without it).
    pub fn wait_for(&self, marker: &str, secs: u64) -> Vec<String> {
        let deadline = Instant::now() + Duration::from_secs(secs);
        let mut seen = Vec::new();
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(line) => {
                    let hit = line.contains(marker);
                    seen.push(line);
                    if hit {
                        return seen;
                    }
                }
                Err(_) => panic!("no `{marker}` within {secs} s; output: {seen:?}"),
            }
        }
    }
}

impl Drop for Background {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// GET `path` from the view at `url` (`http://host:port/`): the body.
pub fn http_get(url: &str, path: &str) -> String {
    use std::io::{Read, Write};
    let addr = url.trim_start_matches("http://").trim_end_matches('/');
    let mut c = std::net::TcpStream::connect(addr).unwrap();
    c.set_read_timeout(Some(std::time::Duration::from_secs(10)))
        .unwrap();
    write!(c, "GET {path} HTTP/1.1\r\nHost: {addr}\r\n\r\n").unwrap();
    let mut all = String::new();
    c.read_to_string(&mut all).unwrap();
    all.split_once("\r\n\r\n")
        .map(|(_, b)| b.to_string())
        .unwrap_or(all)
}

/// The pick example's output: each step returned 0, and it ended `pick: done`.
pub fn check_pick(out: &str) {
    for step in [
        "TROLHome(0)",
        "TROLAppro(test_001, -90, 1)",
        "TROLMove(test_001, 1)",
        "TROLClose(60)",
        "TROLDepart(&loc, 1)",
    ] {
        let line = out
            .lines()
            .find(|l| l.starts_with(step))
            .unwrap_or_else(|| panic!("{step} missing:\n{out}"));
        assert!(line.ends_with("-> 0"), "{line}");
    }
    assert!(out.contains("pick: done"), "{out}");
}

/// Poll a view's `/state` at `url` until its joints are `want` (within 1e-3 rad); that
/// state. Panics after 30 s.
pub fn view_state_at(url: &str, want: [f64; 6]) -> serde_json::Value {
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        let body = http_get(url, "/state");
        if let Ok(s) = serde_json::from_str::<serde_json::Value>(&body) {
            let q: Vec<f64> = s["joints"]
                .as_array()
                .map(|a| a.iter().filter_map(|v| v.as_f64()).collect())
                .unwrap_or_default();
            if q.len() == 6 && (0..6).all(|i| (q[i] - want[i]).abs() < 1e-3) {
                return s;
            }
        }
        assert!(
            Instant::now() < deadline,
            "the view never showed the arm at {want:?}: {body}"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
}

/// Run `trol` with `args` (a `rapl probe --poses N`), answering each pose prompt by moving
/// the simulated C500's arm through its pendant (`sim`, started with --pendant), then Enter;
/// its output. Panics when it fails.
pub fn probe_with_poses(
    dir: &Path,
    args: &[String],
    sim: &mut Background,
    poses: &[&str],
) -> String {
    let mut probe = std::process::Command::new(TROL)
        .args(args)
        .current_dir(dir)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut answer = probe.stdin.take().unwrap();
    let mut said = std::io::BufReader::new(probe.stdout.take().unwrap()).lines();
    let mut out = Vec::new();
    for (k, pose) in poses.iter().enumerate() {
        let ask = format!("pose {} of {}", k + 1, poses.len());
        loop {
            let line = said
                .next()
                .unwrap_or_else(|| panic!("the probe ended early: {out:?}"))
                .unwrap();
            let hit = line.starts_with(&ask);
            out.push(line);
            if hit {
                break;
            }
        }
        sim.type_line(pose);
        sim.wait_for("pendant: at", 60);
        writeln!(answer).unwrap();
    }
    drop(answer);
    out.extend(said.map_while(Result::ok));
    let status = probe.wait().unwrap();
    let out = out.join("\n");
    assert!(status.success(), "{args:?}:\n{out}");
    out
}

/// The objects a world line names (`cube at x 400 y 0 z 135 mm, resting; ...`): each name,
/// where it is (mm) and where it rests ("resting", "in the gripper"), from the last such
/// line in `text`.
pub fn world_objects(text: &str) -> Vec<(String, [f64; 3], String)> {
    let Some(line) = text.lines().rev().find(|l| l.contains(" mm, ")) else {
        return Vec::new();
    };
    let line = line.rsplit(": ").next().unwrap_or(line);
    line.split("; ")
        .filter_map(|o| {
            let (name, rest) = o.split_once(" at x ")?;
            let (xyz, place) = rest.split_once(" mm, ")?;
            let v: Vec<f64> = xyz
                .split(' ')
                .filter(|w| !matches!(*w, "y" | "z"))
                .map(|w| w.parse().ok())
                .collect::<Option<_>>()?;
            let name = name.rsplit(' ').next().unwrap_or(name);
            Some((
                name.to_string(),
                [*v.first()?, *v.get(1)?, *v.get(2)?],
                place.to_string(),
            ))
        })
        .collect()
}

/// Whether `text`'s last world line puts `name` within 0.05 mm of `at` (None: any), `place`.
pub fn object_is(text: &str, name: &str, at: [Option<f64>; 3], place: &str) -> bool {
    world_objects(text).iter().any(|(n, p, pl)| {
        n == name
            && pl == place
            && at
                .iter()
                .zip(p)
                .all(|(want, got)| want.is_none_or(|w| (w - got).abs() <= 0.05))
    })
}

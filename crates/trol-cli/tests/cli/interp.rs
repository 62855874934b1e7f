//! `trol interp`: scripts, the first failure, messages that point at the column, help,
//! JSON, the interactive interpreter in a real terminal, teaching locations.

use super::*;

pub(super) const SCRIPT: &str = "\
; the manual's pick example
TROLHome 0
finish
speed 150
appro test_001 c(-150)
Appro test_001 (-90) straight
move test_001 1
finish wait
close 60
finish
getposition cart commanded
getposition prec actual
depart c(-90) 1
finish
getposition joint
getstatus
";

#[test]
pub(super) fn interp_runs_a_script_and_prints_each_result_with_its_name() {
    let dir = scratch("script");
    std::fs::write(dir.join("pick.trol"), SCRIPT).unwrap();
    std::fs::write(
        dir.join("locations.txt"),
        "test_001 400 0 150 0 1.5707963 0\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("trol.cfg"),
        "9600\nsim\n0 0 0 0 0 0\ntime_scale = 50\nlocations = locations.txt\n",
    )
    .unwrap();
    let o = trol(&dir, &["interp", "pick.trol"], "");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    let results: Vec<&str> = out.lines().collect();
    assert_eq!(results.len(), 15, "{out}");
    assert!(
        results[0].starts_with("TROLHome 0  ->  0 (success)"),
        "{out}"
    );
    assert!(
        results[9].contains("->  c(400, ") && results[9].contains(", 150, "),
        "{out}"
    );
    // The actual position: J1 at 0 to within the servo's dither of 2 counts.
    let counts = results[10]
        .split("->  p(")
        .nth(1)
        .expect("a precision point");
    let j1: i32 = counts.split(',').next().unwrap().trim().parse().unwrap();
    assert!(j1.abs() <= 2, "{out}");
    assert!(
        results[14].contains("BIOSCalled 1, lastErrorCode 0 (success)"),
        "{out}"
    );
}

#[test]
pub(super) fn interp_stops_at_the_first_failure_unless_told_to_go_on() {
    let dir = scratch("failures");
    let script = "home 0\nmove nowhere\nready\nclose 200\nfly 3\nfinish\n";
    let o = trol(&dir, &["interp", "--time-scale", "50"], script);
    let (out, err) = text(&o);
    assert!(!o.status.success());
    assert!(
        err.contains("<stdin>:2: error: TROLMove failed: -32102 (TROL_ERR_LOCATION)"),
        "{err}"
    );
    assert!(err.contains("stopped at line 2"), "{err}");
    assert!(!out.contains("ready"), "{out}");

    let o = trol(&dir, &["interp", "-k", "--time-scale", "50"], script);
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(1));
    assert!(out.contains("ready  ->  0 (success)"), "{out}");
    assert!(out.contains("finish  ->  0 (success)"), "{out}");
    assert!(
        err.contains(
            "<stdin>:4:7: error: `perForce` 200 is out of range 1..100 (TROL_ERR_ARG_RANGE, -32003)\n  close 200\n        ^^^"
        ),
        "{err}"
    );
    assert!(
        err.contains("<stdin>:5:1: error: unknown command `fly`"),
        "{err}"
    );
    assert!(err.contains("3 command(s) failed"), "{err}");
}

#[test]
pub(super) fn interp_error_messages_point_at_the_column() {
    let dir = scratch("syntax");
    let cases = [
        (
            "moveii c(400, 0, 150",
            "1:21: error: expected `)` to close the location begun at column 8",
        ),
        (
            "home",
            "1:5: error: expected `axis`, a whole number 0..6 after `Home`",
        ),
        (
            "joint 2 abc",
            "1:9: error: expected `radians`, a number, found `abc`",
        ),
        (
            "speed 0",
            "1:7: error: `perMaxSpeed` 0 is out of range 1..150",
        ),
        ("grip 51", "1:6: error: `dist` 51 is out of range 0..50"),
        (
            "ma c(0.1)",
            "1:4: error: MA takes j(...) here, not a cartesian location",
        ),
        (
            "halt 1",
            "1:6: error: unexpected `1`: Halt takes no more arguments",
        ),
        (
            "move test_001 maybe",
            "1:15: error: expected the straight flag",
        ),
        ("close 5x", "1:7: error: `5x` is not a number"),
        ("42", "1:1: error: expected a command name"),
        (
            "trolfinsh",
            "1:1: error: unknown command `trolfinsh`; did you mean `Finish`?",
        ),
    ];
    for (line, expected) in cases {
        let o = trol(&dir, &["interp"], &format!("{line}\n"));
        let (_, err) = text(&o);
        assert!(!o.status.success(), "{line}");
        assert!(err.contains(expected), "{line}: {err}");
    }
}

#[test]
pub(super) fn interp_help_lists_every_command_with_arguments_and_ranges() {
    let dir = scratch("help");
    let o = trol(&dir, &["interp"], "help\nhelp trolclose\n");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    for name in [
        "Appro locName:NAME pDisp:c(1..6 values) [straight:0|1]",
        "ApproII pTarget:c|p(1..6 values)",
        "Close perForce:1..100",
        "Depart pDisp:",
        "Finish [mode:wait|status]",
        "Grip dist:0..50",
        "Halt",
        "Home axis:0..6",
        "Jog pDisp:c(1..3 values)",
        "Joint jointNum:1..6 radians:real",
        "MA pTarget:j(1..6 values)",
        "MI pDisp:",
        "Move locName:NAME",
        "MoveII pTarget:c|p(1..6 values)",
        "Open perForce:1..100",
        "Ready",
        "SetToolTransform md:",
        "Speed perMaxSpeed:1..150",
        "GetPosition [pos:cart|joint|prec] [mode:commanded|actual]",
        "TerminatePCP",
        "GetStatus",
        "delay ms:0..600000",
    ] {
        assert!(out.contains(name), "help lacks `{name}`:\n{out}");
    }
    assert!(
        out.contains("TROLClose (CAT1, code 2): close the gripper"),
        "{out}"
    );
}

/// The example lines of `trol interp --help` run, as written, against the simulator with
/// the example locations; a failure says what to do next.
#[test]
pub(super) fn the_interpreters_own_example_runs_and_failures_hint_at_the_next_step() {
    let dir = scratch("interp-example");
    let help = text(&trol(&dir, &["interp", "--help"], "")).0;
    let lines: Vec<&str> = help
        .lines()
        .skip_while(|l| !l.starts_with("A line is a command"))
        .skip(2)
        .take_while(|l| l.starts_with("  "))
        .map(str::trim)
        .collect();
    assert!(lines.len() >= 6, "{help}");
    let locations = cbuild::root().join("examples/locations.txt");
    let o = trol(
        &dir,
        &[
            "interp",
            "--locations",
            locations.to_str().unwrap(),
            "--time-scale",
            "50",
        ],
        &(lines.join("\n") + "\n"),
    );
    let (out, err) = text(&o);
    assert!(o.status.success(), "{lines:?}\n{out}\n{err}");
    assert_eq!(
        out.lines().filter(|l| l.contains("->")).count(),
        lines.len(),
        "{out}"
    );

    // Not homed: the hint says how.
    let o = trol(
        &dir,
        &["interp", "--time-scale", "50"],
        "moveii c(400, 0, 300, 0, 1.5707963, 0)\n",
    );
    let (_, err) = text(&o);
    assert!(
        err.contains("BIOS_NOT_HOMED") && err.contains("hint: home the arm first: `home 0`"),
        "{err}"
    );
    // A name the controller does not know: the hint says how to load locations.
    let o = trol(&dir, &["interp"], "move test_001\n");
    let (_, err) = text(&o);
    assert!(
        err.contains("TROL_ERR_LOCATION") && err.contains("--locations FILE"),
        "{err}"
    );
}

#[test]
pub(super) fn interp_json_prints_one_object_per_reply() {
    let dir = scratch("interp-json");
    let o = trol(
        &dir,
        &[
            "interp",
            "--json",
            "-k",
            "--port",
            "sim",
            "--time-scale",
            "50",
        ],
        "speed 50\ngetposition joint commanded\ngetstatus\nmove nowhere\n",
    );
    let (out, err) = text(&o);
    assert!(!o.status.success(), "the failed move is in the exit status");
    let objects: Vec<serde_json::Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{l}: {e}\n{err}")))
        .collect();
    assert_eq!(objects.len(), 4, "{out}");
    assert_eq!(objects[0]["command"], "TROLSpeed");
    assert_eq!(objects[0]["ok"], true);
    assert_eq!(objects[0]["name"], "success");
    assert_eq!(objects[1]["position"]["form"], "joint");
    assert_eq!(
        objects[1]["position"]["values"].as_array().unwrap().len(),
        6
    );
    assert_eq!(objects[2]["status"]["bios_called"], true);
    assert_eq!(objects[3]["ok"], false);
    assert_eq!(objects[3]["code"], -32102);
    assert_eq!(objects[3]["name"], "TROL_ERR_LOCATION");
    assert!(objects[3]["hint"].as_str().unwrap().contains("--locations"));
}

/// The interactive interpreter in a real terminal (`script` gives it a pseudo-terminal that is
/// its controlling terminal): lines typed ahead run in order, a bracketed paste runs line by
/// line, completion offers each argument's words and the location names, Ctrl-C during a wait
/// halts the arm and gives the prompt back, Ctrl-D leaves.
#[test]
pub(super) fn the_interactive_interpreter_in_a_real_terminal() {
    use std::io::{Read, Write};
    use std::sync::{Arc, Mutex};
    let dir = scratch("interactive");
    let locations = cbuild::root().join("examples/locations.txt");
    let command = format!(
        "exec {} interp --port sim --time-scale 2 --locations {}",
        common::TROL,
        locations.display()
    );
    let mut child = std::process::Command::new("script")
        .args(["-qfec", &command, "/dev/null"])
        .current_dir(&dir)
        .env("HOME", &dir)
        .env("TERM", "xterm")
        .env("SHELL", "/bin/sh")
        .env_remove("TROL_CONFIG")
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("script (util-linux) runs the interpreter in a pseudo-terminal");
    let screen = Arc::new(Mutex::new(String::new()));
    let mut out = child.stdout.take().unwrap();
    let keep = screen.clone();
    std::thread::spawn(move || {
        let mut buf = [0u8; 4096];
        while let Ok(n) = out.read(&mut buf) {
            if n == 0 {
                break;
            }
            keep.lock()
                .unwrap()
                .push_str(&String::from_utf8_lossy(&buf[..n]));
        }
    });
    let mut keys = child.stdin.take().unwrap();
    let mut typed = |s: &str| {
        keys.write_all(s.as_bytes()).unwrap();
        keys.flush().unwrap();
    };
    // Wait until the screen shows `what` at least `n` times.
    let wait = |what: &str, n: usize| {
        let deadline = Instant::now() + Duration::from_secs(20);
        loop {
            let seen = screen.lock().unwrap().matches(what).count();
            if seen >= n {
                return;
            }
            assert!(
                Instant::now() < deadline,
                "`{what}` x{n} not seen:\n{}",
                screen.lock().unwrap()
            );
            std::thread::sleep(Duration::from_millis(20));
        }
    };
    wait("trol> ", 1);
    // Typed ahead: three lines at once, each runs.
    typed("speed 10\rspeed 20\rspeed 30\r");
    wait("0 (success)", 3);
    // A bracketed paste of two lines.
    typed("\u{1b}[200~speed 40\nspeed 50\n\u{1b}[201~\r");
    wait("0 (success)", 5);
    // Completion: the command, then each argument's own words.
    typed("getpos\t");
    wait("getposition", 1);
    typed(" jo\t");
    wait("getposition joint", 1);
    typed(" act\t\r");
    wait("j(", 1);
    // A location name from the location file.
    typed("home 0\r");
    wait("0 (success)", 6);
    typed("move test_\t");
    wait("move test_001", 1);
    typed("\r");
    wait("0 (success)", 7);
    // Ctrl-C during a wait: Halt, and the prompt comes back.
    typed("speed 5\rjoint 1 2.5\rfinish\r");
    wait("0 (success)", 9);
    std::thread::sleep(Duration::from_millis(500));
    typed("\u{3}");
    wait("interrupted: Halt sent", 1);
    typed("getposition joint\r");
    wait("j(", 2);
    // Ctrl-D leaves.
    typed("\u{4}");
    let status = child.wait().unwrap();
    assert!(status.success(), "{}", screen.lock().unwrap());
}

/// A byte that is not UTF-8 in a script is that line's error, with its line and column; the
/// script stops there, or goes on with -k (it used to end the script with no line number).
#[test]
pub(super) fn a_line_that_is_not_text_is_its_lines_error() {
    let dir = scratch("interp-bytes");
    std::fs::write(dir.join("bad.trol"), b"speed 50\nre\xffady\nspeed 60\n").unwrap();
    let o = trol(&dir, &["interp", "bad.trol", "--port", "sim"], "");
    let (out, err) = text(&o);
    assert!(!o.status.success(), "{out}");
    assert!(
        err.contains("bad.trol:2:3: error: byte 0xff is not UTF-8"),
        "{err}"
    );
    assert!(err.contains("stopped at line 2"), "{err}");
    assert!(!out.contains("speed 60"), "{out}");
    let o = trol(&dir, &["interp", "-k", "bad.trol", "--port", "sim"], "");
    let (out, err) = text(&o);
    assert!(!o.status.success(), "{out}");
    assert!(out.contains("speed 60  ->  0 (success)"), "{out}");
    assert!(err.contains("1 command(s) failed"), "{err}");
    // A comment is never a command, whatever bytes it holds (a Latin-1 note, issue 44).
    std::fs::write(
        dir.join("note.trol"),
        b"; caf\xe9 au lait\n  ; \xff\nspeed 50\n",
    )
    .unwrap();
    let o = trol(&dir, &["interp", "note.trol", "--port", "sim"], "");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}{err}");
    assert!(out.contains("speed 50  ->  0 (success)"), "{out}");
}

/// Teaching in the interpreter (issue 28, docs/teach.md): `here`, RAPL-II's `listl`, `point`
/// and `dlocn`, `savelocations`; the list as JSON; a taught location survives a restart of
/// the (embedded) simulator through its locations file.
#[test]
pub(super) fn interp_teaches_lists_deletes_and_saves_locations() {
    let dir = scratch("teach");
    std::fs::write(
        dir.join("trol.cfg"),
        "9600\nsim\n0 0 0 0 0 0\ntime_scale = 50\nhomed = yes\nlocations = taught.txt\n",
    )
    .unwrap();
    std::fs::write(dir.join("taught.txt"), "").unwrap();
    let script = "moveii c(420, -50, 330, 0, 1.5708, 0)\nfinish\nhere p1\nhere #pp prec\n\
                  point up c(400, 0, 450, 0, 1.5708, 0)\nlistl\ndlocn up\nready\nfinish\n\
                  move p1\nfinish\ngetposition cart\nsavelocations\n";
    let o = trol(&dir, &["interp"], script);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    let lines: Vec<&str> = out.lines().collect();
    assert!(lines[2].starts_with("here p1  ->  0 (success)"), "{out}");
    assert!(
        lines[5].contains("#pp p(")
            && lines[5].contains("; p1 c(420, -50, 330")
            && lines[5].contains("; up c(400, 0, 450"),
        "{out}"
    );
    assert!(lines[11].contains("c(420, -50, 330"), "{out}");
    let saved = std::fs::read_to_string(dir.join("taught.txt")).unwrap();
    let p1: Vec<f64> = saved
        .lines()
        .find_map(|l| l.strip_prefix("p1 "))
        .unwrap_or_else(|| panic!("{saved}"))
        .split_whitespace()
        .map(|v| v.parse().unwrap())
        .collect();
    assert!(
        (p1[0] - 420.0).abs() < 1e-3 && (p1[2] - 330.0).abs() < 1e-3,
        "{saved}"
    );
    assert!(!saved.contains("\nup "), "{saved}");
    // A new session, a new simulator: the table is back; as JSON.
    let o = trol(&dir, &["interp", "--json"], "listl\n");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    let names: Vec<&str> = v["locations"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["#pp", "p1"], "{v}");
    assert_eq!(v["locations"][1]["form"], "cart");
}

/// A trajectory in the interpreter: `trajectory w(t, q1..q6) ...`, run timed on the embedded
/// simulator; a waypoint of the wrong form is a syntax error at its column, and times that
/// go back are TROL_ERR_ARG_RANGE before anything is sent.
#[test]
pub(super) fn interp_runs_a_trajectory_of_waypoints() {
    let dir = scratch("trajectory");
    std::fs::write(
        dir.join("path.trol"),
        "home 0\nfinish wait\ntrajectory w(1, 0.3, 0.2, 0.5, 0, 0.2, 0) w(2, 0.5, 0.3, 0.8, 0.1, 0.3, 0.2)\n\
         finish wait\ngetposition joint\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("trol.cfg"),
        "9600\nsim\n0 0 0 0 0 0\ntime_scale = 50\n",
    )
    .unwrap();
    let o = trol(&dir, &["interp", "path.trol"], "");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert!(
        out.contains("trajectory w(1, 0.3, 0.2, 0.5, 0, 0.2, 0) w(2, 0.5, 0.3, 0.8, 0.1, 0.3, 0.2)  ->  0 (success)"),
        "{out}"
    );
    assert!(out.contains("->  j(0.5, 0.3, 0.8, 0.1, 0.3, 0.2)"), "{out}");
    std::fs::write(
        dir.join("bad.trol"),
        "trajectory w(1, 0.3, 0.2)\ntrajectory w(2, 0, 0, 0, 0, 0, 0) w(1, 0, 0, 0, 0, 0, 0)\n",
    )
    .unwrap();
    let o = trol(&dir, &["interp", "-k", "bad.trol"], "");
    let (out, err) = text(&o);
    let all = format!("{out}\n{err}");
    assert!(
        all.contains("a waypoint is its time and six joint angles: 3 values given"),
        "{all}"
    );
    assert!(all.contains("times must increase"), "{all}");
}

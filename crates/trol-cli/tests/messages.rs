//! Messages that name their cause and one thing to do (issue 44, item 3).

mod common;

use common::{scratch, text, trol};

/// A misspelt `--locations` folder is the start's failure, before any command runs (it was
/// reported at the first command, as `home 0`'s failure).
#[test]
fn a_locations_folder_that_does_not_exist_is_refused_at_start() {
    let dir = scratch("locations-folder");
    for args in [
        &["interp", "--locations", "exmaples/locations.txt"][..],
        &["demo", "--locations", "exmaples/locations.txt"],
    ] {
        let o = trol(&dir, args, "home 0\nfinish\n");
        let (out, err) = text(&o);
        assert!(!o.status.success(), "{args:?}: {out}");
        assert!(
            err.contains("the folder exmaples does not exist: create it"),
            "{args:?}: {err}"
        );
        // Nothing ran: not the first command, not the demo's first step.
        assert!(!out.contains("home 0"), "{args:?}: {out}");
        assert!(!out.contains("TROLHome"), "{args:?}: {out}");
    }
    // A file that does not exist yet in a folder that does: an empty table, said at start.
    let o = trol(&dir, &["interp", "--locations", "new.txt"], "listl\n");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert!(err.contains("new.txt does not exist yet"), "{err}");
    assert!(err.contains("TROLSaveLocations creates the file"), "{err}");
}

/// The note that a locations file does not exist yet is said once per path, as notices are
/// once each: the same misspelt name in another folder is said again (issue 68, item 3: it
/// was said once per name ever, so a typo repeated elsewhere was a silent empty table).
#[test]
fn a_missing_locations_file_is_noted_once_for_each_path() {
    let cache = scratch("notice-cache");
    let run = |dir: &std::path::Path| {
        std::fs::write(dir.join("list.trol"), "listl\n").unwrap();
        let o = std::process::Command::new(common::TROL)
            .args(["interp", "list.trol", "--locations", "lcoations.txt"])
            .current_dir(dir)
            .env_remove("TROL_CONFIG")
            .env_remove("TROL_VERBOSE")
            .env("XDG_CACHE_HOME", &cache)
            .stdin(std::process::Stdio::null())
            .output()
            .unwrap();
        let (_, err) = text(&o);
        err
    };
    let (a, b) = (scratch("notice-a"), scratch("notice-b"));
    let first = run(&a);
    assert!(
        first.contains("lcoations.txt does not exist yet"),
        "{first}"
    );
    assert!(
        first.contains(&a.join("lcoations.txt").display().to_string()),
        "{first}"
    );
    // The same folder again: said already.
    assert!(!run(&a).contains("does not exist yet"));
    // Another folder, the same name: its own path, said.
    let other = run(&b);
    assert!(
        other.contains(&b.join("lcoations.txt").display().to_string()),
        "{other}"
    );
}

/// After Home the arm stands stretched upright at the edge of its reach: a jog there is out
/// of reach, and the hint says what goes instead, which then works.
#[test]
fn a_jog_out_of_reach_after_home_says_what_to_do() {
    let dir = scratch("jog-after-home");
    let o = trol(
        &dir,
        &["interp", "--time-scale", "50"],
        "home 0\nfinish\njog c(10)\n",
    );
    let (_, err) = text(&o);
    assert!(!o.status.success());
    assert!(err.contains("BIOS_OUT_OF_REACH"), "{err}");
    assert!(err.contains("After Home it stands"), "{err}");
    assert!(
        err.contains("`jog c(0, 0, -100)` or `joint 3 0.5` first"),
        "{err}"
    );
    let o = trol(
        &dir,
        &["interp", "--time-scale", "50"],
        "home 0\nfinish\njog c(0, 0, -100)\nfinish\njog c(10)\nfinish\n",
    );
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
}

/// A port that is not there says the name it is near and where the ports are; a help topic
/// misspelt, the command it is near (issue 68, item 3: `help hme` and `--port Sim` said
/// nothing to go on; `trol interp` with a wrong device said less than `trol init`).
#[test]
fn a_misspelt_port_or_help_topic_suggests_what_is_near() {
    let dir = scratch("misspelt");
    let o = trol(&dir, &["interp", "--port", "Sim"], "home 0\n");
    let (_, err) = text(&o);
    assert!(!o.status.success());
    assert!(
        err.contains("did you mean `sim` (the embedded simulator)?"),
        "{err}"
    );
    for args in [
        &["interp", "--port", "/dev/ttyNOPE0"][..],
        &["init", "--port", "/dev/ttyNOPE0"],
    ] {
        let o = trol(&dir, args, "home 0\n");
        let (_, err) = text(&o);
        assert!(
            err.contains("serial ports: ") || err.contains("shows no serial port"),
            "{args:?}: {err}"
        );
    }
    let o = trol(&dir, &["interp", "--port", "marz:/dev/ttyUSB0"], "home 0\n");
    let (_, err) = text(&o);
    assert!(err.contains("did you mean `mars:/dev/ttyUSB0`?"), "{err}");
    let o = trol(&dir, &["interp"], "help hme\n");
    let (_, err) = text(&o);
    assert!(err.contains("did you mean `Home`?"), "{err}");
}

/// To a pipe, the interpreter's errors and hints are whole lines, whatever $COLUMNS says (a
/// program reads them: a test harness may set COLUMNS); on a terminal they wrap between
/// words (issue 68, item 4; `wrapped`'s unit test in common.rs).
#[test]
fn errors_to_a_pipe_are_whole_lines_whatever_columns_says() {
    let dir = scratch("wrap-pipe");
    let run = |columns: Option<&str>| {
        let mut c = std::process::Command::new(common::TROL);
        c.args(["interp", "--port", "/dev/ttyNOPE0"])
            .current_dir(&dir)
            .env_remove("TROL_CONFIG")
            .env("TROL_VERBOSE", "1")
            .env_remove("COLUMNS")
            .stdin(std::process::Stdio::piped())
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped());
        if let Some(w) = columns {
            c.env("COLUMNS", w);
        }
        let mut child = c.spawn().unwrap();
        use std::io::Write;
        let _ = child.stdin.take().unwrap().write_all(b"home 0\n");
        let o = child.wait_with_output().unwrap();
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let whole = run(None);
    assert!(whole.lines().any(|l| l.chars().count() > 60), "{whole}");
    assert_eq!(run(Some("60")), whole);
}

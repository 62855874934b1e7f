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

//! Teaching on the embedded simulator (docs/teach.md): locations stored, listed, deleted,
//! moved to and saved; one rule for names on every backend (issue 42: case does not tell
//! two names apart, `T1` to `T18` are the controller's); saving that names its cause and
//! never spoils the file; a locations file checked when the program starts.

use trol::code::*;
use trol::{Location, PosMode, Robot, SimSettings, Tag};
use trol_a465::arm::{Stored, code};

fn settings() -> SimSettings {
    let mut s = SimSettings {
        time_scale: 50.0,
        ..SimSettings::default()
    };
    s.arm.homed = true;
    s
}

/// A folder of its own for one test.
fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("trol-teach-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A robot from a trol.cfg in `dir` naming `locations` (relative to `dir`), or what
/// reading trol.cfg or starting the controller said.
fn from_config(dir: &std::path::Path, locations: &str) -> Result<Robot, String> {
    std::fs::write(
        dir.join("trol.cfg"),
        format!("38400\nsim\n0 0 0 0 0 0\ntime_scale = 50\nlocations = {locations}\nhomed = yes\n"),
    )
    .unwrap();
    let cfg = trol::Config::from_file(&dir.join("trol.cfg")).map_err(|e| e.to_string())?;
    trol::Connect::config(&cfg)
        .connect()
        .map_err(|e| e.to_string())
}

/// Teaching (issue 28, docs/teach.md) on the embedded simulator: store where the arm is in
/// each form, define a location, list, delete, move back to a taught location, save, and
/// find the table again after a restart. Wrong names and forms are refused before anything
/// is sent.
#[test]
fn taught_locations_are_stored_listed_deleted_moved_to_and_survive_a_restart() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("trol-teach");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("taught.txt");
    std::fs::write(&file, "; nothing taught yet\n").unwrap();
    std::fs::write(
        dir.join("trol.cfg"),
        "38400\nsim\n0 0 0 0 0 0\ntime_scale = 50\nlocations = taught.txt\nhomed = yes\n",
    )
    .unwrap();
    let cfg = trol::Config::from_file(&dir.join("trol.cfg")).unwrap();
    let mut r = trol::Connect::config(&cfg).connect().unwrap();
    assert!(r.locations().unwrap().is_empty());
    // Somewhere off READY, then teach it three ways.
    let pose = [420.0, -50.0, 330.0, 0.0, std::f64::consts::FRAC_PI_2, 0.0];
    r.move_ii(&Location::Cart(pose.to_vec()), false).unwrap();
    r.finish().unwrap();
    let at = r.position(Tag::Joint, PosMode::Commanded).unwrap();
    r.here("p1", Tag::Cart).unwrap();
    r.here("pj", Tag::Joint).unwrap();
    r.here("#pp", Tag::Prec).unwrap();
    r.define(
        "up",
        &Location::Cart(vec![300.0, 0.0, 500.0, 0.0, 1.5, 0.0]),
    )
    .unwrap();
    let all = r.locations().unwrap();
    let names: Vec<&str> = all.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["#pp", "p1", "pj", "up"]);
    let p1 = all[1].1.to_array6();
    for i in 0..3 {
        assert!((p1[i] - pose[i]).abs() < 1e-2, "{p1:?}");
    }
    assert_eq!(all[2].1.tag(), Tag::Joint);
    // Away and back, by each taught form.
    for name in ["p1", "pj", "#pp"] {
        r.ready().unwrap();
        r.finish().unwrap();
        r.move_to(name, false).unwrap();
        r.finish().unwrap();
        let back = r.position(Tag::Joint, PosMode::Commanded).unwrap();
        for (a, b) in back.to_array6().iter().zip(at.to_array6()) {
            assert!((a - b).abs() < 1e-3, "{name}: {back:?} vs {at:?}");
        }
    }
    // Refused before anything is sent: a precision point without '#', a '#' name for
    // cartesian values, a name too long.
    for e in [
        r.here("pp", Tag::Prec).unwrap_err(),
        r.define("#c", &Location::Cart(vec![0.0; 6])).unwrap_err(),
        r.here("much_too_long", Tag::Cart).unwrap_err(),
    ] {
        assert_eq!(e.code(), TROL_ERR_ARG_RANGE, "{e}");
    }
    // Delete: gone; deleting it again is TROL_ERR_LOCATION, as moving to it is.
    r.delete_location("up").unwrap();
    assert_eq!(
        r.delete_location("up").unwrap_err().code(),
        TROL_ERR_LOCATION
    );
    assert_eq!(
        r.move_to("up", false).unwrap_err().code(),
        TROL_ERR_LOCATION
    );
    // Saved, then a new controller (a restart) reads them back.
    r.save_locations().unwrap();
    drop(r);
    let mut again = trol::Connect::config(&cfg).connect().unwrap();
    let names: Vec<String> = again
        .locations()
        .unwrap()
        .into_iter()
        .map(|(n, _)| n)
        .collect();
    assert_eq!(names, ["#pp", "p1", "pj"]);
    again.move_to("pj", false).unwrap();
    again.finish().unwrap();
    let back = again.position(Tag::Joint, PosMode::Commanded).unwrap();
    for (a, b) in back.to_array6().iter().zip(at.to_array6()) {
        assert!((a - b).abs() < 1e-3, "after the restart: {back:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Without a locations file the simulator cannot save: BIOS_NO_FILE, which says what to do;
/// the table itself works.
#[test]
fn saving_without_a_locations_file_says_how_to_get_one() {
    let mut r = trol::Connect::sim(settings()).connect().unwrap();
    r.here("p9", Tag::Cart).unwrap();
    let e = r.save_locations().unwrap_err();
    assert_eq!(e.code().0, trol_a465::arm::code::NO_FILE, "{e}");
    assert!(e.to_string().contains("--locations FILE"), "{e}");
}

/// One rule for names (docs/teach.md, "Names"): `up` and `UP` are one location, as on a
/// C500, which upper-cases what it is typed; it keeps the spelling it was first stored
/// with. `T1` to `T18` (with or without `#`, any case) are the scratch locations of the C500
/// backend, refused on every backend before anything is sent, with one message.
#[test]
fn names_are_one_location_in_any_case_and_reserved_names_are_refused() {
    let mut r = trol::Connect::sim(settings()).connect().unwrap();
    r.define(
        "up",
        &Location::Cart(vec![300.0, 0.0, 500.0, 0.0, 1.5, 0.0]),
    )
    .unwrap();
    r.define(
        "UP",
        &Location::Cart(vec![310.0, 0.0, 500.0, 0.0, 1.5, 0.0]),
    )
    .unwrap();
    let all = r.locations().unwrap();
    assert_eq!(all.len(), 1, "{all:?}");
    assert_eq!(all[0].0, "up");
    assert!((all[0].1.to_array6()[0] - 310.0).abs() < 1e-3, "{all:?}");
    r.move_to("Up", false).unwrap();
    r.finish().unwrap();
    r.delete_location("uP").unwrap();
    assert!(r.locations().unwrap().is_empty());
    let sent = r.last_transaction();
    for e in [
        r.define(
            "T1",
            &Location::Cart(vec![300.0, 0.0, 500.0, 0.0, 1.5, 0.0]),
        )
        .unwrap_err(),
        r.here("#t18", Tag::Prec).unwrap_err(),
        r.move_to("t5", false).unwrap_err(),
        r.delete_location("T9").unwrap_err(),
    ] {
        assert_eq!(e.code(), TROL_ERR_ARG_RANGE, "{e}");
        assert!(e.to_string().contains("is reserved"), "{e}");
        assert!(e.to_string().contains("choose another name"), "{e}");
    }
    assert_eq!(r.last_transaction(), sent, "a reserved name was sent");
    // T19 and TL are ordinary names.
    r.here("T19", Tag::Cart).unwrap();
    r.here("TL", Tag::Joint).unwrap();
}

/// A file that is read-only stays as it is, and Save says so with its own code; the
/// folder gone, Save says that; the table is kept either way and saves once the cause is
/// mended.
#[cfg(unix)]
#[test]
fn saving_names_its_cause_and_never_replaces_a_read_only_file() {
    use std::os::unix::fs::PermissionsExt;
    let dir = scratch("save");
    let file = dir.join("taught.txt");
    std::fs::write(&file, "p0 400 0 300 0 1.5707963 0\n").unwrap();
    std::fs::set_permissions(&file, std::fs::Permissions::from_mode(0o444)).unwrap();
    let mut r = from_config(&dir, "taught.txt").unwrap();
    r.here("p1", Tag::Cart).unwrap();
    let e = r.save_locations().unwrap_err();
    assert_eq!(e.code().0, code::FILE_DENIED, "{e}");
    assert!(e.to_string().contains("left as it is"), "{e}");
    assert_eq!(
        std::fs::read_to_string(&file).unwrap(),
        "p0 400 0 300 0 1.5707963 0\n"
    );
    let mode = std::fs::metadata(&file).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode, 0o444);
    // Writable again: saved, with the permissions it had.
    std::fs::set_permissions(&file, std::fs::Permissions::from_mode(0o640)).unwrap();
    r.save_locations().unwrap();
    let text = std::fs::read_to_string(&file).unwrap();
    assert!(text.contains("p0 ") && text.contains("p1 "), "{text}");
    let mode = std::fs::metadata(&file).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode, 0o640);
    assert!(!dir.join("taught.trol-tmp").exists());
    // The folder gone: its own code.
    std::fs::remove_dir_all(&dir).unwrap();
    let e = r.save_locations().unwrap_err();
    assert_eq!(e.code().0, code::NO_FOLDER, "{e}");
    std::fs::create_dir_all(&dir).unwrap();
    r.save_locations().unwrap();
    assert!(std::fs::read_to_string(&file).unwrap().contains("p1 "));
    let _ = std::fs::remove_dir_all(&dir);
}

/// The locations file is checked when the program starts, with what to do: a folder that
/// does not exist, more locations than the table holds, a file far too large to be one (not
/// read whole), a reserved name. A file that does not exist yet in a folder that does is an
/// empty table that Save creates.
#[test]
fn a_locations_file_is_checked_when_the_program_starts() {
    let dir = scratch("load");
    let e = from_config(&dir, "nowhere/taught.txt").unwrap_err();
    assert!(
        e.contains("the folder of") && e.contains("nowhere/taught.txt"),
        "{e}"
    );

    let mut r = from_config(&dir, "new.txt").unwrap();
    // Said once, so that a misspelt name is not a silent empty table.
    let notice = r.take_notice().expect("a notice");
    assert!(notice.contains("new.txt does not exist yet"), "{notice}");
    assert!(
        notice.contains("TROLSaveLocations creates the file"),
        "{notice}"
    );
    assert!(r.locations().unwrap().is_empty());
    r.here("p1", Tag::Cart).unwrap();
    r.save_locations().unwrap();
    assert!(
        std::fs::read_to_string(dir.join("new.txt"))
            .unwrap()
            .contains("p1 ")
    );
    drop(r);

    let many: String = (0..1001)
        .map(|i| format!("p{i} 400 0 300 0 1.5707963 0\n"))
        .collect();
    std::fs::write(dir.join("many.txt"), many).unwrap();
    let e = from_config(&dir, "many.txt").unwrap_err();
    assert!(e.to_string().contains("the table holds 1000"), "{e}");

    let huge = vec![b';'; (trol_a465::arm::MAX_LOCATIONS_FILE + 1) as usize];
    std::fs::write(dir.join("huge.txt"), huge).unwrap();
    let e = from_config(&dir, "huge.txt").unwrap_err();
    assert!(e.to_string().contains("is it a locations file?"), "{e}");

    std::fs::write(dir.join("t1.txt"), "T1 400 0 300 0 1.5707963 0\n").unwrap();
    let e = from_config(&dir, "t1.txt").unwrap_err();
    assert!(e.to_string().contains("T1 is reserved"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A name that differs only in case is the same location in a locations file too: the
/// later line wins, under the first spelling.
#[test]
fn a_file_with_one_name_in_two_cases_holds_one_location() {
    let mut s = settings();
    s.locations = vec![
        (
            "up".into(),
            Stored::Cart([300.0, 0.0, 500.0, 0.0, 1.5, 0.0]),
        ),
        (
            "UP".into(),
            Stored::Cart([320.0, 0.0, 500.0, 0.0, 1.5, 0.0]),
        ),
    ];
    let mut r = trol::Connect::sim(s).connect().unwrap();
    let all = r.locations().unwrap();
    assert_eq!(all.len(), 1, "{all:?}");
    assert!((all[0].1.to_array6()[0] - 320.0).abs() < 1e-3);
}

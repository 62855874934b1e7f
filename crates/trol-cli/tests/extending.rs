//! docs/extending.md, step by step: its blocks stand as written in the files it names, and
//! those files work: the guide's commands from Rust against an in-process controller and a
//! controller process over a pseudo-terminal, from C through TransSR and Cat1Transaction,
//! through `trol interp` and through `trol trace`. And every surface knows every built-in
//! command.

#[path = "../../trol-c/tests/common/cbuild.rs"]
mod cbuild;
mod common;

use std::process::Command;

use cbuild::{Link, build_libtrol, compile, lib_dir, program, root};
use common::{Background, scratch, text, trol};
use trol::table::BUILTIN;
use trol::{Location, PosMode, Robot, SimSettings, Tag};

#[test]
fn the_guides_blocks_stand_in_the_files_they_name() {
    let guide = std::fs::read_to_string(root().join("docs/extending.md")).unwrap();
    let mut checked = 0;
    for block in guide.split("```").skip(1).step_by(2) {
        let (head, body) = block.split_once('\n').unwrap();
        let Some(file) = head
            .split_whitespace()
            .find_map(|w| w.strip_prefix("file="))
        else {
            continue;
        };
        let text = std::fs::read_to_string(root().join(file))
            .unwrap_or_else(|e| panic!("docs/extending.md names {file}: {e}"));
        assert!(
            text.contains(body),
            "docs/extending.md's block for {file} is not in it as written:\n{body}"
        );
        checked += 1;
    }
    assert!(checked >= 8, "only {checked} blocks name a file");
}

fn example(name: &str) -> std::path::PathBuf {
    build_libtrol();
    lib_dir().join("examples").join(name)
}

#[test]
fn the_guides_commands_work_in_process_across_processes_from_c_and_in_the_utilities() {
    let dir = scratch("extending");
    let toml = root().join("examples/extending.toml");
    let toml = toml.to_str().unwrap();

    // Step 3 against an in-process controller.
    let o = Command::new(example("extending_client")).output().unwrap();
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert!(
        out.contains("TROLForwardKin j(0, 0.5, 1) -> [551.51"),
        "{out}"
    );
    assert!(
        out.contains("after TROLJointAbs 2 0.25: Joint([0.0, 0.25, 0.0, 0.0, 0.0, 0.0])"),
        "{out}"
    );
    assert!(
        out.contains(
            "TROLJointAbs 7 0: TROL_ERR_ARG_RANGE: TROLJointAbs: `jointNum` 7 out of 1..6"
        ),
        "{out}"
    );

    // Step 2: the controller program as a process, with `trol trace` in between.
    let ctl = Background::start_program(example("extending_controller"), &dir, &[], "serving on ");
    let spy = Background::start(
        &dir,
        &["trace", "spy", &ctl.name, "pty", "--commands", toml],
        "application on ",
    );

    // Step 3 against it.
    let o = Command::new(example("extending_client"))
        .arg(&spy.name)
        .output()
        .unwrap();
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert!(
        out.contains("TROLForwardKin j(0, 0.5, 1) -> [551.51"),
        "{out}"
    );

    // Step 4: C, through TransSR and Cat1Transaction.
    let exe = compile(
        &root().join("examples/extending.c"),
        "extending",
        Link::Static,
    );
    std::fs::write(
        dir.join("trol.cfg"),
        format!("9600\n{}\n0 0 0 0 0 0\n", spy.name),
    )
    .unwrap();
    let o = program(&exe).current_dir(&dir).output().unwrap();
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert!(
        out.contains("TROLForwardKin -> 0: x 551.511 y 0.000 z 626.435"),
        "{out}"
    );
    assert!(out.contains("TROLJointAbs(2, 0.25) -> 0"), "{out}");
    assert!(out.contains("joint 2 now 0.250"), "{out}");
    assert!(out.contains("TROLJointAbs(7, 0.25) -> -32003"), "{out}");

    // Step 5: the interpreter reads, checks and shows them from the description file.
    let o = trol(
        &dir,
        &["interp", "--port", &spy.name, "--commands", toml],
        "forwardkin j(0, 0.5, 1)\njointabs 3 0.5\nhelp trolforwardkin\n",
    );
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert!(
        out.contains("forwardkin j(0, 0.5, 1)  ->  0 (success), values (551.510864, "),
        "{out}"
    );
    assert!(out.contains("jointabs 3 0.5  ->  0 (success)"), "{out}");
    assert!(
        out.contains("TROLForwardKin (CAT2, code 64): the cartesian pose"),
        "{out}"
    );
    let o = trol(
        &dir,
        &["interp", "--port", &spy.name, "--commands", toml],
        "jointabs 9 0.5\n",
    );
    assert!(
        text(&o).1.contains("`jointNum` 9 is out of range 1..6"),
        "{:?}",
        text(&o)
    );

    // The spy and the controller log after they answered: read until the lines are there
    // (a pause of 300 ms was a guess a loaded machine could outrun).
    let traced = spy.output_until("TROLJointAbs 2 0.25", 1, 30).join("\n");
    assert!(
        traced.contains("REQUEST #") && traced.contains(": TROLForwardKin j(0, 0.5, 1)"),
        "{traced}"
    );
    assert!(
        traced.contains("0 (success), values (551.510864, "),
        "{traced}"
    );
    assert!(traced.contains("TROLJointAbs 2 0.25"), "{traced}");
    let logged = ctl
        .output_until("TROLJointAbs: `jointNum` 7 out of 1..6", 1, 30)
        .join("\n");
    assert!(
        logged.contains("TROLForwardKin j(0, 0.5, 1) -> 0 (success), values (551.510864"),
        "{logged}"
    );
    assert!(
        logged.contains("TROLJointAbs: `jointNum` 7 out of 1..6"),
        "{logged}"
    );
}

/// Call a built-in command through the Rust API by its table entry: a command added to the
/// table without a Robot method fails here.
fn call_rust(robot: &mut Robot, code: u8) -> trol::Result<()> {
    use trol::table::*;
    let cart = Location::Cart(vec![400.0, 0.0, 300.0, 0.0, 1.5, 0.0]);
    match code {
        TROL_APPRO => robot.appro("p1", &[-10.0], false),
        TROL_APPRO_II => robot.appro_ii(&cart, &[-10.0], false),
        TROL_CLOSE => robot.close_gripper(50),
        TROL_DEPART => robot.depart(&[-10.0], false),
        TROL_FINISH => robot.finish(),
        TROL_GRIP => robot.grip(20),
        TROL_HALT => robot.halt(),
        TROL_HOME => robot.home(0),
        TROL_JOG => robot.jog(&[0.0, 0.0, -5.0], false),
        TROL_JOINT => robot.joint(1, 0.01),
        TROL_MA => robot.ma(&[0.0, 0.5, 1.0]),
        TROL_MI => robot.mi(&[0.01]),
        TROL_MOVE => robot.move_to("p1", false),
        TROL_MOVE_II => robot.move_ii(&cart, false),
        TROL_OPEN => robot.open_gripper(50),
        TROL_READY => robot.ready(),
        TROL_SET_TOOL_TRANSFORM => robot.set_tool_transform(&[0.0; 6]),
        TROL_SPEED => robot.speed(100),
        TROL_GET_POSITION => robot.position(Tag::Cart, PosMode::Actual).map(drop),
        TROL_TERMINATE_PCP => robot.terminate_pcp(),
        TROL_GET_STATUS => robot.status().map(drop),
        TROL_GET_VERSION => robot.check_version().map(drop),
        TROL_SET_WATCHDOG => robot.set_watchdog(std::time::Duration::ZERO),
        TROL_GET_CODES => robot.get_codes().map(drop),
        TROL_GET_REPLY_TIME => robot.reply_time().map(drop),
        TROL_GET_GRIPPER => robot.gripper().map(drop),
        TROL_LIST_LOCATIONS => robot.locations().map(drop),
        TROL_HERE => robot.here("p2", Tag::Cart),
        TROL_DEFINE => robot.define(
            "p3",
            &trol::Location::Cart(vec![400.0, 0.0, 300.0, 0.0, 1.5, 0.0]),
        ),
        TROL_DELETE_LOCATION => robot.delete_location("p2"),
        // The embedded simulator here has no locations file: the controller says so.
        TROL_SAVE_LOCATIONS => match robot.save_locations() {
            Err(e) if e.code().0 == trol_a465::arm::code::NO_FILE => Ok(()),
            other => other,
        },
        TROL_TRAJECTORY => robot
            .trajectory(&[trol::Waypoint {
                time: 1.0,
                joints: [0.1, 0.5, 1.0, 0.0, 0.0, 0.0],
            }])
            .map(drop),
        other => panic!("command {other} of the table has no method on Robot"),
    }
}

#[test]
fn every_surface_knows_every_builtin_command() {
    // Rust: a method per command, and it reaches the controller.
    let settings = SimSettings {
        time_scale: 100.0,
        locations: vec![(
            "p1".into(),
            trol_a465::arm::Stored::Cart([400.0, 0.0, 300.0, 0.0, 1.5, 0.0]),
        )],
        ..SimSettings::default()
    };
    let mut robot = trol::Connect::sim(settings).connect().unwrap();
    robot.home(0).unwrap();
    // TerminatePCP last: it ends the server.
    let mut defs: Vec<_> = BUILTIN.to_vec();
    defs.sort_by_key(|d| d.code == trol::table::TROL_TERMINATE_PCP);
    for def in defs {
        call_rust(&mut robot, def.code)
            .map_err(|e| format!("{}: {e}", def.name))
            .unwrap();
    }

    // The interpreter: a usage line each.
    let dir = scratch("surfaces");
    let o = trol(&dir, &["interp"], "help\n");
    let (out, _) = text(&o);
    for def in BUILTIN {
        let short = def.short_name();
        assert!(
            out.lines().any(|l| {
                let l = l.trim_start();
                l.strip_prefix(short)
                    .is_some_and(|rest| rest.is_empty() || rest.starts_with(' '))
            }),
            "`help` lacks {}:\n{out}",
            def.name
        );
    }

    // The C header and the library: every function declared, exported and linked.
    let mut c = String::from("#include <stdio.h>\n#include \"trol.h\"\nint main(void) {\n");
    for def in BUILTIN {
        c.push_str(&format!(
            "    printf(\"%s %p\\n\", \"{0}\", (void *)&{0});\n",
            def.name
        ));
    }
    c.push_str("    return 0;\n}\n");
    let src = dir.join("symbols.c");
    std::fs::write(&src, c).unwrap();
    for link in [Link::Static, Link::Shared] {
        let exe = compile(&src, "symbols", link);
        let o = program(&exe).output().unwrap();
        let (out, err) = text(&o);
        assert!(o.status.success(), "{out}\n{err}");
        for def in BUILTIN {
            assert!(out.contains(&format!("{} 0x", def.name)), "{link:?}: {out}");
        }
    }
}

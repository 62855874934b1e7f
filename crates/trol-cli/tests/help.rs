//! The utilities' help: wrapped to the terminal, and complete where it lists names.

mod common;

use common::{scratch, text, trol};

/// `trol sim --help` names every variant of both simulated controllers (it named 16 of the
/// C500's 21).
#[test]
fn sim_help_names_every_variant() {
    let dir = scratch("sim-help-variants");
    let out = trol(&dir, &["sim", "--help"], "");
    let (help, _) = text(&out);
    // The help wraps its lines: compare the words.
    let words: String = help.split_whitespace().collect::<Vec<_>>().join(" ");
    for (name, _) in trol_rapl::c500::VARIANTS
        .iter()
        .chain(trol_mars::mars8::VARIANTS)
    {
        assert!(
            words.contains(&format!(" {name},")) || words.contains(&format!(" {name}.")),
            "`trol sim --help` does not name the variant {name}:\n{help}"
        );
    }
}

/// Every help page wraps to the terminal's width (COLUMNS, as a terminal of 80 columns
/// gives it), never past it (issue 44: lines broke mid-word in 80 columns).
#[test]
fn help_wraps_to_the_terminal() {
    let dir = scratch("help-wraps");
    for args in [
        &["--help"][..],
        &["sim", "--help"],
        &["gateway", "--help"],
        &["interp", "--help"],
        &["rapl", "probe", "--help"],
        &["mars", "probe", "--help"],
        &["c500c", "probe", "--help"],
        &["init", "--help"],
        &["config", "--help"],
        &["demo", "--help"],
        &["trace", "--help"],
        &["link", "--help"],
        &["urdf", "--help"],
        &["completions", "--help"],
        &["rapl", "term", "--help"],
        &["c500c", "step", "--help"],
        &["c500c", "backup", "--help"],
        &["c500c", "restore", "--help"],
        &["ports", "--help"],
        &["cleanup", "--help"],
    ] {
        let out = std::process::Command::new(common::TROL)
            .args(args)
            .env("COLUMNS", "80")
            .current_dir(&dir)
            .output()
            .unwrap();
        let (help, err) = text(&out);
        assert!(out.status.success(), "{args:?}: {err}");
        // Clap writes the usage line whole (a shell command; it does not wrap it).
        for line in help.lines().filter(|l| !l.starts_with("Usage:")) {
            assert!(
                line.chars().count() <= 80,
                "`trol {}` has a line of {} columns:\n{line}",
                args.join(" "),
                line.chars().count()
            );
        }
        // An example whose comment wrapped leaves a line of prose among the examples
        // (issue 68, item 4: "  (or the simulator)"): every line of them is a command.
        // A command may go on after a `\`, and a comment may stand on a line of its own.
        for block in help.split("Examples:\n").skip(1) {
            let mut continued = false;
            for line in block.lines().take_while(|l| !l.is_empty()) {
                let ok = line.starts_with("  ")
                    && (continued || line.contains("trol") || line.trim_start().starts_with('#'));
                assert!(
                    ok,
                    "`trol {}`: an example's comment wrapped:\n{line}",
                    args.join(" ")
                );
                continued = line.ends_with('\\');
            }
        }
    }
}

/// The help's first line names every controller TROL drives, not only the C500 (issue 44).
#[test]
fn the_help_names_every_controller() {
    let dir = scratch("help-controllers");
    let out = trol(&dir, &["--help"], "");
    let (help, _) = text(&out);
    let first: String = help
        .split("\n\n")
        .next()
        .unwrap()
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ");
    for name in ["C500", "RAPL-II", "MARS 8", "C500C", "simulated"] {
        assert!(
            first.contains(name),
            "the help's top does not name {name}: {first}"
        );
    }
    // The lines of the commands that serve or simulate a controller name every one.
    let words: String = help.split_whitespace().collect::<Vec<_>>().join(" ");
    for (command, names) in [
        ("gateway", &["C500", "MARS 8", "C500C"][..]),
        ("sim", &["RAPL-II", "MARS 8", "C500C"]),
    ] {
        let line = words
            .split(&format!(" {command} "))
            .nth(1)
            .unwrap_or_else(|| panic!("no `{command}` in {help}"));
        let line = &line[..line
            .find(" rapl ")
            .or(line.find(" link "))
            .unwrap_or(line.len())];
        for name in names {
            assert!(
                line.contains(name),
                "`{command}` does not name {name}: {line}"
            );
        }
    }
}

/// Every command that takes `--port` names every kind of port in its help: the simulator,
/// a TROL server's devices and sockets, and each real controller's prefix (issue 68, item 4:
/// `trol interp --port` named no `rapl:`, `mars:`, `c500c:`).
#[test]
fn every_port_option_names_every_prefix() {
    let dir = scratch("help-ports");
    for command in ["interp", "init", "cleanup", "config", "demo"] {
        let out = trol(&dir, &[command, "--help"], "");
        let (help, _) = text(&out);
        let words: String = help.split_whitespace().collect::<Vec<_>>().join(" ");
        let port = words
            .split("--port <PORT>")
            .nth(1)
            .unwrap_or_else(|| panic!("`trol {command}` has no --port: {help}"));
        for prefix in ["sim", "socket://", "listen://", "rapl:", "mars:", "c500c:"] {
            assert!(
                port.contains(prefix),
                "`trol {command} --help` does not name {prefix} at --port: {port}"
            );
        }
    }
}

/// A negative number is a value wherever a value is expected: the value's own check answers
/// (it says what it takes), not clap's "unexpected argument '-1'" (issue 44, item 3).
#[test]
fn a_negative_number_is_a_value() {
    let dir = scratch("negative-values");
    for (args, says) in [
        (
            &["demo", "--linger", "-1"][..],
            "give 0 to 3600 seconds, not -1",
        ),
        (
            &["demo", "--time-scale", "-1"],
            "not a number greater than 0",
        ),
        (
            &["sim", "--time-scale", "-2.5"],
            "not a number greater than 0",
        ),
    ] {
        let out = trol(&dir, args, "");
        let (_, err) = text(&out);
        assert!(!out.status.success(), "{args:?} was taken");
        assert!(err.contains(says), "{args:?}: {err}");
        assert!(!err.contains("unexpected argument"), "{args:?}: {err}");
    }
}

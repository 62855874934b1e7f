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
    ] {
        let out = std::process::Command::new(common::TROL)
            .args(args)
            .env("COLUMNS", "80")
            .current_dir(&dir)
            .output()
            .unwrap();
        let (help, err) = text(&out);
        assert!(out.status.success(), "{args:?}: {err}");
        for line in help.lines() {
            assert!(
                line.chars().count() <= 80,
                "`trol {}` has a line of {} columns:\n{line}",
                args.join(" "),
                line.chars().count()
            );
        }
    }
}

//! An A465 on its C500C: a 1998 TROL program (the position example), `trol interp` and the
//! pick example against `trol sim --c500c` over a pty pair, on every variant: in-process
//! (`c500c:PTY` in trol.cfg, with the matching profile and with a contrary one) and through
//! `trol gateway --controller c500c:PTY`.

#[path = "../../trol-c/tests/common/cbuild.rs"]
mod cbuild;
mod common;

use std::path::Path;

use common::{Background, scratch, text, trol};

/// `trol sim --c500c --variant NAME` on a new pty, the profile that matches it in `dir`
/// (c500c.toml), and a trol.cfg that drives it in-process through `c500c:`, with the profile
/// when `settled`.
fn c500c_sim(dir: &Path, variant: &str, settled: bool) -> Background {
    c500c_sim_profiled(dir, variant, settled, false)
}

/// [`c500c_sim`], with the profile of the contrary motion return where `contrary`.
fn c500c_sim_profiled(dir: &Path, variant: &str, settled: bool, contrary: bool) -> Background {
    let out = trol(
        dir,
        &["sim", "--c500c", "--variant", variant, "--print-profile"],
        "",
    );
    assert!(out.status.success(), "{}", text(&out).1);
    let mut profile = String::from_utf8(out.stdout).unwrap();
    if contrary {
        profile = if profile.contains("motion-return = \"start\"") {
            profile.replace("motion-return = \"start\"", "motion-return = \"end\"")
        } else {
            profile.replace("motion-return = \"end\"", "motion-return = \"start\"")
        };
    }
    std::fs::write(dir.join("c500c.toml"), profile).unwrap();
    // The application's variables: the examples' locations, as a lab's `.v3` file has them.
    let locations = cbuild::root().join("examples").join("locations.txt");
    let locations = locations.to_str().unwrap();
    let args = [
        "sim",
        "--c500c",
        "--variant",
        variant,
        "--time-scale",
        "10",
        "--locations",
        locations,
    ];
    let sim = Background::start(dir, &args, "serving on ");
    c500c_cfg(dir, &sim.name, settled);
    sim
}

/// A trol.cfg in `dir` that drives the simulated C500C on `port` in-process through `c500c:`,
/// with the profile c500c.toml where `settled`.
fn c500c_cfg(dir: &Path, port: &str, settled: bool) {
    let profile = if settled {
        "c500c-profile = c500c.toml\n"
    } else {
        ""
    };
    std::fs::write(
        dir.join("trol.cfg"),
        format!("9600\nc500c:{port}\n0 0 0 0 0 0\n{profile}"),
    )
    .unwrap();
}

fn run_example(name: &str, dir: &Path) -> (bool, String, String) {
    let exe = cbuild::compile(
        &cbuild::root().join("examples").join(format!("{name}.c")),
        &format!("{name}-c500c"),
        cbuild::Link::Static,
    );
    let run = cbuild::program(&exe).current_dir(dir).output().unwrap();
    (
        run.status.success(),
        String::from_utf8_lossy(&run.stdout).into_owned(),
        String::from_utf8_lossy(&run.stderr).into_owned(),
    )
}

/// A variant whose console TROL cannot check a line on before ash runs it (no echo, or a
/// Ctrl-C that keeps a typed line): TROL types only reads, and refuses every other call with
/// BIOS_UNSUPPORTED (issue 62).
fn reads_only(variant: &str) -> bool {
    matches!(variant, "echo-off" | "ctrl-c-keeps-line")
}

/// Runs the position example in `dir` against `sim` playing `variant` with the profile that
/// matches it, and checks it: done, or (the pendant holding the point of control) failed with
/// nothing moved. Returns whether it was done.
fn check_position(variant: &str, dir: &Path, sim: &Background) -> bool {
    let (ok, out, err) = run_example("position", dir);
    if variant == "pendant-holds" || reads_only(variant) {
        // Home refused (BIOS_NO_CONTROL), so the joint motion is refused unhomed: nothing
        // moved, and the program says it failed.
        assert!(!ok && out.contains("position: FAILED"), "{out}");
        assert!(
            !sim.output().iter().any(|l| l.contains("typed: joint")),
            "{out}"
        );
        return false;
    }
    assert!(
        ok,
        "{variant}:\n{out}\n{err}\nsimulated C500C:\n{}",
        sim.output().join("\n")
    );
    assert!(out.contains("position: done"), "{out}");
    true
}

/// The position example (Home, a joint motion, the three position forms, a location it does
/// not know) runs unchanged on every variant with the matching profile, but where the pendant
/// holds the point of control: then it fails with that said.
fn position_on_variant(variant: &str) {
    let dir = scratch(&format!("c500c-{variant}"));
    let sim = c500c_sim(&dir, variant, true);
    if !check_position(variant, &dir, &sim) {
        return;
    }
    drop(sim);
    // The contrary profile: the example works, or fails with the arm where TROL said (the
    // example checks the position it reads after a success).
    let dir = scratch(&format!("c500c-{variant}-contrary"));
    let sim = c500c_sim_profiled(&dir, variant, true, true);
    let (ok, out, err) = run_example("position", &dir);
    if ok {
        assert!(out.contains("position: done"), "{out}");
    } else {
        assert!(
            out.contains("position: FAILED") || err.contains("InitTROL"),
            "{variant}, contrary:\n{out}\n{err}\n{}",
            sim.output().join("\n")
        );
    }
}

/// The manual's pick example (Appro joint-interpolated and straight, Move straight, Close,
/// Depart) on every variant, `test_001` a cartesian location of the application's: done, or
/// (the pendant holding control, a print form TROL does not read, no gripper set) failed with
/// the reason and the arm never where it was not sent.
fn pick_on_variant(variant: &str) {
    let dir = scratch(&format!("c500c-pick-{variant}"));
    let sim = c500c_sim(&dir, variant, true);
    check_pick(variant, &dir, &sim);
}

/// Runs the pick example in `dir` against `sim` playing `variant` with the profile that
/// matches it, and checks it ([`pick_on_variant`]).
fn check_pick(variant: &str, dir: &Path, sim: &Background) {
    let (ok, out, err) = run_example("pick", dir);
    let log = sim.output().join("\n");
    match variant {
        v if reads_only(v) => {
            assert!(!ok, "{out}");
            assert!(
                out.contains("TROLHome(0)                  -> -11"),
                "{out}\n{err}"
            );
            assert!(!log.contains("typed: move"), "{log}");
        }
        "pendant-holds" => {
            assert!(!ok, "{out}");
            assert!(
                out.contains("TROLHome(0)                  -> -27"),
                "{out}\n{err}"
            );
        }
        "print-braced" => {
            // `print test_001` in a form TROL does not read: UNSURE, nothing moved to it.
            assert!(!ok, "{out}");
            assert!(out.contains("-> -32054"), "{out}\n{err}");
            assert!(!log.contains("typed: move"), "{log}");
        }
        "gripper-none" => {
            assert!(!ok, "{out}");
            assert!(
                out.contains("TROLClose(60)                -> -11"),
                "{out}\n{err}"
            );
            // Every motion went, the Depart too.
            assert!(out.contains("TROLDepart(&loc, 1)          -> 0"), "{out}");
        }
        _ => {
            assert!(ok, "{variant}:\n{out}\n{err}\nsimulated C500C:\n{log}");
            common::check_pick(&out);
        }
    }
}

macro_rules! pick_on_variants {
    ($($test:ident => $name:literal),* $(,)?) => {
        $(
            #[test]
            fn $test() {
                pick_on_variant($name);
            }
        )*

        #[test]
        fn the_pick_example_runs_on_every_variant() {
            let tested = [$($name),*];
            for (name, _) in trol_c500c::c500c::VARIANTS {
                assert!(tested.contains(name), "variant {name} has no pick run");
            }
        }
    };
}

pick_on_variants! {
    pick_default => "default",
    pick_return_at_end => "return-at-end",
    pick_error_prefixed => "error-prefixed",
    pick_error_bracketed => "error-bracketed",
    pick_echo_off => "echo-off",
    pick_ctrl_c_keeps_line => "ctrl-c-keeps-line",
    pick_lf_only => "lf-only",
    pick_pendant_holds => "pendant-holds",
    pick_unstoppable => "unstoppable",
    pick_ctrl_c_no_prompt => "ctrl-c-no-prompt",
    pick_power_loss_silent => "power-loss-silent",
    pick_print_braced => "print-braced",
    pick_gripper_air => "gripper-air",
    pick_gripper_none => "gripper-none",
    pick_grip_return_at_end => "grip-return-at-end",
    pick_world_xyz => "world-xyz",
    pick_world_flange => "world-flange",
    pick_pulses_offset => "pulses-offset",
    pick_rows_apart => "rows-apart",
    pick_home_elsewhere => "home-elsewhere",
    pick_cloc_reversed => "cloc-reversed",
    pick_setvalid_silent => "setvalid-silent",
}

macro_rules! position_on_variants {
    ($($test:ident => $name:literal),* $(,)?) => {
        $(
            #[test]
            fn $test() {
                position_on_variant($name);
            }
        )*

        #[test]
        fn the_position_example_runs_on_every_variant() {
            let tested = [$($name),*];
            for (name, _) in trol_c500c::c500c::VARIANTS {
                assert!(tested.contains(name), "variant {name} has no C example run");
            }
        }
    };
}

position_on_variants! {
    position_default => "default",
    position_return_at_end => "return-at-end",
    position_error_prefixed => "error-prefixed",
    position_error_bracketed => "error-bracketed",
    position_echo_off => "echo-off",
    position_ctrl_c_keeps_line => "ctrl-c-keeps-line",
    position_lf_only => "lf-only",
    position_pendant_holds => "pendant-holds",
    position_unstoppable => "unstoppable",
    position_ctrl_c_no_prompt => "ctrl-c-no-prompt",
    position_power_loss_silent => "power-loss-silent",
    position_print_braced => "print-braced",
    position_gripper_air => "gripper-air",
    position_gripper_none => "gripper-none",
    position_grip_return_at_end => "grip-return-at-end",
    position_world_xyz => "world-xyz",
    position_world_flange => "world-flange",
    position_pulses_offset => "pulses-offset",
    position_rows_apart => "rows-apart",
    position_home_elsewhere => "home-elsewhere",
    position_cloc_reversed => "cloc-reversed",
    position_setvalid_silent => "setvalid-silent",
}

/// Without a profile nothing moves, and the interpreter says which key to set; with one that
/// does not state `world-angles`, the pick example homes and then stops at its first
/// cartesian motion with the reason, nothing moved to it.
#[test]
fn unsettled_motions_are_refused_with_the_key_to_set() {
    let dir = scratch("c500c-unsettled");
    let sim = c500c_sim(&dir, "default", false);
    let o = trol(&dir, &["interp", "-v"], "home 0\n");
    let (out, err) = text(&o);
    assert!(!o.status.success(), "{out}");
    assert!(out.contains("BIOS_UNSETTLED"), "{out}\n{err}");
    assert!(err.contains("motion-return"), "{err}");
    // The simulator logs what was typed after it answered: read until armstat is there.
    let typed = sim.output_until("typed: armstat", 1, 30);
    assert!(
        typed.iter().any(|l| l.contains("typed: armstat")),
        "{typed:?}"
    );
    assert!(
        !typed.iter().any(|l| l.contains("typed: home")),
        "nothing moved: {typed:?}"
    );
    // With a profile that states when the prompt returns but not how the WORLD row's angles
    // compose: joint motions go, cartesian ones are refused before sending, naming the key.
    let toml = std::fs::read_to_string(dir.join("c500c.toml")).unwrap();
    let without: String = toml
        .lines()
        .filter(|l| !l.starts_with("world-angles"))
        .map(|l| format!("{l}\n"))
        .collect();
    assert_ne!(without, toml, "the printed profile states world-angles");
    std::fs::write(dir.join("c500c.toml"), without).unwrap();
    std::fs::write(
        dir.join("trol.cfg"),
        format!(
            "9600\nc500c:{}\n0 0 0 0 0 0\nc500c-profile = c500c.toml\nlocations = {}\n",
            sim.name,
            cbuild::root().join("examples/locations.txt").display()
        ),
    )
    .unwrap();
    let (ok, out, err) = run_example("pick", &dir);
    assert!(!ok, "{out}");
    assert!(out.contains("TROLHome(0)                  -> 0"), "{out}");
    assert!(
        out.contains("TROLAppro(test_001, -90, 0)  -> -28"),
        "{out}\n{err}"
    );
    let typed = sim.output();
    assert!(
        !typed.iter().any(|l| l.contains("typed: move")),
        "{typed:?}"
    );
}

/// The C examples unchanged through `trol gateway --controller c500c:` in front of the
/// simulated C500C playing `variant`: the position example, then the pick example, each done
/// or failed safe as in-process ([`check_position`], [`check_pick`]); the manual's codes cross
/// the gateway as they are.
fn examples_through_gateway(variant: &str) {
    let dir = scratch(&format!("c500c-gateway-examples-{variant}"));
    let (gw, sim) = gateway(&dir, variant);
    check_position(variant, &dir, &sim);
    // CleanupTROL ended the server, as the manual has it: activated again for the next.
    let init = trol(&dir, &["init", "--port", &gw.name], "");
    let (o, e) = text(&init);
    assert!(init.status.success(), "{o}{e}");
    check_pick(variant, &dir, &sim);
}

/// The simulated C500C playing `variant` and `trol gateway --controller c500c:` in front of it
/// (with the profile that matches it), activated (`trol init`), and a trol.cfg in `dir` that
/// drives the gateway as a 1998 host drives a PCP server. Returns the gateway and the simulated
/// controller, which must live as long.
fn gateway(dir: &Path, variant: &str) -> (Background, Background) {
    let sim = c500c_sim(dir, variant, true);
    let gw = Background::start(
        dir,
        &[
            "gateway",
            "--controller",
            &format!("c500c:{}", sim.name),
            "--profile",
            "c500c.toml",
        ],
        "serving on ",
    );
    let init = trol(dir, &["init", "--port", &gw.name], "");
    let (o, e) = text(&init);
    assert!(init.status.success(), "{o}{e}");
    std::fs::write(
        dir.join("trol.cfg"),
        format!("9600\n{}\n0 0 0 0 0 0\n", gw.name),
    )
    .unwrap();
    (gw, sim)
}

/// `trol gateway --controller c500c:` in front of the simulated C500C playing `variant`,
/// activated (`trol init`), and the interpreter through it: Home, a joint motion, where the
/// arm is. Where the pendant holds the point of control, Home is refused with that code.
/// Returns the folder, the gateway and the simulated controller, which must live as long.
fn through_gateway(variant: &str) -> (std::path::PathBuf, Background, Background) {
    let dir = scratch(&format!("c500c-gateway-{variant}"));
    let (gw, sim) = gateway(&dir, variant);
    let o = trol(
        &dir,
        &["interp"],
        "home 0\nfinish\njoint 1 0.3\nfinish\ngetposition joint actual\n",
    );
    let (out, err) = text(&o);
    if variant == "pendant-holds" {
        assert!(!o.status.success(), "{out}");
        assert!(out.contains("BIOS_NO_CONTROL"), "{out}\n{err}");
        return (dir, gw, sim);
    }
    if reads_only(variant) {
        assert!(!o.status.success(), "{out}");
        assert!(out.contains("BIOS_UNSUPPORTED"), "{out}\n{err}");
        return (dir, gw, sim);
    }
    assert!(
        o.status.success(),
        "{variant}: {out}\n{err}\ngateway:\n{}",
        gw.output().join("\n")
    );
    assert!(
        out.contains("getposition joint actual  ->  j(0.3") || out.contains("j(0.299"),
        "{out}"
    );
    // A precision point taught, left and reached again by name, as ash's own variable.
    let o = trol(
        &dir,
        &["interp"],
        "here #g1 prec\njoint 2 0.2\nfinish\nmove #g1\nfinish\ngetposition joint actual\n\
         listlocations\n",
    );
    let (out, err) = text(&o);
    if variant == "print-braced" {
        // `print` in a form TROL does not read: UNSURE at Here, nothing moved after.
        assert!(!o.status.success(), "{out}");
        assert!(out.contains("TROL_ERR_ROBOT_UNSURE"), "{out}\n{err}");
        assert!(!out.contains("joint 2 0.2  ->"), "{out}");
        return (dir, gw, sim);
    }
    assert!(
        o.status.success(),
        "{variant}: {out}\n{err}\ngateway:\n{}",
        gw.output().join("\n")
    );
    // Back where it was taught: joint 1 at 0.3 (within the encoders' dither), joint 2 at 0.
    let back = out
        .lines()
        .find_map(|l| l.strip_prefix("getposition joint actual  ->  j("))
        .and_then(|v| v.strip_suffix(')'))
        .map(|v| {
            v.split(", ")
                .map(|x| x.parse::<f64>().unwrap())
                .collect::<Vec<_>>()
        })
        .unwrap_or_else(|| panic!("{out}"));
    assert!(
        (back[0] - 0.3).abs() < 1e-3 && back[1].abs() < 1e-3,
        "{out}"
    );
    assert!(out.contains("listlocations  ->  #g1 p("), "{out}");
    (dir, gw, sim)
}

macro_rules! gateway_on_variants {
    ($($test:ident => $name:literal),* $(,)?) => {
        $(
            mod $test {
                #[test]
                fn interpreter() {
                    super::through_gateway($name);
                }

                #[test]
                fn c_examples() {
                    super::examples_through_gateway($name);
                }
            }
        )*

        #[test]
        fn the_gateway_runs_on_every_variant() {
            let tested = [$($name),*];
            for (name, _) in trol_c500c::c500c::VARIANTS {
                assert!(tested.contains(name), "variant {name} has no gateway runs");
            }
        }
    };
}

gateway_on_variants! {
    gateway_default => "default",
    gateway_return_at_end => "return-at-end",
    gateway_error_prefixed => "error-prefixed",
    gateway_error_bracketed => "error-bracketed",
    gateway_echo_off => "echo-off",
    gateway_ctrl_c_keeps_line => "ctrl-c-keeps-line",
    gateway_lf_only => "lf-only",
    gateway_pendant_holds => "pendant-holds",
    gateway_unstoppable => "unstoppable",
    gateway_ctrl_c_no_prompt => "ctrl-c-no-prompt",
    gateway_power_loss_silent => "power-loss-silent",
    gateway_print_braced => "print-braced",
    gateway_gripper_air => "gripper-air",
    gateway_gripper_none => "gripper-none",
    gateway_grip_return_at_end => "grip-return-at-end",
    gateway_world_xyz => "world-xyz",
    gateway_world_flange => "world-flange",
    gateway_pulses_offset => "pulses-offset",
    gateway_rows_apart => "rows-apart",
    gateway_home_elsewhere => "home-elsewhere",
    gateway_cloc_reversed => "cloc-reversed",
    gateway_setvalid_silent => "setvalid-silent",
}

/// First contact reads only: the findings are said, every byte is in the transcript, and
/// nothing that moves the arm or changes a setting was typed.
#[test]
fn the_probe_reads_only_and_records_every_byte() {
    let dir = scratch("c500c-probe");
    let sim = c500c_sim(&dir, "pendant-holds", true);
    let o = trol(
        &dir,
        &[
            "c500c",
            "probe",
            "--controller",
            &format!("c500c:{}", sim.name),
            "--out",
            "first.txt",
        ],
        "",
    );
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert!(out.contains("an A465 arm, power on"), "{out}");
    assert!(
        out.contains("the pendant holds the point of control"),
        "{out}"
    );
    let transcript = std::fs::read_to_string(dir.join("first.txt")).unwrap();
    assert!(transcript.contains("> armstat\\x0d"), "{transcript}");
    let typed: Vec<String> = sim
        .output_until("typed: y", 1, 10)
        .into_iter()
        .filter_map(|l| l.split_once("typed: ").map(|(_, t)| t.trim().to_string()))
        .filter(|t| !t.is_empty())
        .collect();
    assert_eq!(
        typed,
        [
            "crosver", "ash test", "robotver", "armstat", "w0", "w2", "speed", "exit", "y"
        ],
        "{typed:?}"
    );
}

/// `trol c500c step NAME` against `sim` with c500c.toml, its transcript into `out`, with
/// `extra` arguments and `input` typed.
fn run_step(
    dir: &Path,
    sim: &Background,
    name: &str,
    out: &str,
    extra: &[&str],
    input: &str,
) -> std::process::Output {
    let mut a = vec![
        "c500c",
        "step",
        name,
        "--controller",
        sim.name.as_str(),
        "--profile",
        "c500c.toml",
        "--out",
        out,
    ];
    a.extend_from_slice(extra);
    trol(dir, &a, input)
}

/// A supervised step answered `no`: it fails, says nothing was sent, and the profile is
/// `before` still.
fn step_unconfirmed(
    dir: &Path,
    step: &dyn Fn(&[&str], &str) -> std::process::Output,
    before: &str,
) {
    let o = step(&[], "no\n");
    let (out, err) = text(&o);
    assert!(!o.status.success(), "{out}");
    assert!(err.contains("not confirmed: nothing was sent"), "{err}");
    assert_eq!(
        std::fs::read_to_string(dir.join("c500c.toml")).unwrap(),
        before
    );
}

/// The supervised step `motion-return` (`trol c500c step`): not confirmed, nothing is
/// typed; confirmed, it moves joint 6 and back at 5 % and writes what it saw into the
/// profile, keeping its other keys: `end` on a controller whose prompt returns at a
/// motion's end.
#[test]
fn the_motion_return_step_asks_first_and_writes_only_what_it_saw() {
    let dir = scratch("c500c-step");
    let args = [
        "sim",
        "--c500c",
        "--variant",
        "return-at-end",
        "--homed",
        "--time-scale",
        "1",
    ];
    let sim = Background::start(&dir, &args, "serving on ");
    std::fs::write(dir.join("c500c.toml"), "settle-ms = 400\n").unwrap();
    let step = |extra: &[&str], input: &str| {
        run_step(&dir, &sim, "motion-return", "step.txt", extra, input)
    };
    step_unconfirmed(&dir, &step, "settle-ms = 400\n");

    let o = step(&["--yes"], "");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert!(out.contains("motion-return = \"end\""), "{out}");
    let profile = std::fs::read_to_string(dir.join("c500c.toml")).unwrap();
    assert!(profile.contains("motion-return = \"end\""), "{profile}");
    assert!(profile.contains("settle-ms = 400"), "{profile}");
    let transcript = std::fs::read_to_string(dir.join("step.txt")).unwrap();
    assert!(transcript.contains("> joint 6,3\\x0d"), "{transcript}");
    // Only the confirmed run typed a motion.
    let typed: Vec<String> = sim
        .output_until("typed: y", 1, 30)
        .into_iter()
        .filter_map(|l| l.split_once("typed: ").map(|(_, t)| t.trim().to_string()))
        .filter(|t| t.starts_with("joint") || t.starts_with("speed "))
        .collect();
    assert_eq!(
        typed,
        ["speed 5", "joint 6,3", "joint 6,-3", "speed 100"],
        "{typed:?}"
    );
}

/// `trol c500c step pulses` asks first; confirmed, it moves each joint by 3 degrees and back
/// and writes each joint's pulses per degree and where it counts from (a controller whose
/// axes count from elsewhere than zero, and joint 3 the other way), the profile's other keys
/// kept. With that profile the interpreter approaches a precision point it taught.
#[test]
fn the_pulses_step_asks_first_and_its_profile_approaches_a_precision_point() {
    let dir = scratch("c500c-pulses");
    let print = trol(
        &dir,
        &[
            "sim",
            "--c500c",
            "--variant",
            "pulses-offset",
            "--print-profile",
        ],
        "",
    );
    let unsettled: String = String::from_utf8(print.stdout)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with("pulses-"))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(dir.join("c500c.toml"), &unsettled).unwrap();
    let args = [
        "sim",
        "--c500c",
        "--variant",
        "pulses-offset",
        "--homed",
        "--time-scale",
        "10",
    ];
    let sim = Background::start(&dir, &args, "serving on ");
    let step =
        |extra: &[&str], input: &str| run_step(&dir, &sim, "pulses", "pulses.txt", extra, input);
    step_unconfirmed(&dir, &step, &unsettled);
    let o = step(&["--yes"], "");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    let profile = trol_c500c::Profile::from_file(&dir.join("c500c.toml")).unwrap();
    let want = trol_c500c::c500c::offset_pulses();
    let got = profile.pulses().unwrap_or_else(|| panic!("{out}"));
    for j in 0..6 {
        let k = want.per_degree[j];
        assert!((got.per_degree[j] - k).abs() <= 0.001 * k.abs(), "{got:?}");
        assert!((got.at_zero[j] - want.at_zero[j]).abs() <= 100, "{got:?}");
    }
    assert!(profile.world_angles.is_some() && profile.motion_return.is_some());
    let transcript = std::fs::read_to_string(dir.join("pulses.txt")).unwrap();
    assert!(transcript.contains("> joint 3,-3\\x0d"), "{transcript}");
    // Only the confirmed run typed a motion: six joints there and back.
    let typed: Vec<String> = sim
        .output_until("typed: y", 1, 30)
        .into_iter()
        .filter_map(|l| l.split_once("typed: ").map(|(_, t)| t.trim().to_string()))
        .filter(|t| t.starts_with("joint"))
        .collect();
    assert_eq!(typed.len(), 12, "{typed:?}");

    // The profile at work: a point taught off zero, left, and approached.
    c500c_cfg(&dir, &sim.name, true);
    let o = trol(
        &dir,
        &["interp"],
        "joint 2 0.3\nfinish\njoint 3 0.6\nfinish\njoint 5 0.4\nfinish\n\
         here #bin prec\ndepart c(-30) straight\nfinish\nappro #bin c(-10)\nfinish\n\
         getposition joint actual\n",
    );
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert!(out.contains("appro #bin c(-10)  ->  0 (success)"), "{out}");
    // 10 mm back from the point along the tool's axis, as TROL's kinematics have it.
    let q: Vec<f64> = out
        .lines()
        .find_map(|l| l.strip_prefix("getposition joint actual  ->  j("))
        .and_then(|v| v.strip_suffix(')'))
        .unwrap_or_else(|| panic!("{out}"))
        .split(", ")
        .map(|x| x.parse().unwrap())
        .collect();
    let kin = trol_a465::kinematics::Kinematics::new([0.0; 6]);
    let at = kin.fk_xyzypr(&[q[0], q[1], q[2], q[3], q[4], q[5]]);
    let taught = kin.fk_xyzypr(&[0.0, 0.3, 0.6, 0.0, 0.4, 0.0]);
    let gap = (0..3)
        .map(|j| (at[j] - taught[j]).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!((gap - 10.0).abs() < 0.5, "{gap} mm from the point: {out}");
}

/// `trol c500c step home-pose` (issue 62, item 1): a Home is refused until the profile says
/// where ash homes the arm; the step homes it after `yes`, shows the joints, and writes
/// `home-joints` only once the person at the arm answers `yes` again (a `no` writes
/// nothing); then the interpreter's Home works, and ends with the arm there.
#[test]
fn the_home_pose_step_writes_where_ash_homes_the_arm_once_confirmed() {
    let dir = scratch("c500c-home-pose");
    let sim = Background::start(
        &dir,
        &["sim", "--c500c", "--time-scale", "10"],
        "serving on ",
    );
    let out = trol(&dir, &["sim", "--c500c", "--print-profile"], "");
    let printed = String::from_utf8_lossy(&out.stdout).to_string();
    let without: String = printed
        .lines()
        .filter(|l| !l.starts_with("home-joints"))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(dir.join("c500c.toml"), &without).unwrap();
    c500c_cfg(&dir, &sim.name, true);
    let o = trol(&dir, &["interp"], "home 0\n");
    let (out, err) = text(&o);
    assert!(out.contains("-28 (BIOS_UNSETTLED)"), "{out}");
    // The interpreter says why, in the backend's words.
    assert!(err.contains("home-joints"), "{err}");
    let step = |answers: &str| {
        trol(
            &dir,
            &[
                "c500c",
                "step",
                "home-pose",
                "--controller",
                sim.name.as_str(),
                "--profile",
                "c500c.toml",
                "--out",
                "home.txt",
            ],
            answers,
        )
    };
    // Homed, but the person at the arm does not confirm the marks: nothing written.
    let o = step("yes\nno\n");
    let (out, err) = text(&o);
    assert!(!o.status.success(), "{out}");
    assert!(out.contains("home marks"), "{out}\n{err}");
    let profile = std::fs::read_to_string(dir.join("c500c.toml")).unwrap();
    assert!(!profile.contains("home-joints"), "{profile}");
    let o = step("yes\nyes\n");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    let profile = std::fs::read_to_string(dir.join("c500c.toml")).unwrap();
    // Where the simulated C500C homes (every joint 0), to the encoders' dither.
    let home = trol_c500c::Profile::parse(&profile)
        .unwrap()
        .home_joints
        .unwrap_or_else(|| panic!("{profile}"));
    assert!(home.iter().all(|v| v.abs() < 0.01), "{profile}");
    let o = trol(&dir, &["interp"], "home 0\nfinish\n");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
}

/// `trol c500c step world-angles` reads only: where the arm stands so that both orders of
/// the WORLD row's angles coincide (READY) it settles nothing and says what to do; with a
/// wrist joint turned it writes the controller's reading (the order, and the frame the
/// angles turn), the profile's other keys kept.
#[test]
fn the_world_angles_step_reads_only_and_writes_what_it_saw() {
    world_angles_step_on(
        "world-xyz",
        "world-angles = \"xyz\"",
        "tool-rotation = [0.0, 0.0, 0.0]",
    );
}

/// The same on a controller whose angles turn the public A465 models' flange frame (issue
/// 62, item 3: no cartesian motion was possible there).
#[test]
fn the_world_angles_step_reads_the_frame_the_angles_turn() {
    world_angles_step_on(
        "world-flange",
        "world-angles = \"zyx\"",
        "tool-rotation = [0.0, 90.0, 0.0]",
    );
}

fn world_angles_step_on(variant: &str, angles: &str, frame: &str) {
    let dir = scratch(&format!("c500c-angles-{variant}"));
    let args = [
        "sim",
        "--c500c",
        "--variant",
        variant,
        "--homed",
        "--time-scale",
        "10",
    ];
    let sim = Background::start(&dir, &args, "serving on ");
    std::fs::write(
        dir.join("c500c.toml"),
        "motion-return = \"start\"\nsettle-ms = 400\n",
    )
    .unwrap();
    let step = || {
        trol(
            &dir,
            &[
                "c500c",
                "step",
                "world-angles",
                "--controller",
                sim.name.as_str(),
                "--profile",
                "c500c.toml",
                "--out",
                "angles.txt",
            ],
            "",
        )
    };
    let o = step();
    let (out, err) = text(&o);
    assert!(!o.status.success(), "{out}");
    assert!(out.contains("both orders fit"), "{out}\n{err}");
    assert!(err.contains("nothing settled"), "{err}");
    assert!(
        !std::fs::read_to_string(dir.join("c500c.toml"))
            .unwrap()
            .contains("world-angles")
    );
    // Turn the wrist through the interpreter (joint motions need no world-angles).
    c500c_cfg(&dir, &sim.name, true);
    let o = trol(
        &dir,
        &["interp"],
        "joint 4 0.5\nfinish\njoint 5 0.5\nfinish\n",
    );
    assert!(o.status.success(), "{}", text(&o).0);
    let o = step();
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    let profile = std::fs::read_to_string(dir.join("c500c.toml")).unwrap();
    assert!(profile.contains(angles), "{profile}");
    assert!(profile.contains(frame), "{profile}");
    assert!(profile.contains("settle-ms = 400"), "{profile}");
    let typed: Vec<String> = sim
        .output()
        .into_iter()
        .filter_map(|l| l.split_once("typed: ").map(|(_, t)| t.trim().to_string()))
        .collect();
    // What moved the arm was the interpreter's two joint motions, nothing of the steps'.
    let moving: Vec<&String> = typed
        .iter()
        .filter(|t| {
            ["joint", "move", "home", "speed ", "set"]
                .iter()
                .any(|m| t.starts_with(m))
        })
        .collect();
    assert_eq!(moving, ["joint 4,28.648", "joint 5,28.648"], "{typed:?}");
}

/// A fault script (`trol sim --c500c --console`): the arm's power cut during a motion that
/// `trol interp` waits for. Finish is never success, the interpreter says why, and the next
/// motion is not sent.
#[test]
fn a_power_cut_during_a_motion_is_never_success() {
    let dir = scratch("c500c-power-cut");
    let out = trol(&dir, &["sim", "--c500c", "--print-profile"], "");
    std::fs::write(dir.join("c500c.toml"), &out.stdout).unwrap();
    let mut sim = Background::start(
        &dir,
        &["sim", "--c500c", "--console", "--homed"],
        "serving on ",
    );
    c500c_cfg(&dir, &sim.name, true);
    let interp = {
        let dir = dir.clone();
        // Joint 1 by 1 rad at 10 %: about 3 s in real time.
        std::thread::spawn(move || {
            trol(
                &dir,
                &["interp", "-k"],
                "speed 10\njoint 1 1.0\nfinish\njoint 1 0.1\n",
            )
        })
    };
    let seen = sim.output_until("typed: joint 1,57.296", 1, 30);
    assert!(
        seen.iter().any(|l| l.contains("typed: joint 1,57.296")),
        "{seen:?}"
    );
    sim.type_line("power off");
    let o = interp.join().unwrap();
    let (out, err) = text(&o);
    assert!(!o.status.success(), "{out}");
    let finish = out
        .lines()
        .find(|l| l.starts_with("finish"))
        .unwrap_or_else(|| panic!("{out}\n{err}"));
    assert!(!finish.contains("0 (success)"), "{out}");
    let later = out
        .lines()
        .find(|l| l.starts_with("joint 1 0.1"))
        .unwrap_or_else(|| panic!("{out}"));
    assert!(!later.contains("0 (success)"), "{out}");
    let typed = sim.output();
    assert!(
        !typed.iter().any(|l| l.contains("typed: joint 1,5.730")),
        "a motion went out after the power cut: {typed:?}"
    );
}

/// `trol c500c backup` and `restore` over a pty: the application's locations out to a file,
/// and back into a controller that lost them (a new simulated one): the cartesian location
/// written and read back, the precision point's name created and listed to teach again;
/// `--dry-run` and an unconfirmed run write nothing.
#[test]
fn backup_and_restore_bring_back_what_a_controller_lost() {
    let dir = scratch("c500c-backup");
    let locations = cbuild::root().join("examples").join("locations.txt");
    let args = [
        "sim",
        "--c500c",
        "--homed",
        "--locations",
        locations.to_str().unwrap(),
    ];
    let first = Background::start(&dir, &args, "serving on ");
    let o = trol(
        &dir,
        &[
            "c500c",
            "backup",
            "--controller",
            &first.name,
            "--out",
            "cell.locations",
        ],
        "",
    );
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert!(out.contains("2 location variable(s)"), "{out}");
    let file = std::fs::read_to_string(dir.join("cell.locations")).unwrap();
    assert!(file.contains("park ploc 0 0 0 0 0 0"), "{file}");
    assert!(
        file.contains("test_001 cloc 400.000 0.000 150.000"),
        "{file}"
    );
    drop(first);

    // The battery died: a controller with no variables.
    let second = Background::start(&dir, &["sim", "--c500c", "--homed"], "serving on ");
    let restore = |extra: &[&str], input: &str| {
        let mut a = vec![
            "c500c",
            "restore",
            "--controller",
            second.name.as_str(),
            "cell.locations",
        ];
        a.extend_from_slice(extra);
        trol(&dir, &a, input)
    };
    let o = restore(&["--dry-run"], "");
    let (out, _) = text(&o);
    assert!(o.status.success(), "{out}");
    assert!(
        out.contains("cartesian locations to write: test_001"),
        "{out}"
    );
    let o = restore(&[], "no\n");
    assert!(!o.status.success());
    assert!(text(&o).1.contains("nothing was written"));
    // Every line the controller took, gathered as it logs them (each read takes them).
    let typed = |lines: Vec<String>| -> Vec<String> {
        lines
            .into_iter()
            .filter_map(|l| l.split_once("typed: ").map(|(_, t)| t.trim().to_string()))
            .collect()
    };
    // The unconfirmed run's last read is logged before what is checked (the dry run and
    // the unconfirmed one each read the controller's variables once).
    let mut log = typed(second.output_until("typed: list cloc", 2, 30));
    assert_eq!(
        log.iter().filter(|t| *t == "list cloc").count(),
        2,
        "{log:?}"
    );
    assert!(
        !log.iter()
            .any(|t| t.starts_with("set ") || t.starts_with("new ")),
        "written before a yes: {log:?}"
    );
    let o = restore(&["--yes"], "");
    let (out, err) = text(&o);
    // The precision point cannot be restored: the run says so, and fails (issue 62).
    assert!(!o.status.success(), "{out}\n{err}");
    assert!(
        err.contains("restore is partial: the precision point(s) park"),
        "{err}"
    );
    assert!(
        out.contains("cartesian locations written and read back: test_001"),
        "{out}"
    );
    assert!(
        out.contains("precision point park: teach again on the arm"),
        "{out}"
    );
    // What the controller holds now, read back by a second backup.
    let o = trol(
        &dir,
        &[
            "c500c",
            "backup",
            "--controller",
            &second.name,
            "--out",
            "after.locations",
        ],
        "",
    );
    assert!(o.status.success(), "{}", text(&o).1);
    let after = std::fs::read_to_string(dir.join("after.locations")).unwrap();
    assert!(
        after.contains("test_001 cloc 400.000 0.000 150.000"),
        "{after}"
    );
    assert!(after.contains("park ploc untaught"), "{after}");
    // The restore's own last line is logged before what is checked.
    log.extend(typed(second.output_until("typed: save", 1, 30)));
    let set = "set _test_001 = {400.000, 0.000, 150.000, 0.000, 90.000, 0.000, 0, 0}";
    let at = |line: &str| log.iter().position(|t| t == line);
    // Read back before it is made valid.
    let (set, print, valid) = (
        at(set).expect("set"),
        at("print test_001"),
        at("setvalid test_001"),
    );
    assert!(print.is_some_and(|p| p > set), "{log:?}");
    assert!(valid.is_some_and(|v| v > print.unwrap()), "{log:?}");
    let moving = ["move", "joint", "home", "ready", "here "];
    assert!(
        !log.iter().any(|t| moving.iter().any(|m| t.starts_with(m))),
        "{log:?}"
    );
}

/// A C program learns why its call failed (issue 62, item 5): trol_last_error_text names the
/// profile key a BIOS_UNSETTLED needs, and TROL_VERBOSE=1 prints the backend's lines on stderr
/// (libtrol printed nothing, whatever RUST_LOG or TROL_VERBOSE).
#[test]
fn a_c_program_reads_why_its_call_failed() {
    let dir = scratch("c500c-why");
    let _sim = c500c_sim(&dir, "default", false);
    let src = dir.join("why.c");
    std::fs::write(
        &src,
        r#"#include <stdio.h>
#include "trol.h"
int main(void)
{
    TINT r;
    if (InitTROL(1) != INITTROL_SUCCESS) { fprintf(stderr, "InitTROL failed\n"); return 1; }
    printf("before: [%s]\n", trol_last_error_text(NULL));
    r = TROLJoint(1, 0.1f);
    printf("TROLJoint -> %d\n", (int)r);
    printf("why: %s\n", trol_last_error_text(NULL));
    CleanupTROL();
    return r == 0;
}
"#,
    )
    .unwrap();
    let exe = cbuild::compile(&src, "why-c500c", cbuild::Link::Static);
    for verbose in [false, true] {
        let mut cmd = cbuild::program(&exe);
        cmd.current_dir(&dir);
        if verbose {
            cmd.env("TROL_VERBOSE", "1");
        } else {
            cmd.env_remove("TROL_VERBOSE");
        }
        let run = cmd.output().unwrap();
        let out = String::from_utf8_lossy(&run.stdout);
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(run.status.success(), "{out}\n{err}");
        assert!(out.contains("before: []"), "{out}");
        assert!(out.contains("TROLJoint -> -28"), "{out}");
        let why = out.lines().find(|l| l.starts_with("why: ")).unwrap();
        assert!(why.contains("BIOS_UNSETTLED"), "{why}");
        assert!(why.contains("motion-return"), "{why}");
        assert_eq!(
            err.contains("TROL: c500c: refused before sending"),
            verbose,
            "{err}"
        );
    }
}

/// The simulator's banner names the command that prints its variant's profile, whole and
/// without a run of spaces inside it (issue 68, item 4: a wrapped source line had put ten
/// spaces into the command), and that command runs.
#[test]
fn the_banner_names_the_print_profile_command_of_its_variant() {
    let dir = scratch("c500c-banner");
    let sim = Background::start(
        &dir,
        &[
            "sim",
            "--c500c",
            "--variant",
            "echo-off",
            "--time-scale",
            "10",
        ],
        "serving on ",
    );
    let until = std::time::Instant::now() + std::time::Duration::from_secs(30);
    let mut seen = Vec::new();
    let line = loop {
        seen.extend(sim.output());
        if let Some(l) = seen.iter().find(|l| l.contains("drive it with")) {
            break l.clone();
        }
        assert!(std::time::Instant::now() < until, "{seen:?}");
        std::thread::sleep(std::time::Duration::from_millis(50));
    };
    let command = line.split('`').nth(1).unwrap();
    assert_eq!(
        command,
        "trol sim --c500c --variant echo-off --print-profile"
    );
    let args: Vec<&str> = command.split(' ').skip(1).collect();
    let out = trol(&dir, &args, "");
    assert!(out.status.success(), "{}", text(&out).1);
    assert!(text(&out).0.contains("baud = "), "{}", text(&out).0);
}

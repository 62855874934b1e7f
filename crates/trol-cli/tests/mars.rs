//! An A465 on a MARS 8: a 1998 TROL program, unchanged, `trol interp` and `trol mars probe`
//! against `trol sim --mars` over a pty pair, in-process (`mars:PTY` in trol.cfg, on every
//! variant of the unit) and through `trol gateway --controller mars:PTY`.

#[path = "../../trol-c/tests/common/cbuild.rs"]
mod cbuild;
mod common;

use std::path::Path;

use common::{Background, check_pick, http_get, scratch, text, trol, view_state_at};

/// `trol sim --mars --variant NAME` on a new pty, its profile in `dir` (arm.toml), and a
/// trol.cfg that drives it in-process through `mars:` with the examples' locations.
fn mars_sim(dir: &Path, variant: &str) -> Background {
    mars_sim_with(dir, variant, &[])
}

fn mars_sim_with(dir: &Path, variant: &str, extra: &[&str]) -> Background {
    let out = trol(dir, &["sim", "--mars", "--print-profile"], "");
    assert!(out.status.success(), "{}", text(&out).1);
    std::fs::write(dir.join("arm.toml"), &out.stdout).unwrap();
    let mut args = vec!["sim", "--mars", "--variant", variant, "--time-scale", "20"];
    args.extend_from_slice(extra);
    let sim = Background::start(dir, &args, "serving on ");
    let locations = cbuild::root().join("examples/locations.txt");
    std::fs::write(
        dir.join("trol.cfg"),
        format!(
            "9600\nmars:{}\n0 0 0 0 0 0\nmars-profile = arm.toml\nlocations = {}\n",
            sim.name,
            locations.display()
        ),
    )
    .unwrap();
    sim
}

/// `trol gateway` in front of the simulated unit `sim`, with its profile (arm.toml in `dir`).
fn mars_gateway(dir: &Path, sim: &Background) -> Background {
    Background::start(
        dir,
        &[
            "gateway",
            "--controller",
            &format!("mars:{}", sim.name),
            "--profile",
            "arm.toml",
        ],
        "serving on ",
    )
}

fn try_example(name: &str, dir: &Path) -> (bool, String, String) {
    let exe = cbuild::compile(
        &cbuild::root().join("examples").join(format!("{name}.c")),
        &format!("{name}-mars"),
        cbuild::Link::Static,
    );
    let run = cbuild::program(&exe).current_dir(dir).output().unwrap();
    (
        run.status.success(),
        String::from_utf8_lossy(&run.stdout).into_owned(),
        String::from_utf8_lossy(&run.stderr).into_owned(),
    )
}

fn pick_on_variant(variant: &str) {
    let dir = scratch(&format!("mars-{variant}"));
    let sim = mars_sim(&dir, variant);
    let (ok, out, err) = try_example("pick", &dir);
    assert!(
        ok,
        "{variant}:\n{out}\n{err}\nsimulated MARS 8:\n{}",
        sim.output().join("\n")
    );
    check_pick(&out);
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
            for (name, _) in trol_mars::mars8::VARIANTS {
                assert!(tested.contains(name), "variant {name} has no C example run");
            }
        }
    };
}

pick_on_variants! {
    pick_default => "default",
    pick_echo => "echo",
    pick_noise => "noise",
    pick_moving_lag => "moving-lag",
    pick_refusal_line => "refusal-line",
    pick_refusal_error_bit => "refusal-error-bit",
    pick_stop_latches => "stop-latches",
    pick_lf_only => "lf-only",
    pick_r_blocks => "r-blocks",
    pick_gripper_moving => "gripper-moving",
    pick_stop_ignored => "stop-ignored",
    pick_homing_silent => "homing-silent",
    pick_unstoppable => "unstoppable",
}

#[test]
fn the_position_example_and_interp_run_through_mars_pty() {
    let dir = scratch("mars-inproc");
    let _sim = mars_sim(&dir, "default");
    let (ok, out, err) = try_example("position", &dir);
    assert!(ok, "{out}\n{err}");
    assert!(out.contains("position: done"), "{out}");
    // The interpreter, with trol.cfg's port: Home, a joint move, where the arm is.
    let o = trol(
        &dir,
        &["interp"],
        "home 0\nma j(0.2, 0.1, 0.8, 0, 0.6, 0)\nfinish\ngetposition joint actual\ngetstatus\n",
    );
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert!(out.contains("home 0  ->  0 (success)"), "{out}");
    let at = out
        .lines()
        .find(|l| l.starts_with("getposition"))
        .unwrap_or_else(|| panic!("{out}"));
    // Where the encoders say the arm is: at the target, to a few IRC counts.
    let j: Vec<f64> = at
        .split("j(")
        .nth(1)
        .and_then(|r| r.strip_suffix(')'))
        .unwrap_or_else(|| panic!("{at}"))
        .split(',')
        .map(|v| v.trim().parse().unwrap())
        .collect();
    let want = [0.2, 0.1, 0.8, 0.0, 0.6, 0.0];
    assert!((0..6).all(|i| (j[i] - want[i]).abs() < 1e-3), "{at}");
}

#[test]
fn without_a_profile_mars_is_refused_with_what_to_do() {
    let dir = scratch("mars-noprofile");
    std::fs::write(dir.join("trol.cfg"), "9600\nmars:/dev/null\n0 0 0 0 0 0\n").unwrap();
    let o = trol(&dir, &["interp"], "home 0\n");
    let (out, err) = text(&o);
    assert!(!o.status.success(), "{out}");
    assert!(err.contains("mars-profile = FILE"), "{err}");
}

#[test]
fn the_position_example_runs_through_trol_gateway_with_init_and_cleanup() {
    let dir = scratch("mars-gateway");
    let sim = mars_sim(&dir, "default");
    let gw = mars_gateway(&dir, &sim);
    let init = trol(&dir, &["init", "--port", &gw.name], "");
    let (o, e) = text(&init);
    assert!(init.status.success(), "{o}{e}");
    std::fs::write(
        dir.join("trol.cfg"),
        format!("9600\n{}\n0 0 0 0 0 0\n", gw.name),
    )
    .unwrap();
    let (ok, out, err) = try_example("position", &dir);
    assert!(ok, "{out}\n{err}\ngateway:\n{}", gw.output().join("\n"));
    assert!(out.contains("position: done"), "{out}");
    // CleanupTROL ended the server (manual); init again, the interpreter through the
    // gateway, and cleanup.
    let init = trol(&dir, &["init", "--port", &gw.name], "");
    let (o, e) = text(&init);
    assert!(init.status.success(), "{o}{e}");
    let o = trol(
        &dir,
        &["interp"],
        "home 0\nma j(0.2, 0.1, 0.8, 0, 0.6, 0)\nfinish\ngetposition joint actual\n",
    );
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert!(
        out.contains("getposition joint actual  ->  j(0.199"),
        "{out}"
    );
    let cleanup = trol(&dir, &["cleanup", "--port", &gw.name], "");
    let (o, e) = text(&cleanup);
    assert!(cleanup.status.success(), "{o}{e}");
}

/// A MARS 8's homed state across programs (issue 37, item 6): the unit does not say whether
/// it is homed, so the state is kept by whoever holds the unit. Through `trol gateway`, a
/// program after one that homed moves at once; in-process (`mars:` in trol.cfg) each program
/// holds the unit anew, and its motions are refused BIOS_NOT_HOMED until it homes.
#[test]
fn the_gateway_keeps_the_homed_state_across_programs() {
    let dir = scratch("mars-homed-across");
    let sim = mars_sim(&dir, "default");
    let ma = "ma j(0.2, 0.1, 0.8, 0, 0.6, 0)\nfinish\n";
    let o = trol(&dir, &["interp"], "home 0\n");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    let o = trol(&dir, &["interp"], ma);
    let (out, err) = text(&o);
    assert!(!o.status.success(), "{out}\n{err}");
    assert!(out.contains("BIOS_NOT_HOMED"), "{out}\n{err}");

    let gw = mars_gateway(&dir, &sim);
    std::fs::write(
        dir.join("trol.cfg"),
        format!("9600\n{}\n0 0 0 0 0 0\n", gw.name),
    )
    .unwrap();
    for script in ["home 0\n", ma] {
        // Each program ends the server (CleanupTROL); init serves the next.
        let init = trol(&dir, &["init", "--port", &gw.name], "");
        let (o, e) = text(&init);
        assert!(init.status.success(), "{o}{e}");
        let run = trol(&dir, &["interp"], script);
        let (out, err) = text(&run);
        assert!(
            run.status.success(),
            "{script}: {out}\n{err}\ngateway:\n{}",
            gw.output().join("\n")
        );
    }
}

#[test]
fn the_probe_only_reads_and_records_every_byte() {
    let dir = scratch("mars-probe");
    let sim = mars_sim(&dir, "echo");
    let o = trol(
        &dir,
        &[
            "mars",
            "probe",
            "--controller",
            &sim.name,
            "--out",
            "first.txt",
        ],
        "",
    );
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert!(out.contains("VER? -> VER=TROL simulated MARS 8"), "{out}");
    assert!(out.contains("status: ready, no fault"), "{out}");
    let t = std::fs::read_to_string(dir.join("first.txt")).unwrap();
    let sent: Vec<&str> = t.lines().filter(|l| l.starts_with("> ")).collect();
    assert_eq!(
        sent,
        [
            "> \\x0aVER?\\x0a",
            "> \\x0aST?\\x0a",
            "> \\x0aCOORDAP?\\x0a"
        ],
        "{t}"
    );
    // The unit echoes (this variant): the transcript shows it.
    assert!(t.contains("< "), "{t}");
}

#[test]
fn faults_typed_at_the_simulated_unit_reach_the_program_by_name() {
    let dir = scratch("mars-console");
    let mut sim = mars_sim_with(&dir, "default", &["--console"]);
    sim.type_line("power off");
    sim.wait_for("console: arm power off", 30);
    let o = trol(&dir, &["interp"], "home 0\n");
    let (out, err) = text(&o);
    assert!(!o.status.success(), "{out}");
    assert!(err.contains("-8 (BIOS_ARM_POWER)"), "{err}");
    sim.type_line("power on");
    sim.wait_for("console: arm power on", 30);
    sim.type_line("power sideways");
    sim.wait_for("expected on or off", 30);
    let o = trol(
        &dir,
        &["interp"],
        "home 0\nma j(0.2, 0.1, 0.8, 0, 0.6, 0)\nfinish\n",
    );
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
}

#[test]
fn the_gateway_s_view_shows_the_arm_the_mars8_reports() {
    let dir = scratch("mars-gateway-view");
    let sim = mars_sim(&dir, "default");
    let gw = Background::start(
        &dir,
        &[
            "gateway",
            "--controller",
            &format!("mars:{}", sim.name),
            "--profile",
            "arm.toml",
            "--server",
            "--view",
            "127.0.0.1:0",
        ],
        "serving on ",
    );
    let url = gw
        .wait_for("the view: ", 30)
        .last()
        .and_then(|l| l.split("the view: ").nth(1))
        .expect("the view's address")
        .trim()
        .to_string();
    // Before Home the unit's counters mean nothing: the view says no axis is homed (the page
    // shows "not homed" for each), reported about ten times a second.
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(30);
    let before = loop {
        let body = http_get(&url, "/state");
        if let Ok(s) = serde_json::from_str::<serde_json::Value>(&body) {
            break s;
        }
        assert!(std::time::Instant::now() < deadline, "no report: {body}");
        std::thread::sleep(std::time::Duration::from_millis(100));
    };
    assert_eq!(
        before["homed"],
        serde_json::json!([false, false, false, false, false, false]),
        "{before}"
    );
    std::fs::write(
        dir.join("trol.cfg"),
        format!("9600\n{}\n0 0 0 0 0 0\n", gw.name),
    )
    .unwrap();
    let o = trol(
        &dir,
        &["interp"],
        "home 0\nma j(0.2, 0.1, 0.8, 0, 0.6, 0)\nfinish\n",
    );
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    // The report is renewed about ten times a second: wait for one after the motion.
    let s = view_state_at(&url, [0.2, 0.1, 0.8, 0.0, 0.6, 0.0]);
    assert_eq!(s["reported"], true, "{s}");
    assert_eq!(s["gripper_mm"], 50.0, "{s}");
    assert_eq!(
        s["homed"],
        serde_json::json!([true, true, true, true, true, true]),
        "{s}"
    );
}

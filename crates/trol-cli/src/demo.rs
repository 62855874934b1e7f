//! `trol demo`: the manual's pick example ("TROLAppro") against the embedded controller,
//! printing each step, its result and where the arm is.

use std::process::ExitCode;

use clap::Args;
use trol::{PosMode, Robot, Tag};
use trol_a465::arm::{Stored, WorldObject};

use trol_proto::application::record::Value;
use trol_proto::application::table;

use crate::common::{
    Conn, catch_interrupts, clear_interrupt, interrupted, sleep_unless_interrupted, stdout_closed,
    waiting,
};

#[derive(Args, Debug)]
#[command(after_help = "\
Examples:
  trol demo                      # embedded simulator, 5 times real time
  trol demo --time-scale 1       # in real time
  trol demo --port /dev/ttyUSB0  # a real controller, with location test_001")]
pub struct DemoArgs {
    #[command(flatten)]
    conn: Conn,
    /// Serve the live 3D view of the arm at ADDR while the demo runs (default
    /// 127.0.0.1:8465, this machine only); open the address it prints in a browser.
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = trol_view::DEFAULT_ADDR)]
    view: Option<String>,
    /// With the view (--view, or trol.cfg's `view = ADDR`): keep serving it this many seconds
    /// after the last step (up to 3600)
    #[arg(long, value_name = "S", default_value_t = 0.0)]
    linger: f64,
    /// With the view: before the first step, wait up to this many seconds for a page to
    /// open it (the demo at 5x real time is over in seconds); 0 starts at once
    #[arg(long, value_name = "S", default_value_t = 30.0)]
    wait_view: f64,
}

/// Before the first step: wait up to `secs` for a page to open the view (or Ctrl-C), saying
/// so, so that a person who opens the printed address sees the whole demo.
fn wait_for_a_page(watchers: &trol_view::Watchers, secs: f64) {
    if secs <= 0.0 || watchers.opened() > 0 {
        return;
    }
    say!(
        "  waiting for a page to open the view (at most {secs} s; Ctrl-C or --wait-view 0 \
         starts at once)"
    );
    let until = std::time::Instant::now() + std::time::Duration::from_secs_f64(secs);
    while watchers.opened() == 0 && std::time::Instant::now() < until {
        if sleep_unless_interrupted(std::time::Duration::from_millis(50)) {
            clear_interrupt();
            break;
        }
    }
    if watchers.opened() > 0 {
        say!("  a page opened the view: starting");
    } else {
        say!("  no page opened the view: starting anyway");
    }
}

/// The location of the manual's example: 400 mm in front of the robot, 150 mm above the
/// table, the tool pointing down.
pub const TEST_001: [f64; 6] = [400.0, 0.0, 150.0, 0.0, std::f64::consts::FRAC_PI_2, 0.0];

pub fn run(mut a: DemoArgs) -> Result<ExitCode, String> {
    if a.conn.time_scale.is_none() {
        a.conn.time_scale = Some(5.0);
    }
    if !(a.linger.is_finite() && (0.0..=3600.0).contains(&a.linger)) {
        return Err(format!(
            "--linger: give 0 to 3600 seconds, not {}",
            a.linger
        ));
    }
    if !(a.wait_view.is_finite() && (0.0..=3600.0).contains(&a.wait_view)) {
        return Err(format!(
            "--wait-view: give 0 to 3600 seconds, not {}",
            a.wait_view
        ));
    }
    let cfg = a.conn.config()?;
    // Ctrl-C from here on halts the arm (and ends the wait for a page) instead of killing.
    catch_interrupts();
    if a.view.is_some() && cfg.port != "sim" {
        return Err(format!(
            "--view: the demo serves the view only with the embedded simulator (port sim), \
             not on {}; a simulator process serves its own (trol sim --view)",
            cfg.port
        ));
    }
    // --view, or trol.cfg's `view = ADDR`.
    let view = a.view.clone().or_else(|| cfg.view.clone());
    let mut viewing = false;
    let mut robot = if cfg.port == "sim" {
        let mut settings = trol::sim_settings(&cfg).map_err(|e| e.to_string())?;
        if !settings.locations.iter().any(|(n, _)| n == "test_001") {
            settings
                .locations
                .push(("test_001".into(), Stored::Cart(TEST_001)));
        }
        if settings.arm.objects.is_empty() && settings.arm.object_width.is_none() {
            // Something to pick: a 30 mm cube whose centre is test_001 (where the fingers
            // close), resting on the table: unless trol.cfg placed the table, it is raised
            // to the cube's base.
            let width = 30.0;
            let base = TEST_001[2] - width / 2.0;
            if settings.arm.table_z == 0.0 {
                settings.arm.table_z = base;
            }
            settings.arm.objects.push(WorldObject {
                name: "cube".into(),
                pos: [TEST_001[0], TEST_001[1], base],
                width,
            });
        }
        say!(
            "trol demo: the manual's pick example on the embedded simulator ({}x real time)",
            settings.time_scale
        );
        say!(
            "  motion commands return as soon as the controller accepted them; the arm moves \
             on while the program goes on, until TROLFinish(FINISH_WAIT) waits for it"
        );
        match &view {
            Some(addr) => {
                let link = trol_proto::link::LinkConfig {
                    check: cfg.block_check(),
                    ..Default::default()
                };
                let viewed = crate::common::embedded_viewed(settings, link, addr)?;
                say!("  the view: {}", viewed.url);
                if let Some(w) = &viewed.exposure {
                    tracing::warn!("{w}");
                }
                viewing = true;
                wait_for_a_page(&viewed.watchers, a.wait_view);
                viewed.robot
            }
            None => trol::Connect::sim(settings)
                .connect()
                .map_err(|e| e.to_string())?,
        }
    } else {
        let (robot, _) = a.conn.robot()?;
        say!("trol demo: the manual's pick example on {}", cfg.port);
        robot
    };
    type Step = (&'static str, fn(&mut Robot) -> trol::Result<()>);
    let steps: &[Step] = &[
        ("TROLHome(0)", |r| {
            // Home, waiting as TROLHome does, but so that Ctrl-C halts the arm.
            r.call(&table::HOME, &[Value::Int(0)])?;
            r.finish_unless(interrupted()).map(drop)
        }),
        ("TROLFinish(FINISH_WAIT)", finish),
        ("TROLOpen(50)", |r| r.open_gripper(50)),
        // From READY (upright) the tool must turn over to point down: a joint-interpolated
        // approach first, then the manual's straight one.
        ("TROLAppro(\"test_001\", x -150, joint)", |r| {
            r.appro("test_001", &[-150.0], false)
        }),
        ("TROLAppro(\"test_001\", x -90, straight)", |r| {
            r.appro("test_001", &[-90.0], true)
        }),
        ("TROLMove(\"test_001\", straight)", |r| {
            r.move_to("test_001", true)
        }),
        ("TROLFinish(FINISH_WAIT)", finish),
        ("TROLClose(60)", |r| r.close_gripper(60)),
        ("TROLFinish(FINISH_WAIT)", finish),
        ("TROLDepart(x -90, straight)", |r| r.depart(&[-90.0], true)),
        ("TROLFinish(FINISH_WAIT)", finish),
    ];
    let mut failed = 0;
    for (i, (name, f)) in steps.iter().enumerate() {
        let result = waiting(name, || f(&mut robot));
        let outcome = match &result {
            Ok(()) => "0 (success)".to_string(),
            Err(e) => e.to_string(),
        };
        let moving = robot.is_moving().unwrap_or(false);
        say!(
            "{:>2}/{} {name:<44} -> {outcome:<14} arm at {}{}",
            i + 1,
            steps.len(),
            where_is(&mut robot),
            if moving { ", moving" } else { "" }
        );
        if stdout_closed() {
            // Nobody watches any more: stop the arm rather than move it unseen.
            let _ = robot.halt();
            eprintln!("trol demo: stdout closed; Halt sent, stopping");
            return Ok(ExitCode::FAILURE);
        }
        if interrupted().load(std::sync::atomic::Ordering::SeqCst) {
            let _ = robot.finish_unless(interrupted());
            say!("trol demo: interrupted: Halt sent, the arm has stopped");
            return Ok(ExitCode::from(130));
        }
        if result.is_err() {
            failed += 1;
            say!("trol demo: stopped at the failed step");
            break;
        }
        // Show the arm moving after a command that returned before its motion ended.
        if moving && !name.starts_with("TROLFinish") {
            std::thread::sleep(std::time::Duration::from_millis(100));
            say!(
                "      {:<44}    {:<14} arm at {}",
                "(0.1 s later, the program not waiting)",
                "",
                where_is(&mut robot)
            );
        }
    }
    if let Some(world) = robot.world() {
        say!("trol demo: {world}");
    }
    if a.linger > 0.0 && viewing {
        say!("trol demo: the view stays for {} s", a.linger);
        let _ = sleep_unless_interrupted(std::time::Duration::from_secs_f64(a.linger));
    }
    if failed == 0 {
        say!("trol demo: all {} steps succeeded", steps.len());
        Ok(ExitCode::SUCCESS)
    } else {
        say!("trol demo: {failed} of {} steps failed", steps.len());
        Ok(ExitCode::FAILURE)
    }
}

/// TROLFinish(FINISH_WAIT), polled; Ctrl-C halts the arm.
fn finish(r: &mut Robot) -> trol::Result<()> {
    r.finish_unless(interrupted()).map(drop)
}

/// Where the tool is, commanded.
fn where_is(robot: &mut Robot) -> String {
    robot
        .position(Tag::Cart, PosMode::Commanded)
        .map(|l| {
            // To the micrometre, never -0 (as every surface prints a pose), in columns.
            let v = trol_proto::application::record::format_values(Tag::Cart, &l.to_array6());
            format!("x {:>8} y {:>8} z {:>8} mm", v[0], v[1], v[2])
        })
        .unwrap_or_else(|e| format!("position unknown: {e}"))
}

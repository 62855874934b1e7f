//! Short, seeded runs of `trol bench restarts` (500 kills each way are in docs/reliability.md,
//! "Across a restart"): `trol gateway` in front of a simulated MARS 8, killed at a random
//! instant of each relative move's call and started again; the application recovers as
//! trol.h's worked example does (TROLGetStatusOf, the arm read where the call may have run)
//! or as the manual does (TROLGetStatus), with and without the gateway's journal; the arm,
//! read from the unit and not through TROL, shows every move ran exactly once.

mod common;

use common::{json, scratch};

fn n(r: &serde_json::Value, key: &str) -> u64 {
    r[key].as_u64().unwrap_or_else(|| panic!("no {key} in {r}"))
}

fn killed_each_move(args: &[&str]) {
    let dir = scratch("restarts");
    let mut all = vec!["restarts", "--json", "--moves", "40"];
    all.extend_from_slice(args);
    let r = json(&dir, &all);
    assert_eq!(n(&r, "kills"), 40, "{r:#}");
    for key in ["lost", "twice", "wrong"] {
        assert_eq!(n(&r, key), 0, "{key}: {r:#}");
    }
    assert_eq!(n(&r, "ran_once"), 40, "{r:#}");
    // The kills came while calls were under way, so the recoveries were exercised.
    assert!(n(&r, "failed_calls") >= 5, "{r:#}");
}

#[test]
fn a_gateway_killed_under_each_move_runs_none_twice_with_trol_h_s_method_and_its_journal() {
    killed_each_move(&["--recovery", "getstatus", "--seed", "3"]);
}

#[test]
fn a_gateway_killed_under_each_move_runs_none_twice_with_the_manual_s_method_and_no_journal() {
    killed_each_move(&[
        "--recovery",
        "manual",
        "--no-journal",
        "--repeats",
        "0",
        "--seed",
        "4",
    ]);
}

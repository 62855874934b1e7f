//! Short, seeded runs of `trol bench faults` (the full runs and their figures are in
//! docs/reliability.md): over a noisy line (BER 1e-3) and a line cut at a random byte of
//! every relative move, no corrupted request is executed, no corrupted reply is accepted,
//! no relative move is lost or runs twice, and the controller's log holds every request it
//! ran, with the API's repeats and with the manual's GetStatus method.

mod common;

use common::{json, scratch};

fn run(args: &[&str]) -> serde_json::Value {
    let dir = scratch("faults");
    let mut all = vec!["faults", "--json"];
    all.extend_from_slice(args);
    json(&dir, &all)
}

fn n(r: &serde_json::Value, key: &str) -> u64 {
    r[key].as_u64().unwrap_or_else(|| panic!("no {key} in {r}"))
}

fn assert_nothing_wrong(r: &serde_json::Value) {
    for key in [
        "corrupted_requests_executed",
        "corrupted_replies_accepted",
        "lost_moves",
        "repeated_moves",
        "unlogged_executions",
    ] {
        assert_eq!(n(r, key), 0, "{key}: {r:#}");
    }
    assert!(n(r, "relative_moves") > 0, "{r:#}");
}

#[test]
fn a_noisy_line_neither_executes_nor_accepts_a_corrupted_block() {
    let r = run(&[
        "--mode", "noise", "--ber", "1e-3", "--count", "1500", "--seed", "7",
    ]);
    assert!(n(&r, "flipped_bits") > 100, "the line was noisy: {r:#}");
    assert_nothing_wrong(&r);
    // (BER 1e-2 is measured over 100,000 calls in docs/reliability.md; a short run there
    // would pass by luck, so it is not here.)
}

/// The noisy line of issue 67 (BER 5e-3 both ways), recovered the manual's way (GetStatus's
/// BIOSCalled alone decides): a call whose request never arrived was taken for run when the
/// call before it had run, and one move of 1,000 was lost in each of three runs. Now
/// GetStatus speaks of the call in doubt, and none is lost or repeated.
#[test]
fn a_very_noisy_line_recovered_the_manual_s_way_loses_no_move() {
    let r = run(&[
        "--mode",
        "noise",
        "--ber",
        "5e-3",
        "--recovery",
        "manual",
        "--count",
        "600",
        "--seed",
        "5",
    ]);
    assert!(n(&r, "failed_calls") > 20, "the line failed calls: {r:#}");
    assert_nothing_wrong(&r);
}

/// Lines cut while a request goes, and while its reply comes back: one test each, so that
/// the two (mostly waiting out the cuts) run side by side.
#[test]
fn cut_lines_lose_no_move_and_repeat_none() {
    cut_lines("request");
}

#[test]
fn cut_lines_during_the_reply_lose_no_move_and_repeat_none() {
    cut_lines("reply");
}

fn cut_lines(side: &str) {
    {
        for recovery in ["api", "getstatus"] {
            // 4 and 10 link timeouts of 15 ms: a line silent that long is taken for a dead
            // controller (docs/reliability.md: a call then fails within three timeouts, the
            // request run or not, and the GetStatus method decides); nothing may be lost or
            // run twice either way.
            for cut in ["60", "150"] {
                let r = run(&[
                    "--mode",
                    "cut",
                    "--side",
                    side,
                    "--recovery",
                    recovery,
                    "--cut-ms",
                    cut,
                    "--count",
                    "80",
                    "--seed",
                    "3",
                ]);
                assert!(n(&r, "cuts") > 10, "{r:#}");
                // (How many calls fail depends on the machine's timing; the figures are
                // in docs/reliability.md. What must never happen does not depend on it.)
                assert_nothing_wrong(&r);
            }
        }
    }
}

#[test]
fn the_soak_reports_the_memory_it_used() {
    let r = run(&["--mode", "soak", "--seconds", "2"]);
    assert!(n(&r, "transactions") > 100, "{r:#}");
    if cfg!(target_os = "linux") {
        assert!(n(&r, "rss_end_kb") > 0, "{r:#}");
    }
}

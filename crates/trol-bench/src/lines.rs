//! `trol bench lines`: the straight-line survey of the simulated A465
//! ([`trol_a465::survey`]): the share accepted from READY and from J5 = 0, each line's
//! duration against its least time, the limits and the distance from the line.

use clap::Args;

#[derive(Args)]
pub struct LinesArgs {
    /// How many lines of each set.
    #[arg(long, default_value_t = 300, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    count: u32,
    /// The random generator's seed (the same seed draws the same lines).
    #[arg(long, default_value_t = 42)]
    seed: u64,
    /// Print each refused line (its start, its target, the code and why), each blocked line,
    /// and each line slower than 2.5 times its least time.
    #[arg(long)]
    show_refused: bool,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

pub fn run(a: LinesArgs) -> Result<(), String> {
    let sets = trol_a465::survey::survey(a.count, a.seed, a.show_refused);
    if a.json {
        let each: Vec<serde_json::Value> = sets
            .iter()
            .map(|s| {
                serde_json::json!({
                    "set": s.set,
                    "tried": s.tried,
                    "impossible": s.impossible,
                    "blocked": s.blocked,
                    "accepted": s.accepted,
                    "accepted_percent": s.accepted_percent,
                    "accepted_of_tried_percent": s.accepted_of_tried_percent,
                    "refused": s.refused,
                    "ratio_median": s.ratio_median,
                    "ratio_p99": s.ratio_p99,
                    "ratio_max": s.ratio_max,
                    "plain_ratio_max": s.plain_ratio_max,
                    "limit_excursions": s.limit_excursions,
                    "max_off_line_mm": s.max_off_line_mm,
                })
            })
            .collect();
        say!("{}", serde_json::Value::Array(each));
        return Ok(());
    }
    for s in &sets {
        for r in &s.refusals {
            say!("{}: {r}", s.set);
        }
        say!(
            "{}: {} lines, {} impossible (a point beyond every configuration's limits), {} \
             blocked (every way along them meets a joint limit); {} of the {} others accepted \
             ({:.1} %; {:.1} % of all {}), refused {:?}; duration / least time: median {:.2}, \
             99 % {:.2}, largest {:.2} (largest {:.2} without the turn first in the least \
             time); {} samples beyond a limit; at most {:.4} mm off the line",
            s.set,
            s.tried,
            s.impossible,
            s.blocked,
            s.accepted,
            s.tried - s.impossible - s.blocked,
            s.accepted_percent,
            s.accepted_of_tried_percent,
            s.tried,
            s.refused,
            s.ratio_median,
            s.ratio_p99,
            s.ratio_max,
            s.plain_ratio_max,
            s.limit_excursions,
            s.max_off_line_mm
        );
    }
    Ok(())
}

//! The conformance suite (`trol_conformance::run`) against every simulated controller: the
//! simulated A465, every simulated C500 and C500C variant the matching profile can drive,
//! every simulated MARS 8 variant. One test each, so that a failure names its controller.

use trol_conformance::{Subject, run, subjects};

fn check(mut s: Subject) {
    let f = run(&mut s);
    if std::env::var_os("TROL_SHOW").is_some() {
        eprintln!("{}", f.steps.join("\n  "));
    }
    assert!(
        f.broken.is_empty(),
        "{}: {}\n\nwhat happened:\n  {}",
        s.label,
        f.broken.join("; "),
        f.steps.join("\n  ")
    );
}

#[test]
fn the_simulated_a465() {
    check(subjects::sim());
}

macro_rules! each {
    ($kind:ident, $start:path, $all:expr, $skip:expr; $($test:ident => $name:literal),* $(,)?) => {
        mod $kind {
            use super::*;
            $(
                #[test]
                fn $test() {
                    check($start($name));
                }
            )*

            #[test]
            fn every_variant_has_a_test() {
                let tested = [$($name),*];
                for (name, _) in $all {
                    let skipped: &[(&str, &str)] = $skip;
                    assert!(
                        tested.contains(name) || skipped.iter().any(|(n, _)| n == name),
                        "variant {name} has no test here"
                    );
                }
            }
        }
    };
}

each! {
    c500, subjects::c500, trol_rapl::c500::VARIANTS, subjects::C500_FAIL_SAFE;
    default => "default",
    colon_refusal => "colon-refusal",
    stars_refusal => "stars-refusal",
    no_period => "no-period",
    ack_at_end => "ack-at-end",
    done_lag => "done-lag",
    estop_line => "estop-line",
    no_ack => "no-ack",
    ma_radians => "ma-radians",
    inch => "inch",
    world_offset => "world-offset",
    pulses_g3000 => "pulses-g3000",
    nul_after_digit => "nul-after-digit",
    not_homed => "not-homed",
    home_elsewhere => "home-elsewhere",
    jog_tool => "jog-tool",
    halt_ignored => "halt-ignored",
    ctrl_c_cancels_line => "ctrl-c-cancels-line",
    unstoppable => "unstoppable",
    finish => "finish",
    finish_trusted => "finish-trusted",
    finish_at_once => "finish-at-once",
    finish_refused => "finish-refused",
}

each! {
    mars8, subjects::mars, trol_mars::mars8::VARIANTS, &[];
    default => "default",
    echo => "echo",
    noise => "noise",
    moving_lag => "moving-lag",
    refusal_line => "refusal-line",
    refusal_error_bit => "refusal-error-bit",
    stop_latches => "stop-latches",
    lf_only => "lf-only",
    r_blocks => "r-blocks",
    gripper_moving => "gripper-moving",
    stop_ignored => "stop-ignored",
    homing_silent => "homing-silent",
    unstoppable => "unstoppable",
}

each! {
    c500c, subjects::c500c, trol_c500c::c500c::VARIANTS, subjects::C500C_FAIL_SAFE;
    default => "default",
    return_at_end => "return-at-end",
    rows_apart => "rows-apart",
    home_elsewhere => "home-elsewhere",
    error_prefixed => "error-prefixed",
    error_bracketed => "error-bracketed",
    lf_only => "lf-only",
    unstoppable => "unstoppable",
    ctrl_c_no_prompt => "ctrl-c-no-prompt",
    power_loss_silent => "power-loss-silent",
}

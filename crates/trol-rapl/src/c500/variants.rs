//! The simulated C500's variants: one for each point the public sources leave open, and
//! for the faults (docs/c500.md, "Variants").

use super::*;

/// The controllers the public sources allow, one per open point (docs/c500.md, "What TROL
/// assumes"): a name, what it changes, and the profile that makes the simulated C500 play
/// it. `trol sim --rapl --variant NAME` serves one; the backend's tests run across all.
pub const VARIANTS: &[(&str, &str)] = &[
    (
        "default",
        "the simulator's own readings of every open point",
    ),
    (
        "colon-refusal",
        "refusals as `:NNN-TEXT.` (the form of the only public program error)",
    ),
    (
        "stars-refusal",
        "refusals as `*** TEXT ***`, without a number",
    ),
    ("no-period", "refusals as `NNN-TEXT`, without the period"),
    (
        "ack-at-end",
        "a motion's ACK and prompt come at its end; Ctrl-C halts",
    ),
    (
        "done-lag",
        "the DONE row still says done for 0.3 s after a motion's ACK",
    ),
    (
        "estop-line",
        "an emergency stop prints `*** EMERGENCY STOP ***` unasked",
    ),
    (
        "warning-then-ack",
        "a numbered warning line before the ACK of every motion",
    ),
    (
        "no-ack",
        "no ACK on success (the G3000 driver never looks for one)",
    ),
    ("ma-radians", "MA and MI take radians (R2JSON, RobWork)"),
    ("inch", "lengths in inches (RobWork's controller)"),
    (
        "world-offset",
        "WORLD angles of a model with identity orientation at all joints zero",
    ),
    (
        "pulses-g3000",
        "one pulse per encoder line and a negative sign (the G3000 driver's table)",
    ),
    (
        "nul-after-digit",
        "four NUL bytes after a number's first character",
    ),
    ("no-echo", "echo off (RAPL-II's CONFIG ECHO)"),
    ("not-homed", "the arm is not homed at power-up"),
    (
        "home-elsewhere",
        "HOME leaves joints 3 and 5 at 90 degrees, not every joint at 0",
    ),
    (
        "finish",
        "completion = \"finish\": FINISH waits in immediate mode, Ctrl-C ends it",
    ),
    (
        "finish-trusted",
        "as finish, and FINISH after a motion stopped short answers 037, never ACK \
         (finish_ack_means_arrived)",
    ),
    (
        "finish-at-once",
        "as finish, but FINISH answers at once while the arm still moves",
    ),
    (
        "finish-refused",
        "as finish, but FINISH is refused in immediate mode (program mode only, as R2JSON lists it)",
    ),
    (
        "jog-tool",
        "JOG moves along the tool's axes, not the world's (jog_frame = \"tool\")",
    ),
    (
        "halt-ignored",
        "HALT is acknowledged but does not stop a motion (ABORT does)",
    ),
    (
        "ctrl-c-cancels-line",
        "as ack-at-end, but Ctrl-C only cancels the line (RobWork's reading); HALT stops",
    ),
    (
        "unstoppable",
        "no stop stops a motion (HALT and ABORT acknowledged, Ctrl-C cancels the line): a \
         fault, for the rule that Halt never says done unseen",
    ),
    (
        "finish-deaf",
        "as finish, but Ctrl-C is ignored while FINISH waits (the profile's \
         ctrl_c_ends_finish is wrong)",
    ),
];

/// The profile of variant `name` (see [`VARIANTS`]), and whether its arm starts homed.
pub fn variant(name: &str) -> Option<(Profile, bool)> {
    let base = Profile::simulator();
    let twin = base.twin.clone();
    let p = match name {
        "default" | "not-homed" => base,
        "colon-refusal" => Profile {
            twin: crate::profile::Twin {
                refusal: ":NNN-TEXT.".into(),
                ..twin
            },
            ..base
        },
        "stars-refusal" => Profile {
            twin: crate::profile::Twin {
                refusal: "*** TEXT ***".into(),
                ..twin
            },
            ..base
        },
        "no-period" => Profile {
            twin: crate::profile::Twin {
                refusal: "NNN-TEXT".into(),
                ..twin
            },
            ..base
        },
        "ack-at-end" => Profile {
            motion_ack: crate::profile::MotionAck::End,
            halt: Halt::CtrlC,
            ..base
        },
        "home-elsewhere" => Profile {
            twin: crate::profile::Twin {
                home_deg: [0.0, 0.0, 90.0, 0.0, 90.0, 0.0],
                ..twin
            },
            ..base
        },
        "done-lag" => Profile {
            twin: crate::profile::Twin {
                done_lag_ms: 3000,
                ..twin
            },
            ..base
        },
        "estop-line" => Profile {
            twin: crate::profile::Twin {
                estop_line: "*** EMERGENCY STOP ***".into(),
                ..twin
            },
            ..base
        },
        "warning-then-ack" => Profile {
            twin: crate::profile::Twin {
                motion_warning: "101-NEAR JOINT LIMIT.".into(),
                ..twin
            },
            ..base
        },
        "no-ack" => Profile {
            ack: Ack::Never,
            twin: crate::profile::Twin {
                refusal: "*** TEXT ***".into(),
                ..twin
            },
            ..base
        },
        "ma-radians" => Profile {
            joint_units: "radians".into(),
            ..base
        },
        "inch" => Profile {
            units: Units::Inch,
            ..base
        },
        "world-offset" => Profile {
            tool_rotation: [0.0, 90.0, 0.0],
            ..base
        },
        "pulses-g3000" => Profile {
            pulse_scale: trol_a465::model::ENCODER_LINES
                .iter()
                .zip(trol_a465::model::GEAR_RATIOS)
                .map(|(l, g)| -l * g / 360.0)
                .collect(),
            pulse_zero: vec![120.0, -40.0, 7.0, 0.0, 2.0, -9.0],
            ..base
        },
        "nul-after-digit" => Profile {
            twin: crate::profile::Twin {
                extra_byte: 0,
                ..twin
            },
            ..base
        },
        "no-echo" => Profile {
            twin: crate::profile::Twin {
                echo: false,
                ..twin
            },
            ..base
        },
        "jog-tool" => Profile {
            jog_frame: "tool".into(),
            twin: crate::profile::Twin {
                jog_tool: true,
                ..twin
            },
            ..base
        },
        "halt-ignored" => Profile {
            twin: crate::profile::Twin {
                halt_stops: false,
                ..twin
            },
            ..base
        },
        "ctrl-c-cancels-line" => Profile {
            motion_ack: crate::profile::MotionAck::End,
            halt: Halt::CtrlC,
            twin: crate::profile::Twin {
                ctrl_c_stops: Some(false),
                ..twin
            },
            ..base
        },
        "unstoppable" => Profile {
            twin: crate::profile::Twin {
                halt_stops: false,
                abort_stops: false,
                ctrl_c_stops: Some(false),
                ..twin
            },
            ..base
        },
        "finish" | "finish-trusted" | "finish-at-once" | "finish-refused" | "finish-deaf" => {
            let twin = crate::profile::Twin {
                finish: match name {
                    "finish-at-once" => TwinFinish::AtOnce,
                    "finish-refused" => TwinFinish::Refused,
                    _ => TwinFinish::Waits,
                },
                finish_ctrl_c: name != "finish-deaf",
                finish_stopped: if name == "finish-trusted" { 37 } else { 0 },
                ..twin
            };
            Profile {
                completion: crate::profile::Completion::Finish,
                ctrl_c_ends_finish: true,
                finish_ack_means_arrived: name == "finish-trusted",
                twin,
                ..base
            }
        }
        _ => return None,
    };
    Some((p, name != "not-homed"))
}

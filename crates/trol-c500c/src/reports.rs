//! What ash prints, read exactly (shared/reference/c500c.md, "Position reports" and
//! "Commands"): a reply that does not have the known form is not guessed at.

/// A position report (`w0`: commanded, `w2`: actual).
#[derive(Clone, Debug, PartialEq)]
pub struct Position {
    /// The PULSES row.
    pub pulses: [i64; 6],
    /// The JOINTS row, degrees.
    pub joints_deg: [f64; 6],
    /// The WORLD row: x, y, z (in the controller's units), then the three angles as printed
    /// (their composition order is an open point).
    pub world: [f64; 6],
}

/// Why a reply was not the known form.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{what}: not the form ash prints ({line})")]
pub struct Unread {
    /// What was read.
    pub what: &'static str,
    /// The line that did not fit, or what was missing.
    pub line: String,
}

fn unread(what: &'static str, line: impl Into<String>) -> Unread {
    Unread {
        what,
        line: line.into(),
    }
}

fn row<T: std::str::FromStr, const N: usize>(
    what: &'static str,
    line: &str,
    label: &str,
) -> Result<[T; N], Unread> {
    let rest = line.strip_prefix(label).ok_or_else(|| unread(what, line))?;
    let v: Vec<T> = rest
        .split_whitespace()
        .map(|w| w.parse::<T>())
        .collect::<Result<_, _>>()
        .map_err(|_| unread(what, line))?;
    v.try_into().map_err(|_| unread(what, line))
}

/// Read a position report from its lines (the echo and the prompt taken off): `Actual
/// Position :` (or `Commanded Position :`), the axis header, PULSES, JOINTS, the WORLD
/// header and its values.
pub fn position(lines: &[String], actual: bool) -> Result<Position, Unread> {
    let what = if actual { "w2" } else { "w0" };
    let title = if actual {
        "Actual Position :"
    } else {
        "Commanded Position :"
    };
    let lines: Vec<&str> = lines
        .iter()
        .map(|l| l.trim_end())
        .filter(|l| !l.is_empty())
        .collect();
    let [t, axes, pulses, joints, world_head, world_units, world] = lines[..] else {
        return Err(unread(what, format!("{} lines", lines.len())));
    };
    if t.trim() != title {
        return Err(unread(what, t));
    }
    if !axes.trim_start().starts_with("Axis 1/7") {
        return Err(unread(what, axes));
    }
    if !world_head.trim_start().starts_with("X/TrackX") {
        return Err(unread(what, world_head));
    }
    if !world_units.starts_with("WORLD") {
        return Err(unread(what, world_units));
    }
    Ok(Position {
        pulses: row(what, pulses, "PULSES")?,
        joints_deg: row(what, joints, "JOINTS")?,
        world: row(what, world, "")?,
    })
}

/// Print a position report as ash prints it (the simulated C500C's; the formats of the ash
/// bytecode: `{+10}` and `{+10.3f}`, taken here as a forced sign).
pub fn print_position(p: &Position, actual: bool, metric: bool) -> Vec<String> {
    let unit = if metric { "(mm)" } else { "(in)" };
    let mut out = vec![
        if actual {
            "Actual Position :".to_string()
        } else {
            "Commanded Position :".to_string()
        },
        "          Axis 1/7   Axis 2/8     Axis 3     Axis 4     Axis 5     Axis 6".into(),
    ];
    out.push(format!(
        "PULSES  {}",
        p.pulses
            .iter()
            .map(|v| format!("{v:>+10}"))
            .collect::<Vec<_>>()
            .join(" ")
    ));
    out.push(format!(
        "JOINTS  {}",
        p.joints_deg
            .iter()
            .map(|v| format!("{v:>+10.3}"))
            .collect::<Vec<_>>()
            .join(" ")
    ));
    out.push("          X/TrackX   Y/TrackY          Z      Z-Rot      Y-Rot      X-Rot".into());
    out.push(format!(
        "WORLD   {:>10} {:>10} {:>10} {:>10} {:>10} {:>10}",
        unit, unit, unit, "(deg)", "(deg)", "(deg)"
    ));
    out.push(format!(
        "        {}",
        p.world
            .iter()
            .map(|v| format!("{v:>+10.3}"))
            .collect::<Vec<_>>()
            .join(" ")
    ));
    out
}

/// Homed and calibrated, as `armstat` says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Homing {
    /// `Robot is calibrated and homed`.
    Homed,
    /// `Robot is not homed`.
    NotHomed,
    /// `Robot is not calibrated`.
    NotCalibrated,
}

/// What `armstat` says.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ArmStat {
    /// `Robot arm is of type A465`: the arm's type.
    pub arm: String,
    /// `Arm power is ON|OFF`.
    pub power: bool,
    /// Homed and calibrated.
    pub homing: Homing,
    /// `Units are Metric|Imperial`: metric.
    pub metric: bool,
    /// `Online is ON|OFF`.
    pub online: bool,
}

/// Read `armstat`'s lines: each of its five statements exactly once, nothing else.
pub fn armstat(lines: &[String]) -> Result<ArmStat, Unread> {
    let what = "armstat";
    let (mut arm, mut power, mut homing, mut metric, mut online) = (None, None, None, None, None);
    for l in lines.iter().map(|l| l.trim()).filter(|l| !l.is_empty()) {
        let slot_taken = |taken: bool| {
            if taken { Err(unread(what, l)) } else { Ok(()) }
        };
        if let Some(t) = l.strip_prefix("Robot arm is of type ") {
            slot_taken(arm.is_some())?;
            arm = Some(t.to_string());
        } else if let Some(v) = l.strip_prefix("Arm power is ") {
            slot_taken(power.is_some())?;
            power = Some(on_off(what, l, v)?);
        } else if let Some(v) = l.strip_prefix("Units are ") {
            slot_taken(metric.is_some())?;
            metric = Some(match v {
                "Metric" => true,
                "Imperial" => false,
                _ => return Err(unread(what, l)),
            });
        } else if let Some(v) = l.strip_prefix("Online is ") {
            slot_taken(online.is_some())?;
            online = Some(on_off(what, l, v)?);
        } else if l.starts_with("Robot is ") {
            slot_taken(homing.is_some())?;
            homing = Some(match l {
                "Robot is calibrated and homed" => Homing::Homed,
                "Robot is not homed" => Homing::NotHomed,
                "Robot is not calibrated" => Homing::NotCalibrated,
                _ => return Err(unread(what, l)),
            });
        } else {
            return Err(unread(what, l));
        }
    }
    let missing = |name: &str| unread(what, format!("no line on {name}"));
    Ok(ArmStat {
        arm: arm.ok_or_else(|| missing("the arm's type"))?,
        power: power.ok_or_else(|| missing("arm power"))?,
        homing: homing.ok_or_else(|| missing("homing"))?,
        metric: metric.ok_or_else(|| missing("units"))?,
        online: online.ok_or_else(|| missing("online"))?,
    })
}

fn on_off(what: &'static str, line: &str, v: &str) -> Result<bool, Unread> {
    match v {
        "ON" => Ok(true),
        "OFF" => Ok(false),
        _ => Err(unread(what, line)),
    }
}

/// Print `armstat` as ash prints it (the simulated C500C's).
pub fn print_armstat(s: &ArmStat) -> Vec<String> {
    let on = |b: bool| if b { "ON" } else { "OFF" };
    vec![
        format!("Robot arm is of type {}", s.arm),
        format!("Arm power is {}", on(s.power)),
        match s.homing {
            Homing::Homed => "Robot is calibrated and homed",
            Homing::NotHomed => "Robot is not homed",
            Homing::NotCalibrated => "Robot is not calibrated",
        }
        .to_string(),
        format!("Units are {}", if s.metric { "Metric" } else { "Imperial" }),
        format!("Online is {}", on(s.online)),
    ]
}

/// `robotver`'s one line: `Version string: '<version>'`.
pub fn robotver(lines: &[String]) -> Result<String, Unread> {
    match lines {
        [l] => l
            .trim_end()
            .strip_prefix("Version string: '")
            .and_then(|v| v.strip_suffix('\''))
            .map(str::to_string)
            .ok_or_else(|| unread("robotver", l.as_str())),
        _ => Err(unread("robotver", format!("{} lines", lines.len()))),
    }
}

/// `speed`'s one line: `Current speed is N`.
pub fn speed(lines: &[String]) -> Result<u8, Unread> {
    match lines {
        [l] => l
            .trim_end()
            .strip_prefix("Current speed is ")
            .and_then(|v| v.parse().ok())
            .filter(|v| (1..=100).contains(v))
            .ok_or_else(|| unread("speed", l.as_str())),
        _ => Err(unread("speed", format!("{} lines", lines.len()))),
    }
}

/// An error text of CRS's tables (/lib/errors, ash's parse errors), and what it means to TROL.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Known {
    /// `Arm power is OFF`.
    NoPower,
    /// `Not homed or not calibrated`.
    NotHomed,
    /// `Joint $1 limit exceeded`.
    JointLimit,
    /// `Location out of reach`.
    OutOfReach,
    /// `Axis $1 is limp`.
    Limp,
    /// `Ash doesn't have control. ...` (the pendant holds the point of control).
    NoControl,
    /// `Halt() command invoked`.
    Halted,
    /// `Unrecognized command.` or `error: ...` (ash's parse errors): the command did not run.
    Parse,
    /// A servo fault: encoder alarm, collision, excessive lag.
    Servo,
}

/// The error texts TROL knows, each as CRS words it (`$1` stands for an axis number).
pub const ERRORS: &[(&str, Known)] = &[
    ("Arm power is OFF", Known::NoPower),
    ("Not homed or not calibrated", Known::NotHomed),
    ("Joint $1 limit exceeded", Known::JointLimit),
    ("Location out of reach", Known::OutOfReach),
    ("Axis $1 is limp", Known::Limp),
    ("Ash doesn't have control.", Known::NoControl),
    ("Halt() command invoked", Known::Halted),
    ("Unrecognized command.", Known::Parse),
    (
        "Axis $1 encoder alarm -- batteries may be low",
        Known::Servo,
    ),
    ("Collision error on axis $1", Known::Servo),
    ("Excessive lag error on axis $1", Known::Servo),
    ("Invalid location flags", Known::Parse),
    ("Location has not been taught", Known::Parse),
];

/// The known error a line carries, wherever ash puts it in the line (how ash prefixes a
/// robot error is an open point: `test: `, `error: ` or nothing). Only a text of the tables
/// counts, `$1` matching one axis number.
pub fn known_error(line: &str) -> Option<Known> {
    let l = line.trim();
    // A text of CRS's tables keeps its own code behind any prefix (`error: Joint 2 limit
    // exceeded` is a joint limit: issue 62); another `error: ` line is ash's parser's.
    ERRORS
        .iter()
        .find(|(pattern, _)| matches(l, pattern))
        .map(|&(_, k)| k)
        .or_else(|| l.starts_with("error: ").then_some(Known::Parse))
}

fn matches(line: &str, pattern: &str) -> bool {
    match pattern.split_once("$1") {
        None => line.ends_with(pattern) || line.contains(&format!("{pattern} ")),
        Some((head, tail)) => line.match_indices(head).any(|(i, _)| {
            let rest = &line[i + head.len()..];
            let digits = rest.chars().take_while(char::is_ascii_digit).count();
            (1..=2).contains(&digits) && rest[digits..].starts_with(tail)
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn a_table_error_keeps_its_code_behind_ash_s_error_prefix() {
        assert_eq!(
            known_error("error: Joint 2 limit exceeded"),
            Some(Known::JointLimit)
        );
        assert_eq!(known_error("error: missing comma."), Some(Known::Parse));
        assert_eq!(known_error("Arm power is OFF"), Some(Known::NoPower));
    }

    #[test]
    fn a_printed_position_reads_back() {
        let p = Position {
            pulses: [0, -1200, 34000, 0, 5, -7],
            joints_deg: [0.0, -1.5, 90.25, 0.0, 0.006, -0.009],
            world: [300.0, 0.0, 500.125, 0.0, 90.0, -180.0],
        };
        let printed = print_position(&p, true, true);
        assert_eq!(position(&printed, true), Ok(p.clone()));
        // As A255ROS cuts it: after the echo `w2` CR LF, the PULSES values begin at byte 106.
        let bytes = format!("w2\r\n{}\r\n", printed.join("\r\n"));
        assert_eq!(&bytes[98..106], "PULSES  ");
        // The commanded report is not the actual one.
        assert!(position(&printed, false).is_err());
        let mut short = printed.clone();
        short.pop();
        assert!(position(&short, true).is_err());
    }

    #[test]
    fn armstat_reads_each_statement_once() {
        let s = ArmStat {
            arm: "A465".into(),
            power: true,
            homing: Homing::NotHomed,
            metric: true,
            online: false,
        };
        assert_eq!(armstat(&print_armstat(&s)), Ok(s.clone()));
        let mut twice = print_armstat(&s);
        twice.push("Arm power is OFF".into());
        assert!(armstat(&twice).is_err());
        let mut odd = print_armstat(&s);
        odd[2] = "Robot is ready".into();
        assert!(armstat(&odd).is_err());
    }

    #[test]
    fn versions_speeds_and_errors() {
        assert_eq!(
            robotver(&lines(&["Version string: 'A465 2.1'"])),
            Ok("A465 2.1".into())
        );
        assert!(robotver(&lines(&["Version: A465"])).is_err());
        assert_eq!(speed(&lines(&["Current speed is 25"])), Ok(25));
        assert!(speed(&lines(&["Current speed is 0"])).is_err());
        assert_eq!(
            known_error("Joint 3 limit exceeded"),
            Some(Known::JointLimit)
        );
        assert_eq!(
            known_error("test: Joint 12 limit exceeded"),
            Some(Known::JointLimit)
        );
        assert_eq!(known_error("Joint x limit exceeded"), None);
        assert_eq!(known_error("error: missing comma."), Some(Known::Parse));
        assert_eq!(known_error("Arm power is OFF"), Some(Known::NoPower));
        assert_eq!(known_error("Arm power is OFFLINE"), None);
        assert_eq!(known_error("joint moved"), None);
    }
}

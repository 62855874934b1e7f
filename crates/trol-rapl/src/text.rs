//! The text of RAPL-II: numbers in commands, and the replies of W0/W2/W5, STATUS and LISTL,
//! written by the simulated C500 and read by the gateway (one module, so each layout is
//! written and read by the same rules; the layouts follow the public samples in
//! ../shared/reference/a465.md §2.3, with six axes wrapped after five as on the G3000).

/// A number as a command carries it: to four decimals, without trailing zeros (`0`, `-3`,
/// `12.5`: a line shorter to type, issue 43), never `-0`, never an exponent.
pub fn num(v: f64) -> String {
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s.trim_start_matches('-').bytes().all(|b| b == b'0') {
        "0".into()
    } else {
        s.into()
    }
}

/// A position as the controller prints it: motor pulses, joint angles in degrees, and the
/// WORLD row (x y z in the controller's units, three angles in degrees in its order).
#[derive(Clone, Debug, PartialEq)]
pub struct Position {
    /// PULSES.
    pub pulses: [i64; 6],
    /// JOINTS, degrees.
    pub joints: [f64; 6],
    /// WORLD.
    pub world: [f64; 6],
}

fn deg(v: f64) -> String {
    format!("{v:+09.4}")
}

/// The body of a W0 (`commanded`) or W2 reply, after the command's echo.
pub fn write_position(commanded: bool, p: &Position) -> String {
    let mut s = String::from("\n\r\n");
    s.push_str(if commanded {
        "CURRENT COMMANDED POSITION :\r\n"
    } else {
        "CURRENT ACTUAL POSITION :\r\n"
    });
    s.push_str("NAME       AX#1/6      AX#2/7      AX#3/8      AX#4        AX#5\r\n");
    let pulses: Vec<String> = p.pulses.iter().map(|v| format!("{v:+011}")).collect();
    s.push_str(&format!("PULSES   {}\r\n", pulses[..5].join(" ")));
    s.push_str(&format!("         {}\r\n", pulses[5]));
    s.push_str("NAME       JT#1/6    JT#2/7    JT#3/8    JT#4      JT#5\r\n");
    let joints: Vec<String> = p.joints.iter().map(|v| deg(*v)).collect();
    s.push_str(&format!("JOINTS   {}\r\n", joints[..5].join(" ")));
    s.push_str(&format!("         {}\r\n", joints[5]));
    let world: Vec<String> = p.world.iter().map(|v| deg(*v)).collect();
    s.push_str(&format!("WORLD     {}\r\n", world.join(" ")));
    s.push_str(".\r\n");
    s
}

/// The body of a W5 reply: joint velocities, degrees per second.
pub fn write_velocity(v: &[f64; 6]) -> String {
    let mut s = String::from("\n\r\nCURRENT VELOCITY :\r\n");
    s.push_str("NAME       JT#1/6    JT#2/7    JT#3/8    JT#4      JT#5\r\n");
    let cols: Vec<String> = v.iter().map(|x| deg(*x)).collect();
    s.push_str(&format!("JOINTS   {}\r\n", cols[..5].join(" ")));
    s.push_str(&format!("         {}\r\n.\r\n", cols[5]));
    s
}

/// The six numbers of the row `label` and its continuation lines (lines that start with a
/// blank), in a reply's text.
pub fn row(text: &str, label: &str) -> Result<[f64; 6], String> {
    let mut values = Vec::new();
    let mut lines = text.split(['\r', '\n']).filter(|l| !l.is_empty());
    let mut found = false;
    for line in lines.by_ref() {
        if let Some(rest) = line.strip_prefix(label) {
            if rest.starts_with(|c: char| c.is_whitespace()) {
                found = true;
                collect_numbers(rest, &mut values)?;
                break;
            }
        }
    }
    if !found {
        return Err(format!("no {label} row"));
    }
    for line in lines {
        if values.len() >= 6 || !line.starts_with(' ') {
            break;
        }
        collect_numbers(line, &mut values)?;
    }
    <[f64; 6]>::try_from(values.as_slice())
        .map_err(|_| format!("the {label} row has {} numbers, not 6", values.len()))
}

fn collect_numbers(s: &str, out: &mut Vec<f64>) -> Result<(), String> {
    for tok in s.split_whitespace() {
        let v: f64 = tok
            .parse()
            .map_err(|_| format!("`{tok}` is not a number"))?;
        if !v.is_finite() {
            return Err(format!("`{tok}` is not a finite number"));
        }
        out.push(v);
    }
    Ok(())
}

/// Read a W0 or W2 reply.
pub fn read_position(text: &str) -> Result<Position, String> {
    let pulses = row(text, "PULSES")?;
    if pulses.iter().any(|p| p.fract() != 0.0 || p.abs() > 1e10) {
        return Err("the PULSES row holds a number that is not a pulse count".into());
    }
    Ok(Position {
        pulses: pulses.map(|p| p as i64),
        joints: row(text, "JOINTS")?,
        world: row(text, "WORLD")?,
    })
}

/// What STATUS says.
#[derive(Clone, Debug, PartialEq)]
pub struct Status {
    /// The first line (version and robot).
    pub version: String,
    /// LAST ERROR CODE's text.
    pub last_error: String,
    /// SPEED (% OF FULL).
    pub speed: f64,
    /// Per axis: LOCK, DONE, LIMP, HOMED.
    pub lock: [bool; 6],
    /// Per axis: the motion is done.
    pub done: [bool; 6],
    /// Per axis: limp (no power).
    pub limp: [bool; 6],
    /// Per axis: homed.
    pub homed: [bool; 6],
    /// The units line: Some(true) metric, Some(false) inches, None not said.
    pub metric: Option<bool>,
}

fn flags(f: &[bool; 6]) -> String {
    f.iter()
        .map(|b| if *b { "Y" } else { "N" })
        .collect::<Vec<_>>()
        .join(" ")
}

/// The body of a STATUS reply (the G3000 sample's layout with six axes; the version line
/// and the inch units line are assumptions).
pub fn write_status(s: &Status, tool: &[f64; 6]) -> String {
    let mut o = String::from("\n\r\n");
    o.push_str(&format!("{}\r\n", s.version));
    o.push_str(&format!("LAST ERROR CODE: {}\r\n", s.last_error));
    o.push_str(&format!(
        "SPEED (% OF FULL) :    {:+}\r\n",
        s.speed.round() as i64
    ));
    o.push_str("MAX LINEAR SPEED: +1000.0000\r\n");
    o.push_str("CURRENT PROGRAM EXECUTING:\r\n");
    o.push_str("JOINT LIMIT CHECK IS ON\r\n");
    o.push_str(if s.homed.iter().all(|h| *h) {
        "CONTROLLER IS HOMED\r\n"
    } else {
        "CONTROLLER IS NOT HOMED\r\n"
    });
    o.push_str("TOOL TRANSFORM\r\n");
    let t: Vec<String> = tool.iter().map(|v| deg(*v)).collect();
    o.push_str(&format!("NULL      {}\r\n", t.join(" ")));
    o.push_str("GRIPPER TYPE:  SERVO\r\n");
    o.push_str("AXIS#        1 2 3 4 5 6\r\n");
    o.push_str(&format!("LOCK         {}\r\n", flags(&s.lock)));
    o.push_str(&format!("DONE         {}\r\n", flags(&s.done)));
    o.push_str(&format!("LIMP         {}\r\n", flags(&s.limp)));
    o.push_str(&format!("HOMED        {}\r\n", flags(&s.homed)));
    o.push_str("REQUESTED ROBOT CONFIG : UPRIGHT/REACH FORWARD/ELBOW UP/WRIST FREE\r\n");
    o.push_str("CURRENT ROBOT CONFIG : UPRIGHT/REACH FORWARD/ELBOW UP/WRIST FREE\r\n");
    o.push_str("MANUAL MODE STATUS IS OFF\r\n");
    match s.metric {
        Some(true) => o.push_str("METRIC UNITS.\r\n"),
        Some(false) => o.push_str("ENGLISH UNITS.\r\n"),
        None => {}
    }
    o
}

fn flag_row(text: &str, label: &str) -> Result<[bool; 6], String> {
    let line = text
        .split(['\r', '\n'])
        .find(|l| l.starts_with(label))
        .ok_or_else(|| format!("STATUS has no {label} row"))?;
    let v: Vec<bool> = line[label.len()..]
        .split_whitespace()
        .map(|w| match w {
            "Y" => Ok(true),
            "N" => Ok(false),
            other => Err(format!("STATUS {label} row: `{other}` is neither Y nor N")),
        })
        .collect::<Result<_, _>>()?;
    <[bool; 6]>::try_from(v.as_slice())
        .map_err(|_| format!("STATUS {label} row has {} axes, not 6", v.len()))
}

/// Read a STATUS reply.
pub fn read_status(text: &str) -> Result<Status, String> {
    let lines: Vec<&str> = text
        .split(['\r', '\n'])
        .map(str::trim_end)
        .filter(|l| !l.is_empty())
        .collect();
    let version = lines
        .iter()
        .find(|l| l.starts_with("RAPL"))
        .map(|l| l.to_string())
        .unwrap_or_default();
    let last_error = lines
        .iter()
        .find_map(|l| l.strip_prefix("LAST ERROR CODE:"))
        .map(|s| s.trim().to_string())
        .unwrap_or_default();
    let speed = lines
        .iter()
        .find_map(|l| l.strip_prefix("SPEED (% OF FULL) :"))
        .and_then(|s| s.trim().parse::<f64>().ok())
        .unwrap_or(f64::NAN);
    let metric = if lines.iter().any(|l| l.starts_with("METRIC UNITS")) {
        Some(true)
    } else if lines
        .iter()
        .any(|l| l.starts_with("ENGLISH UNITS") || l.starts_with("INCH UNITS"))
    {
        Some(false)
    } else {
        None
    };
    Ok(Status {
        version,
        last_error,
        speed,
        lock: flag_row(text, "LOCK")?,
        done: flag_row(text, "DONE")?,
        limp: flag_row(text, "LIMP")?,
        homed: flag_row(text, "HOMED")?,
        metric,
    })
}

/// A location of the controller's table as LISTL prints it.
#[derive(Clone, Debug, PartialEq)]
pub enum Listed {
    /// Cartesian: x y z (units), three angles (degrees, the controller's order).
    Cart([f64; 6]),
    /// A precision point: motor pulses.
    Prec([i64; 6]),
}

/// LISTL's header line: 69 characters (RW reads it as 72 bytes with the line feed before
/// it and the CR LF after it).
pub const LISTL_HEADER: &str =
    "NAME              X         Y         Z      ANG1      ANG2      ANG3";

/// The body of a LISTL reply for `rows`: a line feed, the header and one row per location
/// (a cartesian row is 69 characters: RW reads it as 71 bytes with its CR LF).
pub fn write_listl(rows: &[(String, Listed)]) -> String {
    let mut s = format!("\n{LISTL_HEADER}\r\n");
    for (name, loc) in rows {
        s.push_str(&format!("{name:<9}"));
        match loc {
            Listed::Cart(v) => v.iter().for_each(|x| s.push_str(&format!(" {x:+09.3}"))),
            Listed::Prec(p) => p.iter().for_each(|x| s.push_str(&format!(" {x:+010}"))),
        }
        s.push_str("\r\n");
    }
    s
}

/// Read a LISTL reply: the locations it lists (none when the name is unknown).
pub fn read_listl(text: &str) -> Result<Vec<(String, Listed)>, String> {
    let mut out = Vec::new();
    for line in text.split(['\r', '\n']).map(str::trim) {
        if line.is_empty() || line.starts_with("NAME") || line == "." {
            continue;
        }
        let mut words = line.split_whitespace();
        let name = words.next().unwrap_or_default().to_string();
        let rest: Vec<&str> = words.collect();
        if rest.len() != 6 {
            return Err(format!("LISTL row `{line}` does not hold six values"));
        }
        let loc = if name.starts_with('#') {
            let mut p = [0i64; 6];
            for (slot, w) in p.iter_mut().zip(&rest) {
                *slot = w
                    .parse()
                    .map_err(|_| format!("LISTL row `{line}`: `{w}` is not a pulse count"))?;
            }
            Listed::Prec(p)
        } else {
            let mut v = Vec::new();
            collect_numbers(&rest.join(" "), &mut v)
                .map_err(|e| format!("LISTL row `{line}`: {e}"))?;
            Listed::Cart(<[f64; 6]>::try_from(v.as_slice()).expect("six values"))
        };
        out.push((name, loc));
    }
    Ok(out)
}

/// An error line: `NNN-TEXT.` at the start of a line of the reply.
pub fn error_line(text: &str) -> Option<(u16, String)> {
    text.split(['\r', '\n']).map(str::trim).find_map(|l| {
        let b = l.as_bytes();
        if b.len() >= 6 && b[..3].iter().all(u8::is_ascii_digit) && b[3] == b'-' && l.ends_with('.')
        {
            Some((l[..3].parse().ok()?, l[4..l.len() - 1].to_string()))
        } else {
            None
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_g3000_sample_reads() {
        // The public W2 sample (a465.md §2.3), five axes plus the wrapped sixth.
        let w2 = "\r\nCURRENT ACTUAL POSITION :\r\nNAME       AX#1/6      AX#2/7      AX#3/8      AX#4        AX#5\r\nPULSES   -0000000001 -0000000001 -0000000001 -0000000001 -0000000001\r\n         -0000000114\r\nNAME       JT#1/6    JT#2/7    JT#3/8    JT#4      JT#5\r\nJOINTS   +000.0150 +000.0150 +000.0150 +000.0071 +000.0036\r\n         +000.8126\r\nWORLD     +000.0198 +000.0149 -076.1849 +000.0000 +089.9964 +000.8198\r\n.\r\n";
        let p = read_position(w2).unwrap();
        assert_eq!(p.pulses, [-1, -1, -1, -1, -1, -114]);
        assert_eq!(p.joints[5], 0.8126);
        assert_eq!(p.world[2], -76.1849);
    }

    #[test]
    fn what_is_written_reads_back() {
        let p = Position {
            pulses: [1, -2, 30000, -400000, 5, -114],
            joints: [12.5, -90.0, 110.0, 0.0, -0.0036, 179.9],
            world: [420.0, -1050.25, 3.0, -90.0, 89.9964, 0.8198],
        };
        assert_eq!(read_position(&write_position(false, &p)).unwrap(), p);
        let s = Status {
            version: "RAPL-II Version 2.60     A465 Robot".into(),
            last_error: "000-NO ERROR.".into(),
            speed: 50.0,
            lock: [false; 6],
            done: [true, true, false, true, true, true],
            limp: [false; 6],
            homed: [true; 6],
            metric: Some(true),
        };
        assert_eq!(read_status(&write_status(&s, &[0.0; 6])).unwrap(), s);
        let rows = vec![
            (
                "T1".to_string(),
                Listed::Cart([400.0, 0.0, 150.0, 0.0, 90.0, 0.0]),
            ),
            ("#PARK".to_string(), Listed::Prec([0, 1, -2, 3, 4, 5])),
        ];
        let text = write_listl(&rows);
        assert_eq!(read_listl(&text).unwrap(), rows);
        // RW's fixed-length read: 72 bytes of header, 71 of the first row.
        assert_eq!(text.find("T1").unwrap(), 72);
        assert_eq!(text[72..].find("#PARK").unwrap(), 71);
    }

    #[test]
    fn numbers_and_error_lines() {
        assert_eq!(num(-0.00001), "0");
        assert_eq!(num(12.34567), "12.3457");
        assert_eq!(num(-3.0), "-3");
        assert_eq!(num(100.0), "100");
        assert_eq!(num(0.5), "0.5");
        assert_eq!(num(-0.25), "-0.25");
        assert_eq!(
            error_line("\r\n012-COMMAND ERROR.\r\n"),
            Some((12, "COMMAND ERROR".into()))
        );
        // STATUS's report of the last error is not an error of this command.
        assert_eq!(error_line("LAST ERROR CODE: 012-COMMAND ERROR.\r\n"), None);
        assert!(read_position("PULSES 1 2 3\r\n").is_err());
        assert!(row("WORLD  1 2 x 4 5 6", "WORLD").is_err());
    }
}

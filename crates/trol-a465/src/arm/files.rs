//! The locations file (the manual's `SaveLocations` text) and the world file of the
//! simulated cell, read and parsed.

use super::*;

/// Read the locations file at `path` ([`parse_locations`]); a file larger than
/// [`MAX_LOCATIONS_FILE`] is refused unread.
pub fn read_locations(path: &std::path::Path) -> Result<Vec<(String, Stored)>, String> {
    use std::io::Read;
    let file =
        std::fs::File::open(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let mut text = String::new();
    file.take(MAX_LOCATIONS_FILE + 1)
        .read_to_string(&mut text)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    if text.len() as u64 > MAX_LOCATIONS_FILE {
        return Err(format!(
            "{}: larger than {} MiB; the table holds {MAX_TABLE} locations, which fit in far \
             less: is it a locations file?",
            path.display(),
            MAX_LOCATIONS_FILE >> 20
        ));
    }
    parse_locations(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// Read a location file: one location per line, `NAME v1 v2 v3 v4 v5 v6` (blanks or commas
/// between). A name starting with `#` is a precision point (six encoder counts); any other
/// is cartesian (x y z in mm, yaw pitch roll in radians), or joint angles in radians with
/// the word `joint` before the values (`NAME joint q1 .. q6`). Blank lines and lines
/// starting with `;` are ignored.
pub fn parse_locations(text: &str) -> Result<Vec<(String, Stored)>, String> {
    let mut out: Vec<(String, Stored)> = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with(';') {
            continue;
        }
        if out.len() == MAX_TABLE {
            return Err(format!(
                "line {}: more than {MAX_TABLE} locations; the table holds {MAX_TABLE}: split \
                 the file, or delete locations no program uses",
                n + 1
            ));
        }
        let mut parts = line
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|s| !s.is_empty());
        let name = parts.next().unwrap_or_default();
        let err = |why: &str| {
            format!(
                "line {}: {why}; expected `NAME v1 v2 v3 v4 v5 v6` (a name of up to 8 \
                 characters, the first a letter or '#', the rest letters, digits or '_')",
                n + 1
            )
        };
        let ok_name = !name.is_empty()
            && name.len() <= 8
            && (name.as_bytes()[0].is_ascii_alphabetic() || name.starts_with('#'))
            && name[1..]
                .bytes()
                .all(|b| b.is_ascii_alphanumeric() || b == b'_');
        if !ok_name {
            return Err(err(&format!("bad name {name:?}")));
        }
        let mut values: Vec<&str> = parts.collect();
        let joint = values.first() == Some(&"joint");
        if joint {
            if name.starts_with('#') {
                return Err(err(
                    "a precision point (#NAME) holds encoder counts, not joints",
                ));
            }
            values.remove(0);
        }
        if values.len() != 6 {
            return Err(err(&format!("{} values", values.len())));
        }
        let loc = if joint {
            let mut q = [0f64; 6];
            for (i, v) in values.iter().enumerate() {
                q[i] = v
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| err(&format!("{v:?} is not a number")))?;
            }
            Stored::Joints(q)
        } else if name.starts_with('#') {
            let mut c = [0i32; 6];
            for (i, v) in values.iter().enumerate() {
                c[i] = v
                    .parse()
                    .map_err(|_| err(&format!("{v:?} is not a whole number of counts")))?;
            }
            Stored::Prec(c)
        } else {
            let mut c = [0f64; 6];
            for (i, v) in values.iter().enumerate() {
                c[i] = v
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| err(&format!("{v:?} is not a number")))?;
            }
            // Angles are radians; one past a full turn was almost surely written in degrees
            // (the words every surface uses: the command table refuses the same).
            if let Some(why) = trol_proto::application::location::orientation_beyond_a_turn(&c) {
                return Err(format!("line {}: {why}", n + 1));
            }
            Stored::Cart(c)
        };
        out.push((name.to_string(), loc));
    }
    Ok(out)
}

/// Read an objects file: one object per line, `NAME x y z width` (mm; blanks or commas
/// between). Blank lines and lines starting with `;` are ignored.
pub fn parse_objects(text: &str) -> Result<Vec<WorldObject>, String> {
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with(';') {
            continue;
        }
        let parts: Vec<&str> = line
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|s| !s.is_empty())
            .collect();
        let err = |why: String| {
            format!(
                "line {}: {why}; expected `NAME x y z width` (mm, a width of 0..{FINGER_MAX})",
                n + 1
            )
        };
        if parts.len() != 5 {
            return Err(err(format!("{} fields", parts.len())));
        }
        let mut v = [0.0; 4];
        for (i, p) in parts[1..].iter().enumerate() {
            v[i] = p
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| err(format!("{p:?} is not a number")))?;
        }
        if !(v[3] > 0.0 && v[3] <= FINGER_MAX) {
            return Err(err(format!("width {}", v[3])));
        }
        out.push(WorldObject {
            name: parts[0].to_string(),
            pos: [v[0], v[1], v[2]],
            width: v[3],
        });
    }
    Ok(out)
}

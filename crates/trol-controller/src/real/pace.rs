//! The pace of a trajectory on a controller that has no timed path (issue 41): each
//! waypoint is a joint move of its own, at the speed setting the waypoint's time implies.

/// The speed setting for one joint move of a trajectory.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Pace {
    /// No joint moves: any setting does.
    Still,
    /// This percent of each joint's top speed: the lowest at which the move, at its joints'
    /// speed limits alone, takes no longer than its time (acceleration makes it a little
    /// longer: the trajectory runs untimed).
    Percent(u8),
    /// The move needs more than the ceiling (the user's speed setting) in its time: the
    /// percent it would need (infinite for a move in no time).
    TooFast(f64),
}

/// A joint move shorter than this at every joint (radians) does not move.
const STILL_RAD: f64 = 1e-9;

/// The pace of the move from `from` to `to` (radians) in `dt` seconds, for an arm whose
/// joints' top speeds are `top` (rad/s at 100 %), never above `ceiling` percent.
pub fn pace(from: &[f64; 6], to: &[f64; 6], dt: f64, top: &[f64; 6], ceiling: u8) -> Pace {
    let longest = (0..6)
        .map(|j| (to[j] - from[j]).abs() / top[j])
        .fold(0.0, f64::max);
    if from.iter().chain(to).any(|x| !x.is_finite()) || !longest.is_finite() {
        return Pace::TooFast(f64::INFINITY);
    }
    if longest <= STILL_RAD {
        return Pace::Still;
    }
    if dt.is_nan() || dt <= 0.0 {
        return Pace::TooFast(f64::INFINITY);
    }
    let needed = 100.0 * longest / dt;
    // A hair over a whole percent is that percent (times travel as f32).
    let percent = (needed - 1e-6).ceil().max(1.0);
    if percent > f64::from(ceiling) {
        Pace::TooFast(needed)
    } else {
        Pace::Percent(percent as u8)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TOP: [f64; 6] = [3.0, 3.0, 3.0, 3.0, 3.0, 3.0];

    #[test]
    fn the_slowest_joint_that_keeps_the_time_sets_the_pace() {
        // Joint 2 travels 0.6 rad in 1 s: 20 % of 3 rad/s; joint 1's 0.3 rad needs 10 %.
        let to = [0.3, 0.6, 0.0, 0.0, 0.0, 0.0];
        assert_eq!(pace(&[0.0; 6], &to, 1.0, &TOP, 100), Pace::Percent(20));
        // Half the time, twice the speed; a fraction of a percent rounds up.
        assert_eq!(pace(&[0.0; 6], &to, 0.5, &TOP, 100), Pace::Percent(40));
        assert_eq!(pace(&[0.0; 6], &to, 0.7, &TOP, 100), Pace::Percent(29));
        // A long time: never below 1 %.
        assert_eq!(pace(&[0.0; 6], &to, 1000.0, &TOP, 100), Pace::Percent(1));
    }

    #[test]
    fn above_the_ceiling_or_in_no_time_is_too_fast() {
        let to = [0.0, 0.6, 0.0, 0.0, 0.0, 0.0];
        match pace(&[0.0; 6], &to, 1.0, &TOP, 19) {
            Pace::TooFast(p) => assert!((p - 20.0).abs() < 1e-9, "{p}"),
            other => panic!("{other:?}"),
        }
        assert_eq!(pace(&[0.0; 6], &to, 1.0, &TOP, 20), Pace::Percent(20));
        assert_eq!(
            pace(&[0.0; 6], &to, 0.0, &TOP, 100),
            Pace::TooFast(f64::INFINITY)
        );
        assert_eq!(
            pace(&[0.0; 6], &to, f64::NAN, &TOP, 100),
            Pace::TooFast(f64::INFINITY)
        );
        assert_eq!(
            pace(&[0.0; 6], &[f64::NAN; 6], 1.0, &TOP, 100),
            Pace::TooFast(f64::INFINITY)
        );
    }

    #[test]
    fn a_move_that_goes_nowhere_is_still_even_in_no_time() {
        assert_eq!(pace(&[0.1; 6], &[0.1; 6], 0.0, &TOP, 100), Pace::Still);
    }
}

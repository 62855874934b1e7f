//! Halt as the arm shows it ([`halt`]), and the "standing" test ([`seen_standing`]) it and the
//! supervised steps use.

use std::time::{Duration, Instant};

/// The pause between the two readings that show an arm standing (a motion at the slowest
/// speed moves about 1 degree in it).
pub const STILL_GAP: Duration = Duration::from_millis(250);

/// How far (degrees, on every joint) two readings [`STILL_GAP`] apart may differ for an arm
/// that stands (encoder dither).
pub const STILL_DEG: f64 = 0.02;

/// A backend's side of [`halt`] and [`seen_standing`].
pub trait Stopping {
    /// One of the controller's ways to stop the arm.
    type Stop: Copy;

    /// How the stop is written in messages (`HALT`, `Ctrl-C`, `STOP:`).
    fn stop_name(&self, stop: Self::Stop) -> String;

    /// Send `stop`: what the controller answered (for the messages), or why it could not
    /// be sent or confirmed as taken.
    fn send_stop(&mut self, stop: Self::Stop) -> Result<String, String>;

    /// Where the arm is (one reading, each joint in the unit of [`Stopping::still_within`]);
    /// `None` where the controller itself says the arm moves.
    fn reading(&mut self) -> Result<Option<[f64; 6]>, String>;

    /// How far two readings of a standing arm may differ, per joint.
    fn still_within(&self) -> [f64; 6];

    /// The backend's clock.
    fn now(&self) -> Instant;

    /// Let `d` pass (the backend sleeps, or serves its line meanwhile).
    fn pause(&mut self, d: Duration);
}

/// How long a Halt may take.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HaltTimes {
    /// From the call to the arm seen standing, every stop included.
    pub halt_within: Duration,
    /// How long one stop is given to show the arm standing before the next is tried.
    pub stop_within: Duration,
}

/// What a [`halt`] saw.
#[derive(Debug, Clone, PartialEq)]
pub enum Halted {
    /// The arm stands at `at`, after the stop named in `note` where others did not work
    /// (`None`: the first stop worked).
    Standing {
        /// The last reading.
        at: [f64; 6],
        /// What to tell the log: which stops did not work before one did.
        note: Option<String>,
    },
    /// No stop was seen to work within the Halt's time: what each stop got, and what to do
    /// (TROL_ERR_NOT_STOPPED with this text).
    NotStopped(String),
}

/// Whether the arm is seen standing before `until` (at most `stop_within` from now): two
/// readings [`STILL_GAP`] apart that agree within [`Stopping::still_within`], neither
/// while the controller says the arm moves. `Ok(Err(why))` where it still moved.
pub fn seen_standing<A: Stopping + ?Sized>(
    arm: &mut A,
    until: Instant,
    stop_within: Duration,
) -> Result<Result<[f64; 6], String>, String> {
    let until = until.min(arm.now() + stop_within);
    let tol = arm.still_within();
    let mut last: Option<[f64; 6]> = None;
    let mut why: String;
    loop {
        let now = arm.reading()?;
        match (last, now) {
            (Some(a), Some(b)) => match (0..6).find(|&j| (a[j] - b[j]).abs() > tol[j]) {
                None => return Ok(Ok(b)),
                Some(j) => {
                    why = format!(
                        "the arm still moved (joint {} by {:.3} in {} ms)",
                        j + 1,
                        (a[j] - b[j]).abs(),
                        STILL_GAP.as_millis()
                    )
                }
            },
            (None, Some(_)) => why = "the arm was read standing only once".into(),
            (_, None) => why = "the controller still said the arm moves".into(),
        }
        last = now;
        if arm.now() + STILL_GAP > until {
            return Ok(Err(why));
        }
        arm.pause(STILL_GAP);
    }
}

/// Halt as the arm shows it: each of `stops` in turn until the arm is seen standing
/// ([`seen_standing`]); success only then. An arm that stands only after the Halt's time
/// ran its motion to its end: no stop was seen to work, and that is said.
pub fn halt<A: Stopping + ?Sized>(arm: &mut A, stops: &[A::Stop], times: HaltTimes) -> Halted {
    let start = arm.now();
    let until = start + times.halt_within;
    let mut said = Vec::new();
    for &stop in stops {
        if arm.now() >= until {
            break;
        }
        let name = arm.stop_name(stop);
        let sent = match arm.send_stop(stop) {
            Ok(s) => s,
            Err(e) => {
                said.push(format!("{name}: {e}"));
                continue;
            }
        };
        match seen_standing(arm, until, times.stop_within) {
            Ok(Ok(_)) if arm.now() > until + STILL_GAP => {
                said.push(format!(
                    "{name}: {sent}, and the arm stood only {:.1} s after the Halt (its motion \
                     may have ended by itself)",
                    (arm.now() - start).as_secs_f64()
                ));
                break;
            }
            Ok(Ok(at)) => {
                let note = (!said.is_empty()).then(|| {
                    format!(
                        "Halt: the arm stands after {name} ({sent}), where {} did not stop it",
                        said.join("; ")
                    )
                });
                return Halted::Standing { at, note };
            }
            Ok(Err(why)) => said.push(format!("{name}: {sent}, but {why}")),
            Err(e) => said.push(format!("{name}: {sent}, then reading the arm: {e}")),
        }
    }
    Halted::NotStopped(format!(
        "{}; use the emergency stop",
        if said.is_empty() {
            "no stop could be sent".to_string()
        } else {
            said.join("; ")
        }
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A scripted arm in virtual time: it moves at `speed` per second until the stop that
    /// works (by index) is sent, and stands from then on (after `brake`).
    struct Scripted {
        t: Instant,
        start: Instant,
        speed: f64,
        works: Option<usize>,
        brake: Duration,
        stopped_at: Option<Instant>,
        refuses: Vec<usize>,
        says_moving: bool,
        sent: Vec<usize>,
        ends_by_itself: Option<Duration>,
    }

    impl Scripted {
        fn new(works: Option<usize>) -> Self {
            let t = Instant::now();
            Scripted {
                t,
                start: t,
                speed: 10.0,
                works,
                brake: Duration::from_millis(300),
                stopped_at: None,
                refuses: Vec::new(),
                says_moving: false,
                sent: Vec::new(),
                ends_by_itself: None,
            }
        }
        fn moving(&self) -> bool {
            let braked = self.stopped_at.is_some_and(|s| self.t >= s + self.brake);
            let ended = self
                .ends_by_itself
                .is_some_and(|d| self.t >= self.start + d);
            !(braked || ended)
        }
    }

    impl Stopping for Scripted {
        type Stop = usize;
        fn stop_name(&self, stop: usize) -> String {
            format!("STOP{stop}")
        }
        fn send_stop(&mut self, stop: usize) -> Result<String, String> {
            self.t += Duration::from_millis(20);
            if self.refuses.contains(&stop) {
                return Err("not sent: the line is down".into());
            }
            self.sent.push(stop);
            if self.works == Some(stop) {
                self.stopped_at = Some(self.t);
            }
            Ok("acknowledged".into())
        }
        fn reading(&mut self) -> Result<Option<[f64; 6]>, String> {
            self.t += Duration::from_millis(30);
            if self.moving() && self.says_moving {
                return Ok(None);
            }
            let until = match (self.stopped_at, self.ends_by_itself) {
                (Some(s), _) if self.t >= s + self.brake => s + self.brake,
                (_, Some(d)) if self.t >= self.start + d => self.start + d,
                _ => self.t,
            };
            let x = (until - self.start).as_secs_f64() * self.speed;
            Ok(Some([x, 0.0, 0.0, 0.0, 0.0, 0.0]))
        }
        fn still_within(&self) -> [f64; 6] {
            [STILL_DEG; 6]
        }
        fn now(&self) -> Instant {
            self.t
        }
        fn pause(&mut self, d: Duration) {
            self.t += d;
        }
    }

    const TIMES: HaltTimes = HaltTimes {
        halt_within: Duration::from_millis(3300),
        stop_within: Duration::from_millis(1000),
    };

    #[test]
    fn the_first_stop_that_works_is_success_and_the_others_are_named() {
        let mut arm = Scripted::new(Some(0));
        let Halted::Standing { note, at } = halt(&mut arm, &[0, 1], TIMES) else {
            panic!("the first stop works");
        };
        assert_eq!(note, None);
        assert_eq!(arm.sent, [0]);
        assert!(at[0] > 0.0);

        let mut arm = Scripted::new(Some(1));
        let Halted::Standing { note, .. } = halt(&mut arm, &[0, 1], TIMES) else {
            panic!("the second stop works");
        };
        let note = note.expect("the stop that did not work is told");
        assert!(note.contains("after STOP1"), "{note}");
        assert!(
            note.contains("STOP0: acknowledged, but the arm still moved"),
            "{note}"
        );
        assert_eq!(arm.sent, [0, 1]);
    }

    #[test]
    fn no_stop_that_works_is_not_stopped_within_the_halt_s_time() {
        let mut arm = Scripted::new(None);
        let Halted::NotStopped(text) = halt(&mut arm, &[0, 1, 2, 3, 4, 5], TIMES) else {
            panic!("nothing stops this arm");
        };
        assert!(text.ends_with("use the emergency stop"), "{text}");
        assert!(text.contains("still moved (joint 1"), "{text}");
        // Bounded: not one stop more once the Halt's time is over.
        assert!(
            arm.t - arm.start <= TIMES.halt_within + STILL_GAP * 2,
            "{text}"
        );
        assert!(arm.sent.len() < 6, "{:?}", arm.sent);
    }

    #[test]
    fn an_arm_that_stands_only_after_the_halt_s_time_is_not_a_stop() {
        // The motion ends by itself 3.2 s on; the controller says "moving" until then, so
        // the standing is seen only after the Halt's time.
        let mut arm = Scripted::new(None);
        arm.says_moving = true;
        arm.ends_by_itself = Some(Duration::from_millis(3200));
        let got = halt(&mut arm, &[0, 1, 2, 3, 4], TIMES);
        let Halted::NotStopped(text) = got else {
            panic!("standing late is no stop: {got:?}");
        };
        assert!(
            text.contains("said the arm moves")
                || text.contains("standing only once")
                || text.contains("stood only"),
            "{text}"
        );
    }

    #[test]
    fn a_stop_that_cannot_be_sent_is_told_and_the_next_is_tried() {
        let mut arm = Scripted::new(Some(1));
        arm.refuses = vec![0];
        let Halted::Standing { note, .. } = halt(&mut arm, &[0, 1], TIMES) else {
            panic!("the second stop works");
        };
        assert!(note.unwrap().contains("STOP0: not sent: the line is down"));

        let mut arm = Scripted::new(Some(0));
        arm.refuses = vec![0];
        let Halted::NotStopped(text) = halt(&mut arm, &[0], TIMES) else {
            panic!("the only stop could not be sent");
        };
        assert!(text.starts_with("STOP0: not sent"), "{text}");
        assert_eq!(
            halt(&mut Scripted::new(None), &[], TIMES),
            Halted::NotStopped("no stop could be sent; use the emergency stop".into())
        );
    }

    #[test]
    fn standing_needs_two_readings_that_agree_and_the_controller_s_word() {
        // Standing from the start: two readings one gap apart.
        let mut arm = Scripted::new(Some(0));
        arm.stopped_at = Some(arm.t - Duration::from_secs(1));
        let t0 = arm.t;
        let until = t0 + Duration::from_secs(10);
        assert!(matches!(
            seen_standing(&mut arm, until, TIMES.stop_within),
            Ok(Ok(_))
        ));
        assert!(arm.t - t0 >= STILL_GAP);
        // Moving: never standing, within the stop's time.
        let mut arm = Scripted::new(None);
        let t0 = arm.t;
        let got = seen_standing(&mut arm, t0 + Duration::from_secs(10), TIMES.stop_within);
        assert!(matches!(got, Ok(Err(_))), "{got:?}");
        assert!(arm.t - t0 <= TIMES.stop_within + STILL_GAP);
        // A controller that says "moving" is believed even where the readings agree.
        let mut arm = Scripted::new(None);
        arm.speed = 0.0;
        arm.says_moving = true;
        let t0 = arm.t;
        let got = seen_standing(&mut arm, t0 + Duration::from_secs(10), TIMES.stop_within);
        assert_eq!(
            got,
            Ok(Err("the controller still said the arm moves".into()))
        );
    }
}

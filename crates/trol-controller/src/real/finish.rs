//! Finish's end rule: when a motion sent to a real controller has ended, stopped short, or
//! can no longer be judged.
//!
//! A motion has ended only when two things agree: the controller says it is done (a STATUS
//! row, a moving bit, a FINISH answer) and the arm is read at the motion's end within the
//! backend's tolerance. Neither alone is success. The controller's "done" with the arm
//! standing short of the end is a stop short (a servo fault, a stop at the controller): a
//! refusal, known as soon as the arm has stood for the settle time. A controller that says
//! done while the arm is neither at the end nor standing is given up after the motion's own
//! time and a margin: whether the motion ran as asked is then not known (UNSURE), and the
//! backend sends nothing further of it.

use std::time::{Duration, Instant};

/// How long a motion's end may take to show.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EndTimes {
    /// How long the arm must be read standing short of the motion's end, while the
    /// controller says done, before that counts as a stop short (the profile's settle time).
    pub settle: Duration,
    /// From the motion sent: how long a motion whose end is neither seen nor ruled out is
    /// looked for before it is given up as unsure.
    pub give_up: Duration,
}

/// What one look at a motion under way shows.
#[derive(Debug, Clone, PartialEq)]
pub enum End {
    /// Not ended yet: look again.
    Running,
    /// The controller says done and the arm is at the motion's end.
    Arrived,
    /// The controller says done and the arm has stood for the settle time at this reading,
    /// short of the end: a refusal (the controller's "not at target" code), and whatever
    /// waits behind the motion is dropped unsent.
    StoppedShort([f64; 6]),
    /// The motion's end was neither seen nor ruled out within [`EndTimes::give_up`]:
    /// UNSURE, and nothing further of it is sent.
    TimedOut,
}

/// One motion's end, followed look by look. The backend feeds it what the controller says
/// ([`EndWatch::saw_moving`]) and where the arm is read ([`EndWatch::saw_at`]); it decides
/// whether the arm is at the end by its own tolerance, and asks [`EndWatch::verdict`].
#[derive(Debug, Clone)]
pub struct EndWatch {
    sent: Instant,
    planned_end: Option<Instant>,
    from: Option<[f64; 6]>,
    still: [f64; 6],
    seen_moving: bool,
    moved: bool,
    standing: Option<(Instant, [f64; 6])>,
}

impl EndWatch {
    /// A motion sent at `sent`, from where the arm was last seen at rest (`from`, if it was);
    /// two readings within `still` of each other (per joint) are an arm that stands.
    pub fn new(sent: Instant, from: Option<[f64; 6]>, still: [f64; 6]) -> EndWatch {
        EndWatch {
            sent,
            planned_end: None,
            from,
            still,
            seen_moving: false,
            moved: false,
            standing: None,
        }
    }

    /// The motion is planned to end at `at` (a backend that plans its motions): the arm read
    /// at the end before then, without the controller ever saying it moved, is still slowing
    /// down, and a stop short is not judged before `at` and the settle time.
    pub fn planned_to_end(mut self, at: Instant) -> EndWatch {
        self.planned_end = Some(at);
        self
    }

    /// The controller says the arm moves (or answered the motion at its end, which it does
    /// only once it ran). Standing is judged afresh from the next reading.
    pub fn saw_moving(&mut self) {
        self.seen_moving = true;
        self.standing = None;
    }

    /// The arm was read at `at` (the controller saying done).
    pub fn saw_at(&mut self, now: Instant, at: [f64; 6]) {
        match self.standing {
            Some((_, q)) if self.near(&q, &at) => {}
            Some(_) => {
                self.moved = true;
                self.standing = Some((now, at));
            }
            None => self.standing = Some((now, at)),
        }
    }

    /// Whether the controller was seen to say the arm moves since the motion was sent.
    pub fn seen_moving(&self) -> bool {
        self.seen_moving
    }

    /// Whether the motion is seen to have run: the controller said it moves, two readings
    /// differed, or the arm left where it rested before.
    pub fn ran(&self) -> bool {
        self.seen_moving
            || self.moved
            || matches!((self.from, self.standing), (Some(a), Some((_, b))) if !self.near(&a, &b))
    }

    /// How long the arm has been read standing in one place, as of `now`.
    pub fn stood_for(&self, now: Instant) -> Option<Duration> {
        self.standing.map(|(t, _)| now.saturating_duration_since(t))
    }

    /// Whether the motion was sent longer than `d` before `now`.
    pub fn older_than(&self, now: Instant, d: Duration) -> bool {
        now.saturating_duration_since(self.sent) > d
    }

    /// The rule, as of `now`, with `at_end`: whether the backend reads the arm at the
    /// motion's end (the controller saying done).
    pub fn verdict(&self, now: Instant, at_end: bool, times: EndTimes) -> End {
        let plan_over = |margin: Duration| self.planned_end.is_none_or(|e| now >= e + margin);
        if at_end && (self.seen_moving || plan_over(Duration::ZERO)) {
            return End::Arrived;
        }
        if !at_end {
            let stood = self.stood_for(now).is_some_and(|d| d >= times.settle);
            // A motion that never showed as running may still be about to start (a status
            // row that lags): only a planned one should have run by its planned end.
            let should_have_run = self.ran() || self.planned_end.is_some();
            if stood && should_have_run && plan_over(times.settle) {
                let at = self.standing.map(|(_, q)| q).unwrap_or_default();
                return End::StoppedShort(at);
            }
        }
        if self.older_than(now, times.give_up) {
            return End::TimedOut;
        }
        End::Running
    }

    fn near(&self, a: &[f64; 6], b: &[f64; 6]) -> bool {
        (0..6).all(|j| (a[j] - b[j]).abs() <= self.still[j])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TIMES: EndTimes = EndTimes {
        settle: Duration::from_millis(300),
        give_up: Duration::from_secs(10),
    };
    const STILL: [f64; 6] = [0.02; 6];

    fn ms(t0: Instant, n: u64) -> Instant {
        t0 + Duration::from_millis(n)
    }

    fn at(x: f64) -> [f64; 6] {
        [x, 0.0, 0.0, 0.0, 0.0, 0.0]
    }

    #[test]
    fn done_and_at_the_end_is_arrival_and_neither_alone_is() {
        let t0 = Instant::now();
        let mut w = EndWatch::new(t0, Some(at(0.0)), STILL);
        w.saw_moving();
        // The controller says done, the arm is not at the end and still moves: running.
        w.saw_at(ms(t0, 100), at(5.0));
        assert_eq!(w.verdict(ms(t0, 100), false, TIMES), End::Running);
        w.saw_at(ms(t0, 150), at(9.0));
        assert_eq!(w.verdict(ms(t0, 150), false, TIMES), End::Running);
        // At the end: arrived.
        w.saw_at(ms(t0, 200), at(10.0));
        assert_eq!(w.verdict(ms(t0, 200), true, TIMES), End::Arrived);
    }

    #[test]
    fn standing_short_for_the_settle_time_is_a_stop_short_and_not_before() {
        let t0 = Instant::now();
        let mut w = EndWatch::new(t0, Some(at(0.0)), STILL);
        w.saw_moving();
        w.saw_at(ms(t0, 100), at(4.0));
        w.saw_at(ms(t0, 200), at(4.01));
        assert_eq!(w.verdict(ms(t0, 399), false, TIMES), End::Running);
        assert_eq!(
            w.verdict(ms(t0, 400), false, TIMES),
            End::StoppedShort(at(4.0))
        );
        // The controller saying "moving" again starts the standing afresh.
        w.saw_moving();
        w.saw_at(ms(t0, 500), at(4.0));
        assert_eq!(w.verdict(ms(t0, 700), false, TIMES), End::Running);
    }

    #[test]
    fn a_motion_never_seen_running_waits_for_its_time_then_is_unsure() {
        // The controller says done from the start and the arm stands where it rested: the
        // status row may lag, so this is no stop short; after give_up it is not known.
        let t0 = Instant::now();
        let mut w = EndWatch::new(t0, Some(at(0.0)), STILL);
        for n in 1..=100 {
            w.saw_at(ms(t0, n * 100), at(0.0));
            assert_eq!(w.verdict(ms(t0, n * 100), false, TIMES), End::Running);
        }
        w.saw_at(ms(t0, 10_001), at(0.0));
        assert_eq!(w.verdict(ms(t0, 10_001), false, TIMES), End::TimedOut);
        // Having left its rest and stood is a run that stopped short.
        let mut w = EndWatch::new(t0, Some(at(0.0)), STILL);
        w.saw_at(ms(t0, 100), at(2.0));
        assert_eq!(
            w.verdict(ms(t0, 400), false, TIMES),
            End::StoppedShort(at(2.0))
        );
        // An arm that never stands, with the controller saying done: unsure at give_up.
        let mut w = EndWatch::new(t0, None, STILL);
        for n in 1..=101 {
            w.saw_at(ms(t0, n * 100), at(n as f64));
        }
        assert!(w.ran());
        assert_eq!(w.verdict(ms(t0, 10_100), false, TIMES), End::TimedOut);
    }

    #[test]
    fn a_planned_motion_is_not_judged_before_its_planned_end() {
        let t0 = Instant::now();
        let w = EndWatch::new(t0, Some(at(0.0)), STILL).planned_to_end(ms(t0, 1000));
        let mut w2 = w.clone();
        // At the end early, never seen moving: still slowing down.
        w2.saw_at(ms(t0, 500), at(10.0));
        assert_eq!(w2.verdict(ms(t0, 500), true, TIMES), End::Running);
        assert_eq!(w2.verdict(ms(t0, 1000), true, TIMES), End::Arrived);
        // Seen moving, then at the end: arrived at once.
        let mut w3 = w.clone();
        w3.saw_moving();
        w3.saw_at(ms(t0, 500), at(10.0));
        assert_eq!(w3.verdict(ms(t0, 500), true, TIMES), End::Arrived);
        // Never left: a stop short only after the planned end and the settle time.
        let mut w4 = w;
        w4.saw_at(ms(t0, 100), at(0.0));
        assert_eq!(w4.verdict(ms(t0, 1299), false, TIMES), End::Running);
        assert_eq!(
            w4.verdict(ms(t0, 1300), false, TIMES),
            End::StoppedShort(at(0.0))
        );
    }
}

//! What was seen of the arm a moment ago, standing in for the same read before the next
//! motion (issue 43): one rule for every real controller.
//!
//! A backend that has just seen the arm (a status showing it idle, powered and homed; where
//! a motion ended, confirmed on the arm) may skip reading it again right before the next
//! motion, so that the motion reaches the line at once. It may only while:
//!
//! - the reading is no older than its window ([`SEEN_FOR`] unless the backend says
//!   otherwise);
//! - nothing but reads went to the controller since, nothing came unasked, and nothing
//!   failed: any other line, any unasked byte, an interrupt, a failed read makes the
//!   backend [`Recent::forget`] it.
//!
//! What a reading stands in for is never the motion's own check: a motion sent on it to a
//! controller that lost power or control meanwhile is refused by the controller's own reply,
//! or caught by the read right after the motion's lines, as every motion is. So no success
//! is ever reported on a reading alone.

use std::time::{Duration, Instant};

/// How long a reading stands in for the same read: 250 ms. About as old as a read made before
/// the motion is by the time the motion is typed (a C500's STATUS reply alone takes 166 ms at
/// 38400 Bd), so the arm's state is not trusted for longer than a read would have it; a
/// program's next motion after Finish comes within a few milliseconds.
pub const SEEN_FOR: Duration = Duration::from_millis(250);

/// One reading of the arm with when it was seen, which stands in for the same read for a
/// while ([module docs](self)). The clock is the backend's: every call takes `now`.
#[derive(Clone, Debug)]
pub struct Recent<T> {
    held: Option<(Instant, T)>,
    window: Duration,
}

impl<T> Default for Recent<T> {
    fn default() -> Self {
        Recent {
            held: None,
            window: SEEN_FOR,
        }
    }
}

impl<T> Recent<T> {
    /// Nothing seen yet, standing in for [`SEEN_FOR`].
    pub fn new() -> Recent<T> {
        Recent::default()
    }

    /// How long a reading stands in (tests shorten or stretch it); zero: never, so a read goes
    /// before every motion.
    pub fn set_window(&mut self, window: Duration) {
        self.window = window;
    }

    /// The arm was seen so at `at`; `None` forgets what was seen before.
    pub fn saw(&mut self, at: Instant, reading: Option<T>) {
        self.held = reading.map(|r| (at, r));
    }

    /// Forget it: a line that is not a read went out, something came unasked, something
    /// failed.
    pub fn forget(&mut self) {
        self.held = None;
    }

    /// The reading, if it is no older than the window at `now`.
    pub fn get(&self, now: Instant) -> Option<&T> {
        self.held
            .as_ref()
            .filter(|(at, _)| fresh(*at, now, self.window))
            .map(|(_, r)| r)
    }

    /// The reading as [`Recent::get`] gives it, forgotten in any case: for a motion, whose
    /// own lines would make it stale.
    pub fn take(&mut self, now: Instant) -> Option<T> {
        let window = self.window;
        self.held
            .take()
            .filter(|(at, _)| fresh(*at, now, window))
            .map(|(_, r)| r)
    }
}

fn fresh(at: Instant, now: Instant, window: Duration) -> bool {
    !window.is_zero() && now.saturating_duration_since(at) <= window
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reading_stands_in_for_its_window_and_no_longer() {
        let t0 = Instant::now();
        let mut r = Recent::new();
        assert_eq!(r.get(t0), None);
        r.saw(t0, Some(7));
        assert_eq!(r.get(t0), Some(&7));
        assert_eq!(r.get(t0 + SEEN_FOR), Some(&7));
        assert_eq!(r.get(t0 + SEEN_FOR + Duration::from_millis(1)), None);
        // A clock that reads earlier than the reading (another thread's now) is not "old".
        r.saw(t0 + Duration::from_millis(5), Some(8));
        assert_eq!(r.get(t0), Some(&8));
    }

    #[test]
    fn forgetting_and_a_missing_reading_leave_nothing() {
        let t0 = Instant::now();
        let mut r = Recent::new();
        r.saw(t0, Some("idle"));
        r.forget();
        assert_eq!(r.get(t0), None);
        r.saw(t0, Some("idle"));
        r.saw(t0, None);
        assert_eq!(r.get(t0), None);
    }

    #[test]
    fn taking_forgets_even_a_stale_reading() {
        let t0 = Instant::now();
        let mut r = Recent::new();
        r.saw(t0, Some(1));
        assert_eq!(r.take(t0 + Duration::from_millis(10)), Some(1));
        assert_eq!(r.get(t0), None);
        r.saw(t0, Some(2));
        assert_eq!(r.take(t0 + Duration::from_secs(1)), None);
        r.set_window(Duration::from_secs(2));
        r.saw(t0, Some(3));
        assert_eq!(r.take(t0 + Duration::from_secs(1)), Some(3));
    }

    #[test]
    fn a_zero_window_never_stands_in() {
        let t0 = Instant::now();
        let mut r = Recent::new();
        r.set_window(Duration::ZERO);
        r.saw(t0, Some(1));
        assert_eq!(r.get(t0), None);
        assert_eq!(r.take(t0), None);
    }
}

//! Before a motion: the gate (may it go now, wait behind the one under way, or is it
//! refused), and the bounded queue of motions that wait.

use std::collections::VecDeque;

/// What a backend knows of the controller just before a motion: one status snapshot, read
/// now or seen a moment ago with nothing unasked since.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Snapshot {
    /// The arm has power.
    pub powered: bool,
    /// Every axis is homed.
    pub homed: bool,
    /// The host has the point of control (not the pendant; `true` where the controller has
    /// no such notion).
    pub in_control: bool,
    /// The controller says something moves.
    pub moving: bool,
    /// A motion of TROL's is under way or waits.
    pub ours: bool,
    /// A Home of TROL's is under way or waits: the axes will be homed when a motion queued
    /// now gets its turn (the simulated A465 queues a motion behind a Home so).
    pub homing: bool,
}

/// Why the gate refuses a motion before anything is sent.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refusal {
    /// The arm has no power (the manual's BIOS_ARM_POWER).
    NoPower,
    /// The pendant (or another program) holds the point of control.
    NoControl,
    /// Not every axis is homed, and the motion is not a Home.
    NotHomed,
    /// The arm moves, and not by TROL's doing (a pendant, another program): a motion behind
    /// it would start from a place TROL does not know.
    Busy,
}

impl Refusal {
    /// What to tell the log, and what to do.
    pub fn text(self) -> &'static str {
        match self {
            Refusal::NoPower => {
                "refused before sending: the arm has no power: restore arm power at the controller"
            }
            Refusal::NoControl => {
                "refused before sending: the pendant holds the point of control: give it back \
                 to the host at the pendant"
            }
            Refusal::NotHomed => {
                "refused before sending: the arm is not homed: call TROLHome(0) (with the arm \
                 near its home position)"
            }
            Refusal::Busy => {
                "refused before sending: the arm moves, and not by a motion of TROL's (the \
                 pendant, another program): wait until it stands"
            }
        }
    }
}

/// What the gate lets a motion do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Gate {
    /// Refused before anything was sent.
    Refuse(Refusal),
    /// The arm stands: send it now.
    Send,
    /// A motion of TROL's runs or waits: the new one waits behind it.
    Queue,
}

/// The gate before a motion (`homes`: the motion is a Home, which needs no homing).
pub fn gate(s: &Snapshot, homes: bool) -> Gate {
    if !s.powered {
        Gate::Refuse(Refusal::NoPower)
    } else if !s.in_control {
        Gate::Refuse(Refusal::NoControl)
    } else if !homes && !s.homed && !s.homing {
        Gate::Refuse(Refusal::NotHomed)
    } else if s.ours || s.homing {
        Gate::Queue
    } else if s.moving {
        Gate::Refuse(Refusal::Busy)
    } else {
        Gate::Send
    }
}

/// The motions that wait behind the one under way, at most `cap`. When the one under way
/// fails, what waits is dropped unsent ([`MotionQueue::drop_all`]): a motion planned from
/// where a failed one should have ended would go somewhere nobody asked for.
#[derive(Debug)]
pub struct MotionQueue<T> {
    items: VecDeque<T>,
    cap: usize,
}

impl<T> MotionQueue<T> {
    /// An empty queue for at most `cap` motions.
    pub fn new(cap: usize) -> MotionQueue<T> {
        MotionQueue {
            items: VecDeque::new(),
            cap,
        }
    }

    /// How many motions may wait.
    pub fn cap(&self) -> usize {
        self.cap
    }

    /// Queue `item`; a full queue gives it back (the manual's BIOS_QUEUE_FULL).
    pub fn push(&mut self, item: T) -> Result<(), T> {
        if self.items.len() >= self.cap {
            return Err(item);
        }
        self.items.push_back(item);
        Ok(())
    }

    /// The next motion, when its turn has come.
    pub fn pop(&mut self) -> Option<T> {
        self.items.pop_front()
    }

    /// How many motions wait.
    pub fn len(&self) -> usize {
        self.items.len()
    }

    /// What waits, next first.
    pub fn iter(&self) -> impl Iterator<Item = &T> {
        self.items.iter()
    }

    /// Whether nothing waits.
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// Drop everything that waits, unsent; how many were dropped.
    pub fn drop_all(&mut self) -> usize {
        let n = self.items.len();
        self.items.clear();
        n
    }

    /// What to tell the log when `n` motions were dropped after `what` failed (nothing
    /// where none were).
    pub fn dropped_note(n: usize, what: &str) -> Option<String> {
        (n > 0).then(|| format!("{n} queued motion(s) dropped after {what}: not sent"))
    }

    /// Take what waits aside, leaving the queue empty (to compute one motion from where
    /// the arm stands while the rest waits); put it back with [`MotionQueue::restore`].
    pub fn set_aside(&mut self) -> MotionQueue<T> {
        MotionQueue {
            items: std::mem::take(&mut self.items),
            cap: self.cap,
        }
    }

    /// Put back what [`MotionQueue::set_aside`] took, behind anything queued meanwhile.
    pub fn restore(&mut self, aside: MotionQueue<T>) {
        let mut items = aside.items;
        items.append(&mut self.items);
        self.items = items;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const IDLE: Snapshot = Snapshot {
        powered: true,
        homed: true,
        in_control: true,
        moving: false,
        ours: false,
        homing: false,
    };

    #[test]
    fn the_gate_refuses_what_cannot_go_and_queues_only_behind_trol_s_own() {
        assert_eq!(gate(&IDLE, false), Gate::Send);
        let off = Snapshot {
            powered: false,
            ..IDLE
        };
        assert_eq!(gate(&off, true), Gate::Refuse(Refusal::NoPower));
        let pendant = Snapshot {
            in_control: false,
            ..IDLE
        };
        assert_eq!(gate(&pendant, false), Gate::Refuse(Refusal::NoControl));
        let unhomed = Snapshot {
            homed: false,
            ..IDLE
        };
        assert_eq!(gate(&unhomed, false), Gate::Refuse(Refusal::NotHomed));
        assert_eq!(gate(&unhomed, true), Gate::Send);
        let other = Snapshot {
            moving: true,
            ..IDLE
        };
        assert_eq!(gate(&other, false), Gate::Refuse(Refusal::Busy));
        let ours = Snapshot {
            moving: true,
            ours: true,
            ..IDLE
        };
        assert_eq!(gate(&ours, false), Gate::Queue);
        // Behind a Home of TROL's, a motion waits (the axes will be homed by its turn).
        let homing = Snapshot {
            homing: true,
            homed: false,
            moving: true,
            ..IDLE
        };
        assert_eq!(gate(&homing, false), Gate::Queue);
        // Power is checked first: a queued motion on an arm without power is no motion.
        assert_eq!(
            gate(
                &Snapshot {
                    powered: false,
                    ..ours
                },
                false
            ),
            Gate::Refuse(Refusal::NoPower)
        );
    }

    #[test]
    fn the_queue_is_bounded_and_drops_what_waits_with_a_note() {
        let mut q = MotionQueue::new(2);
        assert_eq!(q.push(1), Ok(()));
        assert_eq!(q.push(2), Ok(()));
        assert_eq!(q.push(3), Err(3));
        let mut aside = q.set_aside();
        assert!(q.is_empty());
        q.push(9).unwrap();
        assert_eq!(aside.pop(), Some(1));
        q.restore(aside);
        assert_eq!(q.len(), 2);
        assert_eq!(q.pop(), Some(2));
        assert_eq!(q.drop_all(), 1);
        assert_eq!(MotionQueue::<u8>::dropped_note(0, "`MOVE T1` failed"), None);
        assert_eq!(
            MotionQueue::<u8>::dropped_note(2, "`MOVE T1` failed").unwrap(),
            "2 queued motion(s) dropped after `MOVE T1` failed: not sent"
        );
    }
}

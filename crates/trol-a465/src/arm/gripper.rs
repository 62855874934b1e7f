//! The simulated gripper and the world it takes objects from: the fingers in time, an object
//! taken where the tool centre point meets it, carried with the tool, and dropped onto the
//! table when the fingers open past it.

use super::*;

/// An object of the simulated world: a point with a width, on the table or in the gripper.
#[derive(Clone, Debug, PartialEq)]
pub struct WorldObject {
    /// Its name (from the objects file).
    pub name: String,
    /// Where it is: x y z, mm (its reference point: the middle of its base).
    pub pos: [f64; 3],
    /// Its width between the fingers, mm.
    pub width: f64,
}

/// An object in the gripper: which one, and where its centre sits in the tool frame.
#[derive(Clone, Copy, Debug)]
pub(super) struct Held {
    pub(super) index: usize,
    pub(super) in_tool: glam::DVec3,
}

/// The centre of an object whose base's middle is at `pos` (where the fingers take it).
fn centre_of(o: &WorldObject) -> glam::DVec3 {
    glam::DVec3::from_array(o.pos) + glam::DVec3::Z * (o.width / 2.0)
}

#[derive(Clone, Copy, Debug)]
pub(super) struct Fingers {
    pub(super) from: f64,
    pub(super) to: f64,
    pub(super) start: f64,
}

impl Fingers {
    pub(super) fn at(&self, t: f64) -> f64 {
        let d = self.to - self.from;
        let dt = (t - self.start).max(0.0);
        // At done_at exactly the end, whatever the rounding of start + d / speed.
        if t >= self.done_at() || d.abs() <= FINGER_SPEED * dt {
            self.to
        } else {
            self.from + d.signum() * FINGER_SPEED * dt
        }
    }

    pub(super) fn done_at(&self) -> f64 {
        self.start + (self.to - self.from).abs() / FINGER_SPEED
    }
}

impl Arm {
    /// The finger distance at `now`, mm.
    pub fn fingers(&self, now: f64) -> f64 {
        self.fingers.at(now)
    }

    /// The fingers to `dist` mm (Grip; full force). Closing stops at an object.
    pub fn grip(&mut self, dist: f64, now: f64) -> i16 {
        self.fingers_to(dist.clamp(0.0, FINGER_MAX), now)
    }

    /// Open the gripper.
    pub fn open(&mut self, _force: f64, now: f64) -> i16 {
        self.fingers_to(FINGER_MAX, now)
    }

    /// Close the gripper (on an object, if there is one).
    pub fn close(&mut self, _force: f64, now: f64) -> i16 {
        self.fingers_to(0.0, now)
    }

    pub(super) fn fingers_to(&mut self, target: f64, now: f64) -> i16 {
        if !self.powered {
            return code::ARM_POWER;
        }
        let from = self.fingers.at(now);
        let q = self.commanded(now);
        let tcp = self.kin.fk(&q);
        // Opening past a held object's width lets it go: it drops onto the table.
        if let Some(h) = self.held {
            let width = self.objects[h.index].width;
            if target >= width {
                let at = tcp.pos + tcp.rot * h.in_tool;
                self.objects[h.index].pos = [at.x, at.y, self.settings.table_z];
                self.held = None;
            }
        }
        // Closing on an object at the tool centre point that is wider than the opening: the
        // fingers are not around it, and they cannot pass through it.
        if self.held.is_none() && target < from {
            let blocked = self
                .objects
                .iter()
                .any(|o| (centre_of(o) - tcp.pos).length() <= GRASP_DISTANCE && from < o.width);
            if blocked {
                return code::GRIPPER_BLOCKED;
            }
        }
        // Closing with an object's centre at the tool centre point takes it: the fingers stop
        // at its width and it moves with the tool from now on.
        if self.held.is_none() {
            let grasped = self.objects.iter().position(|o| {
                let d = (centre_of(o) - tcp.pos).length();
                d <= GRASP_DISTANCE && target < o.width && from >= o.width
            });
            if let Some(index) = grasped {
                let rel = centre_of(&self.objects[index]) - tcp.pos;
                self.held = Some(Held {
                    index,
                    in_tool: tcp.rot.transpose() * rel,
                });
            }
        }
        let stop = match self.held {
            Some(h) => target.max(self.objects[h.index].width),
            None => target,
        };
        self.fingers = Fingers {
            from,
            to: stop,
            start: now,
        };
        // A motion the power cut short is the Finish's news no longer.
        self.cut_short = false;
        code::OK
    }

    /// The objects of the world at `now`: a held one where the tool has carried it.
    pub fn objects(&mut self, now: f64) -> Vec<WorldObject> {
        let mut out = self.objects.clone();
        if let Some(h) = self.held {
            let q = self.commanded(now);
            let tcp = self.kin.fk(&q);
            let centre = tcp.pos + tcp.rot * h.in_tool;
            let half = out[h.index].width / 2.0;
            out[h.index].pos = (centre - glam::DVec3::Z * half).to_array();
        }
        out
    }

    /// The lowest point of what the arm carries with the tool centre point at `tcp`: the tool
    /// centre point, or a held object's underside below it (its centre less half its width).
    pub(super) fn lowest_z(&self, tcp: &Pose) -> f64 {
        match self.held {
            Some(h) => {
                let centre = tcp.pos + tcp.rot * h.in_tool;
                tcp.pos.z.min(centre.z - self.objects[h.index].width / 2.0)
            }
            None => tcp.pos.z,
        }
    }

    /// The name of the object in the gripper, if any.
    pub fn held(&self) -> Option<&str> {
        self.held.map(|h| self.objects[h.index].name.as_str())
    }
}

//! The simulated A465 behind the BIOS interface, on a clock that may run faster than real
//! time.

use std::time::{Duration, Instant};

use trol_a465::arm::{Arm, ArmSettings, Stored, Target, Which};
use trol_a465::model::joints_to_counts;
use trol_proto::application::{FinishMode, LocName, Location, PosMode, Tag};

use crate::bios::Bios;

/// Settings of the simulated controller.
#[derive(Clone, Debug)]
pub struct SimSettings {
    /// The arm's settings (table height, object between the fingers, homed at start).
    pub arm: ArmSettings,
    /// How much faster than real time the simulation runs (1 = real time).
    pub time_scale: f64,
    /// Locations loaded at start.
    pub locations: Vec<(String, Stored)>,
    /// The tool transform at start.
    pub tool: [f64; 6],
}

impl Default for SimSettings {
    fn default() -> Self {
        SimSettings {
            arm: ArmSettings::default(),
            time_scale: 1.0,
            locations: Vec::new(),
            tool: [0.0; 6],
        }
    }
}

/// The simulated A465 as a BIOS.
pub struct SimBios {
    arm: Arm,
    epoch: Instant,
    scale: f64,
}

impl SimBios {
    /// A simulated arm with `settings`.
    pub fn new(settings: SimSettings) -> SimBios {
        let mut arm = Arm::new(settings.arm);
        arm.set_tool(settings.tool);
        for (name, loc) in settings.locations {
            arm.set_location(&name, loc);
        }
        SimBios {
            arm,
            epoch: Instant::now(),
            scale: settings.time_scale.max(1e-3),
        }
    }

    /// Simulation time now, s.
    pub fn now(&self) -> f64 {
        self.epoch.elapsed().as_secs_f64() * self.scale
    }

    /// The arm.
    pub fn arm(&self) -> &Arm {
        &self.arm
    }

    /// The arm, mutably.
    pub fn arm_mut(&mut self) -> &mut Arm {
        &mut self.arm
    }

    fn target(&self, loc: &Location) -> Target {
        match loc {
            Location::Cart(_) => Target::Cart(loc.to_array6()),
            Location::Prec(_) => Target::Prec(loc.to_array6()),
            Location::Joint(_) => Target::Joints(loc.to_array6()),
        }
    }
}

impl Bios for SimBios {
    fn appro(&mut self, target: &Location, disp: [f64; 6], straight: bool) -> i16 {
        let t = self.target(target);
        let now = self.now();
        self.arm.appro(t, disp, straight, now)
    }
    fn close(&mut self, force: u8) -> i16 {
        let now = self.now();
        self.arm.close(force as f64, now)
    }
    fn depart(&mut self, disp: [f64; 6], straight: bool) -> i16 {
        let now = self.now();
        self.arm.depart(disp, straight, now)
    }
    fn finish(&mut self, mode: FinishMode) -> i16 {
        match mode {
            FinishMode::Status => {
                let now = self.now();
                self.arm.finish_status(now)
            }
            FinishMode::Wait => loop {
                let now = self.now();
                let done = self.arm.done_at(now);
                if done <= now {
                    return 0;
                }
                let real = Duration::from_secs_f64(((done - now) / self.scale).min(0.05));
                std::thread::sleep(real.max(Duration::from_micros(100)));
            },
        }
    }
    fn grip(&mut self, dist: u8) -> i16 {
        let now = self.now();
        self.arm.grip(dist as f64, now)
    }
    fn halt(&mut self) -> i16 {
        let now = self.now();
        self.arm.halt(now)
    }
    fn home(&mut self, axis: u8) -> i16 {
        let now = self.now();
        self.arm.home(axis, now)
    }
    fn jog(&mut self, d: [f64; 3], straight: bool) -> i16 {
        let now = self.now();
        self.arm.jog(d, straight, now)
    }
    fn joint(&mut self, joint: u8, radians: f64) -> i16 {
        let now = self.now();
        self.arm.joint(joint, radians, now)
    }
    fn ma(&mut self, q: [f64; 6]) -> i16 {
        let now = self.now();
        self.arm.ma(q, now)
    }
    fn mi(&mut self, dq: [f64; 6]) -> i16 {
        let now = self.now();
        self.arm.mi(dq, now)
    }
    fn move_to(&mut self, target: &Location, straight: bool) -> i16 {
        let t = self.target(target);
        let now = self.now();
        self.arm.move_to(t, straight, now)
    }
    fn open(&mut self, force: u8) -> i16 {
        let now = self.now();
        self.arm.open(force as f64, now)
    }
    fn ready(&mut self) -> i16 {
        let now = self.now();
        self.arm.ready(now)
    }
    fn set_tool(&mut self, tool: [f64; 6]) -> i16 {
        self.arm.set_tool(tool)
    }
    fn speed(&mut self, percent: u8) -> i16 {
        self.arm.set_speed(percent as f64)
    }
    fn position(&mut self, tag: Tag, mode: PosMode) -> Location {
        let now = self.now();
        let which = match mode {
            PosMode::Commanded => Which::Commanded,
            PosMode::Actual => Which::Actual,
        };
        let q = self.arm.position(now, which);
        match tag {
            Tag::Joint => Location::from_array6(Tag::Joint, q),
            Tag::Prec => Location::Prec(joints_to_counts(&q).to_vec()),
            Tag::Cart => Location::from_array6(Tag::Cart, self.arm.kinematics().fk_xyzypr(&q)),
        }
    }
    fn location(&self, name: &LocName) -> Option<Location> {
        self.arm.location(name.as_str()).map(|s| match s {
            Stored::Cart(v) => Location::from_array6(Tag::Cart, v),
            Stored::Prec(c) => Location::Prec(c.to_vec()),
        })
    }
}

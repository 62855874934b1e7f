//! The simulated C500C's gripper: `griptype_set`, `grip_open`, `grip_close`, `grip` and
//! `wgrip`.

use super::*;

impl C500c {
    /// `griptype_set [0|none|1|air|2|servo]`: with no argument, what is set.
    pub(super) fn grip_type_set(&mut self, args: &str) {
        let t = match args {
            "" => {
                let what = match self.grip_type {
                    GripType::Servo => "set to 2--SERVO",
                    GripType::Air => "set to 1--AIR",
                    GripType::None => "not set.",
                };
                self.line(&format!("Gripper type {what}"));
                return;
            }
            "0" | "none" => GripType::None,
            "1" | "air" => GripType::Air,
            "2" | "servo" => GripType::Servo,
            _ => {
                self.line("Gripper type must be 1(air) or 2(servo)");
                return;
            }
        };
        self.grip_type = t;
    }

    /// A grip command; true when its prompt waits for the jaws.
    pub(super) fn gripper(&mut self, word: &str, args: &str) -> bool {
        if self.pendant {
            self.error(
                "Ash doesn't have control. Transfer control back by pressing <SHIFT><ESC> on \
                 the pendant keyboard.",
            );
            return false;
        }
        if self.grip_type == GripType::None {
            // Assumed: ash's words for a gripper that is not set are not public.
            self.line("Gripper type not set.");
            return false;
        }
        if !self.power {
            self.error("Arm power is OFF");
            return false;
        }
        let t = self.now();
        let value = if args.is_empty() {
            None
        } else {
            match args.parse::<f64>() {
                Ok(v) if v.is_finite() && v >= 0.0 => Some(v),
                _ => {
                    self.line("error: missing number.");
                    return false;
                }
            }
        };
        match (word, value) {
            ("grip" | "gripdist_set", None) => {
                self.line("error: missing value(s).");
                return false;
            }
            ("grip" | "gripdist_set", Some(_)) if self.grip_type == GripType::Air => {
                self.line("Gripper type must be 2(servo)");
                return false;
            }
            ("grip" | "gripdist_set", Some(d)) => {
                self.arm.grip(d, t);
            }
            ("grip_open" | "gopen" | "go", f) => {
                self.arm.open(f.unwrap_or(100.0), t);
            }
            (_, f) => {
                self.arm.close(f.unwrap_or(100.0), t);
            }
        }
        if self.sw.grip_return == Return::AtEnd && self.jaws_moving() {
            self.busy = true;
            return true;
        }
        false
    }
}

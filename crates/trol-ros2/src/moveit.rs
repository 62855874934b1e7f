//! MoveIt's files for this node, generated from the one model of the arm (`trol ros2
//! --write-config DIR`): the description (URDF, SRDF), the joint limits MoveIt plans within,
//! its kinematics and controllers files, and a launch file for `move_group` that uses them.
//!
//! The limits are TROL's own, so that a trajectory MoveIt times within them is not refused
//! as BIOS_TOO_FAST: the arm's top speeds and accelerations (trol-a465's model at 100 %)
//! times [`SPEED_SHARE`] and [`ACCEL_SHARE`]. TROL runs a trajectory as a C1 cubic spline
//! through its points at their times, and such a spline through a MoveIt trajectory's
//! samples goes faster, and accelerates harder, than the samples do between them (at the
//! corners of a trapezoidal profile most); the shares leave room for that, and a test times
//! random trajectories as MoveIt's planners do and sends them to the simulated arm.

use std::fmt::Write as _;
use std::path::Path;

/// The share of the arm's top joint speeds MoveIt is given.
pub const SPEED_SHARE: f64 = 0.9;
/// The share of the arm's top joint accelerations MoveIt is given (the issue that asked for
/// these files measured refusals from about 65 % of them with a planner's own timing).
pub const ACCEL_SHARE: f64 = 0.35;

/// The velocity and acceleration limits written to `joint_limits.yaml`, per joint.
pub fn limits() -> ([f64; 6], [f64; 6]) {
    let (v, a) = trol_a465::arm::joint_limits(100.0);
    (v.map(|x| x * SPEED_SHARE), a.map(|x| x * ACCEL_SHARE))
}

/// The files, by name, for a node with `joints` (its `--prefix`) serving its action under
/// `ns` (`/` or `/arm1`), with the description `urdf` and `srdf` already prefixed.
pub fn files(joints: &[String; 6], ns: &str, urdf: &str, srdf: &str) -> Vec<(String, String)> {
    let (v, a) = limits();
    let mut limits_yaml = String::from(
        "# The joint limits MoveIt plans within: TROL's own (trol-a465's model), with room for\n\
         # the spline TROL runs through a trajectory's points (crates/trol-ros2/src/moveit.rs).\n\
         joint_limits:\n",
    );
    for (i, j) in joints.iter().enumerate() {
        let _ = write!(
            limits_yaml,
            "  {j}:\n    has_velocity_limits: true\n    max_velocity: {:.6}\n    \
             has_acceleration_limits: true\n    max_acceleration: {:.6}\n",
            v[i], a[i]
        );
    }
    let kinematics =
        "# KDL for the group `arm` (the A465's IK is analytic; KDL is MoveIt's default).\n\
         arm:\n  kinematics_solver: kdl_kinematics_plugin/KDLKinematicsPlugin\n  \
         kinematics_solver_search_resolution: 0.005\n  kinematics_solver_timeout: 0.05\n"
            .to_string();
    // moveit_simple_controller_manager finds a controller's action at `<name>/<action_ns>`,
    // or at `<name>` where action_ns is empty, relative to move_group's namespace: move_group
    // runs in the node's namespace, and each controller is named after the node's action.
    let mut controllers = String::from(
        "# moveit_simple_controller_manager on `trol ros2`'s actions; move_group runs in the\n\
         # node's namespace, so each controller's name is the node's action.\n\
         moveit_controller_manager: moveit_simple_controller_manager/MoveItSimpleControllerManager\n\
         moveit_simple_controller_manager:\n  controller_names: [follow_joint_trajectory, gripper_cmd]\n  \
         follow_joint_trajectory:\n    type: FollowJointTrajectory\n    action_ns: \"\"\n    \
         default: true\n    joints:\n",
    );
    for j in joints {
        let _ = writeln!(controllers, "      - {j}");
    }
    let gripper_joint = joints[0].replace("joint_1", "gripper_joint");
    let _ = write!(
        controllers,
        "  gripper_cmd:\n    type: GripperCommand\n    action_ns: \"\"\n    default: true\n    \
         joints:\n      - {gripper_joint}\n"
    );
    let namespace = ns.trim_matches('/');
    let launch = format!(
        "\"\"\"move_group for the CRS A465 on `trol ros2` (written by `trol ros2 --write-config`).\n\n\
         Start `trol ros2` with the same --namespace and --prefix on the machine with the arm's\n\
         line; this starts MoveIt's move_group, in the node's namespace, with the files beside it.\n\"\"\"\n\n\
         import os\n\n\
         import yaml\n\
         from launch import LaunchDescription\n\
         from launch_ros.actions import Node\n\n\
         HERE = os.path.dirname(os.path.abspath(__file__))\n\n\n\
         def text(name):\n    with open(os.path.join(HERE, name)) as f:\n        return f.read()\n\n\n\
         def data(name):\n    return yaml.safe_load(text(name))\n\n\n\
         def generate_launch_description():\n    \
         params = {{\n        \
         \"robot_description\": text(\"crs_a465.urdf\"),\n        \
         \"robot_description_semantic\": text(\"crs_a465.srdf\"),\n        \
         \"robot_description_kinematics\": data(\"kinematics.yaml\"),\n        \
         \"robot_description_planning\": data(\"joint_limits.yaml\"),\n        \
         **data(\"moveit_controllers.yaml\"),\n    }}\n    \
         # In the node's namespace: joint_states and the controllers' actions are the node's.\n    \
         return LaunchDescription([\n        \
         Node(package=\"moveit_ros_move_group\", executable=\"move_group\", output=\"screen\",\n             \
         namespace=\"{namespace}\", parameters=[params]),\n    ])\n"
    );
    vec![
        ("crs_a465.urdf".into(), urdf.to_string()),
        ("crs_a465.srdf".into(), srdf.to_string()),
        ("joint_limits.yaml".into(), limits_yaml),
        ("kinematics.yaml".into(), kinematics),
        ("moveit_controllers.yaml".into(), controllers),
        ("move_group.launch.py".into(), launch),
    ]
}

/// Write [`files`] into `dir` (made if missing).
pub fn write(dir: &Path, files: &[(String, String)]) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot make {}: {e}", dir.display()))?;
    for (name, body) in files {
        let path = dir.join(name);
        std::fs::write(&path, body).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use trol_a465::arm::{Arm, ArmSettings};

    /// A trajectory as MoveIt's planners time a joint-space line: every joint on a
    /// trapezoidal profile within `v` and `a`, all arriving together (the slowest joint sets
    /// the time), sampled every `dt` s, from `from` to `to`.
    fn timed_line(
        from: [f64; 6],
        to: [f64; 6],
        v: [f64; 6],
        a: [f64; 6],
        dt: f64,
    ) -> Vec<(f64, [f64; 6])> {
        // The path parameter s runs 0..1 on one trapezoid whose rate and acceleration keep
        // every joint within its own limits (joint i moves d_i * s).
        let d: [f64; 6] = std::array::from_fn(|i| (to[i] - from[i]).abs());
        let sv = (0..6)
            .filter(|&i| d[i] > 0.0)
            .map(|i| v[i] / d[i])
            .fold(f64::INFINITY, f64::min);
        let sa = (0..6)
            .filter(|&i| d[i] > 0.0)
            .map(|i| a[i] / d[i])
            .fold(f64::INFINITY, f64::min);
        // Reaching the top rate takes sv / sa and covers sv² / sa of s; short lines never do.
        let (ramp, total) = if sv * sv / sa >= 1.0 {
            let r = (1.0 / sa).sqrt();
            (r, 2.0 * r)
        } else {
            (sv / sa, 1.0 / sv + sv / sa)
        };
        let peak = sa * ramp;
        let s = |t: f64| {
            if t < ramp {
                0.5 * sa * t * t
            } else if t > total - ramp {
                let r = total - t;
                1.0 - 0.5 * sa * r * r
            } else {
                0.5 * sa * ramp * ramp + peak * (t - ramp)
            }
        };
        let steps = (total / dt).ceil() as usize;
        (1..=steps)
            .map(|k| {
                let t = (k as f64 * dt).min(total);
                let f = s(t).clamp(0.0, 1.0);
                (t, std::array::from_fn(|i| from[i] + f * (to[i] - from[i])))
            })
            .collect()
    }

    /// A small deterministic generator (xorshift): the test's trajectories are the same on
    /// every run.
    struct Rng(u64);
    impl Rng {
        fn unit(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    #[test]
    fn a_trajectory_timed_within_joint_limits_yaml_is_never_refused_as_too_fast() {
        let (v, a) = limits();
        let lim = trol_a465::model::LIMITS_RAD;
        let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
        let mut tried = 0;
        for trial in 0..1000 {
            // Within 80 % of each joint's range, away from the table: the elbow up.
            let pose = |r: &mut Rng| -> [f64; 6] {
                std::array::from_fn(|i| {
                    let x = (r.unit() * 2.0 - 1.0) * 0.8 * lim[i];
                    if i == 1 {
                        x.clamp(-0.8, 0.3)
                    } else if i == 2 {
                        x.clamp(0.3, 1.6)
                    } else {
                        x
                    }
                })
            };
            let (from, to) = (pose(&mut rng), pose(&mut rng));
            let dt = [0.05, 0.1, 0.2][trial % 3];
            let mut arm = Arm::new(ArmSettings {
                homed: true,
                ..Default::default()
            });
            // To the start first (a plain joint move), then the line from there.
            assert_eq!(arm.ma(from, 0.0), 0, "trial {trial}: the start {from:?}");
            // The trajectory starts where the move before it ends.
            let points = timed_line(from, to, v, a, dt);
            let c = arm.trajectory(&points, 0.0);
            if c == trol_a465::arm::code::BELOW_TABLE {
                continue;
            }
            assert_eq!(
                c,
                0,
                "trial {trial} (every {dt} s, {} points from {from:?} to {to:?}): {:?}",
                points.len(),
                arm.take_refusal()
            );
            tried += 1;
        }
        assert!(tried >= 750, "only {tried} trials reached the arm");
    }
}

//! The ROS 2 messages the node speaks, field for field as ROS 2's own definitions give them
//! (CDR encodes a struct's fields in order, so the order here is the wire's):
//!
//! - builtin_interfaces/msg/Time: `int32 sec`, `uint32 nanosec`;
//! - std_msgs/msg/Header: `builtin_interfaces/Time stamp`, `string frame_id`;
//! - sensor_msgs/msg/JointState: `std_msgs/Header header`, `string[] name`,
//!   `float64[] position`, `float64[] velocity`, `float64[] effort`;
//! - std_msgs/msg/String: `string data`;
//! - std_srvs/srv/Trigger: an empty request (which ROS 2's IDL gives the one member
//!   `uint8 structure_needs_at_least_one_member`), and `bool success`, `string message`.

use ros2_client::Message;
use serde::{Deserialize, Serialize};

/// builtin_interfaces/msg/Time.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Time {
    /// Seconds since the Unix epoch.
    pub sec: i32,
    /// Nanoseconds within the second.
    pub nanosec: u32,
}

impl Time {
    /// Now, by the system clock (what ROS 2 stamps with when it does not simulate time).
    pub fn now() -> Time {
        let d = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap_or_default();
        Time {
            sec: i32::try_from(d.as_secs()).unwrap_or(i32::MAX),
            nanosec: d.subsec_nanos(),
        }
    }
}

/// std_msgs/msg/Header.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// When the data was taken.
    pub stamp: Time,
    /// The frame it is in ("" for joint states).
    pub frame_id: String,
}

/// sensor_msgs/msg/JointState.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct JointState {
    /// The stamp of the reading.
    pub header: Header,
    /// The joints' names, as the URDF has them.
    pub name: Vec<String>,
    /// Radians.
    pub position: Vec<f64>,
    /// Radians per second.
    pub velocity: Vec<f64>,
    /// Not measured: empty, as ROS 2 allows.
    pub effort: Vec<f64>,
}

impl Message for JointState {}

/// std_srvs/srv/Trigger's request.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TriggerRequest {
    /// The member ROS 2's IDL gives an empty structure.
    pub structure_needs_at_least_one_member: u8,
}

impl Message for TriggerRequest {}

/// std_srvs/srv/Trigger's response.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TriggerResponse {
    /// Whether it was done.
    pub success: bool,
    /// What happened, in words (on failure: the TROL code's name and what to do).
    pub message: String,
}

impl Message for TriggerResponse {}

// ---- control_msgs/action/FollowJointTrajectory (Humble and Jazzy, control_msgs 4.x/5.x) ----
//
// trajectory_msgs/JointTrajectoryPoint: `float64[] positions`, `float64[] velocities`,
// `float64[] accelerations`, `float64[] effort`, `builtin_interfaces/Duration
// time_from_start`; trajectory_msgs/JointTrajectory: `std_msgs/Header header`, `string[]
// joint_names`, `JointTrajectoryPoint[] points`; trajectory_msgs/MultiDOFJointTrajectory(Point)
// with geometry_msgs Transform (Vector3 translation, Quaternion rotation) and Twist (Vector3
// linear, Vector3 angular); control_msgs/JointTolerance: `string name`, `float64 position`,
// `float64 velocity`, `float64 acceleration`; control_msgs/JointComponentTolerance: `string
// joint_name`, `uint16 component`, and the same three; the action's goal, result and feedback
// as control_msgs/action/FollowJointTrajectory.action has them.

/// builtin_interfaces/msg/Duration.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Duration {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds within the second.
    pub nanosec: u32,
}

impl Duration {
    /// In seconds.
    pub fn seconds(self) -> f64 {
        f64::from(self.sec) + f64::from(self.nanosec) * 1e-9
    }

    /// From seconds (0 for what is not a finite non-negative number).
    pub fn from_seconds(s: f64) -> Duration {
        if !(s.is_finite() && s >= 0.0) {
            return Duration::default();
        }
        let sec = s.floor();
        Duration {
            sec: sec.min(f64::from(i32::MAX)) as i32,
            nanosec: (((s - sec) * 1e9).round() as u32).min(999_999_999),
        }
    }
}

/// trajectory_msgs/msg/JointTrajectoryPoint.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct JointTrajectoryPoint {
    /// Radians, in the order of the trajectory's joint names.
    pub positions: Vec<f64>,
    /// Radians per second (empty or one per joint).
    pub velocities: Vec<f64>,
    /// Radians per second squared (empty or one per joint).
    pub accelerations: Vec<f64>,
    /// Not used by this arm.
    pub effort: Vec<f64>,
    /// When, from the trajectory's start.
    pub time_from_start: Duration,
}

/// trajectory_msgs/msg/JointTrajectory.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct JointTrajectory {
    /// Its stamp (the start; zero: now).
    pub header: Header,
    /// The joints, in the order of every point's values.
    pub joint_names: Vec<String>,
    /// The waypoints.
    pub points: Vec<JointTrajectoryPoint>,
}

/// geometry_msgs/msg/Vector3.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Vector3 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

/// geometry_msgs/msg/Quaternion.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

/// geometry_msgs/msg/Transform.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Transform {
    /// Translation.
    pub translation: Vector3,
    /// Rotation.
    pub rotation: Quaternion,
}

/// geometry_msgs/msg/Twist.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Twist {
    /// Linear.
    pub linear: Vector3,
    /// Angular.
    pub angular: Vector3,
}

/// trajectory_msgs/msg/MultiDOFJointTrajectoryPoint.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MultiDofJointTrajectoryPoint {
    /// Transforms.
    pub transforms: Vec<Transform>,
    /// Velocities.
    pub velocities: Vec<Twist>,
    /// Accelerations.
    pub accelerations: Vec<Twist>,
    /// When.
    pub time_from_start: Duration,
}

/// trajectory_msgs/msg/MultiDOFJointTrajectory (an A465 has none: must be empty).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MultiDofJointTrajectory {
    /// Header.
    pub header: Header,
    /// Joint names.
    pub joint_names: Vec<String>,
    /// Points.
    pub points: Vec<MultiDofJointTrajectoryPoint>,
}

/// control_msgs/msg/JointTolerance (0: the default; -1: none).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct JointTolerance {
    /// The joint.
    pub name: String,
    /// Radians.
    pub position: f64,
    /// Radians per second (not checked here).
    pub velocity: f64,
    /// Radians per second squared (not checked here).
    pub acceleration: f64,
}

/// control_msgs/msg/JointComponentTolerance (for multi-DOF joints: must be empty here).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct JointComponentTolerance {
    /// The joint.
    pub joint_name: String,
    /// X_AXIS 1 .. ROTATION 5.
    pub component: u16,
    /// Position.
    pub position: f64,
    /// Velocity.
    pub velocity: f64,
    /// Acceleration.
    pub acceleration: f64,
}

/// FollowJointTrajectory's goal.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FollowGoal {
    /// The trajectory.
    pub trajectory: JointTrajectory,
    /// Must be empty for this arm.
    pub multi_dof_trajectory: MultiDofJointTrajectory,
    /// Allowed error along the way.
    pub path_tolerance: Vec<JointTolerance>,
    /// Must be empty for this arm.
    pub component_path_tolerance: Vec<JointComponentTolerance>,
    /// Allowed error at the end.
    pub goal_tolerance: Vec<JointTolerance>,
    /// Must be empty for this arm.
    pub component_goal_tolerance: Vec<JointComponentTolerance>,
    /// How late the end may be (0: not checked).
    pub goal_time_tolerance: Duration,
}

impl ros2_client::Message for FollowGoal {}

/// FollowJointTrajectory's error codes.
pub mod follow_code {
    /// SUCCESSFUL.
    pub const SUCCESSFUL: i32 = 0;
    /// INVALID_GOAL.
    pub const INVALID_GOAL: i32 = -1;
    /// INVALID_JOINTS.
    pub const INVALID_JOINTS: i32 = -2;
    /// PATH_TOLERANCE_VIOLATED.
    pub const PATH_TOLERANCE_VIOLATED: i32 = -4;
    /// GOAL_TOLERANCE_VIOLATED.
    pub const GOAL_TOLERANCE_VIOLATED: i32 = -5;
}

/// FollowJointTrajectory's result.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FollowResult {
    /// One of [`follow_code`].
    pub error_code: i32,
    /// What happened, in words.
    pub error_string: String,
}

impl ros2_client::Message for FollowResult {}

/// FollowJointTrajectory's feedback, in either of control_msgs's layouts: Humble's and
/// Jazzy's (control_msgs 4 and 5), or Kilted's and Rolling's (6.3 on), which add `int32
/// index` after `error` and `int32 multi_dof_index` at the end. CDR has no field names, so a
/// peer of the other layout cannot read it at all: the node sends its distribution's
/// (`--distro`).
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
pub struct FollowFeedback {
    /// When.
    pub header: Header,
    /// The joints, in the goal's order.
    pub joint_names: Vec<String>,
    /// Where the arm should be now.
    pub desired: JointTrajectoryPoint,
    /// Where it is.
    pub actual: JointTrajectoryPoint,
    /// actual - desired.
    pub error: JointTrajectoryPoint,
    /// Kilted on: the trajectory's point in use (the first not yet due).
    #[serde(skip)]
    pub index: i32,
    /// Empty.
    pub multi_dof_joint_names: Vec<String>,
    /// Empty.
    pub multi_dof_desired: MultiDofJointTrajectoryPoint,
    /// Empty.
    pub multi_dof_actual: MultiDofJointTrajectoryPoint,
    /// Empty.
    pub multi_dof_error: MultiDofJointTrajectoryPoint,
    /// Kilted on: the multi-DOF point in use (0: this arm has none).
    #[serde(skip)]
    pub multi_dof_index: i32,
    /// Whether to send Kilted's layout (with the two indices).
    #[serde(skip)]
    pub kilted: bool,
}

impl Serialize for FollowFeedback {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let mut st = s.serialize_struct("FollowFeedback", if self.kilted { 11 } else { 9 })?;
        st.serialize_field("header", &self.header)?;
        st.serialize_field("joint_names", &self.joint_names)?;
        st.serialize_field("desired", &self.desired)?;
        st.serialize_field("actual", &self.actual)?;
        st.serialize_field("error", &self.error)?;
        if self.kilted {
            st.serialize_field("index", &self.index)?;
        }
        st.serialize_field("multi_dof_joint_names", &self.multi_dof_joint_names)?;
        st.serialize_field("multi_dof_desired", &self.multi_dof_desired)?;
        st.serialize_field("multi_dof_actual", &self.multi_dof_actual)?;
        st.serialize_field("multi_dof_error", &self.multi_dof_error)?;
        if self.kilted {
            st.serialize_field("multi_dof_index", &self.multi_dof_index)?;
        }
        st.end()
    }
}

impl ros2_client::Message for FollowFeedback {}

// ---- control_msgs/action/GripperCommand: `GripperCommand command` (control_msgs/msg/
// GripperCommand: `float64 position`, `float64 max_effort`); result and feedback alike:
// `float64 position`, `float64 effort`, `bool stalled`, `bool reached_goal`. ----

/// control_msgs/msg/GripperCommand.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct GripperCommand {
    /// The gap between the fingers, m.
    pub position: f64,
    /// The most force, N (the A465's gripper grips at its own force: not used).
    pub max_effort: f64,
}

/// GripperCommand's goal.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct GripperGoal {
    /// What to do.
    pub command: GripperCommand,
}

impl ros2_client::Message for GripperGoal {}

/// GripperCommand's result (and its feedback, which has the same fields).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct GripperResult {
    /// The gap, m.
    pub position: f64,
    /// Not measured: 0.
    pub effort: f64,
    /// The fingers stopped on an object short of the gap.
    pub stalled: bool,
    /// The fingers stand at the gap.
    pub reached_goal: bool,
}

impl ros2_client::Message for GripperResult {}

/// GripperCommand's feedback: the result's fields.
pub type GripperFeedback = GripperResult;

#[cfg(test)]
mod layout_tests {
    use super::*;

    #[test]
    fn kilted_s_feedback_has_the_two_indices_where_control_msgs_6_3_put_them() {
        let jazzy = FollowFeedback {
            index: 3,
            ..Default::default()
        };
        let kilted = FollowFeedback {
            kilted: true,
            ..jazzy.clone()
        };
        let cdr = |f: &FollowFeedback| {
            rustdds::cdr_encoding::to_vec::<FollowFeedback, byteorder::LittleEndian>(f).unwrap()
        };
        let (a, b) = (cdr(&jazzy), cdr(&kilted));
        assert_eq!(b.len(), a.len() + 8, "two int32 more");
        // Up to `error` the same bytes; then Kilted's index.
        let at = prefix_len(&a, &b);
        assert_eq!(&b[at..at + 4], &3i32.to_le_bytes());
        assert_eq!(&b[b.len() - 4..], &0i32.to_le_bytes());
    }

    /// How many leading bytes two encodings share.
    fn prefix_len(a: &[u8], b: &[u8]) -> usize {
        a.iter().zip(b).take_while(|(x, y)| x == y).count()
    }
}

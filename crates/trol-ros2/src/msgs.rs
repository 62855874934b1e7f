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

//! What the node says, on stderr and on ROS 2's `/rosout` (rcl_interfaces/Log, as every
//! ROS 2 node logs), so `ros2 topic echo /rosout` and rqt_console show it with the node's name.

use std::sync::OnceLock;

use ros2_client::{Node, NodeLoggingHandle, RosoutRaw};

pub use ros2_client::log::LogLevel;

/// The node's `/rosout` writer, once the node exists.
static ROSOUT: OnceLock<NodeLoggingHandle> = OnceLock::new();

/// Log to `/rosout` from now on as `node`.
pub fn attach(node: &Node) {
    let _ = ROSOUT.set(node.logging_handle());
}

/// Say `text` on stderr, and on `/rosout` at `level` once attached (without the program's
/// name, which the log's `name` carries).
pub fn said(level: LogLevel, text: &str) {
    trol_cli::tell!("{text}");
    to_rosout(level, text);
}

/// The node's news (its first line: what it serves) on stdout, and on `/rosout` as info.
pub fn info(text: &str) {
    trol_cli::say!("{text}");
    to_rosout(LogLevel::Info, text);
}

fn to_rosout(level: LogLevel, text: &str) {
    if let Some(h) = ROSOUT.get() {
        let msg = text.strip_prefix("trol-ros2: ").unwrap_or(text);
        h.rosout_raw(
            ros2_client::builtin_interfaces::Time::now(),
            level,
            h.base_name(),
            msg,
            file!(),
            "",
            line!(),
        );
    }
}

/// A warning on stderr and `/rosout` (`format!`'s arguments).
#[macro_export]
macro_rules! warn_ros {
    ($($arg:tt)+) => {
        $crate::rosout::said($crate::rosout::LogLevel::Warn, &format!($($arg)+))
    };
}

//! The CRS A465: its kinematic model, closed-form inverse kinematics, and a simulation of
//! the arm in time behind the C500's BIOS.
//!
//! - [`model`]: link lengths, limits, speeds, encoders, the READY pose;
//! - [`kinematics`]: forward kinematics and all-solutions inverse kinematics with a tool
//!   transform; usable on the PC as well as in the simulated controller;
//! - [`arm`]: the simulated arm (timed motion, gripper, location table, safety checks);
//! - [`survey`]: a survey of straight lines (`trol bench lines`);
//! - [`urdf`]: the arm as a URDF with TROL's joints (`trol urdf`, docs/ros2.md).
//!
//! Conventions, and which figures are published and which are assumptions: docs/a465.md in
//! TROL's repository.
//!
//! The kinematics on the PC:
//!
//! ```rust
//! use trol_a465::{Kinematics, Pose};
//!
//! let kin = Kinematics::new([0.0, 0.0, 0.0, 0.0, 0.0, 0.0]); // no tool transform
//! // Tool straight down, 400 mm in front of the robot, 150 mm above the table.
//! let tcp = Pose::from_xyzypr([400.0, 0.0, 150.0, 0.0, std::f64::consts::FRAC_PI_2, 0.0]);
//! for s in kin.ik_all(&tcp, &[0.0; 6]).as_slice() {
//!     println!("{} {:?} within limits: {}", s.config, s.q, s.within_limits);
//! }
//! let q = kin.ik_nearest(&tcp, &[0.0; 6]).expect("reachable");
//! assert!((kin.fk(&q).pos - tcp.pos).length() < 1e-6);
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs, missing_debug_implementations)]

pub mod arm;
#[cfg(feature = "backend")]
pub mod backend;
pub mod kinematics;
pub mod model;
pub mod motion;
pub mod survey;
pub mod urdf;

pub use kinematics::{Config, IkError, Joints, Kinematics, Pose, Solution, Solutions};

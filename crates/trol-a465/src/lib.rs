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
//! Conventions and which figures are assumptions: docs/a465.md, included below (its
//! example runs as a doctest).
//!
#![doc = include_str!("../../../docs/a465.md")]
#![forbid(unsafe_code)]
#![warn(missing_docs, missing_debug_implementations)]

pub mod arm;
pub mod kinematics;
pub mod model;
pub mod motion;
pub mod survey;
pub mod urdf;

pub use kinematics::{Config, IkError, Joints, Kinematics, Pose, Solution, Solutions};

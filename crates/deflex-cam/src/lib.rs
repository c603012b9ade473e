//! # deflex-cam
//!
//! CAM for a robot: G-code in ([`gcode`]), robot programs out ([`program`]), a calibrated robot
//! out where controllers and ROS stacks read it ([`export`]).

#![warn(missing_docs)]

pub mod export;
pub mod gcode;
pub mod program;

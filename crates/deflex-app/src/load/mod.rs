//! # The user's files
//!
//! The layers below read no file: they parse text and return typed values. This module opens the
//! files a user names and hands their text to those parsers, every read bounded in size:
//!
//! * [`robot_file`]: a robot by built-in name or TOML path, with the URDF it names resolved next to
//!   it ([`load_robot`]), and writing a robot's TOML for another folder
//!   ([`robot_to_toml_for`]);
//! * [`measurements`]: measurement, plan and point files ([`read_file`], [`read_points`]);
//! * [`wrench_log`]: a previous run's log (`deflex run`, `deflex sim isf`) as the compensation's
//!   wrench source ([`read_wrench_log`]);
//! * [`gcode_file`]: G-code files as the twin's tool paths ([`gcode_file::read_gcode`]) and the
//!   built-in paths or a G-code file by name ([`gcode_file::tool_path_by_name`]);
//!
//! Every read is [`deflex_files::read_bounded`] (only a regular file, its size counted while
//! reading); a reader's error holds the shared [`deflex_files::FileIoError`] and
//! [`deflex_files::FileTooLarge`], the latter naming what the file is
//! ([`deflex_files::InputError::reported_as`]). (The twin's cell files are read by
//! [`crate::cell::twin_cell_file`].)

#![warn(missing_docs)]

pub mod gcode_file;
pub mod measurements;
pub mod robot_file;
pub mod wrench_log;

pub use measurements::{
    read_file, read_file_ignoring, read_for_robot, read_measurements, read_plan, read_points,
};
pub use robot_file::{
    FileUrdfResolver, MAX_ROBOT_FILE_BYTES, RobotFileError, load_robot, robot_from_toml_file,
    robot_to_toml_for,
};
pub use wrench_log::{WrenchLogError, parse_wrench_log, read_wrench_log};

//! # deflex-load
//!
//! The maths crates read no file: they parse text and return typed values. This crate opens the
//! files a user names and hands their text to those parsers, every read bounded in size:
//!
//! * [`robot_file`]: a robot by built-in name or TOML path, with the URDF it names resolved next to
//!   it ([`load_robot`]), and writing a robot's TOML for another folder
//!   ([`robot_to_toml_for`]);
//! * [`measurements`]: measurement, plan and point files ([`read_file`], [`read_points`]);
//! * [`read_bounded`]: any text file, read only when it is not larger than a limit.
//!
//! (The twin's cell files are read by `deflex-twin`, above the twin.)

#![warn(missing_docs)]

pub mod measurements;
pub mod robot_file;

pub use measurements::{read_file, read_for_robot, read_measurements, read_plan, read_points};
pub use robot_file::{
    FileUrdfResolver, MAX_ROBOT_FILE_BYTES, load_robot, robot_from_toml_file, robot_to_toml_for,
};

use std::path::Path;

/// Why a bounded read failed.
#[derive(Debug)]
pub enum BoundedReadError {
    /// The operating system's error.
    Io(std::io::Error),
    /// The file has this many bytes, more than allowed.
    TooLarge(u64),
}

/// The text of `path` when it has at most `limit` bytes.
pub fn read_bounded(path: &Path, limit: u64) -> Result<String, BoundedReadError> {
    let size = std::fs::metadata(path).map_err(BoundedReadError::Io)?.len();
    if size > limit {
        return Err(BoundedReadError::TooLarge(size));
    }
    std::fs::read_to_string(path).map_err(BoundedReadError::Io)
}

#[cfg(test)]
mod tests;

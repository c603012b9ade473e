//! The `deflex sim isf` log (`log.csv` of a twin run, SIMULATED) as its readers find it: the
//! names of the columns they read, with their units (the twin writes it:
//! `deflex_sim::FormingLog::to_csv`, 50 Hz, a `# SIMULATED` first line). Read with the one log
//! reader, [`crate::log_reader::LogReader`].
//!
//! It is a format of its own, not a variant of the run log ([`crate::run_log`]): it is the
//! forming process seen by the twin, not the controller's cycle. Its positions are in the part
//! frame in millimetres, its wrench is the contact's in part-frame axes, and most of it is
//! ground truth no real cell has (the true TCP, the path error, the sheet's penetration and
//! flow level), at the twin's logging rate rather than one row per control cycle; the run log
//! is the controller's state in the robot's base axes in SI units, one row per cycle, what a
//! real cell records. A reader that takes both (`deflex plot`, the compensation's
//! `--wrench log:FILE`) tells them apart by their columns.

/// Time since the start of the run (s).
pub const TIME: &str = "time_s";
/// Desired TCP, part frame (mm).
pub const DESIRED_MM: [&str; 3] = ["des_x_mm", "des_y_mm", "des_z_mm"];
/// Commanded TCP, part frame (mm); optional for a reader (older logs lack it).
pub const COMMANDED_MM: [&str; 3] = ["cmd_x_mm", "cmd_y_mm", "cmd_z_mm"];
/// The TCP measured by the simulated laser tracker, part frame (mm); optional for a reader.
pub const TRACKED_MM: [&str; 3] = ["tracked_x_mm", "tracked_y_mm", "tracked_z_mm"];
/// Path error, true − desired TCP, part frame (mm).
pub const ERROR_MM: [&str; 3] = ["err_x_mm", "err_y_mm", "err_z_mm"];
/// Wrench on the tool at the TCP, part-frame axes (N, N·m).
pub const WRENCH: [&str; 6] = ["fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm"];
/// The controller's correction ξ, position part, part-frame axes (mm).
pub const CORRECTION_MM: [&str; 3] = ["corr_x_mm", "corr_y_mm", "corr_z_mm"];
/// The tool's penetration into the sheet (mm; above 0 in contact).
pub const PENETRATION_MM: &str = "penetration_mm";
/// The simulated force sensor saturated (0 or 1); optional for a reader.
pub const SENSOR_SATURATED: &str = "sensor_saturated";

//! deflex-app's tests, through its public API: a module per part of the application layer.

mod calibrate;
mod calibrate_geometry;
mod cell;
mod compensate;
mod error;
mod example_cell;
mod export;
mod load;
mod load_gcode_file;
mod log_law;
mod option_names;
mod report;
mod robot;
mod study;
mod table;
mod twin;
mod twin_runs;
mod wrench_log;

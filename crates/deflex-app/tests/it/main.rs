//! deflex-app's tests, through its public API: a module per part of the application layer.

mod cell;
mod load;
mod load_gcode_file;
mod report;
mod study;
mod twin;
mod wrench_log;

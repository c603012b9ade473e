//! The tests of `deflex_cam::program` (the old `deflex-program`).

mod common;
mod config;
mod fanuc;
mod gcode_offset;
mod inform;
mod names;
mod round_trip;
mod streaming;

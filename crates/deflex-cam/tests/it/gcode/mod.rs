//! The tests of `deflex_cam::gcode` (the old `deflex-gcode`). Its fuzz test is in the facade's
//! `tests/it/fuzz/cam.rs`.

mod arc;
mod corpus;
mod line_reader;
mod refusals;
mod words;

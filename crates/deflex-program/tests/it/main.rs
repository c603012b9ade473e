//! Integration tests of `deflex-program`: one test binary (modules below), so a fresh clone links one
//! executable for this crate instead of one per file.

mod orientation;
mod round_trip;
mod streaming;

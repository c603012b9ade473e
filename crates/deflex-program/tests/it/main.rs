//! deflex-program's tests, through its public API as a user of the crate would call it (one
//! test binary; the library has no test build of its own).

mod comments;
mod config;
mod names;
mod orientation;
mod round_trip;
mod streaming;

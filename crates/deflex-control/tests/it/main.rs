//! Integration tests of `deflex-control` (the control law): one test binary (modules below), so a
//! fresh clone links one executable for this crate instead of one per file, and the library is
//! not compiled a second time in test mode (`[lib] test = false`): the pieces of the law (wrench
//! path, PID, limiter, safety, runaway guard and its loop-gain analysis, feed-forward tracker and
//! table) are tested here through the public API. That a control cycle allocates nothing is
//! checked in the facade's test binary (`no_alloc::control`). The runtime's tests (threads, links, sessions,
//! `CELL.toml`) are `deflex-runtime`'s.

// Six-axis loops index several arrays in lockstep; an index is the clearest form.
#![allow(clippy::needless_range_loop)]

mod common;
mod faults;
mod feedforward;
mod feedforward_tracker;
mod limiter;
mod model_check;
mod pid;
mod runaway;
mod runaway_analysis;
mod runaway_guard;
mod safety;
mod wrench;

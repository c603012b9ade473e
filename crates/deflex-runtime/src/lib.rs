//! # deflex-runtime
//!
//! The real-time runtime around the correction law of `deflex-control`: what `deflex run`
//! needs to drive a robot from a force/torque sensor, and nothing of the law itself.
//!
//! * [`session`]: the robot-link, sensor and control threads ([`spawn`], [`Runtime`]), their
//!   typed messages ([`messages`]: joint samples, wrench accumulations, the correction command
//!   with its rotation and joint map, in sequence cells), the summary and how a session ends;
//! * [`clock`]: injectable time, wall ([`WallClock`]) or simulated ([`SimClock`]);
//! * [`rt`]: SCHED_FIFO and mlockall, best-effort;
//! * [`config`]: `CELL.toml` (serde enums for every choice, bounds and errors naming the field);
//! * [`links`]: the link factory for both sides of a cell (controller and simulated robot);
//! * [`send_shaper`]: the last limiter before the wire, per robot answer;
//! * [`telemetry`]: the stream of one [`deflex_telemetry::CycleSample`] per control cycle,
//!   published without blocking or allocating, read by any number of sinks, the first of which
//!   is the CSV [`log`];
//! * [`feedforward`]: the offline compensation's table read from `compensated_path.csv`;
//! * [`cell_run`]: all of it from a `CELL.toml` ([`CellRun`]);
//! * [`stats`]: cycle-time histograms.
//!
//! Layering: model → control law → io (protocols) → **runtime** → twin → front ends.

#![warn(missing_docs)]
// Six-axis loops index several arrays in lockstep; an index is the clearest form.
#![allow(clippy::needless_range_loop)]

pub mod clock;
pub mod messages;
pub mod rt;
pub mod send_shaper;
pub mod session;
pub mod stats;
pub mod telemetry;

pub use clock::{Clock, SimClock, WallClock};
pub use session::{
    LiveStatus, RunSummary, Runtime, RuntimeOptions, SessionEnd, SessionError, spawn,
};
pub use telemetry::Telemetry;

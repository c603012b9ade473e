//! # deflex-runtime
//!
//! The real-time runtime around the correction law of `deflex-control`: what `deflex run`
//! needs to drive a robot from a force/torque sensor, and nothing of the law itself.
//!
//! * [`session`]: the robot-link, sensor and control threads ([`spawn`], [`Runtime`]), their
//!   typed messages ([`messages`]: joint samples, wrench accumulations, the correction command
//!   with its rotation and joint map, in sequence cells), the summary and how a session ends;
//! * [`clock`]: injectable time, wall ([`WallClock`]) or simulated ([`SimClock`]);
//! * [`rt`]: SCHED_FIFO and mlockall, best-effort, and the interrupt flag of SIGINT/SIGTERM;
//! * [`send_shaper`]: the last limiter before the wire, per robot answer;
//! * [`telemetry`]: the stream of one [`deflex_telemetry::CycleSample`] per control cycle,
//!   published without blocking or allocating, read by any number of sinks (the CSV log and the
//!   MCAP recording of `deflex-record`, the live view, the ROS 2 bridge);
//! * [`stats`]: cycle-time histograms.
//!
//! The runtime takes links that are built and configuration that is parsed, and opens no file:
//! `CELL.toml`, its link factory, the feed-forward table and a whole session from a `CELL.toml`
//! (`CellRun`, the CSV log and the recording subscribed to its telemetry) are the application
//! layer's (`deflex_app::cell`).
//!
//! Layering: model → telemetry → control law → io (protocols) → outlets (record, view, ROS 2)
//! → **runtime** → simulation (twin) → application → front ends.

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

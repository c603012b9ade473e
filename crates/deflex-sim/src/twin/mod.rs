//! # The twin and the controller (`deflex_sim::twin`)
//!
//! The one home of the glue between deflex's controller and its digital twin (`deflex-sim`),
//! every result of which is SIMULATED:
//!
//! * [`closed_loop`]: the correction law in-process in the twin's simulated time
//!   ([`TwinController`] as the twin's `CorrectionController`), what `deflex sim isf
//!   --correction on` and the demo's closed-loop studies run, optionally publishing the same
//!   telemetry as `deflex run`;
//! * [`cell_server`]: the twin served over the protocols of a real cell — the robot controller of
//!   `robot.kind` and an ATI Net F/T on loopback, built by the runtime's robot-side link factory
//!   — so `deflex run` can be tried end to end without hardware (`deflex cell --sim`);
//! * [`sim_time`]: the runtime's own threads (`deflex run`'s code path) against the twin in
//!   simulated time, through in-memory links and a driven clock;
//! * [`twin_stream`]: the twin's own telemetry stream (what the robot reports and the plant's
//!   ground truth, no controller in it) for `cell --sim` and open-loop runs, and the watch of an
//!   in-process run (pace for a live view, stop on Ctrl-C).
//!
//! Layering: model → control law → io → runtime → **twin** → front ends (CLI, demo, report).
//! The twin never hands the plant to the controller: it sees only what hardware would give it.

#![warn(missing_docs)]

pub mod cell_server;
pub mod closed_loop;
pub mod sim_time;
pub mod twin_stream;

pub use closed_loop::{
    ClosedLoopRun, TwinController, TwinProgram, controller_config_for, run_closed_loop,
    run_twin_controller,
};
pub use sim_time::run_runtime_in_sim_time;
pub use twin_stream::{RunWatch, SampleSink, TwinCellStream, twin_cell_session_info};

/// Why a twin run could not be made.
#[derive(Debug, thiserror::Error)]
pub enum TwinError {
    /// The controller refuses its settings.
    #[error(transparent)]
    Controller(#[from] deflex_control::ControlError),
    /// The twin refuses its settings or its path.
    #[error(transparent)]
    Sim(#[from] crate::SimError),
    /// The runtime's threads could not be started.
    #[error("starting the runtime threads: {0}")]
    Threads(std::io::Error),
    /// A runtime thread panicked while it held the twin.
    #[error("the twin's state was lost: a runtime thread panicked while holding it")]
    Poisoned,
}

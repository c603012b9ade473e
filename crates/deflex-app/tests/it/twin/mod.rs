//! Workflows on the twin (SIMULATED): a twin cell from a robot or twin file, the correction
//! controller from an identified model file, the in-process closed loop and its telemetry with a
//! model identified from the twin's campaign, the runtime's threads in simulated time, and
//! `deflex cell --sim` with `deflex run` over loopback for every robot protocol, and the offline
//! compensation from a run's log on plants no built-in cell has.

mod cell_file;
mod cell_server;
mod closed_loop;
pub mod common;
mod fanuc_stream;
mod loopback;
mod sim_time;
mod telemetry;
mod unseen_plant;

/// Real-time loopback sessions sleep most of every robot cycle: the harness runs two at once
/// (its two threads on a 2-core machine) and each still meets its links' timeouts, with every
/// check holding whatever the scheduling (late answers are counted; the tracking comparison
/// applies only when at least 90 % arrived in time). They share this turn.
pub fn session_turn() -> std::sync::RwLockReadGuard<'static, ()> {
    TURN.read().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// The simulated-time runtime's lockstep threads keep both cores busy: it runs alone, so that
/// it cannot starve a loopback session's 4 ms deadlines.
pub fn cores_alone() -> std::sync::RwLockWriteGuard<'static, ()> {
    TURN.write()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

static TURN: std::sync::RwLock<()> = std::sync::RwLock::new(());

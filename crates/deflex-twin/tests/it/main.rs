//! Integration tests of `deflex-twin` (everything here is SIMULATED): one test binary (modules
//! below). The in-process closed loop, the runtime's threads in simulated time, and `deflex
//! cell --sim` with `deflex run` over loopback for every robot protocol.

mod cell_file;
mod cell_server;
mod closed_loop;
mod common;
mod loopback;
mod sim_time;
mod telemetry;

/// Tests that run the real-time threads (wall-clock loopback sessions, and the simulated-time
/// runtime whose lockstep threads keep both cores busy) take turns, so one cannot starve
/// another's 4 ms deadlines on a 2-core machine.
pub fn realtime_turn() -> std::sync::MutexGuard<'static, ()> {
    static TURN: std::sync::Mutex<()> = std::sync::Mutex::new(());
    TURN.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

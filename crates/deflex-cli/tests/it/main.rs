//! Integration tests of `deflex-cli`: one test binary (modules below), so a fresh clone links one
//! executable for this crate instead of one per file.

// Ignored by default: headless Chromium on the live pages of a real SIMULATED session.
mod browser;
// The DevTools client of deflex-view's browser test, shared rather than copied.
#[path = "../../../deflex-view/tests/it/cdp.rs"]
mod cdp;
mod cli_calib;
mod cli_egcal;
mod cli_model;
mod cli_run;
mod cli_sim;
mod hostile;
mod strict_inputs;
mod walkthrough;

/// Tests that run the real-time threads against loopback peers take turns: on a busy 2-core
/// machine two such sessions at once would starve each other's millisecond deadlines (a test
/// binary runs its tests on parallel threads).
pub fn realtime_turn() -> std::sync::MutexGuard<'static, ()> {
    static TURN: std::sync::Mutex<()> = std::sync::Mutex::new(());
    TURN.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

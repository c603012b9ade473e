//! Integration tests of `deflex-cli`: one test binary (modules below), so a fresh clone links one
//! executable for this crate instead of one per file.

// Ignored by default: headless Chromium on the live pages of a real SIMULATED session.
mod browser;
// The DevTools client and the live-page checks of deflex-view's browser test, compiled here
// rather than copied (both packages check a live page with one client).
#[path = "../../../deflex-view/tests/it/cdp.rs"]
mod cdp;
mod cli_calib;
mod cli_cell;
mod cli_compensate;
mod cli_egcal;
mod cli_export;
mod cli_live;
mod cli_model;
mod cli_plot;
mod cli_run;
mod cli_sim;
// The documented CELL.toml as a test session runs it, deflex-app's test fixture, compiled here
// rather than copied.
#[path = "../../../deflex-app/tests/it/example_cell.rs"]
mod example_cell;
mod hostile;
mod operator_frames;
mod strict_inputs;
mod support;
mod walkthrough;

/// `deflex run` and `deflex cell --sim` processes against each other on loopback sleep most of
/// every robot cycle: the harness runs two such tests at once (its two threads on a 2-core
/// machine), each still meeting its links' timeouts, and they share this turn.
pub fn session_turn() -> std::sync::RwLockReadGuard<'static, ()> {
    TURN.read().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// A test that drives a browser beside its sessions keeps both cores busy: it runs alone.
pub fn cores_alone() -> std::sync::RwLockWriteGuard<'static, ()> {
    TURN.write()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

static TURN: std::sync::RwLock<()> = std::sync::RwLock::new(());

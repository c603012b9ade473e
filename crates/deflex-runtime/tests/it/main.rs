//! Integration tests of `deflex-runtime`: one test binary (modules below). The threads against
//! real protocols on loopback (sessions, link glitches, faults), the control thread's whole
//! per-cycle path without allocation (telemetry publish included), the CSV log written from the
//! telemetry stream, the feed-forward table read from `compensated_path.csv`, the `CELL.toml`
//! fuzz target, and the pieces one by one: `CELL.toml` parsing and bounds, the clocks, the send
//! shaper, the cycle-time statistics and SCHED_FIFO.

// Counts only the calling thread's allocations (see `deflex-alloc-count`), so the
// no-allocation tests are undisturbed by the other tests of this binary running in parallel.
#[global_allocator]
static GLOBAL: deflex_alloc_count::CountingAllocator = deflex_alloc_count::CountingAllocator;

mod clock;
mod common;
mod config;
mod feedforward_table;
mod fuzz;
mod link_glitch;
mod links;
mod log;
mod loopback;
mod no_alloc;
mod rt;
mod send_shaper;
mod session;
mod stats;
mod telemetry;

/// Tests that run the real-time threads against loopback peers take turns: on a busy 2-core
/// machine two such sessions at once would starve each other's millisecond deadlines (a test
/// binary runs its tests on parallel threads).
pub fn realtime_turn() -> std::sync::MutexGuard<'static, ()> {
    static TURN: std::sync::Mutex<()> = std::sync::Mutex::new(());
    TURN.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

//! Integration tests of `deflex-control`: one test binary (modules below), so a fresh clone links one
//! executable for this crate instead of one per file.

// Counts only the calling thread's allocations (see `deflex-alloc-count`), so the
// no-allocation tests are undisturbed by the other tests of this binary running in parallel.
#[global_allocator]
static GLOBAL: deflex_alloc_count::CountingAllocator = deflex_alloc_count::CountingAllocator;

mod common;
mod faults;
mod feedforward;
mod fuzz;
mod link_glitch;
mod no_alloc;
mod runaway;
mod runtime;
mod session;

/// Tests that run the real-time threads against loopback peers take turns: on a busy 2-core
/// machine two such sessions at once would starve each other's millisecond deadlines (a test
/// binary runs its tests on parallel threads).
pub fn realtime_turn() -> std::sync::MutexGuard<'static, ()> {
    static TURN: std::sync::Mutex<()> = std::sync::Mutex::new(());
    TURN.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

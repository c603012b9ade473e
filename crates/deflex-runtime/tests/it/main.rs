//! Integration tests of `deflex-runtime`: one test binary (modules below). The threads against
//! real protocols on loopback (sessions, link glitches, faults), the control thread's whole
//! per-cycle path without allocation (telemetry publish included), the CSV log written from the
//! telemetry stream, the feed-forward table read from `compensated_path.csv`, the `CELL.toml`
//! fuzz target, and the pieces one by one: `CELL.toml` parsing and bounds, the clocks, the send
//! shaper, the cycle-time statistics and SCHED_FIFO.

// The real-time sessions against loopback peers sleep most of every cycle: the harness runs two
// of them at once (its two threads on a 2-core machine) without either missing the links'
// timeouts, and every check of a session holds whatever the scheduling (a late answer is
// counted, a fault during a warm-up repeats the session).
//
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

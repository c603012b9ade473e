//! Integration tests of `deflex-runtime`: one test binary (modules below). The threads against
//! real protocols on loopback (sessions, link glitches, faults), the telemetry stream of a
//! session and the CSV log written from it, and the pieces one by one: the clocks, the send
//! shaper, the cycle-time statistics and SCHED_FIFO. Above the runtime: `CELL.toml`, the link
//! factory and the feed-forward table in deflex-app's `tests/it/cell`; the control thread's
//! whole per-cycle path without allocation in the facade's `no_alloc::runtime` and the
//! `CELL.toml` fuzz target in its `fuzz::cell_config` (crates/deflex/tests/it).

// The real-time sessions against loopback peers sleep most of every cycle: the harness runs two
// of them at once (its two threads on a 2-core machine) without either missing the links'
// timeouts, and every check of a session holds whatever the scheduling (a late answer is
// counted, a fault during a warm-up repeats the session).

mod clock;
mod common;
mod fanuc_stream;
mod link_glitch;
mod loopback;
mod rt;
mod send_shaper;
mod session;
mod stats;
mod telemetry;

//! The tests of `deflex-io`, through its public API: one test binary (modules below), so a fresh
//! clone links one executable for this crate instead of one per file, and compiles the library
//! once (it has no test build of its own). A module per protocol or piece (`egm`, `rsi`, …) and
//! per concern across them (`fuzz`, `no_alloc`, `peers`, …).

// Counts only the calling thread's allocations (see `deflex-alloc-count`), so the
// no-allocation tests are undisturbed by the other tests of this binary running in parallel.
#[global_allocator]
static GLOBAL: deflex_alloc_count::CountingAllocator = deflex_alloc_count::CountingAllocator;

mod egm;
mod fuzz;
mod guard;
mod link;
mod netft;
mod no_alloc;
mod peer;
mod peer_policy;
mod peers;
mod replays;
mod rsi;
mod simple_tcp;
mod simple_udp;
mod staubli;
mod tcp_abuse;
mod udp;
mod xml;

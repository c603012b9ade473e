//! Integration tests of `deflex-view`: one test binary. `server` talks to the server over
//! loopback sockets; `browser` (ignored by default, run with `cargo test -p deflex-view --
//! --ignored`) drives Debian's headless Chromium over the DevTools protocol; `control_cost`
//! measures what an open page costs the control loop of a session against the twin; `frame`
//! checks the decimation, the p99 and the wire format against separately written computations.

// Counts only the calling thread's allocations (see `deflex-alloc-count`): the control thread's
// count is undisturbed by the other tests of this binary running in parallel.
#[global_allocator]
static GLOBAL: deflex_alloc_count::CountingAllocator = deflex_alloc_count::CountingAllocator;

mod browser;
mod cdp;
mod control_cost;
mod frame;
mod server;
mod support;

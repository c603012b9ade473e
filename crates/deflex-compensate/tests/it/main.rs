//! Integration tests of `deflex-compensate`: one test binary (modules below), so a fresh clone links one
//! executable for this crate instead of one per file.

// Counts only the calling thread's allocations (see `deflex-alloc-count`), so the
// no-allocation tests are undisturbed by the other tests of this binary running in parallel.
#[global_allocator]
static GLOBAL: deflex_alloc_count::CountingAllocator = deflex_alloc_count::CountingAllocator;

mod compensate;
mod log;
mod logged;
mod no_alloc;
mod path;
mod table;

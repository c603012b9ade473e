//! Integration tests of `deflex-telemetry`: one test binary.

// Counts only the calling thread's allocations (see `deflex-alloc-count`).
#[global_allocator]
static GLOBAL: deflex_alloc_count::CountingAllocator = deflex_alloc_count::CountingAllocator;

mod ring;

//! Test support for deflex's "the per-cycle path allocates nothing" tests: a global allocator
//! that counts every allocation (`alloc`, `alloc_zeroed`, `realloc`) **of the thread that makes
//! it**, so a test's count is never disturbed by other test threads, the harness or a library's
//! background thread.
//!
//! ```text
//! #[global_allocator]
//! static GLOBAL: deflex_alloc_count::CountingAllocator = deflex_alloc_count::CountingAllocator;
//!
//! let (value, allocations) = deflex_alloc_count::count(|| hot_path());
//! assert_eq!(allocations, 0);
//! ```

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

thread_local! {
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

fn bump() {
    // `try_with`: an allocation while the thread's locals are being torn down is not counted
    // (and must not panic inside the allocator).
    let _ = ALLOCATIONS.try_with(|n| n.set(n.get() + 1));
}

/// The system allocator, counting the calling thread's allocations.
pub struct CountingAllocator;

// SAFETY: every call is forwarded unchanged to `System`; the counter is a thread-local `Cell`
// with a const initialiser, which does not allocate.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        bump();
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        bump();
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        bump();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

/// Allocations made so far by the calling thread (counted only when [`CountingAllocator`] is
/// the global allocator).
pub fn allocations() -> u64 {
    ALLOCATIONS.with(Cell::get)
}

/// Runs `f` and returns its value with the number of allocations it made on this thread.
pub fn count<R>(f: impl FnOnce() -> R) -> (R, u64) {
    let before = allocations();
    let value = f();
    (value, allocations() - before)
}

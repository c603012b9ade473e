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
use std::sync::atomic::{AtomicU64, Ordering};

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

/// The counter sees this thread's allocations, and only them.
#[cfg(test)]
mod tests {
    #[global_allocator]
    static GLOBAL: super::CountingAllocator = super::CountingAllocator;

    #[test]
    fn counts_this_threads_allocations_only() {
        let (v, n) = super::count(|| vec![1u8; 100]);
        assert_eq!((v.len(), n), (100, 1));
        let (_, n) = super::count(|| {
            let mut v: Vec<u64> = Vec::with_capacity(1);
            v.extend(0..1000); // grows by realloc
            std::hint::black_box(v)
        });
        assert!(n >= 2, "{n}");
        let (_, n) = super::count(|| std::hint::black_box(3.0f64).sqrt());
        assert_eq!(n, 0);
        // Another thread's allocations are its own: spawn outside, allocate inside.
        let (tx, rx) = std::sync::mpsc::sync_channel::<()>(0);
        let worker = std::thread::spawn(move || {
            rx.recv().unwrap();
            let v: Vec<Vec<u8>> = (0..1000).map(|i| vec![0u8; i + 1]).collect();
            std::hint::black_box(v).len()
        });
        let (_, n) = super::count(|| tx.send(()).unwrap());
        assert_eq!(worker.join().unwrap(), 1000);
        assert!(n < 10, "{n}"); // the channel hand-over itself, never the worker's 1000
    }
}

/// The allocations one thread makes between consecutive calls of [`CycleCounter::cycle`]
/// (a control thread's clock calls it once per cycle), filed under one of `N` classes (e.g.
/// "page closed" / "page open"); the first `skip` calls are left out (they include the
/// thread's start). Shared between the measured thread and the test through an `Arc`.
#[derive(Debug)]
pub struct CycleCounter<const N: usize> {
    skip: u64,
    calls: AtomicU64,
    last: AtomicU64,
    allocations: [AtomicU64; N],
    cycles: [AtomicU64; N],
}

impl<const N: usize> CycleCounter<N> {
    /// A counter that leaves out the first `skip` calls.
    pub fn new(skip: u64) -> Self {
        CycleCounter {
            skip,
            calls: AtomicU64::new(0),
            last: AtomicU64::new(0),
            allocations: [const { AtomicU64::new(0) }; N],
            cycles: [const { AtomicU64::new(0) }; N],
        }
    }

    /// Called by the measured thread once per cycle: files its allocations since the previous
    /// call under `class` (< `N`).
    pub fn cycle(&self, class: usize) {
        let count = allocations();
        if self.calls.fetch_add(1, Ordering::Relaxed) >= self.skip {
            let previous = self.last.load(Ordering::Relaxed);
            self.allocations[class].fetch_add(count - previous, Ordering::Relaxed);
            self.cycles[class].fetch_add(1, Ordering::Relaxed);
        }
        self.last.store(count, Ordering::Relaxed);
    }

    /// Allocations filed under `class`.
    pub fn allocations(&self, class: usize) -> u64 {
        self.allocations[class].load(Ordering::Relaxed)
    }

    /// Cycles measured under `class`.
    pub fn cycles(&self, class: usize) -> u64 {
        self.cycles[class].load(Ordering::Relaxed)
    }
}

//! No per-cycle path allocates: one module per layer's hot path.
//!
//! [`setup`] is deflex-runtime's test set-up, with deflex-control's in it (the TX200 controller
//! with a known bias and a tool, the raw sensor reading for a TCP wrench, a KUKA and a Net F/T
//! on loopback, a session's telemetry): compiled here from those packages' tests by `#[path]`,
//! not copied, so that the control cycles and the sessions measured here are the ones their
//! own tests run (the no-allocation tests need this binary's counting allocator, so they cannot
//! live in those packages' test binaries).

mod compensate;
mod control;
mod cycle_counter;
mod io;
mod model;
mod ros2;
mod runtime;
#[path = "../../../../deflex-runtime/tests/it/common/mod.rs"]
mod setup;
mod telemetry;
mod view;

/// Allocations made so far by the calling thread (allocations and reallocations).
pub fn allocations() -> u64 {
    let stats = densa_alloc::thread_stats();
    stats.allocs + stats.reallocs
}

/// Runs `f` and returns its value with the number of allocations it made on this thread.
pub fn count<R>(f: impl FnOnce() -> R) -> (R, u64) {
    let before = allocations();
    let value = f();
    (value, allocations() - before)
}

#[test]
fn the_counter_counts_this_threads_allocations_only() {
    assert!(densa_alloc::is_active());
    let (v, n) = count(|| vec![1u8; 100]);
    assert_eq!((v.len(), n), (100, 1));
    let (_, n) = count(|| {
        let mut v: Vec<u64> = Vec::with_capacity(1);
        v.extend(0..1000); // grows by realloc
        std::hint::black_box(v)
    });
    assert!(n >= 2, "{n}");
    let (_, n) = count(|| std::hint::black_box(3.0f64).sqrt());
    assert_eq!(n, 0);
    // Another thread's allocations are its own: spawn outside, allocate inside.
    let (tx, rx) = std::sync::mpsc::sync_channel::<()>(0);
    let worker = std::thread::spawn(move || {
        rx.recv().unwrap();
        let v: Vec<Vec<u8>> = (0..1000).map(|i| vec![0u8; i + 1]).collect();
        std::hint::black_box(v).len()
    });
    let (_, n) = count(|| tx.send(()).unwrap());
    assert_eq!(worker.join().unwrap(), 1000);
    assert!(n < 10, "{n}"); // the channel hand-over itself, never the worker's 1000
}

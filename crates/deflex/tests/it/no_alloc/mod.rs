//! No per-cycle path allocates: one module per layer's hot path.

mod compensate;
mod control;
mod cycle_counter;
mod io;
mod model;
mod ros2;
mod runtime;
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

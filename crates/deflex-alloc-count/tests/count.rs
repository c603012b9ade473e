//! The counter sees this thread's allocations, and only them.

#[global_allocator]
static GLOBAL: deflex_alloc_count::CountingAllocator = deflex_alloc_count::CountingAllocator;

#[test]
fn counts_this_threads_allocations_only() {
    let (v, n) = deflex_alloc_count::count(|| vec![1u8; 100]);
    assert_eq!((v.len(), n), (100, 1));
    let (_, n) = deflex_alloc_count::count(|| {
        let mut v: Vec<u64> = Vec::with_capacity(1);
        v.extend(0..1000); // grows by realloc
        std::hint::black_box(v)
    });
    assert!(n >= 2, "{n}");
    let (_, n) = deflex_alloc_count::count(|| std::hint::black_box(3.0f64).sqrt());
    assert_eq!(n, 0);
    // Another thread's allocations are its own: spawn outside, allocate inside.
    let (tx, rx) = std::sync::mpsc::sync_channel::<()>(0);
    let worker = std::thread::spawn(move || {
        rx.recv().unwrap();
        let v: Vec<Vec<u8>> = (0..1000).map(|i| vec![0u8; i + 1]).collect();
        std::hint::black_box(v).len()
    });
    let (_, n) = deflex_alloc_count::count(|| tx.send(()).unwrap());
    assert_eq!(worker.join().unwrap(), 1000);
    assert!(n < 10, "{n}"); // the channel hand-over itself, never the worker's 1000
}

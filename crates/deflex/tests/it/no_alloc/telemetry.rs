//! No allocation on deflex-telemetry's per-cycle path: publishing a cycle sample into the ring,
//! writing a sequence cell and reading both (what the control thread and its sinks do every
//! cycle), counted on this thread by the binary's counting allocator.

use deflex_telemetry::{CycleSample, SeqCell, broadcast};

#[test]
fn publishing_and_reading_allocate_nothing() {
    let (mut publisher, ring) = broadcast::<CycleSample>(16);
    let mut sub = ring.subscribe();
    let cell = SeqCell::<CycleSample>::new();
    // The values do not matter here (the ring's own tests check them): a sample per cycle.
    let stamped = |i: u64| CycleSample {
        time_s: i as f64,
        cycle: i,
        ..CycleSample::default()
    };
    let ((), allocations) = super::count(|| {
        for i in 0..100 {
            publisher.publish(&stamped(i));
            cell.write(&stamped(i));
            let _ = sub.try_next();
            let _ = ring.latest();
            let _ = cell.read();
        }
    });
    assert_eq!(allocations, 0);
}

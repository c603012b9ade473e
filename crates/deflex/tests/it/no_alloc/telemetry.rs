//! No allocation on deflex-telemetry's per-cycle path: publishing a cycle sample into the ring,
//! writing a sequence cell and reading both (what the control thread and its sinks do every
//! cycle), counted on this thread by the binary's counting allocator.

use deflex_telemetry::{CycleSample, SeqCell, broadcast};

/// A sample whose every number is derived from `i`.
fn stamped(i: u64) -> CycleSample {
    let x = i as f64;
    let mut s = CycleSample {
        time_s: x,
        cycle: i,
        ..CycleSample::default()
    };
    s.q_rad = [x; 8];
    s.wrench_tcp = [x; 6];
    s.correction = [-x; 6];
    s.tcp_position_m = [x; 3];
    s.fault = (i % 7) as u32;
    s
}

#[test]
fn publishing_and_reading_allocate_nothing() {
    let (mut publisher, ring) = broadcast::<CycleSample>(16);
    let mut sub = ring.subscribe();
    let cell = SeqCell::<CycleSample>::new();
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

//! Cycle-time statistics ([`deflex_runtime::stats`]).

use deflex_runtime::stats::CycleStats;
use std::time::Duration;

#[test]
fn percentiles_and_misses() {
    let mut s = CycleStats::new(Duration::from_micros(100));
    for us in 1..=100u64 {
        s.record(Duration::from_micros(us) - Duration::from_nanos(500));
    }
    s.record(Duration::from_millis(200));
    let sum = s.summary();
    assert_eq!(sum.count, 101);
    assert!((sum.p50_us - 51.0).abs() <= 1.0, "{sum:?}");
    assert!(sum.p99_us >= 99.0 && sum.p99_us <= 101.0, "{sum:?}");
    assert_eq!(sum.max_us, 200_000.0);
    assert_eq!(sum.deadline_misses, 1);
}

//! Best-effort real-time scheduling ([`deflex_runtime::rt`]).

use deflex_runtime::rt::try_realtime;

#[test]
fn never_panics_and_reports() {
    // Run in a scratch thread (it ends at once) so a successful SCHED_FIFO does not affect
    // other tests.
    let report = std::thread::spawn(|| try_realtime(10, false))
        .join()
        .unwrap();
    assert!(report.mlock.is_none());
    let _ = report.warnings();
}

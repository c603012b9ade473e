//! Best-effort real-time scheduling ([`deflex_runtime::rt`]).

use deflex_runtime::rt::try_realtime;

#[test]
fn never_panics_and_reports() {
    // A SCHED_FIFO thread: it takes its turn with the real-time sessions.
    let _turn = crate::realtime_turn();
    // Run in a scratch thread so a successful SCHED_FIFO does not affect other tests.
    let report = std::thread::spawn(|| try_realtime(10, false))
        .join()
        .unwrap();
    assert!(report.mlock.is_none());
    let _ = report.warnings();
}

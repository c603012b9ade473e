//! The simulated and wall clocks ([`deflex_runtime::clock`]).

use deflex_runtime::clock::{Clock, SimClock, WallClock};
use std::time::Duration;

#[test]
fn sim_clock_jumps_and_never_goes_back() {
    let c = SimClock::new();
    let c2 = c.clone();
    c.sleep_until(1.5);
    assert_eq!(c2.now(), 1.5);
    c2.sleep_until(1.0);
    assert_eq!(c.now(), 1.5);
}

#[test]
fn driven_clock_runs_every_due_cycle_at_its_time() {
    let clock = SimClock::driven();
    let follower = {
        let clock = clock.clone();
        std::thread::spawn(move || {
            let mut seen = Vec::new();
            for k in 1..=10 {
                let t = k as f64 * 0.01;
                clock.sleep_until(t);
                seen.push(clock.now());
            }
            clock.release();
            seen
        })
    };
    assert!(clock.wait_for_follower(Duration::from_secs(5)));
    let mut t = 0.0;
    while t < 0.2 {
        t += 0.004;
        clock.advance_to(t);
    }
    clock.finish();
    let seen = follower.join().unwrap();
    for (k, s) in seen.iter().enumerate() {
        assert!((s - (k + 1) as f64 * 0.01).abs() < 1e-12, "{seen:?}");
    }
}

#[test]
fn wall_clock_sleeps_until() {
    let c = WallClock::new();
    let t = c.now() + 0.003;
    c.sleep_until(t);
    assert!(c.now() >= t);
}

//! The runaway guard on its own ([`deflex_control::runaway`]): the loop-gain estimate along u, the trip, withdrawal, latch and release, the cap along the held direction.

use deflex_control::runaway::*;

fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Feeds the guard a motion of `step` per cycle with a force against u rising by
/// `stiffness` per metre along `normal`, for `cycles` cycles; returns the last update.
fn feed(
    guard: &mut RunawayGuard,
    u: [f64; 3],
    step: [f64; 3],
    normal: [f64; 3],
    stiffness: f64,
    cycles: usize,
) -> GuardUpdate {
    let mut x = [0.0; 3];
    let mut last = GuardUpdate::default();
    for k in 0..cycles {
        let penetration = dot(&x, &normal);
        // Contact force along −normal·(…): the reaction against u is k·penetration·(n·u).
        let f = -stiffness * penetration;
        let force = normal.map(|n| f * n);
        let xi = u.map(|v| v * 1e-4 * (k + 1) as f64);
        last = guard.update(&x, &force, &xi, Some(u), 1e-6, 0.01);
        for i in 0..3 {
            x[i] += step[i];
        }
    }
    last
}

#[test]
fn estimate_along_u_matches_the_contact_and_ignores_tangential_motion() {
    let u = [0.0, 0.0, 1.0];
    // Motion along u into a 10⁶ N/m contact: ĝ = ĉ k = 10⁻⁶ · 10⁶ = 1 (hand value).
    let mut guard = RunawayGuard::new(RunawayConfig {
        action: RunawayAction::Fault,
        ..RunawayConfig::default()
    });
    let update = feed(&mut guard, u, [0.0, 0.0, 5e-6], u, 1e6, 30);
    assert!((update.gain - 1.0).abs() < 1e-9, "{}", update.gain);
    // Motion 80° away from u (a traverse), the force unchanged: only cos²80° = 3 % of each
    // sample's motion counts, 20 µm/cycle gives a weighted travel of 10 × 0.03 × 3.5 µm ≈
    // 1 µm within the window: unknown, not "low".
    let mut guard = RunawayGuard::new(RunawayConfig::default());
    let (s, c) = 80f64.to_radians().sin_cos();
    let update = feed(&mut guard, u, [20e-6 * s, 0.0, 20e-6 * c], u, 0.0, 30);
    assert!(update.gain.is_nan(), "{}", update.gain);
    // The same traverse with every sample counted alike would read ĝ = 0: check that the
    // motion along u alone (3.5 µm/cycle) is enough when it is all there is.
    let mut guard = RunawayGuard::new(RunawayConfig::default());
    let update = feed(&mut guard, u, [0.0, 0.0, 20e-6 * c], u, 0.0, 30);
    assert!(update.gain.abs() < 1e-12, "{}", update.gain);
}

#[test]
fn trip_withdraws_then_latches_and_releases_at_its_rate() {
    let u = [0.0, 0.0, 1.0];
    let config = RunawayConfig::default();
    let mut guard = RunawayGuard::new(config);
    let update = feed(&mut guard, u, [0.0, 0.0, 5e-6], u, 1e6, 30);
    let hold = guard.hold().expect("tripped on ĝ = 1 > 0.5");
    assert!(update.holding);
    assert_eq!(hold.phase, HoldPhase::Withdrawing);
    // The law keeps asking for 1 mm along u: withdrawn to 0 over 0.5 s, then latched.
    let mut xi = [0.0, 0.0, 1e-3, 0.0, 0.0, 0.0];
    let x = [0.0; 3];
    let force = [0.0, 0.0, -100.0];
    let mut caps = Vec::new();
    for _ in 0..80 {
        guard.update(&x, &force, &[0.0; 3], None, 1e-6, 0.01);
        xi[2] = 1e-3;
        guard.limit(&mut xi);
        caps.push(xi[2]);
    }
    assert!(caps.windows(2).all(|w| w[1] <= w[0]), "never grows");
    assert_eq!(caps[60], 0.0);
    assert_eq!(guard.hold().unwrap().phase, HoldPhase::Holding);
    // The law stops pushing (ξ·u below 50 µm): released at 0.5 mm/s, i.e. 5 µm per cycle.
    let mut given = Vec::new();
    for _ in 0..40 {
        guard.update(&x, &force, &[0.0; 3], None, 1e-6, 0.01);
        let mut xi = [0.0, 0.0, 40e-6, 0.0, 0.0, 0.0];
        guard.limit(&mut xi);
        given.push(xi[2]);
    }
    // Cycle 0: the law's 40 µm is seen; cycle 1: the release begins; then 5 µm per cycle.
    assert_eq!(&given[..2], &[0.0, 0.0]);
    assert!((given[2] - 5e-6).abs() < 1e-12, "{}", given[2]);
    assert!((given[9] - 40e-6).abs() < 1e-12, "{}", given[9]);
    assert!(
        guard.hold().is_none(),
        "released once the cap passed the law by 50 µm"
    );
}

#[test]
fn guard_caps_growth_only_along_the_held_direction() {
    // A hold along u = −z with its cap at 1 mm, latched (action `hold`), reached through the
    // guard's own updates: motion along u into a 10⁶ N/m contact (ĝ = 1) with the law's ξ·u
    // stepped from 0 to 1 mm on the second cycle and kept there until the trip.
    let u = [0.0, 0.0, -1.0];
    let mut guard = RunawayGuard::new(RunawayConfig {
        action: RunawayAction::Hold,
        ..RunawayConfig::default()
    });
    let mut x = [0.0; 3];
    for k in 0..200 {
        if guard.hold().is_some() {
            break;
        }
        let f = -1e6 * dot(&x, &u);
        let force = u.map(|n| f * n);
        let xi = u.map(|v| if k == 0 { 0.0 } else { v * 1e-3 });
        guard.update(&x, &force, &xi, Some(u), 1e-6, 0.01);
        x[2] -= 5e-6;
    }
    let hold = guard.hold().expect("tripped on ĝ = 1 > 0.5");
    assert_eq!(
        (hold.u, hold.cap, hold.phase),
        ([0.0, 0.0, -1.0], 1e-3, HoldPhase::Holding)
    );
    let mut xi = [2e-4, 0.0, -3e-3, 0.0, 0.0, 0.0];
    assert!(guard.limit(&mut xi));
    assert_eq!(xi, [2e-4, 0.0, -1e-3, 0.0, 0.0, 0.0]);
    let mut smaller = [0.0, 5e-4, -5e-4, 0.0, 0.0, 0.0];
    assert!(!guard.limit(&mut smaller));
}

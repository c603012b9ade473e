//! The laser tracker's noise against distance.

use deflex_sim::cell_config::TrackerConfig;
use deflex_sim::tracker::LaserTracker;
use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

#[test]
fn noise_grows_with_distance_as_specified() {
    let config = TrackerConfig {
        position_m: [0.0, 0.0, 0.0],
        samples_per_reading: 25,
        ..TrackerConfig::default()
    };
    let mut tracker = LaserTracker::new(&config, ChaCha8Rng::seed_from_u64(3));
    for (distance, expected) in [(1.0, 15e-6), (4.0, 30e-6)] {
        let p = Vector3::new(distance, 0.0, 0.0);
        assert!((tracker.sigma_at(&p) - expected).abs() < 1e-12);
        let n = 4000;
        let mut sq = 0.0;
        let mut mean = Vector3::zeros();
        for _ in 0..n {
            let e = tracker.measure(&p) - p;
            mean += e;
            sq += e.norm_squared();
        }
        let sigma = (sq / (3 * n) as f64).sqrt();
        assert!(
            (sigma / expected - 1.0).abs() < 0.05,
            "{sigma} vs {expected}"
        );
        assert!((mean / n as f64).norm() < 3.0 * expected / (n as f64).sqrt() * 2.0);
    }
    let (_, s) = tracker.measure_static(&Vector3::new(1.0, 0.0, 0.0));
    assert!((s - 15e-6 / 5.0).abs() < 1e-12);
}

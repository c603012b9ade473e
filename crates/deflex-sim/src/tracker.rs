//! Laser tracker (API Radian class): 3D points with isotropic Gaussian noise whose standard
//! deviation grows with range, σ(d) = σ₀ + σ₁·d (defaults 10 µm + 5 µm/m, the datasheet envelope
//! used as 1σ), at up to 50 Hz.

use crate::cell_config::TrackerConfig;
use nalgebra::Vector3;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

/// The simulated tracker.
#[derive(Clone, Debug)]
pub struct LaserTracker {
    config: TrackerConfig,
    head: Vector3<f64>,
    rng: ChaCha8Rng,
}

impl LaserTracker {
    /// A tracker at `config.position_m`.
    pub fn new(config: &TrackerConfig, rng: ChaCha8Rng) -> LaserTracker {
        LaserTracker {
            config: config.clone(),
            head: Vector3::from(config.position_m),
            rng,
        }
    }

    /// 1σ per axis at a point (m).
    pub fn sigma_at(&self, point: &Vector3<f64>) -> f64 {
        self.config.sigma_const_m + self.config.sigma_per_m * (point - self.head).norm()
    }

    /// Sample period (s).
    pub fn period_s(&self) -> f64 {
        1.0 / self.config.rate_hz
    }

    /// One reading of a true point.
    pub fn measure(&mut self, point: &Vector3<f64>) -> Vector3<f64> {
        let sigma = self.sigma_at(point);
        let n = Vector3::new(
            self.rng.sample::<f64, _>(StandardNormal),
            self.rng.sample::<f64, _>(StandardNormal),
            self.rng.sample::<f64, _>(StandardNormal),
        );
        point + n * sigma
    }

    /// A static reading: the mean of `samples_per_reading` samples. Returns the point and its 1σ.
    pub fn measure_static(&mut self, point: &Vector3<f64>) -> (Vector3<f64>, f64) {
        let n = self.config.samples_per_reading;
        let mut sum = Vector3::zeros();
        for _ in 0..n {
            sum += self.measure(point);
        }
        (sum / n as f64, self.sigma_at(point) / (n as f64).sqrt())
    }
}

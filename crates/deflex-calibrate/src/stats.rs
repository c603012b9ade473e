//! Statistics of prediction errors (measured − predicted), one pair of types for both
//! calibrations and both units (metres for positions and displacements, radians for rotations):
//!
//! * [`ErrorNormStats`]: the distribution of the size of the errors, |e| (count, RMS, mean, 95th
//!   percentile, maximum): the elasto-geometric calibration's held-out, fit and prediction
//!   scores, which know each reading's error norm;
//! * [`ErrorStats`]: 3-D errors, per axis (RMS, largest |e|, mean) and their norm
//!   ([`ErrorNormStats`]): the stiffness calibration's residuals and validation errors.
//!
//! The unit is the errors' unit; the field that holds the statistics says which.

/// The distribution of error norms |e| (any one unit).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ErrorNormStats {
    /// Number of errors.
    pub count: usize,
    /// Root mean square.
    pub rms: f64,
    /// Mean.
    pub mean: f64,
    /// 95th percentile (the smallest norm at or above 95 % of them).
    pub p95: f64,
    /// Maximum.
    pub max: f64,
}

impl ErrorNormStats {
    /// Statistics of error norms (all zero when there are none).
    pub fn of(norms: &[f64]) -> ErrorNormStats {
        if norms.is_empty() {
            return ErrorNormStats::default();
        }
        let n = norms.len() as f64;
        let mut sorted = norms.to_vec();
        sorted.sort_by(f64::total_cmp);
        ErrorNormStats {
            count: norms.len(),
            rms: (norms.iter().map(|e| e * e).sum::<f64>() / n).sqrt(),
            mean: norms.iter().sum::<f64>() / n,
            p95: percentile_95(&sorted),
            max: sorted[sorted.len() - 1],
        }
    }
}

/// The 95th percentile of sorted values (nearest rank); `sorted` is not empty.
fn percentile_95(sorted: &[f64]) -> f64 {
    let rank = ((0.95 * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len()) - 1;
    sorted[rank]
}

/// Statistics of 3-D errors (any one unit): per axis, and of their norm.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ErrorStats {
    /// RMS per axis.
    pub rms: [f64; 3],
    /// Largest absolute error per axis.
    pub max_abs: [f64; 3],
    /// Mean (bias) per axis.
    pub mean: [f64; 3],
    /// The norms' distribution (its RMS is √(Σ|e|²/n) from the squared norms).
    pub norm: ErrorNormStats,
}

impl ErrorStats {
    /// Statistics of 3-D errors (all zero when there are none).
    pub fn of(errors: &[[f64; 3]]) -> ErrorStats {
        let mut s = ErrorStats::default();
        let n = errors.len().max(1) as f64;
        let mut sum2 = [0.0; 3];
        let mut norm2 = 0.0;
        let mut norms = Vec::with_capacity(errors.len());
        for e in errors {
            let mut n2 = 0.0;
            for ax in 0..3 {
                sum2[ax] += e[ax] * e[ax];
                s.mean[ax] += e[ax] / n;
                s.max_abs[ax] = s.max_abs[ax].max(e[ax].abs());
                n2 += e[ax] * e[ax];
            }
            norm2 += n2;
            let norm = n2.sqrt();
            s.norm.max = s.norm.max.max(norm);
            norms.push(norm);
        }
        for (rms, s2) in s.rms.iter_mut().zip(sum2) {
            *rms = (s2 / n).sqrt();
        }
        s.norm.rms = (norm2 / n).sqrt();
        s.norm.count = errors.len();
        if !norms.is_empty() {
            s.norm.mean = norms.iter().sum::<f64>() / n;
            norms.sort_by(f64::total_cmp);
            s.norm.p95 = percentile_95(&norms);
        }
        s
    }
}

//! Resampling by configuration: k-fold cross-validation of a fitted model step and the
//! bootstrap of its parameters. Both refit warm-started from the full fit with the same
//! identifiable set, so a fold or a replicate costs a few LM iterations.

use crate::geometry::campaign::Campaign;
use crate::geometry::fit::relative_value;
use crate::geometry::params::{EgModel, Param};
use crate::geometry::solve::{self, Loss, SolveOptions};
use crate::stats::ErrorNormStats;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// k-fold cross-validation by configuration: refit (warm start, same identifiable set) on the
/// other folds and score each fold's absolute readings. RMS of the held-out error norms (m).
pub fn cross_validate(
    model: &EgModel,
    campaign: &Campaign,
    kept: &[Param],
    fit_mult: &[f64],
    fold_of: &[usize],
    folds: usize,
    options: &SolveOptions,
) -> f64 {
    let mut norms = Vec::new();
    for fold in 0..folds {
        let train: Vec<f64> = (0..campaign.len())
            .map(|i| {
                if fold_of[campaign.config(i)] == fold {
                    0.0
                } else {
                    fit_mult[i]
                }
            })
            .collect();
        let held: Vec<usize> = (0..campaign.absolute.len())
            .filter(|&i| fit_mult[i] > 0.0 && fold_of[campaign.config(i)] == fold)
            .collect();
        if held.is_empty() {
            continue;
        }
        let mut trained = model.clone();
        solve::solve(&mut trained, campaign, kept, &train, options);
        norms.extend(
            held.iter()
                .map(|&i| campaign.residual(&trained, i, &[], None).norm()),
        );
    }
    ErrorNormStats::of(&norms).rms
}

/// Bootstrap by configuration: resample configurations with replacement, refit with the final
/// robust weights fixed (warm start), and return each parameter's standard deviation.
pub fn bootstrap_se(
    model: &EgModel,
    campaign: &Campaign,
    kept: &[Param],
    fit_mult: &[f64],
    weights: &[f64],
    replicates: usize,
    rng: &mut ChaCha8Rng,
) -> Vec<f64> {
    let configs = campaign.total_configs();
    let fitted: Vec<usize> = {
        let mut c: Vec<usize> = (0..campaign.len())
            .filter(|&i| fit_mult[i] > 0.0)
            .map(|i| campaign.config(i))
            .collect();
        c.sort_unstable();
        c.dedup();
        c
    };
    let options = SolveOptions {
        loss: Loss::Squared,
        max_iterations: 20,
        ..SolveOptions::default()
    };
    let mut sums = vec![0.0; kept.len()];
    let mut squares = vec![0.0; kept.len()];
    for _ in 0..replicates {
        let mut draws = vec![0.0; configs];
        for _ in 0..fitted.len() {
            draws[fitted[rng.gen_range(0..fitted.len())]] += 1.0;
        }
        let mult: Vec<f64> = (0..campaign.len())
            .map(|i| fit_mult[i] * draws[campaign.config(i)] * weights[i])
            .collect();
        let mut replica = model.clone();
        solve::solve(&mut replica, campaign, kept, &mult, &options);
        for (k, &param) in kept.iter().enumerate() {
            let v = relative_value(&replica, model, param);
            sums[k] += v;
            squares[k] += v * v;
        }
    }
    let n = replicates as f64;
    sums.iter()
        .zip(&squares)
        .map(|(s, q)| {
            ((q / n - (s / n).powi(2)) * n / (n - 1.0).max(1.0))
                .max(0.0)
                .sqrt()
        })
        .collect()
}

//! Who plays which part in a fit: readings fitted, readings held out as a test of the fit
//! set-ups, set-ups seen only as held-out series (registered, then scored), and the folds of
//! the configuration cross-validation. Always by configuration, never by row.

use super::options::FitOptions;
use crate::geometry::campaign::{Campaign, ReadingKind};
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeSet;

/// The roles of a fit's readings.
#[derive(Clone, Debug)]
pub struct Roles {
    /// Multiplicity of each reading in the fit (1 fitted, 0 not).
    pub fit_mult: Vec<f64>,
    /// Set-ups with fitted readings.
    pub fit_setups: Vec<usize>,
    /// Set-ups seen only as held-out series.
    pub registration_only: Vec<usize>,
    /// Absolute rows fitted.
    pub fit_rows: Vec<usize>,
    /// Absolute rows of fit set-ups held out (test configurations, test files).
    pub test_rows: Vec<usize>,
    /// Loaded readings fitted.
    pub fit_loaded: Vec<usize>,
    /// Fold of each configuration (`usize::MAX`: not in a fold).
    pub fold_of: Vec<usize>,
}

impl Roles {
    /// Split `campaign` as `options` ask (module documentation).
    pub fn split(
        campaign: &Campaign,
        options: &FitOptions,
        setup_count: usize,
        rng: &mut ChaCha8Rng,
    ) -> Roles {
        let total = campaign.len();
        let n_abs = campaign.absolute.len();
        let configs = campaign.total_configs();
        let held_out: BTreeSet<usize> = options.held_out_readings.iter().copied().collect();
        let mut config_ids: Vec<usize> = (0..n_abs)
            .filter(|i| !held_out.contains(i))
            .map(|i| campaign.config_of[i])
            .collect();
        config_ids.sort_unstable();
        config_ids.dedup();
        config_ids.shuffle(rng);
        let test_count = (options.test_fraction * config_ids.len() as f64).round() as usize;
        let mut is_test_config = vec![false; configs];
        for &c in config_ids.iter().take(test_count) {
            is_test_config[c] = true;
        }
        let mut fit_mult: Vec<f64> = (0..total)
            .map(|i| f64::from(u8::from(!is_test_config[campaign.config(i)])))
            .collect();
        for (i, m) in fit_mult.iter_mut().enumerate() {
            if campaign
                .absolute_row(i)
                .is_some_and(|r| held_out.contains(&r))
            {
                *m = 0.0;
            }
        }
        let fit_setups: Vec<usize> = (0..setup_count)
            .filter(|&s| (0..n_abs).any(|i| campaign.setup_of[i] == s && fit_mult[i] > 0.0))
            .collect();
        let registration_only = (0..setup_count)
            .filter(|s| !fit_setups.contains(s))
            .filter(|&s| campaign.setup_of.contains(&s))
            .collect();
        let fit_rows = (0..n_abs).filter(|&i| fit_mult[i] > 0.0).collect();
        let test_rows = (0..n_abs)
            .filter(|&i| fit_mult[i] == 0.0 && fit_setups.contains(&campaign.setup_of[i]))
            .collect();
        let fit_loaded = campaign
            .loaded_readings()
            .filter(|&i| fit_mult[i] > 0.0)
            .collect();
        let fold_of = {
            let mut ids: Vec<usize> = (0..configs).filter(|&c| !is_test_config[c]).collect();
            ids.shuffle(rng);
            let mut fold = vec![usize::MAX; configs];
            for (k, c) in ids.into_iter().enumerate() {
                fold[c] = k % options.folds.max(1);
            }
            fold
        };
        Roles {
            fit_mult,
            fit_setups,
            registration_only,
            fit_rows,
            test_rows,
            fit_loaded,
            fold_of,
        }
    }

    /// The role of reading `i` in the final residual table.
    pub fn role(&self, campaign: &Campaign, i: usize) -> crate::geometry::outcome::Role {
        use crate::geometry::outcome::Role;
        if self.fit_mult[i] > 0.0 {
            return Role::Fit;
        }
        match campaign.absolute_row(i) {
            Some(r) if self.registration_only.contains(&campaign.setup_of[r]) => {
                Role::HeldOutSeries
            }
            _ => Role::Test,
        }
    }

    /// Whether reading `i` is an orientation.
    pub fn is_orientation(campaign: &Campaign, i: usize) -> bool {
        campaign.kind(i) == ReadingKind::Orientation
    }
}

//! Scoring a model on what the fit did not see: held-out configurations of the fit set-ups
//! (scored as they are), held-out series (each registered by the protocol, then scored), and
//! groups of the fit data (sessions, set-ups, series) left out in turn: refitted without the
//! group, the group registered by the protocol and scored.

use super::options::FitOptions;
use super::roles::Roles;
use crate::geometry::campaign::Campaign;
use crate::geometry::joint_maps::{self, JointMapsHyper};
use crate::geometry::outcome::TestGroup;
use crate::geometry::params::{EgModel, Param};
use crate::geometry::protocol::{row_errors, score_group};
use crate::geometry::residual_model::{ResidualHyper, ResidualModel};
use crate::geometry::solve::{self, SolveOptions};
use crate::stats::ErrorNormStats;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;

/// How a model is refitted inside a held-out loop: the same free parameters, then the joint maps
/// and the residual model retrained on the training rows with these hyper-parameters.
#[derive(Clone, Copy, Debug)]
pub struct Refit<'a> {
    /// Free parameters.
    pub kept: &'a [Param],
    /// Residual model hyper-parameters (`None`: no residual model).
    pub residual: Option<ResidualHyper>,
    /// Joint maps' hyper-parameters (`None`: no joint maps).
    pub maps: Option<JointMapsHyper>,
}

/// Residuals of the fitted absolute rows in joint 1's frame, with their joint values, for
/// training a residual model.
pub fn residual_training_set(
    model: &EgModel,
    campaign: &Campaign,
    mult: &[f64],
) -> (Vec<Vec<f64>>, Vec<nalgebra::Vector3<f64>>) {
    let mut q = Vec::new();
    let mut y = Vec::new();
    for i in (0..campaign.absolute.len()).filter(|&i| mult[i] > 0.0) {
        let row = &campaign.absolute[i];
        let ev = model.evaluate(
            &row.q_rad,
            campaign.target_of[i],
            &campaign.conditions(model, i),
        );
        let r = nalgebra::Vector3::from(row.position_m)
            - model.tracker_position(&ev, campaign.setup_of[i]);
        let world = model.setups[campaign.setup_of[i]].pose.rotation.inverse() * r;
        q.push(row.q_rad.clone());
        y.push(ev.data.joint_frames[0].rotation.inverse() * world);
    }
    (q, y)
}

/// Refit `model` on the readings with `mult > 0` as `refit` says (warm start): the parametric
/// model without maps or residual model, then the maps on its residuals, then the residual
/// model on what is left.
pub fn refit(
    model: &EgModel,
    campaign: &Campaign,
    mult: &[f64],
    refit: Refit,
    solve_options: &SolveOptions,
    seed: u64,
) -> EgModel {
    let mut trained = model.clone();
    trained.residual = None;
    trained.joint_maps = None;
    solve::solve(&mut trained, campaign, refit.kept, mult, solve_options);
    if let Some(hyper) = refit.maps {
        // A failed training (no readings) leaves the parametric model alone.
        let _ = joint_maps::train_into(&mut trained, campaign, mult, hyper);
    }
    if let Some(hyper) = refit.residual {
        let (q, y) = residual_training_set(&trained, campaign, mult);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        // A failed training (fewer than 10 readings, a singular system) leaves the model without
        // a residual model, scored as it is (as a failed map training leaves the maps out).
        trained.residual = ResidualModel::train(&q, &y, hyper, &mut rng).ok();
    }
    trained
}

/// Held-out configurations of the fit set-ups, scored as they are, one group per set-up.
pub fn test_groups(model: &EgModel, campaign: &Campaign, roles: &Roles) -> Vec<TestGroup> {
    let mut by_setup: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for &i in &roles.test_rows {
        by_setup.entry(campaign.setup_of[i]).or_default().push(i);
    }
    by_setup
        .into_iter()
        .map(|(s, rows)| {
            let (position, orientation): (Vec<f64>, Vec<Option<f64>>) =
                rows.iter().map(|&i| row_errors(model, campaign, i)).unzip();
            let orientation: Vec<f64> = orientation.into_iter().flatten().collect();
            let stats = ErrorNormStats::of(&position);
            TestGroup {
                name: format!("{}: held-out configurations", model.setups[s].name),
                stats,
                orientation: (!orientation.is_empty()).then(|| ErrorNormStats::of(&orientation)),
                draw_rms: vec![stats.rms],
                registered: false,
            }
        })
        .collect()
}

/// Held-out series (set-ups without fitted readings): each registered by the protocol and
/// scored. Returns the groups and the model with each series' first-draw registration.
pub fn series_groups(
    model: &EgModel,
    campaign: &Campaign,
    roles: &Roles,
    options: &FitOptions,
) -> (Vec<TestGroup>, EgModel) {
    let mut registered = model.clone();
    let mut groups = Vec::new();
    for &s in &roles.registration_only {
        let rows: Vec<usize> = (0..campaign.absolute.len())
            .filter(|&i| campaign.setup_of[i] == s)
            .collect();
        let mut rng = ChaCha8Rng::seed_from_u64(options.seed ^ (s as u64).wrapping_mul(0x9e37));
        let (score, scored) = score_group(
            model,
            campaign,
            &rows,
            s,
            &options.protocol,
            options.loss,
            &mut rng,
        );
        registered.setups[s] = scored.setups[s].clone();
        groups.push(TestGroup::registered(
            format!("{}: {}", model.setups[s].name, describe(options)),
            score,
        ));
    }
    (groups, registered)
}

/// What the protocol did, for table headers.
pub fn describe(options: &FitOptions) -> String {
    let p = &options.protocol;
    let what = if p.register_target {
        "set-up + target"
    } else {
        "set-up"
    };
    if p.register_readings == 0 {
        format!("own {what} registration on half, scored on the rest")
    } else {
        format!(
            "{what} registered from {} random readings ({} draws), scored on the rest",
            p.register_readings, p.draws
        )
    }
}

/// Groups of the fit rows left out in turn (`options.groups`): refit without the group,
/// register the group by the protocol, score it.
pub fn cross_groups(
    model: &EgModel,
    campaign: &Campaign,
    roles: &Roles,
    options: &FitOptions,
    refit_with: Refit,
    solve_options: &SolveOptions,
) -> Vec<TestGroup> {
    let Some(groups) = &options.groups else {
        return Vec::new();
    };
    let mut members: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for &i in &roles.fit_rows {
        members.entry(groups[i]).or_default().push(i);
    }
    if members.len() < 2 {
        return Vec::new();
    }
    let mut out = Vec::new();
    for (g, rows) in members {
        let mut in_group = vec![false; campaign.absolute.len()];
        for &i in &rows {
            in_group[i] = true;
        }
        let train: Vec<f64> = (0..campaign.len())
            .map(|i| match campaign.absolute_row(i) {
                Some(r) if in_group[r] => 0.0,
                _ => roles.fit_mult[i],
            })
            .collect();
        let trained = refit(
            model,
            campaign,
            &train,
            refit_with,
            solve_options,
            options.seed,
        );
        // Score per set-up of the group (a session lies in one set-up).
        let mut by_setup: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
        for &i in &rows {
            by_setup.entry(campaign.setup_of[i]).or_default().push(i);
        }
        for (s, rows) in by_setup {
            let mut rng = ChaCha8Rng::seed_from_u64(options.seed ^ ((g as u64 + 1) * 0x51));
            let (score, _) = score_group(
                &trained,
                campaign,
                &rows,
                s,
                &options.protocol,
                options.loss,
                &mut rng,
            );
            out.push(TestGroup::registered(
                format!("group {g} ({}), left out", model.setups[s].name),
                score,
            ));
        }
    }
    out
}

/// Pooled position RMS over registered held-out groups (m), `None` without any.
pub fn pooled_rms(groups: &[&TestGroup]) -> Option<f64> {
    let mut squares = 0.0;
    let mut count = 0usize;
    for g in groups.iter().filter(|g| g.registered) {
        squares += g.stats.rms.powi(2) * g.stats.count as f64;
        count += g.stats.count;
    }
    (count > 0).then(|| (squares / count as f64).sqrt())
}

//! The whole identification: registration, a sequence of growing models (the iteration
//! table), and for the final model its uncertainty, bootstrap, outliers and residuals.
//!
//! **Protocol.** Readings are split by *configuration* (never by row): an optional test set
//! ([`FitOptions::test_fraction`] of the configurations, and/or readings of set-ups that have
//! no fit readings, such as a second series) is never seen by the fit; k-fold
//! cross-validation, also by configuration, runs inside the fit set. A test set-up without fit
//! readings (a held-out series) is scored by the registration protocol of
//! [`crate::geometry::protocol`]: its own registration from some of its readings, robot frozen, scored
//! on the rest. With [`FitOptions::groups`] (sessions, set-ups or series of the fit data) each
//! group is in turn left out, the model refitted without it, and the group scored the same way.
//!
//! **Steps.** Each step frees more parameters than the one before, reduces them to the
//! identifiable set ([`crate::geometry::identify`]) and refits: registration only (set-ups and targets
//! on the nominal, rigid robot), + geometry (DH rows with Hayati β), + compliance (the robot's
//! eDoFs, sagging under gravity and any loads; the earlier steps are rigid), and opt-in steps
//! (lumped masses, joint harmonics, gear-periodic terms, backlash, nonlinear torsion, a
//! residual model on the joint angles). An opt-in step is kept only when the pooled held-out RMS of the registered
//! groups improves (the `steps` module); without held-out groups every step is kept.
//!
//! **Orientations.** When the campaign carries measured orientations
//! ([`Campaign::use_orientations`]) they are fitted with the positions, each target gaining its
//! frame's rotation; otherwise the target rotations are set, after the fit, from the fitted
//! readings' orientations in closed form, so orientation errors can still be reported.

mod heldout;
mod options;
mod roles;
mod steps;
mod uncertainty;

pub use heldout::pooled_rms;
pub use options::{
    ACCEPTANCE_GAIN, ChoiceError, FitError, FitOptions, HeldOutProtocol, MAX_BOOTSTRAP, MAX_DRAWS,
    MAX_FOLDS, OptionError, Step,
};
pub use roles::Roles;

use crate::geometry::campaign::Campaign;
pub use crate::geometry::outcome::{
    Acceptance, Estimate, FitResult, Outlier, Role, RowResidual, StepReport, TestGroup,
};
use crate::geometry::params::{EgModel, Param};
use crate::geometry::register::start;
use crate::geometry::solve::SolveOptions;
use deflex_model::spatial::rotation_log;
use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Value of `param` in `model` relative to `reference` (set-up rotations: the rotation vector
/// from the reference's rotation, robot-world axes).
pub fn relative_value(model: &EgModel, reference: &EgModel, param: Param) -> f64 {
    match param {
        Param::SetupRotation(s, k) => {
            let r = reference.setups[s].pose.rotation.inverse() * model.setups[s].pose.rotation;
            rotation_log(&r)[k]
        }
        _ => model.value(param) - reference.value(param),
    }
}

/// The closed-form start: unknown set-ups (identity) and targets (at the flange origin)
/// registered on the fit readings, the robot rigid unless the first step is elastic.
fn registered_start(
    start: &EgModel,
    campaign: &Campaign,
    options: &FitOptions,
    roles: &Roles,
) -> EgModel {
    let mut model = start.clone();
    let unknown_setups: Vec<usize> = roles
        .fit_setups
        .iter()
        .copied()
        .filter(|&s| model.setups[s].pose == deflex_model::Pose::identity())
        .collect();
    let unknown_targets: Vec<usize> = (0..model.targets.len())
        .filter(|&t| model.targets[t].position == Vector3::zeros())
        .collect();
    if !options.steps.first().is_some_and(|s| s.elastic()) {
        model.compliance.iter_mut().for_each(|c| *c = 0.0);
    }
    start::initialise(
        &mut model,
        campaign,
        &unknown_setups,
        &unknown_targets,
        &roles.fit_mult,
        4,
    );
    if !campaign.orientation_rows.is_empty() {
        let targets: Vec<usize> = (0..model.targets.len())
            .filter(|&t| model.targets[t].rotation.is_none())
            .collect();
        start::initialise_target_rotations(&mut model, campaign, &targets, &roles.fit_mult);
    }
    model
}

/// Run the identification (module documentation).
pub fn fit(
    start: &EgModel,
    campaign: &Campaign,
    options: &FitOptions,
) -> Result<FitResult, FitError> {
    let elastic = options.validate(&start.robot, campaign.absolute.len())?;
    let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
    let roles = Roles::split(campaign, options, start.setups.len(), &mut rng);
    if roles.fit_mult.iter().all(|m| *m == 0.0) {
        return Err(FitError::NoFitData);
    }
    let registered = registered_start(start, campaign, options, &roles);
    let context = steps::StepContext {
        campaign,
        options,
        roles: &roles,
        elastic: &elastic,
        solve_options: SolveOptions {
            loss: options.loss,
            ..SolveOptions::default()
        },
        nominal_compliance: &start.compliance,
    };
    let mut accepted = steps::Accepted {
        model: registered.clone(),
        steps: Vec::new(),
        reduction: None,
        outcome: None,
        residual: None,
        maps: None,
        held_out_rms: None,
        with_series: registered.clone(),
    };
    let reports: Vec<StepReport> = options
        .steps
        .iter()
        .map(|&step| steps::run_step(step, &mut accepted, &context))
        .collect();
    let (Some(reduction), Some(outcome)) = (accepted.reduction, accepted.outcome) else {
        return Err(OptionError::NoSteps.into());
    };
    let mut model = accepted.with_series;
    if campaign.orientation_rows.is_empty() {
        // Not fitted: the target frames from the fitted readings' orientations, for reports.
        let targets: Vec<usize> = (0..model.targets.len()).collect();
        start::initialise_target_rotations(&mut model, campaign, &targets, &roles.fit_mult);
    }
    let u = uncertainty::uncertainty(
        &model,
        start,
        &registered,
        campaign,
        &roles,
        &reduction,
        &outcome,
        options.bootstrap,
        &mut rng,
    );
    let (outliers, downweighted) = uncertainty::outliers(&model, campaign, &roles, &outcome);
    let residuals = (0..campaign.len())
        .map(|i| RowResidual {
            index: i,
            residual: campaign.residual(&model, i, &[], None),
            role: roles.role(campaign, i),
        })
        .collect();
    Ok(FitResult {
        steps: reports,
        start: start.clone(),
        reduction,
        estimates: u.estimates,
        covariance: u.covariance,
        chi2_per_dof: u.chi2_per_dof,
        warning: u.warning,
        outliers,
        downweighted,
        residuals,
        fit_rows: roles.fit_mult.iter().map(|m| *m > 0.0).collect(),
        correlations: u.correlations,
        loss: options.loss,
        registration_only_setups: roles
            .registration_only
            .iter()
            .map(|&s| model.setups[s].name.clone())
            .collect(),
        kept_steps: accepted.steps,
        model,
    })
}

/// Cross-validation groups of absolute rows by measuring session: rows of one set-up whose
/// time stamps follow each other within `gap_s` share a session; rows without a time stamp form
/// one session per set-up. Returns one group index per row.
pub fn session_groups(campaign: &Campaign, gap_s: f64) -> Vec<usize> {
    let n = campaign.absolute.len();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| {
        let (ra, rb) = (&campaign.absolute[a], &campaign.absolute[b]);
        campaign.setup_of[a]
            .cmp(&campaign.setup_of[b])
            .then(ra.time_s.is_none().cmp(&rb.time_s.is_none()))
            .then(
                ra.time_s
                    .unwrap_or(0.0)
                    .total_cmp(&rb.time_s.unwrap_or(0.0)),
            )
    });
    let mut group = vec![0; n];
    let mut current = 0;
    for (k, &i) in order.iter().enumerate() {
        if k > 0 {
            let p = order[k - 1];
            let (a, b) = (&campaign.absolute[p], &campaign.absolute[i]);
            let same_setup = campaign.setup_of[p] == campaign.setup_of[i];
            let close = match (a.time_s, b.time_s) {
                (Some(ta), Some(tb)) => tb - ta <= gap_s,
                (None, None) => true,
                _ => false,
            };
            if !(same_setup && close) {
                current += 1;
            }
        }
        group[i] = current;
    }
    group
}

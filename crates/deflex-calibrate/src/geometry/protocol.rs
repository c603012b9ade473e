//! The held-out protocol a user meets: a calibrated robot, a new measuring session (or a new
//! probe), a handful of readings to register it, and the accuracy on everything else.
//!
//! For a group of absolute rows (a test series, a left-out session): draw
//! [`HeldOutProtocol::register_readings`] of its configurations at random, register the group's
//! set-up (and, for a new probe, its target) on them with the robot frozen
//! ([`crate::geometry::register`]), predict the group's other readings and score them; repeat for
//! [`HeldOutProtocol::draws`] draws and pool the errors. With `register_readings` 0 the group's
//! configurations alternate (every other one registers, the rest score; one draw).
//! A target no fitted reading has seen (another probe) is registered with the set-up whatever
//! the protocol says. Orientation errors are the angle of `R_measured · R_predictedᵀ`.

use crate::geometry::campaign::Campaign;
use crate::geometry::fit::HeldOutProtocol;
use crate::geometry::params::EgModel;
use crate::geometry::register::{self, RegisterOptions, start};
use crate::geometry::solve::Loss;
use crate::stats::ErrorNormStats;
use deflex_model::spatial::rotation_log;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeSet;

/// A held-out group's score under the protocol.
#[derive(Clone, Debug, PartialEq)]
pub struct GroupScore {
    /// Position errors of the scored readings, pooled over the draws (m).
    pub position: ErrorNormStats,
    /// Orientation errors (rad), when the readings measure orientations.
    pub orientation: Option<ErrorNormStats>,
    /// Position RMS of each draw (m).
    pub draw_rms: Vec<f64>,
    /// Readings registered per draw.
    pub registered: usize,
}

/// Score absolute rows `rows` (all in set-up `setup`) of `campaign` under `protocol` (module
/// documentation). Returns the score and the model registered by the first draw.
pub fn score_group(
    model: &EgModel,
    campaign: &Campaign,
    rows: &[usize],
    setup: usize,
    protocol: &HeldOutProtocol,
    loss: Loss,
    rng: &mut ChaCha8Rng,
) -> (GroupScore, EgModel) {
    let mut configs: Vec<usize> = rows.iter().map(|&i| campaign.config_of[i]).collect();
    configs.sort_unstable();
    configs.dedup();
    let target = rows.first().map(|&i| campaign.target_of[i]);
    // A target no fitted reading has seen (a new probe in a held-out series) is always
    // registered with the set-up.
    let register_target = protocol.register_target
        || target.is_some_and(|t| model.targets[t].position == nalgebra::Vector3::zeros());
    let draws = if protocol.register_readings == 0 {
        1
    } else {
        protocol.draws
    };
    let mut position = Vec::new();
    let mut orientation = Vec::new();
    let mut draw_rms = Vec::new();
    let mut first = None;
    let mut registered = 0;
    let mut in_group = vec![false; campaign.absolute.len()];
    for &i in rows {
        in_group[i] = true;
    }
    for _ in 0..draws {
        let chosen: BTreeSet<usize> = if protocol.register_readings == 0 {
            configs.iter().copied().step_by(2).collect()
        } else {
            let mut shuffled = configs.clone();
            shuffled.shuffle(rng);
            shuffled
                .into_iter()
                .take(protocol.register_readings)
                .collect()
        };
        let mult: Vec<f64> = (0..campaign.len())
            .map(|i| match campaign.absolute_row(i) {
                Some(r) if in_group[r] && chosen.contains(&campaign.config_of[r]) => 1.0,
                _ => 0.0,
            })
            .collect();
        let mut scored = model.clone();
        if protocol.register_target
            && let Some(t) = target
        {
            scored.targets[t].position = nalgebra::Vector3::zeros();
            scored.targets[t].rotation = None;
        }
        let options = RegisterOptions {
            setup,
            target: target.filter(|_| register_target),
            loss,
            recalibrate_above_m: None,
            restart_setup: true,
        };
        match register::register(&mut scored, campaign, &mult, &options) {
            Ok(r) => registered = r.readings,
            // Too few readings in this group to register: nothing to score.
            Err(_) => continue,
        }
        if let Some(t) = target
            && scored.targets[t].rotation.is_none()
        {
            start::initialise_target_rotations(&mut scored, campaign, &[t], &mult);
        }
        let scored_from = position.len();
        for &i in rows.iter().filter(|&&i| mult[i] == 0.0) {
            let (p, o) = row_errors(&scored, campaign, i);
            position.push(p);
            orientation.extend(o);
        }
        draw_rms.push(ErrorNormStats::of(&position[scored_from..]).rms);
        if first.is_none() {
            first = Some(scored);
        }
    }
    (
        GroupScore {
            position: ErrorNormStats::of(&position),
            orientation: (!orientation.is_empty()).then(|| ErrorNormStats::of(&orientation)),
            draw_rms,
            registered,
        },
        first.unwrap_or_else(|| model.clone()),
    )
}

/// Position error norm (m) and, when measured and the target's rotation is known, orientation
/// error angle (rad) of absolute row `i`.
pub fn row_errors(model: &EgModel, campaign: &Campaign, i: usize) -> (f64, Option<f64>) {
    let row = &campaign.absolute[i];
    let (s, t) = (campaign.setup_of[i], campaign.target_of[i]);
    let ev = model.evaluate(&row.q_rad, t, &campaign.conditions(model, i));
    let position =
        (nalgebra::Vector3::from(row.position_m) - model.tracker_position(&ev, s)).norm();
    let orientation = match (campaign.measured_orientation(i), model.targets[t].rotation) {
        (Some(measured), Some(_)) => {
            Some(rotation_log(&(measured * model.tracker_orientation(&ev, s).inverse())).norm())
        }
        _ => None,
    };
    (position, orientation)
}

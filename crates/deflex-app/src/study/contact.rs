//! Stiff contact (issue 11, items 3–4): the correction loop against a stiff fixture, where it is
//! positive feedback (see `deflex_sim::fixture` and `deflex_control::runaway`). The twin plunges
//! the tool 1 mm into a fixture of contact stiffness k and traverses 20 mm at that depth
//! ([`deflex_sim::PlungeParams`]) three times: without correction, with the correction and no
//! runaway guard, and with the correction and the controller's runaway guard (as configured,
//! on by default). The numbers show how far the force runs away without the guard and where the
//! guard holds it.

use crate::study::DemoError;
use deflex_control::ControllerConfig;
use deflex_model::Robot;
use deflex_sim::twin::{ClosedLoopRun, controller_config_for, run_closed_loop};
use deflex_sim::{CellConfig, FormingRun, PlungeParams, ProcessKind, ToolPath};
use serde::Serialize;

/// What one closed-loop plunge measured.
#[derive(Clone, Debug, Serialize)]
#[allow(non_snake_case)]
pub struct ContactLoopNumbers {
    /// The runaway guard was on.
    pub guard: bool,
    /// Largest contact force (N).
    pub max_force_N: f64,
    /// Largest contact force over the largest one without correction.
    pub force_ratio_to_uncorrected: f64,
    /// Largest correction applied (mm).
    pub max_correction_mm: f64,
    /// The controller's latched fault, if any (the force trip is what stops an unguarded run).
    pub fault: Option<String>,
    /// Simulated time at which the force first exceeded twice the uncorrected maximum (s).
    pub runaway_at_s: Option<f64>,
    /// Times the guard acted (`contact_runaway` warnings).
    pub runaway_warnings: u64,
    /// The first `contact_runaway` the guard reported (text with its time).
    pub first_runaway: Option<String>,
}

/// What one stiff-contact comparison measured.
#[derive(Clone, Debug, Serialize)]
#[allow(non_snake_case)]
pub struct StiffContactNumbers {
    /// Contact stiffness of the fixture (N/m).
    pub stiffness_n_m: f64,
    /// Programmed interference (mm).
    pub interference_mm: f64,
    /// Largest contact force without correction (N).
    pub open_max_force_N: f64,
    /// Force the rigid-robot interference asks for, `k · interference` (N): where an exact
    /// correction would take the force.
    pub rigid_robot_force_N: f64,
    /// With the correction and no runaway guard.
    pub unguarded: ContactLoopNumbers,
    /// With the correction and the runaway guard.
    pub guarded: ContactLoopNumbers,
}

/// The three runs behind [`StiffContactNumbers`].
pub struct StiffContactRuns {
    /// Without correction.
    pub open: FormingRun,
    /// With the correction, no guard.
    pub unguarded: ClosedLoopRun,
    /// With the correction and the guard.
    pub guarded: ClosedLoopRun,
}

/// The plunge cell: the cell with its process switched to the fixture of stiffness `k`.
pub fn fixture_cell(cell: &CellConfig, stiffness_n_m: f64) -> CellConfig {
    let mut c = cell.clone();
    c.process.kind = ProcessKind::Fixture;
    c.process.fixture_stiffness_n_m = stiffness_n_m;
    c
}

fn loop_numbers(run: &ClosedLoopRun, guard: bool, open_max: f64) -> ContactLoopNumbers {
    let summary = &run.forming.summary;
    ContactLoopNumbers {
        guard,
        max_force_N: summary.max_force_norm_N,
        force_ratio_to_uncorrected: summary.max_force_norm_N / open_max,
        max_correction_mm: summary.max_correction_mm,
        fault: run.fault.map(|f| f.to_string()),
        runaway_at_s: run
            .forming
            .log
            .rows
            .iter()
            .find(|r| r.truth.force_norm_n() > 2.0 * open_max)
            .map(|r| r.time_s),
        runaway_warnings: run.runaway_events,
        first_runaway: run.first_runaway.map(|f| f.to_string()),
    }
}

/// The default plunge ([`PlungeParams::default`]) without correction, with it unguarded and
/// with it guarded (`model` in the controller; `configure` adjusts the cell's controller
/// configuration for both closed-loop runs, after which the unguarded run has its guard turned
/// off).
pub fn stiff_contact(
    cell: &CellConfig,
    model: &Robot,
    stiffness_n_m: f64,
    seed: u64,
    configure: &dyn Fn(&mut ControllerConfig),
) -> Result<(StiffContactNumbers, StiffContactRuns), DemoError> {
    stiff_contact_with(
        cell,
        model,
        stiffness_n_m,
        &PlungeParams::default(),
        seed,
        configure,
    )
}

/// [`stiff_contact`] on the plunge `params`.
pub fn stiff_contact_with(
    cell: &CellConfig,
    model: &Robot,
    stiffness_n_m: f64,
    params: &PlungeParams,
    seed: u64,
    configure: &dyn Fn(&mut ControllerConfig),
) -> Result<(StiffContactNumbers, StiffContactRuns), DemoError> {
    let path = ToolPath::plunge(params)?;
    let c = fixture_cell(cell, stiffness_n_m);
    let open = deflex_sim::run_forming(&c, path.clone(), seed, None)?;
    let mut guarded_config = controller_config_for(&c);
    configure(&mut guarded_config);
    let mut unguarded_config = guarded_config;
    unguarded_config.runaway.enabled = false;
    let closed = |config: ControllerConfig| {
        run_closed_loop(
            &c,
            path.clone(),
            seed,
            model.clone(),
            config,
            false,
            &mut |_| {},
        )
        .map_err(DemoError::from)
    };
    let unguarded = closed(unguarded_config)?;
    let guarded = closed(guarded_config)?;
    let open_max = open.summary.max_force_norm_N;
    let numbers = StiffContactNumbers {
        stiffness_n_m,
        interference_mm: params.depth_mm,
        open_max_force_N: open_max,
        rigid_robot_force_N: stiffness_n_m * params.depth_mm * 1e-3,
        unguarded: loop_numbers(&unguarded, false, open_max),
        guarded: loop_numbers(&guarded, guarded_config.runaway.enabled, open_max),
    };
    Ok((
        numbers,
        StiffContactRuns {
            open,
            unguarded,
            guarded,
        },
    ))
}

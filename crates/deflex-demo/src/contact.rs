//! Stiff contact (issue 11, item 3): the correction loop against a stiff fixture, where it is
//! positive feedback (see `deflex_sim::fixture`). The twin plunges the tool 1 mm into a fixture
//! of contact stiffness k and traverses 20 mm at that depth ([`deflex_sim::PlungeParams`]),
//! without and with the correction; the numbers show how far the force runs away.

use crate::twin_controller::{ClosedLoopRun, controller_config_for, run_closed_loop};
use deflex_model::Robot;
use deflex_sim::{CellConfig, FormingRun, PlungeParams, ProcessKind, ToolPath};
use serde::Serialize;

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
    /// Largest contact force with correction (N).
    pub closed_max_force_N: f64,
    /// Force the rigid-robot interference asks for, `k · interference` (N): where an exact
    /// correction would take the force.
    pub rigid_robot_force_N: f64,
    /// Largest correction applied (mm).
    pub closed_max_correction_mm: f64,
    /// The controller's latched fault, if any (the force trip is what stops an unguarded run).
    pub fault: Option<String>,
    /// Simulated time at which the closed-loop force first exceeded twice the open-loop maximum
    /// (s), if it did.
    pub runaway_at_s: Option<f64>,
}

/// The plunge cell: the cell with its process switched to the fixture of stiffness `k`.
pub fn fixture_cell(cell: &CellConfig, stiffness_n_m: f64) -> CellConfig {
    let mut c = cell.clone();
    c.process.kind = ProcessKind::Fixture;
    c.process.fixture_stiffness_n_m = stiffness_n_m;
    c
}

/// Plunge without and with the correction (`model` in the controller, the cell's controller
/// configuration as `configure` leaves it).
pub fn stiff_contact(
    cell: &CellConfig,
    model: &Robot,
    stiffness_n_m: f64,
    seed: u64,
    configure: &dyn Fn(&mut deflex_control::ControllerConfig),
) -> Result<(StiffContactNumbers, FormingRun, ClosedLoopRun), String> {
    let params = PlungeParams::default();
    let path = ToolPath::plunge(&params).map_err(|e| e.to_string())?;
    let c = fixture_cell(cell, stiffness_n_m);
    let open = deflex_sim::run_forming(&c, path.clone(), seed, None).map_err(|e| e.to_string())?;
    let mut config = controller_config_for(&c);
    configure(&mut config);
    let closed = run_closed_loop(&c, path, seed, model.clone(), config, false, &mut |_| {})?;
    let open_max = open.summary.max_force_norm_N;
    let runaway_at_s = closed
        .forming
        .log
        .rows
        .iter()
        .find(|r| r.truth.wrench.fixed_rows::<3>(0).norm() > 2.0 * open_max)
        .map(|r| r.time_s);
    let numbers = StiffContactNumbers {
        stiffness_n_m,
        interference_mm: params.depth_mm,
        open_max_force_N: open_max,
        closed_max_force_N: closed.forming.summary.max_force_norm_N,
        rigid_robot_force_N: stiffness_n_m * params.depth_mm * 1e-3,
        closed_max_correction_mm: closed.forming.summary.max_correction_mm,
        fault: closed.fault.map(|f| f.to_string()),
        runaway_at_s,
    };
    Ok((numbers, open, closed))
}

/// Force along the plunge without and with the correction (PNG).
pub fn contact_figure(
    path: &std::path::Path,
    open: &FormingRun,
    closed: &FormingRun,
    stiffness_n_m: f64,
) -> Result<(), String> {
    let series = |run: &FormingRun, label: &str| {
        deflex_report::Series::line(
            label,
            run.log.column(|r| r.time_s),
            run.log.column(|r| r.truth.wrench.fixed_rows::<3>(0).norm()),
        )
    };
    deflex_report::line_plot(
        path,
        &deflex_report::PlotSpec::new(
            format!(
                "SIMULATED — plunge into a {stiffness_n_m:.0e} N/m fixture: contact force without and with correction"
            ),
            "time [s]",
            "contact force norm [N]",
        )
        .size(1000, 500),
        &[
            series(open, "without correction"),
            series(closed, "with correction (no runaway guard)"),
        ],
    )
    .map_err(|e| e.to_string())
}

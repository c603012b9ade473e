//! The study pipeline: plan → campaign → identification → validation → forming → stiff contact
//! → sensitivity → compensation, computed in memory ([`run_study`]); its files, figures and page
//! are `crate::report::study`'s.

use crate::study::DemoError;
use crate::study::compensation::PartRuns;
use crate::study::conditions::{conditions, one_edof_start};
use crate::study::contact::StiffContactRuns;
use crate::study::numbers::{error_numbers, grid_rows, stiffness_rows};
use crate::study::sensitivity::{SensitivityPlan, run_sensitivity};
use crate::study::summary::{
    BASELINE, DemoSummary, FormingNumbers, IDENTIFIED, ModelErrorNumbers, TABLE1,
};
use deflex_calibrate::measurements::MeasurementRow;
use deflex_calibrate::stiffness::plan::{Plan, PlanOptions, plan_experiments};
use deflex_calibrate::stiffness::validation::predict;
use deflex_calibrate::stiffness::{
    SearchOptions, SearchResult, Structure, calibrate_fixed, search_structure,
};
use deflex_model::Robot;
use deflex_sim::profile::Maker;
use deflex_sim::twin::{ClosedLoopRun, controller_config_for, run_closed_loop};
use deflex_sim::twin_campaign::{GridParams, SpiralParams, run_campaign, spiral, validation_grid};
use deflex_sim::{CellConfig, FormingRun, ToolPath, run_forming_with_progress};
use deflex_telemetry::{OnProgress, Progress};
use std::time::Instant;

/// What to run.
#[derive(Clone, Debug)]
pub struct DemoOptions {
    /// Seed of every random draw (campaign noise, sensor noise, planner).
    pub seed: u64,
    /// A shortened study for tests: fewer load cases, a short spiral, the first part of the cone,
    /// a 2 × 2 sensitivity on a short path.
    pub quick: bool,
    /// The robot the twin plays (built-in name or robot file) as the user named it: the cell
    /// given to [`run_study`] is this robot's (`deflex_app::cell::twin_cell_file::cell_for_robot`). The paper's
    /// comparisons are shown for the TX200 only.
    pub robot: String,
    /// Run the sensitivity section.
    pub sensitivity: bool,
}

impl Default for DemoOptions {
    fn default() -> Self {
        DemoOptions {
            seed: 1,
            quick: false,
            robot: "tx200".into(),
            sensitivity: true,
        }
    }
}

/// The study's stages, each reported as `Progress::Stage { index, count: Some(STAGES), .. }`,
/// its work in per mille ([`Progress::per_mille`]; the identification's as the structure
/// search's candidates) and its one-line result (`Progress::Done`).
pub const STAGES: usize = 10;

/// Predicted displacements (m) of every row, per model: `(model name, one per row)`.
pub type Predictions = Vec<(&'static str, Vec<[f64; 3]>)>;

/// Everything the study computed: its numbers ([`Study::summary`], `summary.json`) and the data
/// behind its files and figures.
pub struct Study {
    /// The numbers.
    pub summary: DemoSummary,
    /// The twin's cell.
    pub cell: CellConfig,
    /// The cell's nominal robot (what the planner and the controller start from).
    pub nominal: Robot,
    /// The calibration campaign's plan.
    pub plan: Plan,
    /// The campaign measured on the twin (SIMULATED).
    pub campaign: Vec<MeasurementRow>,
    /// The structure search.
    pub search: SearchResult,
    /// The identified model.
    pub identified: Robot,
    /// The one-eDoF-per-joint model calibrated on the same campaign.
    pub baseline: Robot,
    /// The Fig. 7 test's rows (empty for robots other than the TX200); its points are in the
    /// summary.
    pub fig7_rows: Vec<MeasurementRow>,
    /// The validation grid's parameters.
    pub grid_params: GridParams,
    /// The grid measured on the twin.
    pub grid: Vec<MeasurementRow>,
    /// Every model's prediction of the grid.
    pub grid_predictions: Predictions,
    /// The spiral's parameters.
    pub spiral_params: SpiralParams,
    /// The spiral measured on the twin.
    pub spiral: Vec<MeasurementRow>,
    /// Every model's prediction of the spiral.
    pub spiral_predictions: Predictions,
    /// The cone without correction.
    pub open: FormingRun,
    /// The cone with the correction (and the controller's per-cycle trace).
    pub closed: ClosedLoopRun,
    /// The plunge into the 10⁷ N/m fixture: the three runs.
    pub plunge: StiffContactRuns,
    /// The runs of the compensation comparison: the cone, then the CAM part.
    pub compensation_runs: [PartRuns; 2],
}

/// Stage timings of the run (`summary.json`'s `stage_seconds`).
struct Timings(Vec<(String, f64)>);

impl Timings {
    /// Run `work`, timing it as `name`.
    fn time<T>(&mut self, name: &str, work: impl FnOnce() -> T) -> T {
        let clock = Instant::now();
        let out = work();
        self.0
            .push((name.to_string(), clock.elapsed().as_secs_f64()));
        out
    }
}

/// The identified model and the baseline, with the search behind them.
struct Identification {
    search: SearchResult,
    identified: Robot,
    baseline: Robot,
}

/// Run the whole study on `cell` (the cell of `options.robot`), in memory; `progress` hears of
/// every stage (see [`STAGES`]). Write it with `crate::report::study::write_study`.
pub fn run_study(
    options: &DemoOptions,
    cell: CellConfig,
    progress: OnProgress<'_>,
) -> Result<Study, DemoError> {
    let seed = options.seed;
    let nominal = cell.nominal_robot()?;
    let paper_comparison = Maker::of(&options.robot, &nominal.name) == Maker::StaubliTx200;
    let mut timings = Timings(Vec::new());

    // 1–2. Plan and campaign.
    let plan = timings.time("plan", || plan_stage(options, &cell, &nominal, progress))?;
    let load_cases = deflex_calibrate::measurements::load_case_count(&plan.rows);
    let campaign = timings.time("campaign", || {
        progress(Progress::Stage {
            index: 2,
            count: Some(STAGES),
            name: "simulate the campaign (tracker noise)",
        });
        let campaign = run_campaign(&cell, &plan.rows, seed)?;
        progress(Progress::Done {
            note: &format!("{} measured points", campaign.len()),
        });
        Ok::<_, DemoError>(campaign)
    })?;

    // 3. Identification.
    let id = timings.time("identification", || identify(&nominal, &campaign, progress))?;
    let plant_robot = cell.plant.linear_robot(&nominal)?;
    let stiffness = stiffness_rows(&id.search, &plant_robot);
    let models: [(&'static str, &Robot); 3] = [
        (IDENTIFIED, &id.identified),
        (BASELINE, &id.baseline),
        (TABLE1, &nominal),
    ];

    // The paper's Figs. 8–9: M1–M3 at the Fig. 7 configuration (TX200 only).
    let (fig7_rows, fig7) = if paper_comparison {
        timings.time("Fig. 7 test", || {
            crate::study::fig7::fig7_study(&cell, &nominal, &models, seed.wrapping_add(3))
        })?
    } else {
        (Vec::new(), Vec::new())
    };

    // 4–5. Validation on the grid and along the spiral.
    let (grid_params, grid, grid_predictions, mut validation) = timings
        .time("grid validation", || {
            grid_stage(&cell, seed, &models, progress)
        })?;
    let (spiral_params, spiral_rows, spiral_predictions) = timings
        .time("spiral validation", || {
            spiral_stage(options, &cell, &models, &mut validation, progress)
        })?;

    // 6–7. Forming without and with correction.
    let path = if options.quick {
        ToolPath::paper_cone().truncated(1500.0)
    } else {
        ToolPath::paper_cone()
    };
    let open = timings.time("forming without correction", || {
        progress(Progress::Stage {
            index: 6,
            count: Some(STAGES),
            name: "form the cone without correction",
        });
        let open = run_forming_with_progress(&cell, path.clone(), seed, None, &mut |f| {
            progress(Progress::per_mille(f))
        })?;
        progress(Progress::Done {
            note: &format!(
                "max error norm {:.2} mm, max |F| {:.0} N",
                open.summary.max_error_norm_mm, open.summary.max_force_norm_N
            ),
        });
        Ok::<_, DemoError>(open)
    })?;
    let closed = timings.time("forming with correction", || {
        closed_loop_stage(&cell, &path, seed, &id.identified, &open, progress)
    })?;
    let improvement =
        100.0 * (1.0 - closed.forming.summary.max_error_norm_mm / open.summary.max_error_norm_mm);

    // 8. Stiff contact.
    let (stiff_contact, stiff_contact_sweep, plunge) = timings.time("stiff contact", || {
        stiff_contact_stage(options, &cell, &id.identified, progress)
    })?;

    // 9. Sensitivity.
    let sensitivity = timings.time("sensitivity", || {
        sensitivity_stage(options, &cell, &id.identified, progress)
    })?;

    // 10. Offline, online and both.
    let (compensation, compensation_runs) = timings.time("compensation", || {
        progress(Progress::Stage {
            index: 10,
            count: Some(STAGES),
            name: "compare offline compensation, online correction and both",
        });
        let (study, runs) = crate::study::compensation::study(
            &cell,
            &id.identified,
            seed,
            options.quick,
            (&path, &open, &closed.forming),
        )?;
        progress(Progress::Done {
            note: &crate::study::compensation::one_line(&study),
        });
        Ok::<_, DemoError>((study, runs))
    })?;

    let summary = DemoSummary {
        simulated: true,
        robot: nominal.name.clone(),
        robot_spec: options.robot.clone(),
        paper_comparison,
        conditions: conditions(&cell),
        seed,
        quick: options.quick,
        campaign_load_cases: load_cases,
        campaign_rows: campaign.len(),
        identified_structure: id.search.calibration.structure.label(),
        search_steps: id.search.steps.len().saturating_sub(1),
        search_stop_reason: id.search.stop_reason.clone(),
        identification_rms_um: id.search.calibration.residuals.rms_all_m * 1e6,
        identification_reduced_chi2: id.search.calibration.reduced_chi2,
        stiffness,
        validation,
        fig7,
        forming_open: FormingNumbers::from_run(&open),
        forming_closed: FormingNumbers::from_run(&closed.forming),
        improvement_percent: improvement,
        controller_status: closed.status.clone(),
        stiff_contact,
        stiff_contact_sweep,
        sensitivity,
        compensation,
        stage_seconds: timings.0,
    };
    Ok(Study {
        summary,
        cell,
        nominal,
        plan,
        campaign,
        search: id.search,
        identified: id.identified,
        baseline: id.baseline,
        fig7_rows,
        grid_params,
        grid,
        grid_predictions,
        spiral_params,
        spiral: spiral_rows,
        spiral_predictions,
        open,
        closed,
        plunge,
        compensation_runs,
    })
}

/// Stage 1: plan the calibration campaign in the cell's floor and work table.
fn plan_stage(
    options: &DemoOptions,
    cell: &CellConfig,
    nominal: &Robot,
    progress: OnProgress<'_>,
) -> Result<Plan, DemoError> {
    progress(Progress::Stage {
        index: 1,
        count: Some(STAGES),
        name: "plan the calibration campaign",
    });
    let paper_comparison = Maker::of(&options.robot, &nominal.name) == Maker::StaubliTx200;
    let level = cell.forming_force_level_n();
    let plan_options = PlanOptions {
        // The paper loads its TX200 to 1.4 kN; other cells to 1.1 × their forming force.
        max_force_n: if paper_comparison {
            1400.0
        } else {
            (1.1 * level / 10.0).round() * 10.0
        },
        load_cases: if options.quick { 24 } else { 40 },
        configurations: if options.quick { 300 } else { 600 },
        seed: options.seed,
        full_family: true,
        // The cell's floor and work table, as `deflex plan` checks them.
        ..PlanOptions::for_a_real_cell()
    };
    let plan = plan_experiments(nominal, &plan_options)?;
    progress(Progress::Done {
        note: &format!(
            "{} load cases, {} points to measure",
            deflex_calibrate::measurements::load_case_count(&plan.rows),
            plan.rows.len()
        ),
    });
    Ok(plan)
}

/// Stage 3: structure search from one z-eDoF per joint, and the one-eDoF baseline calibrated on
/// the same data.
fn identify(
    nominal: &Robot,
    campaign: &[MeasurementRow],
    progress: OnProgress<'_>,
) -> Result<Identification, DemoError> {
    progress(Progress::Stage {
        index: 3,
        count: Some(STAGES),
        name: "identify the model structure and stiffnesses",
    });
    let start = one_edof_start(nominal);
    let search = search_structure(
        &start,
        campaign,
        &SearchOptions::default(),
        // The search's work is this stage's; its steps stay inside it.
        &mut |p| {
            if let Progress::Work { .. } = p {
                progress(p)
            }
        },
    )?;
    let mut identified = search.calibration.to_robot(&start);
    identified.name = format!(
        "deflex-identified {} (from the SIMULATED twin campaign)",
        nominal.name
    );
    let baseline_calibration = calibrate_fixed(&start, campaign, &Structure::from_robot(&start))?;
    let mut baseline = baseline_calibration.to_robot(&start);
    baseline.name = "one eDoF per joint, calibrated on the SIMULATED twin campaign".into();
    progress(Progress::Done {
        note: &format!(
            "{} in {} steps, RMS residual {:.1} µm",
            search.calibration.structure.label(),
            search.steps.len().saturating_sub(1),
            search.calibration.residuals.rms_all_m * 1e6
        ),
    });
    Ok(Identification {
        search,
        identified,
        baseline,
    })
}

/// Every model's prediction of `rows`.
fn predictions(
    models: &[(&'static str, &Robot)],
    rows: &[MeasurementRow],
) -> Result<Predictions, DemoError> {
    let mut out = Vec::new();
    for (name, robot) in models {
        out.push((*name, predict(robot, rows)?));
    }
    Ok(out)
}

/// Stage 4: the grid of dead-weight loads measured on the twin, predicted by every model, with
/// the error numbers per load.
fn grid_stage(
    cell: &CellConfig,
    seed: u64,
    models: &[(&'static str, &Robot)],
    progress: OnProgress<'_>,
) -> Result<
    (
        GridParams,
        Vec<MeasurementRow>,
        Predictions,
        Vec<ModelErrorNumbers>,
    ),
    DemoError,
> {
    progress(Progress::Stage {
        index: 4,
        count: Some(STAGES),
        name: "validate on the grid of dead-weight loads",
    });
    let grid_params = GridParams::for_cell(cell)?;
    let grid_plan = validation_grid(cell, &grid_params)?;
    let grid = run_campaign(cell, &grid_plan, seed.wrapping_add(1))?;
    let grid_predictions = predictions(models, &grid)?;
    let mut validation = Vec::new();
    for &load in &grid_params.loads_n {
        let selected = grid_rows(&grid, load);
        for (name, predicted) in &grid_predictions {
            validation.push(error_numbers(
                name,
                &format!("grid {load:.0} N"),
                &grid,
                predicted,
                &selected,
            ));
        }
    }
    let last = validation.len().saturating_sub(3);
    progress(Progress::Done {
        note: &format!(
            "δz RMS at {:.0}/{:.0} N: identified {:.3}/{:.3} mm, one-eDoF {:.3}/{:.3} mm",
            grid_params.loads_n[0],
            grid_params.loads_n[grid_params.loads_n.len() - 1],
            validation[0].rms_z_mm,
            validation[last].rms_z_mm,
            validation[1].rms_z_mm,
            validation[last + 1].rms_z_mm
        ),
    });
    Ok((grid_params, grid, grid_predictions, validation))
}

/// Stage 5: the spiral (Fig. 14) tracked on the twin and predicted by every model; its error
/// numbers are appended to `validation`.
fn spiral_stage(
    options: &DemoOptions,
    cell: &CellConfig,
    models: &[(&'static str, &Robot)],
    validation: &mut Vec<ModelErrorNumbers>,
    progress: OnProgress<'_>,
) -> Result<(SpiralParams, Vec<MeasurementRow>, Predictions), DemoError> {
    progress(Progress::Stage {
        index: 5,
        count: Some(STAGES),
        name: "validate along the spiral",
    });
    let mut spiral_params = SpiralParams::for_cell(cell)?;
    if options.quick {
        spiral_params.length_m *= 0.3 / 2.7;
    }
    let spiral_rows = spiral(cell, &spiral_params, options.seed.wrapping_add(2))?;
    let all: Vec<usize> = (0..spiral_rows.len()).collect();
    let spiral_label = format!("spiral {:.0} N", spiral_params.load_n);
    let spiral_predictions = predictions(models, &spiral_rows)?;
    for (name, predicted) in &spiral_predictions {
        validation.push(error_numbers(
            name,
            &spiral_label,
            &spiral_rows,
            predicted,
            &all,
        ));
    }
    let spiral_identified = &validation[validation.len() - 3];
    progress(Progress::Done {
        note: &format!(
            "{} samples, identified δz RMS {:.3} mm",
            spiral_rows.len(),
            spiral_identified.rms_z_mm
        ),
    });
    Ok((spiral_params, spiral_rows, spiral_predictions))
}

/// Stage 7: the cone with the online correction by the identified model.
fn closed_loop_stage(
    cell: &CellConfig,
    path: &ToolPath,
    seed: u64,
    identified: &Robot,
    open: &FormingRun,
    progress: OnProgress<'_>,
) -> Result<ClosedLoopRun, DemoError> {
    progress(Progress::Stage {
        index: 7,
        count: Some(STAGES),
        name: "form the cone with online correction",
    });
    let closed = run_closed_loop(
        cell,
        path.clone(),
        seed,
        identified.clone(),
        controller_config_for(cell),
        true,
        &mut |f| progress(Progress::per_mille(f)),
    )
    .map_err(DemoError::from)?;
    let improvement =
        100.0 * (1.0 - closed.forming.summary.max_error_norm_mm / open.summary.max_error_norm_mm);
    progress(Progress::Done {
        note: &format!(
            "max error norm {:.2} mm ({improvement:.0} % better), max |F| {:.0} N",
            closed.forming.summary.max_error_norm_mm, closed.forming.summary.max_force_norm_N
        ),
    });
    Ok(closed)
}

/// Stage 8: the plunge into a 10⁷ N/m fixture (its runs kept for the figure) and the sweep over
/// fixture stiffnesses.
fn stiff_contact_stage(
    options: &DemoOptions,
    cell: &CellConfig,
    identified: &Robot,
    progress: OnProgress<'_>,
) -> Result<
    (
        crate::study::contact::StiffContactNumbers,
        Vec<crate::study::contact::StiffContactNumbers>,
        StiffContactRuns,
    ),
    DemoError,
> {
    progress(Progress::Stage {
        index: 8,
        count: Some(STAGES),
        name: "plunge into a stiff fixture (1e7 N/m)",
    });
    let seed = options.seed;
    let (stiff_contact, plunge_runs) =
        crate::study::contact::stiff_contact(cell, identified, 1e7, seed, &|_| {})?;
    let mut sweep_numbers = Vec::new();
    let sweep: &[f64] = if options.quick {
        &[]
    } else {
        &[1e5, 1e6, 1e7, 1e8]
    };
    for &k in sweep {
        if k == stiff_contact.stiffness_n_m {
            sweep_numbers.push(stiff_contact.clone());
            continue;
        }
        let (numbers, _) =
            crate::study::contact::stiff_contact(cell, identified, k, seed, &|_| {})?;
        sweep_numbers.push(numbers);
    }
    let (u, g) = (&stiff_contact.unguarded, &stiff_contact.guarded);
    progress(Progress::Done {
        note: &format!(
            "max |F| {:.0} N uncorrected, {:.0} N corrected without guard{}, {:.0} N with guard{}",
            stiff_contact.open_max_force_N,
            u.max_force_N,
            u.fault
                .as_ref()
                .map(|f| format!(" ({f})"))
                .unwrap_or_default(),
            g.max_force_N,
            if g.runaway_warnings > 0 {
                " (contact_runaway)"
            } else {
                ""
            }
        ),
    });
    Ok((stiff_contact, sweep_numbers, plunge_runs))
}

/// Stage 9: the sensitivity of the closed loop (when asked for).
fn sensitivity_stage(
    options: &DemoOptions,
    cell: &CellConfig,
    identified: &Robot,
    progress: OnProgress<'_>,
) -> Result<Option<crate::study::sensitivity::SensitivityResult>, DemoError> {
    progress(Progress::Stage {
        index: 9,
        count: Some(STAGES),
        name: "sensitivity of the closed loop",
    });
    if !options.sensitivity {
        progress(Progress::Done { note: "skipped" });
        return Ok(None);
    }
    let plan = if options.quick {
        SensitivityPlan {
            delays_s: vec![0.008, 0.060],
            model_scales: vec![1.0, 1.3],
            gain_errors: vec![],
            drift_factors: vec![],
            contact_stiffness_n_m: vec![],
            threads: 2,
            length_mm: Some(300.0),
        }
    } else {
        SensitivityPlan::demo()
    };
    let fraction = std::sync::Mutex::new(0.0f64);
    let result = run_sensitivity(cell, identified, &plan, options.seed, &|f| {
        if let Ok(mut v) = fraction.lock() {
            *v = f;
        }
    })?;
    progress(Progress::per_mille(1.0));
    let worst = result
        .rows
        .iter()
        .map(|r| r.improvement_percent)
        .fold(f64::INFINITY, f64::min);
    progress(Progress::Done {
        note: &format!("{} runs, worst improvement {worst:.0} %", result.runs),
    });
    Ok(Some(result))
}

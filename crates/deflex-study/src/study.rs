//! The study pipeline: plan → campaign → identification → validation → forming → report.

use crate::conditions::{conditions, one_edof_start};
use crate::sensitivity::{SensitivityPlan, run_sensitivity};
use crate::tables::{
    error_numbers, grid_rows, paper_vs_deflex_csv, predictions_csv, stiffness_csv, stiffness_rows,
    write_text,
};
use crate::twin_controller::{controller_config_for, run_closed_loop};
use deflex_stiffness::plan::{PlanOptions, plan_experiments};
use deflex_stiffness::validate::predict;
use deflex_stiffness::{SearchOptions, Structure, calibrate_fixed, search_structure};
use deflex_model::{Robot, robot_to_toml};
use deflex_sim::campaign::{
    GridParams, SpiralParams, campaign_text, run_campaign, spiral, validation_grid,
};
use deflex_sim::profile::Maker;
use deflex_sim::{CellConfig, FormingRun, ToolPath, run_forming_with_progress};
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;

/// What to run.
#[derive(Clone, Debug)]
pub struct DemoOptions {
    /// Output folder (built aside and swapped in whole at the end).
    pub out_dir: PathBuf,
    /// Seed of every random draw (campaign noise, sensor noise, planner).
    pub seed: u64,
    /// A shortened study for tests: fewer load cases, a short spiral, the first part of the cone,
    /// a 2 × 2 sensitivity on a short path.
    pub quick: bool,
    /// The robot the twin plays (built-in name or robot file): its cell comes from
    /// `deflex_sim::profile`. The paper's comparisons are shown for the TX200 only.
    pub robot: String,
    /// Run the sensitivity section.
    pub sensitivity: bool,
}

impl Default for DemoOptions {
    fn default() -> Self {
        DemoOptions {
            out_dir: PathBuf::from("deflex-report"),
            seed: 1,
            quick: false,
            robot: "tx200".into(),
            sensitivity: true,
        }
    }
}

/// Progress callbacks for a terminal front end.
pub trait Progress {
    /// A stage starts (`index` of `total`).
    fn stage(&mut self, index: usize, total: usize, name: &str);
    /// Fraction (0..1) of the current stage done.
    fn fraction(&mut self, fraction: f64);
    /// The current stage is done; `note` is a one-line result.
    fn done(&mut self, note: &str);
}

/// Prediction error of one model on one data set (δz as in the paper's Figs. 10–13, and the
/// norm), mm.
#[derive(Clone, Debug, Default, Serialize)]
pub struct ModelErrorNumbers {
    /// Model name.
    pub model: String,
    /// Data set (`grid 600 N`, `grid 1100 N`, `spiral 600 N`).
    pub data: String,
    /// Points.
    pub points: usize,
    /// RMS of the δz error (mm).
    pub rms_z_mm: f64,
    /// Largest |δz error| (mm).
    pub max_z_mm: f64,
    /// RMS of the 3D error norm (mm).
    pub rms_norm_mm: f64,
    /// Largest 3D error norm (mm).
    pub max_norm_mm: f64,
    /// RMS of the measured δz, for scale (mm).
    pub measured_rms_z_mm: f64,
}

/// One identified stiffness beside the paper's Table 1 and the twin's (simulated) truth.
#[derive(Clone, Debug, Serialize)]
pub struct StiffnessRow {
    /// eDoF label (`J3.x`) or shift (`δr3`).
    pub name: String,
    /// Identified value (N·m/rad, or m for a shift).
    pub identified: Option<f64>,
    /// Standard error.
    pub se: Option<f64>,
    /// 95 % interval.
    pub interval95: Option<(f64, f64)>,
    /// Status from the calibration.
    pub status: String,
    /// The paper's Table 1 value.
    pub table1: Option<f64>,
    /// The twin plant's linear value (SIMULATED ground truth).
    pub plant: Option<f64>,
}

/// Numbers of one forming run.
#[derive(Clone, Debug, Default, Serialize)]
#[allow(non_snake_case)]
pub struct FormingNumbers {
    /// Largest TCP error norm (mm).
    pub max_error_norm_mm: f64,
    /// RMS TCP error norm (mm).
    pub rms_error_norm_mm: f64,
    /// Largest vertical force (N).
    pub max_fz_N: f64,
    /// Largest in-plane force (N).
    pub max_fxy_N: f64,
    /// Largest force norm (N).
    pub max_force_norm_N: f64,
    /// Deepest formed point (mm).
    pub final_part_depth_mm: f64,
    /// Programmed depth (mm).
    pub target_depth_mm: f64,
    /// Simulated duration (s).
    pub duration_s: f64,
}

impl FormingNumbers {
    fn from_run(run: &FormingRun) -> Self {
        let s = &run.summary;
        FormingNumbers {
            max_error_norm_mm: s.max_error_norm_mm,
            rms_error_norm_mm: s.rms_error_norm_mm,
            max_fz_N: s.max_fz_N,
            max_fxy_N: s.max_fxy_N,
            max_force_norm_N: s.max_force_norm_N,
            final_part_depth_mm: s.final_part_depth_mm,
            target_depth_mm: s.target_depth_mm,
            duration_s: s.duration_s,
        }
    }
}

/// Everything the study measured (`summary.json`).
#[derive(Clone, Debug, Serialize)]
pub struct DemoSummary {
    /// Always true: the cell is the digital twin.
    pub simulated: bool,
    /// The robot the twin played (its description's name) and the spec it was given as.
    pub robot: String,
    /// The robot spec (`tx200`, `ur10e`, a file).
    pub robot_spec: String,
    /// The paper's comparisons apply (the TX200 cell).
    pub paper_comparison: bool,
    /// The error sources and effects of the twin, with their levels and whether they were on:
    /// `(source, level, on)`.
    pub conditions: Vec<(String, String, bool)>,
    /// Seed.
    pub seed: u64,
    /// Shortened study.
    pub quick: bool,
    /// Load cases and measured points of the campaign.
    pub campaign_load_cases: usize,
    /// Rows of the campaign file.
    pub campaign_rows: usize,
    /// Identified structure label.
    pub identified_structure: String,
    /// Search iterations accepted.
    pub search_steps: usize,
    /// Why the search stopped.
    pub search_stop_reason: String,
    /// RMS residual of the identification (µm, all components).
    pub identification_rms_um: f64,
    /// χ²/dof of the identification.
    pub identification_reduced_chi2: f64,
    /// Identified stiffnesses and shifts beside Table 1 and the plant.
    pub stiffness: Vec<StiffnessRow>,
    /// Validation errors (grid and spiral, every model).
    pub validation: Vec<ModelErrorNumbers>,
    /// The paper's Figs. 8–9 test (Fig. 7 configuration, lateral 1400 N): per point the
    /// SIMULATED measurement and each model's prediction. Empty for robots other than the TX200.
    pub fig7: Vec<crate::fig7::Fig7Point>,
    /// Forming without correction.
    pub forming_open: FormingNumbers,
    /// Forming with correction.
    pub forming_closed: FormingNumbers,
    /// `100 (1 − closed/open)` of the maximum error norm.
    pub improvement_percent: f64,
    /// Status line of the controller at the end of the corrected run.
    pub controller_status: String,
    /// The plunge into a stiff fixture (10⁷ N/m) without correction, with it unguarded and with
    /// the runaway guard.
    pub stiff_contact: crate::contact::StiffContactNumbers,
    /// The same plunge across fixture stiffnesses 10⁵–10⁸ N/m.
    pub stiff_contact_sweep: Vec<crate::contact::StiffContactNumbers>,
    /// The sensitivity study, when run.
    pub sensitivity: Option<crate::sensitivity::SensitivityResult>,
    /// Offline compensation, online correction and both, on the cone and a CAM part.
    pub compensation: crate::compensation::CompensationStudy,
    /// Wall time of each stage (s).
    pub stage_seconds: Vec<(String, f64)>,
}

impl DemoSummary {
    /// The validation numbers of one model on one data set.
    pub fn errors(&self, model: &str, data: &str) -> Option<&ModelErrorNumbers> {
        self.validation
            .iter()
            .find(|v| v.model == model && v.data == data)
    }
}

/// Model names used in the report.
pub(crate) const IDENTIFIED: &str = "identified (deflex)";
pub(crate) const BASELINE: &str = "one eDoF per joint";
pub(crate) const TABLE1: &str = "paper Table 1";

const STAGES: usize = 10;

/// Run the whole study; writes every output into `options.out_dir`, which appears whole at the
/// end (or not at all when the study fails).
pub fn run_demo(options: &DemoOptions, progress: &mut dyn Progress) -> Result<DemoSummary, String> {
    let building = deflex_files::AtomicDir::create(&options.out_dir)
        .map_err(|e| format!("{}: {e}", options.out_dir.display()))?;
    let out = building.path().to_path_buf();
    let summary = study(options, &out, progress)?;
    building
        .commit()
        .map_err(|e| format!("{}: {e}", options.out_dir.display()))?;
    Ok(summary)
}

fn study(
    options: &DemoOptions,
    out: &std::path::Path,
    progress: &mut dyn Progress,
) -> Result<DemoSummary, String> {
    let seed = options.seed;
    let cell = CellConfig::for_robot(&options.robot).map_err(|e| e.to_string())?;
    let nominal = cell.nominal_robot().map_err(|e| e.to_string())?;
    let paper_comparison = Maker::of(&options.robot, &nominal.name) == Maker::StaubliTx200;
    let mut timings = Vec::new();

    // 1. Plan.
    let clock = Instant::now();
    progress.stage(1, STAGES, "plan the calibration campaign");
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
        seed,
        full_family: true,
        // The cell's floor and work table, as `deflex plan` checks them.
        ..PlanOptions::for_a_real_cell()
    };
    let plan = plan_experiments(&nominal, &plan_options).map_err(|e| e.to_string())?;
    deflex_stiffness::data::write_rows_for(&out.join("plan.csv"), &nominal, &plan.rows, &[])
        .map_err(|e| e.to_string())?;
    let load_cases = deflex_stiffness::data::load_case_count(&plan.rows);
    progress.done(&format!(
        "{load_cases} load cases, {} points to measure",
        plan.rows.len()
    ));
    timings.push(("plan".to_string(), clock.elapsed().as_secs_f64()));

    // 2. Campaign on the twin.
    let clock = Instant::now();
    progress.stage(2, STAGES, "simulate the campaign (tracker noise)");
    let campaign = run_campaign(&cell, &plan.rows, seed).map_err(|e| e.to_string())?;
    let campaign_file = |rows: &[deflex_stiffness::MeasurementRow], what: &str, seed: u64| {
        campaign_text(&cell, rows, what, seed, None).map_err(|e| e.to_string())
    };
    write_text(
        &out.join("campaign.csv"),
        &campaign_file(&campaign, "calibration campaign", seed)?,
    )?;
    progress.done(&format!("{} measured points", campaign.len()));
    timings.push(("campaign".to_string(), clock.elapsed().as_secs_f64()));

    // 3. Identification: structure search from one z-eDoF per joint, and the one-eDoF baseline
    // calibrated on the same data.
    let clock = Instant::now();
    progress.stage(3, STAGES, "identify the model structure and stiffnesses");
    let start = one_edof_start(&nominal);
    let search = search_structure(
        &start,
        &campaign,
        &SearchOptions::default(),
        &mut |_iteration, done, total| {
            if total > 0 {
                progress.fraction(done as f64 / total as f64);
            }
        },
    )
    .map_err(|e| e.to_string())?;
    let mut identified = search.calibration.to_robot(&start);
    identified.name = format!(
        "deflex-identified {} (from the SIMULATED twin campaign)",
        nominal.name
    );
    let baseline_calibration = calibrate_fixed(&start, &campaign, &Structure::from_robot(&start))
        .map_err(|e| e.to_string())?;
    let mut baseline = baseline_calibration.to_robot(&start);
    baseline.name = "one eDoF per joint, calibrated on the SIMULATED twin campaign".into();
    write_text(&out.join("identified.toml"), &robot_to_toml(&identified))?;
    write_text(&out.join("baseline-1edof.toml"), &robot_to_toml(&baseline))?;
    write_text(
        &out.join("search_iterations.csv"),
        &deflex_stiffness::report::table_csv(
            &deflex_stiffness::report::ITERATION_HEADERS,
            &deflex_stiffness::report::iteration_rows(&search.steps),
        ),
    )?;
    let plant_robot = cell
        .plant
        .linear_robot(&nominal)
        .map_err(|e| e.to_string())?;
    let stiffness = stiffness_rows(&search, &plant_robot);
    write_text(&out.join("stiffness.csv"), &stiffness_csv(&stiffness))?;
    progress.done(&format!(
        "{} in {} steps, RMS residual {:.1} µm",
        search.calibration.structure.label(),
        search.steps.len().saturating_sub(1),
        search.calibration.residuals.rms_all_m * 1e6
    ));
    timings.push(("identification".to_string(), clock.elapsed().as_secs_f64()));

    // The paper's Figs. 8–9: M1–M3 at the Fig. 7 configuration (TX200 only).
    let clock = Instant::now();
    let mut fig7_files = Vec::new();
    let fig7 = if paper_comparison {
        let models: [(&str, &Robot); 3] = [
            (IDENTIFIED, &identified),
            (BASELINE, &baseline),
            (TABLE1, &nominal),
        ];
        let (rows, points) =
            crate::fig7::fig7_study(&cell, &nominal, &models, seed.wrapping_add(3))?;
        write_text(
            &out.join("fig7_points.csv"),
            &crate::fig7::fig7_csv(&rows, &points),
        )?;
        let figure = out.join("fig7_displacements.png");
        crate::fig7::fig7_figure(&figure, &points)?;
        fig7_files.push((
            figure,
            "Elastic displacements δp_x (top, cf. Fig. 8) and δp_y (bottom, cf. Fig. 9) of M1, M2, \
             M3 and the TCP at q = (0, 90°, 0, 0, 0, 0) under f_y = 1400 N at the TCP: the \
             twin's tracker (SIMULATED) against each model"
                .to_string(),
        ));
        timings.push(("Fig. 7 test".to_string(), clock.elapsed().as_secs_f64()));
        points
    } else {
        Vec::new()
    };

    // 4. Validation on the grid.
    let clock = Instant::now();
    progress.stage(4, STAGES, "validate on the grid of dead-weight loads");
    let grid_params = GridParams::for_cell(&cell).map_err(|e| e.to_string())?;
    let grid_plan = validation_grid(&cell, &grid_params).map_err(|e| e.to_string())?;
    let grid = run_campaign(&cell, &grid_plan, seed.wrapping_add(1)).map_err(|e| e.to_string())?;
    write_text(
        &out.join("grid.csv"),
        &campaign_file(&grid, "validation grid", seed.wrapping_add(1))?,
    )?;
    let models: [(&str, &Robot); 3] = [
        (IDENTIFIED, &identified),
        (BASELINE, &baseline),
        (TABLE1, &nominal),
    ];
    let mut grid_predictions = Vec::new();
    for (name, robot) in models {
        grid_predictions.push((name, predict(robot, &grid).map_err(|e| e.to_string())?));
    }
    write_text(
        &out.join("grid_predictions.csv"),
        &predictions_csv(&grid, &grid_predictions),
    )?;
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
    let grid_files =
        crate::figures::grid_figures(out, &grid, &grid_params.loads_n, &grid_predictions)?;
    let last = validation.len().saturating_sub(3);
    progress.done(&format!(
        "δz RMS at {:.0}/{:.0} N: identified {:.3}/{:.3} mm, one-eDoF {:.3}/{:.3} mm",
        grid_params.loads_n[0],
        grid_params.loads_n[grid_params.loads_n.len() - 1],
        validation[0].rms_z_mm,
        validation[last].rms_z_mm,
        validation[1].rms_z_mm,
        validation[last + 1].rms_z_mm
    ));
    timings.push(("grid validation".to_string(), clock.elapsed().as_secs_f64()));

    // 5. Spiral (Fig. 14).
    let clock = Instant::now();
    progress.stage(5, STAGES, "validate along the spiral");
    let mut spiral_params = SpiralParams::for_cell(&cell).map_err(|e| e.to_string())?;
    if options.quick {
        spiral_params.length_m *= 0.3 / 2.7;
    }
    let spiral_rows =
        spiral(&cell, &spiral_params, seed.wrapping_add(2)).map_err(|e| e.to_string())?;
    write_text(
        &out.join("spiral.csv"),
        &campaign_file(&spiral_rows, "spiral", seed.wrapping_add(2))?,
    )?;
    let all: Vec<usize> = (0..spiral_rows.len()).collect();
    let mut spiral_predictions = Vec::new();
    let spiral_label = format!("spiral {:.0} N", spiral_params.load_n);
    for (name, robot) in models {
        let predicted = predict(robot, &spiral_rows).map_err(|e| e.to_string())?;
        validation.push(error_numbers(
            name,
            &spiral_label,
            &spiral_rows,
            &predicted,
            &all,
        ));
        spiral_predictions.push((name, predicted));
    }
    write_text(
        &out.join("spiral_predictions.csv"),
        &predictions_csv(&spiral_rows, &spiral_predictions),
    )?;
    let spiral_files =
        crate::figures::spiral_figures(out, &spiral_rows, &spiral_params, &spiral_predictions)?;
    let spiral_identified = &validation[validation.len() - 3];
    progress.done(&format!(
        "{} samples, identified δz RMS {:.3} mm",
        spiral_rows.len(),
        spiral_identified.rms_z_mm
    ));
    timings.push((
        "spiral validation".to_string(),
        clock.elapsed().as_secs_f64(),
    ));

    // 6–7. Forming without and with correction.
    let path = if options.quick {
        ToolPath::paper_cone().truncated(1500.0)
    } else {
        ToolPath::paper_cone()
    };
    let clock = Instant::now();
    progress.stage(6, STAGES, "form the cone without correction");
    let open = run_forming_with_progress(&cell, path.clone(), seed, None, &mut |f| {
        progress.fraction(f)
    })
    .map_err(|e| e.to_string())?;
    open.write_outputs(&out.join("forming_open"))
        .map_err(|e| e.to_string())?;
    progress.done(&format!(
        "max error norm {:.2} mm, max |F| {:.0} N",
        open.summary.max_error_norm_mm, open.summary.max_force_norm_N
    ));
    timings.push((
        "forming without correction".to_string(),
        clock.elapsed().as_secs_f64(),
    ));

    let clock = Instant::now();
    progress.stage(7, STAGES, "form the cone with online correction");
    let closed = run_closed_loop(
        &cell,
        path.clone(),
        seed,
        identified.clone(),
        controller_config_for(&cell),
        true,
        &mut |f| progress.fraction(f),
    )?;
    closed
        .forming
        .write_outputs(&out.join("forming_closed"))
        .map_err(|e| e.to_string())?;
    write_text(
        &out.join("forming_closed").join("controller_log.csv"),
        &crate::tables::controller_log_csv(&closed.trace, &nominal.name),
    )?;
    let improvement =
        100.0 * (1.0 - closed.forming.summary.max_error_norm_mm / open.summary.max_error_norm_mm);
    progress.done(&format!(
        "max error norm {:.2} mm ({improvement:.0} % better), max |F| {:.0} N",
        closed.forming.summary.max_error_norm_mm, closed.forming.summary.max_force_norm_N
    ));
    timings.push((
        "forming with correction".to_string(),
        clock.elapsed().as_secs_f64(),
    ));
    let forming_files = crate::figures::forming_figures(out, &open, &closed.forming)?;
    let controller_files = crate::figures::controller_figures(out, &closed.trace)?;
    let mut contact_files = Vec::new();
    let mut sensitivity_files = Vec::new();

    // 8. Stiff contact.
    let clock = Instant::now();
    progress.stage(8, STAGES, "plunge into a stiff fixture (1e7 N/m)");
    let (stiff_contact, plunge_runs) =
        crate::contact::stiff_contact(&cell, &identified, 1e7, seed, &|_| {})?;
    let figure = out.join("stiff_contact_force.png");
    crate::contact::contact_figure(&figure, &plunge_runs, 1e7)?;
    contact_files.push((
        figure,
        "Plunge into a 10⁷ N/m fixture: the contact force over time without correction, with \
         correction and no runaway guard, and with the runaway guard, whose curve lies on the \
         uncorrected one once the guard has withdrawn the correction along the runaway \
         direction (SIMULATED)"
            .to_string(),
    ));
    let mut stiff_contact_sweep = Vec::new();
    let sweep: &[f64] = if options.quick {
        &[]
    } else {
        &[1e5, 1e6, 1e7, 1e8]
    };
    for &k in sweep {
        if k == stiff_contact.stiffness_n_m {
            stiff_contact_sweep.push(stiff_contact.clone());
            continue;
        }
        let (numbers, _) = crate::contact::stiff_contact(&cell, &identified, k, seed, &|_| {})?;
        stiff_contact_sweep.push(numbers);
    }
    let (u, g) = (&stiff_contact.unguarded, &stiff_contact.guarded);
    progress.done(&format!(
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
    ));
    timings.push(("stiff contact".to_string(), clock.elapsed().as_secs_f64()));

    // 9. Sensitivity.
    let clock = Instant::now();
    progress.stage(9, STAGES, "sensitivity of the closed loop");
    let sensitivity = if options.sensitivity {
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
        let result = run_sensitivity(&cell, &identified, &plan, seed, &|f| {
            if let Ok(mut v) = fraction.lock() {
                *v = f;
            }
        })?;
        progress.fraction(1.0);
        write_text(&out.join("sensitivity.csv"), &result.csv())?;
        let figure = out.join("sensitivity_heatmap.png");
        result.heatmap(&figure)?;
        sensitivity_files.push((
            figure,
            "Improvement of the max path error across the correction delay and the model's \
             compliance scale (SIMULATED, sensitivity cone)"
                .to_string(),
        ));
        let worst = result
            .rows
            .iter()
            .map(|r| r.improvement_percent)
            .fold(f64::INFINITY, f64::min);
        progress.done(&format!(
            "{} runs, worst improvement {worst:.0} %",
            result.runs
        ));
        Some(result)
    } else {
        progress.done("skipped");
        None
    };
    timings.push(("sensitivity".to_string(), clock.elapsed().as_secs_f64()));

    // 10. Offline, online and both.
    let clock = Instant::now();
    progress.stage(
        10,
        STAGES,
        "compare offline compensation, online correction and both",
    );
    let (compensation, compensation_files) = crate::compensation::study(
        &cell,
        &identified,
        seed,
        options.quick,
        (&path, &open, &closed.forming),
        out,
    )?;
    progress.done(&crate::compensation::one_line(&compensation));
    timings.push(("compensation".to_string(), clock.elapsed().as_secs_f64()));

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
        identified_structure: search.calibration.structure.label(),
        search_steps: search.steps.len().saturating_sub(1),
        search_stop_reason: search.stop_reason.clone(),
        identification_rms_um: search.calibration.residuals.rms_all_m * 1e6,
        identification_reduced_chi2: search.calibration.reduced_chi2,
        stiffness,
        validation,
        fig7,
        forming_open: FormingNumbers::from_run(&open),
        forming_closed: FormingNumbers::from_run(&closed.forming),
        improvement_percent: improvement,
        controller_status: closed.status,
        stiff_contact,
        stiff_contact_sweep,
        sensitivity,
        compensation,
        stage_seconds: timings,
    };
    write_text(
        &out.join("summary.json"),
        &serde_json::to_string_pretty(&summary).map_err(|e| e.to_string())?,
    )?;
    write_text(
        &out.join("paper_vs_deflex.csv"),
        &paper_vs_deflex_csv(&summary),
    )?;
    let page = crate::page::Page {
        summary: &summary,
        search: &search,
        plan: &plan,
        grid: &grid_params,
        spiral: &spiral_params,
        fig7_files,
        grid_files,
        spiral_files,
        forming_files,
        controller_files,
        contact_files,
        sensitivity_files,
        compensation_files,
    };
    crate::page::write(out, &page)?;
    Ok(summary)
}

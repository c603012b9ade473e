//! `deflex calibrate`, `validate`, `plan`: identification of the elasto-geometrical model
//! (Johra et al. 2022, Section 3) from laser-tracker measurements.

use crate::args::{CliResult, robot};
use clap::Args;
use deflex_calib::fit::{Calibration, Status, Structure, calibrate_fixed};
use deflex_calib::plan::{PlanOptions, plan_experiments};
use deflex_calib::report::{
    EXPECTED_SE_HEADERS, EXPECTED_SHIFT_HEADERS, ITERATION_HEADERS, STIFFNESS_HEADERS,
    VALIDATION_HEADERS, correlation_table, expected_se_rows, expected_shift_rows, iteration_rows,
    render_table, residual_summary, stiffness_rows, table_csv, validation_rows,
};
use deflex_calib::search::{Criterion, SearchOptions, SearchStep, search_structure};
use deflex_calib::validate::{validate as run_validation, write_report};
use deflex_calib::{read_for_robot, write_rows};
use deflex_model::robot_to_toml;
use deflex_report::HtmlReport;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct CalibrateArgs {
    /// Start model: built-in name (tx200, tx200-1edof) or TOML file. Gives the geometry; with
    /// --structure fixed also the eDoFs and centre shifts.
    #[arg(long)]
    pub robot: String,
    /// Measurement CSV (see `deflex plan` for the columns).
    #[arg(long)]
    pub data: PathBuf,
    /// auto: structure search from one z-eDoF per joint (see --criterion); fixed: the start
    /// model's eDoFs and centre shifts as given.
    #[arg(long, default_value = "auto", value_parser = ["auto", "fixed"])]
    pub structure: String,
    /// Stop the search once the RMS residual (all components) is at most this (mm).
    #[arg(long)]
    pub target_rms_mm: Option<f64>,
    /// With --structure fixed: also fit the centre shift of every joint with an x or y eDoF.
    #[arg(long)]
    pub fit_shifts: bool,
    /// Do not consider base tilt eDoFs in the search.
    #[arg(long)]
    pub no_base: bool,
    /// Smallest BIC decrease for the search to accept a refinement.
    #[arg(long, default_value_t = 10.0)]
    pub min_bic_gain: f64,
    /// How the search ranks structures: bic, or cv (held-out χ² of k-fold cross-validation by
    /// load case). The iteration table shows the cross-validated RMS either way.
    #[arg(long, default_value = "bic", value_parser = ["bic", "cv"])]
    pub criterion: String,
    /// Folds of the cross-validation (by load case; at most one per load case).
    #[arg(long, default_value_t = 5)]
    pub folds: usize,
    /// With --criterion cv: smallest relative decrease of the held-out χ² for the search to
    /// accept a refinement (%).
    #[arg(long, default_value_t = 2.0)]
    pub min_cv_gain_percent: f64,
    /// Output robot TOML (a drop-in for every other command).
    #[arg(long)]
    pub out: PathBuf,
    /// Folder for an HTML report and CSV tables.
    #[arg(long)]
    pub report: Option<PathBuf>,
}

#[derive(Args)]
pub struct ValidateArgs {
    /// Model to validate: built-in name or TOML file.
    #[arg(long)]
    pub robot: String,
    /// Measurement CSV.
    #[arg(long)]
    pub data: PathBuf,
    /// Baseline model shown side by side (e.g. tx200-1edof).
    #[arg(long)]
    pub baseline: Option<String>,
    /// Folder for PNG plots and validation.html.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

#[derive(Args)]
pub struct PlanArgs {
    /// Nominal model: built-in name or TOML file.
    #[arg(long)]
    pub robot: String,
    /// Load magnitude (N), applied at the TCP along ±x, ±y or ±z of the world.
    #[arg(long = "max-force-N", default_value_t = 1500.0)]
    pub max_force_n: f64,
    /// Number of load cases (axis-by-axis ones included).
    #[arg(long, default_value_t = 24)]
    pub load_cases: usize,
    /// Plan for every eDoF of the model family (what `calibrate --structure auto` needs), not
    /// only the model's.
    #[arg(long)]
    pub full_family: bool,
    /// Do not measure the base reflector M0 (which separates a baseplate tilt from joint 1).
    #[arg(long)]
    pub no_base_point: bool,
    /// Tracker noise (µm) for the expected standard errors.
    #[arg(long, default_value_t = 15.0)]
    pub noise_um: f64,
    /// Random configurations tried (each with 6 load directions).
    #[arg(long, default_value_t = 600)]
    pub configurations: usize,
    /// Keep every joint origin and the TCP at or above this world height (m): the floor, table
    /// or fixture under the robot (the world is the robot file's frame).
    #[arg(long)]
    pub floor_z_m: Option<f64>,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output plan CSV.
    #[arg(long)]
    pub out: PathBuf,
}

/// A number, or JSON null when it is infinite or NaN (not identifiable).
fn finite_or_null(x: f64) -> Value {
    if x.is_finite() { json!(x) } else { Value::Null }
}

fn calibration_json(cal: &Calibration) -> Value {
    let edofs: Vec<Value> = cal
        .edofs
        .iter()
        .map(|e| {
            let (status, reason) = match &e.status {
                Status::Identified => ("identified", None),
                Status::Weak => ("weak", None),
                Status::NotIdentifiable(r) => ("not_identifiable", Some(r.clone())),
            };
            json!({
                "edof": e.label,
                "status": status,
                "reason": reason,
                "stiffness_Nm_per_rad": e.stiffness,
                "stiffness_se": e.stiffness_se,
                "interval95": e.interval95.map(|(a, b)| json!([a, if b.is_finite() { json!(b) } else { json!("inf") }])),
                "compliance": e.compliance,
                "compliance_se": finite_or_null(e.compliance_se),
            })
        })
        .collect();
    let shifts: Vec<Value> = cal
        .shifts
        .iter()
        .map(|s| json!({"joint": s.joint, "center_shift_m": s.value_m, "se_m": s.se_m, "fitted": s.free}))
        .collect();
    let r = &cal.residuals;
    json!({
        "structure": cal.structure.label(),
        "edofs": edofs,
        "center_shifts": shifts,
        "parameters": cal.parameter_labels,
        "correlation": (0..cal.correlation.nrows()).map(|i| (0..cal.correlation.ncols()).map(|j| cal.correlation[(i, j)]).collect::<Vec<_>>()).collect::<Vec<_>>(),
        "condition_number": cal.condition_number,
        "reduced_chi2": cal.reduced_chi2,
        "bic": cal.bic,
        "rows": cal.rows,
        "residual_rms_m": r.rms_m,
        "residual_max_m": r.max_abs_m,
        "residual_rms_all_m": r.rms_all_m,
        "residual_rms_norm_m": r.rms_norm_m,
        "residual_max_norm_m": r.max_norm_m,
        "rotation_rows": cal.rotation_rows,
        "residual_rotation_rms_rad": r.rotation_rms_rad,
        "warnings": cal.warnings,
    })
}

fn write_file(path: &Path, text: &str) -> Result<(), String> {
    std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))
}

pub fn calibrate(args: CalibrateArgs, json_output: bool) -> CliResult {
    let start = robot(&args.robot)?;
    let rows = read_for_robot(&args.data, start.joint_count(), true).map_err(|e| e.to_string())?;
    if let Some(t) = args.target_rms_mm
        && !(t.is_finite() && t >= 0.0)
    {
        return Err("--target-rms-mm must be a non-negative number".into());
    }
    let t0 = std::time::Instant::now();
    let (cal, steps, stop): (Calibration, Vec<SearchStep>, Option<String>) =
        if args.structure == "fixed" {
            let mut st = Structure::from_robot(&start);
            if args.fit_shifts {
                st = st.with_free_shifts();
            }
            let cal = calibrate_fixed(&start, &rows, &st).map_err(|e| e.to_string())?;
            (cal, Vec::new(), None)
        } else {
            if args.folds < 2 {
                return Err(format!("--folds: expected 2 or more, got {}", args.folds));
            }
            if !(0.0..100.0).contains(&args.min_cv_gain_percent) {
                return Err(format!(
                    "--min-cv-gain-percent: expected 0 to 100, got {}",
                    args.min_cv_gain_percent
                ));
            }
            let criterion = if args.criterion == "cv" {
                Criterion::CrossValidated {
                    folds: args.folds,
                    min_relative_gain: args.min_cv_gain_percent / 100.0,
                }
            } else {
                Criterion::Bic
            };
            let options = SearchOptions {
                criterion,
                report_folds: args.folds,
                target_rms_m: args.target_rms_mm.map(|v| v * 1e-3),
                min_bic_gain: args.min_bic_gain,
                allow_base: !args.no_base,
                ..SearchOptions::default()
            };
            let bar = if json_output {
                indicatif::ProgressBar::hidden()
            } else {
                indicatif::ProgressBar::new(1)
            };
            bar.set_style(
                indicatif::ProgressStyle::with_template(
                    "structure search {msg} [{bar:30}] {pos}/{len} candidates",
                )
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            let mut progress = |iteration: usize, done: usize, total: usize| {
                bar.set_length(total as u64);
                bar.set_position(done as u64);
                bar.set_message(format!("step {iteration}"));
            };
            let result = search_structure(&start, &rows, &options, &mut progress)
                .map_err(|e| e.to_string())?;
            bar.finish_and_clear();
            (result.calibration, result.steps, Some(result.stop_reason))
        };
    let elapsed = t0.elapsed();
    let mut model = cal.to_robot(&start);
    // The geometry is the start model's; the elasticity is new: say so in the name.
    let geometry = model
        .name
        .split(" — calibrated")
        .next()
        .unwrap_or("")
        .to_string();
    model.name = format!(
        "{geometry} — calibrated from {} ({})",
        args.data.display(),
        cal.structure.label()
    );
    write_file(&args.out, &robot_to_toml(&model))?;
    let it_rows = iteration_rows(&steps);
    let st_rows = stiffness_rows(&cal);
    if let Some(dir) = &args.report {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        write_file(
            &dir.join("iterations.csv"),
            &table_csv(&ITERATION_HEADERS, &it_rows),
        )?;
        write_file(
            &dir.join("stiffness.csv"),
            &table_csv(&STIFFNESS_HEADERS, &st_rows),
        )?;
        let mut html = HtmlReport::new(format!("Calibration of {}", start.name));
        html.paragraph(format!(
            "Data: {} ({} rows). Structure: {}. Output model: {}.",
            args.data.display(),
            cal.rows,
            cal.structure.label(),
            args.out.display()
        ));
        if !steps.is_empty() {
            html.section("Structure search (test-model loop, cf. Tables A1/A2)");
            html.table(&ITERATION_HEADERS, &it_rows);
            if let Some(s) = &stop {
                html.paragraph(format!("Stopped: {s}."));
            }
        }
        html.section("Identified stiffnesses (cf. Table 1)");
        html.table(&STIFFNESS_HEADERS, &st_rows);
        html.preformatted(residual_summary(&cal));
        html.section("Parameter correlation");
        html.preformatted(correlation_table(&cal));
        for w in &cal.warnings {
            html.note(w.clone());
        }
        html.write(&dir.join("calibration.html"))
            .map_err(|e| e.to_string())?;
    }
    if json_output {
        let steps_json: Vec<Value> = steps
            .iter()
            .map(|s| json!({"step": s.iteration, "change": s.change, "structure": s.structure, "parameters": s.parameters, "rms_m": s.residuals.rms_all_m, "rms_axis_m": s.residuals.rms_m, "bic": s.bic, "delta_bic": s.delta_bic, "cv_rms_m": s.cv_rms_m}))
            .collect();
        let mut v = calibration_json(&cal);
        v["iterations"] = json!(steps_json);
        v["stop_reason"] = json!(stop);
        v["output"] = json!(args.out.display().to_string());
        v["elapsed_s"] = json!(elapsed.as_secs_f64());
        println!("{}", serde_json::to_string_pretty(&v).unwrap_or_default());
        return Ok(());
    }
    if !steps.is_empty() {
        println!(
            "Structure search ({} rows, {:.2} s)",
            cal.rows,
            elapsed.as_secs_f64()
        );
        print!("{}", render_table(&ITERATION_HEADERS, &it_rows));
        if let Some(s) = &stop {
            println!("stopped: {s}");
        }
        println!();
    }
    println!("Identified model: {}", cal.structure.label());
    print!("{}", render_table(&STIFFNESS_HEADERS, &st_rows));
    println!();
    print!("{}", residual_summary(&cal));
    println!("\nParameter correlation:");
    print!("{}", correlation_table(&cal));
    for w in &cal.warnings {
        println!("warning: {w}");
    }
    println!("\nwrote {}", args.out.display());
    if let Some(dir) = &args.report {
        println!("report: {}", dir.join("calibration.html").display());
    }
    Ok(())
}

pub fn validate(args: ValidateArgs, json_output: bool) -> CliResult {
    let model = robot(&args.robot)?;
    let baseline = args.baseline.as_deref().map(robot).transpose()?;
    let rows = read_for_robot(&args.data, model.joint_count(), true).map_err(|e| e.to_string())?;
    let v = run_validation(&model, baseline.as_ref(), &rows).map_err(|e| e.to_string())?;
    let files = match &args.out {
        Some(dir) => write_report(&v, dir).map_err(|e| e.to_string())?,
        None => Vec::new(),
    };
    if json_output {
        let m = |e: &deflex_calib::validate::ModelErrors| {
            let rotation = e.rotation.as_ref().map(|r| {
                let s = &r.stats;
                json!({"rows": s.rows, "rms_rad": s.rms_rad, "max_abs_rad": s.max_abs_rad, "mean_rad": s.mean_rad, "rms_norm_rad": s.rms_norm_rad, "max_norm_rad": s.max_norm_rad})
            });
            json!({"name": e.name, "rms_m": e.stats.rms_m, "max_abs_m": e.stats.max_abs_m, "mean_m": e.stats.mean_m, "rms_norm_m": e.stats.rms_norm_m, "max_norm_m": e.stats.max_norm_m, "rotation": rotation})
        };
        let value = json!({
            "rows": v.measured.len(),
            "model": m(&v.model),
            "baseline": v.baseline.as_ref().map(m),
            "files": files.iter().map(|f| f.display().to_string()).collect::<Vec<_>>(),
        });
        println!(
            "{}",
            serde_json::to_string_pretty(&value).unwrap_or_default()
        );
        return Ok(());
    }
    println!(
        "Prediction errors (measured − predicted), {} points; measured RMS x/y/z {:.4} / {:.4} / {:.4} mm",
        v.measured.len(),
        v.measured_rms_m[0] * 1e3,
        v.measured_rms_m[1] * 1e3,
        v.measured_rms_m[2] * 1e3
    );
    print!(
        "{}",
        render_table(&VALIDATION_HEADERS, &validation_rows(&v))
    );
    if let Some(rotation) = deflex_calib::report::validation_rotation_summary(&v) {
        print!("{rotation}");
    }
    if let Some(dir) = &args.out {
        println!(
            "wrote {} files to {} (validation.html)",
            files.len(),
            dir.display()
        );
    }
    Ok(())
}

pub fn plan(args: PlanArgs, json_output: bool) -> CliResult {
    let nominal = robot(&args.robot)?;
    if args.load_cases == 0 {
        return Err("--load-cases must be at least 1".into());
    }
    let options = PlanOptions {
        max_force_n: args.max_force_n,
        load_cases: args.load_cases,
        configurations: args.configurations.max(1),
        noise_sigma_m: args.noise_um * 1e-6,
        seed: args.seed,
        full_family: args.full_family,
        base_point: !args.no_base_point,
        floor_z_m: args.floor_z_m,
    };
    let plan = plan_experiments(&nominal, &options).map_err(|e| e.to_string())?;
    write_rows(&args.out, &plan.rows).map_err(|e| e.to_string())?;
    let cases = deflex_calib::data::load_case_count(&plan.rows);
    if json_output {
        let expected: Vec<Value> = plan
            .expected
            .iter()
            .map(|e| json!({"edof": e.label, "nominal_k": e.nominal_k, "expected_se_k": finite_or_null(e.se_k), "relative": finite_or_null(e.relative)}))
            .collect();
        let shifts: Vec<Value> = plan
            .expected_shifts
            .iter()
            .map(|e| json!({"joint": e.joint, "nominal_m": e.nominal_m, "expected_se_m": finite_or_null(e.se_m)}))
            .collect();
        let axis: Vec<Value> = plan
            .axis_cases
            .iter()
            .map(|a| json!({"edof": deflex_calib::edof_label(a.id), "load_case": a.load_case, "share": a.share, "snr": a.snr}))
            .collect();
        println!(
            "{}",
            serde_json::to_string_pretty(&json!({"load_cases": cases, "rows": plan.rows.len(), "output": args.out.display().to_string(), "expected": expected, "expected_shifts": shifts, "axis_by_axis": axis, "log_det": plan.log_det}))
                .unwrap_or_default()
        );
        return Ok(());
    }
    println!(
        "Plan for {}: {} load cases ({} axis-by-axis + D-optimal), {} points to measure, |F| = {:.0} N at the TCP",
        nominal.name,
        cases,
        plan.axis_cases
            .iter()
            .map(|a| a.load_case.as_str())
            .collect::<std::collections::BTreeSet<_>>()
            .len(),
        plan.rows.len(),
        args.max_force_n
    );
    println!(
        "Expected standard errors with {:.1} µm tracker noise:",
        args.noise_um
    );
    print!(
        "{}",
        render_table(&EXPECTED_SE_HEADERS, &expected_se_rows(&plan))
    );
    if !plan.expected_shifts.is_empty() {
        print!(
            "{}",
            render_table(&EXPECTED_SHIFT_HEADERS, &expected_shift_rows(&plan))
        );
    }
    if args.load_cases < cases {
        println!(
            "note: {cases} load cases instead of the {} asked for: every eDoF gets its own axis-by-axis case",
            args.load_cases
        );
    }
    println!(
        "\nLoad cases for the technician (joint values in degrees; force at the TCP, world axes):"
    );
    print!(
        "{}",
        render_table(
            &["case", "q [deg]", "force [N]", "measure", "why"],
            &technician_rows(&plan.rows)
        )
    );
    println!("wrote {}", args.out.display());
    Ok(())
}

/// One line per load case: configuration in degrees, force vector, points to measure, purpose.
fn technician_rows(rows: &[deflex_calib::MeasurementRow]) -> Vec<Vec<String>> {
    let mut out: Vec<Vec<String>> = Vec::new();
    for row in rows {
        match out.last_mut() {
            Some(last) if last[0] == row.load_case => {
                last[3] = format!("{}, {}", last[3], row.point);
            }
            _ => {
                let q: Vec<String> = row
                    .q_rad
                    .iter()
                    .map(|q| format!("{:.1}", q.to_degrees()))
                    .collect();
                let f = row.wrench;
                out.push(vec![
                    row.load_case.clone(),
                    q.join(", "),
                    format!("({:.0}, {:.0}, {:.0})", f[0], f[1], f[2]),
                    row.point.clone(),
                    row.purpose.clone().unwrap_or_default(),
                ]);
            }
        }
    }
    out
}

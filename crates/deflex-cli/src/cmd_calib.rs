//! `deflex calibrate`, `validate` (and `plan`, in `cmd_plan`): identification of the
//! elasto-geometrical model (Johra et al. 2022, Section 3) from laser-tracker measurements.

use crate::args::{check_range, finite_or_null, robot};
use crate::error::{CliError, CommandResult, UsageError};
use clap::{Args, ValueEnum};

use deflex_app::load::{read_file_ignoring, robot_to_toml_for};
use deflex_app::report::calibration_report::{
    CalibrationReport, CouplingSection, write_calibration_report,
};
use deflex_app::report::calibration_tables::{
    ITERATION_HEADERS, SHIFT_HEADERS, STIFFNESS_HEADERS, correlated_pairs_text, correlation_table,
    iteration_rows, residual_summary, shift_rows, stiffness_rows,
};
use deflex_app::report::validation_report::{
    VALIDATION_HEADERS, validation_rotation_summary, validation_rows, write_validation_report,
};
use deflex_calibrate::stiffness::consistency::{
    GeometryCheck, MAX_FK_TOLERANCE_M, MIN_FK_TOLERANCE_M, check_geometry, enforce,
};
use deflex_calibrate::stiffness::search::{Criterion, SearchOptions, SearchStep, search_structure};
use deflex_calibrate::stiffness::stiffness_fit::{Calibration, Status, Structure, calibrate_fixed};
use deflex_calibrate::stiffness::validation::{predict, validate as run_validation};
use deflex_files::{AtomicDir, AtomicFile};
use deflex_model::Robot;
use deflex_plot::text_table::render_table;
use serde_json::{Value, json};
use std::io::Write as _;
use std::path::{Path, PathBuf};

mod couplings;

#[derive(Args)]
pub struct CalibrateArgs {
    /// Start model: built-in name (tx200, tx200-1edof, …) or TOML file. Gives the geometry; with
    /// --structure fixed also the eDoFs and centre shifts.
    #[arg(long)]
    pub robot: String,
    /// Measurement CSV (see `deflex plan` for the columns).
    #[arg(long)]
    pub data: PathBuf,
    /// auto: structure search from one z-eDoF per joint (see --criterion); fixed: the start
    /// model's eDoFs and centre shifts as given.
    #[arg(long, value_enum, default_value = "auto")]
    pub structure: StructureChoice,
    /// Stop the search once the RMS residual (all components) is at most this (mm, 0 to 1000).
    #[arg(long)]
    pub target_rms_mm: Option<f64>,
    /// With --structure fixed: also fit the centre shift of every joint with an x or y eDoF.
    #[arg(long)]
    pub fit_shifts: bool,
    /// Do not consider base tilt eDoFs in the search.
    #[arg(long)]
    pub no_base: bool,
    /// Smallest BIC decrease for the search to accept a refinement (0 to 1e6).
    #[arg(long, default_value_t = 10.0)]
    pub min_bic_gain: f64,
    /// How the search ranks structures: bic, or cv (held-out χ² of k-fold cross-validation by
    /// load case). The iteration table shows the cross-validated RMS either way.
    #[arg(long, value_enum, default_value = "bic")]
    pub criterion: CriterionChoice,
    /// Folds of the cross-validation (by load case; 2 to 100, at most one per load case).
    #[arg(long, default_value_t = 5)]
    pub folds: usize,
    /// With --criterion cv: smallest relative decrease of the held-out χ² for the search to
    /// accept a refinement (%, 0 to 100).
    #[arg(long, default_value_t = 2.0)]
    pub min_cv_gain_percent: f64,
    /// Largest distance between a row's point coordinates and the robot's forward kinematics of
    /// its joint values (mm, 0.001 to 1000): more refuses the file.
    #[arg(long, default_value_t = 1.0)]
    pub fk_tolerance_mm: f64,
    /// Use the file even when its coordinates disagree with the robot's forward kinematics
    /// (the disagreement is printed as a warning).
    #[arg(long)]
    pub ignore_fk_check: bool,
    /// A column of the measurement file that deflex does not read, kept knowingly (repeatable).
    /// Without it an unknown column is an error naming the closest known one (a typo such as
    /// `sigma_mm` would otherwise drop the σ it meant).
    #[arg(long = "ignore-column", value_name = "NAME")]
    pub ignore_column: Vec<String>,
    /// Off-diagonal joint compliances to fit once the structure is identified, together with
    /// the eDoF compliances (weighted least squares, standard errors as the stiffnesses'):
    /// pairs of eDoFs of the identified structure, e.g. `J2.z:J3.z` (a shared counterbalance or
    /// casting), separated by commas, at most 8. Written into the output model as
    /// `[[coupling]]`, with the stiffnesses refitted with them.
    #[arg(long, value_name = "A:B[,A:B…]")]
    pub couplings: Option<String>,
    /// Output robot TOML (a drop-in for every other command).
    #[arg(long)]
    pub out: PathBuf,
    /// Folder for an HTML report with plots and CSV tables (replaced whole).
    #[arg(long)]
    pub report: Option<PathBuf>,
}

/// `--structure`: how the calibrated structure is found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum StructureChoice {
    // Structure search from one z-eDoF per joint. (Plain comments: a doc comment would become
    // the value's help and change `--help`.)
    Auto,
    // The start model's eDoFs and centre shifts.
    Fixed,
}

/// `--criterion`: how the search ranks structures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum CriterionChoice {
    // Bayesian information criterion.
    Bic,
    // Held-out χ² of k-fold cross-validation by load case.
    Cv,
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
    /// Largest distance between a row's point coordinates and the model's forward kinematics
    /// of its joint values (mm, 0.001 to 1000): more refuses the file.
    #[arg(long, default_value_t = 1.0)]
    pub fk_tolerance_mm: f64,
    /// Use the file even when its coordinates disagree with the model's forward kinematics.
    #[arg(long)]
    pub ignore_fk_check: bool,
    /// A column of the measurement file that deflex does not read, kept knowingly (repeatable).
    /// Without it an unknown column is an error naming the closest known one (a typo such as
    /// `sigma_mm` would otherwise drop the σ it meant).
    #[arg(long = "ignore-column", value_name = "NAME")]
    pub ignore_column: Vec<String>,
    /// Folder for PNG plots and validation.html (replaced whole, or left as it was on error).
    #[arg(long)]
    pub out: Option<PathBuf>,
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
        "correlated_pairs": cal.correlated_pairs().iter().map(|p| json!({"first": p.first, "second": p.second, "rho": p.rho, "text": p.to_string()})).collect::<Vec<_>>(),
        "correlation_flag_threshold": deflex_calibrate::stiffness::stiffness_fit::STRONG_CORRELATION,
        "condition_number": cal.condition_number,
        "reduced_chi2": cal.reduced_chi2,
        "bic": cal.bic,
        "rows": cal.rows,
        "residual_rms_m": r.position.rms,
        "residual_max_m": r.position.max_abs,
        "residual_rms_all_m": r.rms_all_m,
        "residual_rms_norm_m": r.position.norm.rms,
        "residual_max_norm_m": r.position.norm.max,
        "rotation_rows": cal.rotation_rows,
        "residual_rotation_rms_rad": r.rotation_rms_rad,
        "chi2_well_above_one": cal.reduced_chi2 > deflex_calibrate::stiffness::stiffness_fit::CHI2_WELL_ABOVE_ONE,
        "model_form_note": cal.model_form_note(),
        "warnings": cal.warnings,
    })
}

/// A measurement file read and checked against the robot's forward kinematics.
struct CheckedFile {
    rows: Vec<deflex_calibrate::measurements::MeasurementRow>,
    check: GeometryCheck,
    /// Warnings to print.
    warnings: Vec<String>,
    /// The file's header comments (a `SIMULATED` note marks simulated data).
    notes: Vec<String>,
}

/// Read a measurement file for `robot` and check its coordinates against the robot's forward
/// kinematics (or refuse it).
fn read_checked(
    robot: &Robot,
    data: &Path,
    tolerance_mm: f64,
    ignore: bool,
    ignore_columns: &[String],
) -> Result<CheckedFile, CliError> {
    if !(tolerance_mm.is_finite()
        && (MIN_FK_TOLERANCE_M * 1e3..=MAX_FK_TOLERANCE_M * 1e3).contains(&tolerance_mm))
    {
        return Err(UsageError::invalid(
            "--fk-tolerance-mm",
            format!(
                "{} to {} mm",
                MIN_FK_TOLERANCE_M * 1e3,
                MAX_FK_TOLERANCE_M * 1e3
            ),
            tolerance_mm,
        )
        .into());
    }
    let file = read_file_ignoring(data, Some(robot.joint_count()), true, ignore_columns)?;
    let check = check_geometry(
        robot,
        &file.rows,
        Some(&file.lines),
        Some(&file.header),
        tolerance_mm * 1e-3,
    )
    .map_err(|e| CliError::in_context(data.display().to_string())(e.into()))?;
    let warnings = enforce(
        &check,
        &data.display().to_string(),
        ignore,
        "Is this the robot the file was measured on? Widen the tolerance with --fk-tolerance-mm, or use the file anyway with --ignore-fk-check.",
    )?;
    Ok(CheckedFile {
        rows: file.rows,
        check,
        warnings,
        notes: file.header.notes,
    })
}

fn geometry_json(check: &GeometryCheck) -> Value {
    json!({
        "robot": check.robot,
        "geometry": check.geometry,
        "tolerance_m": check.tolerance_m,
        "rows": check.rows,
        "checked_points": check.checked_points,
        "checked_loads": check.checked_loads,
        "disagreeing_rows": check.disagreeing_rows(),
        "max_distance_m": check.max_distance_m,
        "first_disagreements": check.disagreements.iter().take(deflex_calibrate::stiffness::consistency::ROWS_NAMED).map(|d| json!({"row": d.row + 1, "line": d.line, "load_case": d.load_case, "point": d.point, "distance_m": d.distance_m, "text": d.to_string()})).collect::<Vec<_>>(),
        "unchecked": check.unchecked,
        "header_mismatch": check.header_mismatch,
    })
}

pub fn calibrate(args: CalibrateArgs, json_output: bool) -> CommandResult {
    if let Some(t) = args.target_rms_mm {
        check_range("--target-rms-mm", t, 0.0, 1000.0)?;
    }
    check_range("--min-bic-gain", args.min_bic_gain, 0.0, 1e6)?;
    check_range(
        "--min-cv-gain-percent",
        args.min_cv_gain_percent,
        0.0,
        99.999,
    )?;
    if !(2..=100).contains(&args.folds) {
        return Err(UsageError::invalid("--folds", "2 to 100", args.folds).into());
    }
    let requested = args
        .couplings
        .as_deref()
        .map(couplings::parse)
        .transpose()?;
    let start = robot(&args.robot)?;
    let CheckedFile {
        rows,
        check,
        mut warnings,
        notes: data_notes,
    } = read_checked(
        &start,
        &args.data,
        args.fk_tolerance_mm,
        args.ignore_fk_check,
        &args.ignore_column,
    )?;
    let t0 = std::time::Instant::now();
    let (cal, steps, stop) = identify(&args, &start, &rows, json_output).map_err(
        CliError::in_context(format!("--data {}", deflex_files::shown_path(&args.data))),
    )?;
    let elapsed = t0.elapsed();
    if !cal.edofs.iter().any(|e| e.stiffness.is_some()) {
        return Err(CliError::NothingIdentified {
            data: args.data.clone(),
        });
    }
    let diagonal = cal.to_robot(&start);
    let coupling_fit = requested
        .as_deref()
        .map(|r| couplings::fit(&diagonal, &cal.structure.label(), &rows, r))
        .transpose()?;
    let mut model = coupling_fit
        .as_ref()
        .map_or_else(|| diagonal.clone(), |f| f.robot.clone());
    // The geometry is the start model's; the elasticity is new: say so in the name.
    let geometry = model
        .name
        .split(" — calibrated")
        .next()
        .unwrap_or("")
        .to_string();
    model.name = format!(
        "{geometry} — calibrated from {} ({}{})",
        args.data.display(),
        cal.structure.label(),
        model
            .couplings
            .iter()
            .map(|c| format!(", coupling {}", c.label()))
            .collect::<String>()
    );
    // Everything is built aside and appears only when complete: the report folder first,
    // then the model.
    let mut model_file = AtomicFile::create(&args.out).map_err(CliError::write(&args.out))?;
    model_file
        .write_all(robot_to_toml_for(&model, &args.out).as_bytes())
        .map_err(CliError::write(&args.out))?;
    if let Some(dir) = &args.report {
        let folder = AtomicDir::create(dir).map_err(CliError::write(dir))?;
        let predicted = predict(&model, &rows)?;
        let report = CalibrationReport {
            start_name: &start.name,
            data_name: &args.data.display().to_string(),
            output_name: &args.out.display().to_string(),
            calibration: &cal,
            predicted: &predicted,
            steps: &steps,
            stop_reason: stop.as_deref(),
            rows: &rows,
            warnings: &warnings,
            data_notes: &data_notes,
            couplings: coupling_fit.as_ref().map(|fit| CouplingSection {
                diagonal: &diagonal,
                fit,
            }),
        };
        write_calibration_report(folder.path(), &report)?;
        folder.commit().map_err(CliError::write(dir))?;
    }
    model_file.commit().map_err(CliError::write(&args.out))?;
    warnings.extend(cal.warnings.iter().cloned());
    let it_rows = iteration_rows(&steps);
    let st_rows = stiffness_rows(&cal);
    let sh_rows = shift_rows(&cal);
    if json_output {
        let steps_json: Vec<Value> = steps
            .iter()
            .map(|s| json!({"step": s.iteration, "change": s.change, "structure": s.structure, "parameters": s.parameters, "rms_m": s.residuals.rms_all_m, "rms_axis_m": s.residuals.position.rms, "bic": s.bic, "delta_bic": s.delta_bic, "cv_rms_m": s.cv_rms_m}))
            .collect();
        let mut v = calibration_json(&cal);
        v["iterations"] = json!(steps_json);
        v["stop_reason"] = json!(stop);
        v["output"] = json!(args.out.display().to_string());
        v["elapsed_s"] = json!(elapsed.as_secs_f64());
        v["geometry_check"] = geometry_json(&check);
        if let Some(fit) = &coupling_fit {
            let (list, summary) = couplings::json(fit);
            v["couplings"] = list;
            v["coupling_fit"] = summary;
        }
        v["warnings"] = json!(warnings);
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
    if !sh_rows.is_empty() {
        print!("{}", render_table(&SHIFT_HEADERS, &sh_rows));
    }
    println!();
    print!("{}", residual_summary(&cal));
    println!("\nParameter correlation:");
    print!("{}", correlation_table(&cal));
    let flagged = correlated_pairs_text(&cal);
    if !flagged.is_empty() {
        print!("\n{flagged}");
    }
    if let Some(fit) = &coupling_fit {
        print!("{}", couplings::text(&diagonal, fit));
    }
    println!(
        "\nfile check: {} points and {} load points agree with the forward kinematics within {:.3} mm (largest {:.3} mm)",
        check.checked_points,
        check.checked_loads,
        check.tolerance_m * 1e3,
        check.max_distance_m * 1e3
    );
    for w in &warnings {
        println!("warning: {w}");
    }
    println!("\nwrote {}", args.out.display());
    if let Some(dir) = &args.report {
        println!("report: {}", dir.join("calibration.html").display());
    }
    Ok(())
}

/// The calibration `args` ask for: the start model's structure (`--structure fixed`) or the
/// structure search, with a progress bar unless the output is JSON. Returns the calibration, the
/// search's steps and why it stopped.
fn identify(
    args: &CalibrateArgs,
    start: &Robot,
    rows: &[deflex_calibrate::measurements::MeasurementRow],
    json_output: bool,
) -> Result<(Calibration, Vec<SearchStep>, Option<String>), CliError> {
    Ok(if args.structure == StructureChoice::Fixed {
        let mut st = Structure::from_robot(start);
        if args.fit_shifts {
            st = st.with_free_shifts();
        }
        let cal = calibrate_fixed(start, rows, &st)?;
        (cal, Vec::new(), None)
    } else {
        let criterion = match args.criterion {
            CriterionChoice::Cv => Criterion::CrossValidated {
                folds: args.folds,
                min_relative_gain: args.min_cv_gain_percent / 100.0,
            },
            CriterionChoice::Bic => Criterion::Bic,
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
        let mut progress = |p: deflex_telemetry::Progress<'_>| match p {
            deflex_telemetry::Progress::Stage { name, .. } => bar.set_message(name.to_string()),
            deflex_telemetry::Progress::Work { done, total } => {
                bar.set_length(total as u64);
                bar.set_position(done as u64);
            }
            deflex_telemetry::Progress::Done { .. } => {}
        };
        let result = search_structure(start, rows, &options, &mut progress)?;
        bar.finish_and_clear();
        (result.calibration, result.steps, Some(result.stop_reason))
    })
}

pub fn validate(args: ValidateArgs, json_output: bool) -> CommandResult {
    let model = robot(&args.robot)?;
    let baseline = args.baseline.as_deref().map(robot).transpose()?;
    let CheckedFile {
        rows,
        check,
        warnings,
        ..
    } = read_checked(
        &model,
        &args.data,
        args.fk_tolerance_mm,
        args.ignore_fk_check,
        &args.ignore_column,
    )?;
    let v = run_validation(&model, baseline.as_ref(), &rows)?;
    let files = match &args.out {
        Some(dir) => write_validation_report(&v, dir)?,
        None => Vec::new(),
    };
    if json_output {
        let m = |e: &deflex_calibrate::stiffness::validation::ModelErrors| {
            let rotation = e.rotation.as_ref().map(|r| {
                let s = &r.stats;
                json!({"rows": s.norm.count, "rms_rad": s.rms, "max_abs_rad": s.max_abs, "mean_rad": s.mean, "rms_norm_rad": s.norm.rms, "max_norm_rad": s.norm.max})
            });
            json!({"name": e.name, "rms_m": e.stats.rms, "max_abs_m": e.stats.max_abs, "mean_m": e.stats.mean, "rms_norm_m": e.stats.norm.rms, "max_norm_m": e.stats.norm.max, "rotation": rotation})
        };
        let value = json!({
            "rows": v.measured.len(),
            "model": m(&v.model),
            "baseline": v.baseline.as_ref().map(m),
            "files": files.iter().map(|f| f.display().to_string()).collect::<Vec<_>>(),
            "geometry_check": geometry_json(&check),
            "warnings": warnings,
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
    if let Some(rotation) = validation_rotation_summary(&v) {
        print!("{rotation}");
    }
    for w in &warnings {
        println!("warning: {w}");
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

//! `deflex calibrate`, `validate`, `plan`: identification of the elasto-geometrical model
//! (Johra et al. 2022, Section 3) from laser-tracker measurements.

use crate::args::{CliResult, robot};
use clap::Args;
use deflex_calib::calib_report::{CalibrationReport, write_calibration_report};
use deflex_calib::cell::{
    MAX_PLAN_FORCE_N, MAX_USER_POINTS, default_force_n, parse_directions, parse_point_flag,
    read_points,
};
use deflex_calib::consistency::{
    GeometryCheck, MAX_FK_TOLERANCE_M, MIN_FK_TOLERANCE_M, check_geometry, enforce,
};
use deflex_calib::fit::{Calibration, Status, Structure, calibrate_fixed};
use deflex_calib::plan::{
    BasePoint, Floor, LoadKind, PlanOptions, PointSet, Table, TableOption, plan_experiments,
};
use deflex_calib::report::{
    EXPECTED_SE_HEADERS, EXPECTED_SHIFT_HEADERS, ITERATION_HEADERS, SHIFT_HEADERS,
    STIFFNESS_HEADERS, TECHNICIAN_HEADERS, VALIDATION_HEADERS, correlation_table, expected_se_rows,
    expected_shift_rows, iteration_rows, render_table, residual_summary, shift_rows,
    stiffness_rows, technician_rows, validation_rows,
};
use deflex_calib::search::{Criterion, SearchOptions, SearchStep, search_structure};
use deflex_calib::validate::{validate as run_validation, write_report};
use deflex_calib::{read_file, write_rows_for};
use deflex_files::{AtomicDir, AtomicFile};
use deflex_model::{Robot, robot_to_toml_for};
use serde_json::{Value, json};
use std::io::Write as _;
use std::path::{Path, PathBuf};

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
    #[arg(long, default_value = "auto", value_parser = ["auto", "fixed"])]
    pub structure: String,
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
    #[arg(long, default_value = "bic", value_parser = ["bic", "cv"])]
    pub criterion: String,
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
    /// Output robot TOML (a drop-in for every other command).
    #[arg(long)]
    pub out: PathBuf,
    /// Folder for an HTML report with plots and CSV tables (replaced whole).
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
    /// Largest distance between a row's point coordinates and the model's forward kinematics
    /// of its joint values (mm, 0.001 to 1000): more refuses the file.
    #[arg(long, default_value_t = 1.0)]
    pub fk_tolerance_mm: f64,
    /// Use the file even when its coordinates disagree with the model's forward kinematics.
    #[arg(long)]
    pub ignore_fk_check: bool,
    /// Folder for PNG plots and validation.html (replaced whole, or left as it was on error).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

#[derive(Args)]
pub struct PlanArgs {
    /// Nominal model: built-in name or TOML file (joint limits required).
    #[arg(long)]
    pub robot: String,
    /// Cable tension (N, up to 1e5). Default: from the robot (the force whose median TCP
    /// deflection is 2.5 mm with its stiffnesses, at most half the arm's weight when its masses
    /// are known): 1400 N for the TX200, 140 N for a UR10e.
    #[arg(long = "max-force-N")]
    pub max_force_n: Option<f64>,
    /// How loads are applied: cable (tension along --cable-directions) or dead-weight (masses
    /// along gravity, --masses-kg).
    #[arg(long, default_value = "cable", value_parser = ["cable", "dead-weight"])]
    pub load: String,
    /// Directions a cable may lead from the attachment (world axes): x,-x,y,-y,z,-z (default
    /// all; +z needs an overhead anchor).
    #[arg(long)]
    pub cable_directions: Option<String>,
    /// Dead weights (kg, comma-separated, at most 4). Default: one weight of the default force.
    #[arg(long)]
    pub masses_kg: Option<String>,
    /// Off-axis bracket: load point offset from the TCP in the TCP frame (m, `x,y,z`, e.g.
    /// 0.2,0,0). Loads then also act there, its moment turns the wrist, and the bracket point
    /// is measured (`BR`).
    #[arg(long)]
    pub bracket_m: Option<String>,
    /// Number of load cases (1 to 1000; axis-by-axis ones included).
    #[arg(long, default_value_t = 24)]
    pub load_cases: usize,
    /// Plan for every eDoF of the model family (what `calibrate --structure auto` needs), not
    /// only the model's.
    #[arg(long)]
    pub full_family: bool,
    /// Points measured on the arm besides the TCP: `standard` (two mid-arm points), `none`, or
    /// a CSV file with columns name,link,x_m,y_m,z_m (position in the link's frame).
    #[arg(long, default_value = "standard")]
    pub points: String,
    /// An extra measured point `NAME,LINK,X,Y,Z` (m, link frame; repeatable).
    #[arg(long)]
    pub point: Vec<String>,
    /// Base reflector M0 position in R0 (m, `x,y,z`). Default: (0.3, 0, −0.3), raised to
    /// 0.15 m above the floor when the floor is higher.
    #[arg(long)]
    pub base_point_m: Option<String>,
    /// Do not measure the base reflector M0 (which separates a baseplate tilt from joint 1).
    #[arg(long)]
    pub no_base_point: bool,
    /// Floor height (world z, m). Default: from the robot (its base pivot, the TX200's
    /// 0.642 m shoulder height, or R0 when R0 is below the shoulder).
    #[arg(long)]
    pub floor_z_m: Option<f64>,
    /// No floor check.
    #[arg(long)]
    pub no_floor: bool,
    /// Work table `x_min,x_max,y_min,y_max,top_z` (world, m). Default: in front of the robot,
    /// x 0.5–0.85 × reach, y ±0.3 × reach, top 0.2 × reach above the floor.
    #[arg(long)]
    pub table: Option<String>,
    /// No table check.
    #[arg(long)]
    pub no_table: bool,
    /// Clearance kept above the floor and the table (m, 0 to 1).
    #[arg(long, default_value_t = 0.05)]
    pub clearance_m: f64,
    /// Free height a dead weight or a cable leading down needs below its attachment (m, 0 to 5).
    #[arg(long, default_value_t = 0.3)]
    pub hanging_drop_m: f64,
    /// Tracker noise (µm, 0.001 to 10000) for the expected standard errors.
    #[arg(long, default_value_t = 15.0)]
    pub noise_um: f64,
    /// Random configurations tried (1 to 2000; each with every load direction or weight).
    #[arg(long, default_value_t = 600)]
    pub configurations: usize,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output plan CSV (with `# robot:` and `# geometry:` header lines).
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
        "chi2_well_above_one": cal.reduced_chi2 > deflex_calib::fit::CHI2_WELL_ABOVE_ONE,
        "model_form_note": cal.model_form_note(),
        "warnings": cal.warnings,
    })
}

/// Read a measurement file for `robot` and check its coordinates against the robot's forward
/// kinematics; the warnings to print, or the refusal.
fn read_checked(
    robot: &Robot,
    data: &Path,
    tolerance_mm: f64,
    ignore: bool,
) -> Result<
    (
        Vec<deflex_calib::MeasurementRow>,
        GeometryCheck,
        Vec<String>,
    ),
    String,
> {
    if !(tolerance_mm.is_finite()
        && (MIN_FK_TOLERANCE_M * 1e3..=MAX_FK_TOLERANCE_M * 1e3).contains(&tolerance_mm))
    {
        return Err(format!(
            "--fk-tolerance-mm: expected {} to {} mm, got {tolerance_mm}",
            MIN_FK_TOLERANCE_M * 1e3,
            MAX_FK_TOLERANCE_M * 1e3
        ));
    }
    let file = read_file(data, Some(robot.joint_count()), true).map_err(|e| e.to_string())?;
    let check = check_geometry(
        robot,
        &file.rows,
        Some(&file.lines),
        Some(&file.header),
        tolerance_mm * 1e-3,
    )
    .map_err(|e| format!("{}: {e}", data.display()))?;
    let warnings = enforce(
        &check,
        &data.display().to_string(),
        ignore,
        "Is this the robot the file was measured on? Widen the tolerance with --fk-tolerance-mm, or use the file anyway with --ignore-fk-check.",
    )
    .map_err(|e| e.to_string())?;
    Ok((file.rows, check, warnings))
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
        "first_disagreements": check.disagreements.iter().take(deflex_calib::consistency::ROWS_NAMED).map(|d| json!({"row": d.row + 1, "line": d.line, "load_case": d.load_case, "point": d.point, "distance_m": d.distance_m, "text": d.to_string()})).collect::<Vec<_>>(),
        "unchecked": check.unchecked,
        "header_mismatch": check.header_mismatch,
    })
}

/// A number flag within a range, named in the error.
fn check_range(flag: &str, value: f64, lo: f64, hi: f64) -> Result<(), String> {
    if value.is_finite() && value >= lo && value <= hi {
        Ok(())
    } else {
        Err(format!(
            "{flag}: expected a number from {lo} to {hi}, got {value}"
        ))
    }
}

pub fn calibrate(args: CalibrateArgs, json_output: bool) -> CliResult {
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
        return Err(format!("--folds: expected 2 to 100, got {}", args.folds));
    }
    let start = robot(&args.robot)?;
    let (rows, check, mut warnings) = read_checked(
        &start,
        &args.data,
        args.fk_tolerance_mm,
        args.ignore_fk_check,
    )?;
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
    if !cal.edofs.iter().any(|e| e.stiffness.is_some()) {
        return Err(format!(
            "{}: no eDoF could be identified from this data (every compliance is at its bound or not observable); nothing written",
            args.data.display()
        ));
    }
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
    // Everything is built aside and appears only when complete: the report folder first,
    // then the model.
    fn io(path: &Path) -> impl Fn(std::io::Error) -> String + '_ {
        move |e| format!("{}: {e}", path.display())
    }
    let mut model_file = AtomicFile::create(&args.out).map_err(io(&args.out))?;
    model_file
        .write_all(robot_to_toml_for(&model, &args.out).as_bytes())
        .map_err(io(&args.out))?;
    if let Some(dir) = &args.report {
        let folder = AtomicDir::create(dir).map_err(io(dir))?;
        let report = CalibrationReport {
            start_name: &start.name,
            data_name: &args.data.display().to_string(),
            output_name: &args.out.display().to_string(),
            calibration: &cal,
            model: &model,
            steps: &steps,
            stop_reason: stop.as_deref(),
            rows: &rows,
            warnings: &warnings,
        };
        write_calibration_report(folder.path(), &report).map_err(|e| e.to_string())?;
        folder.commit().map_err(io(dir))?;
    }
    model_file.commit().map_err(io(&args.out))?;
    warnings.extend(cal.warnings.iter().cloned());
    let it_rows = iteration_rows(&steps);
    let st_rows = stiffness_rows(&cal);
    let sh_rows = shift_rows(&cal);
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
        v["geometry_check"] = geometry_json(&check);
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

pub fn validate(args: ValidateArgs, json_output: bool) -> CliResult {
    let model = robot(&args.robot)?;
    let baseline = args.baseline.as_deref().map(robot).transpose()?;
    let (rows, check, warnings) = read_checked(
        &model,
        &args.data,
        args.fk_tolerance_mm,
        args.ignore_fk_check,
    )?;
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
    if let Some(rotation) = deflex_calib::report::validation_rotation_summary(&v) {
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

/// Comma-separated numbers of a flag, exactly `N` of them.
fn fixed<const N: usize>(flag: &str, text: &str) -> Result<[f64; N], String> {
    crate::args::parse_fixed::<N>(text, flag)
}

/// The plan options from the flags (every number checked, the flag named).
fn plan_options(args: &PlanArgs, nominal: &Robot) -> Result<PlanOptions, String> {
    let n = nominal.joint_count();
    let max_force_n = match args.max_force_n {
        Some(f) => {
            check_range("--max-force-N", f, 1e-3, MAX_PLAN_FORCE_N)?;
            f
        }
        None => default_force_n(nominal).map_err(|e| e.to_string())?,
    };
    check_range("--noise-um", args.noise_um, 1e-3, 1e4)?;
    check_range("--clearance-m", args.clearance_m, 0.0, 1.0)?;
    check_range("--hanging-drop-m", args.hanging_drop_m, 0.0, 5.0)?;
    if let Some(z) = args.floor_z_m {
        check_range("--floor-z-m", z, -100.0, 100.0)?;
    }
    let load = if args.load == "dead-weight" {
        if args.cable_directions.is_some() {
            return Err("--cable-directions: only with --load cable".into());
        }
        let g = nominal.gravity.norm();
        let masses_kg = match &args.masses_kg {
            Some(text) => crate::args::parse_list(text, "--masses-kg")?,
            None if g > 0.0 => vec![(max_force_n / g).round().max(1.0)],
            None => {
                return Err(format!(
                    "--load dead-weight: robot \"{}\" has no gravity",
                    nominal.name
                ));
            }
        };
        LoadKind::DeadWeight { masses_kg }
    } else {
        if args.masses_kg.is_some() {
            return Err("--masses-kg: only with --load dead-weight".into());
        }
        match &args.cable_directions {
            Some(text) => LoadKind::Cable {
                directions: parse_directions(text)
                    .map_err(|e| format!("--cable-directions: {e}"))?,
            },
            None => LoadKind::cable_all_axes(),
        }
    };
    let mut points = match args.points.as_str() {
        "standard" => PointSet::Standard,
        "none" => PointSet::Custom(Vec::new()),
        file => {
            PointSet::Custom(read_points(Path::new(file), n).map_err(|e| format!("--points: {e}"))?)
        }
    };
    if !args.point.is_empty() {
        let mut list = match points {
            PointSet::Standard => Vec::new(),
            PointSet::Custom(list) => list,
        };
        if args.points == "standard" {
            return Err(
                "--point: give --points none (or a file) with it; the standard mid-arm points are not combined with others".into(),
            );
        }
        for text in args.point.iter().take(MAX_USER_POINTS + 1) {
            list.push(parse_point_flag(text, n).map_err(|e| format!("--point {text}: {e}"))?);
        }
        if list.len() > MAX_USER_POINTS {
            return Err(format!("--point: at most {MAX_USER_POINTS} points"));
        }
        points = PointSet::Custom(list);
    }
    let base_point = match (&args.base_point_m, args.no_base_point) {
        (Some(_), true) => return Err("give --base-point-m or --no-base-point, not both".into()),
        (Some(text), false) => BasePoint::At(fixed::<3>("--base-point-m", text)?),
        (None, true) => BasePoint::Off,
        (None, false) => BasePoint::Default,
    };
    let floor = match (args.floor_z_m, args.no_floor) {
        (Some(_), true) => return Err("give --floor-z-m or --no-floor, not both".into()),
        (Some(z), false) => Floor::At(z),
        (None, true) => Floor::Off,
        (None, false) => Floor::Default,
    };
    let table = match (&args.table, args.no_table) {
        (Some(_), true) => return Err("give --table or --no-table, not both".into()),
        (Some(text), false) => {
            let [x0, x1, y0, y1, top] = fixed::<5>("--table", text)?;
            TableOption::At(Table {
                x_m: [x0, x1],
                y_m: [y0, y1],
                top_z_m: top,
            })
        }
        (None, true) => TableOption::Off,
        (None, false) => TableOption::Default,
    };
    let bracket_m = args
        .bracket_m
        .as_deref()
        .map(|text| fixed::<3>("--bracket-m", text))
        .transpose()?;
    Ok(PlanOptions {
        max_force_n,
        load_cases: args.load_cases,
        configurations: args.configurations,
        noise_sigma_m: args.noise_um * 1e-6,
        seed: args.seed,
        full_family: args.full_family,
        base_point,
        points,
        floor,
        table,
        clearance_m: args.clearance_m,
        hanging_drop_m: args.hanging_drop_m,
        load,
        bracket_m,
    })
}

pub fn plan(args: PlanArgs, json_output: bool) -> CliResult {
    let nominal = robot(&args.robot)?;
    let options = plan_options(&args, &nominal)?;
    let plan = plan_experiments(&nominal, &options).map_err(|e| e.to_string())?;
    write_rows_for(&args.out, &nominal, &plan.rows, &[]).map_err(|e| e.to_string())?;
    let cases = deflex_calib::data::load_case_count(&plan.rows);
    let setup = &plan.setup;
    let load_text = match &setup.load {
        LoadKind::Cable { directions } => format!(
            "cable, {:.0} N along {}",
            setup.force_n,
            directions
                .iter()
                .map(|d| direction_name(*d))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        LoadKind::DeadWeight { masses_kg } => format!(
            "dead weights {} kg",
            masses_kg
                .iter()
                .map(|m| format!("{m}"))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    if json_output {
        let expected: Vec<Value> = plan
            .expected
            .iter()
            .map(|e| json!({"edof": e.label, "nominal_k": e.nominal_k, "expected_se_k": finite_or_null(e.se_k), "relative": finite_or_null(e.relative), "identifiable": e.identifiable()}))
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
        let setup_json = json!({
            "force_N": setup.force_n,
            "load": load_text,
            "bracket_m": setup.bracket_m,
            "floor_z_m": setup.floor_z_m,
            "table": setup.table.map(|t| json!({"x_m": t.x_m, "y_m": t.y_m, "top_z_m": t.top_z_m})),
            "base_point_r0_m": setup.base_point_r0_m,
            "configurations_drawn": setup.configurations_drawn,
            "configurations_kept": setup.configurations_kept,
        });
        let sheet: Vec<Value> = technician_rows(&plan)
            .into_iter()
            .map(|r| json!({"case": r[0], "q_deg": r[1], "load": r[2], "force_N": r[3], "measure": r[4], "why": r[5]}))
            .collect();
        println!(
            "{}",
            serde_json::to_string_pretty(&json!({"robot": nominal.name, "geometry": nominal.geometry_fingerprint(), "load_cases": cases, "rows": plan.rows.len(), "output": args.out.display().to_string(), "setup": setup_json, "expected": expected, "expected_shifts": shifts, "axis_by_axis": axis, "technician_sheet": sheet, "log_det": plan.log_det}))
                .unwrap_or_default()
        );
        return Ok(());
    }
    println!(
        "Plan for {}: {} load cases ({} axis-by-axis + D-optimal), {} points to measure; {load_text}{}",
        nominal.name,
        cases,
        plan.axis_cases
            .iter()
            .map(|a| a.load_case.as_str())
            .collect::<std::collections::BTreeSet<_>>()
            .len(),
        plan.rows.len(),
        setup
            .bracket_m
            .map(|b| format!(
                ", at the TCP and at the bracket ({:.3}, {:.3}, {:.3}) m in the TCP frame",
                b[0], b[1], b[2]
            ))
            .unwrap_or_else(|| " at the TCP".into())
    );
    println!(
        "Cell: floor {}; table {}; base reflector M0 {}; {} of {} configurations drawn were clear",
        setup
            .floor_z_m
            .map_or("not checked".to_string(), |z| format!("at z = {z:.3} m")),
        setup.table.map_or("not checked".to_string(), |t| format!(
            "top z = {:.3} m over x {:.3}…{:.3} m, y {:.3}…{:.3} m",
            t.top_z_m, t.x_m[0], t.x_m[1], t.y_m[0], t.y_m[1]
        )),
        setup
            .base_point_r0_m
            .map_or("not measured".to_string(), |p| format!(
                "at ({:.3}, {:.3}, {:.3}) m in R0",
                p[0], p[1], p[2]
            )),
        setup.configurations_kept,
        setup.configurations_drawn
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
        "\nLoad cases for the technician (joint values in degrees within the joint limits; force in world axes):"
    );
    print!(
        "{}",
        render_table(&TECHNICIAN_HEADERS, &technician_rows(&plan))
    );
    println!("wrote {}", args.out.display());
    Ok(())
}

/// `+x`, `-z`, … for a world axis direction, else the vector.
fn direction_name(d: [f64; 3]) -> String {
    for (axis, name) in ["x", "y", "z"].iter().enumerate() {
        if d[axis] == 1.0 {
            return format!("+{name}");
        }
        if d[axis] == -1.0 {
            return format!("-{name}");
        }
    }
    format!("({:.2}, {:.2}, {:.2})", d[0], d[1], d[2])
}

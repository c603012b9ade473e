//! What a compensation reports: the header lines of the table and the programs, the table
//! (`compensated_path.csv`), the summaries (text and JSON) and the refusal when points are not
//! compensated or the iteration did not converge.

use super::CompensationRun;
use crate::error::{Error, Result};
use deflex_compensate::table::write_csv;
use serde_json::{Value, json};
use std::fmt::Write as _;

/// Failed points listed in a refusal.
const LISTED_FAILURES: usize = 20;

/// Failed points listed in the JSON summaries.
const JSON_FAILURES: usize = 1000;

/// Header lines of the table and of the programs: the path, the robot and the wrench source,
/// the placement, the predicted errors.
pub fn description(run: &CompensationRun) -> Vec<String> {
    let s = &run.setup;
    let result = &run.result;
    let simulated = if result.simulated { "SIMULATED " } else { "" };
    vec![
        format!(
            "{simulated}deflex offline compensation of \"{}\" ({} points, {:.1} mm)",
            s.path.name(),
            s.path.len(),
            s.path.length_m() * 1e3
        ),
        format!(
            "robot model \"{}\", geometry {}; wrenches: {}",
            s.robot.name,
            s.robot.geometry_fingerprint(),
            result.source
        ),
        s.placement_line(),
        s.tool_line(),
        format!(
            "predicted error {:.4} mm uncompensated, {:.4} mm compensated; largest compensation {:.4} mm, {:.4} mrad",
            result
                .iterations
                .first()
                .map_or(0.0, |r| r.max_predicted_error_m * 1e3),
            result.final_max_error_m * 1e3,
            result.max_compensation_m * 1e3,
            result.max_compensation_rad * 1e3
        ),
    ]
}

/// The comment lines of `compensated_path.csv`.
pub fn table_comments(run: &CompensationRun) -> Vec<String> {
    let mut comments = description(run);
    comments.extend(run.source_lines.iter().cloned());
    comments.push("SI units; commanded = desired ⊕ compensation (dx_m … drz_rad); world frame of the robot model; rx_rad … rz_rad: the TCP orientation (rotation vector, world)".into());
    comments
}

/// `compensated_path.csv` in memory (usable as `deflex run`'s `[feedforward]`).
pub fn table_csv(run: &CompensationRun) -> String {
    write_csv(
        &run.setup.path,
        &run.result,
        run.setup.robot.joint_count(),
        &table_comments(run),
    )
}

/// Per point `ok` or the code of the reason it was not compensated.
pub fn statuses(run: &CompensationRun) -> Vec<String> {
    run.result
        .points
        .iter()
        .map(|p| p.failure.map_or_else(|| "ok".to_string(), |f| f.code()))
        .collect()
}

/// The refusal: no program when points are not compensated (listing the first ones, with what
/// to try) or the iteration did not converge.
pub fn refusal(run: &CompensationRun) -> Result<()> {
    let s = &run.setup;
    let result = &run.result;
    let count = result.failure_count();
    if count > 0 {
        let names = s.front;
        let mut list: Vec<String> = result
            .failures()
            .take(LISTED_FAILURES)
            .map(|(i, f)| format!("  point {i}: {f}"))
            .collect();
        if count > LISTED_FAILURES {
            list.push(format!("  … and {} more", count - LISTED_FAILURES));
        }
        return Err(Error::PointsNotCompensated {
            count,
            points: s.path.len(),
            list: list.join("\n"),
            hint: format!(
                "The path was placed with the {}: move the part with {} x,y,z or choose the arm's branch with {} (deflex sim robot --robot R prints the robot's cell).",
                s.placement_line(),
                names.name("part_xyz_m"),
                names.name("seed_q"),
            ),
        });
    }
    if !result.converged {
        let last = result.iterations.last();
        return Err(Error::NotConverged {
            iterations: result.iterations.len(),
            change_mm: last.map_or(f64::NAN, |r| r.max_change_m * 1e3),
            change_mrad: last.map_or(f64::NAN, |r| r.max_change_rad * 1e3),
            tolerance_mm: s.options.tolerance_m * 1e3,
        });
    }
    Ok(())
}

/// The iterations for the JSON summaries.
fn iteration_json(run: &CompensationRun) -> Vec<Value> {
    run.result
        .iterations
        .iter()
        .map(|r| {
            json!({
                "iteration": r.iteration,
                "max_predicted_error_m": r.max_predicted_error_m,
                "max_predicted_error_rad": r.max_predicted_error_rad,
                "max_force_N": r.max_force_n,
                "max_deflection_m": r.max_deflection_m,
                "max_change_m": r.max_change_m,
                "max_change_rad": r.max_change_rad,
                "failed_points": r.failed_points,
                "solved_points": r.solved_points,
            })
        })
        .collect()
}

/// The compensation's numbers (`summary.json`'s `compensation`, SI): the wrench source, the
/// iterations, the final predicted error, the largest compensation, the failed points, the law
/// identified from a log.
pub fn compensation_json(run: &CompensationRun) -> Value {
    let result = &run.result;
    let failures: Vec<Value> = result
        .failures()
        .take(JSON_FAILURES)
        .map(|(i, f)| json!({"index": i, "status": f.code(), "reason": f.to_string()}))
        .collect();
    json!({
        "simulated": result.simulated,
        "wrench_source": result.source,
        "converged": result.converged,
        "iterations": iteration_json(run),
        "final_max_predicted_error_m": result.final_max_error_m,
        "final_max_predicted_error_rad": result.final_max_error_rad,
        "final_max_force_N": result.final_max_force_n,
        "max_compensation_m": result.max_compensation_m,
        "max_compensation_rad": result.max_compensation_rad,
        "failed_points": result.failure_count(),
        "failures": failures,
        "log_law": run.log_law,
    })
}

/// The run's part of `summary.json`: the robot, the path and its placement, the options, the
/// compensation ([`compensation_json`]); the output folder adds its programs and files.
pub(super) fn run_json(run: &CompensationRun) -> serde_json::Map<String, Value> {
    let s = &run.setup;
    let fields = [
        ("robot", json!(s.robot.name)),
        ("robot_geometry", json!(s.robot.geometry_fingerprint())),
        ("path", json!(s.path.name())),
        ("points", json!(s.path.len())),
        ("path_length_m", json!(s.path.length_m())),
        ("part_frame", json!(s.frame_name)),
        ("part_origin_m", json!(s.part_origin_mm.map(|v| v * 1e-3))),
        ("seed_q_rad", json!(s.seed)),
        ("placement", json!(s.placement_source)),
        (
            "tool_xyz_m",
            json!(<[f64; 3]>::from(s.robot.tool.translation.vector)),
        ),
        (
            "tool_rpy_rad",
            json!(deflex_model::spatial::rpy_from_rotation(
                &s.robot.tool.rotation
            )),
        ),
        ("tool", json!(s.tool_source)),
        ("gcode_notes", json!(s.notes)),
        ("orientation_compensated", json!(s.options.orientation)),
        ("tolerance_m", json!(s.options.tolerance_m)),
        ("tolerance_rad", json!(s.options.tolerance_rad)),
        ("compensation", compensation_json(run)),
        ("run_on_a_real_controller", json!(false)),
        ("elapsed_s", json!(run.elapsed_s)),
    ];
    fields
        .into_iter()
        .map(|(key, value)| (key.to_string(), value))
        .collect()
}

/// The summary as one flat object (Python's `Compensation.to_dict`): the run's part of
/// `summary.json` with the compensation's numbers at the top and the wrench source's lines.
pub fn summary_dict(run: &CompensationRun) -> Value {
    let mut map = run_json(run);
    if let Some(Value::Object(numbers)) = map.remove("compensation") {
        map.extend(numbers);
    }
    map.insert("source_lines".into(), json!(run.source_lines));
    Value::Object(map)
}

/// The summary's text: the path, the robot and the placement, the wrench source, a line per
/// iteration, the result (the output folder adds its programs and files).
pub fn summary_text(run: &CompensationRun) -> String {
    let s = &run.setup;
    let result = &run.result;
    let mut t = String::new();
    for line in description(run).iter().take(4) {
        let _ = writeln!(t, "{line}");
    }
    for line in &run.source_lines {
        let _ = writeln!(t, "  {line}");
    }
    let _ = writeln!(
        t,
        "  iteration   predicted error (mm, mrad)   max force (N)   max change (mm, mrad)   solved   failed"
    );
    for r in &result.iterations {
        let _ = writeln!(
            t,
            "  {:>9}   {:>10.4} {:>10.4}        {:>10.1}      {:>9.5} {:>9.5}   {:>6}   {:>6}",
            r.iteration,
            r.max_predicted_error_m * 1e3,
            r.max_predicted_error_rad * 1e3,
            r.max_force_n,
            r.max_change_m * 1e3,
            r.max_change_rad * 1e3,
            r.solved_points,
            r.failed_points
        );
    }
    let _ = writeln!(
        t,
        "  {} in {} iteration(s) (tolerance {:.4} mm); after compensation the model predicts {:.5} mm, {:.5} mrad of error at {:.0} N",
        if result.converged {
            "converged"
        } else {
            "NOT converged"
        },
        result.iterations.len(),
        s.options.tolerance_m * 1e3,
        result.final_max_error_m * 1e3,
        result.final_max_error_rad * 1e3,
        result.final_max_force_n
    );
    let _ = writeln!(
        t,
        "  largest compensation {:.4} mm, {:.4} mrad; {} point(s) not compensated; {:.2} s",
        result.max_compensation_m * 1e3,
        result.max_compensation_rad * 1e3,
        result.failure_count(),
        run.elapsed_s
    );
    t
}

//! The measurement campaign for a real cell (`deflex plan`): floor, table, cable or dead-weight
//! loads, bracket, measured points; the plan file, the expected standard errors and the
//! technician's sheet.
//!
//! The front end builds the [`PlanOptions`] from its arguments (with [`default_force_n`],
//! [`default_masses_kg`] and [`read_point_set`] for what the robot or a file decides); [`plan`]
//! plans and writes the file, [`plan_text`] and [`plan_json`] say what it holds.

use super::choice::PointsChoice;
use super::summary::finite_or_null;
use crate::error::Result;
use crate::report::plan_tables::{
    EXPECTED_SE_HEADERS, EXPECTED_SHIFT_HEADERS, TECHNICIAN_HEADERS, expected_se_rows,
    expected_shift_rows, technician_rows,
};
use crate::report::text_table::render_table;
pub use deflex_calibrate::measurements::points::{
    MAX_USER_POINTS, PointProblem, PointSpec, parse_point_flag,
};
use deflex_calibrate::measurements::{format_rows_for, load_case_count};
pub use deflex_calibrate::stiffness::campaign_cell::{MAX_PLAN_FORCE_N, parse_directions};
pub use deflex_calibrate::stiffness::plan::{
    BasePoint, Floor, LoadKind, Plan, PlanOptions, PointSet, TableOption, WorkTable,
};
use deflex_calibrate::stiffness::{CalibError, PlanError, plan::plan_experiments};
use deflex_model::Robot;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// The cable tension (or dead weight's force) a plan uses by default for `nominal` (N): the
/// force whose median TCP deflection is 2.5 mm with its stiffnesses, at most half the arm's
/// weight when its masses are known.
pub fn default_force_n(nominal: &Robot) -> Result<f64> {
    Ok(deflex_calibrate::stiffness::campaign_cell::default_force_n(
        nominal,
    )?)
}

/// The dead weight a plan uses by default (kg): one weight of `force_n`, rounded to the
/// kilogram (at least 1 kg); refused for a robot without gravity.
pub fn default_masses_kg(nominal: &Robot, force_n: f64) -> Result<Vec<f64>> {
    let g = nominal.gravity.norm();
    if g > 0.0 {
        Ok(vec![(force_n / g).round().max(1.0)])
    } else {
        Err(CalibError::from(PlanError::NoGravity {
            robot: nominal.name.clone(),
        })
        .into())
    }
}

/// The points measured besides the TCP, for a robot with `joint_count` joints: the standard
/// mid-arm points, none, or the points of a file (read here).
pub fn read_point_set(choice: &PointsChoice, joint_count: usize) -> Result<PointSet> {
    Ok(match choice {
        PointsChoice::Standard => PointSet::Standard,
        PointsChoice::None => PointSet::Custom(Vec::new()),
        PointsChoice::File(file) => PointSet::Custom(crate::load::read_points(file, joint_count)?),
    })
}

/// A campaign planned and written.
pub struct CampaignPlan {
    /// The nominal model it was planned for.
    pub robot: Robot,
    /// The plan.
    pub plan: Plan,
    /// Where the plan file was written.
    pub output: PathBuf,
    /// Load cases asked for (the plan may hold more: every eDoF gets its own axis-by-axis case).
    pub load_cases_asked: usize,
}

/// Plan the campaign for `nominal` and write it to `out` (the measurement format without
/// displacements, with `# robot:` and `# geometry:` header lines), whole or not at all.
pub fn plan(nominal: &Robot, options: &PlanOptions, out: &Path) -> Result<CampaignPlan> {
    let plan = plan_experiments(nominal, options)?;
    crate::table::write_text(out, &format_rows_for(nominal, &plan.rows, &[]))?;
    Ok(CampaignPlan {
        robot: nominal.clone(),
        plan,
        output: out.to_path_buf(),
        load_cases_asked: options.load_cases,
    })
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

/// The loads in words: `cable, 1400 N along +x, -x` or `dead weights 140 kg`.
fn load_text(p: &CampaignPlan) -> String {
    let setup = &p.plan.setup;
    match &setup.load {
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
    }
}

/// The plan as JSON (SI; `deflex plan --json`): the set-up, the expected standard errors, the
/// axis-by-axis cases and the technician's sheet.
pub fn plan_json(p: &CampaignPlan) -> Value {
    let plan = &p.plan;
    let setup = &plan.setup;
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
        .map(|a| json!({"edof": deflex_calibrate::stiffness::edof_label(a.id), "load_case": a.load_case, "share": a.share, "snr": a.snr}))
        .collect();
    let setup_json = json!({
        "force_N": setup.force_n,
        "load": load_text(p),
        "bracket_m": setup.bracket_m,
        "floor_z_m": setup.floor_z_m,
        "table": setup.table.map(|t| json!({"x_m": t.x_m, "y_m": t.y_m, "top_z_m": t.top_z_m})),
        "base_point_r0_m": setup.base_point_r0_m,
        "configurations_drawn": setup.configurations_drawn,
        "configurations_kept": setup.configurations_kept,
    });
    let sheet: Vec<Value> = technician_rows(plan)
        .into_iter()
        .map(|r| json!({"case": r[0], "q_deg": r[1], "load": r[2], "force_N": r[3], "measure": r[4], "why": r[5]}))
        .collect();
    json!({
        "robot": p.robot.name,
        "geometry": p.robot.geometry_fingerprint(),
        "load_cases": load_case_count(&plan.rows),
        "rows": plan.rows.len(),
        "output": p.output.display().to_string(),
        "setup": setup_json,
        "expected": expected,
        "expected_shifts": shifts,
        "axis_by_axis": axis,
        "technician_sheet": sheet,
        "log_det": plan.log_det,
    })
}

/// The plan as text (`deflex plan`): what it measures, the cell, the expected standard errors
/// with `noise_um` of tracker noise (µm, as the user gave it: the options hold it in metres),
/// the technician's sheet and the file written.
pub fn plan_text(p: &CampaignPlan, noise_um: f64) -> String {
    let plan = &p.plan;
    let setup = &plan.setup;
    let cases = load_case_count(&plan.rows);
    let mut t = format!(
        "Plan for {}: {} load cases ({} axis-by-axis + D-optimal), {} points to measure; {}{}\n",
        p.robot.name,
        cases,
        plan.axis_cases
            .iter()
            .map(|a| a.load_case.as_str())
            .collect::<std::collections::BTreeSet<_>>()
            .len(),
        plan.rows.len(),
        load_text(p),
        setup
            .bracket_m
            .map(|b| format!(
                ", at the TCP and at the bracket ({:.3}, {:.3}, {:.3}) m in the TCP frame",
                b[0], b[1], b[2]
            ))
            .unwrap_or_else(|| " at the TCP".into())
    );
    t.push_str(&format!(
        "Cell: floor {}; table {}; base reflector M0 {}; {} of {} configurations drawn were clear\n",
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
    ));
    t.push_str(&format!(
        "Expected standard errors with {noise_um:.1} µm tracker noise:\n"
    ));
    t.push_str(&render_table(&EXPECTED_SE_HEADERS, &expected_se_rows(plan)));
    if !plan.expected_shifts.is_empty() {
        t.push_str(&render_table(
            &EXPECTED_SHIFT_HEADERS,
            &expected_shift_rows(plan),
        ));
    }
    if p.load_cases_asked < cases {
        t.push_str(&format!(
            "note: {cases} load cases instead of the {} asked for: every eDoF gets its own axis-by-axis case\n",
            p.load_cases_asked
        ));
    }
    t.push_str(
        "\nLoad cases for the technician (joint values in degrees within the joint limits; force in world axes):\n",
    );
    t.push_str(&render_table(&TECHNICIAN_HEADERS, &technician_rows(plan)));
    t.push_str(&format!("wrote {}\n", p.output.display()));
    t
}

//! Shared set-up: the model identified from the twin's own calibration campaign (seed 11), made
//! once for the whole test binary; a careful loaded campaign on a twin and its structure search.

use deflex_calibrate::measurements::MeasurementRow;
use deflex_calibrate::stiffness::plan::{PlanOptions, plan_experiments};
use deflex_calibrate::stiffness::search::{SearchOptions, SearchResult, search_structure};
use deflex_model::Robot;
use deflex_sim::CellConfig;
use std::sync::OnceLock;

/// The TX200 model identified from the default cell's campaign (never the plant).
pub fn calibrated_model() -> Robot {
    static MODEL: OnceLock<Robot> = OnceLock::new();
    MODEL
        .get_or_init(|| {
            deflex_app::twin::identify_from_twin_campaign(&CellConfig::default(), 11)
                .expect("identification from the twin's campaign")
        })
        .clone()
}

/// A careful static campaign on the twin of `cell`, planned for `nominal` (40 load cases, every
/// eDoF family; seed 1), each tracker reading the mean of 25 samples (0.5 s at 50 Hz, so the
/// white part of the tracker noise drops below the unmodelled effects), and the model structure
/// searched from it: the measurements and the search.
pub fn careful_campaign(nominal: &Robot, cell: &CellConfig) -> (Vec<MeasurementRow>, SearchResult) {
    let plan = plan_experiments(
        nominal,
        &PlanOptions {
            load_cases: 40,
            full_family: true,
            ..PlanOptions::default()
        },
    )
    .unwrap();
    let mut campaign_cell = cell.clone();
    campaign_cell.tracker.samples_per_reading = 25;
    let rows = deflex_sim::twin_campaign::run_campaign(&campaign_cell, &plan.rows, 1).unwrap();
    let search = search_structure(nominal, &rows, &SearchOptions::default(), &mut |_| {}).unwrap();
    (rows, search)
}

/// Largest path error (mm) over the rows with at least 20 N of contact force whose desired
/// TCP is on a feed move of `reference` (not on a rapid: the retract); `None`: every row.
pub fn max_contact_error_mm(
    run: &deflex_sim::FormingRun,
    reference: Option<&deflex_sim::ToolPath>,
) -> f64 {
    let rapids: Vec<(nalgebra::Vector3<f64>, nalgebra::Vector3<f64>)> =
        reference.map_or(Vec::new(), |r| {
            r.waypoints
                .windows(2)
                .filter(|w| w[1].feed_mm_s.is_none())
                .map(|w| {
                    (
                        nalgebra::Vector3::from(w[0].p_mm) * 1e-3,
                        nalgebra::Vector3::from(w[1].p_mm) * 1e-3,
                    )
                })
                .collect()
        });
    let on_rapid = |p: &nalgebra::Vector3<f64>| {
        rapids.iter().any(|(a, b)| {
            let ab = b - a;
            let t = ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
            (a + ab * t - p).norm() < 1e-6 && (p - a).norm() > 1e-6
        })
    };
    run.log
        .rows
        .iter()
        .filter(|row| reference.is_none() || row.truth.force_norm_n() >= 20.0)
        .filter(|row| !on_rapid(&row.truth.desired_m))
        .map(|row| row.truth.path_error_m().norm() * 1e3)
        .fold(0.0, f64::max)
}

/// A KR 210-like cell with an unseen plant (kept here, out of the built-in cells).
fn unseen_cell(
    coupling: f64,
    lost_motion_rad: f64,
    takeup_nm: f64,
    holder: (f64, f64),
) -> CellConfig {
    let mut cell = CellConfig::for_robot("kr210-r2700").unwrap();
    let p = &mut cell.plant;
    p.j2_j3_coupling = coupling;
    // Hardening wrist: lost motion taken up over a large torque.
    p.wrist_lost_motion_rad = [lost_motion_rad; 3];
    p.wrist_takeup_torque_nm = takeup_nm;
    p.wrist_hysteresis_nm = 0.1 * takeup_nm;
    // A compliant tool holder: J6 bending about x and y, centred down the tool.
    p.joint_stiffness[5][0] = holder.0;
    p.joint_stiffness[5][1] = holder.0;
    p.center_shift_m[5] = holder.1;
    cell.validate().unwrap();
    cell
}

/// Plant 1: J2/J3 coupling 0.3, 0.4 mrad of wrist lost motion taken up over 600 N·m, a tool
/// holder of 4e5 N·m/rad 80 mm down the tool.
pub fn plant_1() -> CellConfig {
    unseen_cell(0.3, 0.4e-3, 600.0, (4.0e5, 0.08))
}

/// Plant 2: coupling 0.2, 0.3 mrad over 400 N·m, a holder of 6e5 N·m/rad 60 mm down the tool.
pub fn plant_2() -> CellConfig {
    unseen_cell(0.2, 0.3e-3, 400.0, (6.0e5, 0.06))
}

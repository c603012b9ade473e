//! What the study starts from and states beside its headline: the one-eDoF start of the
//! structure search, and the twin's error sources with their levels.

use deflex_model::Robot;
use deflex_sim::CellConfig;

/// The one-eDoF-per-joint start of the structure search, from the nominal robot (with the
/// cell's tool and base pivot): its z-eDoFs, no x/y eDoF, no centre shift, no base eDoF (for the
/// TX200 the paper's baseline, `tx200-1edof`).
pub fn one_edof_start(nominal: &Robot) -> Robot {
    let mut start = nominal.clone();
    start.name = format!("{}, one eDoF per joint", nominal.name);
    start.base_stiffness = deflex_model::AxisStiffness::RIGID;
    for joint in &mut start.joints {
        let z = joint.stiffness.get(deflex_model::Axis::Z);
        joint.stiffness = deflex_model::AxisStiffness::RIGID;
        joint.stiffness.set(deflex_model::Axis::Z, z);
        joint.center_shift = 0.0;
    }
    start
}

/// The twin's error sources and effects with their levels, for the table beside the headline.
pub fn conditions(cell: &CellConfig) -> Vec<(String, String, bool)> {
    let e = &cell.errors;
    let c = &cell.controller;
    let s = &cell.sensor;
    let p = &cell.plant;
    let t = &cell.tracker;
    let max_abs = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let out = vec![
        (
            "plant: finite-rotation spring chain (geometric stiffness)".to_string(),
            "torques in the deformed configuration".to_string(),
            p.large_rotation,
        ),
        (
            "plant: base tilt about a floor pivot".to_string(),
            format!(
                "{:.1e} / {:.1e} N·m/rad about a pivot {:.0} mm below R0",
                p.base_stiffness[0],
                p.base_stiffness[1],
                -p.base_pivot_m[2] * 1e3
            ),
            p.base_stiffness.iter().any(|k| *k > 0.0),
        ),
        (
            "plant: J2/J3 coupling, secondary springs, wrist lost motion".to_string(),
            format!(
                "ρ = {}, lost motion up to ±{:.2} mrad with ±{} N·m hysteresis",
                p.j2_j3_coupling,
                max_abs(&p.wrist_lost_motion_rad) * 1e3,
                p.wrist_hysteresis_nm
            ),
            true,
        ),
        (
            "geometry: residual joint offsets and link-length errors".to_string(),
            format!(
                "up to {:.2} mrad and {:.2} mm (tool {:.2} mm)",
                max_abs(&p.joint_offset_error_rad) * 1e3,
                p.link_error_m
                    .iter()
                    .map(|l| max_abs(l))
                    .fold(0.0, f64::max)
                    * 1e3,
                norm(&p.tool_error_m) * 1e3
            ),
            e.geometry,
        ),
        (
            "robot controller: transport delay and interpolator filter".to_string(),
            format!(
                "{:.0} ms + {:.0} ms first order at {:.0} Hz",
                c.correction_delay_s * 1e3,
                c.correction_filter_s * 1e3,
                c.rate_hz
            ),
            true,
        ),
        (
            "servo dynamics and look-ahead".to_string(),
            format!(
                "{} Hz second order (ζ 0.7), {:.0} ms look-ahead",
                c.servo_bandwidth_hz,
                c.lookahead_s * 1e3
            ),
            e.servo,
        ),
        (
            "F/T gain error".to_string(),
            format!("up to {:.1} %", max_abs(&s.gain_error) * 100.0),
            e.sensor_gain,
        ),
        (
            "F/T bias drift".to_string(),
            format!("{:.1} N of Fz per 100 s", s.bias_drift_per_s[2] * 100.0),
            e.bias_drift,
        ),
        (
            "F/T noise".to_string(),
            format!("{} N, {} N·m (1σ)", s.noise_sigma[0], s.noise_sigma[3]),
            e.sensor_noise,
        ),
        (
            "sensor mounting the controller is not told".to_string(),
            format!(
                "{:.2} mm, {:.2}°",
                norm(&s.mounting_error_xyz_m) * 1e3,
                norm(&s.mounting_error_rpy).to_degrees()
            ),
            e.mounting,
        ),
        (
            "tool mass and centre of mass the controller is not told".to_string(),
            format!(
                "{:+.2} kg, {:.1} mm",
                s.tool_mass_error_kg,
                norm(&s.tool_com_error_m) * 1e3
            ),
            e.tool_load,
        ),
        (
            "tracker registration error (campaigns)".to_string(),
            format!(
                "{:.0} µm, {:.0} µrad",
                norm(&t.registration_error_xyz_m) * 1e6,
                norm(&t.registration_error_rpy) * 1e6
            ),
            e.tracker_registration,
        ),
        (
            "process: forming force at the actual step-down and wall angle, growing with depth"
                .to_string(),
            format!("Aerens level, κ = {}/mm", cell.sheet.depth_growth_per_mm),
            cell.sheet.actual_geometry,
        ),
    ];
    out
}

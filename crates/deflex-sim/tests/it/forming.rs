//! Forming-run tests of the twin: determinism, error magnitude, the sheet/robot interaction, the
//! correction-controller hook, and the full-length acceptance numbers.

use deflex_sim::sheet::SheetConfig;
use deflex_sim::{
    Cell, CellConfig, ConeParams, ControllerInput, CorrectionController, ToolPath, run_forming,
};

fn short_cone(depth_mm: f64) -> ToolPath {
    ToolPath::cone(&ConeParams {
        depth_mm,
        ..ConeParams::default()
    })
    .unwrap()
}

#[test]
fn same_seed_same_log_other_seed_other_noise() {
    let config = CellConfig::default();
    let path = ToolPath::paper_cone().truncated(60.0);
    let a = run_forming(&config, path.clone(), 1, None).unwrap();
    let b = run_forming(&config, path.clone(), 1, None).unwrap();
    assert_eq!(a.log, b.log);
    assert_eq!(a.summary, b.summary);
    assert_eq!(a.log.to_csv(), b.log.to_csv());
    let c = run_forming(&config, path, 2, None).unwrap();
    assert_ne!(a.log, c.log, "noise must depend on the seed");
    // The physics does not: same truth.
    assert_eq!(a.summary.max_error_norm_mm, c.summary.max_error_norm_mm);
}

#[test]
fn shortened_run_error_and_force_magnitudes() {
    // First 3 mm of depth (≈ 12 revolutions, ≈ 140 s).
    let run = run_forming(&CellConfig::default(), short_cone(3.0), 1, None).unwrap();
    let s = &run.summary;
    assert!(s.simulated);
    assert!(
        (0.5..2.0).contains(&s.max_error_norm_mm),
        "max error {} mm",
        s.max_error_norm_mm
    );
    assert!((150.0..800.0).contains(&s.max_fz_N), "Fz {}", s.max_fz_N);
    assert!(s.max_fxy_N < 0.5 * s.max_fz_N);
    // The deflected robot leaves the part shallower than programmed.
    assert!(
        s.final_part_depth_mm < 3.0 - 0.3,
        "depth {}",
        s.final_part_depth_mm
    );
    assert!(s.final_part_depth_mm > 1.0);
    let csv = run.log.to_csv();
    assert!(csv.starts_with("# SIMULATED"));
}

#[test]
fn a_stiffer_robot_forms_a_deeper_part_at_a_higher_force() {
    let soft = CellConfig::default();
    let mut stiff = CellConfig::default();
    for joint in stiff.plant.joint_stiffness.iter_mut() {
        for k in joint.iter_mut() {
            *k *= 20.0;
        }
    }
    for k in stiff.plant.base_stiffness.iter_mut() {
        *k *= 20.0;
    }
    stiff.plant.wrist_lost_motion_rad = [0.0; 3];
    let path = short_cone(4.0);
    let a = run_forming(&soft, path.clone(), 1, None).unwrap().summary;
    let b = run_forming(&stiff, path, 1, None).unwrap().summary;
    assert!(
        b.final_part_depth_mm > a.final_part_depth_mm + 0.5,
        "stiff {} vs soft {}",
        b.final_part_depth_mm,
        a.final_part_depth_mm
    );
    assert!(b.max_error_norm_mm < 0.3 * a.max_error_norm_mm);
    // Deeper forming meets a higher force (the level builds up with depth).
    assert!(b.max_fz_N > a.max_fz_N, "{} vs {}", b.max_fz_N, a.max_fz_N);
}

#[test]
fn a_harder_sheet_pushes_harder_and_deflects_more() {
    let mut hard = CellConfig::default();
    hard.sheet = SheetConfig {
        rm_mpa: 2.0 * hard.sheet.rm_mpa,
        ..hard.sheet.clone()
    };
    let path = short_cone(3.0);
    let a = run_forming(&CellConfig::default(), path.clone(), 1, None)
        .unwrap()
        .summary;
    let b = run_forming(&hard, path, 1, None).unwrap().summary;
    assert!(b.max_fz_N > 1.3 * a.max_fz_N);
    assert!(b.max_error_norm_mm > 1.3 * a.max_error_norm_mm);
}

struct Constant {
    xi: [f64; 6],
    calls: usize,
    samples: Vec<usize>,
}

impl CorrectionController for Constant {
    fn period_s(&self) -> f64 {
        0.01
    }
    fn step(&mut self, input: &ControllerInput) -> [f64; 6] {
        assert_eq!(input.q_measured_rad.len(), 6);
        self.calls += 1;
        self.samples.push(input.wrench_samples.len());
        self.xi
    }
}

#[test]
fn controller_hook_is_called_at_its_rate_and_its_correction_is_applied() {
    let config = CellConfig::default();
    let path = ToolPath::paper_cone().truncated(20.0); // ≈ 2 s
    let mut ctrl = Constant {
        xi: [0.0, 0.0, -0.001, 0.0, 0.0, 0.0],
        calls: 0,
        samples: Vec::new(),
    };
    let run = run_forming(&config, path.clone(), 1, Some(&mut ctrl)).unwrap();
    let duration = run.summary.duration_s;
    assert!(
        (ctrl.calls as f64 - duration / 0.01).abs() <= 2.0,
        "{} calls",
        ctrl.calls
    );
    // 1 kHz sensor, 100 Hz controller: 10 samples per call (after the first).
    assert!(
        ctrl.samples[1..]
            .iter()
            .all(|&n| n == 8 || n == 12 || n == 10 || n == 9 || n == 11)
    );
    let total: usize = ctrl.samples.iter().sum();
    assert!((total as f64 - duration * 1000.0).abs() < 20.0);
    assert!(run.summary.correction);
    let last = run.log.rows.last().unwrap();
    let cmd_minus_des = last.truth.commanded_m - last.truth.desired_m;
    assert!((cmd_minus_des.z + 0.001).abs() < 5e-6, "{cmd_minus_des}");
    // Pushing 1 mm deeper than programmed raises the force compared with open loop.
    let open = run_forming(&config, path, 1, None).unwrap();
    assert!(run.summary.max_fz_N > open.summary.max_fz_N);
}

#[test]
fn sensor_reports_bias_and_tool_weight_before_contact() {
    let config = CellConfig::default();
    let mut cell = Cell::new(&config, ToolPath::paper_cone().truncated(10.0), 1).unwrap();
    let mut sum = [0.0; 6];
    let mut n = 0.0;
    for _ in 0..2 {
        let step = cell.step();
        assert_eq!(step.q_measured_rad.len(), 6);
        for s in &step.sensor_samples {
            for (acc, v) in sum.iter_mut().zip(s.wrench_sensor) {
                *acc += v;
            }
            n += 1.0;
        }
    }
    // The true tool (nominal mass plus its error) hangs below the sensor.
    let (mass, _) = config.true_tool_load();
    let mg = mass * config.sensor.gravity_m_s2;
    // Tool pointing down, sensor z along the tool: the weight pulls along +z of the sensor.
    let fz = sum[2] / n;
    assert!((fz - (mg + config.sensor.bias[2])).abs() < 1.0, "{fz}");
    let fx = sum[0] / n;
    assert!((fx - config.sensor.bias[0]).abs() < 1.0, "{fx}");
    assert!(cell.robot_period_s() == 0.004 && !cell.is_finished());
}

/// The acceptance numbers of the uncorrected paper cone (≈ 494 s at 250 Hz).
#[test]
fn paper_cone_uncorrected_acceptance() {
    let run = run_forming(&CellConfig::default(), ToolPath::paper_cone(), 1, None).unwrap();
    let s = &run.summary;
    assert!(
        (2.88..=4.80).contains(&s.max_error_norm_mm),
        "max error {} mm, paper 3.84 ± 25 %",
        s.max_error_norm_mm
    );
    assert!((1150.0..=1350.0).contains(&s.max_fz_N), "Fz {}", s.max_fz_N);
    assert!(
        (400.0..=600.0).contains(&s.max_fxy_N),
        "Fxy {}",
        s.max_fxy_N
    );
    assert!((480.0..=520.0).contains(&s.duration_s), "{}", s.duration_s);
    // The in-plane force is near its maximum towards the end.
    let n = run.log.rows.len();
    let late_fxy = run.log.rows[n * 9 / 10..]
        .iter()
        .map(|r| r.truth.wrench[0].hypot(r.truth.wrench[1]))
        .fold(0.0, f64::max);
    assert!(late_fxy > 0.9 * s.max_fxy_N);
    assert!(
        s.final_part_depth_mm < 14.0,
        "part {}",
        s.final_part_depth_mm
    );
}

/// The part frame is taught with the robot, so the calibrated robot's residual geometry errors
/// (≈ 0.1–0.3 mm at the TCP) leave only their variation over the part in the path error.
#[test]
fn a_taught_part_frame_absorbs_the_geometry_error_but_not_its_variation() {
    let path = ToolPath::paper_cone().truncated(400.0);
    let mut ideal = CellConfig::default();
    ideal.errors.geometry = false;
    let with = run_forming(&CellConfig::default(), path.clone(), 1, None).unwrap();
    let without = run_forming(&ideal, path, 1, None).unwrap();
    let difference = (with.summary.max_error_norm_mm - without.summary.max_error_norm_mm).abs();
    assert!(difference < 0.05, "{difference} mm");
    // The first logged point, before contact: the taught frame leaves microns at most.
    let first = &with.log.rows[0].truth;
    assert!((first.true_m - first.desired_m).norm() < 5e-6);
}

/// The second scenario: a plunge into a stiff fixture. Without correction the contact and the
/// robot share the programmed interference as springs in series: F = δ / (1/k + C), with C the
/// robot's vertical compliance at the plunge pose (measured here with a small load on a cell
/// whose contact is soft enough for the force not to matter).
#[test]
fn a_plunge_into_a_stiff_fixture_shares_the_interference_with_the_robot() {
    use deflex_sim::{PlungeParams, ProcessKind};
    let path = ToolPath::plunge(&PlungeParams::default()).unwrap();
    let mut forces = Vec::new();
    for k in [1e5, 1e6, 1e7] {
        let mut config = CellConfig::default();
        config.process.kind = ProcessKind::Fixture;
        config.process.fixture_stiffness_n_m = k;
        let run = run_forming(&config, path.clone(), 1, None).unwrap();
        let s = &run.summary;
        assert!(
            s.max_fxy_N < 1e-9,
            "a press has no in-plane force: {}",
            s.max_fxy_N
        );
        assert!(s.max_fz_N < k * 1e-3, "k {k}: {} N", s.max_fz_N);
        forces.push((k, s.max_fz_N, s.final_part_depth_mm));
    }
    // Robot compliance from the two softest fixtures: 1/F = (1/k + C)/δ.
    let delta = 1e-3;
    let c_a = delta / forces[0].1 - 1.0 / forces[0].0;
    let c_b = delta / forces[1].1 - 1.0 / forces[1].0;
    assert!(c_a > 0.5e-6 && c_a < 5e-6, "C = {c_a} m/N");
    assert!((c_b / c_a - 1.0).abs() < 0.15, "{c_a} vs {c_b}");
    // The stiffest fixture takes almost none of the interference: F ≈ δ/C.
    let (_, f_stiff, pen) = forces[2];
    assert!((f_stiff * c_b / delta - 1.0).abs() < 0.2, "{f_stiff} N");
    assert!(pen < 0.2, "penetration {pen} mm");
}

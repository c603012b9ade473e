//! Measured link rotations (6-DoF probe): their equations enter the fit, recover the truth, and
//! sharpen stiffnesses that positions alone determine poorly.

use crate::stiffness::common;

use common::kr_like;
use deflex_calibrate::measurements::{MeasurementRow, format_rows, parse_rows};
use deflex_calibrate::stiffness::campaign_cell::random_q;
use deflex_calibrate::stiffness::stiffness_fit::{Calibration, Status, Structure, calibrate_fixed};
use deflex_calibrate::stiffness::synthetic::{
    SyntheticOptions, case_rows, measure, measure_with_rotations,
};
use deflex_calibrate::stiffness::validation::validate;
use deflex_model::{Axis, Data, EdofSite, Robot};
use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, UnitSphere};

const SIGMA_M: f64 = 15e-6;
const SIGMA_RAD: f64 = 20e-6;

/// Load cases with the wrist nearly straight (|q5| ≤ 0.3 rad): the TCP lies close to the axis
/// of joint 4, so the positions see J4.z only through a short lever arm.
fn straight_wrist_plan(robot: &Robot, cases: usize, seed: u64) -> Vec<MeasurementRow> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut data = Data::new();
    let mut rows = Vec::new();
    for case in 0..cases {
        let mut q = random_q(robot, &mut rng);
        q[4] = rng.gen_range(-0.3..0.3);
        robot.forward_kinematics(&mut data, &q).unwrap();
        let dir: [f64; 3] = UnitSphere.sample(&mut rng);
        let force = Vector3::from(dir) * rng.gen_range(600.0..1400.0);
        rows.extend(case_rows(
            robot,
            &data,
            &q,
            &force,
            &format!("W{case:03}"),
            None,
        ));
    }
    rows
}

fn options(seed: u64) -> SyntheticOptions {
    SyntheticOptions {
        noise_sigma_m: SIGMA_M,
        seed,
        ..Default::default()
    }
}

/// Relative standard error of an eDoF's compliance.
fn rel_se(cal: &Calibration, id: (EdofSite, Axis)) -> f64 {
    let e = cal.edof(id).unwrap();
    e.compliance_se / e.compliance
}

/// |c − c_true| ≤ 3 SE for every eDoF, every eDoF identified.
fn assert_recovered(cal: &Calibration, truth: &Robot) {
    for e in truth.edofs() {
        let est = cal.edof((e.site, e.axis)).unwrap();
        assert!(
            matches!(est.status, Status::Identified),
            "{}: {:?}",
            e.label(),
            est.status
        );
        let c_true = 1.0 / e.stiffness;
        assert!(
            (est.compliance - c_true).abs() <= 3.0 * est.compliance_se,
            "{}: k {:.4e} ± {:.2e} vs true {:.4e}",
            e.label(),
            est.stiffness.unwrap(),
            est.stiffness_se.unwrap(),
            e.stiffness
        );
    }
    let s = cal.shifts.iter().find(|s| s.joint == 3).unwrap();
    let se = s.se_m.expect("δr3 fitted");
    assert!(
        (s.value_m - truth.joints[2].center_shift).abs() <= 3.0 * se,
        "δr3 {} ± {se}",
        s.value_m
    );
}

#[test]
fn rotations_recover_truth_and_sharpen_weak_stiffness() {
    let truth = kr_like();
    let plan = straight_wrist_plan(&truth, 40, 11);
    let with = measure_with_rotations(&truth, &plan, &options(3), SIGMA_RAD).unwrap();
    let without = measure(&truth, &plan, &options(3)).unwrap();
    assert!(with.iter().all(|r| r.rotation_rad.is_some()));
    assert!(without.iter().all(|r| r.rotation_rad.is_none()));
    // Same position noise with and without rotations.
    for (a, b) in with.iter().zip(&without) {
        assert_eq!(a.displacement_m, b.displacement_m);
    }
    let structure = Structure::from_robot(&truth).with_free_shifts();
    let cal_p = calibrate_fixed(&truth, &without, &structure).unwrap();
    let cal_r = calibrate_fixed(&truth, &with, &structure).unwrap();
    eprintln!("{:?}", cal_p.residuals);
    eprintln!("{:?}", cal_r.residuals);
    for e in truth.edofs() {
        let id = (e.site, e.axis);
        eprintln!(
            "{}: relative SE of c: positions {:.4} ({:?}), with rotations {:.4} ({:?})",
            e.label(),
            rel_se(&cal_p, id),
            cal_p.edof(id).unwrap().status,
            rel_se(&cal_r, id),
            cal_r.edof(id).unwrap().status,
        );
    }

    // Positions only: no rotation statistics; rotations: 3 more equations per row.
    assert_eq!(cal_p.residuals.rotation_rms_rad, None);
    assert_eq!(cal_p.rotation_rows, 0);
    assert_eq!(cal_r.rotation_rows, with.len());
    assert_eq!(cal_p.dof + cal_p.parameter_labels.len(), 3 * without.len());
    assert_eq!(cal_r.dof + cal_r.parameter_labels.len(), 6 * with.len());
    // (The residual summary prints a rotation line exactly when there is a rotation RMS:
    // deflex-report's calibration_tables tests.)
    assert!(cal_p.residuals.rotation_rms_rad.is_none());
    assert!(cal_r.residuals.rotation_rms_rad.is_some());
    let rot_rms = cal_r.residuals.rotation_rms_rad.unwrap();
    assert!(
        (0.8 * SIGMA_RAD..1.2 * SIGMA_RAD).contains(&rot_rms),
        "{rot_rms}"
    );
    // Position statistics stay in metres, at the noise floor.
    assert!((0.8 * SIGMA_M..1.2 * SIGMA_M).contains(&cal_r.residuals.rms_all_m));
    assert!(
        (0.8..1.25).contains(&cal_r.reduced_chi2),
        "{}",
        cal_r.reduced_chi2
    );
    assert_recovered(&cal_r, &truth);

    // J4.z: the TCP lies near its axis, so positions see it weakly; the measured rotation of
    // link 6 sees it directly.
    let j4 = (EdofSite::Joint(4), Axis::Z);
    let (p, r) = (rel_se(&cal_p, j4), rel_se(&cal_r, j4));
    // (NaN would mean not identifiable at all from positions: poorer still.)
    assert!(p.is_nan() || p > 0.2, "positions only: relative SE {p}");
    assert!(r < 0.05, "with rotations: relative SE {r}");
    assert!(
        p.is_nan() || p > 5.0 * r,
        "positions {p}, with rotations {r}"
    );
    // No eDoF gets worse.
    for e in truth.edofs().filter(|e| (e.site, e.axis) != j4) {
        let id = (e.site, e.axis);
        assert!(
            rel_se(&cal_r, id) <= 1.15 * rel_se(&cal_p, id),
            "{}",
            e.label()
        );
    }

    // The rows with rotations survive the CSV.
    let text = format_rows(&with);
    assert!(
        text.lines()
            .next()
            .unwrap()
            .contains("drx_rad,dry_rad,drz_rad,sigma_rad")
    );
    assert_eq!(parse_rows(&text, "with.csv", true).unwrap(), with);

    // Validation reports rotation errors (truth: at the noise floor), none without rotations.
    let v = validate(&truth, None, &with).unwrap();
    let rot = v.model.rotation.as_ref().unwrap();
    assert_eq!(rot.stats.norm.count, with.len());
    assert!(rot.stats.norm.rms < 1.3 * 3f64.sqrt() * SIGMA_RAD);
    // (Its one-line summary: deflex-report's validation_report tests.)
    let v = validate(&truth, None, &without).unwrap();
    assert!(v.model.rotation.is_none());
}

/// Some rows with rotations, some without, rotation σ from the default (no `sigma_rad`).
#[test]
fn mixed_rows_and_default_sigma_rad() {
    let truth = kr_like();
    let plan = straight_wrist_plan(&truth, 40, 21);
    let mut rows = measure_with_rotations(
        &truth,
        &plan,
        &SyntheticOptions {
            record_sigma: false,
            ..options(5)
        },
        SIGMA_RAD,
    )
    .unwrap();
    assert_eq!(SIGMA_RAD, deflex_calibrate::measurements::DEFAULT_SIGMA_RAD);
    for (i, r) in rows.iter_mut().enumerate() {
        assert_eq!(r.rotation_rad.unwrap().sigma_rad, None);
        if i % 2 == 0 {
            r.rotation_rad = None;
        }
    }
    let structure = Structure::from_robot(&truth).with_free_shifts();
    let cal = calibrate_fixed(&truth, &rows, &structure).unwrap();
    eprintln!("{:?}", cal.residuals);
    assert_eq!(cal.rotation_rows, rows.len() / 2);
    assert!(
        (0.8..1.25).contains(&cal.reduced_chi2),
        "{}",
        cal.reduced_chi2
    );
    let rot_rms = cal.residuals.rotation_rms_rad.unwrap();
    assert!(
        (0.8 * SIGMA_RAD..1.2 * SIGMA_RAD).contains(&rot_rms),
        "{rot_rms}"
    );
    assert_recovered(&cal, &truth);
}

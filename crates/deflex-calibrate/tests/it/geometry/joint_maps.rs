//! Joint-angle error maps. The B-spline is checked against the Cox–de Boor recursion written
//! here; the step, on SIMULATED readings from `simulated.rs`'s own textbook DH matrices with an
//! angle error planted on joints 2 and 3 (a sum of sines written here, not a spline), must
//! recover the planted curves, earn its place on a held-out series and reach the noise; on
//! readings without such an error its maps stay small; and a terms file carries the maps to a
//! model that predicts the same.

use crate::geometry::simulated::{Truth, point, probe_reading, random_configuration, truth};
use deflex_calibrate::geometry::campaign::Campaign;
use deflex_calibrate::geometry::data::AbsoluteRow;
use deflex_calibrate::geometry::fit::{FitOptions, FitResult, Step, fit};
use deflex_calibrate::geometry::joint_maps::{JointMap, map_size};
use deflex_calibrate::geometry::model::Conditions;
use deflex_calibrate::geometry::params::EgModel;
use deflex_calibrate::geometry::solve::Loss;
use deflex_calibrate::geometry::terms::CalibrationTerms;
use nalgebra::{Rotation3, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

const NOISE_M: f64 = 20e-6;

/// Cox–de Boor recursion of the B-spline of degree `p` on knots `t`, basis `i`, at `x`.
fn cox_de_boor(t: &[f64], i: usize, p: usize, x: f64) -> f64 {
    if p == 0 {
        return f64::from(u8::from(t[i] <= x && x < t[i + 1]));
    }
    let left = if t[i + p] > t[i] {
        (x - t[i]) / (t[i + p] - t[i]) * cox_de_boor(t, i, p - 1, x)
    } else {
        0.0
    };
    let right = if t[i + p + 1] > t[i + 1] {
        (t[i + p + 1] - x) / (t[i + p + 1] - t[i + 1]) * cox_de_boor(t, i + 1, p - 1, x)
    } else {
        0.0
    };
    left + right
}

#[test]
fn a_map_is_the_cubic_b_spline_of_its_coefficients() {
    let map = JointMap {
        joint: 1,
        start_rad: -0.7,
        spacing_rad: 0.05,
        coefficients: (0..23)
            .map(|k| 1e-4 * ((k * 7 % 11) as f64 - 5.0))
            .collect(),
    };
    let knots: Vec<f64> = (0..map.coefficients.len() + 4)
        .map(|k| map.start_rad + k as f64 * map.spacing_rad)
        .collect();
    let mut worst = 0.0f64;
    for s in 0..2000 {
        let x = -0.8 + 1.5 * f64::from(s) / 2000.0;
        let expected: f64 = map
            .coefficients
            .iter()
            .enumerate()
            .map(|(k, c)| c * cox_de_boor(&knots, k, 3, x))
            .sum();
        worst = worst.max((map.value(x) - expected).abs());
    }
    assert!(worst < 1e-15, "largest difference {worst:e} rad");
    // Zero outside the knots; continuous at a knot.
    assert_eq!(map.value(-0.71), 0.0);
    assert_eq!(map.value(map.range_rad().1 + 1e-9), 0.0);
    let knot = map.start_rad + 9.0 * map.spacing_rad;
    // (a jump would be of the order of a coefficient, 1e-4; the slope moves it by ~1e-14)
    assert!((map.value(knot - 1e-12) - map.value(knot + 1e-12)).abs() < 1e-12);
    // Inside, the four weights of a point sum to one (a constant map is that constant).
    let flat = JointMap {
        coefficients: vec![3e-4; 23],
        ..map.clone()
    };
    assert!((flat.value(-0.2) - 3e-4).abs() < 1e-18);
}

/// The planted angle error of joint `j` (0-based): sines of a few periods (rad), none of them a
/// spline.
fn planted(j: usize, q: f64) -> f64 {
    match j {
        1 => 0.25e-3 * (q * std::f64::consts::TAU / 0.35).sin() + 0.15e-3 * (q * 3.1 + 0.4).cos(),
        2 => 0.2e-3 * (q * std::f64::consts::TAU / 0.5 + 1.0).sin(),
        _ => 0.0,
    }
}

/// Readings of the probe in two tracker set-ups (`near` fitted, `far` the held-out series);
/// joints 2 and 3 turn by `planted` when `with_maps`.
fn readings(truth: &Truth, with_maps: bool, seed: u64) -> Vec<AbsoluteRow> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, NOISE_M).unwrap();
    let setups = [
        (
            Rotation3::from_euler_angles(0.01, -0.02, 1.9),
            Vector3::new(2.9, 0.1, -1.2),
        ),
        (
            Rotation3::from_euler_angles(-0.015, 0.01, -0.8),
            Vector3::new(-0.5, -3.2, 0.3),
        ),
    ];
    let mut rows = Vec::new();
    for (s, (rotation, translation)) in setups.iter().enumerate() {
        for _ in 0..[700, 300][s] {
            let q = random_configuration(&mut rng);
            let mut turned = q;
            if with_maps {
                for (j, v) in turned.iter_mut().enumerate() {
                    *v += planted(j, q[j]);
                }
            }
            let p = point(&truth.frames(&turned)[6], truth.target);
            let measured =
                rotation * p + translation + Vector3::from_fn(|_, _| noise.sample(&mut rng));
            rows.push(probe_reading(
                rows.len() as u64 + 2,
                s,
                &q,
                &measured,
                NOISE_M,
            ));
        }
    }
    rows
}

/// A rigid truth (no gravity sag: this test is about the joints' angles) fitted by geometry,
/// then the maps, the `far` series held out.
fn fit_maps(with_maps: bool, seed: u64) -> (FitResult, Campaign) {
    let mut truth = truth();
    truth.compliance = [0.0; 6];
    let rows = readings(&truth, with_maps, seed);
    let far: Vec<usize> = (0..rows.len())
        .filter(|&i| rows[i].setup == "far")
        .collect();
    let mut nominal = deflex_model::builtin("ur10").unwrap();
    for joint in &mut nominal.joints {
        joint.inertia = None;
    }
    let mut model = EgModel::from_robot(&nominal);
    let campaign = Campaign::new(&mut model, rows, Vec::new()).unwrap();
    let options = FitOptions {
        steps: vec![Step::Registration, Step::Geometry, Step::JointMaps],
        loss: Loss::Squared,
        folds: 0,
        held_out_readings: far,
        ..FitOptions::default()
    };
    (fit(&model, &campaign, &options).unwrap(), campaign)
}

#[test]
fn planted_joint_angle_errors_are_recovered_simulated() {
    let (result, _) = fit_maps(true, 3);
    let geometry = &result.steps[1];
    let maps_step = &result.steps[2];
    let far_rms = |s: &deflex_calibrate::geometry::fit::StepReport| {
        s.test
            .iter()
            .find(|g| g.name.contains("far"))
            .map(|g| g.stats.rms)
            .unwrap()
    };
    let (before, after) = (far_rms(geometry), far_rms(maps_step));
    println!(
        "SIMULATED joint maps: held-out series {:.1} → {:.1} µm RMS, fit {:.1} → {:.1} µm",
        before * 1e6,
        after * 1e6,
        geometry.fit.rms * 1e6,
        maps_step.fit.rms * 1e6
    );
    assert!(
        maps_step.acceptance.is_some_and(|a| a.accepted),
        "the maps step must earn its place: {:?}",
        maps_step.acceptance
    );
    assert!(
        before > 80e-6,
        "the planted error shows: {:.1} µm",
        before * 1e6
    );
    // The tracker's 20 µm per axis is 35 µm of 3-D norm; the series' own registration (on half
    // its readings) and the maps' bias add a little.
    assert!(after < 50e-6, "held-out series at {:.1} µm", after * 1e6);
    let maps = result.model.joint_maps.as_ref().expect("maps kept");
    // Each planted curve, less its mean over the range (a constant is the DH θ offset), is found
    // within a fifth of its own RMS; joints without a planted error stay small.
    for j in 0..6 {
        let Some(map) = maps.maps.iter().find(|m| m.joint == j) else {
            assert!(
                planted(j, 0.3) == 0.0,
                "joint {} planted but not mapped",
                j + 1
            );
            continue;
        };
        let (lo, hi) = match j {
            1 => (-2.7, -0.4),
            2 => (-2.5, 2.5),
            _ => (-2.9, 2.9),
        };
        let xs: Vec<f64> = (0..400)
            .map(|k| lo + (hi - lo) * f64::from(k) / 399.0)
            .collect();
        let mean = |f: &dyn Fn(f64) -> f64| xs.iter().map(|&x| f(x)).sum::<f64>() / 400.0;
        let (mp, mm) = (mean(&|x| planted(j, x)), mean(&|x| map.value(x)));
        let rms = |f: &dyn Fn(f64) -> f64| (mean(&|x| f(x).powi(2))).sqrt();
        let size = rms(&|x| planted(j, x) - mp);
        let error = rms(&|x| (map.value(x) - mm) - (planted(j, x) - mp));
        println!(
            "J{}: planted RMS {:.0} µrad, map error RMS {:.0} µrad ({})",
            j + 1,
            size * 1e6,
            error * 1e6,
            maps.hyper.describe()
        );
        if size > 0.0 {
            assert!(
                error < 0.2 * size,
                "J{}: map error {:.0} µrad",
                j + 1,
                error * 1e6
            );
        } else {
            assert!(
                error < 30e-6,
                "J{}: spurious map {:.0} µrad",
                j + 1,
                error * 1e6
            );
        }
    }
}

#[test]
fn without_an_angle_error_the_maps_stay_small_simulated() {
    let (result, _) = fit_maps(false, 4);
    let step = &result.steps[2];
    println!("SIMULATED, no angle error: maps step {:?}", step.acceptance);
    if let Some(maps) = result.model.joint_maps.as_ref() {
        for map in &maps.maps {
            let (rms, _) = map_size(map);
            assert!(
                rms < 20e-6,
                "J{}: map RMS {:.1} µrad",
                map.joint + 1,
                rms * 1e6
            );
        }
    }
}

#[test]
fn a_terms_file_carries_the_maps_and_bad_ones_are_refused() {
    let (result, campaign) = fit_maps(true, 5);
    let terms = CalibrationTerms::of(&result);
    assert!(terms.joint_maps.is_some());
    let json = terms.to_json().expect("the terms serialise");
    let mut model = EgModel::from_robot(&result.model.to_robot());
    CalibrationTerms::from_json(&json)
        .unwrap()
        .apply(&mut model)
        .unwrap();
    for row in campaign.absolute.iter().take(50) {
        let c = Conditions::default();
        let a = result.model.predict_tracker(&row.q_rad, 0, 0, &c);
        let b = model.predict_tracker(&row.q_rad, 0, 0, &c);
        assert!((a - b).norm() < 1e-12, "{:e}", (a - b).norm());
    }
    let bad = |edit: &dyn Fn(&mut CalibrationTerms)| {
        let mut t = CalibrationTerms::from_json(&json).unwrap();
        edit(&mut t);
        t.apply(&mut EgModel::from_robot(&result.model.to_robot()))
            .expect_err("refused")
            .to_string()
    };
    let first = |t: &mut CalibrationTerms| t.joint_maps.as_mut().unwrap().maps[0].clone();
    assert!(
        bad(&|t| t.joint_maps.as_mut().unwrap().maps[0].joint = 7)
            .contains("joint_maps.maps.joint: 7 is outside 1…"),
        "joint out of range"
    );
    assert!(
        bad(&|t| {
            let m = first(t);
            t.joint_maps.as_mut().unwrap().maps.push(m)
        })
        .contains("has two maps")
    );
    assert!(
        bad(&|t| t.joint_maps.as_mut().unwrap().maps[0].coefficients_rad[3] = f64::NAN)
            .contains("coefficients_rad")
    );
    assert!(
        bad(&|t| t.joint_maps.as_mut().unwrap().maps[0].spacing_rad = 0.0).contains("spacing_rad")
    );
    assert!(
        bad(&|t| t.joint_maps.as_mut().unwrap().maps[0].coefficients_rad = vec![0.0; 5000])
            .contains("at most")
    );
}

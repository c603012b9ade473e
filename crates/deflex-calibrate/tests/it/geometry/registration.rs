//! SIMULATED campaigns with a known truth: a moved tracker (new session) and a new probe in a
//! new place, each registered from 30 readings with the robot frozen. Readings, positions and
//! orientations, come from `simulated.rs`'s own textbook DH matrices and gravity sums (no
//! deflex model code); the frozen robot is the model with the true parameters. The registered
//! set-up and target must lie within their stated intervals, and the warnings must fire where
//! the readings cannot separate the parameters.

use crate::geometry::simulated::{Truth, point, random_configuration, true_value, truth, z_axis};
use deflex_calibrate::geometry::campaign::Campaign;
use deflex_calibrate::geometry::data::{AbsoluteRow, RowOrientation};
use deflex_calibrate::geometry::params::{EgModel, Param};
use deflex_calibrate::geometry::register::{RegisterOptions, RegistrationWarning, register};
use deflex_calibrate::geometry::solve::Loss;
use deflex_model::spatial::rotation_log;
use nalgebra::{Rotation3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

const POSITION_NOISE_M: f64 = 20e-6;
const ANGLE_NOISE_RAD: f64 = 50e-6;

/// A probe: offset and frame rotation on the flange.
struct Probe {
    offset: [f64; 3],
    rotation: Rotation3<f64>,
}

/// The frozen robot: the nominal UR10 moved onto every true parameter.
fn frozen(truth: &Truth) -> EgModel {
    let mut model = EgModel::from_robot(&deflex_model::builtin("ur10").unwrap());
    let mut params = model.geometric_params();
    params.extend((0..model.compliance.len()).map(Param::Compliance));
    for b in 0..model.robot.joint_count() {
        params.push(Param::Mass(b));
        params.extend((0..3).map(|k| Param::FirstMoment(b, k)));
    }
    // One parameter at a time: the first moments' truth depends on the geometry set before.
    for p in params {
        if let Some(v) = true_value(truth, p) {
            let delta = v - model.value(p);
            model.apply(&[p], &[delta]);
        }
    }
    model
}

/// Readings of `probe` by a tracker at (`rotation`, `translation`), textbook code; with
/// `wrist_still` the wrist joints stay at one value (the flange never turns about them).
#[allow(clippy::too_many_arguments)]
fn readings(
    truth: &Truth,
    probe: &Probe,
    rotation: Rotation3<f64>,
    translation: Vector3<f64>,
    count: usize,
    wrist_still: bool,
    seed: u64,
    target: &str,
) -> Vec<AbsoluteRow> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, POSITION_NOISE_M).unwrap();
    let angle = Normal::new(0.0, ANGLE_NOISE_RAD).unwrap();
    (0..count)
        .map(|i| {
            let mut q = random_configuration(&mut rng);
            if wrist_still {
                q[3] = -1.2;
                q[4] = 1.4;
                q[5] = 0.3;
                q[0] = 0.5 + 0.01 * q[0];
                q[1] = -1.6 + 0.01 * q[1];
                q[2] = 1.0 + 0.01 * q[2];
            }
            let frames = truth.frames(&q);
            let p = point(&frames[6], probe.offset);
            let tau = truth.torques(&frames, None);
            let p = p + truth.deflection(&frames, &tau, &p);
            let sag: Vector3<f64> = (0..6)
                .map(|j| z_axis(&frames[j]) * (truth.compliance[j] * tau[j]))
                .sum();
            let flange =
                Rotation3::from_matrix_unchecked(frames[6].fixed_view::<3, 3>(0, 0).into_owned());
            let measured_rotation =
                Rotation3::from_scaled_axis(Vector3::from_fn(|_, _| angle.sample(&mut rng)))
                    * rotation
                    * Rotation3::from_scaled_axis(sag)
                    * flange
                    * probe.rotation;
            let measured =
                rotation * p + translation + Vector3::from_fn(|_, _| noise.sample(&mut rng));
            let v = rotation_log(&measured_rotation);
            AbsoluteRow {
                sigma_m: Some(POSITION_NOISE_M),
                orientation: Some(RowOrientation {
                    rotation_vector_rad: [v.x, v.y, v.z],
                    sigma_rad: Some(ANGLE_NOISE_RAD),
                }),
                ..AbsoluteRow::position(
                    i as u64 + 2,
                    "moved",
                    target,
                    q.to_vec(),
                    [measured.x, measured.y, measured.z],
                )
            }
        })
        .collect()
}

/// Standardised errors of the registered set-up (and target) against the truth.
fn z_scores(
    model: &EgModel,
    result: &deflex_calibrate::geometry::register::Registration,
    rotation: Rotation3<f64>,
    translation: Vector3<f64>,
    probe: Option<&Probe>,
) -> Vec<(String, f64)> {
    let s = model.setup_index("moved").unwrap();
    let pose = &model.setups[s].pose;
    // Set-up rotation increments act as R ← R exp(φ): the error is log(Rᵀ R_true).
    let phi = rotation_log(&(pose.rotation.inverse() * rotation));
    let t_error = pose.rotation.inverse() * (translation - pose.translation.vector);
    let mut out = Vec::new();
    for p in &result.params {
        let error = match p.param {
            Param::SetupRotation(_, k) => phi[k],
            Param::SetupTranslation(_, k) => t_error[k],
            Param::Target(t, k) => {
                probe.map_or(0.0, |pr| pr.offset[k] - model.targets[t].position[k])
            }
            Param::TargetRotation(t, k) => probe.map_or(0.0, |pr| {
                rotation_log(&(pr.rotation * model.target_rotation(t).inverse()))[k]
            }),
            _ => continue,
        };
        out.push((p.name.clone(), error / p.standard_error));
    }
    out
}

fn session(truth: &Truth, seed: u64, new_probe: bool) -> Vec<(String, f64)> {
    let mut model = frozen(truth);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let rotation = Rotation3::from_euler_angles(
        rng.gen_range(-0.05..0.05),
        rng.gen_range(-0.05..0.05),
        rng.gen_range(-3.0..3.0),
    );
    let translation = Vector3::new(
        rng.gen_range(-3.0..3.0),
        rng.gen_range(-3.0..3.0),
        rng.gen_range(-1.0..1.0),
    );
    let known_probe = Probe {
        offset: truth.target,
        rotation: Rotation3::from_euler_angles(0.01, -0.02, -1.57),
    };
    let new = Probe {
        offset: [0.012, -0.006, 0.152],
        rotation: Rotation3::from_euler_angles(0.1, -0.2, 0.7),
    };
    let probe = if new_probe { &new } else { &known_probe };
    model.targets.push(deflex_model::NamedPoint {
        name: "probe".into(),
        position: Vector3::from(truth.target),
        rotation: Some(known_probe.rotation),
    });
    let name = if new_probe { "new-probe" } else { "probe" };
    let rows = readings(
        truth,
        probe,
        rotation,
        translation,
        30,
        false,
        seed + 100,
        name,
    );
    let mut campaign = Campaign::new(&mut model, rows, Vec::new()).unwrap();
    campaign.use_orientations(ANGLE_NOISE_RAD);
    let options = RegisterOptions {
        setup: model.setup_index("moved").unwrap(),
        target: new_probe.then(|| model.target_index("new-probe").unwrap()),
        loss: Loss::HUBER_DEFAULT,
        recalibrate_above_m: Some(0.2e-3),
        restart_setup: true,
    };
    let all = vec![1.0; campaign.len()];
    let result = register(&mut model, &campaign, &all, &options).unwrap();
    assert_eq!(result.params.len(), if new_probe { 12 } else { 6 });
    assert!(
        result.warnings.is_empty(),
        "seed {seed}: unexpected warnings {:?}",
        result.warnings
    );
    // The residual is the noise: 20 µm per axis, ≈ 35 µm RMS norm.
    assert!(result.position.rms < 50e-6, "{:?}", result.position);
    z_scores(
        &model,
        &result,
        rotation,
        translation,
        new_probe.then_some(probe),
    )
}

fn check_intervals(new_probe: bool) {
    let truth = truth();
    let mut all = Vec::new();
    for seed in 1..=8 {
        let z = session(&truth, seed, new_probe);
        for (name, z) in &z {
            assert!(
                z.abs() < 4.0,
                "seed {seed}: {name} is {z:.2} SE from the truth: {z:?}"
            );
        }
        all.extend(z.into_iter().map(|(_, z)| z));
    }
    let within = all.iter().filter(|z| z.abs() <= 1.96).count();
    let mean_z2 = all.iter().map(|z| z * z).sum::<f64>() / all.len() as f64;
    println!(
        "SIMULATED {}: {within}/{} registered parameters within their 95 % interval, mean z² {mean_z2:.2}",
        if new_probe {
            "new probe in a new place"
        } else {
            "moved tracker"
        },
        all.len()
    );
    assert!(
        within as f64 >= 0.85 * all.len() as f64,
        "{within}/{} within 95 %",
        all.len()
    );
    assert!((0.4..2.0).contains(&mean_z2), "mean z² {mean_z2:.2}");
}

#[test]
fn moved_tracker_registered_within_its_intervals_simulated() {
    check_intervals(false);
}

#[test]
fn new_probe_in_a_new_place_registered_within_its_intervals_simulated() {
    check_intervals(true);
}

#[test]
fn warnings_name_what_the_readings_cannot_separate_simulated() {
    let truth = truth();
    let mut model = frozen(&truth);
    let probe = Probe {
        offset: [0.012, -0.006, 0.152],
        rotation: Rotation3::identity(),
    };
    let rotation = Rotation3::from_euler_angles(0.0, 0.0, 2.0);
    let translation = Vector3::new(1.5, -2.0, 0.3);
    // Eight readings with the wrist and arm nearly still: too few, too close, no wrist turn.
    let rows = readings(
        &truth,
        &probe,
        rotation,
        translation,
        8,
        true,
        7,
        "new-probe",
    );
    let mut campaign = Campaign::new(&mut model, rows, Vec::new()).unwrap();
    campaign.use_orientations(ANGLE_NOISE_RAD);
    let options = RegisterOptions {
        setup: model.setup_index("moved").unwrap(),
        target: model.target_index("new-probe"),
        loss: Loss::HUBER_DEFAULT,
        recalibrate_above_m: None,
        restart_setup: true,
    };
    let all = vec![1.0; campaign.len()];
    let result = register(&mut model, &campaign, &all, &options).unwrap();
    let has = |f: &dyn Fn(&RegistrationWarning) -> bool| result.warnings.iter().any(f);
    assert!(has(&|w| matches!(
        w,
        RegistrationWarning::TooFewReadings { readings: 8, .. }
    )));
    assert!(has(&|w| matches!(w, RegistrationWarning::TooClose { .. })));
    assert!(has(&|w| matches!(
        w,
        RegistrationWarning::NoWristRotation { .. }
    )));
    for w in &result.warnings {
        println!("warning: {w}");
    }
    // A robot that changed: the same good readings against a robot with J2's offset 2 mrad off.
    let mut changed = frozen(&truth);
    changed.apply(
        &[Param::Dh(
            1,
            deflex_calibrate::geometry::params::DhField::Theta,
        )],
        &[2e-3],
    );
    let rows = readings(
        &truth,
        &Probe {
            offset: truth.target,
            rotation: Rotation3::identity(),
        },
        rotation,
        translation,
        30,
        false,
        9,
        "probe",
    );
    changed.targets.push(deflex_model::NamedPoint {
        name: "probe".into(),
        position: Vector3::from(truth.target),
        rotation: None,
    });
    let campaign = Campaign::new(&mut changed, rows, Vec::new()).unwrap();
    let options = RegisterOptions {
        setup: changed.setup_index("moved").unwrap(),
        target: None,
        loss: Loss::HUBER_DEFAULT,
        recalibrate_above_m: Some(0.3e-3),
        restart_setup: true,
    };
    let all = vec![1.0; campaign.len()];
    let result = register(&mut changed, &campaign, &all, &options).unwrap();
    assert!(
        result
            .warnings
            .iter()
            .any(|w| matches!(w, RegistrationWarning::Recalibrate { .. })),
        "{:?} {:?}",
        result.position,
        result.warnings
    );
}

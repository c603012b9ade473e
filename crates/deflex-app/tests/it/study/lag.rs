//! The lag at force ramps ([`deflex_app::study::compensation::lag`]) on hand-made logs: the ramps
//! found, the error integral and settling time, the contact error.

use deflex_app::study::compensation::lag::{
    CONTACT_FORCE_N, SETTLE_WINDOW_S, error_numbers, ramps,
};
use deflex_sim::cell::TruthState;
use deflex_sim::forming::{FormingLog, FormingLogRow};
use deflex_sim::sheet::ContactState;
use deflex_sim::{FormingRun, FormingSummary, SensorSample};
use nalgebra::Vector3;

/// A hand-made log at 50 Hz along x at 10 mm/s: the force steps to 1000 N at 1 s and at
/// 4 s (after 1 s at zero), and the error is given by `error(t)` along z.
fn run(force: impl Fn(f64) -> f64, error: impl Fn(f64) -> f64) -> FormingRun {
    run_rows(300, force, error)
}

fn run_rows(last: usize, force: impl Fn(f64) -> f64, error: impl Fn(f64) -> f64) -> FormingRun {
    let rows = (0..=last)
        .map(|k| {
            let t = k as f64 * 0.02;
            let desired = Vector3::new(0.01 * t, 0.0, 0.0);
            FormingLogRow {
                time_s: t,
                truth: TruthState {
                    desired_m: desired,
                    commanded_m: desired,
                    true_m: desired + Vector3::new(0.0, 0.0, error(t) * 1e-3),
                    wrench: deflex_model::Wrench::new(0.0, 0.0, force(t), 0.0, 0.0, 0.0),
                    deflection: deflex_model::Displacement::zeros(),
                    contact: ContactState {
                        penetration_m: 0.0,
                        depth_m: 0.0,
                        flow_n: 0.0,
                        force_n: 0.0,
                    },
                    correction: [0.0; 6],
                },
                tracked_m: desired,
                sensor: SensorSample {
                    time_s: t,
                    wrench_sensor: [0.0; 6],
                    saturated: false,
                },
            }
        })
        .collect();
    FormingRun {
        log: FormingLog {
            rows,
            ..FormingLog::default()
        },
        summary: FormingSummary {
            simulated: true,
            robot: String::new(),
            path: String::new(),
            seed: 0,
            correction: false,
            duration_s: 6.0,
            cycles: 0,
            max_error_norm_mm: 0.0,
            rms_error_norm_mm: 0.0,
            max_error_abs_mm: [0.0; 3],
            max_force_norm_N: 0.0,
            max_fz_N: 0.0,
            max_fxy_N: 0.0,
            max_correction_mm: 0.0,
            aerens_steady_fz_N: 0.0,
            aerens_actual_fz_N: 0.0,
            actual_step_down_mm: 0.0,
            actual_wall_angle_deg: 0.0,
            target_depth_mm: 0.0,
            final_part_depth_mm: 0.0,
            saturated_samples: 0,
        },
        profile_mm: Vec::new(),
        programmed_profile_mm: Vec::new(),
        wall_time_s: 0.0,
    }
}

fn steps(t: f64) -> f64 {
    // A linear rise over 30 ms from 1.08 s and from 4.08 s (667 N, past half the step, at
    // the rows of 1.10 s and 4.10 s); zero from 3 s to 4.08 s.
    let ramp = |t0: f64| ((t - t0) / 0.03).clamp(0.0, 1.0) * 1000.0;
    if t < 3.0 { ramp(1.08) } else { ramp(4.08) }
}

#[test]
fn ramps_are_found_where_the_force_reaches_half_its_step() {
    // A slow build-up (the cone's, here over 40 s) is not a ramp.
    assert!(ramps(&run_rows(2000, |t| 1000.0 * (t / 40.0).powi(2), |_| 0.0)).is_empty());
    let r = run(steps, |_| 0.0);
    let found = ramps(&r);
    // 50 % at the rows of 1.10 s and 4.10 s: 11 and 41 mm along.
    assert_eq!(found.len(), 2, "{found:?}");
    assert!((found[0] - 0.011).abs() < 1e-9, "{found:?}");
    assert!((found[1] - 0.041).abs() < 1e-9, "{found:?}");
}

#[test]
fn integral_and_settling_match_hand_computation() {
    let ramp_points = ramps(&run(steps, |_| 0.0));
    // An error of 0.5 mm decaying linearly to 0 over 0.45 s after each 50 % point: integral
    // 0.5 · 0.45 / 2 = 0.1125 mm·s; below 0.2 mm from 0.27 s on, i.e. from the row at
    // 0.28 s (the row at 0.26 s has 0.211 mm).
    let error = |t: f64| {
        let since = if t >= 4.1 { t - 4.1 } else { t - 1.1 };
        if since < 0.0 {
            0.0
        } else {
            (0.5 * (1.0 - since / 0.45)).max(0.0)
        }
    };
    let numbers = error_numbers(&run(steps, error), &ramp_points);
    let integral = numbers.ramp_error_integral_mm_s.unwrap();
    assert!((integral - 0.1125).abs() < 1e-3, "{numbers:?}");
    assert!(
        (numbers.ramp_settle_s.unwrap() - 0.28).abs() < 1e-9,
        "{numbers:?}"
    );
    assert_eq!(numbers.ramps_not_settled, 0);
    // An error that never falls: not settled, counted as the whole window.
    let stuck = error_numbers(&run(steps, |_| 1.0), &ramp_points);
    assert_eq!(stuck.ramps_not_settled, 2);
    assert!((stuck.ramp_settle_s.unwrap() - SETTLE_WINDOW_S).abs() < 1e-12);
    assert!((stuck.ramp_error_integral_mm_s.unwrap() - 1.0).abs() < 1e-9);
    // No ramp: no lag numbers.
    let none = error_numbers(&run(steps, |_| 1.0), &[]);
    assert_eq!(
        (none.ramp_error_integral_mm_s, none.ramp_settle_s),
        (None, None)
    );
}

#[test]
fn contact_error_leaves_out_the_rows_in_the_air() {
    // 1000 N from 1.08 s to 3 s and from 4.08 s on (the steps), nothing between; an error of
    // 2 mm in the air and 0.3 mm (0.4 mm at one row) in contact.
    let error = |t: f64| {
        if steps(t) < CONTACT_FORCE_N {
            2.0
        } else if (t - 2.0).abs() < 1e-9 {
            0.4
        } else {
            0.3
        }
    };
    let numbers = error_numbers(&run(steps, error), &[]);
    assert!(
        (numbers.max_contact_error_mm.unwrap() - 0.4).abs() < 1e-9,
        "{numbers:?}"
    );
    let rms = numbers.rms_contact_error_mm.unwrap();
    assert!(rms > 0.3 && rms < 0.31, "{numbers:?}");
    // Never in contact: no contact numbers.
    let air = error_numbers(&run(|_| 0.0, |_| 2.0), &[]);
    assert_eq!(
        (air.max_contact_error_mm, air.rms_contact_error_mm),
        (None, None)
    );
}

//! Fuzzing the calibration readers (`deflex_calibrate`): random and mutated inputs give rows or
//! an error, never a panic or a hang.
//!
//! * the measurement/plan CSV reader (and what runs on what it accepts: the forward-kinematics
//!   check, the design and a fixed-structure fit) and the planner's points file (the old
//!   `deflex-stiffness` fuzz tests);
//! * the absolute measurement reader and the UR10 series importer (the old `deflex-absolute`
//!   fuzz tests).
//!
//! A quick count here (deterministic, a few seconds in debug); ≥ 10⁶ with
//! `DEFLEX_FUZZ_COUNT=1000000 cargo test --release -p deflex --test it -- fuzz::calibrate --nocapture`.

use crate::fuzz::engine::{count_from_env, fuzz};
use deflex_calibrate::geometry::data::parse_absolute;
use deflex_calibrate::geometry::ur10_tracker::{ImportOptions, parse_series};
use deflex_calibrate::measurements::points::parse_points;
use deflex_calibrate::measurements::{MeasuredRotation, format_rows_for, parse_file};
use deflex_calibrate::stiffness::consistency::check_geometry;
use deflex_calibrate::stiffness::stiffness_fit::{Structure, calibrate_fixed};
use deflex_calibrate::stiffness::synthetic::{SyntheticOptions, measure, random_campaign};
use deflex_model::builtin;

// ---- the measurement/plan CSV and the points file (deflex_calibrate::measurements, ::stiffness)

/// A small plan and a measurement of it (sigma, rotations, purpose), with their headers.
fn corpus() -> Vec<String> {
    let robot = builtin("tx200-1edof").unwrap();
    let plan = random_campaign(&robot, 2, (600.0, 1400.0), 3);
    let mut measured = measure(&robot, &plan, &SyntheticOptions::default()).unwrap();
    measured[0].rotation_rad = Some(MeasuredRotation {
        value_rad: [1e-5, -2e-5, 3e-6],
        sigma_rad: Some(2e-5),
    });
    measured[1].purpose = Some("axis-by-axis J1.z; cable".into());
    vec![
        format_rows_for(&robot, &plan, &["a plan"]),
        format_rows_for(&robot, &measured, &["SIMULATED"]),
    ]
}

#[test]
fn measurement_csv_reader_never_panics() {
    let texts = corpus();
    let corpus: Vec<&[u8]> = texts.iter().map(|t| t.as_bytes()).collect();
    let robot = builtin("tx200-1edof").unwrap();
    let structure = Structure::from_robot(&robot);
    let count = count_from_env(20_000);
    let mut accepted = 0;
    let report = fuzz(&corpus, count, 16_384, |input| {
        let text = String::from_utf8_lossy(input);
        for require in [true, false] {
            let Ok(file) = parse_file(&text, "fuzz.csv", require) else {
                continue;
            };
            accepted += 1;
            if file
                .rows
                .iter()
                .any(|r| r.q_rad.len() != robot.joint_count())
            {
                continue;
            }
            let _ = check_geometry(
                &robot,
                &file.rows,
                Some(&file.lines),
                Some(&file.header),
                1e-3,
            );
            if require {
                let _ = calibrate_fixed(&robot, &file.rows, &structure);
            }
        }
    });
    report.assert_no_panic("measurement CSV");
    println!(
        "measurement CSV: {} inputs, {accepted} parses accepted, no panic",
        report.inputs
    );
    assert!(accepted > 0, "the mutations must leave some inputs valid");
}

#[test]
fn points_file_reader_never_panics() {
    let text =
        "# reflectors on the arm\nname,link,x_m,y_m,z_m\nM1,1,0.1,0.2,0.3\nR3,3,-0.25,0.0,0.05\n";
    let count = count_from_env(20_000);
    let report = fuzz(&[text.as_bytes()], count, 4096, |input| {
        let _ = parse_points(&String::from_utf8_lossy(input), "fuzz.csv", 6);
    });
    report.assert_no_panic("points CSV");
    println!("points CSV: {} inputs, no panic", report.inputs);
}

// ---- the absolute readings and the UR10 series (deflex_calibrate::geometry)

const ABSOLUTE: &str = "# comment\nsetup,target,config,q1_rad,q2_rad,q3_rad,q4_rad,q5_rad,q6_rad,x_m,y_m,z_m,sigma_m,rx_rad,ry_rad,rz_rad,sigma_rad,payload_kg,payload_com_x_m,payload_com_y_m,payload_com_z_m,fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm,temperature_C,time_s\nA,tmac,c1,0.1,-1.2,0.5,0.0,1.5,-0.25,2.361,-1.3685,0.1194,2.1e-5,0.1,-0.2,1.3,3e-5,2.5,0.0,0.01,0.05,0.0,0.0,-100.0,0.0,1.0,0.0,22.5,1500000000.0\nB,tmac,,0,0,0,0,0,0,1,2,3,,,,,,,,,,,,,,,,,\n";

#[test]
fn absolute_reader_never_panics() {
    parse_absolute(ABSOLUTE, "seed.csv", 6).expect("the corpus entry is valid");
    let report = fuzz(
        &[ABSOLUTE.as_bytes()],
        count_from_env(20_000),
        4096,
        |input| {
            let text = String::from_utf8_lossy(input);
            let _ = parse_absolute(&text, "fuzz.csv", 6);
        },
    );
    report.assert_no_panic("absolute CSV");
}

#[test]
fn series_importer_never_panics() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../deflex-calibrate/tests/data/ur10-tracker/Series_B/measurements_joint_configurations.csv");
    let text = std::fs::read_to_string(path).unwrap();
    let seed: String = text.lines().take(4).collect::<Vec<_>>().join("\n");
    let options = ImportOptions {
        setup: "B".into(),
        target: "tmac".into(),
        tracker_sigma: true,
    };
    parse_series(&seed, "seed.csv", &options).expect("the corpus entry is valid");
    let report = fuzz(&[seed.as_bytes()], count_from_env(20_000), 4096, |input| {
        let text = String::from_utf8_lossy(input);
        let _ = parse_series(&text, "fuzz.csv", &options);
    });
    report.assert_no_panic("UR10 series");
}

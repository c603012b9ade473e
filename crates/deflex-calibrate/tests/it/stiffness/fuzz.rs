//! Fuzzing the measurement/plan CSV reader (and what runs on what it accepts: the
//! forward-kinematics check, the design and a fixed-structure fit) and the planner's points
//! file: random and mutated inputs must give `Ok` or an error, never a panic or a hang.
//! A quick count here (deterministic, a few seconds in debug); ≥ 10⁶ with
//! `DEFLEX_FUZZ_COUNT=1000000 cargo test --release -p deflex-stiffness --test fuzz -- --nocapture`.

use deflex_fuzz::{count_from_env, fuzz};
use deflex_model::builtin;
use deflex_calibrate::stiffness::consistency::check_geometry;
use deflex_calibrate::measurements::points::parse_points;
use deflex_calibrate::measurements::{MeasuredRotation, format_rows_for, parse_file};
use deflex_calibrate::stiffness::stiffness_fit::{Structure, calibrate_fixed};
use deflex_calibrate::stiffness::synthetic::{SyntheticOptions, measure, random_campaign};

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

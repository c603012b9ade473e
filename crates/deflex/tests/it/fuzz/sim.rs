//! Fuzzing the twin's parsers (`deflex-sim`): G-code and the twin's `[cell]` TOML. Random and
//! mutated inputs must give `Ok` or an error naming where, never a panic, a hang or an unbounded
//! allocation; a program that parses is also planned into a cell (bounded duration, finite
//! waypoints). A quick count here; ≥ 10⁶ with
//! `DEFLEX_FUZZ_COUNT=1000000 cargo test --release -p deflex --test it fuzz::sim -- --nocapture`.

use crate::fuzz::engine::{count_from_env, fuzz};
use deflex_sim::gcode::parse_gcode;
use deflex_sim::{CellConfig, ToolPath};

const PROGRAMS: [&str; 4] = [
    "%\n(square test) ; header\nN10 G21 G90\nG0 X10 Y0 Z5\nG1 Z0 F600 (plunge)\nG91\nX-5 Y5\nG20 G1 X1 F60\nM30\n",
    "G21 G90\nG0 X20 Y0 Z0\nG1 Z-0.5 F600\nG1 X0 Y20 F600\nG1 X-20 Y0\nG1 X0 Y-20\nG1 X20 Y0\nG1 Z-1.0\nM2\n",
    "G0 X0 Y0 Z2\nG1 Z-0.2 F120.5\nG1 X5.25 Y-3.75\nG1 X-5.25\nG0 Z5\n",
    "N1 G20\nN2 G0 X0.5 Y0.5 Z0.1\nN3 G1 Z-0.01 F10\nN4 G1 X-0.5\nN5 M30\n",
];

#[test]
fn gcode_reader_never_panics() {
    let corpus: Vec<&[u8]> = PROGRAMS.iter().map(|p| p.as_bytes()).collect();
    let count = count_from_env(20_000);
    let mut parsed = 0usize;
    let report = fuzz(&corpus, count, 4096, |input| {
        let text = String::from_utf8_lossy(input);
        match parse_gcode(&text, "fuzz.nc") {
            Ok(path) => {
                parsed += 1;
                assert!(path.waypoints.len() >= 2);
                for w in &path.waypoints {
                    assert!(w.p_mm.iter().all(|v| v.is_finite() && v.abs() <= 10_000.0));
                    assert!(w.feed_mm_s.is_none_or(|f| f.is_finite() && f > 0.0));
                }
                let duration = path.duration_s(50.0);
                assert!(duration.is_finite(), "{duration}");
            }
            Err(e) => {
                let message = e.to_string();
                assert!(message.starts_with("fuzz.nc:"), "{message}");
            }
        }
    });
    report.assert_no_panic("G-code");
    assert!(parsed > 0, "some mutations must still parse");
    println!(
        "G-code: {} inputs, {parsed} parsed, no panic",
        report.inputs
    );
}

/// A parsed program planned into the cell: what the fuzzer found parses is also bounded in time
/// (`Cell::new` refuses runs over 4 h) and never panics the planner.
#[test]
fn parsed_programs_plan_or_are_refused() {
    let config = CellConfig::default();
    for text in [
        "G0 X0 Y0 Z1\nG1 Z0 F0.6\nG1 X5000 F0.6\n",
        "G0 X1\nG1 X2 F60000\n",
        "G0 X0 Y0 Z0\nG0 X9999 Y9999 Z9999\n",
    ] {
        let path: ToolPath = parse_gcode(text, "p.nc").unwrap();
        match deflex_sim::Cell::new(&config, path, 1) {
            Ok(cell) => assert!(cell.path_duration_s() <= deflex_sim::cell_config::MAX_RUN_S),
            Err(e) => {
                let e = e.to_string();
                assert!(
                    e.contains("at most") || e.contains("inverse kinematics"),
                    "{e}"
                );
            }
        }
    }
}

#[test]
fn twin_toml_reader_never_panics() {
    let example = "[cell.controller]\nrate_hz = 250.0\ncorrection_delay_s = 0.008\nservo_bandwidth_hz = 10.0\n\
                   [cell.sensor]\nrate_hz = 1000.0\ntool_mass_kg = 3.2\nbias = [1.0, 2.0, 3.0, 0.1, 0.2, 0.3]\n\
                   [cell.tracker]\nsamples_per_reading = 5\nposition_m = [2.8, -1.6, 0.3]\n\
                   [cell.part]\norigin_mm = [1500.0, 0.0, -183.0]\n\
                   [cell.plant]\nj2_j3_coupling = 0.1\nbase_stiffness = [8e6, 4.5e6, 0.0]\n\
                   [cell.sheet]\nrm_mpa = 320.0\nsectors = 360\n[cell.errors]\nservo = false\n\
                   [cell.process]\nkind = \"fixture\"\nfixture_stiffness_n_m = 1e7\n[cell.log]\nrate_hz = 50.0\n";
    CellConfig::from_toml_str(example).expect("the corpus entry is valid");
    let corpus: &[&[u8]] = &[example.as_bytes()];
    let count = count_from_env(20_000);
    let report = fuzz(corpus, count, 4096, |input| {
        let text = String::from_utf8_lossy(input);
        if let Ok(config) = CellConfig::from_toml_str(&text) {
            assert!(config.validate().is_ok());
        }
    });
    report.assert_no_panic("twin TOML");
    println!("twin TOML: {} inputs, no panic", report.inputs);
}

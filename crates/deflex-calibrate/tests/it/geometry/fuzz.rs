//! Fuzzing the absolute measurement reader and the UR10 series importer: random and mutated
//! inputs give rows or an error, never a panic or a hang. A quick count here; more with
//! `DEFLEX_FUZZ_COUNT=1000000 cargo test --release -p deflex-absolute --test fuzz -- --nocapture`.

use deflex_calibrate::geometry::data::parse_absolute;
use deflex_calibrate::geometry::ur10_tracker::{ImportOptions, parse_series};
use deflex_fuzz::{count_from_env, fuzz};

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
        .join("tests/data/ur10-tracker/Series_B/measurements_joint_configurations.csv");
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

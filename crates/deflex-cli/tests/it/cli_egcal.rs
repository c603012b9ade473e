//! End-to-end: `deflex import ur10-tracker`, `deflex calibrate-geometry`, `deflex predict` and
//! `deflex pose` on the vendored real UR10 subset, through the real binary.

use crate::support::{Run, deflex, json, s, scratch, with_data};
use std::path::{Path, PathBuf};

fn data(series: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../deflex-calibrate/tests/data/ur10-tracker")
        .join(series)
}

#[test]
fn import_calibrate_predict_pose() {
    let dir = scratch("egcal-flow");
    let a = dir.join("A.csv");
    let b = dir.join("B.csv");
    let v = json(&[
        "import",
        "ur10-tracker",
        "--series",
        s(&data("Series_A")),
        "--setup",
        "A",
        "--out",
        s(&a),
    ]);
    assert_eq!(v["rows_written"], 298);
    json(&[
        "import",
        "ur10-tracker",
        "--series",
        s(&data("Series_B")),
        "--setup",
        "B",
        "--out",
        s(&b),
    ]);
    let model = dir.join("ur10-calibrated.toml");
    let report = dir.join("report");
    let v = json(&with_data(
        "calibrate-geometry",
        "ur10",
        &a,
        &[
            "--test-data",
            s(&b),
            "--elastic",
            "J2.z,J3.z",
            "--folds",
            "3",
            "--out",
            s(&model),
            "--report",
            s(&report),
        ],
    ));
    let steps = v["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 3);
    let held = |k: usize| steps[k]["held_out"][0]["stats"]["rms_m"].as_f64().unwrap();
    assert!(
        held(2) < 0.7 * held(0),
        "B held out: {} → {}",
        held(0),
        held(2)
    );
    for file in [
        "index.html",
        "report.json",
        "residuals.csv",
        "residuals_vs_joints.png",
        "error_distribution.png",
    ] {
        assert!(report.join(file).exists(), "{file}");
    }
    // The calibrated file knows set-up A and B (B registered on half of its configurations):
    // `predict` scores A's readings with it.
    let p = json(&with_data(
        "predict",
        s(&model),
        &a,
        &["--out", s(&dir.join("pred.csv"))],
    ));
    let rms = p["rms_m"].as_f64().unwrap();
    let fit_rms = steps[2]["fit"]["rms_m"].as_f64().unwrap();
    assert!((rms - fit_rms).abs() < 1e-9, "{rms} vs {fit_rms}");
    let csv = std::fs::read_to_string(dir.join("pred.csv")).unwrap();
    assert!(csv.lines().next().unwrap().contains("predicted_x_m"));
    assert_eq!(csv.lines().count(), 299);
    // `pose` of the calibrated file reports the calibrated flange plus the fitted sag.
    let pose = json(&["pose", "--robot", s(&model), "--q-deg", "0,-90,0,-90,0,0"]);
    assert!(pose["gravity_sag_m"].is_array());
    // A set-up the model does not know is refused with its name, unless --fit-setup.
    let renamed = dir.join("C.csv");
    std::fs::write(
        &renamed,
        std::fs::read_to_string(&a).unwrap().replace("\nA,", "\nC,"),
    )
    .unwrap();
    let Run { ok, stderr, .. } = deflex(&with_data(
        "predict",
        s(&model),
        &renamed,
        &["--out", s(&dir.join("c.csv"))],
    ));
    assert!(
        !ok && stderr.contains("`C`") && stderr.contains("--fit-setup"),
        "{stderr}"
    );
    let p = json(&with_data(
        "predict",
        s(&model),
        &renamed,
        &["--fit-setup", "--out", s(&dir.join("c.csv"))],
    ));
    assert!(p["rms_m"].as_f64().unwrap() < 0.6e-3);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_inputs_are_named() {
    let Run { ok, stderr, .. } = deflex(&with_data(
        "calibrate-geometry",
        "ur10",
        Path::new("/nonexistent.csv"),
        &["--out", "/tmp/x.toml"],
    ));
    assert!(!ok && stderr.contains("/nonexistent.csv"), "{stderr}");
    let dir = scratch("egcal-bad");
    let bad = dir.join("bad.csv");
    std::fs::write(&bad, "setup,target,q1_rad,q2_rad,q3_rad,q4_rad,q5_rad,q6_rad,x_m,y_m,z_m\nA,t,0,0,0,0,0,0,1,2,nan\n").unwrap();
    let Run { ok, stderr, .. } = deflex(&with_data(
        "calibrate-geometry",
        "ur10",
        &bad,
        &["--out", "/tmp/x.toml"],
    ));
    assert!(
        !ok && stderr.contains("bad.csv:2") && stderr.contains("z_m"),
        "{stderr}"
    );
    let Run { ok, stderr, .. } = deflex(&with_data(
        "calibrate-geometry",
        "ur10",
        &bad,
        &["--steps", "registration,wobble", "--out", "/tmp/x.toml"],
    ));
    assert!(!ok && stderr.contains("wobble"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The two user protocols on the shipped subset: calibrate on Series A (with orientations),
/// then a new session (30 readings of Series B, set-up only) and a new probe in a new place
/// (30 readings, set-up + target), each registered by `deflex register` and scored by
/// `deflex predict` on B's other readings, positions and orientations.
#[test]
fn register_a_new_session_and_a_new_probe() {
    let dir = scratch("egcal-register");
    let a = dir.join("A.csv");
    let b = dir.join("B.csv");
    for (series, setup, out) in [("Series_A", "A", &a), ("Series_B", "B", &b)] {
        json(&[
            "import",
            "ur10-tracker",
            "--series",
            s(&data(series)),
            "--setup",
            setup,
            "--out",
            s(out),
        ]);
    }
    let model = dir.join("ur10.toml");
    json(&with_data(
        "calibrate-geometry",
        "ur10",
        &a,
        &[
            "--elastic",
            "J2.z,J3.z",
            "--orientations",
            "--folds",
            "0",
            "--out",
            s(&model),
        ],
    ));
    assert!(dir.join("ur10.terms.json").exists());
    // Split B: the first 30 configurations register, the rest are scored.
    let text = std::fs::read_to_string(&b).unwrap();
    let lines: Vec<&str> = text.lines().filter(|l| !l.starts_with('#')).collect();
    let header = lines[0];
    let few = dir.join("few.csv");
    let rest = dir.join("rest.csv");
    let probe = |rows: &[&str]| -> String {
        let mut out = vec![header.to_string()];
        out.extend(rows.iter().map(|l| l.replacen(",tmac,", ",tmac2,", 1)));
        out.join("\n") + "\n"
    };
    std::fs::write(&few, lines[..31].join("\n") + "\n").unwrap();
    std::fs::write(&rest, format!("{header}\n{}\n", lines[31..].join("\n"))).unwrap();
    let updated = dir.join("session.toml");
    let r = json(&with_data(
        "register",
        s(&model),
        &few,
        &["--orientations", "--out", s(&updated)],
    ));
    assert_eq!(r["readings"], 30);
    assert_eq!(r["params"].as_array().unwrap().len(), 6);
    assert!(r["position_m"]["rms"].as_f64().unwrap() < 0.8e-3, "{r}");
    assert!(dir.join("session.terms.json").exists());
    let p = json(&with_data(
        "predict",
        s(&updated),
        &rest,
        &["--out", s(&dir.join("p1.csv"))],
    ));
    let rms = p["rms_m"].as_f64().unwrap();
    assert!(rms < 0.7e-3, "new session, held-out RMS {rms}");
    assert!(p["orientation_rms_rad"].as_f64().unwrap() < 3e-3, "{p}");
    // A new probe: the data name a target the robot does not know; predict refuses it until
    // it is registered.
    let few2 = dir.join("few2.csv");
    let rest2 = dir.join("rest2.csv");
    std::fs::write(&few2, probe(&lines[1..31])).unwrap();
    std::fs::write(&rest2, probe(&lines[31..])).unwrap();
    let Run { ok, stderr, .. } = deflex(&with_data(
        "predict",
        s(&updated),
        &rest2,
        &["--out", s(&dir.join("x.csv"))],
    ));
    assert!(
        !ok && stderr.contains("tmac2") && stderr.contains("register"),
        "{stderr}"
    );
    let Run { ok, stderr, .. } = deflex(&with_data(
        "register",
        s(&model),
        &few2,
        &["--out", s(&dir.join("x.toml"))],
    ));
    assert!(!ok && stderr.contains("--target tmac2"), "{stderr}");
    let probe_model = dir.join("probe.toml");
    let r = json(&with_data(
        "register",
        s(&model),
        &few2,
        &[
            "--target",
            "tmac2",
            "--orientations",
            "--out",
            s(&probe_model),
        ],
    ));
    assert_eq!(r["params"].as_array().unwrap().len(), 12);
    let p = json(&with_data(
        "predict",
        s(&probe_model),
        &rest2,
        &["--out", s(&dir.join("p2.csv"))],
    ));
    let rms = p["rms_m"].as_f64().unwrap();
    assert!(rms < 0.7e-3, "new probe, held-out RMS {rms}");
    let written = std::fs::read_to_string(&probe_model).unwrap();
    assert!(
        written.contains("name = \"tmac2\"") && written.contains("rpy"),
        "{written}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

//! A forming run's folder (moved from deflex-sim's tests when the writing moved here).

use deflex_app::report::forming_run::write_forming_run;
use deflex_sim::{CellConfig, ToolPath, run_forming};

#[test]
fn outputs_are_written_and_labelled() {
    let run = run_forming(
        &CellConfig::default(),
        ToolPath::paper_cone().truncated(30.0),
        1,
        None,
    )
    .unwrap();
    let dir = std::env::temp_dir().join(format!("deflex-sim-test-{}", std::process::id()));
    let files = write_forming_run(&run, &dir).unwrap();
    for name in [
        "log.csv",
        "summary.json",
        "deviation_cloud.png",
        "error_along_path.png",
        "forces.png",
        "error_vs_force.png",
    ] {
        assert!(files.iter().any(|f| f.ends_with(name)), "{name} missing");
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(json["simulated"], true);
    for key in [
        "max_error_norm_mm",
        "rms_error_norm_mm",
        "max_force_norm_N",
        "max_fz_N",
        "max_fxy_N",
    ] {
        assert!(json[key].is_number(), "{key}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

//! Runs the shortened study end to end and checks the report's numbers against the run's own
//! CSV files (independent re-computation), plus determinism under a seed.

use deflex_demo::{DemoOptions, DemoSummary, Progress, run_demo};
use std::path::{Path, PathBuf};

struct Silent;
impl Progress for Silent {
    fn stage(&mut self, _: usize, _: usize, _: &str) {}
    fn fraction(&mut self, _: f64) {}
    fn done(&mut self, _: &str) {}
}

fn out_dir(tag: &str) -> PathBuf {
    std::env::temp_dir().join(format!("deflex-demo-{tag}-{}", std::process::id()))
}

fn run(tag: &str, seed: u64) -> (DemoSummary, PathBuf) {
    let dir = out_dir(tag);
    let _ = std::fs::remove_dir_all(&dir);
    let options = DemoOptions {
        out_dir: dir.clone(),
        seed,
        quick: true,
        ..DemoOptions::default()
    };
    (
        run_demo(&options, &mut Silent).expect("quick demo runs"),
        dir,
    )
}

/// Data lines of a CSV (comments skipped) split into fields, with the header.
fn csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    (header, rows)
}

fn column(header: &[String], name: &str) -> usize {
    header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name} in {header:?}"))
}

#[test]
fn quick_demo_numbers_match_its_own_csvs_and_are_deterministic() {
    let (summary, dir) = run("a", 7);
    for file in [
        "index.html",
        "summary.json",
        "plan.csv",
        "campaign.csv",
        "identified.toml",
        "grid_predictions.csv",
        "spiral_predictions.csv",
        "stiffness.csv",
        "search_iterations.csv",
        "paper_vs_deflex.csv",
        "forming_open/log.csv",
        "forming_closed/log.csv",
        "forming_cloud.png",
        "grid_error_identified_1100N.png",
        "stiff_contact_force.png",
        "sensitivity.csv",
        "sensitivity_heatmap.png",
    ] {
        assert!(dir.join(file).exists(), "{file} missing");
    }

    // Validation numbers recomputed from grid_predictions.csv.
    let (header, rows) = csv(&dir.join("grid_predictions.csv"));
    let measured = column(&header, "dz_m");
    let predicted = column(&header, "identified_dz_m");
    for load in ["600", "1100"] {
        let errors: Vec<f64> = rows
            .iter()
            .filter(|r| r[0].starts_with(&format!("grid{load}N")))
            .map(|r| r[measured].parse::<f64>().unwrap() - r[predicted].parse::<f64>().unwrap())
            .collect();
        assert_eq!(errors.len(), 200);
        let rms_mm = (errors.iter().map(|e| e * e).sum::<f64>() / errors.len() as f64).sqrt() * 1e3;
        let max_mm = errors.iter().fold(0.0f64, |m, e| m.max(e.abs())) * 1e3;
        let reported = summary
            .errors("identified (deflex)", &format!("grid {load} N"))
            .unwrap();
        assert!(
            (reported.rms_z_mm - rms_mm).abs() < 1e-9,
            "{load} N: {} vs {rms_mm}",
            reported.rms_z_mm
        );
        assert!((reported.max_z_mm - max_mm).abs() < 1e-9);
        // The identified model beats the paper's 0.04/0.05 mm RMS on the (simulated) grid.
        assert!(
            rms_mm <= if load == "600" { 0.04 } else { 0.05 },
            "{load} N RMS {rms_mm} mm"
        );
    }

    // Forming numbers: the summary agrees with the twin's own summary.json, and the 50 Hz log's
    // largest error norm is within 2 % below the 250 Hz running maximum.
    for (name, numbers) in [
        ("forming_open", &summary.forming_open),
        ("forming_closed", &summary.forming_closed),
    ] {
        let twin: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(dir.join(name).join("summary.json")).unwrap(),
        )
        .unwrap();
        assert_eq!(twin["simulated"], true);
        // serde_json's default float parsing is not always correctly rounded: compare to 1e-12.
        let same = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1.0);
        assert!(same(
            twin["max_error_norm_mm"].as_f64().unwrap(),
            numbers.max_error_norm_mm
        ));
        assert!(same(twin["max_fz_N"].as_f64().unwrap(), numbers.max_fz_N));
        assert!(
            twin["robot"].as_str().unwrap().contains("TX200"),
            "{}",
            twin["robot"]
        );
        let (header, rows) = csv(&dir.join(name).join("log.csv"));
        let norm = column(&header, "err_norm_mm");
        let log_max = rows
            .iter()
            .map(|r| r[norm].parse::<f64>().unwrap())
            .fold(0.0, f64::max);
        assert!(
            log_max <= numbers.max_error_norm_mm + 1e-4
                && log_max >= 0.98 * numbers.max_error_norm_mm,
            "{name}: log max {log_max} vs summary {}",
            numbers.max_error_norm_mm
        );
    }
    // The honest headline: every error source of the twin was on.
    assert!(summary.conditions.len() >= 10);
    assert!(
        summary.conditions.iter().all(|(_, _, on)| *on),
        "{:?}",
        summary.conditions
    );
    let sc = &summary.stiff_contact;
    assert!(sc.unguarded.max_force_N > 2.0 * sc.open_max_force_N);
    assert!(sc.guarded.max_force_N <= 1.2 * sc.open_max_force_N);
    assert!(sc.guarded.runaway_warnings >= 1 && sc.guarded.fault.is_none());
    let expected = 100.0
        * (1.0 - summary.forming_closed.max_error_norm_mm / summary.forming_open.max_error_norm_mm);
    assert!((summary.improvement_percent - expected).abs() < 1e-9);
    assert!(
        summary.improvement_percent > 50.0,
        "correction helps even on the short path: {}",
        summary.improvement_percent
    );

    // The paper-vs-deflex CSV carries the same numbers.
    let table = std::fs::read_to_string(dir.join("paper_vs_deflex.csv")).unwrap();
    assert!(table.contains(&format!("{:.4}", summary.forming_open.max_error_norm_mm)));
    assert!(table.contains(&format!("{:.4}", summary.improvement_percent)));

    // The page is self-contained and labelled.
    let html = std::fs::read_to_string(dir.join("index.html")).unwrap();
    assert!(html.contains("SIMULATED"));
    assert!(!html.contains("http://") && !html.contains("https://"));
    assert!(html.contains("data:image/png;base64,"));

    // Deterministic under the seed: a second run gives the same numbers.
    let (again, dir_b) = run("b", 7);
    let strip = |s: &DemoSummary| {
        let mut v = serde_json::to_value(s).unwrap();
        v.as_object_mut().unwrap().remove("stage_seconds");
        v
    };
    assert_eq!(strip(&summary), strip(&again));
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&dir_b);
}

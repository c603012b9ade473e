//! Runs the shortened study end to end (computed by deflex-study, written here) and checks the
//! report's numbers against the run's own CSV files (independent re-computation), plus
//! determinism under a seed.

use deflex_app::report::study::write_study;
use deflex_app::study::{DemoOptions, DemoSummary, run_study};
use std::path::{Path, PathBuf};

fn out_dir(tag: &str) -> PathBuf {
    std::env::temp_dir().join(format!("deflex-study-{tag}-{}", std::process::id()))
}

fn run(tag: &str, seed: u64) -> (DemoSummary, PathBuf) {
    let dir = out_dir(tag);
    let _ = std::fs::remove_dir_all(&dir);
    let options = DemoOptions {
        seed,
        quick: true,
        ..DemoOptions::default()
    };
    let cell = deflex_sim::CellConfig::for_robot(&options.robot).unwrap();
    let study = run_study(&options, cell, &mut |_| {}).expect("quick demo runs");
    write_study(&study, &dir).expect("quick demo is written");
    (study.summary, dir)
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
    // A contents list at the top, and a link to every CSV file beside the page.
    let contents = html
        .find("<nav class=\"contents\">")
        .expect("contents list");
    assert!(
        contents < html.find("<h2").unwrap(),
        "contents before the first section"
    );
    let csvs = csv_files(&dir, "");
    assert!(csvs.len() >= 15, "{csvs:?}");
    for file in &csvs {
        assert!(
            html.contains(&format!("<a href=\"{file}\">")),
            "{file} is not linked from the page"
        );
    }
    // Every data file is described by what it holds, not by its own first (provenance) line.
    let files_list = &html[html.find("<ul class=\"files\">").expect("files list")..];
    let files_list = &files_list[..files_list.find("</ul>").unwrap()];
    for item in files_list.split("<li>").skip(1) {
        let href = &item[item.find("href=\"").unwrap() + 6..];
        let href = &href[..href.find('"').unwrap()];
        let description = item[item.find("</a>: ").unwrap() + 6..]
            .trim_end()
            .trim_end_matches("</li>");
        let first = std::fs::read_to_string(dir.join(href))
            .unwrap()
            .lines()
            .next()
            .unwrap_or_default()
            .trim_start_matches('#')
            .trim()
            .replace('\'', "&#39;");
        assert!(
            description.len() > 20 && description != first && description != "data file",
            "{href}: {description:?}"
        );
    }
    // No literal backtick in the page's text: code spans are <code>.
    let body = &html[html.find("<body>").unwrap()..];
    assert!(!body.contains('`'), "a literal backtick in the page");
    check_compensation_along_path(&dir);
    // One unit per column: every numeric header of the page's tables names its unit.
    for header in html.split("<th>").skip(1) {
        let header = &header[..header.find("</th>").unwrap()];
        assert!(
            !header.contains("] [") && header.matches('[').count() <= 1,
            "header {header:?} mixes units"
        );
    }

    check_fig7(&dir, &summary);
    check_controller_log(&dir);
    check_profiles(&dir);

    // Deterministic under the seed: a second run gives the same numbers.
    let (again, dir_b) = run("b", 7);
    let strip = |s: &DemoSummary| {
        let mut v = serde_json::to_value(s).unwrap();
        v.as_object_mut().unwrap().remove("stage_seconds");
        // Wall times of the offline compensations.
        for part in v["compensation"]["parts"].as_array_mut().unwrap() {
            for source in ["offline_process", "offline_log"] {
                part[source].as_object_mut().unwrap().remove("seconds");
            }
        }
        v
    };
    assert_eq!(strip(&summary), strip(&again));
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&dir_b);
}

/// CSV files under `dir` (relative paths), two folders deep.
fn csv_files(dir: &Path, prefix: &str) -> Vec<String> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if entry.path().is_dir() {
            out.extend(csv_files(&entry.path(), &format!("{prefix}{name}/")));
        } else if name.ends_with(".csv") {
            out.push(format!("{prefix}{name}"));
        }
    }
    out
}

fn numbers(row: &[String], columns: &[usize]) -> Vec<f64> {
    columns
        .iter()
        .map(|&c| row[c].parse::<f64>().unwrap())
        .collect()
}

/// Figs. 8–9: the CSV carries the summary's numbers; the identified model predicts the twin's
/// M2, M3 and TCP x-displacement (the joint-3 x-eDoF) that the one-eDoF model misses.
fn check_fig7(dir: &Path, summary: &DemoSummary) {
    assert_eq!(summary.fig7.len(), 4);
    let (header, rows) = csv(&dir.join("fig7_points.csv"));
    let cols: Vec<usize> = ["dx_m", "dy_m", "identified_dx_m", "one_edof_dx_m"]
        .iter()
        .map(|c| column(&header, c))
        .collect();
    assert_eq!(rows.len(), 4);
    for (row, point) in rows.iter().zip(&summary.fig7) {
        assert_eq!(row[0], point.point);
        let v = numbers(row, &cols);
        assert!((v[0] * 1e3 - point.measured_mm[0]).abs() < 1e-9);
        assert!((v[1] * 1e3 - point.measured_mm[1]).abs() < 1e-9);
        if point.point != "M1" {
            let (measured, identified, one_edof) = (v[0], v[2], v[3]);
            assert!(measured > 0.2e-3, "{}: δx {measured}", point.point);
            assert!(
                (identified - measured).abs() < 0.25 * measured,
                "{}: identified {identified} vs measured {measured}",
                point.point
            );
            assert!(one_edof.abs() < 0.1 * measured, "{}", point.point);
        }
    }
}

/// The controller log: one row per 10 ms cycle, ε = −ξ − δŝ on every row (eq. 5–7), and the
/// state column agrees with the integer flags.
fn check_controller_log(dir: &Path) {
    let (header, rows) = csv(&dir.join("forming_closed").join("controller_log.csv"));
    assert!(rows.len() > 1000, "{} rows", rows.len());
    let t = column(&header, "time_s");
    let mut previous = f64::NEG_INFINITY;
    for row in &rows {
        let time: f64 = row[t].parse().unwrap();
        assert!(time > previous);
        previous = time;
        for axis in ["x_m", "y_m", "z_m", "rx_rad", "ry_rad", "rz_rad"] {
            let v = numbers(
                row,
                &[
                    column(&header, &format!("xi_{axis}")),
                    column(&header, &format!("ds_{axis}")),
                    column(&header, &format!("eps_{axis}")),
                ],
            );
            let scale = v.iter().fold(1e-9f64, |m, x| m.max(x.abs()));
            assert!(
                (v[2] + v[0] + v[1]).abs() <= 2e-5 * scale,
                "t {time}: ε {} ≠ −ξ − δŝ ({}, {})",
                v[2],
                v[0],
                v[1]
            );
        }
        let flags: u32 = row[column(&header, "flags")].parse().unwrap();
        let status = &row[column(&header, "status")];
        assert_eq!(
            flags & (1 << 20) != 0,
            status.contains("active"),
            "{status}"
        );
    }
    let period = (previous - rows[0][t].parse::<f64>().unwrap()) / (rows.len() - 1) as f64;
    assert!((period - 0.01).abs() < 1e-6, "period {period}");
}

/// Programmed and formed profiles: the programmed one reaches the deepest programmed tool
/// position near the ray θ = 0 (within one step-down of the log's deepest desired point), and
/// the corrected part is closer to it than the uncorrected one.
fn check_profiles(dir: &Path) {
    let mut rms = Vec::new();
    for run in ["forming_open", "forming_closed"] {
        let (header, rows) = csv(&dir.join(run).join("profile.csv"));
        let (d, p) = (
            column(&header, "depth_mm"),
            column(&header, "programmed_depth_mm"),
        );
        let programmed_max = rows
            .iter()
            .map(|r| r[p].parse::<f64>().unwrap())
            .fold(0.0, f64::max);
        let (lh, log) = csv(&dir.join(run).join("log.csv"));
        let z = column(&lh, "des_z_mm");
        let deepest = log
            .iter()
            .map(|r| -r[z].parse::<f64>().unwrap())
            .fold(0.0, f64::max);
        assert!(
            programmed_max <= deepest + 1e-3 && programmed_max >= deepest - 0.25,
            "{run}: programmed {programmed_max} mm, deepest desired {deepest} mm"
        );
        let sq: f64 = rows
            .iter()
            .map(|r| (r[d].parse::<f64>().unwrap() - r[p].parse::<f64>().unwrap()).powi(2))
            .sum();
        rms.push((sq / rows.len() as f64).sqrt());
    }
    assert!(
        rms[1] < 0.8 * rms[0],
        "profile RMS open {} closed {}",
        rms[0],
        rms[1]
    );
}

/// The README's generated blocks are what `deflex demo --seed 1` measures (`results.md`): the
/// headline table and the details under it, compared with the blocks between the README's
/// markers; with `with_sensitivity` the sensitivity bullet too (the study then runs its
/// sensitivity section). `DEFLEX_BLESS_README=1` rewrites the blocks instead.
fn check_readme_blocks(with_sensitivity: bool) {
    use deflex_app::report::study::readme::{
        ReadmeBlock, current_block, details_list, replace_block, results_table, sensitivity_list,
    };
    let options = DemoOptions {
        seed: 1,
        sensitivity: with_sensitivity,
        ..DemoOptions::default()
    };
    let cell = deflex_sim::CellConfig::for_robot(&options.robot).unwrap();
    let study = run_study(&options, cell, &mut |_| {}).expect("the demo's study runs");
    let blocks: Vec<(ReadmeBlock, String)> = if with_sensitivity {
        vec![(ReadmeBlock::Sensitivity, sensitivity_list(&study.summary))]
    } else {
        vec![
            (ReadmeBlock::Results, results_table(&study.summary)),
            (ReadmeBlock::Details, details_list(&study.summary)),
        ]
    };
    let readme_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../README.md");
    let mut readme = std::fs::read_to_string(&readme_path).expect("README.md is readable");
    let bless = std::env::var_os("DEFLEX_BLESS_README").is_some();
    let mut stale = Vec::new();
    for (block, text) in blocks {
        let current = current_block(&readme, block)
            .unwrap_or_else(|| panic!("README.md has no {:?} block markers", block));
        if current == text {
            continue;
        }
        if bless {
            readme = replace_block(&readme, block, &text).expect("markers in order");
        } else {
            stale.push(format!(
                "--- README {block:?}:\n{current}\n--- demo:\n{text}"
            ));
        }
    }
    if bless {
        std::fs::write(&readme_path, readme).expect("README.md is writable");
    }
    if !with_sensitivity {
        // The README's screenshot of the page: scripts/report-screenshot keeps the headline it
        // shows beside it.
        let shot = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/report-screenshot.txt");
        let shown = std::fs::read_to_string(&shot).expect("docs/report-screenshot.txt is readable");
        let expected = format!(
            "headline: {}",
            deflex_app::report::study::headline_text(&study.summary)
                .split_whitespace()
                .collect::<Vec<_>>()
                .join(" ")
        );
        if shown.trim_end() != expected {
            stale.push(format!(
                "--- docs/report-screenshot.txt (what the screenshot shows):\n{}\n--- demo:\n{expected}\n\
                 Retake it: scripts/report-screenshot",
                shown.trim_end()
            ));
        }
    }
    assert!(
        stale.is_empty(),
        "README.md's generated results are not the demo's (seed 1).\n{}\n\
         If the change is intended: DEFLEX_BLESS_README=1 cargo test -p deflex-app readme_ -- --include-ignored",
        stale.join("\n")
    );
}

/// The headline table and the details under it (the study without its sensitivity section).
#[test]
fn readme_results_are_the_demos_own() {
    check_readme_blocks(false);
}

/// The sensitivity bullet (the study with its sensitivity section: slow in a debug build, so run
/// by `scripts/test` with the ignored tests).
#[test]
#[ignore = "runs the seed-1 study with its sensitivity section; scripts/test runs it"]
fn readme_sensitivity_is_the_demos_own() {
    check_readme_blocks(true);
}

/// The compensation error files give every way's error against its position along the desired
/// path (what the figures are drawn against): each way from the start of the path, in order, to
/// its end, whatever time each way took.
fn check_compensation_along_path(dir: &Path) {
    for tag in ["cone", "part"] {
        let path = dir.join(format!("compensation_{tag}_error.csv"));
        if !path.exists() {
            continue;
        }
        // Way names hold commas (quoted): a real CSV reader.
        let mut reader = ::csv::ReaderBuilder::new()
            .comment(Some(b'#'))
            .from_path(&path)
            .unwrap();
        let header: Vec<String> = reader.headers().unwrap().iter().map(String::from).collect();
        assert_eq!(header, ["way", "path_s_m", "time_s", "error_m"], "{tag}");
        let rows: Vec<::csv::StringRecord> = reader.records().map(Result::unwrap).collect();
        let mut ways: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
        for row in &rows {
            let (s, t): (f64, f64) = (row[1].parse().unwrap(), row[2].parse().unwrap());
            match ways.last_mut() {
                Some((way, points)) if *way == row[0] => points.push((s, t)),
                _ => ways.push((row[0].to_string(), vec![(s, t)])),
            }
        }
        assert!(ways.len() >= 3, "{tag}: {} ways", ways.len());
        for (way, points) in &ways {
            assert_eq!(points[0].0, 0.0, "{tag} {way} starts at the path's start");
            assert!(
                points
                    .windows(2)
                    .all(|w| w[1].0 >= w[0].0 && w[1].1 > w[0].1),
                "{tag} {way}: position and time in order"
            );
        }
        // Every way covers the same path: their end positions agree within 1 %.
        let ends: Vec<f64> = ways.iter().map(|(_, p)| p.last().unwrap().0).collect();
        let longest = ends.iter().copied().fold(0.0, f64::max);
        assert!(longest > 0.0);
        for ((way, _), end) in ways.iter().zip(&ends) {
            assert!(
                (end - longest).abs() <= 0.01 * longest,
                "{tag} {way}: {end} of {longest} m"
            );
        }
    }
}

//! Issue 18's remaining input and output rules through the real binary: `--ignore-column`, one
//! load case holding two configurations, estimate pairs correlated at |ρ| ≥ 0.95, `import`'s
//! labels, `run`'s log on a full disk and two processes on one output folder.

use deflex_model::{Robot, builtin};
use deflex_stiffness::format_rows_for;
use deflex_stiffness::plan::{PlanOptions, plan_experiments};
use deflex_stiffness::synthetic::{SyntheticOptions, measure};
use std::path::{Path, PathBuf};
use std::process::Command;

pub struct Run {
    pub code: Option<i32>,
    pub stdout: String,
    pub stderr: String,
}

pub fn deflex(args: &[&str]) -> Run {
    let output = Command::new(env!("CARGO_BIN_EXE_deflex"))
        .args(args)
        .output()
        .expect("run deflex");
    Run {
        code: output.status.code(),
        stdout: String::from_utf8_lossy(&output.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&output.stderr).into_owned(),
    }
}

/// A fresh folder for one test.
pub fn folder(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("deflex-cli-strict-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A SIMULATED campaign of `robot` (planned for it, measured on it) as file text.
fn campaign_text(robot: &Robot) -> String {
    let plan = plan_experiments(
        robot,
        &PlanOptions {
            max_force_n: 150.0,
            load_cases: 16,
            full_family: false,
            ..PlanOptions::for_a_real_cell()
        },
    )
    .unwrap();
    let rows = measure(robot, &plan.rows, &SyntheticOptions::default()).unwrap();
    format_rows_for(robot, &rows, &["SIMULATED test campaign"])
}

/// `text` (a CSV with `#` comments) with one more column `name` holding `value` on every row.
fn with_column(text: &str, name: &str, value: &str) -> String {
    let mut header_seen = false;
    text.lines()
        .map(|l| {
            if l.starts_with('#') || l.is_empty() {
                l.to_string()
            } else if !header_seen {
                header_seen = true;
                format!("{l},{name}")
            } else {
                format!("{l},{value}")
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
        + "\n"
}

#[test]
fn an_extra_measurement_column_is_refused_unless_ignored_by_name() {
    let dir = folder("ignore-column");
    let robot = builtin("ur10e").unwrap();
    let data = dir.join("meas.csv");
    let text = with_column(&campaign_text(&robot), "operator", "ann");
    std::fs::write(&data, &text).unwrap();
    let model = dir.join("m.toml");
    let base = [
        "calibrate",
        "--robot",
        "ur10e",
        "--data",
        s(&data),
        "--structure",
        "fixed",
        "--out",
        s(&model),
    ];
    let run = deflex(&base);
    assert_eq!(run.code, Some(1), "{}{}", run.stdout, run.stderr);
    assert!(
        run.stderr.contains("meas.csv")
            && run.stderr.contains("unknown column `operator`")
            && run.stderr.contains("--ignore-column operator"),
        "{}",
        run.stderr
    );
    assert!(!model.exists());
    // Named, it is skipped; validate takes the same flag.
    let mut ignoring = base.to_vec();
    ignoring.extend(["--ignore-column", "operator"]);
    let run = deflex(&ignoring);
    assert_eq!(run.code, Some(0), "{}{}", run.stdout, run.stderr);
    assert!(model.exists());
    let run = deflex(&[
        "validate",
        "--robot",
        s(&model),
        "--data",
        s(&data),
        "--ignore-column",
        "operator",
    ]);
    assert_eq!(run.code, Some(0), "{}{}", run.stdout, run.stderr);
    // A typo of a known column is not something to ignore: it names the column it meant.
    let typo = dir.join("typo.csv");
    std::fs::write(&typo, with_column(&text, "sigma_mm", "0.01")).unwrap();
    let run = deflex(&[
        "validate",
        "--robot",
        "ur10e",
        "--data",
        s(&typo),
        "--ignore-column",
        "operator",
    ]);
    assert!(
        run.code == Some(1) && run.stderr.contains("did you mean `sigma_m`?"),
        "{}",
        run.stderr
    );
    // Duplicated columns stay an error, and a known column cannot be ignored.
    let dup = dir.join("dup.csv");
    std::fs::write(&dup, with_column(&campaign_text(&robot), "fz_N", "0.0")).unwrap();
    let run = deflex(&["validate", "--robot", "ur10e", "--data", s(&dup)]);
    assert!(
        run.code == Some(1)
            && run.stderr.contains("dup.csv")
            && run.stderr.contains("column `fz_N` appears twice"),
        "{}",
        run.stderr
    );
    let run = deflex(&[
        "validate",
        "--robot",
        "ur10e",
        "--data",
        s(&data),
        "--ignore-column",
        "operator",
        "--ignore-column",
        "sigma_m",
    ]);
    assert!(
        run.code == Some(1) && run.stderr.contains("`sigma_m` is read by the format"),
        "{}",
        run.stderr
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn one_load_case_holding_two_configurations_is_refused_naming_lines() {
    let dir = folder("load-case");
    let robot = builtin("ur10e").unwrap();
    let text = campaign_text(&robot);
    // Give the second load case's rows the first one's label: same label, other configuration.
    let header_line = text
        .lines()
        .position(|l| l.starts_with("load_case"))
        .unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let first_case = lines[header_line + 1]
        .split(',')
        .next()
        .unwrap()
        .to_string();
    let other = lines[header_line + 1..]
        .iter()
        .position(|l| !l.starts_with(&format!("{first_case},")))
        .unwrap()
        + header_line
        + 1;
    let other_case = lines[other].split(',').next().unwrap().to_string();
    let merged: String = lines
        .iter()
        .map(|l| {
            if l.starts_with(&format!("{other_case},")) {
                format!("{first_case}{}\n", &l[other_case.len()..])
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    let data = dir.join("merged.csv");
    std::fs::write(&data, merged).unwrap();
    let run = deflex(&["validate", "--robot", "ur10e", "--data", s(&data)]);
    assert_eq!(run.code, Some(1), "{}{}", run.stdout, run.stderr);
    assert!(
        run.stderr.contains("merged.csv")
            && run.stderr.contains(&format!("load case `{first_case}`"))
            && run.stderr.contains(&format!("line {}", header_line + 2))
            && run.stderr.contains(&format!("line {}", other + 1)),
        "{}",
        run.stderr
    );
    let _ = std::fs::remove_dir_all(&dir);
}

//! Issue 18's remaining input and output rules through the real binary: `--ignore-column`, one
//! load case holding two configurations, estimate pairs correlated at |ρ| ≥ 0.95, `import`'s
//! labels, `run`'s log on a full disk and two processes on one output folder.

use crate::support::{deflex, s, scratch, with_data};
use deflex_calibrate::measurements::format_rows_for;
use deflex_calibrate::stiffness::plan::{PlanOptions, plan_experiments};
use deflex_calibrate::stiffness::synthetic::{SyntheticOptions, measure};
use deflex_model::{Robot, builtin};
use std::path::Path;
use std::process::Command;

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
    let dir = scratch("strict-ignore-column");
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
    let run = deflex(&with_data(
        "validate",
        s(&model),
        &data,
        &["--ignore-column", "operator"],
    ));
    assert_eq!(run.code, Some(0), "{}{}", run.stdout, run.stderr);
    // A typo of a known column is not something to ignore: it names the column it meant.
    let typo = dir.join("typo.csv");
    std::fs::write(&typo, with_column(&text, "sigma_mm", "0.01")).unwrap();
    let run = deflex(&with_data(
        "validate",
        "ur10e",
        &typo,
        &["--ignore-column", "operator"],
    ));
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
    let run = deflex(&with_data(
        "validate",
        "ur10e",
        &data,
        &["--ignore-column", "operator", "--ignore-column", "sigma_m"],
    ));
    assert!(
        run.code == Some(1) && run.stderr.contains("`sigma_m` is read by the format"),
        "{}",
        run.stderr
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn one_load_case_holding_two_configurations_is_refused_naming_lines() {
    let dir = scratch("strict-load-case");
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

/// A SIMULATED two-axis arm whose two vertical axes stand 30 mm apart with the tool 1 m out:
/// a horizontal force at the tool twists both joints by nearly the same lever, so the two
/// z-eDoFs are nearly collinear in every reading.
const TWO_AXES: &str = "name = \"SIMULATED two-axis arm\"
[[joint]]
alpha = 0.0
a = 0.0
d = 0.0
theta_offset = 0.0
limits = [-3.0, 3.0]
stiffness = { z = 1.0e5 }
[[joint]]
alpha = 0.0
a = 0.03
d = 0.0
theta_offset = 0.0
limits = [-3.0, 3.0]
stiffness = { z = 2.0e5 }
[tool]
xyz = [1.0, 0.0, 0.0]
";

/// Its SIMULATED campaign: 8 × 3 configurations, a 100 N horizontal force at the tool along x
/// then y, the tool measured (`deflex_calibrate::stiffness::synthetic::measure`, 15 µm noise).
fn two_axes_campaign(robot: &Robot) -> String {
    use deflex_calibrate::measurements::MeasurementRow;
    let mut data = deflex_model::Data::new();
    let mut plan = Vec::new();
    for i in 0..8 {
        for q2 in [-0.2, 0.0, 0.2] {
            let q = vec![-1.4 + 0.4 * f64::from(i), q2];
            robot.forward_kinematics(&mut data, &q).unwrap();
            let tcp: [f64; 3] = data.tcp_position().into();
            for (axis, force) in [(0, [100.0, 0.0]), (1, [0.0, 100.0])] {
                plan.push(MeasurementRow {
                    load_case: format!("C{i}_{q2}_{axis}"),
                    q_rad: q.clone(),
                    wrench: [force[0], force[1], 0.0, 0.0, 0.0, 0.0],
                    load_link: 2,
                    load_point_m: tcp,
                    point: "TCP".into(),
                    point_link: 2,
                    point_m: tcp,
                    displacement_m: None,
                    sigma_m: None,
                    rotation_rad: None,
                    purpose: None,
                });
            }
        }
    }
    let rows = measure(robot, &plan, &SyntheticOptions::default()).unwrap();
    format_rows_for(robot, &rows, &["SIMULATED nearly collinear campaign"])
}

#[test]
fn calibrate_flags_nearly_collinear_estimates_in_text_json_and_html() {
    let dir = scratch("strict-collinear");
    let robot_file = dir.join("arm.toml");
    std::fs::write(&robot_file, TWO_AXES).unwrap();
    let robot = deflex_app::load::load_robot(s(&robot_file)).unwrap();
    let data = dir.join("meas.csv");
    std::fs::write(&data, two_axes_campaign(&robot)).unwrap();
    let model = dir.join("m.toml");
    let report = dir.join("report");
    let args = [
        "calibrate",
        "--robot",
        s(&robot_file),
        "--data",
        s(&data),
        "--structure",
        "fixed",
        "--out",
        s(&model),
        "--report",
        s(&report),
    ];
    let run = deflex(&args);
    assert_eq!(run.code, Some(0), "{}{}", run.stdout, run.stderr);
    let flagged = |text: &str| {
        text.contains("1 pair(s) of estimates correlated at |ρ| ≥ 0.95")
            && text.contains("J1.z and J2.z correlated at ρ = -")
    };
    assert!(flagged(&run.stdout), "{}", run.stdout);
    let html = std::fs::read_to_string(report.join("calibration.html")).unwrap();
    assert!(flagged(&html), "{html}");
    let mut json_args = vec!["--json"];
    json_args.extend(args);
    let run = deflex(&json_args);
    assert_eq!(run.code, Some(0), "{}{}", run.stdout, run.stderr);
    let v: serde_json::Value = serde_json::from_str(&run.stdout).unwrap();
    let pairs = v["correlated_pairs"].as_array().unwrap();
    assert_eq!(pairs.len(), 1, "{v}");
    assert_eq!(pairs[0]["first"], "J1.z");
    assert_eq!(pairs[0]["second"], "J2.z");
    assert!(pairs[0]["rho"].as_f64().unwrap() < -0.95, "{v}");
    // The same calibration on a campaign that separates them flags nothing: the planner's
    // campaign of the UR10e for its own eDoFs.
    let ur = dir.join("ur.csv");
    std::fs::write(&ur, campaign_text(&builtin("ur10e").unwrap())).unwrap();
    let run = deflex(&[
        "--json",
        "calibrate",
        "--robot",
        "ur10e",
        "--data",
        s(&ur),
        "--structure",
        "fixed",
        "--out",
        s(&model),
    ]);
    assert_eq!(run.code, Some(0), "{}{}", run.stdout, run.stderr);
    let v: serde_json::Value = serde_json::from_str(&run.stdout).unwrap();
    let correlation = v["correlation"].as_array().unwrap();
    let strong = correlation
        .iter()
        .enumerate()
        .flat_map(|(i, row)| {
            row.as_array()
                .unwrap()
                .iter()
                .skip(i + 1)
                .map(|r| r.as_f64().unwrap().abs())
                .collect::<Vec<_>>()
        })
        .filter(|r| *r >= 0.95)
        .count();
    assert_eq!(
        v["correlated_pairs"].as_array().unwrap().len(),
        strong,
        "{v}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A full disk under `deflex run`'s log, made deterministic: the child runs with
/// `RLIMIT_FSIZE` = 256 KiB and SIGXFSZ ignored, so the log's write past it (about 520 rows)
/// fails with EFBIG whatever the machine's load. The session must stop there, ramping the
/// correction out, print its summary with "log: NOT written", keep the earlier log whole and
/// exit with status 4. The robot (simple UDP) and the sensor (Net F/T) are in this process;
/// the sensor pushes 800 N after the robot's 250th answer, once the tare (0.2 s) is done.
#[test]
fn a_full_disk_under_the_run_log_stops_the_session_with_exit_status_4() {
    use crate::support::RunPeers;
    use deflex_model::Wrench;
    use std::os::unix::process::CommandExt as _;
    use std::time::Instant;

    let _turn = crate::session_turn();
    let dir = scratch("strict-full-disk");
    let (cell, robot_port, sensor_port) = crate::cli_run::cell_file(
        &dir,
        "simple-udp",
        "[limits]\nramp_out_s = 0.3\n[log]\npath = \"run.csv\"\n",
    );
    let earlier = "# the log of an earlier run\ntime_s\n0.0\n";
    std::fs::write(dir.join("run.csv"), earlier).unwrap();
    let peers = RunPeers::start(
        robot_port,
        sensor_port,
        |_| true,
        |answered| {
            let fz = if answered < 250 { 0.0 } else { -800.0 };
            Some(Wrench::new(0.0, 0.0, fz, 0.0, 0.0, 0.0))
        },
    );
    let mut command = Command::new(env!("CARGO_BIN_EXE_deflex"));
    command.args(["run", "--config", s(&cell), "--quiet"]);
    // SAFETY: between fork and exec only async-signal-safe calls (setrlimit, signal) on the
    // child's own limits and dispositions; an ignored SIGXFSZ stays ignored across exec.
    unsafe {
        command.pre_exec(|| {
            let limit = libc::rlimit {
                rlim_cur: 1 << 18,
                rlim_max: 1 << 18,
            };
            if libc::setrlimit(libc::RLIMIT_FSIZE, &limit) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
            Ok(())
        });
    }
    let started = Instant::now();
    let out = command.output().unwrap();
    let answers = peers.join();
    let text = String::from_utf8_lossy(&out.stdout);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(4), "{text}\n{err}");
    assert!(
        err.contains("run.csv cannot be written (File too large") && err.contains("ramps out"),
        "{err}"
    );
    assert!(
        text.contains("phase: stopped (correction ramped out)")
            && text.contains("log: NOT written")
            && text.contains("run.csv keeps what it held"),
        "{text}"
    );
    // The session ran past the force (the log held 256 KiB of rows), the correction was
    // active, and the robot's last answers brought it back to zero.
    assert!(answers.len() > 500, "{} answers", answers.len());
    let peak = answers.iter().map(|c| c[2].abs()).fold(0.0, f64::max);
    assert!(peak > 1e-4, "the correction was active: {peak}");
    let last = answers.last().unwrap();
    assert!(
        last.iter().all(|v| v.abs() < 1e-9),
        "not ramped out: {last:?}"
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("run.csv")).unwrap(),
        earlier
    );
    // No temporary of the failed log is left beside it.
    let names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        !names.iter().any(|n| n.contains(".tmp-")),
        "{names:?} ({:.1} s)",
        started.elapsed().as_secs_f64()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every entry of `dir` (recursively) with its size and modification time: what "touching
/// nothing" is checked against.
fn snapshot(dir: &Path) -> Vec<(String, u64, std::time::SystemTime)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let entry = entry.unwrap();
            let meta = std::fs::symlink_metadata(entry.path()).unwrap();
            if meta.is_dir() {
                stack.push(entry.path());
            }
            out.push((
                entry.path().display().to_string(),
                meta.len(),
                meta.modified().unwrap(),
            ));
        }
    }
    out.sort();
    out
}

/// Two processes on one output folder (issue 18, item 2): while this test process holds the
/// folder's lock (`.map.lock`, `flock`ed as deflex-files does, its process id inside), the real
/// binary writing `map --out map` is refused with "being written by another deflex run
/// (process N)" and touches nothing; once the lock is released, the same run succeeds.
#[test]
fn a_folder_being_written_by_another_process_is_refused_then_written_once_released() {
    use std::io::Write as _;
    use std::os::fd::AsRawFd as _;
    let dir = scratch("strict-lock");
    let out = dir.join("map");
    let map = [
        "map",
        "--robot",
        "tx200",
        "--step",
        "100mm",
        "--out",
        s(&out),
    ];
    // An earlier whole result.
    let run = deflex(&map);
    assert_eq!(run.code, Some(0), "{}{}", run.stdout, run.stderr);
    let before = snapshot(&dir);
    let mut lock = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(true)
        .open(dir.join(".map.lock"))
        .unwrap();
    writeln!(lock, "{}", std::process::id()).unwrap();
    // SAFETY: flock on a descriptor this test owns.
    let locked = unsafe { libc::flock(lock.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) };
    assert_eq!(locked, 0, "{}", std::io::Error::last_os_error());
    let held = snapshot(&dir);
    let run = deflex(&map);
    assert_eq!(run.code, Some(1), "{}{}", run.stdout, run.stderr);
    assert!(
        run.stderr.contains(&format!(
            "is being written by another deflex run (process {}",
            std::process::id()
        )) && run.stderr.contains("nothing was written"),
        "{}",
        run.stderr
    );
    assert_eq!(snapshot(&dir), held, "the refused run touched the folder");
    // Released (as the system releases it when the holder ends, however it ends): the second
    // run writes its whole result.
    // SAFETY: as above.
    assert_eq!(unsafe { libc::flock(lock.as_raw_fd(), libc::LOCK_UN) }, 0);
    drop(lock);
    let run = deflex(&map);
    assert_eq!(run.code, Some(0), "{}{}", run.stdout, run.stderr);
    let after = snapshot(&dir);
    assert_ne!(after, before, "the released run wrote its result");
    assert_eq!(
        after.iter().map(|e| &e.0).collect::<Vec<_>>(),
        before
            .iter()
            .chain(held.iter().filter(|e| e.0.ends_with(".map.lock")))
            .map(|e| &e.0)
            .collect::<std::collections::BTreeSet<_>>()
            .into_iter()
            .collect::<Vec<_>>(),
        "the same files, no temporary left"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `deflex import` writes only labels its own reader reads back the same (issue 18, item 6):
/// hostile `--setup`/`--target` labels are refused (not rewritten), naming the flag and why, with
/// nothing written; every label it accepts, however odd, reads back exactly.
#[test]
fn import_writes_only_labels_its_reader_reads_back() {
    let dir = scratch("strict-import-labels");
    let series = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../deflex-calibrate/tests/data/ur10-tracker/Series_A");
    let out = dir.join("a.csv");
    let import = |setup: &str, target: &str| {
        deflex(&[
            "import",
            "ur10-tracker",
            "--series",
            s(&series),
            "--every",
            "50",
            "--setup",
            setup,
            "--target",
            target,
            "--out",
            s(&out),
        ])
    };
    let long = "x".repeat(201);
    let long_utf8 = "é".repeat(101); // 202 bytes
    for (setup, target, flag, why) in [
        ("", "tmac", "--setup", "is empty"),
        (" A", "tmac", "--setup", "white space"),
        ("A", "tmac\t", "--target", "U+0009"),
        ("#1", "tmac", "--setup", "leading `#`"),
        ("A\nB", "tmac", "--setup", "U+000A"),
        ("A\u{1b}[2J", "tmac", "--setup", "U+001B"),
        ("A", long.as_str(), "--target", "201 bytes"),
        (long_utf8.as_str(), "tmac", "--setup", "202 bytes"),
    ] {
        let run = import(setup, target);
        assert_eq!(run.code, Some(1), "{setup:?}/{target:?}: {}", run.stdout);
        assert!(
            run.stderr.contains(flag)
                && run.stderr.contains(why)
                && run
                    .stderr
                    .contains("import refuses it (labels are not rewritten)"),
            "{setup:?}/{target:?}: {}",
            run.stderr
        );
        assert!(
            !run.stderr.contains('\u{1b}'),
            "raw escape: {:?}",
            run.stderr
        );
        assert!(!out.exists(), "{setup:?}/{target:?} wrote a file");
    }
    let edge = "é".repeat(100); // 200 bytes: the longest label the reader takes
    for (setup, target) in [
        ("A", "tmac"),
        ("set-up, east \"wall\"", "T-Mac #2"),
        (edge.as_str(), "Ωµ° probe"),
    ] {
        let run = import(setup, target);
        assert_eq!(run.code, Some(0), "{setup:?}: {}{}", run.stdout, run.stderr);
        let text = std::fs::read_to_string(&out).unwrap();
        let rows = deflex_calibrate::geometry::data::parse_absolute(&text, "a.csv", 6).unwrap();
        assert!(rows.len() > 1, "{}", rows.len());
        assert!(
            rows.iter().all(|r| r.setup == setup && r.target == target),
            "{setup:?}/{target:?} read back as {:?}/{:?}",
            rows[0].setup,
            rows[0].target
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Absolute files (`calibrate-geometry`, `predict`, `register`) follow the same header rule: an
/// extra column is refused unless named with `--ignore-column`. And `calibrate-geometry` flags
/// every pair of estimates correlated at |ρ| ≥ 0.95 in its text, JSON and HTML report: on a
/// sparse subset of the real UR10 series (every 10th reading) the fit has such pairs.
#[test]
fn calibrate_geometry_takes_ignore_column_and_flags_correlated_estimates() {
    let dir = scratch("strict-egcal");
    let series = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../deflex-calibrate/tests/data/ur10-tracker/Series_A");
    let plain = dir.join("a.csv");
    let run = deflex(&[
        "import",
        "ur10-tracker",
        "--series",
        s(&series),
        "--every",
        "10",
        "--setup",
        "A",
        "--out",
        s(&plain),
    ]);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let data = dir.join("b.csv");
    std::fs::write(
        &data,
        with_column(&std::fs::read_to_string(&plain).unwrap(), "operator", "ann"),
    )
    .unwrap();
    let model = dir.join("m.toml");
    let report = dir.join("report");
    let args = [
        "calibrate-geometry",
        "--robot",
        "ur10",
        "--data",
        s(&data),
        "--folds",
        "0",
        "--out",
        s(&model),
        "--report",
        s(&report),
    ];
    let run = deflex(&args);
    assert_eq!(run.code, Some(1), "{}{}", run.stdout, run.stderr);
    assert!(
        run.stderr
            .contains("b.csv: header: unknown column `operator`"),
        "{}",
        run.stderr
    );
    assert!(!model.exists() && !report.exists());
    let mut ignoring = args.to_vec();
    ignoring.extend(["--ignore-column", "operator"]);
    let run = deflex(&ignoring);
    assert_eq!(run.code, Some(0), "{}{}", run.stdout, run.stderr);
    let text = run.stdout;
    let mut json_args = vec!["--json"];
    json_args.extend(&ignoring);
    let run = deflex(&json_args);
    assert_eq!(run.code, Some(0), "{}{}", run.stdout, run.stderr);
    let v: serde_json::Value = serde_json::from_str(&run.stdout).unwrap();
    let pairs = v["correlated_pairs"].as_array().unwrap();
    assert!(!pairs.is_empty(), "{v}");
    let html = std::fs::read_to_string(report.join("index.html")).unwrap();
    let heading = format!(
        "WARNING: {} pair(s) of estimates correlated at |ρ| ≥ 0.95",
        pairs.len()
    );
    assert!(text.contains(&heading), "{text}");
    assert!(html.contains(&heading), "{html}");
    for pair in pairs {
        let rho = pair["rho"].as_f64().unwrap();
        assert!(rho.abs() >= 0.95, "{pair}");
        let line = format!(
            "{} / {}: {rho:+.3}",
            pair["first"].as_str().unwrap(),
            pair["second"].as_str().unwrap()
        );
        assert!(text.contains(&line), "{line}: {text}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

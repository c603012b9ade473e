//! End-to-end tests of `deflex plan`, `calibrate` and `validate` through the real binary:
//! files that know their robot, the planner's cell, and every bad input of issue 12.

use deflex_calibrate::measurements::{MeasurementRow, format_rows_for};
use deflex_calibrate::stiffness::plan::{PlanOptions, plan_experiments};
use deflex_calibrate::stiffness::synthetic::{SyntheticOptions, measure};

/// Write rows for `robot` as a measurement file (what `deflex_calibrate::stiffness::write_rows_for` did).
fn write_rows_for(
    path: &std::path::Path,
    robot: &deflex_model::Robot,
    rows: &[MeasurementRow],
    notes: &[&str],
) -> std::io::Result<()> {
    std::fs::write(path, format_rows_for(robot, rows, notes))
}
use crate::support::{deflex, s, scratch, with_data};
use deflex_model::{Robot, builtin};
use std::path::Path;

/// A SIMULATED campaign of `robot` (planned for it, measured on it), written with its header.
fn campaign(robot: &Robot, force: f64, path: &Path) -> Vec<MeasurementRow> {
    let plan = plan_experiments(
        robot,
        &PlanOptions {
            max_force_n: force,
            load_cases: 16,
            full_family: false,
            ..PlanOptions::for_a_real_cell()
        },
    )
    .unwrap();
    let rows = measure(robot, &plan.rows, &SyntheticOptions::default()).unwrap();
    write_rows_for(path, robot, &rows, &["SIMULATED test campaign"]).unwrap();
    rows
}

/// The issue's acceptance: a UR10e measurement file given with the TX200's model is refused,
/// by `calibrate` and by `validate`, naming rows and distances; nothing is written.
#[test]
fn a_ur10e_measurement_given_with_the_tx200_is_refused() {
    let dir = scratch("calib-ur-vs-tx");
    let data = dir.join("meas_ur.csv");
    campaign(&builtin("ur10e").unwrap(), 150.0, &data);
    let model = dir.join("m.toml");
    let run = deflex(&with_data(
        "calibrate",
        "tx200",
        &data,
        &["--out", s(&model)],
    ));
    assert_eq!(run.code, Some(1), "{}", run.stderr);
    for wanted in [
        "meas_ur.csv: ",
        "rows disagree with the forward kinematics of robot \"Staubli TX200",
        "line 5 (load case A01, point TCP): ",
        " mm from the TCP its joint values give",
        "header names robot \"Universal Robots UR10e",
        "--ignore-fk-check",
    ] {
        assert!(
            run.stderr.contains(wanted),
            "missing {wanted:?} in:\n{}",
            run.stderr
        );
    }
    assert!(!model.exists());
    let val = dir.join("val");
    let run = deflex(&with_data("validate", "tx200", &data, &["--out", s(&val)]));
    assert_eq!(run.code, Some(1), "{}", run.stderr);
    assert!(run.stderr.contains("mm from the TCP"), "{}", run.stderr);
    assert!(!val.exists());
    // Overridden, it goes on with a warning.
    let run = deflex(&with_data(
        "validate",
        "tx200",
        &data,
        &["--ignore-fk-check"],
    ));
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    assert!(run.stdout.contains("warning: ") && run.stdout.contains("going on as asked"));
    // Its own robot takes it, and says how well the coordinates agree.
    let run = deflex(&[
        "--json",
        "calibrate",
        "--robot",
        "ur10e",
        "--data",
        s(&data),
        "--out",
        s(&model),
    ]);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let v: serde_json::Value = serde_json::from_str(&run.stdout).unwrap();
    assert_eq!(v["geometry_check"]["disagreeing_rows"], 0);
    assert!(v["geometry_check"]["max_distance_m"].as_f64().unwrap() < 1e-9);
    assert!(model.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Issue 12: degenerate data (every displacement zero; one force of 1e308 N) gets a clear
/// error, not a panic (exit 101).
#[test]
fn degenerate_calibration_data_is_a_clear_error() {
    let dir = scratch("calib-degenerate");
    let data = dir.join("meas.csv");
    let robot = builtin("tx200").unwrap();
    let mut rows = campaign(&robot, 1400.0, &data);
    for r in &mut rows {
        r.displacement_m = Some([0.0; 3]);
    }
    let zero = dir.join("zero.csv");
    write_rows_for(&zero, &robot, &rows, &[]).unwrap();
    let model = dir.join("m.toml");
    let run = deflex(&with_data(
        "calibrate",
        "tx200",
        &zero,
        &["--out", s(&model)],
    ));
    assert_eq!(run.code, Some(1), "{}", run.stderr);
    assert!(
        run.stderr
            .contains("every measured displacement is exactly zero"),
        "{}",
        run.stderr
    );

    let text = std::fs::read_to_string(&data).unwrap();
    let header = text.lines().find(|l| l.starts_with("load_case")).unwrap();
    let column = header.split(',').position(|c| c == "fx_N").unwrap();
    let first = text.lines().find(|l| l.starts_with("A01")).unwrap();
    let mut fields: Vec<&str> = first.split(',').collect();
    fields[column] = "1e308";
    let big = dir.join("big.csv");
    std::fs::write(&big, text.replacen(first, &fields.join(","), 1)).unwrap();
    let run = deflex(&with_data(
        "calibrate",
        "tx200",
        &big,
        &["--out", s(&model)],
    ));
    assert_eq!(run.code, Some(1), "{}", run.stderr);
    assert!(
        run.stderr.contains("big.csv:5") && run.stderr.contains("fx_N"),
        "{}",
        run.stderr
    );
    assert!(!model.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Issue 12: every numeric flag of plan, calibrate and validate is checked, the flag named;
/// `--max-force-N 1e308` (once an endless SVD on NaN) is refused at once.
#[test]
fn every_numeric_flag_is_checked() {
    let dir = scratch("calib-flags");
    let data = dir.join("meas.csv");
    campaign(&builtin("tx200").unwrap(), 1400.0, &data);
    let out = dir.join("x");
    let plan = |extra: &[&str]| {
        let mut args = vec!["plan", "--robot", "tx200", "--out", s(&out)];
        args.extend_from_slice(extra);
        deflex(&args)
    };
    let cases: &[(&[&str], &str)] = &[
        (&["--max-force-N", "1e308"], "--max-force-N"),
        (&["--max-force-N", "nan"], "--max-force-N"),
        (&["--max-force-N=-1"], "--max-force-N"),
        (&["--noise-um", "nan"], "--noise-um"),
        (&["--noise-um", "0"], "--noise-um"),
        (&["--load-cases", "0"], "--load-cases"),
        (&["--load-cases", "1000000"], "--load-cases"),
        (&["--configurations", "0"], "--configurations"),
        (&["--configurations", "100000000"], "--configurations"),
        (&["--clearance-m", "nan"], "--clearance-m"),
        (&["--hanging-drop-m", "inf"], "--hanging-drop-m"),
        (&["--floor-z-m", "nan"], "--floor-z-m"),
        (&["--table", "1,0,0,1,0"], "--table"),
        (&["--table", "0,1,0,1,nan"], "--table"),
        (&["--bracket-m", "nan,0,0"], "--bracket-m"),
        (&["--bracket-m", "9,0,0"], "--bracket-m"),
        (&["--base-point-m", "0,0,1e300"], "--base-point-m"),
        (
            &["--load", "dead-weight", "--masses-kg", "nan"],
            "--masses-kg",
        ),
        (
            &["--load", "dead-weight", "--masses-kg", "1e9"],
            "--masses-kg",
        ),
        (&["--cable-directions", "x,up"], "--cable-directions"),
        (&["--point", "R1,1,0,0,0"], "--point"),
        (&["--points", "none", "--point", "R1,1,nan,0,0"], "--point"),
    ];
    for (extra, flag) in cases {
        let run = plan(extra);
        assert_eq!(run.code, Some(1), "{extra:?}: {}", run.stderr);
        assert!(run.stderr.contains(flag), "{extra:?}: {}", run.stderr);
    }
    assert!(!out.exists());
    let calibrate = |extra: &[&str]| {
        let mut args = vec![
            "calibrate",
            "--robot",
            "tx200",
            "--data",
            s(&data),
            "--out",
            s(&out),
        ];
        args.extend_from_slice(extra);
        deflex(&args)
    };
    let cases: &[(&[&str], &str)] = &[
        (&["--min-bic-gain", "nan"], "--min-bic-gain"),
        (&["--min-bic-gain=-1"], "--min-bic-gain"),
        (&["--target-rms-mm", "nan"], "--target-rms-mm"),
        (&["--min-cv-gain-percent", "nan"], "--min-cv-gain-percent"),
        (&["--folds", "1"], "--folds"),
        (&["--folds", "100000"], "--folds"),
        (&["--fk-tolerance-mm", "nan"], "--fk-tolerance-mm"),
        (&["--fk-tolerance-mm", "0"], "--fk-tolerance-mm"),
    ];
    for (extra, flag) in cases {
        let run = calibrate(extra);
        assert_eq!(run.code, Some(1), "{extra:?}: {}", run.stderr);
        assert!(run.stderr.contains(flag), "{extra:?}: {}", run.stderr);
    }
    let run = deflex(&with_data(
        "validate",
        "tx200",
        &data,
        &["--fk-tolerance-mm", "inf"],
    ));
    assert_eq!(run.code, Some(1));
    assert!(run.stderr.contains("--fk-tolerance-mm"), "{}", run.stderr);
    assert!(!out.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Issue 12: a failed validate leaves an existing output folder as it was (and creates none).
#[test]
fn a_failed_validate_leaves_the_folder_as_it_was() {
    let dir = scratch("calib-validate-atomic");
    let data = dir.join("meas.csv");
    campaign(&builtin("ur10e").unwrap(), 150.0, &data);
    let val = dir.join("val");
    std::fs::create_dir_all(&val).unwrap();
    std::fs::write(val.join("old.txt"), "from an earlier run").unwrap();
    // An earlier deflex output folder (a foreign one is refused whole).
    std::fs::write(val.join(".deflex-output"), "").unwrap();
    // Fails: the TX200 is not the robot of this file.
    let run = deflex(&with_data("validate", "tx200", &data, &["--out", s(&val)]));
    assert_eq!(run.code, Some(1));
    let names: Vec<String> = std::fs::read_dir(&val)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    let mut names = names;
    names.sort();
    assert_eq!(
        names,
        vec![".deflex-output".to_string(), "old.txt".to_string()]
    );
    // Succeeds: the folder is replaced whole.
    let run = deflex(&with_data("validate", "ur10e", &data, &["--out", s(&val)]));
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    assert!(val.join("validation.html").exists() && !val.join("old.txt").exists());
    // No temporary sibling is left behind.
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp-"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A six-joint URDF arm (UR-like placements) with revolute limits.
const URDF: &str = r#"<?xml version="1.0"?>
<robot name="test_arm">
  <link name="base_link"/><link name="l1"/><link name="l2"/><link name="l3"/><link name="l4"/><link name="l5"/><link name="l6"/>
  <joint name="j1" type="revolute"><origin xyz="0 0 0.18" rpy="0 0 0"/><parent link="base_link"/><child link="l1"/><axis xyz="0 0 1"/><limit lower="-3.1" upper="3.1" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><origin xyz="0 0 0" rpy="1.5708 0 0"/><parent link="l1"/><child link="l2"/><axis xyz="0 0 1"/><limit lower="-3.1" upper="0.0" effort="1" velocity="1"/></joint>
  <joint name="j3" type="revolute"><origin xyz="-0.61 0 0" rpy="0 0 0"/><parent link="l2"/><child link="l3"/><axis xyz="0 0 1"/><limit lower="-2.8" upper="2.8" effort="1" velocity="1"/></joint>
  <joint name="j4" type="revolute"><origin xyz="-0.57 0 0.17" rpy="0 0 0"/><parent link="l3"/><child link="l4"/><axis xyz="0 0 1"/><limit lower="-3.1" upper="3.1" effort="1" velocity="1"/></joint>
  <joint name="j5" type="revolute"><origin xyz="0 -0.12 0" rpy="1.5708 0 0"/><parent link="l4"/><child link="l5"/><axis xyz="0 0 1"/><limit lower="-3.1" upper="3.1" effort="1" velocity="1"/></joint>
  <joint name="j6" type="revolute"><origin xyz="0 0.12 0" rpy="-1.5708 0 0"/><parent link="l5"/><child link="l6"/><axis xyz="0 0 1"/><limit lower="-3.1" upper="3.1" effort="1" velocity="1"/></joint>
</robot>
"#;

/// Issue 12: `calibrate --out sub/m.toml` for a URDF-based robot writes a model that still
/// finds its URDF.
#[test]
fn a_calibrated_urdf_robot_written_elsewhere_finds_its_urdf() {
    let dir = scratch("calib-urdf");
    std::fs::write(dir.join("arm.urdf"), URDF).unwrap();
    let mut toml = String::from("name = \"URDF test arm\"\nurdf = \"arm.urdf\"\n");
    for (i, k) in [1.6e5, 1.3e5, 8.0e4, 2.0e4, 2.0e4, 1.5e4]
        .iter()
        .enumerate()
    {
        toml.push_str(&format!(
            "[[joint]]\nname = \"j{}\"\nstiffness = {{ z = {k:e} }}\n",
            i + 1
        ));
    }
    let robot_file = dir.join("arm.toml");
    std::fs::write(&robot_file, toml).unwrap();
    let robot = deflex_app::load::load_robot(s(&robot_file)).unwrap();
    let data = dir.join("meas.csv");
    campaign(&robot, 150.0, &data);
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    let model = dir.join("sub").join("m.toml");
    let run = deflex(&with_data(
        "calibrate",
        s(&robot_file),
        &data,
        &["--out", s(&model), "--structure", "fixed"],
    ));
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let written = std::fs::read_to_string(&model).unwrap();
    assert!(written.contains("urdf = \"../arm.urdf\""), "{written}");
    let run = deflex(&["model", "show", "--robot", s(&model)]);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `deflex plan` plans a real cell for every built-in robot: header lines, floor, joint values
/// within ±180° where the limits allow, a technician's sheet; a bracket loads the wrist.
#[test]
fn plan_for_every_builtin_robot() {
    let dir = scratch("calib-plans");
    for (name, _) in deflex_model::BUILTIN_ROBOTS {
        let out = dir.join(format!("{name}.csv"));
        let run = deflex(&[
            "--json",
            "plan",
            "--robot",
            name,
            "--out",
            s(&out),
            "--configurations",
            "200",
            "--load-cases",
            "10",
        ]);
        assert_eq!(run.code, Some(0), "{name}: {}", run.stderr);
        let v: serde_json::Value = serde_json::from_str(&run.stdout).unwrap();
        assert!(v["setup"]["floor_z_m"].is_number(), "{name}");
        assert!(v["setup"]["table"].is_object(), "{name}");
        assert!(!v["technician_sheet"].as_array().unwrap().is_empty());
        let text = std::fs::read_to_string(&out).unwrap();
        let robot = builtin(name).unwrap();
        assert!(
            text.starts_with(&format!(
                "# robot: {}\n# geometry: {}\n",
                robot.name,
                robot.geometry_fingerprint()
            )),
            "{name}"
        );
    }
    // Text output, with a bracket and dead weights.
    let out = dir.join("bracket.csv");
    let run = deflex(&[
        "plan",
        "--robot",
        "tx200",
        "--full-family",
        "--bracket-m",
        "0.2,0,0.1",
        "--load",
        "dead-weight",
        "--masses-kg",
        "80,140",
        "--out",
        s(&out),
    ]);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    assert!(
        run.stdout.contains("dead weight 140 kg at BR")
            || run.stdout.contains("dead weight 80 kg at BR"),
        "{}",
        run.stdout
    );
    assert!(
        run.stdout.contains("floor at z = -0.642 m"),
        "{}",
        run.stdout
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The calibration report holds the plots; JSON says when χ²/dof is well above 1.
#[test]
fn calibrate_writes_a_report_with_plots_and_flags_a_high_chi2() {
    let dir = scratch("calib-report");
    let data = dir.join("meas.csv");
    let robot = builtin("tx200").unwrap();
    let mut rows = campaign(&robot, 1400.0, &data);
    // Claim 3 µm where the noise is 15 µm: χ²/dof ≈ 25.
    for r in &mut rows {
        r.sigma_m = Some(3e-6);
    }
    write_rows_for(&data, &robot, &rows, &[]).unwrap();
    let model = dir.join("m.toml");
    let report = dir.join("report");
    let run = deflex(&[
        "--json",
        "calibrate",
        "--robot",
        "tx200",
        "--data",
        s(&data),
        "--out",
        s(&model),
        "--report",
        s(&report),
    ]);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let v: serde_json::Value = serde_json::from_str(&run.stdout).unwrap();
    assert_eq!(v["chi2_well_above_one"], true, "{}", v["reduced_chi2"]);
    assert!(
        v["model_form_note"]
            .as_str()
            .unwrap()
            .contains("well above 1")
    );
    for name in [
        "calibration.html",
        "residuals_per_load_case.png",
        "parity_z.png",
        "correlation.png",
        "shifts.csv",
    ] {
        assert!(report.join(name).exists(), "{name}");
    }
    let run = deflex(&with_data(
        "calibrate",
        "tx200",
        &data,
        &["--out", s(&model)],
    ));
    assert!(run.stdout.contains("well above 1"), "{}", run.stdout);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The simulated campaign names the robot the twin played; a UR10e plan measured on the twin
/// keeps the UR10e's coordinates, so the TX200's model refuses the file.
#[test]
fn simulated_campaigns_carry_their_robot() {
    let dir = scratch("calib-sim");
    let plan = dir.join("plan_ur.csv");
    let run = deflex(&[
        "plan",
        "--robot",
        "ur10e",
        "--out",
        s(&plan),
        "--load-cases",
        "8",
        "--configurations",
        "200",
    ]);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let meas = dir.join("meas_ur.csv");
    let run = deflex(&["sim", "campaign", "--plan", s(&plan), "--out", s(&meas)]);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let text = std::fs::read_to_string(&meas).unwrap();
    let mut lines = text.lines();
    assert!(lines.next().unwrap().starts_with("# SIMULATED"));
    assert!(lines.next().unwrap().starts_with("# robot: "));
    assert!(lines.next().unwrap().starts_with("# geometry: "));
    let run = deflex(&with_data(
        "calibrate",
        "tx200",
        &meas,
        &["--out", s(&dir.join("m.toml"))],
    ));
    assert_eq!(run.code, Some(1), "{}", run.stderr);
    assert!(
        run.stderr.contains("mm from the TCP its joint values give"),
        "{}",
        run.stderr
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The twin settings of a plant as a `[cell]` file.
fn twin_file(path: &Path, cell: &deflex_sim::CellConfig) {
    let mut file = toml::Table::new();
    file.insert("cell".into(), toml::Value::try_from(cell).unwrap());
    std::fs::write(path, toml::to_string(&file).unwrap()).unwrap();
}

/// The KR 210-like unseen plant of deflex-app's held-out check (`twin/unseen_plant.rs`, plant 1):
/// a hardening wrist (0.4 mrad of lost motion taken up over 600 N·m), a compliant tool holder
/// (4e5 N·m/rad, 80 mm down the tool), every error source on, tracker readings of 25 samples;
/// J2.z–J3.z coupling `rho`.
fn unseen_plant(rho: f64) -> deflex_sim::CellConfig {
    let mut cell = deflex_sim::CellConfig::for_robot("kr210-r2700").unwrap();
    let p = &mut cell.plant;
    p.j2_j3_coupling = rho;
    p.wrist_lost_motion_rad = [0.4e-3; 3];
    p.wrist_takeup_torque_nm = 600.0;
    p.wrist_hysteresis_nm = 60.0;
    p.joint_stiffness[5][0] = 4.0e5;
    p.joint_stiffness[5][1] = 4.0e5;
    p.center_shift_m[5] = 0.08;
    cell.tracker.samples_per_reading = 25;
    cell
}

/// `calibrate --couplings` on SIMULATED campaigns, as a user runs them (`sim robot`,
/// `plan --load-cases 40 --full-family`, `sim campaign`, `calibrate`), of the TX200 twin and of
/// the unseen KR 210-like plant, each with every error source on: with a J2.z–J3.z coupling
/// planted in the plant (ρ = 0.3) the stated 95 % interval holds the plant's off-diagonal
/// compliance `ρ/√(k2 k3)` and excludes zero; without one it holds zero. The robot file written
/// carries the coupling; a pair outside the identified structure is refused naming the pair and
/// the structure, and writes nothing.
#[test]
fn couplings_are_fitted_from_a_simulated_campaign() {
    let dir = scratch("calib-couplings");
    let tx200 = |rho: f64| {
        let mut cell = deflex_sim::CellConfig::for_robot("tx200").unwrap();
        cell.plant.j2_j3_coupling = rho;
        cell
    };
    for (name, cell) in [
        ("TX200 twin", tx200(0.3)),
        ("TX200 twin", tx200(0.0)),
        ("unseen plant 1", unseen_plant(0.3)),
        ("unseen plant 1", unseen_plant(0.0)),
    ] {
        let rho = cell.plant.j2_j3_coupling;
        let k = cell.plant.joint_stiffness;
        let truth = rho / (k[1][2] * k[2][2]).sqrt();
        // The planted coupling's compliance: the campaign resolves it to better than 30 %.
        let planted = 0.3 / (k[1][2] * k[2][2]).sqrt();
        let tag = format!("{}_{rho}", cell.part.robot);
        let twin = dir.join(format!("twin_{tag}.toml"));
        twin_file(&twin, &cell);
        let robot = dir.join(format!("robot_{tag}.toml"));
        let plan = dir.join(format!("plan_{tag}.csv"));
        let meas = dir.join(format!("meas_{tag}.csv"));
        let out = dir.join(format!("calibrated_{tag}.toml"));
        for args in [
            vec!["sim", "robot", "--config", s(&twin), "--out", s(&robot)],
            vec![
                "plan",
                "--robot",
                s(&robot),
                "--load-cases",
                "40",
                "--full-family",
                "--out",
                s(&plan),
            ],
            vec![
                "sim",
                "campaign",
                "--config",
                s(&twin),
                "--plan",
                s(&plan),
                "--out",
                s(&meas),
            ],
        ] {
            let run = deflex(&args);
            assert_eq!(run.code, Some(0), "{args:?}: {}", run.stderr);
        }
        // `deflex [--json] calibrate … --couplings PAIRS --out OUT` on this campaign.
        let calibrate = |json: bool, pairs: &str, out: &Path| {
            let mut args = vec![
                "calibrate",
                "--robot",
                s(&robot),
                "--data",
                s(&meas),
                "--couplings",
                pairs,
                "--out",
                s(out),
            ];
            if json {
                args.insert(0, "--json");
            }
            deflex(&args)
        };
        let run = calibrate(true, "J2.z:J3.z", &out);
        assert_eq!(run.code, Some(0), "{}", run.stderr);
        let v: serde_json::Value = serde_json::from_str(&run.stdout).unwrap();
        let coupling = &v["couplings"][0];
        assert_eq!(coupling["coupling"], "J2.z–J3.z", "{coupling}");
        let number = |v: &serde_json::Value| v.as_f64().unwrap();
        let found = number(&coupling["compliance_rad_per_Nm"]);
        let se = number(&coupling["compliance_se"]);
        let (lo, hi) = (
            number(&coupling["interval95"][0]),
            number(&coupling["interval95"][1]),
        );
        println!(
            "SIMULATED {name}, planted ρ {rho}: J2.z–J3.z {found:.3e} ± {se:.2e} rad/(N·m) (95 %: {lo:.3e} … {hi:.3e}), plant {truth:.3e}; ρ {:.3} ± {:.3}; structure {}",
            number(&coupling["correlation"]),
            number(&coupling["correlation_se"]),
            v["structure"]
        );
        assert!(
            lo <= truth && truth <= hi,
            "{name}: {truth:e} not in [{lo:e}, {hi:e}]"
        );
        assert!(se > 0.0 && se < 0.3 * planted, "{name}: {se:e}");
        if rho > 0.0 {
            assert!(
                lo > 0.0,
                "{name}: the planted coupling is told from zero: {lo:e}"
            );
        }
        let fit = &v["coupling_fit"];
        assert!(number(&fit["reduced_chi2"]) <= number(&fit["reduced_chi2_before"]));
        // The robot file written carries it, and every other command reads it back.
        let written = deflex_app::load::load_robot(s(&out)).unwrap();
        assert_eq!(written.couplings.len(), 1);
        assert!((written.couplings[0].compliance / found - 1.0).abs() < 1e-9);
        // The text output says when the interval holds zero (the ρ = 0 plants), and only then.
        let text_out = dir.join(format!("calibrated_text_{tag}.toml"));
        let run = calibrate(false, "J2.z:J3.z", &text_out);
        assert_eq!(run.code, Some(0), "{}", run.stderr);
        assert_eq!(
            run.stdout
                .contains("J2.z–J3.z's 95 % interval contains zero"),
            lo <= 0.0 && hi >= 0.0,
            "{name}: {}",
            run.stdout
        );
        // A pair that is not in the identified structure: named, with the structure.
        let refused = dir.join(format!("refused_{tag}.toml"));
        let run = calibrate(false, "J2.z:J6.y", &refused);
        assert_eq!(run.code, Some(1), "{}", run.stderr);
        let structure = v["structure"].as_str().unwrap();
        assert!(
            run.stderr
                .contains("--couplings J2.z:J6.y: J6.y is not an eDoF")
                && run.stderr.contains(structure),
            "{}",
            run.stderr
        );
        assert!(!refused.exists());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `calibrate --couplings A:B[,A:B…]`: the pairs are split at the commas, each trimmed and read
/// as two eDoF labels (checked against the identified structure in that order), and every bad
/// list is refused before any work, naming `--couplings` and what is wrong.
#[test]
fn coupling_pairs_are_parsed_and_bad_ones_named() {
    let dir = scratch("calib-coupling-pairs");
    let tx200 = builtin("tx200").unwrap();
    let meas = dir.join("meas.csv");
    campaign(&tx200, 1000.0, &meas);
    let calibrate = |pairs: &str, out: &Path| {
        deflex(&[
            "--json",
            "calibrate",
            "--robot",
            "tx200",
            "--data",
            s(&meas),
            "--couplings",
            pairs,
            "--out",
            s(out),
        ])
    };
    let out = dir.join("calibrated.toml");
    let run = calibrate("J2.z:J3.z", &out);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let v: serde_json::Value = serde_json::from_str(&run.stdout).unwrap();
    assert_eq!(v["couplings"].as_array().unwrap().len(), 1, "{v}");
    assert_eq!(
        (&v["couplings"][0]["a"], &v["couplings"][0]["b"]),
        (&"J2.z".into(), &"J3.z".into())
    );
    // Two pairs: the first passes the structure check, the second (J1.x is not identified on
    // this campaign) is named as given, without the space after the comma.
    let refused = dir.join("refused.toml");
    let run = calibrate("J2.z:J3.z, base.x:J1.x", &refused);
    assert_eq!(run.code, Some(1), "{}", run.stderr);
    assert!(
        run.stderr.contains("error: --couplings base.x:J1.x: "),
        "{}",
        run.stderr
    );
    assert!(!refused.exists());
    let many = (1..=9)
        .map(|j| format!("J{j}.x:J{j}.y"))
        .collect::<Vec<_>>()
        .join(",");
    for (bad, says) in [
        ("J2.z", "pairs of eDoFs"),
        ("J2.z:J3.w", "J3.w"),
        ("J2.z:K3.z", "K3.z"),
        ("J2.z:J2.z", "two different eDoFs"),
        ("J2.z:J3.z,J3.z:J2.z", "each pair once"),
        ("", "pairs of eDoFs"),
    ] {
        let run = calibrate(bad, &refused);
        assert_eq!(run.code, Some(1), "{bad}: {}", run.stderr);
        assert!(
            run.stderr.starts_with("error: --couplings") && run.stderr.contains(says),
            "{bad}: {}",
            run.stderr
        );
        assert!(!refused.exists());
    }
    // More than 8 pairs.
    let run = calibrate(&many, &refused);
    assert_eq!(run.code, Some(1), "{}", run.stderr);
    assert!(
        run.stderr.starts_with("error: --couplings"),
        "{}",
        run.stderr
    );
    assert!(!refused.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

//! The stiffness calibration workflows ([`deflex_app::calibrate`]) under `deflex calibrate`,
//! `validate`, `plan` and Python: measurement rows read from an in-memory table, the choices'
//! names, the calibrated model named, saved and reported, the messages in each front end's
//! words, the validation's outputs and the plan's points and outputs.

use deflex_app::calibrate::plan::{self, PlanOptions, PointSet};
use deflex_app::calibrate::*;
use deflex_app::{ErrorKind, OptionNames};
use deflex_calibrate::measurements::{MeasurementRow, format_rows_for};
use deflex_calibrate::stiffness::synthetic::{SyntheticOptions, measure};
use deflex_model::Robot;
use std::path::{Path, PathBuf};

#[test]
fn a_bad_row_of_an_in_memory_table_is_named_by_its_index() {
    let robot = deflex_app::robot::builtin("tx200").unwrap();
    let text = "load_case,q1_rad,q2_rad,q3_rad,q4_rad,q5_rad,q6_rad,fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm,load_link,load_x_m,load_y_m,load_z_m,point,point_link,x_m,y_m,z_m,dx_m,dy_m,dz_m\n\
        a,0,0.5,1,0,0.5,0,0,0,-100,0,0,0,6,1,0,0,TCP,6,1,0,0,0,0,1e-4\n\
        a,0,0.5,1,0,0.5,0,0,0,-100,0,0,0,6,1,0,0,TCP,6,1,0,0,0,0,x\n";
    let source = MeasurementSource::Table {
        text: text.into(),
        origin: "DataFrame".into(),
    };
    let e = read_rows(&source, robot.joint_count(), true).unwrap_err();
    assert!(
        e.to_string().starts_with("DataFrame row 1: column `dz_m`"),
        "{e}"
    );
    let e = read_rows(&source, 5, true).unwrap_err();
    assert!(e.to_string().contains("the robot has 5 joints"), "{e}");
}

/// A fresh folder for one test.
fn folder(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("deflex-app-calib-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A SIMULATED campaign of `robot` (planned with the plan workflow, measured on the robot),
/// written to `dir/meas.csv` with its header; returns the file.
fn campaign(robot: &Robot, dir: &Path) -> PathBuf {
    let options = PlanOptions {
        max_force_n: 1400.0,
        load_cases: 16,
        full_family: false,
        ..PlanOptions::for_a_real_cell()
    };
    let planned = plan::plan(robot, &options, &dir.join("plan.csv")).unwrap();
    let rows = measure(robot, &planned.plan.rows, &SyntheticOptions::default()).unwrap();
    let path = dir.join("meas.csv");
    std::fs::write(
        &path,
        format_rows_for(robot, &rows, &["SIMULATED test campaign"]),
    )
    .unwrap();
    path
}

fn options(structure: StructureChoice, couplings: &str) -> CalibrateOptions {
    let couplings = couplings
        .split(',')
        .filter(|t| !t.is_empty())
        .map(|text| {
            let (a, b) = text.split_once(':').unwrap();
            CouplingRequest {
                text: text.to_string(),
                pair: (
                    couplings::parse_edof_label(a).unwrap(),
                    couplings::parse_edof_label(b).unwrap(),
                ),
            }
        })
        .collect();
    CalibrateOptions {
        structure,
        fit_shifts: false,
        criterion: CriterionChoice::Bic,
        folds: 5,
        min_cv_gain: 0.02,
        target_rms_m: None,
        min_bic_gain: 10.0,
        allow_base: true,
        check: DataCheck {
            fk_tolerance_m: 1e-3,
            ignore_fk_check: false,
            ignore_columns: Vec::new(),
        },
        couplings,
    }
}

/// The CLI's words: the file before a check's error, `--data FILE` before a fit's, its flags
/// in the advice.
const CLI: OptionNames = OptionNames::Cli;
/// Python's words: no context before an error (the call is in the traceback), its keywords in
/// the advice.
const PYTHON: OptionNames = OptionNames::Python;

#[test]
fn the_choices_are_parsed_by_the_names_both_front_ends_use() {
    for choice in [StructureChoice::Auto, StructureChoice::Fixed] {
        assert_eq!(choice.name().parse::<StructureChoice>(), Ok(choice));
    }
    for choice in [CriterionChoice::Bic, CriterionChoice::Cv] {
        assert_eq!(choice.name().parse::<CriterionChoice>(), Ok(choice));
    }
    let e = "aic".parse::<CriterionChoice>().unwrap_err();
    assert_eq!(e.to_string(), "expected \"bic\" or \"cv\", got \"aic\"");
    let e = "Auto".parse::<StructureChoice>().unwrap_err();
    assert_eq!(
        e.to_string(),
        "expected \"auto\" or \"fixed\", got \"Auto\""
    );
    assert_eq!("standard".parse(), Ok(PointsChoice::Standard));
    assert_eq!("none".parse(), Ok(PointsChoice::None));
    assert_eq!(
        "p.csv".parse(),
        Ok(PointsChoice::File(PathBuf::from("p.csv")))
    );
}

/// A fixed structure with a coupling: the model named after its data, structure and coupling;
/// the robot file and the report written; the text and JSON showing the couplings.
#[cfg(feature = "report")]
#[test]
fn a_calibration_with_a_coupling_is_named_saved_and_reported() {
    let dir = folder("coupling");
    let robot = deflex_app::robot::builtin("tx200").unwrap();
    let data = campaign(&robot, &dir);
    let source = MeasurementSource::File(data.clone());
    let cal = calibrate(
        &robot,
        &source,
        &options(StructureChoice::Fixed, "J2.z:J3.z"),
        CLI,
        &mut |_| {},
    )
    .unwrap();
    assert!(cal.simulated_data());
    assert_eq!(cal.model.couplings.len(), 1);
    assert_eq!(
        cal.model.name,
        format!(
            "{} — calibrated from {} ({}, coupling J2.z–J3.z)",
            robot.name,
            data.display(),
            cal.calibration.structure.label()
        )
    );
    assert!(cal.diagonal.couplings.is_empty());
    assert_eq!(cal.predicted.len(), cal.rows.len());
    assert_eq!(cal.residuals.len(), cal.rows.len());
    let out = dir.join("model.toml");
    let report = dir.join("report");
    save(&cal, &out, Some(&report)).unwrap();
    assert!(report.join("calibration.html").is_file());
    let saved = deflex_app::load::load_robot(out.to_str().unwrap()).unwrap();
    assert_eq!(saved.name, cal.model.name);
    assert_eq!(saved.couplings.len(), 1);

    let json = summary_json(&cal, None);
    assert!(json.get("output").is_none(), "{json}");
    assert_eq!(json["couplings"][0]["coupling"], "J2.z–J3.z");
    assert_eq!(json["geometry_check"]["disagreeing_rows"], 0);
    let json = summary_json(&cal, Some(&out));
    assert_eq!(json["output"], out.display().to_string());
    let text = report_text(&cal);
    assert!(text.starts_with("Identified model: "), "{text}");
    assert!(text.contains("Joint-compliance couplings"), "{text}");
    assert!(text.contains("\nfile check: "), "{text}");
    assert_eq!(
        written_text(&out, Some(&report)),
        format!(
            "\nwrote {}\nreport: {}\n",
            out.display(),
            report.join("calibration.html").display()
        )
    );
}

#[test]
fn a_coupling_outside_the_identified_structure_is_refused_naming_it() {
    let dir = folder("outside");
    let robot = deflex_app::robot::builtin("tx200-1edof").unwrap();
    let data = campaign(&robot, &dir);
    let e = calibrate(
        &robot,
        &MeasurementSource::File(data.clone()),
        &options(StructureChoice::Fixed, "J2.z:J6.y"),
        CLI,
        &mut |_| {},
    )
    .err()
    .unwrap();
    assert!(
        matches!(e, deflex_app::Error::CouplingNotInStructure { .. }),
        "{e:?}"
    );
    assert!(
        e.to_string()
            .starts_with("--couplings J2.z:J6.y: J6.y is not an eDoF of the identified structure `J1.z J2.z J3.z J4.z J5.z`"),
        "{e}"
    );
    assert_eq!(e.kind(), ErrorKind::Calibration);
}

/// Another robot's data is refused with the front end's advice, or used with a warning.
#[test]
fn another_robots_data_is_refused_in_the_front_ends_words() {
    let dir = folder("another");
    let tx200 = deflex_app::robot::builtin("tx200").unwrap();
    let ur10 = deflex_app::robot::builtin("ur10").unwrap();
    let data = campaign(&tx200, &dir);
    let source = MeasurementSource::File(data.clone());
    let mut fixed = options(StructureChoice::Fixed, "");
    let e = calibrate(&ur10, &source, &fixed, CLI, &mut |_| {})
        .err()
        .unwrap();
    assert!(
        e.to_string().contains(
            "Widen the tolerance with --fk-tolerance-mm, or use the file anyway with --ignore-fk-check."
        ),
        "{e}"
    );
    assert_eq!(e.kind(), ErrorKind::Calibration);
    let e = validate(&ur10, None, &source, &fixed.check, CLI)
        .err()
        .unwrap();
    assert!(e.to_string().contains("rows disagree"), "{e}");
    fixed.check.ignore_fk_check = true;
    let v = validate(&ur10, None, &source, &fixed.check, PYTHON).unwrap();
    assert_eq!(v.warnings.len(), 1);
    assert!(
        v.warnings[0].ends_with("(going on as asked)"),
        "{:?}",
        v.warnings
    );
    assert!(validation_text(&v).contains("\nwarning: "));
}

/// An error of the identification is named with the front end's context, or told alone.
#[test]
fn the_identification_error_is_named_as_the_front_end_asks() {
    let dir = folder("zero");
    let robot = deflex_app::robot::builtin("tx200").unwrap();
    let data = campaign(&robot, &dir);
    let rows: Vec<MeasurementRow> = read_rows(&MeasurementSource::File(data.clone()), 6, true)
        .unwrap()
        .rows
        .into_iter()
        .map(|mut row| {
            row.displacement_m = Some([0.0; 3]);
            row
        })
        .collect();
    let zero = dir.join("zero.csv");
    std::fs::write(&zero, format_rows_for(&robot, &rows, &[])).unwrap();
    let source = MeasurementSource::File(zero.clone());
    let fixed = options(StructureChoice::Fixed, "");
    let e = calibrate(&robot, &source, &fixed, CLI, &mut |_| {})
        .err()
        .unwrap();
    let prefix = format!(
        "--data {}: every measured displacement is exactly zero",
        zero.display()
    );
    assert!(e.to_string().starts_with(&prefix), "{e}");
    assert_eq!(e.kind(), ErrorKind::Calibration);
    let e = calibrate(&robot, &source, &fixed, PYTHON, &mut |_| {})
        .err()
        .unwrap();
    assert!(
        e.to_string()
            .starts_with("every measured displacement is exactly zero"),
        "{e}"
    );
}

#[cfg(feature = "report")]
#[test]
fn a_validation_lists_its_files_only_when_they_were_written() {
    let dir = folder("validate");
    let robot = deflex_app::robot::builtin("tx200").unwrap();
    let data = campaign(&robot, &dir);
    let check = options(StructureChoice::Fixed, "").check;
    let baseline = deflex_app::robot::builtin("tx200-1edof").unwrap();
    let v = validate(
        &robot,
        Some(&baseline),
        &MeasurementSource::File(data),
        &check,
        PYTHON,
    )
    .unwrap();
    assert!(validation_json(&v, None).get("files").is_none());
    let out = dir.join("val");
    let files = write_validation_report(&v, &out).unwrap();
    assert!(files.iter().any(|f| f.ends_with("validation.html")));
    let json = validation_json(&v, Some(&files));
    assert_eq!(json["files"].as_array().unwrap().len(), files.len());
    assert!(json["baseline"]["rms_m"].is_array(), "{json}");
    assert!(
        validation_text(&v).starts_with("Prediction errors (measured − predicted), "),
        "{}",
        validation_text(&v)
    );
    assert_eq!(
        validation_written_text(&files, &out),
        format!(
            "wrote {} files to {} (validation.html)\n",
            files.len(),
            out.display()
        )
    );
}

/// The plan's measured points: standard, none, or a file read by the application layer.
#[test]
fn a_plan_reads_its_points_file_and_says_what_it_wrote() {
    let dir = folder("plan");
    assert!(matches!(
        plan::read_point_set(&PointsChoice::Standard, 6).unwrap(),
        PointSet::Standard
    ));
    assert!(matches!(
        plan::read_point_set(&PointsChoice::None, 6).unwrap(),
        PointSet::Custom(list) if list.is_empty()
    ));
    let file = dir.join("points.csv");
    std::fs::write(
        &file,
        "name,link,x_m,y_m,z_m\nA1,2,0.3,0,0\nA2,3,0.1,0,0.05\n",
    )
    .unwrap();
    let PointSet::Custom(points) =
        plan::read_point_set(&PointsChoice::File(file.clone()), 6).unwrap()
    else {
        panic!("a file gives custom points");
    };
    assert_eq!(points.len(), 2);
    let e = plan::read_point_set(&PointsChoice::File(dir.join("none.csv")), 6).unwrap_err();
    assert!(matches!(e, deflex_app::Error::Points(_)), "{e:?}");
    assert_eq!(e.kind(), ErrorKind::Data);

    let mut robot = deflex_app::robot::builtin("tx200").unwrap();
    let options = PlanOptions {
        configurations: 100,
        points: PointSet::Custom(points),
        ..PlanOptions::for_a_real_cell()
    };
    let out = dir.join("plan.csv");
    let planned = plan::plan(&robot, &options, &out).unwrap();
    let written = std::fs::read_to_string(&out).unwrap();
    assert_eq!(
        written.lines().filter(|l| !l.starts_with('#')).count(),
        planned.plan.rows.len() + 1
    );
    let json = plan::plan_json(&planned);
    assert_eq!(json["rows"], planned.plan.rows.len());
    assert_eq!(json["output"], out.display().to_string());
    let text = plan::plan_text(&planned, 15.0);
    assert!(
        text.contains("Expected standard errors with 15.0 µm tracker noise:"),
        "{text}"
    );
    assert!(
        text.ends_with(&format!("wrote {}\n", out.display())),
        "{text}"
    );

    assert_eq!(plan::default_masses_kg(&robot, 1400.0).unwrap().len(), 1);
    robot.gravity = nalgebra::Vector3::zeros();
    let e = plan::default_masses_kg(&robot, 1400.0).unwrap_err();
    assert!(e.to_string().contains("has no gravity"), "{e}");
}

//! The compensation workflow ([`deflex_app::compensate`]): a path given as an array,
//! compensated and written as a program; the output folder of `deflex compensate` with its
//! programs read back, or refused; the set-up's messages in each front end's words.

use deflex_app::Error;
use deflex_app::compensate::*;
use deflex_app::option_names::OptionNames;
use deflex_cam::program::{Format, ProgramSettings};
use std::path::PathBuf;

fn options() -> Options {
    Options {
        tolerance_m: 1e-6,
        max_iterations: 30,
        log_forces: LogForces::Fixed,
        ..Options::default()
    }
}

fn tx200() -> RobotChoice {
    RobotChoice {
        model: deflex_app::robot::builtin("tx200").unwrap(),
        spec: None,
    }
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "deflex-app-compensate-{name}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn run_of(
    robot: RobotChoice,
    path: &PathSpec,
    wrench: WrenchSpec,
    options: &Options,
) -> deflex_app::Result<CompensationRun> {
    let s = setup(robot, path, wrench, options, OptionNames::Python)?;
    compensate(s, &mut |_| {})
}

#[test]
fn a_constant_wrench_on_an_array_path_is_compensated_to_the_tolerance() {
    // 20 mm along x in the part frame, 1 mm steps.
    let values: Vec<f64> = (0..=20).flat_map(|i| [i as f64 * 1e-3, 0.0, 0.0]).collect();
    let spec = PathSpec::Array {
        values,
        cols: 3,
        frame: Frame::Part,
        feed_m_s: Some(0.02),
    };
    let wrench = WrenchSpec::Array(vec![0.0, 0.0, 1000.0, 0.0, 0.0, 0.0]);
    let run = run_of(tx200(), &spec, wrench, &options()).unwrap();
    assert!(run.result.converged);
    assert_eq!(run.result.points.len(), 21);
    assert!(run.result.final_max_error_m < 1e-6);
    let settings = ProgramSettings::default();
    let plan = ProgramPlan::new(&run.setup, &run.result, description(&run), &settings).unwrap();
    let files = plan.export_checked(Format::UrScript, &settings).unwrap();
    assert!(files[0].contents.contains("movel"));
    let e = run_of(tx200(), &spec, WrenchSpec::Array(vec![0.0; 12]), &options())
        .err()
        .unwrap();
    assert!(
        e.to_string().contains("2 wrenches for the 21 points"),
        "{e}"
    );
}

/// The CLI's folder: the table, the programs read back within 1 µm, the summaries; the text and
/// `summary.json` say the same.
#[test]
fn the_output_folder_holds_the_table_the_programs_read_back_and_the_summaries() {
    let dir = scratch("folder");
    let out = dir.join("out");
    let options = Options {
        length_mm: Some(5.0),
        formats: ProgramFormat::formats(&[
            ProgramFormat::Krl,
            ProgramFormat::Gcode,
            ProgramFormat::Krl,
        ]),
        ..Options::default()
    };
    let robot = RobotChoice::load("--robot", "tx200").unwrap();
    let s = setup(
        robot,
        &PathSpec::named("cone"),
        WrenchSpec::Process,
        &options,
        OptionNames::Cli,
    )
    .unwrap();
    assert!(
        s.placement_source
            .contains("the tx200 cell (change with --part-xyz-mm, --seed-deg)")
    );
    let run = compensate(s, &mut |_| {}).unwrap();
    let table = table_csv(&run);
    assert!(table.starts_with("# SIMULATED deflex offline compensation"));
    let summary = write_output_folder(run, &out).unwrap();
    assert!(summary.refusal.is_none());
    assert_eq!(
        std::fs::read_to_string(out.join("compensated_path.csv")).unwrap(),
        table
    );
    let programs = summary.json["programs"].as_array().unwrap();
    assert_eq!(programs.len(), 2, "each format once");
    for p in programs {
        assert!(p["readback_max_position_error_m"].as_f64().unwrap() <= 1e-6);
    }
    for file in summary.json["files"].as_array().unwrap() {
        assert!(out.join(file.as_str().unwrap()).is_file(), "{file}");
    }
    assert_eq!(summary.json["compensation"]["converged"], true);
    assert!(summary.text.contains("krl: 2 file(s)"), "{}", summary.text);
    assert_eq!(
        std::fs::read_to_string(out.join("summary.txt")).unwrap(),
        summary.text
    );
    assert_eq!(
        std::fs::read_to_string(out.join("summary.json")).unwrap(),
        serde_json::to_string_pretty(&summary.json).unwrap()
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// A run that did not converge writes its table and summaries, no program, and is refused.
#[test]
fn a_run_that_did_not_converge_writes_no_program_and_is_refused() {
    let dir = scratch("refused");
    let out = dir.join("out");
    let options = Options {
        length_mm: Some(5.0),
        max_iterations: 1,
        formats: vec![Format::Krl],
        ..Options::default()
    };
    let run = run_of(
        RobotChoice::load("--robot", "tx200").unwrap(),
        &PathSpec::named("cone"),
        WrenchSpec::Process,
        &options,
    )
    .unwrap();
    assert!(!run.result.converged);
    let e = refusal(&run).unwrap_err();
    assert!(
        matches!(e, Error::NotConverged { iterations: 1, .. }),
        "{e}"
    );
    let summary = write_output_folder(run, &out).unwrap();
    let e = summary.refusal.unwrap();
    assert!(
        e.to_string().contains("did not converge in 1 iterations"),
        "{e}"
    );
    assert!(out.join("compensated_path.csv").is_file());
    assert!(out.join("summary.json").is_file());
    assert!(!out.join("programs").exists());
    assert!(summary.text.contains("NOT converged"), "{}", summary.text);
    std::fs::remove_dir_all(dir).unwrap();
}

/// The set-up's checks name the option as the front end spells it.
#[test]
fn set_up_refusals_name_the_options_of_the_front_end() {
    let seed = Options {
        seed_q: Some(vec![0.0, 1.0, 2.0]),
        ..Options::default()
    };
    let name = tx200().model.name;
    for (front, option) in [
        (OptionNames::Cli, "--seed-deg"),
        (OptionNames::Python, "seed_q"),
    ] {
        let e = setup(
            tx200(),
            &PathSpec::named("cone"),
            WrenchSpec::Process,
            &seed,
            front,
        )
        .err()
        .unwrap();
        assert_eq!(
            e.to_string(),
            format!("{option}: robot \"{name}\" has 6 joints, 3 values given")
        );
        assert_eq!(e.kind(), deflex_app::ErrorKind::Input);
    }
    // A seed that tilts the tool off the path's axis, a part beyond the arm's reach.
    let tilted = Options {
        seed_q: Some(
            [-1.0, 34.66, -90.0, 0.0, -45.0, 12.0]
                .map(f64::to_radians)
                .to_vec(),
        ),
        part_xyz_mm: Some([-20.0, 0.0, 5.0]),
        ..Options::default()
    };
    let ur10e = || RobotChoice::load("--robot", "ur10e").unwrap();
    let e = setup(
        ur10e(),
        &PathSpec::named("cone"),
        WrenchSpec::Process,
        &tilted,
        OptionNames::Cli,
    )
    .err()
    .unwrap();
    assert!(matches!(e, Error::ToolAxis { .. }), "{e}");
    assert!(e.to_string().contains("Give --seed-deg"), "{e}");
    let far = Options {
        part_xyz_mm: Some([5000.0, 0.0, 0.0]),
        ..Options::default()
    };
    let e = setup(
        tx200(),
        &PathSpec::named("cone"),
        WrenchSpec::Process,
        &far,
        OptionNames::Python,
    )
    .err()
    .unwrap();
    assert!(e.to_string().contains("beyond the arm's reach"), "{e}");
    assert!(
        e.to_string().contains("move the part with part_xyz_m"),
        "{e}"
    );
    // A G-code file that does not exist names the path as given.
    let e = setup(
        tx200(),
        &PathSpec::named("/nonexistent/part.gcode"),
        WrenchSpec::Process,
        &Options::default(),
        OptionNames::Cli,
    )
    .err()
    .unwrap();
    assert!(
        e.to_string()
            .starts_with("--path /nonexistent/part.gcode: "),
        "{e}"
    );
    assert_eq!(e.kind(), deflex_app::ErrorKind::Simulation);
}

/// The option types parse what both front ends write.
#[test]
fn the_choices_parse_the_front_ends_words() {
    assert!(matches!(
        WrenchSpec::parse("process"),
        Some(WrenchSpec::Process)
    ));
    assert!(
        matches!(WrenchSpec::parse("log:a.csv"), Some(WrenchSpec::Log(p)) if p == std::path::Path::new("a.csv"))
    );
    assert!(WrenchSpec::parse("sensor").is_none());
    assert!(matches!(PathSpec::named("pyramid"), PathSpec::Builtin(_)));
    assert!(matches!(PathSpec::named("part.gcode"), PathSpec::Gcode(_)));
    assert_eq!("world".parse::<Frame>().unwrap(), Frame::World);
    assert!(
        "tool"
            .parse::<Frame>()
            .unwrap_err()
            .to_string()
            .starts_with("frame: ")
    );
    assert_eq!(format("urscript").unwrap(), Format::UrScript);
    assert_eq!(format("fanuc").unwrap(), Format::Fanuc);
    assert_eq!(ProgramFormat::Fanuc.format(), Some(Format::Fanuc));
    assert_eq!(format("inform").unwrap(), Format::Inform);
    assert_eq!(ProgramFormat::Inform.format(), Some(Format::Inform));
    assert!(is_part_file("DEFLEX_PATH_P01.JBI") && !is_part_file("DEFLEX_PATH.JBI"));
    assert!(
        format("yaskawa")
            .unwrap_err()
            .to_string()
            .contains("unknown format \"yaskawa\"")
    );
    assert!(ProgramFormat::formats(&[ProgramFormat::Krl, ProgramFormat::None]).is_empty());
    assert!(is_part_file("deflex_path_p01.src") && is_part_file("deflex_path/part2.pgx"));
    assert!(is_part_file("DEFLEX_PATH_P01.ls") && !is_part_file("DEFLEX_PATH.ls"));
    assert!(!is_part_file("deflex_path.src"));
}

//! The elasto-geometric workflows ([`deflex_app::calibrate_geometry`]) that the CLI and Python
//! both call: the choices parsed with each front end's option names, the import, the refusals
//! (too few readings, another robot's readings, which set-up or target to register), and the
//! robot, terms and report written as one unit — on the vendored real UR10 subset.

use deflex_app::calibrate::MeasurementSource;
use deflex_app::calibrate_geometry::*;
use deflex_app::{Error, ErrorKind};
use deflex_calibrate::geometry::data::{format_absolute, parse_absolute};
use deflex_calibrate::geometry::fit::{HeldOutProtocol, Step};
use deflex_calibrate::geometry::solve::Loss;
use std::path::{Path, PathBuf};

fn series(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../deflex-calibrate/tests/data/ur10-tracker")
        .join(name)
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("deflex-app-egcal-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn import(name: &str, setup: &str, every: usize) -> TrackerImport {
    let request = ImportRequest {
        setup: setup.into(),
        target: "tmac".into(),
        tracker_sigma: false,
        every,
        names: OptionNames::Cli,
    };
    import_ur10_tracker(&series(name), &request).unwrap()
}

fn table(text: String) -> MeasurementSource {
    MeasurementSource::Table {
        text,
        origin: "table".into(),
    }
}

fn options(steps: &[Step]) -> GeometryOptions {
    GeometryOptions {
        steps: Some(steps.to_vec()),
        loss: Loss::HUBER_DEFAULT,
        folds: 0,
        bootstrap: 0,
        test_fraction: 0.0,
        seed: 1,
        elastic: Vec::new(),
        orientations: None,
        cv_by: None,
        protocol: HeldOutProtocol::default(),
        ignored_columns: Vec::new(),
        allow_large_changes: false,
        names: OptionNames::Cli,
    }
}

/// The registration and geometry steps of `calibrate_geometry` on the UR10 with `a`.
fn registration_and_geometry(a: &TrackerImport) -> GeometryCalibration {
    calibrate_geometry(
        &ur10(),
        &[table(a.text.clone())],
        &[],
        &[],
        &options(&[Step::Registration, Step::Geometry]),
    )
    .unwrap()
}

fn ur10() -> deflex_model::Robot {
    deflex_app::load::load_robot("ur10").unwrap()
}

#[test]
fn steps_and_losses_are_parsed_with_the_cli_messages() {
    let steps = parse_steps(
        &["registration".into(), "harmonics:2".into()],
        OptionNames::Python,
    )
    .unwrap();
    assert_eq!(steps, vec![Step::Registration, Step::Harmonics(2)]);
    let e = parse_steps(&["harmonics:9".into()], OptionNames::Python).unwrap_err();
    assert!(e.to_string().starts_with("steps: unknown step"), "{e}");
    assert!(
        matches!(parse_loss("cauchy:2", OptionNames::Python).unwrap(), Loss::Cauchy(k) if k == 2.0)
    );
    let e = parse_loss("l1", OptionNames::Python).unwrap_err();
    assert_eq!(
        e.to_string(),
        "loss: expected huber, cauchy or none, got \"l1\""
    );
    // The command line names its flags, and both are input errors.
    let e = parse_steps(&["wobble".into()], OptionNames::Cli).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("--steps: unknown step \"wobble\""),
        "{e}"
    );
    assert_eq!(e.kind(), ErrorKind::Input);
    let e = parse_loss("l1", OptionNames::Cli).unwrap_err();
    assert_eq!(
        e.to_string(),
        "--loss: expected huber, cauchy or none, got \"l1\""
    );
}

#[test]
fn cv_by_and_option_names_are_one_table_for_both_front_ends() {
    for (by, name) in CvBy::NAMES {
        assert_eq!(name.parse::<CvBy>().unwrap(), by);
        assert_eq!(by.name(), name);
    }
    let e = "sessions".parse::<CvBy>().unwrap_err();
    assert_eq!(
        e.to_string(),
        "expected \"session\", \"setup\" or \"series\", got \"sessions\""
    );
    assert_eq!(OptionNames::Cli.name("sigma_rad"), "--sigma-rad");
    assert_eq!(OptionNames::Python.name("sigma_rad"), "sigma_rad");
    assert_eq!(OptionNames::Cli.give("setup"), "--setup");
    assert_eq!(OptionNames::Python.give("setup"), "setup=");
    assert_eq!(OptionNames::Cli.give_text("target", "p2"), "--target p2");
    assert_eq!(
        OptionNames::Python.give_text("target", "p2"),
        "target=\"p2\""
    );
}

#[test]
fn import_refuses_what_it_would_not_read_back_and_names_the_option() {
    let a = import("Series_A", "A", 10);
    let rows = parse_absolute(&a.text, "a.csv", 6).unwrap();
    assert_eq!(rows.len(), a.rows_written);
    assert_eq!(a.summary.rows, 298);
    assert!(rows.iter().all(|r| r.setup == "A" && r.target == "tmac"));
    let json = a.summary_json(None);
    assert_eq!(json["rows_written"], a.rows_written);
    assert!(json.get("out").is_none());
    assert_eq!(a.summary_json(Some(Path::new("a.csv")))["out"], "a.csv");
    assert!(a.saved_text(Path::new("a.csv")).contains(&format!(
        "298 readings, {} written to a.csv (set-up A, target tmac)",
        a.rows_written
    )));
    for (names, every, flag) in [
        (OptionNames::Cli, 0, "--every: expected 1…1000000, got 0"),
        (OptionNames::Python, 0, "every: expected 1…1000000, got 0"),
    ] {
        let request = ImportRequest {
            setup: "A".into(),
            target: "tmac".into(),
            tracker_sigma: false,
            every,
            names,
        };
        let e = import_ur10_tracker(&series("Series_A"), &request)
            .err()
            .unwrap();
        assert_eq!(e.to_string(), flag);
    }
    for (names, option) in [
        (OptionNames::Cli, "--setup \" A\""),
        (OptionNames::Python, "setup \" A\""),
    ] {
        let request = ImportRequest {
            setup: " A".into(),
            target: "tmac".into(),
            tracker_sigma: false,
            every: 1,
            names,
        };
        let e = import_ur10_tracker(&series("Series_A"), &request)
            .err()
            .unwrap();
        assert!(
            e.to_string().starts_with(option)
                && e.to_string()
                    .contains("import refuses it (labels are not rewritten)"),
            "{e}"
        );
        assert_eq!(e.kind(), ErrorKind::Input);
    }
    let empty = scratch("empty-series");
    let request = ImportRequest {
        setup: "A".into(),
        target: "tmac".into(),
        tracker_sigma: false,
        every: 1,
        names: OptionNames::Cli,
    };
    let e = import_ur10_tracker(&empty, &request).err().unwrap();
    assert_eq!(
        e.to_string(),
        format!(
            "{}: expected one measurements_*.csv, found 0",
            empty.display()
        )
    );
    let e = import_ur10_tracker(&empty.join("nowhere"), &request)
        .err()
        .unwrap();
    assert_eq!(e.kind(), ErrorKind::Data);
    let _ = std::fs::remove_dir_all(&empty);
}

#[cfg(feature = "report")]
#[test]
fn a_calibration_is_saved_whole_with_its_terms_and_report_or_not_at_all() {
    let a = import("Series_A", "A", 5);
    let cal = registration_and_geometry(&a);
    let dir = scratch("save");
    let out = dir.join("ur10-cal.toml");
    // A report folder that cannot be made: neither the robot nor its terms are written.
    let blocked = dir.join("blocked");
    std::fs::write(&blocked, "a file").unwrap();
    let e = save(&cal, &out, Some(&blocked.join("report")))
        .err()
        .unwrap();
    assert_eq!(e.kind(), ErrorKind::Io, "{e}");
    assert!(!out.exists() && !terms_path(&out).exists());
    let report = dir.join("report");
    let saved = save(&cal, &out, Some(&report)).unwrap();
    assert_eq!(saved.terms, dir.join("ur10-cal.terms.json"));
    assert!(out.is_file() && saved.terms.is_file());
    for file in ["report.txt", "report.json", "iterations.csv", "index.html"] {
        assert!(report.join(file).is_file(), "{file}");
        assert!(saved.report_files.contains(&report.join(file)), "{file}");
    }
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(report.join("report.json")).unwrap())
            .unwrap();
    assert_eq!(
        written,
        serde_json::from_str::<serde_json::Value>(&report_json(&cal)).unwrap()
    );
    let json = saved_json(&cal, &saved);
    assert_eq!(json["out"], out.display().to_string());
    assert_eq!(json["terms"], saved.terms.display().to_string());
    assert_eq!(
        json["report_files"].as_array().unwrap().len(),
        saved.report_files.len()
    );
    let text = saved_text(&cal, &saved);
    assert!(text.starts_with(&report_text(&cal)));
    assert!(text.ends_with(&format!(
        "report: {}\n",
        report.join("index.html").display()
    )));
    // The saved robot with its terms predicts its own readings as the fit did.
    let model = load_calibrated(out.to_str().unwrap()).unwrap();
    assert!(model.terms.is_some());
    let p = predict(&model, &table(a.text.clone()), false, &[]).unwrap();
    let fit_rms = cal.result.steps.last().unwrap().fit.rms;
    assert!((p.json["rms_m"].as_f64().unwrap() - fit_rms).abs() < 1e-9);
    assert_eq!(p.csv.lines().count(), a.rows_written + 1);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn too_few_readings_and_another_robots_readings_are_refused() {
    let a = import("Series_A", "A", 10);
    let rows = parse_absolute(&a.text, "a.csv", 6).unwrap();
    // Two distinct readings repeated: 6 equations for the 6 parameters of the registration.
    let repeated: Vec<_> = (0..20).map(|k| rows[k % 2].clone()).collect();
    let e = calibrate_geometry(
        &ur10(),
        &[table(format_absolute(&repeated, &[]))],
        &[],
        &[],
        &options(&[Step::Registration]),
    )
    .err()
    .unwrap();
    assert!(
        e.to_string()
            .starts_with("table: 2 distinct reading(s) of 20 give 6 equations for 6 parameters"),
        "{e}"
    );
    assert_eq!(e.kind(), ErrorKind::Calibration);
    // Each reading's position given to another configuration: no registration fits them.
    let mut shuffled = rows.clone();
    for (k, row) in shuffled.iter_mut().enumerate() {
        row.position_m = rows[(k * 7 + 3) % rows.len()].position_m;
    }
    for (names, option) in [
        (OptionNames::Cli, "--robot"),
        (OptionNames::Python, "robot="),
    ] {
        let mut opts = options(&[Step::Registration]);
        opts.names = names;
        let e = calibrate_geometry(
            &ur10(),
            &[table(format_absolute(&shuffled, &[]))],
            &[],
            &[],
            &opts,
        )
        .err()
        .unwrap();
        assert!(matches!(e, Error::ImplausibleFit { .. }), "{e}");
        assert!(
            e.to_string()
                .contains("these are not this robot's readings")
                && e.to_string()
                    .contains(&format!("give it with {option}); nothing written")),
            "{e}"
        );
    }
}

#[test]
fn register_names_the_set_up_and_target_to_choose_in_each_front_ends_words() {
    let a = import("Series_A", "A", 10);
    let b = import("Series_B", "B", 10);
    let cal = registration_and_geometry(&a);
    let mut rows = parse_absolute(&a.text, "a.csv", 6).unwrap();
    rows.truncate(15);
    rows.extend(
        parse_absolute(&b.text, "b.csv", 6)
            .unwrap()
            .into_iter()
            .take(15),
    );
    let both = table(format_absolute(&rows, &[]));
    let request = |names| RegisterRequest {
        setup: None,
        target: None,
        orientations: None,
        recalibrate_above_m: None,
        ignored_columns: Vec::new(),
        allow_large_changes: false,
        names,
    };
    let model = || calibrated_model_of(&cal).unwrap();
    let e = register(model(), &both, &request(OptionNames::Cli))
        .err()
        .unwrap();
    assert_eq!(
        e.to_string(),
        "table: the data names set-ups A, B: choose one with --setup"
    );
    let e = register(model(), &both, &request(OptionNames::Python))
        .err()
        .unwrap();
    assert_eq!(
        e.to_string(),
        "setup: table: the data names set-ups A, B: choose one with setup="
    );
    assert_eq!(e.kind(), ErrorKind::Input);
    let mut probe = rows[15..].to_vec();
    for row in &mut probe {
        row.target = "probe2".into();
    }
    let probe = table(format_absolute(&probe, &[]));
    let e = register(model(), &probe, &request(OptionNames::Cli))
        .err()
        .unwrap();
    assert!(
        e.to_string().ends_with(
            "target `probe2` is not in the robot file: register it with --target probe2"
        ),
        "{e}"
    );
    let e = register(model(), &probe, &request(OptionNames::Python))
        .err()
        .unwrap();
    assert!(
        e.to_string().starts_with("target: table:")
            && e.to_string()
                .ends_with("register it with target=\"probe2\""),
        "{e}"
    );
    let mut asked = request(OptionNames::Cli);
    asked.setup = Some("C".into());
    let e = register(model(), &both, &asked).err().unwrap();
    assert_eq!(e.to_string(), "table: no reading of set-up `C`");
    // Set-up B registered from its readings: the terms carried over unchanged.
    let mut asked = request(OptionNames::Cli);
    asked.setup = Some("B".into());
    let registered = register(model(), &both, &asked).unwrap();
    assert_eq!(registered.registration.readings, 15);
    let dir = scratch("register");
    let out = dir.join("today.toml");
    save_registration(&registered, &out).unwrap();
    assert_eq!(
        std::fs::read_to_string(terms_path(&out)).unwrap(),
        cal.terms.to_json().unwrap()
    );
    assert!(saved_registration_text(&registered, &out).starts_with("Registered set-up `B`"));
    assert_eq!(
        registration_json(&registered, Some(&out))["out"],
        out.display().to_string()
    );
    assert!(registration_json(&registered, None)["out"].is_null());
    let _ = std::fs::remove_dir_all(&dir);
    // Set-up A, calibrated, re-registered from readings 3 m away: beyond the UR10's working
    // volume (its size, 1.54 m), refused in each front end's words unless allowed.
    let mut moved = rows[..15].to_vec();
    for row in &mut moved {
        row.position_m[0] += 3.0;
    }
    let moved = table(format_absolute(&moved, &[]));
    for (names, allow) in [
        (OptionNames::Cli, "--allow-large-changes"),
        (OptionNames::Python, "allow_large_changes=True"),
    ] {
        let e = register(model(), &moved, &request(names)).err().unwrap();
        let text = e.to_string();
        assert!(matches!(e, Error::LargeRegistration { .. }), "{text}");
        assert!(
            text.starts_with("table: the registration puts setup[A] moved +3000 mm (bound ±154")
                && text.ends_with(&format!("allowed with {allow}; nothing written")),
            "{text}"
        );
    }
    let mut allowed = request(OptionNames::Cli);
    allowed.allow_large_changes = true;
    assert!(register(model(), &moved, &allowed).is_ok());
    // Its own readings move it by less than a millimetre.
    let own = table(format_absolute(&rows[..15], &[]));
    assert!(register(model(), &own, &request(OptionNames::Cli)).is_ok());
}

/// A TX200 "calibrated" from a UR10's real tracker readings fits them (the fit reshapes one arm
/// into the other), so the residual guard cannot see it; the bounds on the geometric changes
/// refuse it, naming the parameters, in each front end's words. The UR10 from its own readings
/// stays within them, and the override lets the reshaped fit through.
#[test]
fn another_robots_geometry_is_refused_naming_the_parameters_unless_allowed() {
    let a = import("Series_A", "A", 4);
    let steps = [Step::Registration, Step::Geometry, Step::Compliance];
    let own = calibrate_geometry(
        &ur10(),
        &[table(a.text.clone())],
        &[],
        &[],
        &options(&steps),
    );
    assert!(
        own.is_ok(),
        "the UR10 from its own readings: {:?}",
        own.err()
    );
    let tx200 = deflex_app::load::load_robot("tx200").unwrap();
    for (names, robot, allow) in [
        (OptionNames::Cli, "--robot", "--allow-large-changes"),
        (OptionNames::Python, "robot=", "allow_large_changes=True"),
    ] {
        let mut opts = options(&steps);
        opts.names = names;
        let e = calibrate_geometry(&tx200, &[table(a.text.clone())], &[], &[], &opts)
            .err()
            .expect("a TX200 from UR10 readings is refused");
        let text = e.to_string();
        assert!(matches!(e, Error::LargeChanges { .. }), "{text}");
        assert_eq!(e.kind(), ErrorKind::Calibration);
        assert!(
            text.contains("these readings look like another robot or another target")
                && text.contains(&format!("check {robot} and the targets"))
                && text.contains(&format!("allowed with {allow}; nothing written")),
            "{text}"
        );
        // The arm's lengths are named with their change and bound (mm).
        assert!(text.contains("(bound ±"), "{text}");
        assert!(
            ["J2.", "J3.", "J4."].iter().any(|j| text.contains(j)),
            "{text}"
        );
    }
    let mut opts = options(&steps);
    opts.allow_large_changes = true;
    // Allowed: written, with the warning first in the text and in the JSON.
    let cal = calibrate_geometry(&tx200, &[table(a.text.clone())], &[], &[], &opts).unwrap();
    let text = report_text(&cal);
    assert!(
        text.starts_with("WARNING: the fit reshapes robot \"Staubli TX200")
            && text
                .lines()
                .next()
                .unwrap()
                .ends_with("written because --allow-large-changes was given"),
        "{text}"
    );
    let json: serde_json::Value = serde_json::from_str(&report_json(&cal)).unwrap();
    assert!(
        json["large_changes_allowed"]
            .as_str()
            .unwrap()
            .starts_with("WARNING")
    );
    // Within the bounds: nothing to warn of.
    let own = own.unwrap();
    assert!(own.large_changes.is_none());
    assert!(serde_json::from_str::<serde_json::Value>(&report_json(&own)).unwrap()["large_changes_allowed"].is_null());
}

/// Without named steps a calibration fits the base steps and, when the data is grouped so that
/// the held-out vote can judge them, the joint maps; the report's first line says which and
/// why. Named steps are fitted as named.
#[test]
fn the_default_steps_try_the_joint_maps_when_groups_can_vote_on_them() {
    let a = import("Series_A", "A", 4);
    let b = import("Series_B", "B", 4);
    let data = [table(a.text.clone()), table(b.text.clone())];
    let mut grouped = options(&[]);
    grouped.steps = None;
    grouped.cv_by = Some(CvBy::Setup);
    let cal = calibrate_geometry(&ur10(), &data, &[], &[], &grouped).unwrap();
    let tried: Vec<Step> = cal.result.steps.iter().map(|s| s.step).collect();
    assert_eq!(
        tried,
        [
            Step::Registration,
            Step::Geometry,
            Step::Compliance,
            Step::JointMaps
        ]
    );
    let text = report_text(&cal);
    assert!(
        text.starts_with(
            "default steps: registration, geometry, compliance, and joint-maps (the vote by setup \
             left out in turn judges them)\n"
        ),
        "{text}"
    );
    let json: serde_json::Value = serde_json::from_str(&report_json(&cal)).unwrap();
    assert!(
        json["default_steps"]
            .as_str()
            .unwrap()
            .contains("joint-maps")
    );
    // The vote's verdict is in the iteration table, as for a named opt-in step.
    let maps = cal.result.steps.last().unwrap();
    assert!(
        maps.acceptance.is_some(),
        "the maps were judged by the vote"
    );
    // No groups: the maps are not tried, and the report says how to let them be.
    let mut plain = options(&[]);
    plain.steps = None;
    let cal = calibrate_geometry(&ur10(), &data[..1], &[], &[], &plain).unwrap();
    assert_eq!(cal.result.steps.len(), 3);
    let text = report_text(&cal);
    assert!(
        text.starts_with(
            "default steps: registration, geometry, compliance; joint-maps not tried (no groups \
             to vote with: --cv-by session, setup or series"
        ),
        "{text}"
    );
    // Two series with their sessions: the line says which grouping would let the maps vote,
    // in each front end's words.
    for (names, give) in [
        (OptionNames::Cli, "--cv-by session"),
        (OptionNames::Python, "cv_by=\"session\""),
    ] {
        let mut plain = options(&[]);
        plain.steps = None;
        plain.names = names;
        let cal = calibrate_geometry(&ur10(), &data, &[], &[], &plain).unwrap();
        let first = report_text(&cal).lines().next().unwrap().to_string();
        assert!(
            first.contains("; the data has") && first.ends_with(&format!("{give} lets them vote)")),
            "{first}"
        );
    }
    // Named steps: no line about defaults, `null` in the JSON.
    let cal = calibrate_geometry(&ur10(), &data[..1], &[], &[], &options(&BASE_STEPS)).unwrap();
    assert!(report_text(&cal).starts_with("Elasto-geometric calibration"));
    let json: serde_json::Value = serde_json::from_str(&report_json(&cal)).unwrap();
    assert!(json["default_steps"].is_null());
}

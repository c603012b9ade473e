//! The twin workflows ([`deflex_app::twin`]): forming runs and their folder, the choices and
//! their conflicts, a campaign, the cell's robot file, a sensitivity sweep, the plot of a log.

use deflex_app::twin::*;

#[test]
fn a_short_open_loop_run_logs_si_columns_of_equal_length() {
    let run = form(&FormOptions {
        seed: 1,
        length_mm: Some(50.0),
        ..FormOptions::default()
    })
    .unwrap();
    let columns = log_columns(&run);
    let rows = run.run.log.rows.len();
    assert!(rows > 10);
    assert!(columns.iter().all(|(_, c)| c.len() == rows));
    let err = &columns.iter().find(|(n, _)| *n == "err_norm_m").unwrap().1;
    // The open loop deviates by a fraction of a millimetre to millimetres: metres, not mm.
    assert!(err.iter().cloned().fold(0.0, f64::max) < 0.01);
    let e = form(&FormOptions {
        fixture_stiffness_n_m: Some(1e7),
        ..FormOptions::default()
    })
    .err()
    .unwrap();
    assert!(e.to_string().contains("plunge"), "{e}");
}

fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("deflex-app-twin-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn the_choices_parse_their_names_and_conflicts_are_refused() {
    use std::str::FromStr;
    assert_eq!(FormCorrection::from_str("on").unwrap(), FormCorrection::On);
    assert_eq!(FormCorrection::Off.name(), "off");
    assert_eq!(
        FormCorrection::from_str("yes").unwrap_err().to_string(),
        "correction: expected \"on\" or \"off\", got \"yes\""
    );
    let Ok(choice) = PathChoice::from_str("cone-contour");
    assert_eq!(choice, PathChoice::ConeContour);
    let Ok(choice) = PathChoice::from_str("part.gcode");
    assert_eq!(choice, PathChoice::Gcode("part.gcode".into()));
    use deflex_app::OptionNames::{Cli, Python};
    assert!(matches!(
        check_correction(FormCorrection::Off, true, Python).unwrap_err(),
        deflex_app::Error::FormConflict {
            conflict: FormConflict::ModelWithoutCorrection,
            ..
        }
    ));
    assert!(check_correction(FormCorrection::On, true, Python).is_ok());
    let e = tool_path(
        &PathChoice::Gcode("part.gcode".into()),
        Some(5.0),
        None,
        Cli,
    )
    .unwrap_err();
    assert!(
        matches!(
            e,
            deflex_app::Error::FormConflict {
                conflict: FormConflict::FeedWithGcode,
                ..
            }
        ),
        "{e}"
    );
    // The correction on needs its model, named by the option that gives it.
    let e = form(&FormOptions {
        correction: FormCorrection::On,
        ..FormOptions::default()
    })
    .err()
    .unwrap();
    assert!(e.to_string().contains("--model MODEL.toml"), "{e}");
    let missing = scratch("no-model").join("model.toml");
    let e = form(&FormOptions {
        correction: FormCorrection::On,
        model: Some(form::CorrectionModel::File(missing.clone())),
        ..FormOptions::default()
    })
    .err()
    .unwrap();
    assert!(
        e.to_string()
            .starts_with(&format!("--model {}: ", missing.display())),
        "{e}"
    );
}

#[cfg(feature = "report")]
#[test]
fn a_run_folder_holds_the_runs_files_the_attached_ones_and_its_plot_page() {
    let mut setup = FormingSetup::prepare(&FormOptions {
        seed: 2,
        length_mm: Some(40.0),
        ..FormOptions::default()
    })
    .unwrap();
    assert!(!setup.closed_loop());
    assert!(setup.session_info().unwrap().simulated);
    let out = scratch("folder");
    let folder = RunFolder::create(&out).unwrap();
    std::fs::write(folder.path().join("attached.bin"), b"x").unwrap();
    let mut samples = 0usize;
    let counter = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
    let seen = counter.clone();
    let mut fractions = Vec::new();
    let run = setup
        .run(Outlets {
            sample_sink: Some(Box::new(move |_| {
                seen.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            })),
            progress: Some(&mut |f| fractions.push(f)),
            ..Outlets::default()
        })
        .unwrap();
    samples += counter.load(std::sync::atomic::Ordering::Relaxed);
    // The twin's own stream: one sample per log row.
    assert_eq!(samples, run.run.log.rows.len());
    assert!(!fractions.is_empty());
    let written = folder.finish(&run, &["attached.bin"], true).unwrap();
    let names: Vec<String> = written
        .files
        .iter()
        .map(|f| f.strip_prefix(&out).unwrap().display().to_string())
        .collect();
    assert_eq!(&names[..3], ["log.csv", "summary.json", "profile.csv"]);
    assert_eq!(
        &names[names.len() - 2..],
        ["attached.bin", "plot/index.html"]
    );
    assert!(written.files.iter().all(|f| f.exists()));
    // summary.json is the twin's summary text, byte for byte.
    assert_eq!(
        std::fs::read_to_string(out.join("summary.json")).unwrap(),
        run.run.summary_json().unwrap()
    );
    assert_eq!(summary_json(&run).unwrap(), run.run.summary_json().unwrap());
    let text = run.report_text(&written);
    assert!(
        text.starts_with("SIMULATED open-loop run on the twin of the "),
        "{text}"
    );
    assert!(
        text.ends_with(&format!(
            "  wrote {} files to {}\n",
            names.len(),
            out.display()
        )),
        "{text}"
    );
    assert!(written.plot_page_line().contains("plot/index.html"));
    let json = run.report_json(&written).unwrap();
    assert_eq!(json["robot_spec"], "tx200");
    assert_eq!(json["files"].as_array().unwrap().len(), names.len());
    assert!(json["wall_time_s"].is_number());

    // The run's log plotted on its own, then a label count that does not match.
    let plot_dir = scratch("plot");
    let logs = [out.join("log.csv")];
    let plot = deflex_app::report::plot_logs(&logs, &[], None, &plot_dir).unwrap();
    assert_eq!(plot.traces[0].label, "log.csv");
    assert!(plot.page().exists());
    assert!(plot.text().contains("page: "));
    assert_eq!(plot.to_json()["runs"][0]["label"], "log.csv");
    let e = deflex_app::report::plot_logs(&logs, &["a".into(), "b".into()], None, &plot_dir)
        .unwrap_err();
    assert!(e.to_string().starts_with("labels: "), "{e}");
    let _ = std::fs::remove_dir_all(&out);
    let _ = std::fs::remove_dir_all(&plot_dir);
}

#[test]
fn a_grid_campaign_and_the_cells_robot_file_are_written_and_summed_up() {
    use deflex_app::twin::campaign::{CampaignKind, GridChoice, grid_params, measure};
    let config = cell_config(None, None).unwrap();
    let mut params = grid_params(GridChoice::Cell, &config).unwrap();
    params.points_xy = [2, 2];
    params.loads_n = vec![600.0];
    let dir = scratch("campaign");
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("grid.csv");
    let written = measure(&config, &CampaignKind::Grid(params.clone()), 3, &out).unwrap();
    assert_eq!(written.robot_spec, "tx200");
    assert!(written.campaign.starts_with("validation grid 2 × 2 over "));
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.starts_with("# SIMULATED"), "{text}");
    let json = written.to_json();
    assert_eq!(json["rows"], written.rows.len());
    assert_eq!(json["load_cases"], 4);
    assert!(written.text().contains("largest displacement"));
    params.loads_n.clear();
    let e = measure(
        &config,
        &CampaignKind::Grid(params),
        3,
        &dir.join("bad.csv"),
    )
    .err()
    .unwrap();
    assert!(matches!(e, deflex_app::Error::Sim(_)), "{e}");
    assert!(!dir.join("bad.csv").exists());

    let robot_file = dir.join("cell.toml");
    let cell = write_cell_robot(&config, &robot_file).unwrap();
    let text = std::fs::read_to_string(&robot_file).unwrap();
    assert!(
        text.starts_with("# The robot description of the SIMULATED deflex cell of `tx200`"),
        "{text}"
    );
    assert_eq!(cell.to_json()["simulated"], true);
    assert!(cell.text().starts_with("SIMULATED cell robot "));
    let _ = std::fs::remove_dir_all(&dir);
}

#[cfg(feature = "report")]
#[test]
fn a_small_sensitivity_sweep_writes_its_table_heatmap_and_summary() {
    use deflex_app::study::sensitivity::SensitivityPlan;
    use deflex_app::twin::sensitivity::sweep;
    let config = cell_config(None, None).unwrap();
    let model = cell_robot(&config).unwrap();
    let plan = SensitivityPlan {
        delays_s: vec![0.008],
        model_scales: vec![1.0],
        gain_errors: Vec::new(),
        drift_factors: Vec::new(),
        contact_stiffness_n_m: Vec::new(),
        threads: 1,
        length_mm: Some(20.0),
    };
    let done = sweep(&config, &model, &plan, 1, &|_| {}).unwrap();
    assert_eq!(done.result.rows.len(), 1);
    let out = scratch("sensitivity");
    done.write(&out).unwrap();
    for name in ["sensitivity.csv", "summary.json"] {
        assert!(out.join(name).exists(), "{name}");
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary, done.summary_value().unwrap());
    assert_eq!(summary["model"], model.name);
    assert!(done.text(&out).contains("wrote sensitivity.csv"));
    let _ = std::fs::remove_dir_all(&out);
}

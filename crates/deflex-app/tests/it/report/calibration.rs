//! The calibration report (moved from deflex-stiffness with it): plots and tables written, one unit per column, and the χ²/dof note
//! when the residuals are larger than the noise the file claims.

#[cfg(feature = "report")]
use deflex_app::report::calibration_report::{CalibrationReport, write_calibration_report};
use deflex_app::report::calibration_tables::residual_summary;
#[cfg(feature = "report")]
use deflex_app::report::calibration_tables::{SHIFT_HEADERS, shift_rows};
use deflex_calibrate::stiffness::plan::{BasePoint, PlanOptions, plan_experiments};
use deflex_calibrate::stiffness::stiffness_fit::{
    CHI2_WELL_ABOVE_ONE, Calibration, Structure, calibrate_fixed,
};
use deflex_calibrate::stiffness::synthetic::{SyntheticOptions, measure, random_campaign};
#[cfg(feature = "report")]
use deflex_calibrate::stiffness::validation::{predict, residuals};
use deflex_model::Robot;
use rand::{Rng, SeedableRng};

/// deflex-stiffness's identification campaign fixture: the planner's full-family plan with load
/// magnitudes redrawn in 600–1400 N, plus random load cases.
fn campaign(
    robot: &Robot,
    plan_cases: usize,
    random_cases: usize,
    seed: u64,
) -> Vec<deflex_calibrate::measurements::MeasurementRow> {
    let plan = plan_experiments(
        robot,
        &PlanOptions {
            max_force_n: 1400.0,
            load_cases: plan_cases,
            configurations: 300,
            full_family: true,
            seed,
            base_point: BasePoint::Off,
            ..PlanOptions::default()
        },
    )
    .unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x55);
    let mut rows = plan.rows;
    let mut last = String::new();
    let mut scale = 1.0;
    for r in &mut rows {
        if r.load_case != last {
            last = r.load_case.clone();
            scale = rng.gen_range(600.0..=1400.0) / 1400.0;
        }
        for v in &mut r.wrench {
            *v *= scale;
        }
    }
    rows.extend(random_campaign(
        robot,
        random_cases,
        (600.0, 1400.0),
        seed + 1000,
    ));
    rows
}

/// Calibrate the TX200 (Table 1 structure, δr3 free) on a campaign whose true noise is
/// `noise_m` while every row claims 15 µm.
fn calibrate(
    noise_m: f64,
) -> (
    Calibration,
    Vec<deflex_calibrate::measurements::MeasurementRow>,
) {
    let truth = deflex_model::builtin("tx200").unwrap();
    let plan = campaign(&truth, 16, 8, 2);
    let mut rows = measure(
        &truth,
        &plan,
        &SyntheticOptions {
            noise_sigma_m: noise_m,
            record_sigma: false,
            ..Default::default()
        },
    )
    .unwrap();
    for r in &mut rows {
        r.sigma_m = Some(15e-6);
    }
    let cal = calibrate_fixed(
        &truth,
        &rows,
        &Structure::from_robot(&truth).with_free_shifts(),
    )
    .unwrap();
    (cal, rows)
}

#[test]
fn chi2_well_above_one_is_said() {
    let (honest, _) = calibrate(15e-6);
    let (noisy, _) = calibrate(60e-6);
    eprintln!(
        "χ²/dof with the right σ {:.2}, with σ 4× too small {:.2}",
        honest.reduced_chi2, noisy.reduced_chi2
    );
    assert!(honest.reduced_chi2 < CHI2_WELL_ABOVE_ONE && honest.model_form_note().is_none());
    // 4× the noise: χ²/dof ≈ 16.
    assert!(
        (10.0..25.0).contains(&noisy.reduced_chi2),
        "{}",
        noisy.reduced_chi2
    );
    let note = noisy.model_form_note().unwrap();
    assert!(
        note.contains("well above 1") && note.contains("model-form error"),
        "{note}"
    );
    assert!(residual_summary(&noisy).contains(&note));
    assert!(!residual_summary(&honest).contains("well above 1"));
}

#[cfg(feature = "report")]
#[test]
fn report_has_plots_tables_in_one_unit_per_column_and_the_note() {
    let (cal, rows) = calibrate(60e-6);
    let truth = deflex_model::builtin("tx200").unwrap();
    let model = cal.to_robot(&truth);
    // The plotted residuals are the calibration's own (same model, same rows).
    let res = residuals(&model, &rows).unwrap();
    let predicted = predict(&model, &rows).unwrap();
    let rms = (res
        .iter()
        .map(|e| e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
        .sum::<f64>()
        / (3.0 * res.len() as f64))
        .sqrt();
    assert!(
        (rms - cal.residuals.rms_all_m).abs() < 1e-9 * (1.0 + rms),
        "{rms} vs {}",
        cal.residuals.rms_all_m
    );

    let dir = std::env::temp_dir().join(format!("deflex-stiffness-report-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let report = CalibrationReport {
        start_name: "TX200",
        data_name: "meas.csv",
        output_name: "model.toml",
        calibration: &cal,
        predicted: &predicted,
        steps: &[],
        stop_reason: None,
        rows: &rows,
        warnings: &["a file warning".to_string()],
        data_notes: &[],
        couplings: None,
    };
    let files = write_calibration_report(&dir, &report).unwrap();
    for name in [
        "calibration.html",
        "residuals_per_load_case.png",
        "parity_x.png",
        "parity_y.png",
        "parity_z.png",
        "correlation.png",
        "residuals.csv",
        "shifts.csv",
        "stiffness.csv",
    ] {
        assert!(files.contains(&dir.join(name)), "{name} missing: {files:?}");
        assert!(std::fs::metadata(dir.join(name)).unwrap().len() > 0);
    }
    let html = std::fs::read_to_string(dir.join("calibration.html")).unwrap();
    assert!(html.contains("well above 1") && html.contains("a file warning"));
    // δr in mm throughout: the shift table has mm in every numeric header and 400 mm-ish values.
    assert!(SHIFT_HEADERS[1..5].iter().all(|h| h.ends_with("[mm]")));
    let shift = &shift_rows(&cal)[0];
    let value: f64 = shift[1].parse().unwrap();
    assert!((value - 400.0).abs() < 50.0, "{shift:?}");
    let csv = std::fs::read_to_string(dir.join("residuals.csv")).unwrap();
    assert!(csv.starts_with("load_case,point,point_link,dx_m"));
    assert_eq!(csv.lines().count(), rows.len() + 1);
    // A contents list and a link to every CSV written beside the page; real data is not
    // called simulated.
    assert!(html.contains("<nav class=\"contents\">"));
    for csv in files
        .iter()
        .filter(|f| f.extension().is_some_and(|e| e == "csv"))
    {
        let name = csv.file_name().unwrap().to_string_lossy();
        assert!(
            html.contains(&format!("<a href=\"{name}\">")),
            "{name} not linked"
        );
    }
    assert!(!html.contains("SIMULATED"));
    std::fs::remove_dir_all(&dir).unwrap();

    // The same data said to be simulated by its file header: labelled on the page, in the
    // plot captions and in residuals.csv.
    let dir = std::env::temp_dir().join(format!(
        "deflex-stiffness-report-sim-{}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let notes = [
        "SIMULATED deflex digital-twin campaign (calibration campaign) of `tx200`, seed 1: not a \
         measurement"
            .to_string(),
    ];
    // … with a J2.z–J3.z coupling fitted after the structure (`calibrate --couplings`): its
    // table, the refitted stiffnesses and couplings.csv, linked.
    use deflex_model::{Axis, EdofSite};
    let pair = ((EdofSite::Joint(2), Axis::Z), (EdofSite::Joint(3), Axis::Z));
    let fit = deflex_calibrate::stiffness::fit_couplings(&model, &rows, &[pair]).unwrap();
    let simulated = CalibrationReport {
        data_notes: &notes,
        couplings: Some(deflex_app::report::calibration_report::CouplingSection {
            diagonal: &model,
            fit: &fit,
        }),
        ..report
    };
    assert!(simulated.simulated_note().is_some());
    let files = write_calibration_report(&dir, &simulated).unwrap();
    assert!(files.contains(&dir.join("couplings.csv")));
    let html = std::fs::read_to_string(dir.join("calibration.html")).unwrap();
    assert!(
        html.contains("Joint-compliance couplings")
            && html.contains("J2.z–J3.z")
            && html.contains("k with the couplings")
            && html.contains("<a href=\"couplings.csv\">"),
        "{html}"
    );
    let couplings = std::fs::read_to_string(dir.join("couplings.csv")).unwrap();
    assert_eq!(couplings.lines().count(), 2, "{couplings}");
    assert!(html.contains("(SIMULATED data)") && html.contains("not a measurement"));
    assert_eq!(html.matches("(SIMULATED)</figcaption>").count(), 5);
    let csv = std::fs::read_to_string(dir.join("residuals.csv")).unwrap();
    assert!(csv.starts_with("# data: SIMULATED"));
    std::fs::remove_dir_all(&dir).unwrap();
}

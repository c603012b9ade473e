//! The validation report. Issue 12: a validation report that fails half-way leaves the output folder as it was.

#[cfg(feature = "report")]
use deflex_app::report::validation_report::write_validation_report as write_report;
use deflex_app::report::validation_tables::validation_rotation_summary;
use deflex_calibrate::stiffness::synthetic::{
    SyntheticOptions, measure, measure_with_rotations, random_campaign,
};
use deflex_calibrate::stiffness::validation::validate;

#[cfg(feature = "report")]
#[test]
fn a_report_that_fails_half_way_leaves_the_folder_as_it_was() {
    let robot = deflex_model::builtin("tx200").unwrap();
    let plan = random_campaign(&robot, 6, (600.0, 1400.0), 2);
    let rows = measure(&robot, &plan, &SyntheticOptions::default()).unwrap();
    let mut v = validate(&robot, None, &rows).unwrap();
    let dir = std::env::temp_dir().join(format!("deflex-validate-atomic-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("old.txt"), "earlier").unwrap();
    // An earlier report: deflex's own folder (a foreign one is refused whole).
    std::fs::write(dir.join(deflex_files::MARKER), "").unwrap();
    // The parity plots can be drawn, the heatmaps over the measured points cannot: the report
    // fails after several files were written (to the folder being built aside).
    for p in &mut v.points {
        *p = [f64::NAN; 3];
    }
    let err = write_report(&v, &dir).unwrap_err().to_string();
    assert!(err.contains("report"), "{err}");
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        vec![deflex_files::MARKER.to_string(), "old.txt".to_string()]
    );
    let parent: Vec<String> = std::fs::read_dir(dir.parent().unwrap())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| {
            n.contains(&format!("deflex-validate-atomic-{}", std::process::id()))
                && n.contains(".tmp-")
        })
        .collect();
    assert!(parent.is_empty(), "temporary folders left: {parent:?}");
    // A good report replaces the folder whole.
    let v = validate(&robot, None, &rows).unwrap();
    let files = write_report(&v, &dir).unwrap();
    assert!(files.iter().all(|f| f.starts_with(&dir) && f.exists()));
    assert!(!dir.join("old.txt").exists());
    // A contents list like the study's page: after the introduction, before the first section,
    // linking every section.
    let html = std::fs::read_to_string(dir.join("validation.html")).unwrap();
    let nav = html
        .find("<nav class=\"contents\">")
        .expect("contents list");
    assert!(
        nav < html.find("<h2").unwrap(),
        "contents before the first section"
    );
    for id in [
        "prediction-errors-measured-predicted",
        "predicted-vs-measured",
    ] {
        assert!(html.contains(&format!("<a href=\"#{id}\">")), "{id}");
        assert!(html.contains(&format!("<h2 id=\"{id}\">")), "{id}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The one-line rotation summary is there exactly when the rows carry measured rotations.
#[test]
fn the_rotation_summary_is_there_with_rotations_only() {
    let robot = deflex_model::builtin("tx200").unwrap();
    let plan = random_campaign(&robot, 4, (600.0, 1400.0), 3);
    let with = measure_with_rotations(&robot, &plan, &SyntheticOptions::default(), 20e-6).unwrap();
    let without = measure(&robot, &plan, &SyntheticOptions::default()).unwrap();
    let v = validate(&robot, None, &with).unwrap();
    assert!(v.model.rotation.is_some());
    let line = validation_rotation_summary(&v).unwrap();
    assert!(
        line.contains("rotation errors") && line.contains("µrad"),
        "{line}"
    );
    let v = validate(&robot, None, &without).unwrap();
    assert!(validation_rotation_summary(&v).is_none());
}

//! A build without the `report` feature (`cargo test -p deflex-app --no-default-features`):
//! every workflow asked for a report or a figure refuses, naming what was asked and the feature,
//! before it computes, reads or writes anything.

use deflex_app::{Error, ErrorKind};
use std::path::PathBuf;

fn scratch(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("deflex-app-unbuilt-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// The refusal: its variant, its Python class and its words.
fn assert_refused(e: Error, asked: &str) {
    let text = e.to_string();
    assert!(matches!(e, Error::ReportsNotBuilt { .. }), "{text}");
    assert_eq!(e.kind(), ErrorKind::Input);
    assert!(text.contains(asked), "{text}");
    assert!(
        text.contains("needs deflex built with reports (the `report` feature of deflex-app"),
        "{text}"
    );
}

#[test]
fn leave_to_draw_is_refused_naming_what_was_asked() {
    // Irrefutable: without the feature there is no leave to draw at all.
    let Err(e) = deflex_app::report::require("the thing asked for");
    assert_refused(e, "the thing asked for");
}

#[test]
fn the_workflows_that_draw_refuse_before_reading_computing_or_writing() {
    // `deflex plot`: refused before its (missing) log is read.
    let out = scratch("plot");
    let e = deflex_app::report::plot_logs(&[out.join("missing.csv")], &[], None, &out).unwrap_err();
    assert_refused(e, "`deflex plot`");
    assert!(!out.exists());
    // A forming run's folder: refused before the run.
    let out = scratch("run");
    let Err(e) = deflex_app::twin::RunFolder::create(&out) else {
        panic!("a run folder without reports");
    };
    assert_refused(e, "TwinRun.save");
    assert!(!out.exists());
    // The deflection map: refused before the grid is computed.
    let out = scratch("map");
    let grid = deflex_app::robot::map::MapGrid {
        z_m: 0.1,
        center_m: [1.5, 0.0],
        size_m: 0.08,
        step_m: 0.04,
        wrench: [0.0, 0.0, -1100.0, 0.0, 0.0, 0.0],
    };
    let robot = deflex_model::builtin("tx200").unwrap();
    let e = deflex_app::robot::map::write_map(&robot, &grid, &out).unwrap_err();
    assert_refused(e, "`deflex map`");
    assert!(!out.exists());
    // The demo: refused before the study runs.
    let out = scratch("demo");
    let e = deflex_app::study::demo(
        &deflex_app::study::DemoOptions::default(),
        &out,
        &mut |_| {},
    )
    .unwrap_err();
    assert_refused(e, "`deflex demo`");
    assert!(!out.exists());
}

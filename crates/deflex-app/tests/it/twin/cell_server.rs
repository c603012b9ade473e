//! `deflex cell --sim`'s checks on a CELL.toml: loopback addresses only (the model's geometry
//! against the robot the twin plays is checked in deflex-sim's tests).

use deflex_app::cell::config::CellFile;
use deflex_sim::twin::cell_server::{CellServeError, ServeOptions, serve_cell};
use deflex_sim::{CellConfig, ToolPath};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

/// The simulated cell refuses anything but loopback, naming the field.
#[test]
fn cell_refuses_non_loopback_addresses() {
    let file = CellFile::parse(
        "[robot]\nkind = \"kuka-rsi\"\nbind = \"10.0.0.2:59152\"\npeer = \"10.0.0.3:0\"\n\
         [sensor]\nkind = \"netft\"\naddress = \"127.0.0.1:49152\"\n[model]\nfile = \"tx200\"\n",
        "cell.toml",
        PathBuf::new(),
    )
    .unwrap();
    let options = ServeOptions {
        twin: CellConfig::default(),
        path: ToolPath::paper_cone(),
        seed: 1,
        speed: 1.0,
        wait_s: 1.0,
        dwell_s: 0.5,
        pose_jump: None,
    };
    let sides = file.cell_sides(&options.twin).unwrap();
    let e = serve_cell(&sides, &options, &AtomicBool::new(false), &mut |_| {})
        .err()
        .unwrap();
    assert!(
        matches!(
            e,
            CellServeError::NotLoopback {
                field: "robot.bind",
                ..
            }
        ),
        "{e:?}"
    );
    let text = e.to_string();
    assert!(
        text.contains("loopback") && text.contains("robot.bind"),
        "{text}"
    );
}

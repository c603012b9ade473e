//! `deflex cell --sim`'s checks: loopback addresses only; the CELL.toml model's geometry
//! against the robot the twin plays.

use deflex_app::cell::config::CellFile;
use deflex_sim::{CellConfig, ToolPath};
use deflex_sim::twin::cell_server::{CellServeError, ServeOptions, geometry_note, serve_cell};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

/// The cell's nominal robot matches itself; the built-in lacks the cell's tool; a TX200 model
/// is not a UR10e.
#[test]
fn the_model_geometry_is_checked_against_the_robot_played() {
    let ur = CellConfig::for_robot("ur10e").unwrap();
    let nominal = ur.nominal_robot().unwrap();
    assert_eq!(geometry_note(&nominal, &nominal), "");
    let builtin = deflex_app::load::load_robot("ur10e").unwrap();
    assert!(geometry_note(&builtin, &nominal).contains("another tool"));
    let tx = deflex_app::load::load_robot("tx200").unwrap();
    assert!(geometry_note(&tx, &nominal).contains("is not the geometry"));
}

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
    };
    let e = serve_cell(&file, &options, &AtomicBool::new(false), &mut |_| {})
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

//! `deflex cell --sim`'s check of the CELL.toml model's geometry against the robot the twin
//! plays (the loopback-only check of a CELL.toml's addresses is in deflex-app's tests, which
//! read the CELL.toml).

use deflex_sim::CellConfig;
use deflex_sim::twin::cell_server::geometry_note;

/// The cell's nominal robot matches itself; the built-in lacks the cell's tool; a TX200 model
/// is not a UR10e.
#[test]
fn the_model_geometry_is_checked_against_the_robot_played() {
    let ur = CellConfig::for_robot("ur10e").unwrap();
    let nominal = ur.nominal_robot().unwrap();
    assert_eq!(geometry_note(&nominal, &nominal), "");
    // A built-in's name is its description (what `load_robot` resolves it to).
    let builtin = deflex_model::builtin("ur10e").unwrap();
    assert!(geometry_note(&builtin, &nominal).contains("another tool"));
    let tx = deflex_model::builtin("tx200").unwrap();
    assert!(geometry_note(&tx, &nominal).contains("is not the geometry"));
}

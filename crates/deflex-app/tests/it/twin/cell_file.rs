//! A twin cell from a robot file or a twin file ([`deflex_app::cell::twin_cell_file`]).

use deflex_app::cell::twin_cell_file::{cell_for_robot, load_cell};

fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("deflex-twin-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn the_cell_of_a_robot_file_carries_its_description() {
    let dir = temp_dir("cell");
    let path = dir.join("my-ur10e.toml");
    std::fs::write(
        &path,
        deflex_model::robot_to_toml(&deflex_model::builtin("ur10e").unwrap()),
    )
    .unwrap();
    let spec = path.to_str().unwrap();
    let cell = cell_for_robot(spec).unwrap();
    assert_eq!(cell.part.robot, spec);
    let nominal = cell.nominal_robot().unwrap();
    let builtin = deflex_model::builtin("ur10e").unwrap();
    assert_eq!(nominal.name, builtin.name);
    assert_eq!(nominal.joints, builtin.joints);
    assert_eq!(
        nominal.tool,
        cell.tool(),
        "the cell's tool replaces the file's"
    );
    // A twin file naming it, and the flag winning over the file.
    let twin = dir.join("twin.toml");
    std::fs::write(
        &twin,
        format!("[cell.part]\nrobot = \"{spec}\"\n[cell.controller]\nrate_hz = 500.0\n"),
    )
    .unwrap();
    let from_file = load_cell(&twin, None).unwrap();
    assert_eq!(from_file.part.robot, spec);
    assert!(from_file.part.description.is_some());
    assert_eq!(from_file.controller.rate_hz, 500.0);
    assert_eq!(load_cell(&twin, Some("tx200")).unwrap().part.robot, "tx200");
    // Errors name the file and the field.
    std::fs::write(&twin, "[cell.controller]\nrate_hz = -1.0\n").unwrap();
    let e = load_cell(&twin, None).unwrap_err().to_string();
    assert!(e.contains("twin.toml") && e.contains("rate_hz"), "{e}");
    let e = load_cell(&dir.join("absent.toml"), None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("absent.toml"), "{e}");
    let e = cell_for_robot("/nonexistent/arm.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("/nonexistent/arm.toml"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

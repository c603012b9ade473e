//! G-code files read for the twin and `compensate` ([`deflex_app::load::gcode_file`]): the
//! built-in paths by name, a file named after itself, a missing file refused (the twin reads no
//! file: this test was the twin's `tool_path_by_name` test).

use deflex_app::load::gcode_file::{read_gcode, tool_path_by_name};

#[test]
fn named_paths_resolve_and_files_are_read_here() {
    for name in ["cone", "cone-contour", "pyramid"] {
        assert!(tool_path_by_name(name).is_ok(), "{name}");
    }
    assert!(tool_path_by_name("/nonexistent.gcode").is_err());
    let dir = std::env::temp_dir().join(format!("deflex-app-gcode-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("square.nc");
    std::fs::write(
        &file,
        "G21 G90 G54\nG0 X0 Y0 Z5\nG1 Z0 F600\nG1 X10\nG1 Y10\nM30\n",
    )
    .unwrap();
    let path = read_gcode(&file).unwrap();
    assert_eq!(path.name, "square.nc");
    assert_eq!(path.waypoints.len(), 4);
    assert_eq!(tool_path_by_name(file.to_str().unwrap()).unwrap(), path);
    std::fs::remove_dir_all(&dir).unwrap();
}

//! Robot and measurement files on disk ([`deflex_app::load`]): a URDF found beside its TOML and
//! again after the robot is written to another folder, the errors that name a missing or
//! oversized file, measurement and point files read through their formats.

use deflex_app::load::*;
use std::path::PathBuf;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("deflex-load-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A two-joint URDF arm and its TOML, written into `dir` (as `r.urdf`, `r.toml`).
fn write_urdf_robot(dir: &std::path::Path) -> PathBuf {
    let xml = "<robot name=\"r\"><link name=\"base_link\"/><link name=\"link_1\"/><link name=\"link_2\"/>\
        <joint name=\"j1\" type=\"revolute\"><parent link=\"base_link\"/><child link=\"link_1\"/>\
        <origin xyz=\"0 0 0.4\" rpy=\"0 0 0\"/><axis xyz=\"0 0 1\"/><limit lower=\"-7\" upper=\"7\" effort=\"0\" velocity=\"1\"/></joint>\
        <joint name=\"j2\" type=\"revolute\"><parent link=\"link_1\"/><child link=\"link_2\"/>\
        <origin xyz=\"0.1 0 0\" rpy=\"0 0 0\"/><axis xyz=\"0 1 0\"/><limit lower=\"-7\" upper=\"7\" effort=\"0\" velocity=\"1\"/></joint>\
        <link name=\"tool0\"/><joint name=\"flange\" type=\"fixed\"><parent link=\"link_2\"/><child link=\"tool0\"/>\
        <origin xyz=\"0 0 0\" rpy=\"0 0 0\"/></joint></robot>";
    std::fs::write(dir.join("r.urdf"), xml).unwrap();
    let toml = "name = \"moved from URDF\"\nurdf = \"r.urdf\"\n[[joint]]\nname = \"j1\"\n[[joint]]\nname = \"j2\"\n";
    std::fs::write(dir.join("r.toml"), toml).unwrap();
    dir.join("r.toml")
}

#[test]
fn a_urdf_robot_written_to_another_folder_still_finds_its_urdf() {
    let dir = temp_dir("urdf-path");
    let robot = load_robot(write_urdf_robot(&dir).to_str().unwrap()).unwrap();
    let out = dir.join("sub").join("deeper").join("m.toml");
    std::fs::create_dir_all(out.parent().unwrap()).unwrap();
    std::fs::write(&out, robot_to_toml_for(&robot, &out)).unwrap();
    let again = load_robot(out.to_str().unwrap()).unwrap();
    let q = [0.3, -0.4];
    let a = robot.tcp_pose(&q).unwrap();
    let b = again.tcp_pose(&q).unwrap();
    assert!((a.to_homogeneous() - b.to_homogeneous()).norm() < 1e-12);
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(
        text.contains("urdf = \"../../"),
        "relative path written: {text}"
    );
    // The same file by path, and a TOML naming a URDF that is not there.
    let direct = robot_from_toml_file(&out).unwrap();
    assert_eq!(direct.joint_count(), 2);
    std::fs::remove_file(dir.join("r.urdf")).unwrap();
    let e = load_robot(out.to_str().unwrap()).unwrap_err().to_string();
    assert!(
        e.contains("r.urdf") && e.contains("cannot read file"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn missing_robot_files_are_named_with_the_built_in_names() {
    let e = load_robot("/nonexistent/robot.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("/nonexistent/robot.toml"), "{e}");
    assert!(
        e.contains("tx200") && e.contains("not a built-in robot"),
        "{e}"
    );
    assert_eq!(
        load_robot("ur10e").unwrap().name,
        deflex_model::builtin("ur10e").unwrap().name
    );
}

#[test]
fn measurement_and_point_files_are_read_through_their_formats() {
    let dir = temp_dir("measurements");
    let robot = deflex_model::builtin("tx200").unwrap();
    let row = deflex_calibrate::measurements::MeasurementRow {
        load_case: "L1".into(),
        q_rad: vec![0.0; 6],
        wrench: [0.0, 0.0, -100.0, 0.0, 0.0, 0.0],
        load_link: 6,
        load_point_m: [1.0, 0.0, 0.5],
        point: "TCP".into(),
        point_link: 6,
        point_m: [1.0, 0.0, 0.5],
        displacement_m: Some([1e-4, 0.0, -2e-4]),
        sigma_m: None,
        rotation_rad: None,
        purpose: None,
    };
    let path = dir.join("m.csv");
    std::fs::write(
        &path,
        deflex_calibrate::measurements::format_rows_for(
            &robot,
            std::slice::from_ref(&row),
            &["a note"],
        ),
    )
    .unwrap();
    let file = read_file(&path, Some(6), true).unwrap();
    assert_eq!(file.rows, vec![row.clone()]);
    assert_eq!(file.header.notes, vec!["a note".to_string()]);
    assert_eq!(read_measurements(&path).unwrap(), vec![row.clone()]);
    assert_eq!(read_plan(&path).unwrap().len(), 1);
    let e = read_for_robot(&path, 5, true).unwrap_err().to_string();
    assert!(
        e.contains("6 joint columns") && e.contains("5 joints"),
        "{e}"
    );
    let e = read_measurements(&dir.join("absent.csv"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("absent.csv"), "{e}");
    let points = dir.join("p.csv");
    std::fs::write(&points, "name,link,x_m,y_m,z_m\nM9,3,0.1,0,0\n").unwrap();
    let list = read_points(&points, 6).unwrap();
    assert_eq!(list[0].name, "M9");
    assert_eq!(list[0].link, 3);
    let e = read_points(&dir.join("none.csv"), 6)
        .unwrap_err()
        .to_string();
    assert!(e.contains("none.csv"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The readers of the user's files report through the shared file errors: a file over its
/// reader's limit names what it is, any other failure names the file.
#[test]
fn an_oversized_or_unreadable_file_is_reported_through_the_shared_errors() {
    use deflex_app::cell::twin_cell_file::{MAX_CELL_FILE_BYTES, TwinCellFileError, load_cell};
    let dir = temp_dir("shared-errors");
    let big = dir.join("cell.toml");
    std::fs::write(&big, vec![b'#'; MAX_CELL_FILE_BYTES as usize + 10]).unwrap();
    let e = load_cell(&big, None).unwrap_err();
    assert!(matches!(e, TwinCellFileError::TooLarge(_)), "{e}");
    assert_eq!(
        e.to_string(),
        format!(
            "{}: more than the {MAX_CELL_FILE_BYTES} bytes a cell file may have (stopped reading after {})",
            big.display(),
            MAX_CELL_FILE_BYTES + 1
        )
    );
    let e = load_cell(&dir, None).unwrap_err();
    assert!(matches!(e, TwinCellFileError::Read(_)), "{e}");
    assert!(
        e.to_string().contains("is a folder, not a regular file"),
        "{e}"
    );
    let e = deflex_app::table::read(&dir.join("missing.csv")).unwrap_err();
    assert_eq!(e.kind(), deflex_app::ErrorKind::Io, "{e}");
    assert!(
        e.to_string()
            .starts_with(&format!("{}: ", dir.join("missing.csv").display()))
    );
    let _ = std::fs::remove_dir_all(&dir);
}

//! `deflex export` through the real binary: every format written and read back, or refused
//! whole.

use std::process::{Command, Output};

fn deflex(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_deflex"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn every_format_is_written_and_read_back_or_refused_whole() {
    let dir = std::env::temp_dir().join(format!("deflex-export-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for (format, file, nominal) in [
        ("urdf", "ur10e.urdf", None),
        ("ur-calibration", "ur10e_calibration.yaml", None),
        ("dh-table", "ur10e_dh.csv", Some("ur10e")),
    ] {
        let out = dir.join(file);
        let mut args = vec![
            "--json",
            "export",
            "--robot",
            "ur10e",
            "--format",
            format,
            "--out",
            out.to_str().unwrap(),
        ];
        if let Some(n) = nominal {
            args.extend(["--nominal", n]);
        }
        let run = deflex(&args);
        assert!(
            run.status.success(),
            "{file}: {}",
            String::from_utf8_lossy(&run.stderr)
        );
        assert!(out.exists(), "{file}");
    }
    // The URDF's robot file loads from disk with the stiffnesses.
    let robot = deflex_app::load::load_robot(dir.join("ur10e.toml").to_str().unwrap()).unwrap();
    let original = deflex_model::builtin("ur10e").unwrap();
    assert_eq!(robot.edof_count(), original.edof_count());
    // A KUKA arm has no UR calibration: refused, nothing written.
    let out = dir.join("kr.yaml");
    let run = deflex(&[
        "--json",
        "export",
        "--robot",
        "kr210-r2700",
        "--format",
        "ur-calibration",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!run.status.success());
    let e = String::from_utf8_lossy(&run.stderr);
    assert!(e.contains("ur-calibration"), "{e}");
    assert!(!out.exists());
    std::fs::remove_dir_all(dir).unwrap();
}

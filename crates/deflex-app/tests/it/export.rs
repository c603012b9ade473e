//! The export workflow ([`deflex_app::export`]): every format read back and written, or refused
//! whole.

use deflex_app::Error;
use deflex_app::export::{CONFIGURATIONS_CHECKED, ExportFormat, READBACK_BOUND_M, export};

#[test]
fn every_format_is_read_back_then_written_or_refused_whole() {
    let dir = std::env::temp_dir().join(format!("deflex-app-export-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let ur10e = deflex_model::builtin("ur10e").unwrap();
    for (format, file, name) in [
        (ExportFormat::Urdf, "ur10e.urdf", "urdf"),
        (ExportFormat::UrCalibration, "ur10e.yaml", "ur-calibration"),
        (ExportFormat::DhTable, "ur10e_dh.csv", "dh-table"),
    ] {
        let out = dir.join(file);
        let nominal = (format == ExportFormat::DhTable).then_some(&ur10e);
        let exported = export(&ur10e, format, &out, nominal).unwrap();
        assert!(
            exported.readback_max_tcp_error_m <= READBACK_BOUND_M,
            "{name}"
        );
        assert_eq!(format.name(), name);
        assert_eq!(exported.json()["format"], name);
        assert_eq!(
            exported.json()["configurations_checked"],
            CONFIGURATIONS_CHECKED
        );
        let wrote = format!("{}: wrote {}", ur10e.name, out.display());
        assert!(exported.text().starts_with(&wrote), "{}", exported.text());
        for f in &exported.files {
            assert!(f.is_file(), "{}", f.display());
        }
    }
    // The URDF's robot file sits beside it.
    assert!(dir.join("ur10e.toml").is_file());
    // A KUKA arm has no UR calibration: refused, nothing written.
    let kuka = deflex_model::builtin("kr210-r2700").unwrap();
    let out = dir.join("kr.yaml");
    let e = export(&kuka, ExportFormat::UrCalibration, &out, None).unwrap_err();
    assert!(matches!(e, Error::Export(_)), "{e}");
    assert!(!out.exists());
    std::fs::remove_dir_all(dir).unwrap();
}

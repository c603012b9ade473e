//! The compensated-path table round-trips (the law's lookups of it, by time and arc length, are
//! checked in deflex-app's `cell::feedforward_table`).

use crate::compensated_line::compensated_line;
use deflex_compensate::table::{read_csv, write_csv};

#[test]
fn the_table_round_trips_to_its_printed_precision() {
    let (_, path, result) = compensated_line();
    let text = write_csv(
        &path,
        &result,
        6,
        &["SIMULATED wrenches".into(), "two\nlines".into()],
    );
    assert!(text.starts_with("# SIMULATED wrenches\n# two\n# lines\nindex,s_m,t_s,x_m,"));
    let header = text.lines().nth(3).unwrap();
    for column in ["dx_m", "fz_N", "defl_z_m", "err_m", "q6_rad", "status"] {
        assert!(header.split(',').any(|c| c == column), "{column}");
    }
    let rows = read_csv(&text, "t.csv").unwrap();
    assert_eq!(rows.len(), path.len());
    for ((row, point), computed) in rows.iter().zip(path.points()).zip(&result.points) {
        assert!((row.arc_length_m - point.arc_length_m).abs() < 1e-9);
        assert!((row.desired.translation.vector - point.pose.translation.vector).norm() < 1e-9);
        let angle =
            deflex_model::spatial::orientation_error(&row.desired.rotation, &point.pose.rotation);
        assert!(angle.norm() < 1e-8);
        assert!((row.compensation - computed.compensation).amax() < 1e-9);
        assert!((row.wrench - computed.wrench).amax() < 1e-4);
        assert!((row.deflection - computed.deflection).amax() < 1e-9);
        assert_eq!(row.status, "ok");
    }
    let e = read_csv("index,s_m\n0,0\n", "bad.csv").unwrap_err();
    assert!(
        e.to_string()
            .starts_with("bad.csv: not a compensated path: missing column(s) t_s"),
        "{e}"
    );
    let broken = text.replace("\n2,", "\n2,x");
    let e = read_csv(&broken, "b.csv").unwrap_err();
    assert!(e.to_string().contains("b.csv:7: column `s_m`"), "{e}");
}

//! Writing rows as measurement or plan CSV text (full precision, SI units).

use crate::measurements::bounds::{
    DISPLACEMENT_COLUMNS, LOAD_POINT_COLUMNS, POINT_COLUMNS, ROTATION_COLUMNS, WRENCH_COLUMNS,
};
use crate::measurements::{FileHeader, MeasurementRow};
use deflex_model::Robot;

/// Format rows as CSV text (full precision). Displacement, `sigma_m`, rotation, `sigma_rad` and
/// purpose columns are written when any row has them.
pub fn format_rows(rows: &[MeasurementRow]) -> String {
    let joint_count = rows.first().map(|r| r.q_rad.len()).unwrap_or(0);
    let with_displacement = rows.iter().any(|r| r.displacement_m.is_some());
    let with_sigma = rows.iter().any(|r| r.sigma_m.is_some());
    let with_rotation = rows.iter().any(|r| r.rotation_rad.is_some());
    let with_sigma_rad = rows
        .iter()
        .any(|r| r.rotation_rad.is_some_and(|m| m.sigma_rad.is_some()));
    let with_purpose = rows.iter().any(|r| r.purpose.is_some());
    let mut header: Vec<String> = vec!["load_case".into()];
    header.extend((1..=joint_count).map(|i| format!("q{i}_rad")));
    header.extend(WRENCH_COLUMNS.iter().map(|s| s.to_string()));
    header.push("load_link".into());
    header.extend(LOAD_POINT_COLUMNS.iter().map(|s| s.to_string()));
    header.extend(["point".to_string(), "point_link".to_string()]);
    header.extend(POINT_COLUMNS.iter().map(|s| s.to_string()));
    if with_displacement {
        header.extend(DISPLACEMENT_COLUMNS.iter().map(|s| s.to_string()));
    }
    if with_sigma {
        header.push("sigma_m".into());
    }
    if with_rotation {
        header.extend(ROTATION_COLUMNS.iter().map(|s| s.to_string()));
    }
    if with_sigma_rad {
        header.push("sigma_rad".into());
    }
    if with_purpose {
        header.push("purpose".into());
    }
    let num = |v: f64| format!("{v:e}");
    let record_of = |row: &MeasurementRow| {
        let mut record: Vec<String> = vec![row.load_case.clone()];
        record.extend(row.q_rad.iter().map(|v| format!("{v:?}")));
        record.extend(row.wrench.iter().map(|v| format!("{v:?}")));
        record.push(row.load_link.to_string());
        record.extend(row.load_point_m.iter().map(|v| format!("{v:?}")));
        record.push(row.point.clone());
        record.push(row.point_link.to_string());
        record.extend(row.point_m.iter().map(|v| format!("{v:?}")));
        if with_displacement {
            match row.displacement_m {
                Some(d) => record.extend(d.iter().map(|v| num(*v))),
                None => record.extend(["".to_string(), "".to_string(), "".to_string()]),
            }
        }
        if with_sigma {
            record.push(row.sigma_m.map(num).unwrap_or_default());
        }
        if with_rotation {
            match row.rotation_rad {
                Some(r) => record.extend(r.value_rad.iter().map(|v| num(*v))),
                None => record.extend(["".to_string(), "".to_string(), "".to_string()]),
            }
        }
        if with_sigma_rad {
            record.push(
                row.rotation_rad
                    .and_then(|r| r.sigma_rad)
                    .map(num)
                    .unwrap_or_default(),
            );
        }
        if with_purpose {
            record.push(row.purpose.clone().unwrap_or_default());
        }
        record
    };
    deflex_files::csv_text(std::iter::once(header).chain(rows.iter().map(record_of)))
}

/// [`format_rows`] after a header naming the robot the rows were made for (`# robot: …`,
/// `# geometry: …`, see [`FileHeader`]), preceded by `notes` as comment lines (e.g.
/// `SIMULATED …`).
pub fn format_rows_for(robot: &Robot, rows: &[MeasurementRow], notes: &[&str]) -> String {
    format_rows_with_header(&FileHeader::for_robot(robot), rows, notes)
}

/// [`format_rows`] after `notes` and the robot lines of `robot_lines` (e.g. the header of the
/// plan the rows measured, so the file names the robot its coordinates were made for).
pub fn format_rows_with_header(
    robot_lines: &FileHeader,
    rows: &[MeasurementRow],
    notes: &[&str],
) -> String {
    let mut header = FileHeader::default();
    for note in notes {
        header = header.with_note(*note);
    }
    header.robot = robot_lines.robot.clone();
    header.geometry = robot_lines.geometry.clone();
    format!("{}{}", header.render(), format_rows(rows))
}

//! The CSV tables of the report folder: iterations, estimates, residuals, outliers and, with
//! joint maps, the maps sampled.

use deflex_calibrate::geometry::campaign::{Campaign, ReadingKind};
use deflex_calibrate::geometry::fit::FitResult;

/// A CSV table of the report folder.
pub struct CsvTable {
    /// Its file name (`residuals.csv`).
    pub file: &'static str,
    /// Column names.
    pub headers: Vec<String>,
    /// Rows, each as long as the header.
    pub rows: Vec<Vec<String>>,
}

fn names(names: &[&str]) -> Vec<String> {
    names.iter().map(|n| n.to_string()).collect()
}

/// The report's tables, in the order they are written: `iterations.csv`, `estimates.csv`,
/// `residuals.csv`, `outliers.csv` and, with joint maps, `joint_maps.csv`.
pub fn csv_tables(result: &FitResult, campaign: &Campaign) -> Vec<CsvTable> {
    let (headers, rows) = super::iteration_rows(result);
    let mut tables = vec![
        CsvTable {
            file: "iterations.csv",
            headers,
            rows,
        },
        estimates(result),
        residuals(result, campaign),
        outliers(result),
    ];
    tables.extend(joint_maps(result));
    tables
}

fn estimates(result: &FitResult) -> CsvTable {
    let rows = result
        .estimates
        .iter()
        .map(|e| {
            vec![
                e.name.clone(),
                e.unit.si().to_string(),
                format!("{:e}", e.start),
                format!("{:e}", e.value),
                format!("{:e}", e.standard_error),
                e.bootstrap_se.map_or(String::new(), |b| format!("{b:e}")),
            ]
        })
        .collect();
    CsvTable {
        file: "estimates.csv",
        headers: names(&[
            "parameter",
            "unit",
            "nominal",
            "estimate",
            "standard_error",
            "bootstrap_se",
        ]),
        rows,
    }
}

fn residuals(result: &FitResult, campaign: &Campaign) -> CsvTable {
    let mut rows = Vec::new();
    for r in &result.residuals {
        let (label, line, q) = match campaign.absolute_row(r.index) {
            Some(i) => {
                let row = &campaign.absolute[i];
                (row.setup.clone(), row.line, row.q_rad.clone())
            }
            None => {
                let row = &campaign.loaded[r.index - campaign.absolute.len()];
                (row.load_case.clone(), 0, row.q_rad.clone())
            }
        };
        let kind = match campaign.kind(r.index) {
            ReadingKind::Position => "position_m",
            ReadingKind::Loaded => "displacement_m",
            ReadingKind::Orientation => "orientation_rad",
        };
        let mut cells = vec![
            r.index.to_string(),
            line.to_string(),
            label,
            r.role.name().to_string(),
            kind.to_string(),
            format!("{:e}", r.residual.x),
            format!("{:e}", r.residual.y),
            format!("{:e}", r.residual.z),
        ];
        cells.extend(q.iter().map(|v| format!("{v:?}")));
        rows.push(cells);
    }
    let n = result.model.robot.joint_count();
    let mut headers = names(&[
        "reading",
        "line",
        "setup_or_case",
        "role",
        "kind",
        "ex",
        "ey",
        "ez",
    ]);
    headers.extend((1..=n).map(|i| format!("q{i}_rad")));
    CsvTable {
        file: "residuals.csv",
        headers,
        rows,
    }
}

fn outliers(result: &FitResult) -> CsvTable {
    let rows = result
        .outliers
        .iter()
        .map(|o| {
            vec![
                o.index.to_string(),
                o.line.to_string(),
                o.label.clone(),
                format!("{:e}", o.residual),
                format!("{:.4}", o.weight),
            ]
        })
        .collect();
    CsvTable {
        file: "outliers.csv",
        headers: names(&["reading", "line", "setup_or_case", "residual_m", "weight"]),
        rows,
    }
}

/// Each joint map sampled at a tenth of its knot spacing over its range (the terms file holds
/// its coefficients).
fn joint_maps(result: &FitResult) -> Option<CsvTable> {
    let maps = result.model.joint_maps.as_ref()?;
    let mut rows = Vec::new();
    for map in &maps.maps {
        let (lo, hi) = map.range_rad();
        let step = map.spacing_rad / 10.0;
        for k in 0..=((hi - lo) / step).ceil() as usize {
            let q = lo + k as f64 * step;
            rows.push(vec![
                (map.joint + 1).to_string(),
                format!("{q:e}"),
                format!("{:e}", map.value(q)),
            ]);
        }
    }
    Some(CsvTable {
        file: "joint_maps.csv",
        headers: names(&["joint", "q_rad", "delta_theta_rad"]),
        rows,
    })
}

/// A CSV table: the header, then the rows (each as long as the header, or an error).
pub fn csv_text(headers: &[String], rows: &[Vec<String>]) -> std::io::Result<String> {
    csv_records(std::iter::once(headers).chain(rows.iter().map(Vec::as_slice)))
}

/// CSV text of `records` (the first one the header). A record of another length than the
/// first is an error, not a silently shorter table.
pub fn csv_records<'a>(records: impl IntoIterator<Item = &'a [String]>) -> std::io::Result<String> {
    let mut writer = csv::WriterBuilder::new().from_writer(Vec::new());
    for record in records {
        writer.write_record(record)?;
    }
    let bytes = writer.into_inner().map_err(|e| e.into_error())?;
    String::from_utf8(bytes).map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e))
}

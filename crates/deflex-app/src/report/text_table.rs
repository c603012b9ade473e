//! Tables as aligned text (for terminals) and as CSV (RFC 4180 quoting): no drawing, so in every
//! build (the `report` feature or not), for the tables the front ends print and the CSV files
//! the workflows write.

use std::fmt::Write as _;

/// Render a table with aligned columns.
pub fn render_table(headers: &[&str], rows: &[Vec<String>]) -> String {
    let ncol = headers.len();
    let mut width: Vec<usize> = headers.iter().map(|h| h.chars().count()).collect();
    for r in rows {
        for (i, c) in r.iter().enumerate().take(ncol) {
            width[i] = width[i].max(c.chars().count());
        }
    }
    let mut out = String::new();
    let line = |cells: Vec<&str>, out: &mut String| {
        let parts: Vec<String> = cells
            .iter()
            .enumerate()
            .map(|(i, c)| format!("{c}{}", " ".repeat(width[i] - c.chars().count())))
            .collect();
        let _ = writeln!(out, "{}", parts.join("  ").trim_end());
    };
    line(headers.to_vec(), &mut out);
    let total: usize = width.iter().sum::<usize>() + 2 * (ncol - 1);
    let _ = writeln!(out, "{}", "-".repeat(total));
    for r in rows {
        line(r.iter().map(String::as_str).collect(), &mut out);
    }
    out
}

/// CSV of a table (RFC 4180 quoting). A row of another length than the header is an error, not
/// a silently shorter table.
pub fn table_csv(headers: &[&str], rows: &[Vec<String>]) -> std::io::Result<String> {
    let mut w = csv::WriterBuilder::new().from_writer(Vec::new());
    w.write_record(headers)?;
    for r in rows {
        w.write_record(r)?;
    }
    let bytes = w.into_inner().map_err(|e| e.into_error())?;
    String::from_utf8(bytes).map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e))
}

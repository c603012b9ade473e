//! The validation of a model on measurements as text tables: the prediction error statistics
//! (position in mm, rotation in µrad), what `deflex validate` prints and its page shows.

use deflex_calibrate::stats::ErrorStats;
use deflex_calibrate::stiffness::validation::Validation;
use std::fmt::Write as _;

/// Validation errors as table rows (mm).
pub fn validation_rows(v: &Validation) -> Vec<Vec<String>> {
    std::iter::once(&v.model)
        .chain(v.baseline.as_ref())
        .map(|m| {
            let mut row = vec![m.name.clone()];
            row.extend(stat_cells(&m.stats, |x| format!("{:.4}", x * 1e3)));
            row
        })
        .collect()
}

/// RMS x, y, z, RMS norm, max x, y, z, max norm, each formatted by `fmt`.
fn stat_cells(s: &ErrorStats, fmt: impl Fn(f64) -> String) -> Vec<String> {
    s.rms
        .iter()
        .chain(std::iter::once(&s.norm.rms))
        .chain(s.max_abs.iter())
        .chain(std::iter::once(&s.norm.max))
        .map(|&x| fmt(x))
        .collect()
}

/// Headers of [`validation_rows`].
pub const VALIDATION_HEADERS: [&str; 9] = [
    "model",
    "RMS x [mm]",
    "RMS y [mm]",
    "RMS z [mm]",
    "RMS norm [mm]",
    "max x [mm]",
    "max y [mm]",
    "max z [mm]",
    "max norm [mm]",
];

/// Rotation validation errors as table rows (µrad), one per model; empty when no row has a
/// measured rotation.
pub fn validation_rotation_rows(v: &Validation) -> Vec<Vec<String>> {
    std::iter::once(&v.model)
        .chain(v.baseline.as_ref())
        .filter_map(|m| {
            let s = &m.rotation.as_ref()?.stats;
            let mut row = vec![m.name.clone(), s.norm.count.to_string()];
            row.extend(stat_cells(s, |x| format!("{:.1}", x * 1e6)));
            Some(row)
        })
        .collect()
}

/// Headers of [`validation_rotation_rows`].
pub const VALIDATION_ROTATION_HEADERS: [&str; 10] = [
    "model",
    "rows",
    "rot RMS x [µrad]",
    "RMS y [µrad]",
    "RMS z [µrad]",
    "RMS norm [µrad]",
    "max x [µrad]",
    "max y [µrad]",
    "max z [µrad]",
    "max norm [µrad]",
];

/// One line per model with the rotation prediction errors, `None` when no row has a measured
/// rotation.
pub fn validation_rotation_summary(v: &Validation) -> Option<String> {
    let mut out = String::new();
    for m in std::iter::once(&v.model).chain(v.baseline.as_ref()) {
        let s = &m.rotation.as_ref()?.stats;
        let _ = writeln!(
            out,
            "rotation errors {} ({} rows): RMS x/y/z {:.1} / {:.1} / {:.1} µrad (norm {:.1} µrad), max norm {:.1} µrad",
            m.name,
            s.norm.count,
            s.rms[0] * 1e6,
            s.rms[1] * 1e6,
            s.rms[2] * 1e6,
            s.norm.rms * 1e6,
            s.norm.max * 1e6
        );
    }
    Some(out)
}

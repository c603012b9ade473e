//! The rows of a measurement or plan file and the file as read.

/// Default tracker standard deviation when a row has no `sigma_m` (15 µm).
pub const DEFAULT_SIGMA_M: f64 = 15e-6;

/// Default standard deviation of a measured rotation component when a row has no `sigma_rad`
/// (20 µrad, a 6-DoF tracker probe).
pub const DEFAULT_SIGMA_RAD: f64 = 20e-6;

/// One measured (or planned) point under one load case.
#[derive(Clone, Debug, PartialEq)]
pub struct MeasurementRow {
    /// Load-case label; rows sharing it share configuration and load.
    pub load_case: String,
    /// Joint values (rad).
    pub q_rad: Vec<f64>,
    /// Applied wrench `[fx, fy, fz, mx, my, mz]` (N, N·m), world axes, moment about the load point.
    pub wrench: [f64; 6],
    /// Link carrying the load (0 = base … N = last link).
    pub load_link: usize,
    /// Load point, world coordinates in the unloaded pose (m).
    pub load_point_m: [f64; 3],
    /// Point label (`TCP`, `M1`, …).
    pub point: String,
    /// Link carrying the measured point.
    pub point_link: usize,
    /// Measured point, world coordinates in the unloaded pose (m).
    pub point_m: [f64; 3],
    /// Displacement loaded − unloaded, world axes (m). `None` in a plan.
    pub displacement_m: Option<[f64; 3]>,
    /// Measurement standard deviation for this row (m).
    pub sigma_m: Option<f64>,
    /// Measured small rotation of the point's link (rad), when orientation was measured, with
    /// its standard deviation.
    pub rotation_rad: Option<MeasuredRotation>,
    /// Why this row is in a plan (free text).
    pub purpose: Option<String>,
}

/// A measured small rotation (columns `drx_rad, dry_rad, drz_rad` and `sigma_rad`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeasuredRotation {
    /// Rotation vector loaded − unloaded of the measured point's link, world axes (rad).
    pub value_rad: [f64; 3],
    /// Standard deviation of each component (rad); `None` = [`DEFAULT_SIGMA_RAD`].
    pub sigma_rad: Option<f64>,
}

impl MeasuredRotation {
    /// A rotation with the default standard deviation.
    pub fn new(value_rad: [f64; 3]) -> MeasuredRotation {
        MeasuredRotation {
            value_rad,
            sigma_rad: None,
        }
    }

    /// The standard deviation used for weighting (rad).
    pub fn sigma(&self) -> f64 {
        self.sigma_rad.unwrap_or(DEFAULT_SIGMA_RAD)
    }
}
/// A measurement or plan file as read: its header comments, its rows and the line of each row.
pub type MeasurementFile = crate::measurements::reader::MeasurementTable<MeasurementRow>;

/// Number of distinct load cases among `rows`.
pub fn load_case_count(rows: &[MeasurementRow]) -> usize {
    rows.iter()
        .map(|r| r.load_case.as_str())
        .collect::<std::collections::BTreeSet<_>>()
        .len()
}

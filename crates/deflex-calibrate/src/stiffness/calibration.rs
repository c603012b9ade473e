//! The result of a calibration: the structure fitted (eDoFs, centre shifts, which shifts are
//! free), each eDoF's estimate (stiffness, standard error, 95 % interval, status), the centre
//! shifts, the residual statistics and the calibrated robot (`Calibration::to_robot`). The fit
//! itself is [`crate::stiffness::stiffness_fit`]'s; the uncertainties are computed by `uncertainty`.

use crate::stats::ErrorStats;
use crate::stiffness::design::{EdofId, edof_order};
use deflex_model::{Axis, EdofSite, Robot};
use nalgebra::DMatrix;

/// Relative standard error of a compliance above which it is reported not identifiable.
pub const MAX_RELATIVE_SE: f64 = 5.0;
/// Two-sided 95 % normal quantile.
pub const Z95: f64 = 1.959964;
/// χ²/dof above which a calibration says that its model does not represent the data to the
/// measurement noise. With a right model and right σ, χ²/dof has mean 1 and standard deviation
/// √(2/dof): 0.2 at 50 degrees of freedom, 0.06 at 500, so 2 is ≥ 5 standard deviations away
/// for any campaign worth fitting; a value above it means model-form error (effects the eDoF
/// family cannot represent) or a σ that is too small.
pub const CHI2_WELL_ABOVE_ONE: f64 = 2.0;

/// A model structure: which eDoFs, which centre shifts, and which shifts are fitted.
#[derive(Clone, Debug, PartialEq)]
pub struct Structure {
    /// eDoFs, in robot order.
    pub edofs: Vec<EdofId>,
    /// Centre shift δr of each joint (m), index = joint − 1.
    pub shifts_m: Vec<f64>,
    /// Whether each joint's shift is a fitted parameter.
    pub free_shift: Vec<bool>,
}

impl Structure {
    /// The structure of a robot model: its eDoFs and (fixed) centre shifts.
    pub fn from_robot(robot: &Robot) -> Structure {
        Structure {
            edofs: robot.edofs().map(|e| (e.site, e.axis)).collect(),
            shifts_m: robot.joints.iter().map(|j| j.center_shift).collect(),
            free_shift: vec![false; robot.joint_count()],
        }
    }

    /// The classical VJM start of the paper: one z-eDoF per joint, no shift.
    pub fn one_z_per_joint(joint_count: usize) -> Structure {
        Structure {
            edofs: (1..=joint_count)
                .map(|i| (EdofSite::Joint(i), Axis::Z))
                .collect(),
            shifts_m: vec![0.0; joint_count],
            free_shift: vec![false; joint_count],
        }
    }

    /// Free the shifts of every joint that has an x or y eDoF.
    pub fn with_free_shifts(mut self) -> Structure {
        for &(site, axis) in &self.edofs {
            if let (EdofSite::Joint(i), Axis::X | Axis::Y) = (site, axis) {
                self.free_shift[i - 1] = true;
            }
        }
        self
    }

    /// Joints (1-based) whose centre shift is fitted.
    pub fn free_shift_joints(&self) -> Vec<usize> {
        (1..=self.free_shift.len())
            .filter(|&j| self.free_shift[j - 1])
            .collect()
    }

    /// Keep the eDoFs sorted in robot order.
    pub fn normalize(&mut self) {
        self.edofs.sort_by_key(edof_order);
        self.edofs.dedup();
    }

    /// Number of parameters (compliances + free shifts).
    pub fn parameter_count(&self) -> usize {
        self.edofs.len() + self.free_shift.iter().filter(|f| **f).count()
    }

    /// Compact label, e.g. `J1.z J2.z J3.xz δr3 J4.z J5.z`.
    pub fn label(&self) -> String {
        let mut parts = Vec::new();
        let mut sites: Vec<EdofSite> = self.edofs.iter().map(|e| e.0).collect();
        sites.dedup();
        for site in sites {
            let axes: String = self
                .edofs
                .iter()
                .filter(|e| e.0 == site)
                .map(|e| e.1.letter())
                .collect();
            parts.push(format!("{site}.{axes}"));
            if let EdofSite::Joint(i) = site
                && self.free_shift[i - 1]
            {
                parts.push(format!("δr{i}"));
            }
        }
        parts.join(" ")
    }
}

/// How well the data determines an eDoF.
#[derive(Clone, Debug, PartialEq)]
pub enum Status {
    /// Finite 95 % interval on the stiffness.
    Identified,
    /// Positive estimate but the 95 % interval reaches k = ∞ (c interval touches 0).
    Weak,
    /// The data cannot determine it; the reason says why. Left out of the output model.
    NotIdentifiable(String),
}

/// Estimate of one eDoF.
#[derive(Clone, Debug)]
pub struct EdofEstimate {
    /// The eDoF.
    pub id: EdofId,
    /// Label (`J3.x`).
    pub label: String,
    /// Identifiability.
    pub status: Status,
    /// Compliance c = 1/k (rad/(N·m)); 0 when not identifiable.
    pub compliance: f64,
    /// Standard error of the compliance (NaN when unavailable).
    pub compliance_se: f64,
    /// Stiffness k (N·m/rad), `None` when not identifiable.
    pub stiffness: Option<f64>,
    /// Standard error of k by the delta method.
    pub stiffness_se: Option<f64>,
    /// 95 % interval of k (upper bound may be +∞).
    pub interval95: Option<(f64, f64)>,
}

/// Estimate of one joint's centre shift δr.
#[derive(Clone, Debug)]
pub struct ShiftEstimate {
    /// Joint (1-based).
    pub joint: usize,
    /// Value (m).
    pub value_m: f64,
    /// Whether it was fitted.
    pub free: bool,
    /// Standard error (m), when fitted and identifiable.
    pub se_m: Option<f64>,
}

/// Residual statistics (measured − predicted): positions in metres, plus the RMS of the
/// rotation residuals when the data has measured rotations.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ResidualStats {
    /// The position residual of each row (m): per axis x, y, z and of its norm.
    pub position: ErrorStats,
    /// RMS over all position components (the "RMS" of the iteration table, m).
    pub rms_all_m: f64,
    /// RMS over all rotation components (rad) of the rows with a measured rotation; `None`
    /// when no row has one.
    pub rotation_rms_rad: Option<f64>,
}

/// |ρ| from which two estimates are flagged as correlated ([`Calibration::correlated_pairs`]):
/// the campaign determines little more than their combination.
pub const STRONG_CORRELATION: f64 = 0.95;

/// Two estimates whose correlation reaches [`STRONG_CORRELATION`].
#[derive(Clone, Debug, PartialEq)]
pub struct CorrelatedPair {
    /// The first parameter's label (earlier in [`Calibration::parameter_labels`]).
    pub first: String,
    /// The second parameter's label.
    pub second: String,
    /// Their correlation, −1 … +1.
    pub rho: f64,
}

impl std::fmt::Display for CorrelatedPair {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} and {} correlated at ρ = {:+.2}: this campaign determines their combination, not each (add load cases that load one without the other)",
            self.first, self.second, self.rho
        )
    }
}

/// A calibrated model structure with its uncertainty.
#[derive(Clone, Debug)]
pub struct Calibration {
    /// The structure as calibrated (not-identifiable eDoFs removed, shifts at their estimates).
    pub structure: Structure,
    /// Every eDoF of the requested structure, identifiable or not.
    pub edofs: Vec<EdofEstimate>,
    /// Centre shifts of joints with an x or y eDoF, or fitted.
    pub shifts: Vec<ShiftEstimate>,
    /// Labels of the free parameters (rows/columns of [`Calibration::correlation`]).
    pub parameter_labels: Vec<String>,
    /// Parameter correlation matrix.
    pub correlation: DMatrix<f64>,
    /// Condition number of the weighted, column-scaled Jacobian.
    pub condition_number: f64,
    /// Weighted residual sum of squares χ².
    pub chi2: f64,
    /// Degrees of freedom n − p.
    pub dof: usize,
    /// χ²/(n − p); ≈ 1 when the model and σ are right.
    pub reduced_chi2: f64,
    /// Bayesian information criterion `n ln(χ²/n) + p ln n`.
    pub bic: f64,
    /// Residuals.
    pub residuals: ResidualStats,
    /// Number of data rows.
    pub rows: usize,
    /// Number of rows with a measured rotation (3 extra equations each).
    pub rotation_rows: usize,
    /// Non-fatal observations (unobservable eDoFs, …).
    pub warnings: Vec<String>,
}

impl Calibration {
    /// The start robot with this calibration's eDoFs, stiffnesses and centre shifts: a drop-in
    /// robot for every other command. Geometry, limits and tool are kept.
    pub fn to_robot(&self, start: &Robot) -> Robot {
        let mut robot = start.clone();
        for axis in Axis::ALL {
            robot.base_stiffness.set(axis, None);
        }
        for joint in &mut robot.joints {
            joint.stiffness = deflex_model::AxisStiffness::RIGID;
        }
        for est in &self.edofs {
            if let Some(k) = est.stiffness {
                robot.set_stiffness(est.id.0, est.id.1, Some(k));
            }
        }
        for (i, joint) in robot.joints.iter_mut().enumerate() {
            joint.center_shift = self.structure.shifts_m.get(i).copied().unwrap_or(0.0);
        }
        robot
    }

    /// When χ²/dof is well above 1 ([`CHI2_WELL_ABOVE_ONE`]): a note that the intervals cover
    /// the noise, not the model-form error.
    pub fn model_form_note(&self) -> Option<String> {
        (self.reduced_chi2 > CHI2_WELL_ABOVE_ONE).then(|| {
            format!(
                "χ²/dof = {:.2} is well above 1 (more than {CHI2_WELL_ABOVE_ONE}): the residuals are larger than the measurement noise (sigma_m) explains, so the data holds effects this model does not represent (model-form error), or sigma_m is too small. The standard errors and 95 % intervals are scaled by χ²/dof but cover noise only, not model-form error: true stiffnesses may lie outside them.",
                self.reduced_chi2
            )
        })
    }

    /// Every pair of estimates correlated at |ρ| ≥ [`STRONG_CORRELATION`], the strongest first
    /// (ρ_ij = C_ij / √(C_ii C_jj) of the parameter covariance C, the matrix
    /// [`Calibration::correlation`]).
    pub fn correlated_pairs(&self) -> Vec<CorrelatedPair> {
        let p = self
            .parameter_labels
            .len()
            .min(self.correlation.nrows())
            .min(self.correlation.ncols());
        let mut pairs: Vec<CorrelatedPair> = (0..p)
            .flat_map(|i| (i + 1..p).map(move |j| (i, j)))
            .filter(|&(i, j)| self.correlation[(i, j)].abs() >= STRONG_CORRELATION)
            .map(|(i, j)| CorrelatedPair {
                first: self.parameter_labels[i].clone(),
                second: self.parameter_labels[j].clone(),
                rho: self.correlation[(i, j)],
            })
            .collect();
        pairs.sort_by(|a, b| b.rho.abs().total_cmp(&a.rho.abs()));
        pairs
    }

    /// The estimate of one eDoF.
    pub fn edof(&self, id: EdofId) -> Option<&EdofEstimate> {
        self.edofs.iter().find(|e| e.id == id)
    }
}

//! Off-diagonal joint compliances ([`deflex_model::ComplianceCoupling`]) identified together
//! with the eDoF compliances of a calibrated structure.
//!
//! A robot whose two pitch joints share a counterbalance or a casting has a joint compliance
//! `C_θ` that is not diagonal: the torque on J2 turns J3 and the other way round. A diagonal
//! VJM calibration (eq. 11) cannot represent it and bends the nearest diagonal terms instead
//! (a J3.z found softer than it is), which predicts the wrong direction of the deflection for
//! loads the campaign did not hold. The deflection stays linear in every compliance,
//!
//! `δ(P) = Σ_e c_e j_e(P) j_e(A)ᵀ w + Σ_(a,b) c_ab (j_a(P) j_b(A)ᵀ + j_b(P) j_a(A)ᵀ) w`,
//!
//! so the couplings are fitted with the eDoF compliances by the same weighted linear least
//! squares as the rest of the calibration (weights `1/σ` of each row, rotations when measured).
//! The structure (which eDoFs, their centre shifts) is the one given: fit it first
//! ([`crate::stiffness::search_structure`]), then add the couplings here. The result is refused unless every
//! eDoF compliance stays positive and every coupling keeps the joint compliance positive
//! definite (`|c_ab| < √(c_a c_b)`).
//!
//! **Uncertainty**, as the calibration's (module `uncertainty`): the covariance
//! `s² (XᵀX)⁻¹` of the weighted design, `s² = χ²/(n − p)` the fit's reduced chi-square, so that
//! a model the data do not fit widens the intervals; each coupling's correlation
//! `ρ = c_ab/√(c_a c_b)` gets its standard error by the delta method (its gradient in `c_ab`,
//! `c_a`, `c_b` through that covariance). A campaign that does not separate a coupling from the
//! compliances (a singular design) gives infinite standard errors.

use crate::measurements::DEFAULT_SIGMA_M;
use crate::measurements::MeasurementRow;
use crate::stiffness::calibration::Z95;
use crate::stiffness::error::{CalibError, RowsError, StructureError};
use deflex_model::{
    Axis, ComplianceCoupling, Data, EdofSite, MAX_COUPLINGS, Robot, Wrench, edof_screw,
};
use nalgebra::{DMatrix, DVector, Vector3, Vector6};

/// One eDoF: site and axis.
pub type EdofPair = ((EdofSite, Axis), (EdofSite, Axis));

/// What [`fit_couplings`] found.
#[derive(Clone, Debug, PartialEq)]
pub struct CouplingFit {
    /// The robot with the refitted eDoF stiffnesses and the couplings.
    pub robot: Robot,
    /// χ² per degree of freedom of the robot as given (diagonal) on these rows.
    pub reduced_chi2_before: f64,
    /// … and of the refitted robot.
    pub reduced_chi2: f64,
    /// RMS position residual before and after (m).
    pub rms_before_m: f64,
    /// RMS position residual of the refitted robot (m).
    pub rms_m: f64,
    /// Each coupling's correlation `c_ab / √(c_a c_b)`, in `pairs` order.
    pub correlations: Vec<f64>,
    /// Standard error of each coupling's compliance (rad/(N·m)), in `pairs` order.
    pub coupling_se: Vec<f64>,
    /// Standard error of each correlation, in `pairs` order.
    pub correlation_se: Vec<f64>,
    /// Standard error of each eDoF compliance of the refitted robot (rad/(N·m)), in
    /// [`Robot::edofs`] order.
    pub compliance_se: Vec<f64>,
    /// Equations and unknowns of the fit (`n`, `p`).
    pub equations: usize,
    /// Unknowns: the eDoF compliances and the couplings.
    pub unknowns: usize,
}

impl CouplingFit {
    /// The 95 % interval of coupling `k`'s compliance, `c_ab ± 1.96 SE` (rad/(N·m)).
    pub fn interval95(&self, k: usize) -> (f64, f64) {
        let c = self.robot.couplings[k].compliance;
        let half = Z95 * self.coupling_se[k];
        (c - half, c + half)
    }
}

/// The weighted columns of one row: eDoF compliances first (in [`Robot::edofs`] order), then
/// the couplings; position equations, then rotation equations when the row has them.
fn row_columns(
    robot: &Robot,
    data: &Data,
    row: &MeasurementRow,
    pairs: &[EdofPair],
) -> Vec<(Vector6<f64>, usize)> {
    let p = Vector3::from(row.point_m);
    let a = Vector3::from(row.load_point_m);
    let w = Wrench::from_row_slice(&row.wrench);
    let reach = row.point_link.min(row.load_link);
    let screw = |(site, axis): (EdofSite, Axis), at: &Vector3<f64>| {
        let (v, o) = data.edof_axis_center(robot, site, axis);
        edof_screw(&v, &o, at)
    };
    let mut columns = Vec::new();
    for (index, e) in robot.edofs().enumerate() {
        if e.site.link_index() <= reach {
            let key = (e.site, e.axis);
            columns.push((screw(key, &p) * screw(key, &a).dot(&w), index));
        }
    }
    let first = robot.edof_count();
    // θ_a += c τ_b moves P when a lies below P's link and τ_b exists when b lies below the
    // load's link (and the same with a and b swapped): a marker on the upper arm turns with J2
    // under a torque only J3 carries.
    let (point_link, load_link) = (row.point_link, row.load_link);
    for (k, &(ea, eb)) in pairs.iter().enumerate() {
        let (ia, ib) = (ea.0.link_index(), eb.0.link_index());
        let mut column = Vector6::zeros();
        if ia <= point_link && ib <= load_link {
            column += screw(ea, &p) * screw(eb, &a).dot(&w);
        }
        if ib <= point_link && ia <= load_link {
            column += screw(eb, &p) * screw(ea, &a).dot(&w);
        }
        if column != Vector6::zeros() {
            columns.push((column, first + k));
        }
    }
    columns
}

/// Fit the compliances of `robot`'s eDoFs (its centre shifts kept) and the off-diagonal
/// compliances of `pairs` to measurement rows. See the module documentation.
pub fn fit_couplings(
    robot: &Robot,
    rows: &[MeasurementRow],
    pairs: &[EdofPair],
) -> Result<CouplingFit, CalibError> {
    check_pairs(robot, pairs)?;
    crate::stiffness::design::check_rows(robot, rows, true)?;
    let usable: Vec<&MeasurementRow> = rows.iter().filter(|r| r.displacement_m.is_some()).collect();
    let unknowns = robot.edof_count() + pairs.len();
    let rotation_rows = usable.iter().filter(|r| r.rotation_rad.is_some()).count();
    let equations = 3 * usable.len() + 3 * rotation_rows;
    if equations <= unknowns {
        return Err(RowsError::TooFewReadings {
            rows: rows.len(),
            distinct: crate::stiffness::design::distinct_rows(rows),
            equations,
            parameters: unknowns,
        }
        .into());
    }
    let (x, y) = design_matrix(robot, &usable, pairs, equations, unknowns)?;
    let (c, unit_covariance) = scaled_least_squares(&x, &y)?;
    let dof = (equations - unknowns) as f64;
    let chi2 = |parameters: &[f64]| {
        let p = DVector::from_column_slice(parameters);
        (&x * p - &y).norm_squared()
    };
    let rms = |parameters: &[f64]| {
        let p = DVector::from_column_slice(parameters);
        let residual = &x * p - &y;
        let sum: f64 = usable
            .iter()
            .enumerate()
            .map(|(r, row)| {
                let s = row.sigma_m.unwrap_or(DEFAULT_SIGMA_M);
                (0..3)
                    .map(|ax| (residual[3 * r + ax] * s).powi(2))
                    .sum::<f64>()
            })
            .sum();
        (sum / (3 * usable.len()) as f64).sqrt()
    };
    let mut before: Vec<f64> = robot.edofs().map(|e| 1.0 / e.stiffness).collect();
    before.extend(std::iter::repeat_n(0.0, pairs.len()));
    let (fitted, correlations) = coupled_robot(robot, pairs, &c)?;
    let reduced_chi2 = chi2(&c) / dof;
    let covariance = unit_covariance * reduced_chi2;
    let se = |j: usize| covariance[(j, j)].max(0.0).sqrt();
    let edofs = robot.edof_count();
    let correlation_se = pairs
        .iter()
        .enumerate()
        .map(|(k, pair)| correlation_se(robot, pair, &c, edofs + k, &covariance))
        .collect();
    Ok(CouplingFit {
        robot: fitted,
        reduced_chi2_before: chi2(&before) / dof,
        reduced_chi2,
        rms_before_m: rms(&before),
        rms_m: rms(&c),
        correlations,
        coupling_se: (edofs..unknowns).map(se).collect(),
        correlation_se,
        compliance_se: (0..edofs).map(se).collect(),
        equations,
        unknowns,
    })
}

/// Standard error of `ρ = c_ab / √(c_a c_b)` by the delta method: the gradient
/// `(∂ρ/∂c_ab, ∂ρ/∂c_a, ∂ρ/∂c_b) = (1/√(c_a c_b), −ρ/(2 c_a), −ρ/(2 c_b))` through the
/// covariance of the three.
fn correlation_se(
    robot: &Robot,
    &(a, b): &EdofPair,
    c: &[f64],
    coupling: usize,
    covariance: &DMatrix<f64>,
) -> f64 {
    let index = |(site, axis): (EdofSite, Axis)| {
        robot.edofs().position(|e| e.site == site && e.axis == axis)
    };
    let (Some(ia), Some(ib)) = (index(a), index(b)) else {
        return f64::NAN;
    };
    let (ca, cb) = (c[ia], c[ib]);
    let root = (ca * cb).sqrt();
    let rho = c[coupling] / root;
    let gradient = [
        (coupling, 1.0 / root),
        (ia, -rho / (2.0 * ca)),
        (ib, -rho / (2.0 * cb)),
    ];
    let mut variance = 0.0;
    for &(i, gi) in &gradient {
        for &(j, gj) in &gradient {
            variance += gi * gj * covariance[(i, j)];
        }
    }
    variance.max(0.0).sqrt()
}

/// The couplings asked for: 1 to [`MAX_COUPLINGS`], each end an eDoF of the robot.
fn check_pairs(robot: &Robot, pairs: &[EdofPair]) -> Result<(), CalibError> {
    let label = |(a, b): &EdofPair| {
        ComplianceCoupling {
            a: *a,
            b: *b,
            compliance: 0.0,
        }
        .label()
    };
    if pairs.is_empty() || pairs.len() > MAX_COUPLINGS {
        return Err(StructureError::Coupling {
            label: String::new(),
            reason: format!(
                "expected 1 to {MAX_COUPLINGS} couplings, got {}",
                pairs.len()
            ),
        }
        .into());
    }
    for pair in pairs {
        for (site, axis) in [pair.0, pair.1] {
            if robot.stiffness(site, axis).is_none() {
                let edofs: Vec<String> = robot.edofs().map(|e| e.label()).collect();
                return Err(StructureError::Coupling {
                    label: label(pair),
                    reason: format!(
                        "{site}.{} is not an eDoF of the robot (its eDoFs: {})",
                        axis.letter(),
                        edofs.join(" ")
                    ),
                }
                .into());
            }
        }
    }
    Ok(())
}

/// The weighted design matrix and right-hand side: per usable row, its displacement (and
/// rotation, when measured) against the columns of every eDoF compliance and coupling, each
/// equation divided by its σ.
fn design_matrix(
    robot: &Robot,
    usable: &[&MeasurementRow],
    pairs: &[EdofPair],
    equations: usize,
    unknowns: usize,
) -> Result<(DMatrix<f64>, DVector<f64>), CalibError> {
    let mut x = DMatrix::<f64>::zeros(equations, unknowns);
    let mut y = DVector::<f64>::zeros(equations);
    let mut data = Data::new();
    let mut next_rotation = 3 * usable.len();
    for (r, row) in usable.iter().enumerate() {
        robot.forward_kinematics(&mut data, &row.q_rad)?;
        let s = row.sigma_m.unwrap_or(DEFAULT_SIGMA_M);
        let d = row.displacement_m.unwrap_or([0.0; 3]);
        let rotation = row.rotation_rad.map(|m| {
            let e0 = next_rotation;
            next_rotation += 3;
            (e0, m.value_rad, m.sigma())
        });
        for ax in 0..3 {
            y[3 * r + ax] = d[ax] / s;
        }
        if let Some((e0, value, sr)) = rotation {
            for ax in 0..3 {
                y[e0 + ax] = value[ax] / sr;
            }
        }
        for (column, index) in row_columns(robot, &data, row, pairs) {
            for ax in 0..3 {
                x[(3 * r + ax, index)] = column[ax] / s;
            }
            if let Some((e0, _, sr)) = rotation {
                for ax in 0..3 {
                    x[(e0 + ax, index)] = column[3 + ax] / sr;
                }
            }
        }
    }
    if !(x.iter().all(|v| v.is_finite()) && y.iter().all(|v| v.is_finite())) {
        return Err(RowsError::Overflow.into());
    }
    Ok((x, y))
}

/// The least-squares solution of `x c = y` with the columns scaled to unit norm (SVD, singular
/// values below 10⁻¹² of the largest dropped), in the original units, and `(xᵀx)⁻¹` (infinite
/// on the diagonal when a singular value was dropped: the design does not separate the
/// parameters).
fn scaled_least_squares(
    x: &DMatrix<f64>,
    y: &DVector<f64>,
) -> Result<(Vec<f64>, DMatrix<f64>), CalibError> {
    let unknowns = x.ncols();
    // Column scaling: compliances span orders of magnitude (base tilt vs wrist).
    let scale: Vec<f64> = (0..unknowns)
        .map(|j| {
            let n = x.column(j).norm();
            if n > 0.0 { 1.0 / n } else { 1.0 }
        })
        .collect();
    let mut xs = x.clone();
    for (j, s) in scale.iter().enumerate() {
        xs.column_mut(j).scale_mut(*s);
    }
    let svd = xs.svd(true, true);
    let smax = svd.singular_values.max();
    let floor = smax * 1e-12;
    let solution = svd.solve(y, floor).map_err(|_| RowsError::Overflow)?;
    let c: Vec<f64> = (0..unknowns).map(|j| solution[j] * scale[j]).collect();
    let covariance = match &svd.v_t {
        Some(v_t) if svd.singular_values.iter().all(|&s| s > floor) => {
            // (xsᵀ xs)⁻¹ = V S⁻² Vᵀ; c = D c_s, so cov(c) = D V S⁻² Vᵀ D.
            let mut v = v_t.transpose();
            for (k, s) in svd.singular_values.iter().enumerate() {
                v.column_mut(k).scale_mut(1.0 / s);
            }
            let unscaled = &v * v.transpose();
            DMatrix::from_fn(unknowns, unknowns, |i, j| {
                unscaled[(i, j)] * scale[i] * scale[j]
            })
        }
        _ => DMatrix::from_fn(
            unknowns,
            unknowns,
            |i, j| {
                if i == j { f64::INFINITY } else { 0.0 }
            },
        ),
    };
    Ok((c, covariance))
}

/// The robot with the fitted compliances `c` (eDoFs first, then the couplings) and each
/// coupling's correlation; refused when a compliance is not a spring or the joint compliance
/// would not be positive definite.
fn coupled_robot(
    robot: &Robot,
    pairs: &[EdofPair],
    c: &[f64],
) -> Result<(Robot, Vec<f64>), CalibError> {
    let mut fitted = robot.clone();
    let edofs: Vec<_> = robot.edofs().collect();
    for (e, &ce) in edofs.iter().zip(c) {
        if !(ce.is_finite() && ce > 0.0) {
            return Err(StructureError::Coupling {
                label: e.label(),
                reason: format!(
                    "with the couplings its compliance comes out {ce:e} rad/(N·m): not a spring (the campaign does not separate them)"
                ),
            }
            .into());
        }
        fitted.set_stiffness(e.site, e.axis, Some(1.0 / ce));
    }
    fitted.couplings = pairs
        .iter()
        .zip(&c[edofs.len()..])
        .map(|(&(a, b), &compliance)| ComplianceCoupling { a, b, compliance })
        .collect();
    let correlations: Vec<f64> = fitted
        .couplings
        .iter()
        .map(|k| k.correlation(&fitted).unwrap_or(f64::NAN))
        .collect();
    if let Some((k, rho)) = correlations
        .iter()
        .enumerate()
        .find(|(_, rho)| rho.is_nan() || rho.abs() >= 1.0)
    {
        return Err(StructureError::Coupling {
            label: fitted.couplings[k].label(),
            reason: format!(
                "correlation {rho:.3}: the joint compliance would not be positive definite"
            ),
        }
        .into());
    }
    fitted
        .validate("coupling fit")
        .map_err(|e| StructureError::Coupling {
            label: String::new(),
            reason: e.to_string(),
        })?;
    Ok((fitted, correlations))
}

//! The model over batches of configurations: pose, Jacobian, compliance (eq. 15's
//! `C = J K_θ⁻¹ Jᵀ`), deflection `δs = C w`, gravity sag and inverse kinematics, spread over the
//! cores with rayon (Python's `deflex.Robot`). Arrays are row-major `f64` slices: `q` is
//! `rows × n`, a wrench `rows × 6` (or one row for all), a pose a 4×4 homogeneous matrix (16
//! values, row-major).

use crate::error::{Error, Result};
use deflex_model::{Data, IkOptions, Pose, Robot, Wrench};
use nalgebra::{Matrix3, Rotation3, Translation3, Vector3};
use rayon::prelude::*;

/// Rows per rayon task: large enough that scheduling costs nothing next to the maths
/// (a deflection is ≈ 0.3 µs), small enough to balance two to a few dozen cores. Public so that
/// a test can place rows on both sides of a split.
pub const ROWS_PER_TASK: usize = 2048;

/// Below this many rows the batch runs on the calling thread (no pool wake-up).
const SERIAL_ROWS: usize = 256;

/// Refuse NaN and infinities, naming the first one as `name[row, col]` (`name[i]` when `cols`
/// is `None`, for 1-D arguments).
pub fn check_finite(name: &'static str, values: &[f64], cols: Option<usize>) -> Result<()> {
    match values.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(i) => Err(Error::NonFinite {
            name,
            index: match cols {
                Some(c) if c > 0 => format!("{}, {}", i / c, i % c),
                _ => i.to_string(),
            },
            value: values[i],
        }),
    }
}

/// `f(data, row, out_row)` for every row, `out` holding `out_cols` values per row; in parallel
/// over chunks of rows with one scratch [`Data`] per task. The first error (lowest chunk) wins.
fn for_rows(
    rows: usize,
    out_cols: usize,
    out: &mut [f64],
    f: impl Fn(&mut Data, usize, &mut [f64]) -> Result<()> + Sync,
) -> Result<()> {
    debug_assert_eq!(out.len(), rows * out_cols);
    if out_cols == 0 {
        return Ok(());
    }
    let run_chunk = |chunk_index: usize, chunk: &mut [f64], data: &mut Data| -> Result<()> {
        let first = chunk_index * ROWS_PER_TASK;
        for (k, row_out) in chunk.chunks_mut(out_cols).enumerate() {
            f(data, first + k, row_out)?;
        }
        Ok(())
    };
    if rows < SERIAL_ROWS {
        let mut data = Data::new();
        return run_chunk(0, out, &mut data);
    }
    out.par_chunks_mut(ROWS_PER_TASK * out_cols)
        .enumerate()
        .try_for_each_init(Data::new, |data, (i, chunk)| run_chunk(i, chunk, data))
}

/// Row `i` of `values`, a row-major `rows × cols` array (panics when `i` is not a row of it).
#[inline]
pub fn row(values: &[f64], cols: usize, i: usize) -> &[f64] {
    &values[i * cols..(i + 1) * cols]
}

/// Forward kinematics of one row (its length is checked by the callers).
#[inline]
fn fk(robot: &Robot, data: &mut Data, q: &[f64]) -> Result<()> {
    robot
        .forward_kinematics(data, q)
        .map_err(deflex_model::ModelError::from)?;
    Ok(())
}

/// Write a pose as a row-major 4×4 homogeneous matrix.
#[inline]
pub fn write_pose(pose: &Pose, out: &mut [f64]) {
    let m = pose.to_homogeneous();
    for r in 0..4 {
        for c in 0..4 {
            out[r * 4 + c] = m[(r, c)];
        }
    }
}

/// TCP poses (eq. 1), `rows × 16` (4×4 row-major).
pub fn poses(robot: &Robot, q: &[f64], rows: usize) -> Result<Vec<f64>> {
    let n = robot.joint_count();
    let mut out = vec![0.0; rows * 16];
    for_rows(rows, 16, &mut out, |data, i, o| {
        fk(robot, data, row(q, n, i))?;
        write_pose(&data.tcp, o);
        Ok(())
    })?;
    Ok(out)
}

/// Geometric Jacobians of the motorised joints at the TCP, `rows × 6 × n` (row-major 6×n).
pub fn jacobians(robot: &Robot, q: &[f64], rows: usize) -> Result<Vec<f64>> {
    let n = robot.joint_count();
    let mut out = vec![0.0; rows * 6 * n];
    for_rows(rows, 6 * n, &mut out, |data, i, o| {
        fk(robot, data, row(q, n, i))?;
        let columns = robot.geometric_jacobian_columns(data, &data.tcp_position());
        for (c, column) in columns.iter().take(n).enumerate() {
            for r in 0..6 {
                o[r * n + c] = column[r];
            }
        }
        Ok(())
    })?;
    Ok(out)
}

/// Cartesian compliances at the TCP, `C = J K_θ⁻¹ Jᵀ` (eq. 15), `rows × 36` (row-major 6×6).
pub fn compliances(robot: &Robot, q: &[f64], rows: usize) -> Result<Vec<f64>> {
    let n = robot.joint_count();
    let mut out = vec![0.0; rows * 36];
    for_rows(rows, 36, &mut out, |data, i, o| {
        fk(robot, data, row(q, n, i))?;
        let c = robot.compliance_matrix(data);
        for r in 0..6 {
            for k in 0..6 {
                o[r * 6 + k] = c[(r, k)];
            }
        }
        Ok(())
    })?;
    Ok(out)
}

/// TCP deflections `δs = J K_θ⁻¹ Jᵀ w` (eq. 15), `rows × 6`; `wrench` has one row for every
/// configuration or `rows` rows (world axes, moment about the TCP).
pub fn deflections(robot: &Robot, q: &[f64], rows: usize, wrench: &[f64]) -> Result<Vec<f64>> {
    let n = robot.joint_count();
    let shared = wrench.len() == 6;
    let mut out = vec![0.0; rows * 6];
    for_rows(rows, 6, &mut out, |data, i, o| {
        fk(robot, data, row(q, n, i))?;
        let w = if shared { wrench } else { row(wrench, 6, i) };
        let d = robot.tcp_deflection(data, &Wrench::from_row_slice(w));
        o.copy_from_slice(d.as_slice());
        Ok(())
    })?;
    Ok(out)
}

/// A pose from a row-major 4×4 homogeneous matrix: bottom row `[0, 0, 0, 1]` and an
/// orthonormal, right-handed rotation block (to 1e-9), else an error naming `what`.
pub fn pose_from_matrix(m: &[f64], what: &str) -> Result<Pose> {
    let r = Matrix3::new(m[0], m[1], m[2], m[4], m[5], m[6], m[8], m[9], m[10]);
    let deviation = (r.transpose() * r - Matrix3::identity()).amax();
    if !(deviation < 1e-9 && (r.determinant() - 1.0).abs() < 1e-9) {
        return Err(Error::invalid(
            what,
            format!(
                "the rotation block is not a rotation (RᵀR − I has an entry of {deviation:.1e}, det R = {:.6})",
                r.determinant()
            ),
        ));
    }
    if m[12] != 0.0 || m[13] != 0.0 || m[14] != 0.0 || m[15] != 1.0 {
        return Err(Error::invalid(
            what,
            format!(
                "the bottom row of a homogeneous matrix is [0, 0, 0, 1], got [{}, {}, {}, {}]",
                m[12], m[13], m[14], m[15]
            ),
        ));
    }
    Ok(Pose::from_parts(
        Translation3::new(m[3], m[7], m[11]),
        Rotation3::from_matrix_unchecked(r),
    ))
}

/// What [`inverse_kinematics`] does with a pose it cannot reach.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OnFailure {
    /// Fail the whole call with the first failure (lowest index).
    Raise,
    /// Fill the pose's row with NaN.
    Nan,
}

impl std::str::FromStr for OnFailure {
    type Err = Error;

    /// `raise` or `nan` (Python's `on_failure=`).
    fn from_str(text: &str) -> Result<OnFailure> {
        match text {
            "raise" => Ok(OnFailure::Raise),
            "nan" => Ok(OnFailure::Nan),
            other => Err(Error::invalid(
                "on_failure",
                format!("expected \"raise\" or \"nan\", got \"{other}\""),
            )),
        }
    }
}

/// Joint values reaching each target TCP pose (`rows × 16`, 4×4 row-major, world frame), from
/// `seeds` (one row for all, or `rows` rows, rad): the seed first, then the model's 36 spread
/// seeds (`deflex ik`). Returns `rows × n`.
pub fn inverse_kinematics(
    robot: &Robot,
    targets: &[f64],
    rows: usize,
    seeds: &[f64],
    on_failure: OnFailure,
) -> Result<Vec<f64>> {
    let n = robot.joint_count();
    let shared = seeds.len() == n;
    let options = IkOptions::default();
    let mut out = vec![0.0; rows * n];
    for_rows(rows, n, &mut out, |_, i, o| {
        let what = if rows == 1 {
            "pose".to_string()
        } else {
            format!("pose[{i}]")
        };
        let target = pose_from_matrix(row(targets, 16, i), &what)?;
        let seed = if shared { seeds } else { row(seeds, n, i) };
        match robot.inverse_kinematics_search(&target, Some(seed), &options) {
            Ok(solution) => o.copy_from_slice(&solution.q),
            Err(e) => match on_failure {
                OnFailure::Nan => o.fill(f64::NAN),
                OnFailure::Raise => {
                    let t = target.translation.vector * 1e3;
                    return Err(Error::invalid(
                        what,
                        format!("{e} (target {:.3}, {:.3}, {:.3} mm)", t.x, t.y, t.z),
                    ));
                }
            },
        }
        Ok(())
    })?;
    Ok(out)
}

/// Sag of the TCP under the arm's own weight and payload `[δp; δφ]` (m, rad), when the model
/// knows its masses (as `deflex pose` prints it), `rows × 6`; `None` without masses.
pub fn gravity_sags(robot: &Robot, q: &[f64], rows: usize) -> Result<Option<Vec<f64>>> {
    if !super::knows_masses(robot) {
        return Ok(None);
    }
    let n = robot.joint_count();
    let mut out = vec![0.0; rows * 6];
    for_rows(rows, 6, &mut out, |data, i, o| {
        fk(robot, data, row(q, n, i))?;
        let p: Vector3<f64> = data.tcp_position();
        let d = robot.gravity_displacement(data, &p, n);
        o.copy_from_slice(d.as_slice());
        Ok(())
    })?;
    Ok(Some(out))
}

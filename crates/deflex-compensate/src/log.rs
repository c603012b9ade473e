//! Logged forces of a previous run as a wrench source: the `deflex run` log (one row per control
//! cycle, `crates/deflex-control/src/log.rs`) or the `deflex sim isf` log (`log.csv`, 50 Hz,
//! SIMULATED), read and resampled on the path's arc length.
//!
//! ## Reading
//!
//! * **`deflex run` log**: columns `q1_rad … qN_rad` (the robot's reported joints), the TCP
//!   wrench `w_fx_n … w_mz_nm` (base axes, eq. 2) and `flags`. The TCP position of a row is the
//!   robot model's forward kinematics of its joints (the *commanded* TCP: the robot reports motor
//!   positions, which do not see the deflection). Rows flagged taring, stale wrench, latched or
//!   with any fault bit (`flags & 0x601F`, the bits of `deflex_control::safety::Flags`) are
//!   skipped: their wrench is not a measurement of the process.
//! * **`deflex sim isf` log**: columns `des_x_mm … des_z_mm` (the desired TCP in the part frame)
//!   and the contact wrench `fx_N … mz_Nm` (part-frame axes); positions are mapped to the world
//!   with the part frame. Marked SIMULATED when its header says so.
//!
//! ## Resampling on arc length
//!
//! Each usable row is projected on the path polyline, **monotonically**: from the segment of
//! the previous row, over a window of [`ResampleOptions::window_m`] of arc length ahead (at least
//! three times the distance between the two rows), the closest point. The window keeps a helical
//! path's neighbouring turn (0.24 mm below on the paper's cone) from capturing the projection
//! even when the logged positions are several millimetres off the path (a compensated or
//! corrected run). The search starts at the path's first point, so the log must be of a run
//! of this path from its start (rows before the tool reaches the start, an approach or a dwell
//! elsewhere, are skipped as off the path). Rows farther than
//! [`ResampleOptions::max_offset_m`] from the path are counted and skipped.
//!
//! **The rows as the tool moved along the path.** Only a row that advances along the path
//! (its arc length beyond the last kept row's by more than 1 µm) is kept: a standstill logs a
//! pile of rows at one place (a dwell, the end of the program with the force fading while the
//! tool rests, a pause in contact), and averaging them with the few rows of the pass would
//! weigh the pass by the time spent, not by the path. On an unseen plant, 200 rows logged at
//! rest at the end swamped the 12 moving rows of the last millimetre and halved the last
//! waypoints' force (the compensation then cut the max error 3.36 → 1.63 mm instead of
//! → 0.18 mm). The kept rows define the wrench as a function of arc length, linear between
//! rows (weighted by path advance); each path point gets its mean over ±
//! [`ResampleOptions::half_width_m`] of arc length (a box filter against sensor noise,
//! integrated exactly over the linear pieces; 0: the value itself), the window cut at the
//! ends of the log. Path points beyond the logged arc length by more than
//! [`ResampleOptions::coverage_tolerance_m`] are an error: the log does not cover the path.

use crate::error::LogError;
use crate::path::TcpPath;
use deflex_model::{Data, Pose, Robot, Wrench};
use nalgebra::Vector3;
use std::collections::HashMap;
use std::path::Path;

/// Largest log read (bytes).
pub const MAX_LOG_BYTES: u64 = 1 << 30;
/// Largest number of rows read.
pub const MAX_LOG_ROWS: usize = 20_000_000;
/// `deflex run` flag bits whose rows are skipped: the eleven fault bits, latched, taring and
/// stale wrench (`deflex_control::safety::Flags`; a test in deflex-cli checks the bits against
/// it, since this crate does not depend on the controller).
pub const RUN_LOG_SKIP_FLAGS: u32 = 0x7FF | (1 << 16) | (1 << 21) | (1 << 22);

/// Which program wrote the log.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LogKind {
    /// `deflex run` (the real-time controller).
    DeflexRun,
    /// `deflex sim isf` (the twin).
    SimIsf,
}

impl LogKind {
    /// Name for reports.
    pub fn name(self) -> &'static str {
        match self {
            LogKind::DeflexRun => "deflex run log",
            LogKind::SimIsf => "deflex sim isf log",
        }
    }
}

/// One usable row: the TCP position (world, m) and the wrench on the tool (world axes, at the
/// TCP).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogSample {
    /// TCP position (world, m).
    pub position_m: Vector3<f64>,
    /// Wrench on the tool (N, N·m).
    pub wrench: Wrench,
}

/// A log read for resampling.
#[derive(Clone, Debug, PartialEq)]
pub struct WrenchLog {
    /// Which program wrote it.
    pub kind: LogKind,
    /// The file (for messages).
    pub file: String,
    /// Usable rows, in order.
    pub samples: Vec<LogSample>,
    /// Rows skipped for their flags.
    pub skipped_rows: usize,
    /// The log comes from the twin.
    pub simulated: bool,
}

/// Read a log file (see [`parse_log`]); refuses files over [`MAX_LOG_BYTES`].
pub fn read_log(path: &Path, robot: &Robot, part_frame: &Pose) -> Result<WrenchLog, LogError> {
    let file = path.display().to_string();
    // A regular file of at most MAX_LOG_BYTES, counted while reading.
    let text = deflex_files::read_bounded(path, MAX_LOG_BYTES).map_err(|e| match e.problem() {
        Some(deflex_files::InputProblem::TooLarge { read, .. }) => LogError::TooLarge {
            file: file.clone(),
            message: format!("more than {MAX_LOG_BYTES} bytes (stopped reading after {read})"),
        },
        _ => LogError::Io {
            file: file.clone(),
            message: e.into_io().to_string(),
        },
    })?;
    parse_log(&text, &file, robot, part_frame)
}

const RUN_WRENCH: [&str; 6] = [
    "w_fx_n", "w_fy_n", "w_fz_n", "w_mx_nm", "w_my_nm", "w_mz_nm",
];
const ISF_POSITION: [&str; 3] = ["des_x_mm", "des_y_mm", "des_z_mm"];
const ISF_WRENCH: [&str; 6] = ["fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm"];

/// Parse log text. `robot` gives the forward kinematics of a `deflex run` log's joints and must
/// have its joint count; `part_frame` (world) places a `sim isf` log's part-frame positions and
/// wrenches.
pub fn parse_log(
    text: &str,
    file: &str,
    robot: &Robot,
    part_frame: &Pose,
) -> Result<WrenchLog, LogError> {
    let simulated = text
        .lines()
        .take_while(|l| l.starts_with('#'))
        .any(|l| l.contains("SIMULATED"));
    let mut reader = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let csv_error = |e: csv::Error| LogError::Csv {
        file: file.to_string(),
        line: e.position().map_or(0, |p| p.line() as usize),
        message: e.to_string(),
    };
    let header = reader.headers().map_err(csv_error)?.clone();
    let columns: HashMap<&str, usize> = header.iter().enumerate().map(|(i, h)| (h, i)).collect();
    let find = |names: &[&str]| -> Result<Vec<usize>, Vec<String>> {
        let missing: Vec<String> = names
            .iter()
            .filter(|n| !columns.contains_key(*n))
            .map(|n| n.to_string())
            .collect();
        if missing.is_empty() {
            Ok(names.iter().map(|n| columns[n]).collect())
        } else {
            Err(missing)
        }
    };
    let joint_columns: Vec<usize> = (1..)
        .map_while(|i| columns.get(format!("q{i}_rad").as_str()).copied())
        .collect();
    let run = find(&RUN_WRENCH).and_then(|w| find(&["flags"]).map(|f| (w, f[0])));
    let isf = find(&ISF_POSITION).and_then(|p| find(&ISF_WRENCH).map(|w| (p, w)));
    let kind = match (&run, &isf) {
        (Ok(_), _) if !joint_columns.is_empty() => LogKind::DeflexRun,
        (_, Ok(_)) => LogKind::SimIsf,
        (Ok(_), Err(_)) => {
            return Err(LogError::UnknownKind {
                file: file.to_string(),
                missing: "q1_rad".into(),
            });
        }
        (Err(run_missing), Err(isf_missing)) => {
            let missing = if run_missing.len() <= isf_missing.len() {
                run_missing
            } else {
                isf_missing
            };
            return Err(LogError::UnknownKind {
                file: file.to_string(),
                missing: missing.join(", "),
            });
        }
    };
    if kind == LogKind::DeflexRun && joint_columns.len() != robot.joint_count() {
        return Err(LogError::JointCount {
            file: file.to_string(),
            log: joint_columns.len(),
            robot: robot.joint_count(),
        });
    }
    let mut samples = Vec::new();
    let mut skipped_rows = 0;
    let mut data = Data::new();
    let mut q = vec![0.0; joint_columns.len()];
    for (row_index, record) in reader.records().enumerate() {
        if row_index >= MAX_LOG_ROWS {
            return Err(LogError::TooLarge {
                file: file.to_string(),
                message: format!("more than {MAX_LOG_ROWS} rows"),
            });
        }
        let record = record.map_err(csv_error)?;
        let line = record.position().map_or(0, |p| p.line() as usize);
        let number = |column: usize| -> Result<f64, LogError> {
            let text = record.get(column).unwrap_or("");
            text.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| LogError::BadValue {
                    file: file.to_string(),
                    line,
                    column: header.get(column).unwrap_or("?").to_string(),
                    value: text.to_string(),
                })
        };
        let sample = match (kind, &run, &isf) {
            (LogKind::DeflexRun, Ok((wrench_columns, flags_column)), _) => {
                let flags_text = record.get(*flags_column).unwrap_or("");
                let flags: u32 = flags_text.parse().map_err(|_| LogError::BadValue {
                    file: file.to_string(),
                    line,
                    column: "flags".into(),
                    value: flags_text.to_string(),
                })?;
                if flags & RUN_LOG_SKIP_FLAGS != 0 {
                    skipped_rows += 1;
                    continue;
                }
                for (value, column) in q.iter_mut().zip(&joint_columns) {
                    *value = number(*column)?;
                }
                robot
                    .forward_kinematics(&mut data, &q)
                    .expect("joint count checked");
                let mut w = Wrench::zeros();
                for (k, column) in wrench_columns.iter().enumerate() {
                    w[k] = number(*column)?;
                }
                LogSample {
                    position_m: data.tcp_position(),
                    wrench: w,
                }
            }
            (LogKind::SimIsf, _, Ok((position_columns, wrench_columns))) => {
                let mut p = Vector3::zeros();
                for (k, column) in position_columns.iter().enumerate() {
                    p[k] = number(*column)? * 1e-3;
                }
                let mut f = Vector3::zeros();
                let mut m = Vector3::zeros();
                for (k, column) in wrench_columns.iter().enumerate() {
                    let v = number(*column)?;
                    if k < 3 {
                        f[k] = v;
                    } else {
                        m[k - 3] = v;
                    }
                }
                let r = part_frame.rotation;
                let (f, m) = (r * f, r * m);
                LogSample {
                    position_m: (part_frame * nalgebra::Point3::from(p)).coords,
                    wrench: Wrench::new(f.x, f.y, f.z, m.x, m.y, m.z),
                }
            }
            _ => unreachable!("the kind was chosen from the columns found"),
        };
        samples.push(sample);
    }
    Ok(WrenchLog {
        kind,
        file: file.to_string(),
        samples,
        skipped_rows,
        simulated,
    })
}

/// Settings of [`resample_on_path`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResampleOptions {
    /// Arc length searched ahead of the previous row's projection (m).
    pub window_m: f64,
    /// Rows farther than this from the path are skipped (m).
    pub max_offset_m: f64,
    /// Half width of the box filter on arc length (m); 0: plain linear interpolation.
    pub half_width_m: f64,
    /// Path points this far before the first or after the last logged arc length get the first
    /// or last wrench; farther ones make the log not cover the path (m).
    pub coverage_tolerance_m: f64,
}

impl Default for ResampleOptions {
    fn default() -> Self {
        ResampleOptions {
            window_m: 0.005,
            max_offset_m: 0.02,
            half_width_m: 0.0005,
            coverage_tolerance_m: 0.002,
        }
    }
}

/// Wrenches on the path points from a log.
#[derive(Clone, Debug, PartialEq)]
pub struct Resampled {
    /// One per path point.
    pub wrenches: Vec<Wrench>,
    /// Rows used (near the path, advancing along it).
    pub used_rows: usize,
    /// Rows near the path that did not advance along it (a standstill, a backward jitter):
    /// not used.
    pub standstill_rows: usize,
    /// Rows skipped because they lie farther than `max_offset_m` from the path.
    pub off_path_rows: usize,
    /// Arc length of the first and last used row (m).
    pub covered_m: [f64; 2],
    /// Largest distance of a used row from the path (m).
    pub max_offset_m: f64,
}

/// A kept row must lie this far along the path beyond the previous kept one (m): more than the
/// jitter of a robot at rest (encoder noise, the inverse kinematics of a log's joints), less
/// than a row's advance at the slowest feed worth compensating.
const ADVANCE_M: f64 = 1e-6;

/// The wrench as a function of arc length: linear between the kept rows `(s_k, w_k)` (strictly
/// increasing `s`), with its running integral `P_k = ∫_{s_0}^{s_k} w ds` (trapezoids, exact for
/// the linear pieces).
struct Profile {
    knots: Vec<(f64, Wrench)>,
    integral: Vec<Wrench>,
}

impl Profile {
    fn new(knots: Vec<(f64, Wrench)>) -> Profile {
        let mut integral = Vec::with_capacity(knots.len());
        let mut sum = Wrench::zeros();
        integral.push(sum);
        for pair in knots.windows(2) {
            sum += (pair[0].1 + pair[1].1) * (0.5 * (pair[1].0 - pair[0].0));
            integral.push(sum);
        }
        Profile { knots, integral }
    }

    /// The piece holding `s` (clamped): `k` with `s_k ≤ s ≤ s_{k+1}`.
    fn piece(&self, s: f64) -> usize {
        let k = self.knots.partition_point(|(sk, _)| *sk <= s);
        k.saturating_sub(1).min(self.knots.len().saturating_sub(2))
    }

    /// `w(s)`, clamped to the first and last rows outside them.
    fn value(&self, s: f64) -> Wrench {
        let n = self.knots.len();
        if n == 1 || s <= self.knots[0].0 {
            return self.knots[0].1;
        }
        if s >= self.knots[n - 1].0 {
            return self.knots[n - 1].1;
        }
        let k = self.piece(s);
        let (s0, w0) = self.knots[k];
        let (s1, w1) = self.knots[k + 1];
        w0 + (w1 - w0) * ((s - s0) / (s1 - s0))
    }

    /// `∫_{s_0}^{x} w ds` for `x` within the rows.
    fn integral_to(&self, x: f64) -> Wrench {
        let k = self.piece(x);
        let (s0, w0) = self.knots[k];
        let (s1, w1) = self.knots[(k + 1).min(self.knots.len() - 1)];
        let t = if s1 > s0 { (x - s0) / (s1 - s0) } else { 0.0 };
        self.integral[k] + (w0 + (w1 - w0) * (0.5 * t)) * (x - s0)
    }

    /// The mean of `w` over `[s − h, s + h]` cut to the rows (the value at `s` when `h = 0` or
    /// the cut window is empty).
    fn mean(&self, s: f64, h: f64) -> Wrench {
        let n = self.knots.len();
        let a = (s - h).max(self.knots[0].0);
        let b = (s + h).min(self.knots[n - 1].0);
        if h <= 0.0 || b - a <= ADVANCE_M {
            return self.value(s);
        }
        (self.integral_to(b) - self.integral_to(a)) / (b - a)
    }
}

/// Closest point of segment `j` of the path to `p`: `(distance, arc length)`.
fn project(path: &TcpPath, j: usize, p: &Vector3<f64>) -> (f64, f64) {
    let points = path.points();
    let a = points[j].pose.translation.vector;
    let b = points[j + 1].pose.translation.vector;
    let ab = b - a;
    let length2 = ab.norm_squared();
    let t = if length2 > 0.0 {
        ((p - a).dot(&ab) / length2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let closest = a + ab * t;
    (
        (p - closest).norm(),
        points[j].arc_length_m + t * length2.sqrt(),
    )
}

/// Resample a log's wrenches on the path's points (see the module documentation).
pub fn resample_on_path(
    log: &WrenchLog,
    path: &TcpPath,
    options: &ResampleOptions,
) -> Result<Resampled, LogError> {
    let segments = path.len() - 1;
    let mut located: Vec<(f64, Wrench)> = Vec::with_capacity(log.samples.len());
    let mut off_path_rows = 0;
    let mut max_offset: f64 = 0.0;
    let mut current: usize = 0;
    let mut current_s: f64 = 0.0;
    let mut last_position: Option<Vector3<f64>> = None;
    for sample in &log.samples {
        let p = &sample.position_m;
        let j = current;
        let step = last_position.map_or(0.0, |q| (p - q).norm());
        // The window runs ahead of the last row's place on the path, not of its segment's
        // start: a segment longer than the window must not hide the next one.
        let reach = current_s.max(path.points()[j].arc_length_m) + options.window_m.max(3.0 * step);
        let range_end = path.points()[j..]
            .partition_point(|pt| pt.arc_length_m <= reach)
            .max(1)
            + j;
        let range_start = j;
        let range_end = range_end.max(range_start + 1).min(segments);
        let mut best: Option<(f64, f64, usize)> = None;
        for k in range_start..range_end {
            let (distance, s) = project(path, k, p);
            if best.is_none_or(|(d, _, _)| distance < d) {
                best = Some((distance, s, k));
            }
        }
        match best {
            Some((distance, s, k)) if distance <= options.max_offset_m => {
                max_offset = max_offset.max(distance);
                current = k;
                current_s = s;
                last_position = Some(*p);
                located.push((s, sample.wrench));
            }
            _ => off_path_rows += 1,
        }
    }
    if located.is_empty() {
        return Err(LogError::NoRowNearPath {
            file: log.file.clone(),
            rows: log.samples.len(),
            max_offset_mm: options.max_offset_m * 1e3,
        });
    }
    // The rows as the tool moved: each kept row advances along the path.
    let located_rows = located.len();
    let mut knots: Vec<(f64, Wrench)> = Vec::with_capacity(located.len());
    for (s, w) in located {
        if knots.last().is_none_or(|(last, _)| s > last + ADVANCE_M) {
            knots.push((s, w));
        }
    }
    let standstill_rows = located_rows - knots.len();
    let first = knots[0].0;
    let last = knots[knots.len() - 1].0;
    let tolerance = options.coverage_tolerance_m;
    if let Some(index) = path
        .points()
        .iter()
        .position(|p| p.arc_length_m < first - tolerance || p.arc_length_m > last + tolerance)
    {
        return Err(LogError::PartialCoverage {
            file: log.file.clone(),
            from_mm: first * 1e3,
            to_mm: last * 1e3,
            length_mm: path.length_m() * 1e3,
            first_uncovered: index,
        });
    }
    let profile = Profile::new(knots);
    let h = options.half_width_m;
    let wrenches = path
        .points()
        .iter()
        .map(|point| profile.mean(point.arc_length_m, h))
        .collect();
    Ok(Resampled {
        wrenches,
        used_rows: located_rows - standstill_rows,
        standstill_rows,
        off_path_rows,
        covered_m: [first, last],
        max_offset_m: max_offset,
    })
}

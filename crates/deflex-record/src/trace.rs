//! Any run log as the plain columns of a [`RunTrace`] (what `deflex plot` draws):
//!
//! * a deflex MCAP recording ([`crate::for_each_cycle`]): forces at the TCP, ξ, δŝ, the path
//!   error when the twin recorded it, phase and flags, cycle time; the path position is the arc
//!   length of the program TCP (corrected TCP − ξ);
//! * a `deflex run` CSV log (columns in `crates/deflex-control/src/log.rs`): the same, with the
//!   path position from its `path_s_m` column when every row has one (a feed-forward table), else
//!   — given the robot model — the arc length of the program TCP, forward kinematics of the
//!   logged joints minus ξ; else none (then `deflex plot` draws against time);
//! * a `deflex sim isf` `log.csv` (SIMULATED): desired TCP (its arc length is the path
//!   position), contact force, correction and path error in the part frame, contact state.
//!
//! Which one a file is comes from its content (MCAP magic bytes, then the CSV header), not its
//! name. Errors name the file, and the line and column where a value is wrong.

use crate::{ReadError, for_each_cycle, is_mcap};
use deflex_model::{Data, Robot};
use deflex_telemetry::CycleSample;
use deflex_telemetry::Flags;
use nalgebra::Vector3;
use std::path::Path;

/// Three components over the rows of a run (SI units).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Xyz {
    /// x
    pub x: Vec<f64>,
    /// y
    pub y: Vec<f64>,
    /// z
    pub z: Vec<f64>,
}

impl Xyz {
    /// Euclidean norm per row.
    pub fn norm(&self) -> Vec<f64> {
        self.x
            .iter()
            .zip(&self.y)
            .zip(&self.z)
            .map(|((x, y), z)| (x * x + y * y + z * z).sqrt())
            .collect()
    }

    /// Whether each component has `n` values.
    pub fn len_ok(&self, n: usize) -> bool {
        self.x.len() == n && self.y.len() == n && self.z.len() == n
    }
}

/// One run's log as columns (one entry per logged row; NaN where a value is unknown).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunTrace {
    /// Name in legends (e.g. `closed loop`).
    pub label: String,
    /// The file it was read from.
    pub file: String,
    /// What wrote it (e.g. `deflex sim isf log`).
    pub kind: String,
    /// The run is SIMULATED (the twin, or a simulated cell).
    pub simulated: bool,
    /// Time (s).
    pub time_s: Vec<f64>,
    /// Arc length of the desired path at the row (m), when known.
    pub path_s_m: Option<Vec<f64>>,
    /// Force on the tool at the TCP (N).
    pub force_n: Xyz,
    /// The axes of [`Self::force_n`] and the positions (e.g. `base axes`, `part frame axes`).
    pub axes: String,
    /// Correction ξ, position part (m).
    pub correction_m: Option<Xyz>,
    /// Estimated deflection δŝ, position part (m).
    pub deflection_m: Option<Xyz>,
    /// True minus desired TCP (m), known on the twin only.
    pub path_error_m: Option<Xyz>,
    /// Named on/off states per row (phase, saturation, fault, contact …).
    pub states: Vec<(String, Vec<bool>)>,
    /// Computation time of the control cycle (s), NaN where not logged.
    pub cycle_time_s: Option<Vec<f64>>,
}

/// Largest CSV log read (bytes).
pub const MAX_LOG_BYTES: u64 = 1 << 30;
/// Most rows read from one log.
pub const MAX_ROWS: usize = 2_000_000;

/// Why a log could not be read as a run.
#[derive(Debug, thiserror::Error)]
pub enum TraceError {
    /// Reading the file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// An MCAP file that is not a readable deflex recording.
    #[error(transparent)]
    Recording(#[from] ReadError),
    /// Not a log deflex knows.
    #[error(
        "{path}: line {line}: not a deflex log (expected a `deflex run` log with columns time_s, w_fx_n …, xi_x_m …, a `deflex sim isf` log.csv with time_s, des_x_mm …, or an MCAP recording); the header starts: {found}"
    )]
    Foreign {
        /// The file.
        path: String,
        /// Line of the header (1-based).
        line: usize,
        /// Its first columns.
        found: String,
    },
    /// A cell that is not what its column holds.
    #[error("{path}: line {line}, column {column}: {message}")]
    Cell {
        /// The file.
        path: String,
        /// Line (1-based).
        line: usize,
        /// Column name.
        column: String,
        /// What is wrong.
        message: String,
    },
    /// The file is too large or has too many rows.
    #[error("{path}: {message}")]
    TooLarge {
        /// The file.
        path: String,
        /// The bound passed.
        message: String,
    },
    /// The log has no row.
    #[error("{path}: no data row")]
    Empty {
        /// The file.
        path: String,
    },
    /// The robot given does not fit the log.
    #[error("{path}: {message}")]
    Robot {
        /// The file.
        path: String,
        /// What does not fit.
        message: String,
    },
}

/// Reads `path` (a recording, a `deflex run` log or a `deflex sim isf` log) as a run named
/// `label`. `robot` gives a `deflex run` log without `path_s_m` its path position.
pub fn read_run_log(
    path: &Path,
    label: &str,
    robot: Option<&Robot>,
) -> Result<RunTrace, TraceError> {
    let name = path.display().to_string();
    let io = |e| TraceError::Io {
        path: name.clone(),
        source: e,
    };
    if is_mcap(path).map_err(io)? {
        return from_recording(path, label);
    }
    let text = deflex_files::read_bounded(path, MAX_LOG_BYTES).map_err(|e| match e.problem() {
        Some(deflex_files::InputProblem::TooLarge { read, .. }) => TraceError::TooLarge {
            path: name.clone(),
            message: format!(
                "more than the {MAX_LOG_BYTES} bytes a log may have (stopped reading after {read})"
            ),
        },
        _ => io(e.into_io()),
    })?;
    let simulated = text
        .lines()
        .take_while(|l| l.starts_with('#'))
        .any(|l| l.contains("SIMULATED"));
    let table = Table::parse(&text, &name)?;
    let mut trace = if table.has("des_x_mm") {
        from_sim_isf(&table)?
    } else if table.has("w_fx_n") && table.has("xi_x_m") {
        from_run_log(&table, robot)?
    } else {
        return Err(TraceError::Foreign {
            path: name,
            line: table.header_line,
            found: table
                .columns
                .iter()
                .take(6)
                .cloned()
                .collect::<Vec<_>>()
                .join(","),
        });
    };
    trace.label = label.to_string();
    trace.file = name;
    trace.simulated |= simulated;
    Ok(trace)
}

/// A CSV log's cells, by column (empty cells are NaN).
struct Table {
    file: String,
    columns: Vec<String>,
    header_line: usize,
    lines: Vec<usize>,
    cells: Vec<Vec<String>>,
}

impl Table {
    fn parse(text: &str, file: &str) -> Result<Table, TraceError> {
        let mut reader = csv::ReaderBuilder::new()
            .comment(Some(b'#'))
            .trim(csv::Trim::All)
            .flexible(false)
            .from_reader(text.as_bytes());
        let csv_err = |e: csv::Error| {
            let line = e.position().map_or(0, |p| p.line() as usize);
            TraceError::Cell {
                path: file.to_string(),
                line,
                column: "-".into(),
                message: e.to_string(),
            }
        };
        let columns: Vec<String> = reader
            .headers()
            .map_err(csv_err)?
            .iter()
            .map(String::from)
            .collect();
        let header_line = reader.position().line() as usize;
        let header_line = text
            .lines()
            .position(|l| !l.starts_with('#'))
            .map_or(header_line, |i| i + 1);
        let mut lines = Vec::new();
        let mut cells = Vec::new();
        for record in reader.records() {
            let record = record.map_err(csv_err)?;
            if cells.len() == MAX_ROWS {
                return Err(TraceError::TooLarge {
                    path: file.to_string(),
                    message: format!("more than {MAX_ROWS} rows"),
                });
            }
            lines.push(record.position().map_or(0, |p| p.line() as usize));
            cells.push(record.iter().map(String::from).collect());
        }
        if cells.is_empty() {
            return Err(TraceError::Empty {
                path: file.to_string(),
            });
        }
        Ok(Table {
            file: file.to_string(),
            columns,
            header_line,
            lines,
            cells,
        })
    }

    fn has(&self, name: &str) -> bool {
        self.columns.iter().any(|c| c == name)
    }

    /// A numeric column; empty cells are NaN, anything else that is not a number is an error.
    fn column(&self, name: &str) -> Result<Vec<f64>, TraceError> {
        let k = self
            .columns
            .iter()
            .position(|c| c == name)
            .ok_or_else(|| TraceError::Cell {
                path: self.file.clone(),
                line: self.header_line,
                column: name.into(),
                message: "column missing from the header".into(),
            })?;
        self.cells
            .iter()
            .zip(&self.lines)
            .map(|(row, line)| {
                let cell = row[k].as_str();
                if cell.is_empty() {
                    return Ok(f64::NAN);
                }
                cell.parse::<f64>().map_err(|_| TraceError::Cell {
                    path: self.file.clone(),
                    line: *line,
                    column: name.into(),
                    message: format!("expected a number, found {cell:?}"),
                })
            })
            .collect()
    }

    fn xyz(&self, names: [&str; 3], scale: f64) -> Result<Xyz, TraceError> {
        let c = |n| {
            self.column(n)
                .map(|v| v.iter().map(|x| x * scale).collect::<Vec<_>>())
        };
        Ok(Xyz {
            x: c(names[0])?,
            y: c(names[1])?,
            z: c(names[2])?,
        })
    }
}

/// Cumulative length of a polyline (m), from 0: the path position of a run; a point with a
/// non-finite coordinate adds no length (the next finite point continues from the last finite
/// one).
pub fn arc_length(points: impl Iterator<Item = Vector3<f64>>) -> Vec<f64> {
    let mut out = Vec::new();
    let mut previous: Option<Vector3<f64>> = None;
    let mut s = 0.0;
    for p in points {
        if let Some(q) = previous
            && p.iter().all(|v| v.is_finite())
        {
            s += (p - q).norm();
        }
        if p.iter().all(|v| v.is_finite()) {
            previous = Some(p);
        }
        out.push(s);
    }
    out
}

fn from_sim_isf(t: &Table) -> Result<RunTrace, TraceError> {
    let des = t.xyz(["des_x_mm", "des_y_mm", "des_z_mm"], 1e-3)?;
    let path_s = arc_length((0..des.x.len()).map(|i| Vector3::new(des.x[i], des.y[i], des.z[i])));
    let penetration = t.column("penetration_mm")?;
    let mut states = vec![(
        "in contact".to_string(),
        penetration.iter().map(|p| *p > 0.0).collect(),
    )];
    if t.has("sensor_saturated") {
        states.push((
            "sensor saturated".into(),
            t.column("sensor_saturated")?
                .iter()
                .map(|v| *v > 0.5)
                .collect(),
        ));
    }
    Ok(RunTrace {
        kind: "deflex sim isf log".into(),
        simulated: true,
        time_s: t.column("time_s")?,
        path_s_m: Some(path_s),
        force_n: t.xyz(["fx_N", "fy_N", "fz_N"], 1.0)?,
        axes: "part frame axes".into(),
        correction_m: Some(t.xyz(["corr_x_mm", "corr_y_mm", "corr_z_mm"], 1e-3)?),
        deflection_m: None,
        path_error_m: Some(t.xyz(["err_x_mm", "err_y_mm", "err_z_mm"], 1e-3)?),
        states,
        cycle_time_s: None,
        ..RunTrace::default()
    })
}

/// On/off lanes of the controller's phase and flags.
fn flag_states(flags: &[u32], fault: impl Fn(usize) -> bool) -> Vec<(String, Vec<bool>)> {
    let has = |bit: u32| flags.iter().map(|f| f & bit != 0).collect::<Vec<bool>>();
    vec![
        ("taring".into(), has(Flags::TARING)),
        ("correcting (active)".into(), has(Flags::ACTIVE)),
        ("ramping".into(), has(Flags::RAMPING)),
        (
            "saturated (size or rate)".into(),
            has(Flags::SATURATED_SIZE | Flags::SATURATED_RATE),
        ),
        ("runaway hold".into(), has(Flags::RUNAWAY_HOLD)),
        (
            "fault latched".into(),
            (0..flags.len()).map(fault).collect(),
        ),
    ]
}

fn from_run_log(t: &Table, robot: Option<&Robot>) -> Result<RunTrace, TraceError> {
    let xi = t.xyz(["xi_x_m", "xi_y_m", "xi_z_m"], 1.0)?;
    let path_s_col = t.column("path_s_m")?;
    let path_s_m = if path_s_col.iter().all(|s| s.is_finite()) {
        Some(path_s_col)
    } else if let Some(robot) = robot {
        let n = robot.joint_count();
        let joints: Vec<Vec<f64>> = (1..=n)
            .map(|i| t.column(&format!("q{i}_rad")))
            .collect::<Result<_, _>>()
            .map_err(|e| match e {
                TraceError::Cell { path, column, .. } => TraceError::Robot {
                    path,
                    message: format!(
                        "the robot {} has {n} joints but the log has no column {column}",
                        robot.name
                    ),
                },
                other => other,
            })?;
        let mut data = Data::new();
        let mut q = vec![0.0; n];
        let mut program = Vec::with_capacity(xi.x.len());
        for row in 0..xi.x.len() {
            for (qj, column) in q.iter_mut().zip(&joints) {
                *qj = column[row];
            }
            let p = match robot.forward_kinematics(&mut data, &q) {
                Ok(()) => data.tcp_position() - Vector3::new(xi.x[row], xi.y[row], xi.z[row]),
                Err(_) => Vector3::repeat(f64::NAN),
            };
            program.push(p);
        }
        Some(arc_length(program.into_iter()))
    } else {
        None
    };
    let flags: Vec<u32> = t
        .column("flags")?
        .iter()
        .map(|f| if f.is_finite() { *f as u32 } else { 0 })
        .collect();
    let states = flag_states(&flags, |i| flags[i] & (Flags::LATCHED | 0x7FF) != 0);
    Ok(RunTrace {
        kind: "deflex run log".into(),
        simulated: false,
        time_s: t.column("time_s")?,
        path_s_m,
        force_n: t.xyz(["w_fx_n", "w_fy_n", "w_fz_n"], 1.0)?,
        axes: "base axes".into(),
        correction_m: Some(xi),
        deflection_m: Some(t.xyz(["ds_x_m", "ds_y_m", "ds_z_m"], 1.0)?),
        path_error_m: None,
        states,
        cycle_time_s: Some(t.column("cycle_us")?.iter().map(|v| v * 1e-6).collect()),
        ..RunTrace::default()
    })
}

fn from_recording(path: &Path, label: &str) -> Result<RunTrace, TraceError> {
    let mut rows: Vec<CycleSample> = Vec::new();
    let mut too_many = false;
    let summary = for_each_cycle(path, |s| {
        if rows.len() < MAX_ROWS {
            rows.push(*s);
        } else {
            too_many = true;
        }
    })?;
    let name = path.display().to_string();
    if too_many {
        return Err(TraceError::TooLarge {
            path: name,
            message: format!("more than {MAX_ROWS} cycles"),
        });
    }
    let col = |f: &dyn Fn(&CycleSample) -> f64| rows.iter().map(f).collect::<Vec<f64>>();
    let xyz = |f: &dyn Fn(&CycleSample) -> [f64; 3]| Xyz {
        x: rows.iter().map(|s| f(s)[0]).collect(),
        y: rows.iter().map(|s| f(s)[1]).collect(),
        z: rows.iter().map(|s| f(s)[2]).collect(),
    };
    let flags: Vec<u32> = rows.iter().map(|s| s.flags).collect();
    let mut states = flag_states(&flags, |i| rows[i].fault != 0);
    states.insert(
        0,
        (
            "phase running".into(),
            rows.iter()
                .map(|s| s.phase() == deflex_telemetry::Phase::Running)
                .collect(),
        ),
    );
    let simulated = summary.session.as_ref().is_some_and(|s| s.simulated);
    Ok(RunTrace {
        label: label.to_string(),
        file: name,
        kind: "deflex MCAP recording".into(),
        simulated,
        time_s: col(&|s| s.time_s),
        path_s_m: Some(arc_length(rows.iter().map(|s| s.program_position_m()))),
        force_n: xyz(&|s| [s.wrench_tcp[0], s.wrench_tcp[1], s.wrench_tcp[2]]),
        axes: "base axes".into(),
        correction_m: Some(xyz(&|s| {
            [s.correction[0], s.correction[1], s.correction[2]]
        })),
        deflection_m: Some(xyz(&|s| {
            [s.deflection[0], s.deflection[1], s.deflection[2]]
        })),
        path_error_m: summary.path_error_known.then(|| xyz(&|s| s.truth_error_m)),
        states,
        cycle_time_s: Some(col(&|s| s.cycle_time_s)),
    })
}

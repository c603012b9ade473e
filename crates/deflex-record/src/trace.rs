//! Any run log as the plain columns of a [`RunTrace`] (what `deflex plot` draws):
//!
//! * a deflex MCAP recording ([`crate::for_each_cycle`]): forces at the TCP, ξ, δŝ, the path
//!   error when the twin recorded it, phase and flags, cycle time; the path position is the arc
//!   length of the program TCP (corrected TCP − ξ);
//! * a `deflex run` CSV log (its columns: [`crate::run_log`]): the same, with the
//!   path position from its `path_s_m` column when every row has one (a feed-forward table), else
//!   — given the robot model — the arc length of the program TCP, forward kinematics of the
//!   logged joints minus ξ; else none (then `deflex plot` draws against time);
//! * a `deflex sim isf` `log.csv` (SIMULATED; its columns: [`crate::isf_log`]): desired TCP (its arc length is the path
//!   position), contact force, correction and path error in the part frame, contact state.
//!
//! Which one a file is comes from its content (MCAP magic bytes, then the CSV header), not its
//! name. The CSV logs are read with the one log reader ([`crate::log_reader`]). Errors name the
//! file, and the line and column where a value is wrong.

use crate::log_reader::{LogReadError, LogReader};
use crate::run_log::{RunLogBlock, RunLogColumn};
use crate::{ReadError, for_each_cycle, is_mcap, isf_log};
use deflex_files::{FileIoError, FileTooLarge};
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

/// Largest CSV log read (bytes): the log reader's bound.
pub const MAX_LOG_BYTES: u64 = crate::log_reader::MAX_LOG_BYTES;
/// Most rows a trace holds (a log may have more, [`crate::log_reader::MAX_LOG_ROWS`], for the
/// compensation's logged forces).
pub const MAX_ROWS: usize = 2_000_000;

/// Why a log could not be read as a run.
#[derive(Debug, thiserror::Error)]
pub enum TraceError {
    /// Reading the file failed.
    #[error(transparent)]
    Io(#[from] FileIoError),
    /// The file is larger than a log may be ([`MAX_LOG_BYTES`]; the reader names it `a log`).
    #[error(transparent)]
    TooLarge(#[from] FileTooLarge),
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
    /// The log or recording has more rows (cycles) than a trace holds.
    #[error("{path}: {message}")]
    TooManyRows {
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
    if is_mcap(path).map_err(|e| FileIoError::new(path, e))? {
        return from_recording(path, label);
    }
    let text = deflex_files::read_bounded(path, MAX_LOG_BYTES)
        .map_err(|e| e.reported_as::<TraceError>("a log"))?;
    let log = LogReader::new(&text, &name).map_err(read_error)?;
    let simulated = log.simulated();
    let kind = if log.has(isf_log::DESIRED_MM[0]) {
        Some(Kind::SimIsf)
    } else if log.has(&RunLogColumn::Block(RunLogBlock::TcpWrench, 0).name())
        && log.has(&RunLogColumn::Block(RunLogBlock::Correction, 0).name())
    {
        Some(Kind::DeflexRun)
    } else {
        None
    };
    let wanted = match kind {
        Some(Kind::SimIsf) => sim_isf_columns(),
        Some(Kind::DeflexRun) => run_log_columns(robot),
        None => Vec::new(),
    };
    let table = Table::read(log, &wanted)?;
    let mut trace = match kind {
        Some(Kind::SimIsf) => from_sim_isf(&table)?,
        Some(Kind::DeflexRun) => from_run_log(&table, robot)?,
        None => {
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
        }
    };
    trace.label = label.to_string();
    trace.file = name;
    trace.simulated |= simulated;
    Ok(trace)
}

/// Which CSV log a file is.
#[derive(Clone, Copy)]
enum Kind {
    /// A `deflex run` log.
    DeflexRun,
    /// A `deflex sim isf` log.
    SimIsf,
}

/// The log reader's error as a trace's.
fn read_error(e: LogReadError) -> TraceError {
    match e {
        LogReadError::Csv {
            file,
            line,
            message,
        } => TraceError::Cell {
            path: file,
            line,
            column: "-".into(),
            message,
        },
        LogReadError::TooLarge { file, message, .. } => TraceError::TooManyRows {
            path: file,
            message,
        },
        LogReadError::BadValue {
            file,
            line,
            column,
            value,
        } => TraceError::Cell {
            path: file,
            line,
            column,
            message: format!("expected a number, found {value:?}"),
        },
    }
}

/// The columns a trace of a `deflex sim isf` log draws.
fn sim_isf_columns() -> Vec<String> {
    let mut names = vec![
        isf_log::TIME,
        isf_log::PENETRATION_MM,
        isf_log::SENSOR_SATURATED,
    ];
    names.extend(isf_log::DESIRED_MM);
    names.extend(&isf_log::WRENCH[..3]);
    names.extend(isf_log::CORRECTION_MM);
    names.extend(isf_log::ERROR_MM);
    names.into_iter().map(String::from).collect()
}

/// The columns a trace of a `deflex run` log draws (the joints for the program's arc length
/// when a robot is given).
fn run_log_columns(robot: Option<&Robot>) -> Vec<String> {
    let mut columns = vec![
        RunLogColumn::Time,
        RunLogColumn::PathPosition,
        RunLogColumn::Flags,
        RunLogColumn::CycleTime,
    ];
    for block in [
        RunLogBlock::TcpWrench,
        RunLogBlock::Deflection,
        RunLogBlock::Correction,
    ] {
        columns.extend(&block.columns()[..3]);
    }
    columns.extend((0..robot.map_or(0, Robot::joint_count)).map(RunLogColumn::Joint));
    columns.into_iter().map(RunLogColumn::name).collect()
}

/// A column's values, or the line and text of its first cell that is not a number.
type Cells = Result<Vec<f64>, (usize, String)>;

/// The columns of a CSV log a trace draws, by name, read in one pass over every row (empty
/// cells are NaN). A column's first cell that is not a number is kept, and reported when the
/// trace asks for the column; the log's own errors (malformed CSV, too many rows, no row) come
/// first.
struct Table {
    file: String,
    columns: Vec<String>,
    header_line: usize,
    /// Wanted columns the log has: their values, or the line and text of the first bad cell.
    values: Vec<(String, Cells)>,
}

impl Table {
    fn read(mut log: LogReader<'_>, wanted: &[impl AsRef<str>]) -> Result<Table, TraceError> {
        let file = log.file().to_string();
        let columns = log.columns().to_vec();
        let header_line = log.header_line();
        let mut values: Vec<(String, usize, Cells)> = wanted
            .iter()
            .filter_map(|name| {
                let name = name.as_ref();
                log.column(name)
                    .map(|k| (name.to_string(), k, Ok(Vec::new())))
            })
            .collect();
        let mut rows = 0;
        while let Some(row) = log.next_row().map_err(read_error)? {
            if rows == MAX_ROWS {
                return Err(TraceError::TooManyRows {
                    path: file,
                    message: format!("more than {MAX_ROWS} rows"),
                });
            }
            rows += 1;
            for (_, k, column) in &mut values {
                if let Ok(cells) = column {
                    match row.number(*k) {
                        Ok(v) => cells.push(v),
                        Err(_) => *column = Err((row.line(), row.text(*k).to_string())),
                    }
                }
            }
        }
        if rows == 0 {
            return Err(TraceError::Empty { path: file });
        }
        Ok(Table {
            file,
            columns,
            header_line,
            values: values
                .into_iter()
                .map(|(name, _, column)| (name, column))
                .collect(),
        })
    }

    fn has(&self, name: &str) -> bool {
        self.columns.iter().any(|c| c == name)
    }

    /// A numeric column; empty cells are NaN, anything else that is not a number is an error.
    fn column(&self, name: &str) -> Result<Vec<f64>, TraceError> {
        match self.values.iter().find(|(n, _)| n == name) {
            Some((_, Ok(values))) => Ok(values.clone()),
            Some((_, Err((line, cell)))) => Err(TraceError::Cell {
                path: self.file.clone(),
                line: *line,
                column: name.into(),
                message: format!("expected a number, found {cell:?}"),
            }),
            None => Err(TraceError::Cell {
                path: self.file.clone(),
                line: self.header_line,
                column: name.into(),
                message: "column missing from the header".into(),
            }),
        }
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

    /// The first three columns of a run log's block (`x`, `y`, `z` or `fx`, `fy`, `fz`).
    fn block_xyz(&self, block: RunLogBlock) -> Result<Xyz, TraceError> {
        let [x, y, z, ..] = block.columns().map(RunLogColumn::name);
        self.xyz([&x, &y, &z], 1.0)
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
    let des = t.xyz(isf_log::DESIRED_MM, 1e-3)?;
    let path_s = arc_length((0..des.x.len()).map(|i| Vector3::new(des.x[i], des.y[i], des.z[i])));
    let penetration = t.column(isf_log::PENETRATION_MM)?;
    let mut states = vec![(
        "in contact".to_string(),
        penetration.iter().map(|p| *p > 0.0).collect(),
    )];
    if t.has(isf_log::SENSOR_SATURATED) {
        states.push((
            "sensor saturated".into(),
            t.column(isf_log::SENSOR_SATURATED)?
                .iter()
                .map(|v| *v > 0.5)
                .collect(),
        ));
    }
    Ok(RunTrace {
        kind: "deflex sim isf log".into(),
        simulated: true,
        time_s: t.column(isf_log::TIME)?,
        path_s_m: Some(path_s),
        force_n: t.xyz(
            [isf_log::WRENCH[0], isf_log::WRENCH[1], isf_log::WRENCH[2]],
            1.0,
        )?,
        axes: "part frame axes".into(),
        correction_m: Some(t.xyz(isf_log::CORRECTION_MM, 1e-3)?),
        deflection_m: None,
        path_error_m: Some(t.xyz(isf_log::ERROR_MM, 1e-3)?),
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
    let xi = t.block_xyz(RunLogBlock::Correction)?;
    let path_s_col = t.column(&RunLogColumn::PathPosition.name())?;
    let path_s_m = if path_s_col.iter().all(|s| s.is_finite()) {
        Some(path_s_col)
    } else if let Some(robot) = robot {
        let n = robot.joint_count();
        let joints: Vec<Vec<f64>> = (0..n)
            .map(|i| t.column(&RunLogColumn::Joint(i).name()))
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
        .column(&RunLogColumn::Flags.name())?
        .iter()
        .map(|f| if f.is_finite() { *f as u32 } else { 0 })
        .collect();
    let states = flag_states(&flags, |i| flags[i] & (Flags::LATCHED | 0x7FF) != 0);
    Ok(RunTrace {
        kind: "deflex run log".into(),
        simulated: false,
        time_s: t.column(&RunLogColumn::Time.name())?,
        path_s_m,
        force_n: t.block_xyz(RunLogBlock::TcpWrench)?,
        axes: "base axes".into(),
        correction_m: Some(xi),
        deflection_m: Some(t.block_xyz(RunLogBlock::Deflection)?),
        path_error_m: None,
        states,
        cycle_time_s: Some(
            t.column(&RunLogColumn::CycleTime.name())?
                .iter()
                .map(|v| v * 1e-6)
                .collect(),
        ),
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
        return Err(TraceError::TooManyRows {
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

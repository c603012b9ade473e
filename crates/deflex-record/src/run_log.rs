//! The run log: the controller's state, one row per control cycle, a column per quantity with
//! its unit in its name (SI). The one definition every writer and reader of it uses: `deflex
//! run`'s CSV log ([`crate::csv_log`], [`RunLogFormat::cell`]), the study's controller log of
//! the twin ([`RunLogFormat::twin`]), and its readers (the compensation's logged forces, `deflex
//! plot` through [`crate::trace`], Python), which read it with the one log reader
//! ([`crate::log_reader::LogReader`]) and find its columns with [`RunLogColumn::find`].
//!
//! ## Columns
//!
//! | column | quantity | unit |
//! | --- | --- | --- |
//! | `time_s` | controller time | s |
//! | `q1_rad … qN_rad` | joint values the robot reported | rad |
//! | `raw_fx_n … raw_mz_nm` | the sensor's raw reading, sensor frame | N, N·m |
//! | `ws_fx_n … ws_mz_nm` | the compensated reading (tare, tool load), sensor frame | N, N·m |
//! | `w_fx_n … w_mz_nm` | the wrench on the tool at the TCP (eq. 2), base axes | N, N·m |
//! | `ds_x_m … ds_rz_rad` | the estimated deflection δŝ (eq. 15) | m, rad |
//! | `xi_x_m … xi_rz_rad` | the correction ξ sent (eq. 7) | m, rad |
//! | `eps_x_m … eps_rz_rad` | the tracking error ε (eq. 5) | m, rad |
//! | `ff_x_m … ff_rz_rad` | the feed-forward's prior (`deflex_control::feedforward`) | m, rad |
//! | `path_s_m` | arc length on the feed-forward's table (empty without one, or acquiring) | m |
//! | `loop_gain` | the runaway guard's loop-gain estimate (empty when unknown) | 1 |
//! | `cycle_us` | computation time of the cycle | µs |
//! | `flags` | [`deflex_telemetry::Flags`] as an integer | |
//! | `status` | the flags and the latched fault by name (written, not read) | |
//!
//! A row is a [`CycleSample`]: the writer takes the telemetry stream's samples as they are.
//! `deflex run` writes every column ([`RunLogFormat::cell`]); the twin's controller log of the
//! study has the quantities a simulated controller has, at a coarser precision
//! ([`RunLogFormat::twin`]). A reader takes the columns it needs and ignores the others, so a
//! log of an older deflex (without `ff_*` and `path_s_m`) is read as it is.

use crate::log_reader::LogReader;
use deflex_control::{CycleOutput, RecordCycle};
use deflex_telemetry::{CycleSample, Flags};

/// `deflex run` flag bits whose rows' wrench is not a measurement of the process: the eleven
/// fault bits of the law's checks, latched, taring and stale wrench ([`Flags`]; a
/// `model_mismatch` is latched on the cycle it is detected, so `LATCHED` skips its rows). The compensation's logged forces
/// skip these rows.
pub const RUN_LOG_SKIP_FLAGS: u32 = Flags::FORCE_OVER_LIMIT
    | Flags::TORQUE_OVER_LIMIT
    | Flags::SENSOR_TIMEOUT
    | Flags::SENSOR_STATUS
    | Flags::ROBOT_LINK_LOST
    | Flags::NON_FINITE
    | Flags::SENSOR_OVER_RANGE
    | Flags::JOINT_OUT_OF_LIMITS
    | Flags::JOINT_JUMP
    | Flags::JOINT_COUNT_MISMATCH
    | Flags::CONTACT_RUNAWAY
    | Flags::LATCHED
    | Flags::TARING
    | Flags::STALE_WRENCH;

/// A six-component quantity of the log: a wrench `[f; m]` or a small displacement `[δp; δφ]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RunLogBlock {
    /// The sensor's raw reading, sensor frame (`raw_*`).
    RawWrench,
    /// The compensated reading, sensor frame (`ws_*`).
    SensorWrench,
    /// The wrench on the tool at the TCP, base axes (`w_*`).
    TcpWrench,
    /// The estimated deflection δŝ (`ds_*`).
    Deflection,
    /// The correction ξ (`xi_*`).
    Correction,
    /// The tracking error ε (`eps_*`).
    Error,
    /// The feed-forward's prior (`ff_*`).
    FeedForward,
}

/// Column suffixes of a wrench's components.
const WRENCH_SUFFIXES: [&str; 6] = ["fx_n", "fy_n", "fz_n", "mx_nm", "my_nm", "mz_nm"];
/// Column suffixes of a displacement's components.
const DISPLACEMENT_SUFFIXES: [&str; 6] = ["x_m", "y_m", "z_m", "rx_rad", "ry_rad", "rz_rad"];

impl RunLogBlock {
    /// The column prefix (`raw`, `ws`, `w`, `ds`, `xi`, `eps`, `ff`).
    pub fn prefix(self) -> &'static str {
        match self {
            RunLogBlock::RawWrench => "raw",
            RunLogBlock::SensorWrench => "ws",
            RunLogBlock::TcpWrench => "w",
            RunLogBlock::Deflection => "ds",
            RunLogBlock::Correction => "xi",
            RunLogBlock::Error => "eps",
            RunLogBlock::FeedForward => "ff",
        }
    }

    /// A wrench (N, N·m), else a displacement (m, rad).
    pub fn is_wrench(self) -> bool {
        matches!(
            self,
            RunLogBlock::RawWrench | RunLogBlock::SensorWrench | RunLogBlock::TcpWrench
        )
    }

    /// The block's values in a sample.
    pub fn of(self, sample: &CycleSample) -> &[f64; 6] {
        match self {
            RunLogBlock::RawWrench => &sample.wrench_raw,
            RunLogBlock::SensorWrench => &sample.wrench_sensor,
            RunLogBlock::TcpWrench => &sample.wrench_tcp,
            RunLogBlock::Deflection => &sample.deflection,
            RunLogBlock::Correction => &sample.correction,
            RunLogBlock::Error => &sample.error,
            RunLogBlock::FeedForward => &sample.feedforward,
        }
    }

    /// The six columns of the block, in component order.
    pub fn columns(self) -> [RunLogColumn; 6] {
        std::array::from_fn(|k| RunLogColumn::Block(self, k))
    }
}

/// One column of the run log (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RunLogColumn {
    /// `time_s`.
    Time,
    /// `q{i+1}_rad`: joint `i` (0-based).
    Joint(usize),
    /// Component `k` (0 … 5) of a six-component quantity.
    Block(RunLogBlock, usize),
    /// `path_s_m`.
    PathPosition,
    /// `loop_gain`.
    LoopGain,
    /// `cycle_us`.
    CycleTime,
    /// `flags`.
    Flags,
    /// `status`.
    Status,
}

impl RunLogColumn {
    /// The column's name in the header (its unit in its suffix).
    pub fn name(self) -> String {
        match self {
            RunLogColumn::Time => "time_s".into(),
            RunLogColumn::Joint(i) => format!("q{}_rad", i + 1),
            RunLogColumn::Block(block, k) => {
                let suffixes = if block.is_wrench() {
                    &WRENCH_SUFFIXES
                } else {
                    &DISPLACEMENT_SUFFIXES
                };
                format!(
                    "{}_{}",
                    block.prefix(),
                    suffixes.get(k).copied().unwrap_or("?")
                )
            }
            RunLogColumn::PathPosition => "path_s_m".into(),
            RunLogColumn::LoopGain => "loop_gain".into(),
            RunLogColumn::CycleTime => "cycle_us".into(),
            RunLogColumn::Flags => "flags".into(),
            RunLogColumn::Status => "status".into(),
        }
    }

    /// The unit of the column's values (`""` for a ratio, the flags and the status).
    pub fn unit(self) -> &'static str {
        match self {
            RunLogColumn::Time => "s",
            RunLogColumn::Joint(_) => "rad",
            RunLogColumn::Block(block, k) => match (block.is_wrench(), k < 3) {
                (true, true) => "N",
                (true, false) => "N·m",
                (false, true) => "m",
                (false, false) => "rad",
            },
            RunLogColumn::PathPosition => "m",
            RunLogColumn::CycleTime => "µs",
            RunLogColumn::LoopGain | RunLogColumn::Flags | RunLogColumn::Status => "",
        }
    }

    /// Its place among the columns of a log being read, when the log has it.
    pub fn find(self, log: &LogReader<'_>) -> Option<usize> {
        log.column(&self.name())
    }

    /// The places of several columns, or the names of those the log does not have.
    pub fn find_all(
        columns: &[RunLogColumn],
        log: &LogReader<'_>,
    ) -> Result<Vec<usize>, Vec<String>> {
        let names: Vec<String> = columns.iter().map(|c| c.name()).collect();
        log.columns_of(&names.iter().map(String::as_str).collect::<Vec<_>>())
    }
}

/// The joint columns of a log being read: `q1_rad`, `q2_rad`, … up to the first one missing.
pub fn joint_columns(log: &LogReader<'_>) -> Vec<usize> {
    (0..)
        .map_while(|i| RunLogColumn::Joint(i).find(log))
        .collect()
}

/// How a writer prints the numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Notation {
    /// `deflex run`: time to the µs, joints and displacements to the nm or nrad (9 decimals),
    /// wrenches to 0.1 mN (4 decimals), the cycle time to 10 ns.
    Cell,
    /// The study's controller log of the twin: time to 0.1 ms, wrenches to 1 mN (3 decimals),
    /// displacements with 6 significant digits (`1.23456e-4`).
    Twin,
}

/// The columns a log has and how its numbers are printed: the writer of the run log.
#[derive(Clone, Debug, PartialEq)]
pub struct RunLogFormat {
    columns: Vec<RunLogColumn>,
    notation: Notation,
}

impl RunLogFormat {
    /// `deflex run`'s log for `joint_count` joints: every column.
    pub fn cell(joint_count: usize) -> RunLogFormat {
        let mut columns = vec![RunLogColumn::Time];
        columns.extend((0..joint_count).map(RunLogColumn::Joint));
        for block in [
            RunLogBlock::RawWrench,
            RunLogBlock::SensorWrench,
            RunLogBlock::TcpWrench,
            RunLogBlock::Deflection,
            RunLogBlock::Correction,
            RunLogBlock::Error,
            RunLogBlock::FeedForward,
        ] {
            columns.extend(block.columns());
        }
        columns.extend([
            RunLogColumn::PathPosition,
            RunLogColumn::LoopGain,
            RunLogColumn::CycleTime,
            RunLogColumn::Flags,
            RunLogColumn::Status,
        ]);
        RunLogFormat {
            columns,
            notation: Notation::Cell,
        }
    }

    /// The study's controller log of the twin (`forming_closed/controller_log.csv`): time, the
    /// TCP wrench, δŝ, ξ, ε, the loop gain and the flags. No joint, raw-sensor, feed-forward
    /// or cycle-time columns: the twin's controller runs in simulated time without them.
    pub fn twin() -> RunLogFormat {
        let mut columns = vec![RunLogColumn::Time];
        for block in [
            RunLogBlock::TcpWrench,
            RunLogBlock::Deflection,
            RunLogBlock::Correction,
            RunLogBlock::Error,
        ] {
            columns.extend(block.columns());
        }
        columns.extend([
            RunLogColumn::LoopGain,
            RunLogColumn::Flags,
            RunLogColumn::Status,
        ]);
        RunLogFormat {
            columns,
            notation: Notation::Twin,
        }
    }

    /// The columns, in order.
    pub fn columns(&self) -> &[RunLogColumn] {
        &self.columns
    }

    /// How the numbers are printed.
    pub fn notation(&self) -> Notation {
        self.notation
    }

    /// The header line (without its line end).
    pub fn header(&self) -> String {
        self.columns
            .iter()
            .map(|c| c.name())
            .collect::<Vec<_>>()
            .join(",")
    }

    /// Appends the row of `sample` to `out` (without its line end).
    pub fn write_row(&self, sample: &CycleSample, out: &mut String) {
        use std::fmt::Write as _;
        let cell = self.notation == Notation::Cell;
        for (i, column) in self.columns.iter().enumerate() {
            if i > 0 {
                out.push(',');
            }
            let _ = match *column {
                RunLogColumn::Time if cell => write!(out, "{:.6}", sample.time_s),
                RunLogColumn::Time => write!(out, "{:.4}", sample.time_s),
                RunLogColumn::Joint(j) => {
                    write!(
                        out,
                        "{:.9}",
                        sample.q_rad.get(j).copied().unwrap_or(f64::NAN)
                    )
                }
                RunLogColumn::Block(block, k) => {
                    let v = block.of(sample).get(k).copied().unwrap_or(f64::NAN);
                    match (block.is_wrench(), cell) {
                        (true, true) => write!(out, "{v:.4}"),
                        (true, false) => write!(out, "{v:.3}"),
                        (false, true) => write!(out, "{v:.9}"),
                        (false, false) => write!(out, "{v:.5e}"),
                    }
                }
                RunLogColumn::PathPosition if sample.path_s_m.is_finite() => {
                    write!(out, "{:.6}", sample.path_s_m)
                }
                RunLogColumn::LoopGain if sample.loop_gain.is_finite() => {
                    write!(out, "{:.4}", sample.loop_gain)
                }
                RunLogColumn::PathPosition | RunLogColumn::LoopGain => Ok(()),
                RunLogColumn::CycleTime => write!(out, "{:.2}", sample.cycle_time_s * 1e6),
                RunLogColumn::Flags => write!(out, "{}", sample.flags),
                RunLogColumn::Status => write!(out, "{}", Flags(sample.flags).describe()),
            };
        }
    }

    /// The row of `sample` (without its line end).
    pub fn row(&self, sample: &CycleSample) -> String {
        let mut s = String::with_capacity(512);
        self.write_row(sample, &mut s);
        s
    }
}

/// The sample of a control cycle given its joint values `q_rad`, raw reading `raw` (sensor
/// frame), output `out` and computation time `cycle_us` (µs), without a controller at hand
/// (the runtime fills whole samples; this is for tools and tests that write logs).
pub fn cycle_sample(
    q_rad: &[f64],
    raw: &[f64; 6],
    out: &CycleOutput,
    cycle_us: f64,
) -> CycleSample {
    let mut sample = CycleSample::default();
    sample.set_q(q_rad);
    sample.wrench_raw = *raw;
    sample.record_output(out);
    sample.cycle_time_s = cycle_us * 1e-6;
    sample
}

//! Why a calibration, plan or validation could not be done: one variant per reason, carrying the
//! values that explain it. The messages are meant for the user.

use crate::measurements::{DataError, RowValueError};
use crate::stiffness::consistency::{GeometryMismatch, MAX_FK_TOLERANCE_M, MIN_FK_TOLERANCE_M};
use crate::stiffness::plan::WorkTable;
use deflex_model::QLengthError;
use thiserror::Error;

/// Why a calibration, plan or validation could not be done.
#[derive(Debug, Error)]
pub enum CalibError {
    /// Bad file.
    #[error(transparent)]
    Data(#[from] DataError),
    /// A file's rows do not match the robot's forward kinematics (another robot's file?).
    #[error("{0}")]
    GeometryMismatch(Box<GeometryMismatch>),
    /// A configuration with another number of joint values than the robot has joints
    /// (forward kinematics).
    #[error(transparent)]
    JointValues(#[from] QLengthError),
    /// The measurement rows cannot be used.
    #[error(transparent)]
    Rows(#[from] RowsError),
    /// The structure asked for cannot be fitted.
    #[error(transparent)]
    Structure(#[from] StructureError),
    /// The experiment plan cannot be made.
    #[error(transparent)]
    Plan(#[from] PlanError),
    /// A cross-validation fold failed.
    #[error("cross-validation fold {fold} of {folds}: {source}")]
    Fold {
        /// The fold (1-based).
        fold: usize,
        /// Folds in all.
        folds: usize,
        /// What went wrong in it.
        source: Box<CalibError>,
    },
    /// A noise level a normal distribution refuses (synthetic data).
    #[error("{what}: {source}")]
    Noise {
        /// Which noise.
        what: &'static str,
        /// The distribution's error.
        source: rand_distr::NormalError,
    },
}

/// A row of a set, as named in messages: `row 3 (load case L1, point TCP)`.
#[derive(Clone, Debug, PartialEq)]
pub struct RowRef {
    /// 1-based index of the row in the set.
    pub row: usize,
    /// Its load case.
    pub load_case: String,
    /// Its measured point.
    pub point: String,
}

impl RowRef {
    /// The `index`-th row (0-based) of a set.
    pub fn of(index: usize, row: &crate::measurements::MeasurementRow) -> RowRef {
        RowRef {
            row: index + 1,
            load_case: row.load_case.clone(),
            point: row.point.clone(),
        }
    }
}

impl std::fmt::Display for RowRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "row {} (load case {}, point {})",
            self.row, self.load_case, self.point
        )
    }
}

/// Why a set of measurement rows cannot be used.
#[derive(Debug, Error)]
pub enum RowsError {
    /// No row at all.
    #[error("no data rows")]
    NoRows,
    /// The rows have another number of joint values than the robot has joints.
    #[error(
        "the data has {found} joint columns (q1_rad…q{found}_rad) but robot \"{robot}\" has {joints} joints"
    )]
    JointCount {
        /// Joint values per row.
        found: usize,
        /// The robot's name.
        robot: String,
        /// Its joints.
        joints: usize,
    },
    /// A point or load link beyond the robot's last link.
    #[error("{row}: link index out of range (0 = base … {joints} = last link)")]
    LinkOutOfRange {
        /// The row.
        row: RowRef,
        /// The robot's joints (its last link's index).
        joints: usize,
    },
    /// A value no file could hold (a row built in code).
    #[error("{row}: {source}")]
    Value {
        /// The row.
        row: RowRef,
        /// The value.
        source: RowValueError,
    },
    /// A row without the displacement a calibration or validation needs.
    #[error("{row}: no measured displacement (dx_m, dy_m, dz_m)")]
    NoDisplacement {
        /// The row.
        row: RowRef,
    },
    /// A value that is NaN or infinite (a row built in code).
    #[error("{row}: {what} is NaN or infinite")]
    NotFinite {
        /// The row.
        row: RowRef,
        /// `displacement` or `rotation`.
        what: &'static str,
    },
    /// Every load is zero.
    #[error("every load is zero: nothing to identify")]
    AllLoadsZero,
    /// Every displacement is exactly zero.
    #[error(
        "every measured displacement is exactly zero: nothing to identify (were the loaded readings recorded?)"
    )]
    AllDisplacementsZero,
    /// A measurement standard deviation outside the range a fit can weigh.
    #[error(
        "{row}: {column} = {got:e} is outside {:e} to {:e}: a reading's standard deviation below a nanometre overflows its weight, above a metre it says nothing",
        crate::stiffness::design::SIGMA_RANGE.0,
        crate::stiffness::design::SIGMA_RANGE.1
    )]
    SigmaOutOfRange {
        /// The row.
        row: RowRef,
        /// `sigma_m` or `sigma_rad`.
        column: &'static str,
        /// The value.
        got: f64,
    },
    /// Fewer independent equations than parameters: the data cannot determine them.
    #[error(
        "{distinct} distinct reading(s) of {rows} give {equations} equations for {parameters} parameters: the data cannot determine them (standard errors and χ² would be 0, not a measure of anything); measure more load cases or configurations, or fit fewer eDoFs"
    )]
    TooFewReadings {
        /// Rows in the file.
        rows: usize,
        /// Distinct rows.
        distinct: usize,
        /// Independent equations (3 per distinct reading, 3 more per distinct measured rotation).
        equations: usize,
        /// Parameters to fit (eDoFs and free centre shifts).
        parameters: usize,
    },
    /// The least-squares sums are not finite.
    #[error(
        "the data's magnitudes overflow the least-squares problem (check the loads, coordinates and sigma_m)"
    )]
    Overflow,
    /// Cross-validation needs at least two load cases.
    #[error("cross-validation needs at least 2 load cases")]
    TooFewLoadCases,
    /// A forward-kinematics tolerance outside its range.
    #[error(
        "the forward-kinematics tolerance must be within {} to {} mm, got {got_mm} mm",
        MIN_FK_TOLERANCE_M * 1e3,
        MAX_FK_TOLERANCE_M * 1e3
    )]
    FkTolerance {
        /// The tolerance given (mm).
        got_mm: f64,
    },
}

/// Why a structure cannot be fitted.
#[derive(Debug, Error)]
pub enum StructureError {
    /// An eDoF on a joint the robot does not have.
    #[error("eDoF J{joint}.{axis} does not exist: the robot has {joints} joints")]
    NoSuchEdof {
        /// The joint.
        joint: usize,
        /// The axis letter.
        axis: char,
        /// The robot's joints.
        joints: usize,
    },
    /// An eDoF outside the design it is fitted in.
    #[error("eDoF {label} is not in the design")]
    NotInDesign {
        /// The eDoF's label.
        label: String,
    },
    /// A structure whose centre shifts do not match the robot's joints.
    #[error("structure has {shifts} shifts but the robot has {joints} joints")]
    ShiftCount {
        /// Shifts of the structure.
        shifts: usize,
        /// The robot's joints.
        joints: usize,
    },
    /// A structure without eDoF.
    #[error("the structure has no eDoF to calibrate")]
    Empty,
    /// Every eDoF of the structure was dropped.
    #[error("no eDoF of the structure is observable in this data ({})", reasons(.dropped))]
    NothingObservable {
        /// `(eDoF label, why it was dropped)`.
        dropped: Vec<(String, String)>,
    },
    /// Fewer than two folds.
    #[error("cross-validation needs at least 2 folds, got {folds}")]
    TooFewFolds {
        /// Folds asked for.
        folds: usize,
    },
    /// The cross-validation cannot score the start of the search.
    #[error("cross-validation cannot score the start structure")]
    UnscoredStart,
    /// Off-diagonal compliances that cannot be fitted or do not make a spring.
    #[error("coupling {label}: {reason}")]
    Coupling {
        /// The coupling or eDoF concerned (`J2.z–J3.z`), empty for the whole set.
        label: String,
        /// What is wrong.
        reason: String,
    },
}

fn reasons(dropped: &[(String, String)]) -> String {
    dropped
        .iter()
        .map(|(label, reason)| format!("{label}: {reason}"))
        .collect::<Vec<_>>()
        .join("; ")
}

/// Why an experiment plan cannot be made.
#[derive(Debug, Error)]
pub enum PlanError {
    /// An option outside its range, named by its `deflex plan` flag.
    #[error("{flag}: expected {expected}, got {got}")]
    Option {
        /// The flag (`--load-cases`).
        flag: &'static str,
        /// What it accepts.
        expected: String,
        /// What it was given.
        got: String,
    },
    /// A measured point on a link the robot does not have.
    #[error("point {point}: link {link} does not exist (0 = base … {joints} = last link)")]
    PointLink {
        /// The point's name.
        point: String,
        /// Its link.
        link: usize,
        /// The robot's joints.
        joints: usize,
    },
    /// Dead weights on a robot without gravity.
    #[error("--load dead-weight: robot \"{robot}\" has no gravity, so a dead weight has no force")]
    NoGravity {
        /// The robot's name.
        robot: String,
    },
    /// The floor height is not known.
    #[error(
        "cannot tell where the floor is for robot \"{robot}\": its base frame R0 is not below the shoulder (joint 2 is {shoulder_above_r0_m:.3} m above R0); give the floor height (--floor-z-m) or turn the floor check off (--no-floor)"
    )]
    FloorUnknown {
        /// The robot's name.
        robot: String,
        /// Height of joint 2 above R0 (m).
        shoulder_above_r0_m: f64,
    },
    /// The default table needs the floor height.
    #[error(
        "the default table stands on the floor, whose height is unknown for robot \"{robot}\": give --table or --no-table"
    )]
    TableWithoutFloor {
        /// The robot's name.
        robot: String,
    },
    /// A robot without eDoF does not deflect.
    #[error("robot \"{robot}\" does not deflect (no eDoF): give the load level (--max-force-N)")]
    NoDeflection {
        /// The robot's name.
        robot: String,
    },
    /// A joint without limits.
    #[error(
        "joint {joint} ({name}) of robot \"{robot}\" has no limits: the planner draws configurations within them; give `limits = [min, max]` (rad) in the robot file (a URDF's <limit> is read)"
    )]
    NoLimits {
        /// The joint (1-based).
        joint: usize,
        /// Its name.
        name: String,
        /// The robot's name.
        robot: String,
    },
    /// Nothing to plan for.
    #[error("robot \"{robot}\" has no eDoF to plan for (use the full model family)")]
    NoEdof {
        /// The robot's name.
        robot: String,
    },
    /// Every configuration drawn hits the floor or the table.
    #[error(
        "no configuration out of {drawn} drawn keeps the arm{} clear of the floor (z = {}) and the table ({}): lower the floor or the table, or turn the checks off (--no-floor, --no-table)",
        if *.bracket { ", the bracket" } else { "" },
        .floor_z_m.map_or("not checked".to_string(), |z| format!("{z:.3} m")),
        .table.map_or("not checked".to_string(), |t| format!(
            "top at z = {:.3} m over x {:.3}…{:.3} m, y {:.3}…{:.3} m",
            t.top_z_m, t.x_m[0], t.x_m[1], t.y_m[0], t.y_m[1]
        ))
    )]
    NoClearConfiguration {
        /// Configurations drawn.
        drawn: usize,
        /// A bracket was planned.
        bracket: bool,
        /// The floor checked (world z, m).
        floor_z_m: Option<f64>,
        /// The table checked.
        table: Option<WorkTable>,
    },
}

impl PlanError {
    /// An option outside its range.
    pub(crate) fn option(
        flag: &'static str,
        expected: impl Into<String>,
        got: impl std::fmt::Display,
    ) -> PlanError {
        PlanError::Option {
            flag,
            expected: expected.into(),
            got: got.to_string(),
        }
    }
}

/// A parse error of the cable directions (`--cable-directions`).
#[derive(Clone, Debug, PartialEq, Error)]
#[error("expected directions among x, -x, y, -y, z, -z, got \"{text}\"")]
pub struct DirectionError {
    /// The item that is not a direction (at most 20 characters of it).
    pub text: String,
}

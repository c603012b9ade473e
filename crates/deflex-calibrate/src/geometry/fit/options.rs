//! What a fit is asked to do: the model steps, the loss, the resampling and the held-out
//! protocol; and why it may refuse.

use crate::geometry::identify;
use crate::geometry::params::TorsionShape;
use crate::geometry::solve::Loss;

/// One step of the model sequence.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// Set-ups and targets only, nominal rigid robot.
    Registration,
    /// Adds DH rows (θ, d, a, α, and β on parallel-axis rows).
    Geometry,
    /// Adds the robot's eDoF compliances (gravity sag, payload, loads).
    Compliance,
    /// Adds lumped masses and first moments of the bodies.
    Masses,
    /// Adds joint-angle harmonics up to this order on every joint (eccentricity).
    Harmonics(u8),
    /// Adds a gear's periodic transmission error: `cos`/`sin` of this many cycles per joint turn
    /// on every joint (a strain-wave gear of ratio N errs at N and 2N).
    Periodic(u16),
    /// Adds direction-dependent joint offsets `b_j sign(approach_j)` (backlash, hysteresis).
    Backlash,
    /// Adds a nonlinear torsion term `a·g(τ)` of this shape on each free eDoF (a strain-wave
    /// gear's torsion curve: hardening, or soft around zero torque).
    Torsion(TorsionShape),
    /// Adds a residual model on the joint angles ([`crate::geometry::residual_model`]), trained on what
    /// the parametric model leaves, hyper-parameters by cross-validation.
    ResidualModel,
    /// Adds joint-angle error maps ([`crate::geometry::joint_maps`]): each joint's angle error as a
    /// smooth function of its own angle, trained on what the parametric model leaves,
    /// hyper-parameters by the held-out protocol.
    JointMaps,
}

/// A model step or a loss that its name does not give (`--steps`, `--loss`, their Python
/// equivalents).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ChoiceError {
    /// Not one of the step names.
    #[error(
        "unknown step \"{0}\" (registration, geometry, compliance, masses, harmonics:N with N 1…4, periodic:N with N 1…10000, backlash, torsion:cubic, torsion:soft:T with T 1…1000 N·m, residual, joint-maps)"
    )]
    UnknownStep(String),
    /// A loss threshold that is not a number in 0.1…100.
    #[error("threshold \"{0}\" must be a number in 0.1…100")]
    LossThreshold(String),
    /// Not one of the loss names.
    #[error("expected huber, cauchy or none, got \"{0}\"")]
    UnknownLoss(String),
}

impl std::str::FromStr for Step {
    type Err = ChoiceError;

    /// `registration`, `geometry`, `compliance` (or `gravity`), `masses`, `harmonics:N`
    /// (N 1…4), `periodic:N` (N 1…10 000), `backlash`, `torsion:cubic`, `torsion:soft:T` (T
    /// 1…1000 N·m), `residual`, `joint-maps`; surrounding blanks ignored.
    fn from_str(text: &str) -> Result<Step, ChoiceError> {
        let name = text.trim();
        let bad = || ChoiceError::UnknownStep(name.to_string());
        match name {
            "registration" => Ok(Step::Registration),
            "geometry" => Ok(Step::Geometry),
            "compliance" | "gravity" => Ok(Step::Compliance),
            "masses" => Ok(Step::Masses),
            "backlash" => Ok(Step::Backlash),
            "residual" => Ok(Step::ResidualModel),
            "joint-maps" => Ok(Step::JointMaps),
            "torsion:cubic" => Ok(Step::Torsion(TorsionShape::Cubic)),
            other => {
                if let Some(n) = other.strip_prefix("harmonics:") {
                    match n.parse::<u8>() {
                        Ok(n) if (1..=4).contains(&n) => Ok(Step::Harmonics(n)),
                        _ => Err(bad()),
                    }
                } else if let Some(n) = other.strip_prefix("periodic:") {
                    match n.parse::<u16>() {
                        Ok(n) if (1..=10_000).contains(&n) => Ok(Step::Periodic(n)),
                        _ => Err(bad()),
                    }
                } else if let Some(t) = other.strip_prefix("torsion:soft:") {
                    match t.parse::<u16>() {
                        Ok(t) if (1..=1000).contains(&t) => {
                            Ok(Step::Torsion(TorsionShape::Soft(t)))
                        }
                        _ => Err(bad()),
                    }
                } else {
                    Err(bad())
                }
            }
        }
    }
}

impl std::str::FromStr for Loss {
    type Err = ChoiceError;

    /// `huber`, `cauchy`, `none` (or `squared`), `huber:K`, `cauchy:K` with K in 0.1…100
    /// (defaults 3 and 2.4).
    fn from_str(text: &str) -> Result<Loss, ChoiceError> {
        let (name, k) = match text.split_once(':') {
            Some((n, k)) => (
                n,
                Some(
                    k.parse::<f64>()
                        .ok()
                        .filter(|k| k.is_finite() && (0.1..=100.0).contains(k))
                        .ok_or_else(|| ChoiceError::LossThreshold(k.to_string()))?,
                ),
            ),
            None => (text, None),
        };
        match name {
            "huber" => Ok(Loss::Huber(k.unwrap_or(3.0))),
            "cauchy" => Ok(Loss::Cauchy(k.unwrap_or(2.4))),
            "none" | "squared" => Ok(Loss::Squared),
            other => Err(ChoiceError::UnknownLoss(other.to_string())),
        }
    }
}

impl Step {
    /// Name in tables.
    pub fn name(self) -> String {
        match self {
            Step::Registration => "registration only".into(),
            Step::Geometry => "+ geometry (DH, Hayati β)".into(),
            Step::Compliance => "+ compliance (gravity sag, loads)".into(),
            Step::Masses => "+ lumped masses".into(),
            Step::Harmonics(n) => format!("+ joint harmonics (order ≤ {n})"),
            Step::Periodic(n) => format!("+ gear periodic error ({n} cycles/turn)"),
            Step::Backlash => "+ direction-dependent offsets (backlash)".into(),
            Step::Torsion(TorsionShape::Cubic) => {
                "+ hardening torsion (cubic in the torque)".into()
            }
            Step::Torsion(TorsionShape::Soft(t)) => {
                format!("+ soft zone of the torsion (below {t} N·m)")
            }
            Step::ResidualModel => "+ residual model on joint angles".into(),
            Step::JointMaps => "+ joint-angle error maps".into(),
        }
    }

    /// Whether the robot is elastic at this step.
    pub fn elastic(self) -> bool {
        !matches!(self, Step::Registration | Step::Geometry)
    }

    /// Whether this step is an opt-in addition that must earn its place on held-out data.
    pub fn opt_in(self) -> bool {
        !matches!(self, Step::Registration | Step::Geometry | Step::Compliance)
    }
}

/// How held-out groups score a model: each group gets its own registration (a new set-up)
/// from some of its readings and is scored on the rest.
#[derive(Clone, Debug, PartialEq)]
pub struct HeldOutProtocol {
    /// Readings drawn at random to register each held-out group (0: every other configuration
    /// registers, the rest score; one draw).
    pub register_readings: usize,
    /// Random draws of those readings (the score pools the draws).
    pub draws: usize,
    /// Register the target offset too (a new probe), not only the set-up.
    pub register_target: bool,
}

impl Default for HeldOutProtocol {
    fn default() -> Self {
        HeldOutProtocol {
            register_readings: 0,
            draws: 1,
            register_target: false,
        }
    }
}

/// Options of [`crate::geometry::fit::fit`].
#[derive(Clone, Debug)]
pub struct FitOptions {
    /// Model steps, in order (each adds to the previous).
    pub steps: Vec<Step>,
    /// Robust loss.
    pub loss: Loss,
    /// Cross-validation folds by configuration (0 = none).
    pub folds: usize,
    /// Bootstrap replicates by configuration (0 = none).
    pub bootstrap: usize,
    /// Fraction of the configurations of fit set-ups held out as a test set (0 = none).
    pub test_fraction: f64,
    /// Seed of the splits, the draws and the bootstrap.
    pub seed: u64,
    /// Identifiability tolerance ([`identify::DEFAULT_TOLERANCE`]).
    pub tolerance: f64,
    /// Only these eDoF compliances are free in the compliance step (labels such as `J2.z`);
    /// empty = all of the robot's eDoFs.
    pub elastic_edofs: Vec<String>,
    /// Readings (campaign indices) never fitted: a test file's readings.
    pub held_out_readings: Vec<usize>,
    /// Cross-validation group of each absolute row (sessions, set-ups or series): each group
    /// in turn is left out, the model refitted without it and the group scored by the
    /// [`HeldOutProtocol`]. `None`: no group cross-validation.
    pub groups: Option<Vec<usize>>,
    /// How held-out groups and test set-ups are registered and scored.
    pub protocol: HeldOutProtocol,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            steps: vec![Step::Registration, Step::Geometry, Step::Compliance],
            loss: Loss::HUBER_DEFAULT,
            folds: 5,
            bootstrap: 0,
            test_fraction: 0.0,
            seed: 1,
            tolerance: identify::DEFAULT_TOLERANCE,
            elastic_edofs: Vec::new(),
            held_out_readings: Vec::new(),
            groups: None,
            protocol: HeldOutProtocol::default(),
        }
    }
}

/// Largest number of folds.
pub const MAX_FOLDS: usize = 50;
/// Largest number of bootstrap replicates.
pub const MAX_BOOTSTRAP: usize = 2000;
/// Largest number of registration draws per held-out group.
pub const MAX_DRAWS: usize = 1000;
/// Relative improvement of the held-out RMS an opt-in step must bring to be kept.
pub const ACCEPTANCE_GAIN: f64 = 0.005;

/// An option out of range.
#[derive(Debug, thiserror::Error)]
pub enum OptionError {
    /// Folds.
    #[error("folds: expected 0 (none) or 2…{MAX_FOLDS}, got {0}")]
    Folds(usize),
    /// Bootstrap.
    #[error("bootstrap: at most {MAX_BOOTSTRAP} replicates, got {0}")]
    Bootstrap(usize),
    /// Test fraction.
    #[error("test_fraction: expected 0…0.9, got {0}")]
    TestFraction(f64),
    /// Draws.
    #[error("draws: expected 1…{MAX_DRAWS}, got {0}")]
    Draws(usize),
    /// No step.
    #[error("steps: at least one step is needed")]
    NoSteps,
    /// Groups of the wrong length.
    #[error("groups: one per absolute row expected ({expected}), got {got}")]
    Groups {
        /// Absolute rows.
        expected: usize,
        /// Entries given.
        got: usize,
    },
}

/// Why a fit cannot run.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    /// Options out of range.
    #[error(transparent)]
    Option(#[from] OptionError),
    /// Nothing to fit on.
    #[error("no readings left to fit on (all held out, or none given)")]
    NoFitData,
    /// A geometric step on a robot without a DH table.
    #[error(
        "geometric calibration needs a robot described by a DH table (standard or modified); `{0}` comes from a URDF"
    )]
    NotDh(String),
    /// An `elastic_edofs` label names no eDoF of the robot.
    #[error(
        "eDoF `{label}` is not in the robot (its eDoFs: {known}); add its stiffness to the robot file first"
    )]
    UnknownEdof {
        /// Label given.
        label: String,
        /// The robot's eDoFs.
        known: String,
    },
}

impl FitOptions {
    /// Check the options against the model and campaign; the indices of the eDoFs whose
    /// compliance is free.
    pub fn validate(
        &self,
        robot: &deflex_model::Robot,
        absolute_rows: usize,
    ) -> Result<Vec<usize>, FitError> {
        if self.folds == 1 || self.folds > MAX_FOLDS {
            return Err(OptionError::Folds(self.folds).into());
        }
        if self.bootstrap > MAX_BOOTSTRAP {
            return Err(OptionError::Bootstrap(self.bootstrap).into());
        }
        if !(0.0..=0.9).contains(&self.test_fraction) {
            return Err(OptionError::TestFraction(self.test_fraction).into());
        }
        if self.protocol.draws == 0 || self.protocol.draws > MAX_DRAWS {
            return Err(OptionError::Draws(self.protocol.draws).into());
        }
        if self.steps.is_empty() {
            return Err(OptionError::NoSteps.into());
        }
        if let Some(groups) = &self.groups
            && groups.len() != absolute_rows
        {
            return Err(OptionError::Groups {
                expected: absolute_rows,
                got: groups.len(),
            }
            .into());
        }
        if self.steps.iter().any(|s| *s != Step::Registration) && robot.dh_convention.is_none() {
            return Err(FitError::NotDh(robot.name.clone()));
        }
        let labels: Vec<String> = robot.edofs().map(|e| e.label()).collect();
        if self.elastic_edofs.is_empty() {
            return Ok((0..labels.len()).collect());
        }
        self.elastic_edofs
            .iter()
            .map(|label| {
                labels
                    .iter()
                    .position(|l| l == label)
                    .ok_or_else(|| FitError::UnknownEdof {
                        label: label.clone(),
                        known: labels.join(", "),
                    })
            })
            .collect()
    }
}

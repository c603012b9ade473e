//! The compensation: commanded target = desired − predicted deflection, the deflection predicted
//! by the robot model at the joint values that reach the *commanded* pose, under the wrench of
//! the process at that commanded path, iterated until the commanded path stops changing.
//!
//! ## Definitions
//!
//! A small displacement `δ = [δp; δφ]` (m, rad, world axes) moves a pose `P = (p, R)` to
//! `P ⊕ δ = (p + δp, exp(δφ)·R)` (the twin's own rule for the true TCP). The commanded pose of
//! point `i` is `c_i = d_i ⊕ x_i`, `x_i` its compensation. The model predicts the tool at
//! `a_i = c_i ⊕ δ(q(c_i), w_i)` with `q(c)` the joint values reaching `c` (inverse kinematics
//! seeded along the path), `δ(q, w) = C(q)·w` (eq. 15, plus the robot's own weight when
//! [`CompensationOptions::include_gravity`]) and `w_i` the wrench on the tool. The compensation
//! is the `x_i` for which `a_i = d_i`: `x_i = −δ(q(d_i ⊕ x_i), w_i)` (with
//! [`CompensationOptions::orientation`] off, only `δp` is compensated and `x_i = [−δp; 0]`).
//!
//! ## Iteration
//!
//! Each iteration is one **sweep** along the path, point by point:
//!
//! 1. **Wrench**: the wrench source gives `w_i` at the point's current command (a process model
//!    sees the commanded pose and the model's compliance there, in path order); the deflection
//!    `δ_i` at the commanded configuration and the predicted error `|a_i − d_i|` of the current
//!    command are recorded.
//! 2. **Compensation** of the point. The residual `r⁰_i = −δ_i − x_i` is the first
//!    fixed-point step (and the predicted error to first order). **Per-point criterion**: a
//!    point whose residual is within *half* the tolerance is left as it is. The others are
//!    solved:
//!    `x̂_i` solves `x = −δ(q(d_i ⊕ x), w_i)` by a few fixed-point steps (the compliance changes
//!    little over a millimetre, so two or three steps reach 1e-9 m), each with a tracking IK
//!    from the previous joint values; the joint limits, the size of the compensation and the
//!    joint step from the previous point are checked.
//! 3. The change `r_i = x̂_i − x_i` of the solved points is reported; the run has converged when
//!    no solved point changed by more than the tolerance (position and orientation
//!    separately). Otherwise the next command of a solved point is `x_i + r_i` or, with
//!    [`CompensationOptions::acceleration`], the Anderson(1) mixing
//!    `x_i + r_i − γ_i (Δx_i + Δr_i)`, `γ_i = r_iᵀΔr_i / |Δr_i|²`, per point, with the point's
//!    previous solve: a process whose force grows with the commanded depth makes the plain
//!    iteration alternate with a factor up to `C k / (1 + C k)` (robot compliance × material
//!    stiffness), and the secant step removes it. A change within ten tolerances takes the
//!    plain step (the secant of nearly equal residuals extrapolates the process's noise), unless
//!    the point's residual reversed (an oscillation: the secant step then lies between the
//!    iterates).
//! 4. After convergence (or the last iteration) a final process pass gives the wrenches and the
//!    predicted error of the final command (the last sweep itself when no point moved).
//!
//! A point's wrench is taken before its compensation changes, and a process model's state
//! along the path (the formed sheet) is built from the commands it was given: a sweep is the
//! same iteration as a process pass over the whole path followed by a compensation pass, in one
//! walk over the points.
//!
//! **Why it does not grow with the path.** The criterion is the same for every point and a point
//! is only touched while its own predicted error exceeds half the tolerance, so a longer path
//! does not draw more secant extrapolations on noise: with a max-over-points criterion and
//! mixing at every point, a million-point cone stalled at a 1–4 µm noise floor (the largest
//! change fell to 1.4 µm by iteration 5, then rose to 29 µm) where a 100 000-point one converged
//! in 6 iterations. The other half is the process model's: its discretisation must be the same
//! for every iteration. A model whose state steps where the *command* puts the tool (the twin's
//! forming model booked its per-sector Aerens level at the predicted tool, and counted its
//! sub-steps on the commanded segment) moves each step with the last change; a finer path puts
//! a point within a few µm of every step, and that point's force jumps by a step whenever its
//! command moves by the last change: the million-point cone took 8 iterations against the
//! 100 000-point cone's 6, its last unconverged points the sector entries of the last contour.
//! Booked on the desired path (`deflex_sim::FormingProcess`), both take 6.
//!
//! **Why half the tolerance.** Left alone at residuals up to the full tolerance, points pile up
//! just below it (every solved point lands at ≈ 0 and stays; every unsolved one is anywhere
//! below), and in a process with state along the path (the formed sheet) solving one point
//! changes the next point's wrench by a few hundredths of a tolerance: a point at 0.99 µrad
//! crossed 1 µrad, was solved, and pushed the next one over, one point per iteration (on the
//! 100 000-point cone a front crossed 3 points an iteration from iteration 9 to 14). With the
//! band between half and the whole tolerance, such a push solves a point whose change is within
//! the tolerance, which does not hold the run up; a point left alone is at most half a
//! tolerance off, so the converged command's predicted error stays within the tolerance after
//! the last pass's small pushes (`Compensation::final_max_error_m` reports it).
//!
//! With fixed wrenches (a previous run's log) the wrench does not depend on the command, so one
//! compensation pass is exact and the run stops after it.
//!
//! ## Points that cannot be compensated
//!
//! They are never dropped: each keeps its index, `x_i = 0` (the desired pose is commanded) and a
//! [`PointFailure`] saying why (the desired or the compensated pose is unreachable or needs a
//! joint beyond its limits, the compensation is larger than allowed, or the joint values jump
//! from the previous point). It is up to the caller to refuse a path with failures; `deflex
//! compensate` writes the compensated path with its `status` column and refuses to write robot
//! programs.
//!
//! The per-point work (IK, FK, deflection, mixing) uses fixed-size types and allocates nothing;
//! the buffers are allocated once per run (about 380 bytes a point). The multi-seed IK of the first point, and the
//! fallback IK of a point the tracking IK loses, allocate.

use crate::error::CompensateError;
use crate::ik::{IkFailure, TrackingIkOptions};
use crate::path::TcpPath;
use crate::process::ProcessModel;
use deflex_model::{Displacement, MAX_JOINTS, ModelError, Pose, Robot, Wrench};
use deflex_telemetry::{OnProgress, Progress};
use nalgebra::{Rotation3, Vector3, Vector6};

mod solver;
use solver::Solver;

/// Settings of [`compensate`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CompensationOptions {
    /// Compensate the orientation too (the model predicts `δφ`); off: position only.
    pub orientation: bool,
    /// Add the deflection under the robot's own weight (`Robot::gravity_displacement`). Off by
    /// default: positions taught on the robot already contain it.
    pub include_gravity: bool,
    /// Converged when no point's compensation changes by more than this (m), 1e-9 ..= 1e-3.
    pub tolerance_m: f64,
    /// … and by more than this in orientation (rad), 1e-9 ..= 1e-2.
    pub tolerance_rad: f64,
    /// Most process/compensation iterations, 1 ..= 200.
    pub max_iterations: usize,
    /// Anderson(1) mixing per point (see the module documentation).
    pub acceleration: bool,
    /// Fixed-point steps per point and pass, 1 ..= 20.
    pub inner_iterations: usize,
    /// Largest compensation accepted (m); larger ones are reported, 1e-6 ..= 1.
    pub max_compensation_m: f64,
    /// Largest orientation compensation accepted (rad), 1e-6 ..= 1.
    pub max_compensation_rad: f64,
    /// Largest joint change between consecutive compensated points (rad), 0.01 ..= 6.3: a larger
    /// one means a branch flip or a singularity between them.
    pub max_joint_step_rad: f64,
    /// The tracking inverse kinematics.
    pub ik: TrackingIkOptions,
}

impl Default for CompensationOptions {
    fn default() -> Self {
        CompensationOptions {
            orientation: true,
            include_gravity: false,
            tolerance_m: 1e-6,
            tolerance_rad: 1e-6,
            max_iterations: 30,
            acceleration: true,
            inner_iterations: 6,
            max_compensation_m: 0.05,
            max_compensation_rad: 0.1,
            max_joint_step_rad: 0.5,
            ik: TrackingIkOptions::default(),
        }
    }
}

impl CompensationOptions {
    fn validate(&self) -> Result<(), CompensateError> {
        let check = |option: &'static str, value: f64, lo: f64, hi: f64| {
            if value.is_finite() && (lo..=hi).contains(&value) {
                Ok(())
            } else {
                Err(CompensateError::Option {
                    option,
                    message: format!("expected {lo} ..= {hi}, got {value}"),
                })
            }
        };
        check("tolerance_m", self.tolerance_m, 1e-9, 1e-3)?;
        check("tolerance_rad", self.tolerance_rad, 1e-9, 1e-2)?;
        check("max_iterations", self.max_iterations as f64, 1.0, 200.0)?;
        check("inner_iterations", self.inner_iterations as f64, 1.0, 20.0)?;
        check("max_compensation_m", self.max_compensation_m, 1e-6, 1.0)?;
        check("max_compensation_rad", self.max_compensation_rad, 1e-6, 1.0)?;
        check("max_joint_step_rad", self.max_joint_step_rad, 0.01, 6.3)?;
        check(
            "ik.position_tolerance_m",
            self.ik.position_tolerance_m,
            1e-13,
            1e-6,
        )?;
        check(
            "ik.orientation_tolerance_rad",
            self.ik.orientation_tolerance_rad,
            1e-13,
            1e-6,
        )?;
        check(
            "ik.max_iterations",
            self.ik.max_iterations as f64,
            1.0,
            1000.0,
        )?;
        check("ik.damping", self.ik.damping, 0.0, 1.0)?;
        check("ik.max_step_rad", self.ik.max_step_rad, 1e-3, 3.2)?;
        check(
            "ik.orientation_weight_m",
            self.ik.orientation_weight_m,
            1e-3,
            10.0,
        )
    }
}

/// Where the wrench at each point comes from.
pub enum WrenchSource<'a> {
    /// A process model, evaluated at the commanded path of each iteration.
    Process(&'a mut dyn ProcessModel),
    /// One wrench per path point (e.g. a previous run's log resampled on arc length, see
    /// [`crate::log`]); world axes, at the TCP.
    Fixed {
        /// What the wrenches are, for reports.
        label: String,
        /// They come from a simulation.
        simulated: bool,
        /// One per path point.
        wrenches: &'a [Wrench],
    },
}

/// Why a point keeps its desired pose (is not compensated).
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum PointFailure {
    /// The desired pose itself cannot be given joint values.
    #[error("desired pose: {0}")]
    Desired(IkFailure),
    /// The compensated pose cannot be given joint values.
    #[error("compensated pose: {0}")]
    Compensated(IkFailure),
    /// The compensation is larger than [`CompensationOptions::max_compensation_m`] / `_rad`.
    #[error(
        "compensation of {:.3} mm and {:.3} mrad exceeds the bound",
        position_m * 1e3,
        rotation_rad * 1e3
    )]
    TooLarge {
        /// Position part (m).
        position_m: f64,
        /// Orientation part (rad).
        rotation_rad: f64,
    },
    /// A joint moves more than [`CompensationOptions::max_joint_step_rad`] from the previous
    /// compensated point.
    #[error("joint {joint} moves {step_rad:.3} rad from the previous point")]
    JointJump {
        /// Joint number (1-based).
        joint: usize,
        /// Its change (rad).
        step_rad: f64,
    },
}

impl PointFailure {
    /// Short code for the `status` column (`desired:joint_limit:J3`, `compensated:not_reached`,
    /// `too_large`, `joint_jump:J4`).
    pub fn code(&self) -> String {
        match self {
            PointFailure::Desired(f) => format!("desired:{}", f.code()),
            PointFailure::Compensated(f) => format!("compensated:{}", f.code()),
            PointFailure::TooLarge { .. } => "too_large".into(),
            PointFailure::JointJump { joint, .. } => format!("joint_jump:J{joint}"),
        }
    }
}

/// The result at one point of the path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CompensatedPoint {
    /// `x = [dp; dφ]`: the commanded pose is `desired ⊕ x` (zero for a failed point).
    pub compensation: Displacement,
    /// Joint values reaching the commanded pose (first `joint_count` entries).
    pub q: [f64; MAX_JOINTS],
    /// Wrench on the tool at the final commanded path (world axes, at the TCP).
    pub wrench: Wrench,
    /// Predicted deflection at the commanded configuration under that wrench.
    pub deflection: Displacement,
    /// Predicted position error `|a − d|` of the final command (m).
    pub predicted_error_m: f64,
    /// Predicted orientation error of the final command (rad).
    pub predicted_error_rad: f64,
    /// Why the point is not compensated, if it is not.
    pub failure: Option<PointFailure>,
}

impl CompensatedPoint {
    /// The commanded pose for this point's desired pose.
    pub fn commanded(&self, desired: &Pose) -> Pose {
        commanded_pose(desired, &self.compensation)
    }
}

/// One iteration: the state of the command it started from, and how much it changed it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IterationReport {
    /// 1-based.
    pub iteration: usize,
    /// Largest predicted position error of the command this iteration started from (m): at the
    /// first iteration, the uncompensated path's.
    pub max_predicted_error_m: f64,
    /// Largest predicted orientation error of that command (rad).
    pub max_predicted_error_rad: f64,
    /// Largest force norm the wrench source gave (N).
    pub max_force_n: f64,
    /// Largest predicted deflection |δp| (m).
    pub max_deflection_m: f64,
    /// Largest change of a point's compensation in this iteration (m).
    pub max_change_m: f64,
    /// Largest change of a point's orientation compensation (rad).
    pub max_change_rad: f64,
    /// Points not compensated after this iteration.
    pub failed_points: usize,
    /// Points solved again in this iteration; the others' predicted error was already within
    /// half the tolerance (the per-point criterion), so they were left as they were.
    pub solved_points: usize,
}

/// What [`compensate`] returns.
#[derive(Clone, Debug, PartialEq)]
pub struct Compensation {
    /// The wrench source's name.
    pub source: String,
    /// The wrenches come from a simulation (report them as SIMULATED).
    pub simulated: bool,
    /// One per path point.
    pub points: Vec<CompensatedPoint>,
    /// One per iteration.
    pub iterations: Vec<IterationReport>,
    /// The last change was within the tolerance.
    pub converged: bool,
    /// Largest predicted position error of the final command, compensated points (m).
    pub final_max_error_m: f64,
    /// Largest predicted orientation error of the final command (rad).
    pub final_max_error_rad: f64,
    /// Largest force norm at the final command (N).
    pub final_max_force_n: f64,
    /// Largest compensation (m).
    pub max_compensation_m: f64,
    /// Largest orientation compensation (rad).
    pub max_compensation_rad: f64,
}

impl Compensation {
    /// The points that are not compensated, with their index.
    pub fn failures(&self) -> impl Iterator<Item = (usize, &PointFailure)> {
        self.points
            .iter()
            .enumerate()
            .filter_map(|(i, p)| p.failure.as_ref().map(|f| (i, f)))
    }

    /// Number of points not compensated.
    pub fn failure_count(&self) -> usize {
        self.points.iter().filter(|p| p.failure.is_some()).count()
    }
}

/// `pose ⊕ d = (p + δp, exp(δφ)·R)`: a pose moved by a small displacement.
pub fn apply_displacement(pose: &Pose, d: &Displacement) -> Pose {
    let rotation = Rotation3::new(Vector3::new(d[3], d[4], d[5])) * pose.rotation;
    Pose::from_parts(
        (pose.translation.vector + Vector3::new(d[0], d[1], d[2])).into(),
        rotation,
    )
}

/// The commanded pose `desired ⊕ x`.
pub fn commanded_pose(desired: &Pose, x: &Displacement) -> Pose {
    apply_displacement(desired, x)
}

/// Position and orientation norms of a displacement-like 6-vector.
fn norms(v: &Vector6<f64>) -> (f64, f64) {
    (v.fixed_rows::<3>(0).norm(), v.fixed_rows::<3>(3).norm())
}

/// Compensate `path` for the deflection `robot` predicts under the wrenches of `source`,
/// starting the inverse kinematics from `seed` (rad). See the module documentation.
///
/// `progress` hears of every pass as a stage (`IK of the path`, `the log's force-depth law`
/// for a process model that looks at the desired path first, `iteration N: compensation`,
/// `final process pass`; their number depends on the convergence) and of the path points done
/// in it ([`Progress::Work`], every few thousand points).
pub fn compensate(
    robot: &Robot,
    path: &TcpPath,
    seed: &[f64],
    mut source: WrenchSource,
    options: &CompensationOptions,
    progress: OnProgress<'_>,
) -> Result<Compensation, CompensateError> {
    options.validate()?;
    let n = robot.joint_count();
    if seed.len() != n {
        return Err(ModelError::from(deflex_model::QLengthError {
            expected: n,
            got: seed.len(),
        })
        .into());
    }
    let count = path.len();
    let (mut source_name, simulated, fixed) = match &source {
        WrenchSource::Process(model) => (model.name(), model.simulated(), false),
        WrenchSource::Fixed {
            label,
            simulated,
            wrenches,
        } => {
            if wrenches.len() != count {
                return Err(CompensateError::WrenchCount {
                    expected: count,
                    got: wrenches.len(),
                });
            }
            if let Some(index) = wrenches
                .iter()
                .position(|w| !w.iter().all(|v| v.is_finite()))
            {
                return Err(CompensateError::BadWrench { index });
            }
            (label.clone(), *simulated, true)
        }
    };
    let mut solver = Solver::new(robot, path, options, count);
    let mut stages = 0;
    let mut stage = |name: &str, progress: &mut dyn FnMut(Progress<'_>)| {
        stages += 1;
        progress(Progress::Stage {
            index: stages,
            count: None,
            name,
        });
    };
    stage("IK of the path", &mut *progress);
    solver.desired_pass(seed, progress);
    let fixed = match &mut source {
        WrenchSource::Process(model) if model.observes_desired_path() => {
            stage("the log's force-depth law", &mut *progress);
            solver.observation_pass(&mut **model, progress)?;
            // The name says what the observation identified (a law, or the logged forces).
            source_name = model.name();
            !model.follows_command()
        }
        _ => fixed,
    };
    let mut iterations = Vec::new();
    let mut converged = false;
    let mut final_stats = None;
    for iteration in 1..=options.max_iterations {
        let last = fixed || iteration == options.max_iterations;
        stage(
            &format!("iteration {iteration}: compensation"),
            &mut *progress,
        );
        let (stats, pass) = solver.sweep(&mut source, last, progress)?;
        let failed_points = solver.points.iter().filter(|p| p.failure.is_some()).count();
        iterations.push(IterationReport {
            iteration,
            max_predicted_error_m: stats.max_error_m,
            max_predicted_error_rad: stats.max_error_rad,
            max_force_n: stats.max_force_n,
            max_deflection_m: stats.max_deflection_m,
            max_change_m: pass.max_change_m,
            max_change_rad: pass.max_change_rad,
            failed_points,
            solved_points: pass.solved,
        });
        converged = fixed
            || (pass.max_change_m <= options.tolerance_m
                && pass.max_change_rad <= options.tolerance_rad);
        if converged && pass.solved == 0 {
            // Nothing moved: the process pass just made is the final command's.
            final_stats = Some(stats);
        }
        if converged || last {
            break;
        }
    }
    stage("final process pass", &mut *progress);
    let stats = match final_stats {
        Some(stats) => {
            progress(Progress::Work {
                done: count,
                total: count,
            });
            stats
        }
        None => solver.process_pass(&mut source, progress)?,
    };
    let mut max_compensation_m: f64 = 0.0;
    let mut max_compensation_rad: f64 = 0.0;
    for p in &solver.points {
        let (m, r) = norms(&p.compensation);
        max_compensation_m = max_compensation_m.max(m);
        max_compensation_rad = max_compensation_rad.max(r);
    }
    Ok(Compensation {
        source: source_name,
        simulated,
        points: solver.points,
        iterations,
        converged,
        final_max_error_m: stats.max_error_m,
        final_max_error_rad: stats.max_error_rad,
        final_max_force_n: stats.max_force_n,
        max_compensation_m,
        max_compensation_rad,
    })
}

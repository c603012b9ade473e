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
//! 1. **Process pass** at the current commanded path: the wrench source gives `w_i` for every
//!    point in order (a process model sees the commanded pose and the model's compliance there);
//!    the deflection `δ_i` at the commanded configuration and the predicted error `|a_i − d_i|`
//!    of the current command are recorded.
//! 2. **Compensation pass**, point by point. The residual `r⁰_i = −δ_i − x_i` is the first
//!    fixed-point step (and the predicted error to first order). **Per-point criterion**: a
//!    point whose residual is within the tolerance is left as it is. The others are solved:
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
//!    plain step (the secant of nearly equal residuals extrapolates the process's noise).
//! 4. After convergence (or the last iteration) a final process pass gives the wrenches and the
//!    predicted error of the final command (the last process pass itself when no point moved).
//!
//! **Why it does not grow with the path.** The criterion is the same for every point and a point
//! is only touched while its own predicted error exceeds the tolerance, so a longer path does not
//! draw more secant extrapolations on noise: with a max-over-points criterion and mixing at every
//! point, a million-point cone stalled at a 1–4 µm noise floor (the largest change fell to 1.4 µm
//! by iteration 5, then rose to 29 µm) where a 100 000-point one converged in 6 iterations.
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

use crate::error::{CompensateError, ProcessError};
use crate::ik::{IkFailure, TrackingIkOptions, limit_violation, track};
use crate::path::TcpPath;
use crate::process::{ProcessModel, ProcessPoint};
use deflex_model::spatial::orientation_error;
use deflex_model::{Data, Displacement, IkOptions, MAX_JOINTS, ModelError, Pose, Robot, Wrench};
use nalgebra::{Rotation3, Vector3, Vector6};

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
    /// the tolerance (the per-point criterion), so they were left as they were.
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

/// Stage of a running compensation, for progress bars.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// Inverse kinematics of the desired path.
    Desired,
    /// Process pass of an iteration.
    Process,
    /// Compensation pass of an iteration.
    Compensation,
    /// The final process pass.
    Final,
}

/// Progress of a running compensation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    /// Iteration (0 for the desired path).
    pub iteration: usize,
    /// Stage.
    pub stage: Stage,
    /// Points done in this stage.
    pub done: usize,
    /// Points in the path.
    pub total: usize,
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
pub fn compensate(
    robot: &Robot,
    path: &TcpPath,
    seed: &[f64],
    mut source: WrenchSource,
    options: &CompensationOptions,
    progress: &mut dyn FnMut(&Progress),
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
    let (source_name, simulated, fixed) = match &source {
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
    solver.desired_pass(seed, progress);
    let mut iterations = Vec::new();
    let mut converged = false;
    let mut final_stats = None;
    for iteration in 1..=options.max_iterations {
        let stats = solver.process_pass(&mut source, iteration, Stage::Process, progress)?;
        let last = fixed || iteration == options.max_iterations;
        let pass = solver.compensation_pass(iteration, last, progress);
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
    let stats = match final_stats {
        Some(stats) => {
            progress(&Progress {
                iteration: 0,
                stage: Stage::Final,
                done: count,
                total: count,
            });
            stats
        }
        None => solver.process_pass(&mut source, 0, Stage::Final, progress)?,
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

/// Statistics of a process pass over the compensated points.
struct PassStats {
    max_error_m: f64,
    max_error_rad: f64,
    max_force_n: f64,
    max_deflection_m: f64,
}

/// What a compensation pass did.
struct CompensationPass {
    /// Largest change of a solved point's compensation (m, rad).
    max_change_m: f64,
    max_change_rad: f64,
    /// Points whose compensation was solved again (the others were within the tolerance).
    solved: usize,
}

/// Report progress every this many points.
const PROGRESS_EVERY: usize = 4096;

/// The state of a run (allocated once): per point the result being built (compensation, joint
/// values, wrench, deflection, predicted error, failure) and the previous iterate and change
/// for the Anderson mixing.
struct Solver<'a> {
    robot: &'a Robot,
    path: &'a TcpPath,
    options: &'a CompensationOptions,
    data: Data,
    points: Vec<CompensatedPoint>,
    /// `(x, r)` of the point's previous solve, when it was solved in the previous iteration.
    history: Vec<Option<(Displacement, Displacement)>>,
}

impl<'a> Solver<'a> {
    fn new(
        robot: &'a Robot,
        path: &'a TcpPath,
        options: &'a CompensationOptions,
        count: usize,
    ) -> Solver<'a> {
        Solver {
            robot,
            path,
            options,
            data: Data::new(),
            points: vec![
                CompensatedPoint {
                    compensation: Displacement::zeros(),
                    q: [0.0; MAX_JOINTS],
                    wrench: Wrench::zeros(),
                    deflection: Displacement::zeros(),
                    predicted_error_m: 0.0,
                    predicted_error_rad: 0.0,
                    failure: None,
                };
                count
            ],
            history: vec![None; count],
        }
    }

    fn desired(&self, i: usize) -> &'a Pose {
        &self.path.points()[i].pose
    }

    /// Model deflection at the configuration in `self.data` under `w`.
    fn predicted(&self, w: &Wrench) -> Displacement {
        let mut d = self.robot.tcp_deflection(&self.data, w);
        if self.options.include_gravity {
            d += self.robot.gravity_displacement(
                &self.data,
                &self.data.tcp_position(),
                self.robot.joint_count(),
            );
        }
        d
    }

    /// The tracking IK, with the allocating multi-seed search as a fallback when it loses the
    /// pose (a rapid jump, a large first step).
    fn reach(&mut self, target: &Pose, q: &mut [f64; MAX_JOINTS]) -> Result<(), IkFailure> {
        let first = track(self.robot, &mut self.data, target, q, &self.options.ik);
        match first {
            Ok(_) => Ok(()),
            Err(IkFailure::JointLimit { .. }) => first.map(|_| ()),
            Err(failure) => {
                let n = self.robot.joint_count();
                let ik = IkOptions {
                    position_tolerance_m: self.options.ik.position_tolerance_m,
                    orientation_tolerance_rad: self.options.ik.orientation_tolerance_rad,
                    ..IkOptions::default()
                };
                match self.robot.inverse_kinematics(target, &q[..n], &ik) {
                    Ok(solution) => {
                        q[..n].copy_from_slice(&solution.q);
                        self.robot
                            .forward_kinematics(&mut self.data, &q[..n])
                            .expect("joint count checked");
                        limit_violation(self.robot, &q[..n]).map_or(Ok(()), Err)
                    }
                    Err(_) => Err(failure),
                }
            }
        }
    }

    /// Joint values of the desired path: a multi-seed search for the first point (from `seed`),
    /// then tracking.
    fn desired_pass(&mut self, seed: &[f64], progress: &mut dyn FnMut(&Progress)) {
        let n = self.robot.joint_count();
        let count = self.path.len();
        let mut q = [0.0; MAX_JOINTS];
        q[..n].copy_from_slice(seed);
        let ik = IkOptions {
            position_tolerance_m: self.options.ik.position_tolerance_m,
            orientation_tolerance_rad: self.options.ik.orientation_tolerance_rad,
            ..IkOptions::default()
        };
        let mut first_failure = None;
        match self
            .robot
            .inverse_kinematics_search(self.desired(0), Some(seed), &ik)
        {
            Ok(solution) => q[..n].copy_from_slice(&solution.q),
            Err(ModelError::OutOfReach {
                distance_m,
                reach_m,
            }) => {
                first_failure = Some(IkFailure::OutOfReach {
                    distance_m,
                    reach_m,
                })
            }
            Err(ModelError::NotConverged {
                position_error_m,
                orientation_error_rad,
                ..
            }) => {
                first_failure = Some(IkFailure::NotConverged {
                    position_error_m,
                    orientation_error_rad,
                })
            }
            Err(_) => {}
        }
        for i in 0..count {
            let mut qi = q;
            let result = match (i, first_failure) {
                (0, Some(failure)) => Err(failure),
                _ => self.reach(self.desired(i), &mut qi),
            };
            match result {
                Ok(()) => {
                    q = qi;
                    self.points[i].failure = None;
                }
                Err(failure) => self.points[i].failure = Some(PointFailure::Desired(failure)),
            }
            // A failed point keeps the previous point's joint values (continuity for seeds).
            self.points[i].q = q;
            if (i + 1) % PROGRESS_EVERY == 0 || i + 1 == count {
                progress(&Progress {
                    iteration: 0,
                    stage: Stage::Desired,
                    done: i + 1,
                    total: count,
                });
            }
        }
    }

    fn desired_failed(&self, i: usize) -> bool {
        matches!(self.points[i].failure, Some(PointFailure::Desired(_)))
    }

    /// Wrenches, deflections and predicted errors at the current command.
    fn process_pass(
        &mut self,
        source: &mut WrenchSource,
        iteration: usize,
        stage: Stage,
        progress: &mut dyn FnMut(&Progress),
    ) -> Result<PassStats, CompensateError> {
        let n = self.robot.joint_count();
        let count = self.path.len();
        let mut stats = PassStats {
            max_error_m: 0.0,
            max_error_rad: 0.0,
            max_force_n: 0.0,
            max_deflection_m: 0.0,
        };
        if let WrenchSource::Process(model) = source {
            model.begin_pass();
        }
        for i in 0..count {
            let desired = self.desired(i);
            let commanded = commanded_pose(desired, &self.points[i].compensation);
            self.robot
                .forward_kinematics(&mut self.data, &self.points[i].q[..n])
                .expect("joint count checked");
            let w = match source {
                WrenchSource::Process(model) => {
                    let compliance = self.robot.compliance_matrix(&self.data);
                    let point = &self.path.points()[i];
                    let w = model.wrench(&ProcessPoint {
                        index: i,
                        arc_length_m: point.arc_length_m,
                        desired,
                        commanded: &commanded,
                        compliance: &compliance,
                        travel_direction: self.path.travel_direction(i),
                        rapid: i > 0 && point.feed_m_s.is_none(),
                    })?;
                    if !w.iter().all(|v| v.is_finite()) {
                        return Err(ProcessError {
                            model: model.name(),
                            index: i,
                            message: "the wrench is not finite".into(),
                        }
                        .into());
                    }
                    w
                }
                WrenchSource::Fixed { wrenches, .. } => wrenches[i],
            };
            let d = self.predicted(&w);
            let actual = apply_displacement(&commanded, &d);
            let error_m = (actual.translation.vector - desired.translation.vector).norm();
            let error_rad = orientation_error(&desired.rotation, &actual.rotation).norm();
            let point = &mut self.points[i];
            point.wrench = w;
            point.deflection = d;
            point.predicted_error_m = error_m;
            point.predicted_error_rad = error_rad;
            if point.failure.is_none() {
                stats.max_error_m = stats.max_error_m.max(error_m);
                stats.max_error_rad = stats.max_error_rad.max(error_rad);
                stats.max_force_n = stats.max_force_n.max(w.fixed_rows::<3>(0).norm());
                stats.max_deflection_m = stats.max_deflection_m.max(d.fixed_rows::<3>(0).norm());
            }
            if (i + 1) % PROGRESS_EVERY == 0 || i + 1 == count {
                progress(&Progress {
                    iteration,
                    stage,
                    done: i + 1,
                    total: count,
                });
            }
        }
        Ok(stats)
    }

    /// The first fixed-point residual of point `i` at the current command: `−δ − x`, the
    /// deflection of the process pass being the one at the commanded configuration (orientation
    /// zeroed when position only). It is also the point's predicted error to first order.
    fn residual(&self, i: usize) -> Displacement {
        let p = &self.points[i];
        let mut r = -p.deflection - p.compensation;
        if !self.options.orientation {
            r.fixed_rows_mut::<3>(3).fill(0.0);
        }
        r
    }

    /// Solve point `i`'s compensation `x = −δ(q(d ⊕ x), w)` for its current wrench by a few
    /// fixed-point steps from `x`, `q`; checks the limits, the size and the joint step from
    /// `previous_q`.
    fn solve_point(
        &mut self,
        i: usize,
        mut x: Displacement,
        mut q: [f64; MAX_JOINTS],
        previous_q: Option<[f64; MAX_JOINTS]>,
    ) -> Result<(Displacement, [f64; MAX_JOINTS]), PointFailure> {
        let options = *self.options;
        let n = self.robot.joint_count();
        let inner_m = options.tolerance_m * 0.1;
        let inner_rad = options.tolerance_rad * 0.1;
        let desired = self.desired(i);
        let w = self.points[i].wrench;
        for _ in 0..options.inner_iterations {
            self.reach(&commanded_pose(desired, &x), &mut q)
                .map_err(PointFailure::Compensated)?;
            let mut next = -self.predicted(&w);
            if !options.orientation {
                next.fixed_rows_mut::<3>(3).fill(0.0);
            }
            let (dm, dr) = norms(&(next - x));
            x = next;
            if dm <= inner_m && dr <= inner_rad {
                break;
            }
        }
        self.reach(&commanded_pose(desired, &x), &mut q)
            .map_err(PointFailure::Compensated)?;
        let (m, r) = norms(&x);
        if m > options.max_compensation_m || r > options.max_compensation_rad {
            return Err(PointFailure::TooLarge {
                position_m: m,
                rotation_rad: r,
            });
        }
        if let Some(before) = previous_q
            && let Some((joint, step)) = (0..n)
                .map(|j| (j + 1, (q[j] - before[j]).abs()))
                .find(|(_, step)| *step > options.max_joint_step_rad)
        {
            return Err(PointFailure::JointJump {
                joint,
                step_rad: step,
            });
        }
        Ok((x, q))
    }

    /// The next command of a solved point: `x̂`, or the Anderson(1) mixing of the plain step
    /// with the point's previous one (`r = x̂ − x`); plain when the change is within ten
    /// tolerances (the secant of two nearly equal residuals extrapolates noise).
    fn mixed(&self, i: usize, x: &Displacement, x_hat: &Displacement) -> Displacement {
        let r = x_hat - x;
        let Some((x_previous, r_previous)) = self.history[i] else {
            return *x_hat;
        };
        let (rm, rr) = norms(&r);
        if !self.options.acceleration
            || (rm <= 10.0 * self.options.tolerance_m && rr <= 10.0 * self.options.tolerance_rad)
        {
            return *x_hat;
        }
        let weight = self.options.ik.orientation_weight_m;
        let scaled = |v: &Displacement| {
            let mut s = *v;
            s.fixed_rows_mut::<3>(3).scale_mut(weight);
            s
        };
        let dr = r - r_previous;
        let dx = x - x_previous;
        let denominator = scaled(&dr).norm_squared();
        if denominator <= 1e-30 {
            return *x_hat;
        }
        let gamma = scaled(&r).dot(&scaled(&dr)) / denominator;
        let mixed = x + r - (dx + dr) * gamma;
        // A wild extrapolation (nearly parallel residuals) falls back to x̂.
        if scaled(&(mixed - x_hat)).norm() <= 10.0 * scaled(&r).norm() {
            mixed
        } else {
            *x_hat
        }
    }

    /// One compensation pass. A point whose residual ([`Solver::residual`]) is within the
    /// tolerance is left as it is (the per-point criterion: its predicted error is already
    /// below the tolerance); the others are solved for the pass's wrenches and moved to the
    /// mixed iterate (or to `x̂` when `last`, or when the change is within the tolerance).
    fn compensation_pass(
        &mut self,
        iteration: usize,
        last: bool,
        progress: &mut dyn FnMut(&Progress),
    ) -> CompensationPass {
        let count = self.path.len();
        let options = *self.options;
        let mut pass = CompensationPass {
            max_change_m: 0.0,
            max_change_rad: 0.0,
            solved: 0,
        };
        let mut previous_q: Option<[f64; MAX_JOINTS]> = None;
        let mut previous_x: Option<Displacement> = None;
        for i in 0..count {
            if (i + 1) % PROGRESS_EVERY == 0 || i + 1 == count {
                progress(&Progress {
                    iteration,
                    stage: Stage::Compensation,
                    done: i + 1,
                    total: count,
                });
            }
            if self.desired_failed(i) {
                self.history[i] = None;
                continue;
            }
            let (rm, rr) = norms(&self.residual(i));
            if self.points[i].failure.is_none()
                && rm <= options.tolerance_m
                && rr <= options.tolerance_rad
            {
                self.history[i] = None;
                previous_q = Some(self.points[i].q);
                previous_x = Some(self.points[i].compensation);
                continue;
            }
            pass.solved += 1;
            let x = self.points[i].compensation;
            let (start_x, start_q) = match (x == Displacement::zeros(), previous_x, previous_q) {
                // A point without a compensation yet starts from its neighbour's, which differs
                // little along a path (saves one fixed-point step and most of the IK's).
                (true, Some(px), Some(pq)) => (px, pq),
                _ => (x, self.points[i].q),
            };
            match self.solve_point(i, start_x, start_q, previous_q) {
                Err(failure) => {
                    self.points[i].failure = Some(failure);
                    self.points[i].compensation = Displacement::zeros();
                    self.history[i] = None;
                    let mut q = self.points[i].q;
                    if self.reach(self.desired(i), &mut q).is_ok() {
                        self.points[i].q = q;
                    }
                }
                Ok((x_hat, q_hat)) => {
                    self.points[i].failure = None;
                    let change = x_hat - x;
                    let (dm, dr) = norms(&change);
                    pass.max_change_m = pass.max_change_m.max(dm);
                    pass.max_change_rad = pass.max_change_rad.max(dr);
                    previous_q = Some(q_hat);
                    previous_x = Some(x_hat);
                    let within = dm <= options.tolerance_m && dr <= options.tolerance_rad;
                    let mut next = if last || within {
                        x_hat
                    } else {
                        self.mixed(i, &x, &x_hat)
                    };
                    let mut q = q_hat;
                    if next != x_hat {
                        let target = commanded_pose(self.desired(i), &next);
                        if self.reach(&target, &mut q).is_err() {
                            next = x_hat;
                            q = q_hat;
                        }
                    }
                    self.history[i] = Some((x, change));
                    self.points[i].compensation = next;
                    self.points[i].q = q;
                }
            }
        }
        pass
    }
}

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
//!    the predicted error `|a_i − d_i|` of the current command is recorded.
//! 2. **Compensation pass**: for each point, `x̂_i` solves `x = −δ(q(d_i ⊕ x), w_i)` by a few
//!    fixed-point steps (the compliance changes little over a millimetre, so two or three steps
//!    reach 1e-9 m), each with a tracking IK from the previous joint values; the joint limits,
//!    the size of the compensation and the joint step from the previous point are checked.
//! 3. The change `r_i = x̂_i − x_i` is reported; the run has converged when `max |r_i|` is below
//!    the tolerance (position and orientation separately). Otherwise the next command is
//!    `x_i + r_i` or, with [`CompensationOptions::acceleration`], the Anderson(1) mixing
//!    `x_i + r_i − γ_i (Δx_i + Δr_i)`, `γ_i = r_iᵀΔr_i / |Δr_i|²`, per point: a process whose force
//!    grows with the commanded depth makes the plain iteration alternate with a factor up to
//!    `C k / (1 + C k)` (robot compliance × material stiffness), and the secant step removes it.
//! 4. After convergence (or the last iteration) a final process pass gives the wrenches and the
//!    predicted error of the final commanded path.
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
//! the buffers are allocated once per run. The multi-seed IK of the first point, and the
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
    for iteration in 1..=options.max_iterations {
        let stats = solver.process_pass(&mut source, iteration, Stage::Process, progress)?;
        let (change_m, change_rad) = solver.compensation_pass(iteration, progress);
        let failed_points = solver.failures.iter().filter(|f| f.is_some()).count();
        iterations.push(IterationReport {
            iteration,
            max_predicted_error_m: stats.max_error_m,
            max_predicted_error_rad: stats.max_error_rad,
            max_force_n: stats.max_force_n,
            max_deflection_m: stats.max_deflection_m,
            max_change_m: change_m,
            max_change_rad: change_rad,
            failed_points,
        });
        converged =
            fixed || (change_m <= options.tolerance_m && change_rad <= options.tolerance_rad);
        if converged || iteration == options.max_iterations {
            solver.accept();
            break;
        }
        solver.mix(iteration > 1);
    }
    let stats = solver.process_pass(&mut source, 0, Stage::Final, progress)?;
    let mut max_compensation_m: f64 = 0.0;
    let mut max_compensation_rad: f64 = 0.0;
    let points: Vec<CompensatedPoint> = (0..count)
        .map(|i| {
            let (m, r) = norms(&solver.x[i]);
            max_compensation_m = max_compensation_m.max(m);
            max_compensation_rad = max_compensation_rad.max(r);
            CompensatedPoint {
                compensation: solver.x[i],
                q: solver.q[i],
                wrench: solver.w[i],
                deflection: solver.deflection[i],
                predicted_error_m: solver.error[i].0,
                predicted_error_rad: solver.error[i].1,
                failure: solver.failures[i],
            }
        })
        .collect();
    Ok(Compensation {
        source: source_name,
        simulated,
        points,
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

/// Report progress every this many points.
const PROGRESS_EVERY: usize = 4096;

/// The buffers of a run (allocated once) and the passes over them.
struct Solver<'a> {
    robot: &'a Robot,
    path: &'a TcpPath,
    options: &'a CompensationOptions,
    data: Data,
    /// Joint values of the desired poses.
    q_desired: Vec<[f64; MAX_JOINTS]>,
    /// Current compensation and joint values of the commanded poses.
    x: Vec<Displacement>,
    q: Vec<[f64; MAX_JOINTS]>,
    /// Result of the last compensation pass.
    x_hat: Vec<Displacement>,
    q_hat: Vec<[f64; MAX_JOINTS]>,
    /// Previous iterate and residual (Anderson mixing).
    x_previous: Vec<Displacement>,
    r_previous: Vec<Displacement>,
    /// Wrench, deflection and predicted error of the last process pass.
    w: Vec<Wrench>,
    deflection: Vec<Displacement>,
    error: Vec<(f64, f64)>,
    failures: Vec<Option<PointFailure>>,
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
            q_desired: vec![[0.0; MAX_JOINTS]; count],
            x: vec![Displacement::zeros(); count],
            q: vec![[0.0; MAX_JOINTS]; count],
            x_hat: vec![Displacement::zeros(); count],
            q_hat: vec![[0.0; MAX_JOINTS]; count],
            x_previous: vec![Displacement::zeros(); count],
            r_previous: vec![Displacement::zeros(); count],
            w: vec![Wrench::zeros(); count],
            deflection: vec![Displacement::zeros(); count],
            error: vec![(0.0, 0.0); count],
            failures: vec![None; count],
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
                    self.failures[i] = None;
                }
                Err(failure) => self.failures[i] = Some(PointFailure::Desired(failure)),
            }
            // A failed point keeps the previous point's joint values (continuity for seeds).
            self.q_desired[i] = q;
            self.q[i] = q;
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
        matches!(self.failures[i], Some(PointFailure::Desired(_)))
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
            let commanded = commanded_pose(desired, &self.x[i]);
            self.robot
                .forward_kinematics(&mut self.data, &self.q[i][..n])
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
            self.w[i] = w;
            self.deflection[i] = d;
            self.error[i] = (error_m, error_rad);
            if self.failures[i].is_none() {
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

    /// Solve every point's compensation for the current wrenches; returns the largest change.
    fn compensation_pass(
        &mut self,
        iteration: usize,
        progress: &mut dyn FnMut(&Progress),
    ) -> (f64, f64) {
        let n = self.robot.joint_count();
        let count = self.path.len();
        let options = *self.options;
        let inner_m = options.tolerance_m * 0.1;
        let inner_rad = options.tolerance_rad * 0.1;
        let mut change: (f64, f64) = (0.0, 0.0);
        let mut previous_q: Option<[f64; MAX_JOINTS]> = None;
        let mut previous_x: Option<Displacement> = None;
        for i in 0..count {
            if self.desired_failed(i) {
                self.x_hat[i] = Displacement::zeros();
                self.q_hat[i] = self.q_desired[i];
                continue;
            }
            let desired = self.desired(i);
            let mut x = self.x[i];
            let mut q = self.q[i];
            // A point without a compensation yet starts from its neighbour's, which differs
            // little along a path (saves one fixed-point step and most of the IK's).
            if x == Displacement::zeros()
                && let (Some(px), Some(pq)) = (previous_x, previous_q)
            {
                x = px;
                q = pq;
            }
            let mut failure = None;
            for _ in 0..options.inner_iterations {
                if let Err(f) = self.reach(&commanded_pose(desired, &x), &mut q) {
                    failure = Some(PointFailure::Compensated(f));
                    break;
                }
                let d = self.predicted(&self.w[i]);
                let mut next = -d;
                if !options.orientation {
                    next.fixed_rows_mut::<3>(3).fill(0.0);
                }
                let (dm, dr) = norms(&(next - x));
                x = next;
                if dm <= inner_m && dr <= inner_rad {
                    break;
                }
            }
            if failure.is_none()
                && let Err(f) = self.reach(&commanded_pose(desired, &x), &mut q)
            {
                failure = Some(PointFailure::Compensated(f));
            }
            if failure.is_none() {
                let (m, r) = norms(&x);
                if m > options.max_compensation_m || r > options.max_compensation_rad {
                    failure = Some(PointFailure::TooLarge {
                        position_m: m,
                        rotation_rad: r,
                    });
                }
            }
            if failure.is_none()
                && let Some(before) = previous_q
                && let Some((joint, step)) = (0..n)
                    .map(|j| (j + 1, (q[j] - before[j]).abs()))
                    .find(|(_, step)| *step > options.max_joint_step_rad)
            {
                failure = Some(PointFailure::JointJump {
                    joint,
                    step_rad: step,
                });
            }
            self.failures[i] = failure;
            if failure.is_some() {
                self.x_hat[i] = Displacement::zeros();
                self.q_hat[i] = self.q_desired[i];
            } else {
                let (dm, dr) = norms(&(x - self.x[i]));
                change = (change.0.max(dm), change.1.max(dr));
                self.x_hat[i] = x;
                self.q_hat[i] = q;
                previous_q = Some(q);
                previous_x = Some(x);
            }
            if (i + 1) % PROGRESS_EVERY == 0 || i + 1 == count {
                progress(&Progress {
                    iteration,
                    stage: Stage::Compensation,
                    done: i + 1,
                    total: count,
                });
            }
        }
        change
    }

    /// Take the last compensation pass as the command.
    fn accept(&mut self) {
        self.x.copy_from_slice(&self.x_hat);
        self.q.copy_from_slice(&self.q_hat);
    }

    /// Next command: `x̂` or the Anderson(1) mixing per point (`with_history`: a previous
    /// iterate exists).
    fn mix(&mut self, with_history: bool) {
        let weight = self.options.ik.orientation_weight_m;
        let scaled = |v: &Displacement| {
            let mut s = *v;
            s.fixed_rows_mut::<3>(3).scale_mut(weight);
            s
        };
        for i in 0..self.path.len() {
            let x = self.x[i];
            let r = self.x_hat[i] - x;
            let mut next = self.x_hat[i];
            let ok = self.failures[i].is_none();
            if self.options.acceleration && with_history && ok {
                let dr = r - self.r_previous[i];
                let dx = x - self.x_previous[i];
                let denominator = scaled(&dr).norm_squared();
                if denominator > 1e-30 {
                    let gamma = scaled(&r).dot(&scaled(&dr)) / denominator;
                    let mixed = x + r - (dx + dr) * gamma;
                    // A wild extrapolation (nearly parallel residuals) falls back to x̂.
                    if scaled(&(mixed - next)).norm() <= 10.0 * scaled(&r).norm() {
                        next = mixed;
                    }
                }
            }
            self.x_previous[i] = x;
            self.r_previous[i] = r;
            let mut q = self.q_hat[i];
            if ok && next != self.x_hat[i] {
                let target = commanded_pose(self.desired(i), &next);
                if self.reach(&target, &mut q).is_err() {
                    next = self.x_hat[i];
                    q = self.q_hat[i];
                }
            }
            self.x[i] = next;
            self.q[i] = q;
        }
    }
}

//! The state of a compensation run and its passes (see the parent module's documentation).

use super::{
    CompensatedPoint, CompensationOptions, PointFailure, WrenchSource, apply_displacement,
    commanded_pose, norms,
};
use crate::error::{CompensateError, ProcessError};
use crate::ik::{IkFailure, limit_violation, track};
use crate::path::TcpPath;
use crate::process::{ProcessModel, ProcessPoint};
use deflex_model::spatial::orientation_error;
use deflex_model::{Data, Displacement, IkOptions, MAX_JOINTS, ModelError, Pose, Robot, Wrench};
use deflex_telemetry::{OnProgress, Progress};
use nalgebra::Vector3;

/// Statistics of a process pass over the compensated points.
#[derive(Default)]
pub(super) struct PassStats {
    pub max_error_m: f64,
    pub max_error_rad: f64,
    pub max_force_n: f64,
    pub max_deflection_m: f64,
}

/// What a compensation pass did.
#[derive(Default)]
pub(super) struct CompensationPass {
    /// Largest change of a solved point's compensation (m, rad).
    pub max_change_m: f64,
    pub max_change_rad: f64,
    /// Points whose compensation was solved again (the others were within the tolerance).
    pub solved: usize,
    /// The joint values and compensation of the last point handled (seeds of the next).
    previous_q: Option<[f64; MAX_JOINTS]>,
    previous_x: Option<Displacement>,
}

/// Largest ratio `|r| / |r_prev|` of a consistent contraction that takes the secant step within
/// ten tolerances ([`Solver::mixed`]): the step `r/(1 − c)` then extrapolates at most ten times
/// `r`, the limit of the wild-extrapolation guard. At 0.5 (twice the step) points where the
/// force builds up with the depth converged by plain steps at `c` ≈ 0.6–0.8: on the CAM parts
/// of `docs/parts` split into 5 µm moves, 9 and 12 iterations against 6 and 11.
const MAX_CONTRACTION: f64 = 0.9;

/// Report progress every this many points.
const PROGRESS_EVERY: usize = 4096;

/// The state of a run (allocated once): per point the result being built (compensation, joint
/// values, wrench, deflection, predicted error, failure) and the previous iterate and change
/// for the Anderson mixing.
pub(super) struct Solver<'a> {
    robot: &'a Robot,
    path: &'a TcpPath,
    options: &'a CompensationOptions,
    data: Data,
    pub(super) points: Vec<CompensatedPoint>,
    /// `(x, r)` of the point's previous solve, when it was solved in the previous iteration.
    history: Vec<Option<(Displacement, Displacement)>>,
    /// The deflection the robot model misses at each point, when the process model knows it
    /// ([`ProcessModel::unmodelled_deflection`]; empty otherwise).
    unmodelled: Vec<Vector3<f64>>,
}

impl<'a> Solver<'a> {
    pub(super) fn new(
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
            unmodelled: Vec::new(),
        }
    }

    fn desired(&self, i: usize) -> &'a Pose {
        &self.path.points()[i].pose
    }

    /// Model deflection at the configuration in `self.data` under `w` (the wrench of point `i`),
    /// plus what the process model says the robot model misses there.
    fn predicted(&self, i: usize, w: &Wrench) -> Displacement {
        let mut d = self.robot.tcp_deflection(&self.data, w);
        if let Some(u) = self.unmodelled.get(i) {
            let mut position = d.fixed_rows_mut::<3>(0);
            position += u;
        }
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
    pub(super) fn desired_pass(&mut self, seed: &[f64], progress: OnProgress<'_>) {
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
                progress(Progress::Work {
                    done: i + 1,
                    total: count,
                });
            }
        }
    }

    /// Show the desired path to a process model that asks for it
    /// ([`ProcessModel::observe_desired`]): every point at its desired joint values.
    pub(super) fn observation_pass(
        &mut self,
        model: &mut dyn ProcessModel,
        progress: OnProgress<'_>,
    ) -> Result<(), CompensateError> {
        let n = self.robot.joint_count();
        let count = self.path.len();
        for i in 0..count {
            if (i + 1) % PROGRESS_EVERY == 0 || i + 1 == count {
                progress(Progress::Work {
                    done: i + 1,
                    total: count,
                });
            }
            let desired = self.desired(i);
            self.robot
                .forward_kinematics(&mut self.data, &self.points[i].q[..n])
                .expect("joint count checked");
            let compliance = self.robot.compliance_matrix(&self.data);
            let point = &self.path.points()[i];
            model.observe_desired(&ProcessPoint {
                index: i,
                arc_length_m: point.arc_length_m,
                desired,
                commanded: desired,
                compliance: &compliance,
                travel_direction: self.path.travel_direction(i),
                rapid: i > 0 && point.feed_m_s.is_none(),
            })?;
        }
        model.finish_observation()?;
        Ok(())
    }

    fn desired_failed(&self, i: usize) -> bool {
        matches!(self.points[i].failure, Some(PointFailure::Desired(_)))
    }

    /// Wrenches, deflections and predicted errors at the current command (the final pass).
    pub(super) fn process_pass(
        &mut self,
        source: &mut WrenchSource,
        progress: OnProgress<'_>,
    ) -> Result<PassStats, CompensateError> {
        let count = self.path.len();
        let mut stats = PassStats::default();
        if let WrenchSource::Process(model) = source {
            model.begin_pass();
        }
        for i in 0..count {
            self.process_point(source, i, &mut stats)?;
            if (i + 1) % PROGRESS_EVERY == 0 || i + 1 == count {
                progress(Progress::Work {
                    done: i + 1,
                    total: count,
                });
            }
        }
        Ok(stats)
    }

    /// One iteration: for each point in path order, its wrench at its current command (a
    /// process model sees the commands of the points before it as this sweep left them), then
    /// its compensation (see [`Solver::compensate_point`]).
    pub(super) fn sweep(
        &mut self,
        source: &mut WrenchSource,
        last: bool,
        progress: OnProgress<'_>,
    ) -> Result<(PassStats, CompensationPass), CompensateError> {
        let count = self.path.len();
        let mut stats = PassStats::default();
        let mut pass = CompensationPass::default();
        if let WrenchSource::Process(model) = source {
            model.begin_pass();
        }
        for i in 0..count {
            self.process_point(source, i, &mut stats)?;
            self.compensate_point(i, last, &mut pass);
            if (i + 1) % PROGRESS_EVERY == 0 || i + 1 == count {
                progress(Progress::Work {
                    done: i + 1,
                    total: count,
                });
            }
        }
        Ok((stats, pass))
    }

    /// The wrench, deflection and predicted error of point `i` at its current command.
    fn process_point(
        &mut self,
        source: &mut WrenchSource,
        i: usize,
        stats: &mut PassStats,
    ) -> Result<(), CompensateError> {
        let n = self.robot.joint_count();
        let count = self.path.len();
        {
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
            if let WrenchSource::Process(model) = source
                && let Some(u) = model.unmodelled_deflection(i, &w)
            {
                if self.unmodelled.is_empty() {
                    self.unmodelled = vec![Vector3::zeros(); count];
                }
                self.unmodelled[i] = u;
            }
            let d = self.predicted(i, &w);
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
        }
        Ok(())
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
            let mut next = -self.predicted(i, &w);
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
    /// with the point's previous one (`r = x̂ − x`). Within ten tolerances the plain step is
    /// taken (the secant of two nearly equal residuals extrapolates the process's noise) unless
    /// the residuals show the map's linear part:
    /// * reversed (`r·r_prev < 0`): the point oscillates about its fixed point (an elastic
    ///   contact alternates with a factor up to `C k / (1 + C k)`), and the secant step, with
    ///   `γ ∈ (0, 1)`, lies between the iterates (for a period-2 cycle, halfway);
    /// * a consistent contraction (the same direction within 25°, at most
    ///   [`MAX_CONTRACTION`] as long): the force grows with the depth the compensated tool
    ///   reaches (`r = c·r_prev`, `c ≈ 0.25` at the end of the paper's cone, 0.6–0.8 where a
    ///   tool enters the sheet and the force builds up over the first millimetres of depth, and
    ///   where the twin's radial force turns with the command), and the secant step
    ///   `r/(1 − c)` lands on the fixed point, extrapolating at most ten times the step. Noise
    ///   neither reverses nor shrinks consistently, and a point whose residual is within half
    ///   the tolerance is not solved at all.
    fn mixed(&self, i: usize, x: &Displacement, x_hat: &Displacement) -> Displacement {
        let r = x_hat - x;
        let Some((x_previous, r_previous)) = self.history[i] else {
            return *x_hat;
        };
        if !self.options.acceleration {
            return *x_hat;
        }
        let weight = self.options.ik.orientation_weight_m;
        let scaled = |v: &Displacement| {
            let mut s = *v;
            s.fixed_rows_mut::<3>(3).scale_mut(weight);
            s
        };
        let (rm, rr) = norms(&r);
        let small =
            rm <= 10.0 * self.options.tolerance_m && rr <= 10.0 * self.options.tolerance_rad;
        if small {
            let (now, before) = (scaled(&r), scaled(&r_previous));
            let dot = now.dot(&before);
            let reversed = dot < 0.0;
            let contracting = dot >= 0.9 * now.norm() * before.norm()
                && now.norm() <= MAX_CONTRACTION * before.norm();
            if !(reversed || contracting) {
                return *x_hat;
            }
        }
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

    /// Point `i`'s compensation for its current wrench. A point whose residual
    /// ([`Solver::residual`]) is within half the tolerance is left as it is (the per-point
    /// criterion: its predicted error is already below it); the others are solved and moved to
    /// the mixed iterate (or to `x̂` when `last`, or when the change is within the tolerance).
    fn compensate_point(&mut self, i: usize, last: bool, pass: &mut CompensationPass) {
        let options = *self.options;
        {
            if self.desired_failed(i) {
                self.history[i] = None;
                return;
            }
            let (rm, rr) = norms(&self.residual(i));
            if self.points[i].failure.is_none()
                && rm <= 0.5 * options.tolerance_m
                && rr <= 0.5 * options.tolerance_rad
            {
                self.history[i] = None;
                pass.previous_q = Some(self.points[i].q);
                pass.previous_x = Some(self.points[i].compensation);
                return;
            }
            pass.solved += 1;
            let x = self.points[i].compensation;
            let (start_x, start_q) =
                match (x == Displacement::zeros(), pass.previous_x, pass.previous_q) {
                    // A point without a compensation yet starts from its neighbour's, which differs
                    // little along a path (saves one fixed-point step and most of the IK's).
                    (true, Some(px), Some(pq)) => (px, pq),
                    _ => (x, self.points[i].q),
                };
            match self.solve_point(i, start_x, start_q, pass.previous_q) {
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
                    pass.previous_q = Some(q_hat);
                    pass.previous_x = Some(x_hat);
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
    }
}

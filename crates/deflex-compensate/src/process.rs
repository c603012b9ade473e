//! Process models: what wrench the process puts on the tool when the robot is commanded along a
//! path. The compensation iterates against one because the force depends on the commanded
//! path (a tool commanded deeper pushes harder).
//!
//! ## Adding a process model
//!
//! Implement [`ProcessModel`]. The compensation calls [`ProcessModel::begin_pass`] before each
//! pass over the path and then [`ProcessModel::wrench`] once per point, **in path order**, so a
//! model may carry state along the path (the formed sheet of incremental forming, the material
//! already removed in machining). Each call receives the desired pose, the commanded pose the
//! robot is given in this iteration, the robot model's 6×6 Cartesian compliance at the commanded
//! configuration (so a model can solve its own equilibrium between the robot's compliance and the
//! material, as the twin's forming adapter `deflex_sim::process_model` does) and the direction of
//! travel. It returns the wrench **on the tool, at the TCP, in world axes** (N, N·m; moment about
//! the TCP): the wrench of eq. 15 that deflects the robot. The per-point call should not
//! allocate; it must return a finite wrench or an error naming what went wrong.
//!
//! A model learnt from a previous run may need the path before the first pass: with
//! [`ProcessModel::observes_desired_path`] the compensation calls
//! [`ProcessModel::observe_desired`] once per point, in order, at the desired path (no
//! compensation, the desired pose's joint values and compliance), then
//! [`ProcessModel::finish_observation`]. A model whose wrench turns out not to depend on the
//! command ([`ProcessModel::follows_command`] false) gets one compensation pass, which is then
//! exact. A model that knows the deflection the robot model misses at a point (measured in a
//! previous run) returns it from [`ProcessModel::unmodelled_deflection`]; the compensation adds it
//! to eq. 15's. [`crate::logged::LoggedProcess`] uses all three.
//!
//! [`DepthProportional`] is the smallest useful model (a force growing linearly with the
//! commanded depth below a surface); its fixed point has a closed form, which the tests use.

use crate::error::ProcessError;
use deflex_model::{Pose, Wrench};
use nalgebra::{Matrix6, Vector3};

/// What a process model sees at one point of a pass.
#[derive(Clone, Copy, Debug)]
pub struct ProcessPoint<'a> {
    /// Point index along the path.
    pub index: usize,
    /// Arc length of the point (m).
    pub arc_length_m: f64,
    /// Desired TCP pose (world).
    pub desired: &'a Pose,
    /// Commanded TCP pose in this iteration (world): the desired pose plus the compensation.
    pub commanded: &'a Pose,
    /// The robot model's Cartesian compliance at the commanded configuration (world axes, at the
    /// TCP; maps a wrench to `[δp; δφ]`, eq. 15).
    pub compliance: &'a Matrix6<f64>,
    /// Unit direction of travel of the desired path (world); zero when the TCP does not move.
    pub travel_direction: Vector3<f64>,
    /// The move ending here is a rapid move.
    pub rapid: bool,
}

/// A process that pushes on the tool (see the module documentation).
pub trait ProcessModel {
    /// Name for reports.
    fn name(&self) -> String;
    /// Whether the model is a simulation (its wrenches are then labelled SIMULATED).
    fn simulated(&self) -> bool;
    /// Start a pass over the path from its first point (reset any state).
    fn begin_pass(&mut self);
    /// The wrench on the tool at this point (world axes, moment about the TCP).
    fn wrench(&mut self, point: &ProcessPoint) -> Result<Wrench, ProcessError>;

    /// Whether the model wants to see the desired path before the first pass (default: no).
    fn observes_desired_path(&self) -> bool {
        false
    }

    /// One point of the desired path (compensation zero, the compliance at the desired pose's
    /// joint values), in path order, before the first pass; only when
    /// [`ProcessModel::observes_desired_path`].
    fn observe_desired(&mut self, _point: &ProcessPoint) -> Result<(), ProcessError> {
        Ok(())
    }

    /// The observation of the desired path is complete (identify what needs the whole path).
    fn finish_observation(&mut self) -> Result<(), ProcessError> {
        Ok(())
    }

    /// Whether the wrench depends on the commanded path (after the observation). When it does
    /// not, one compensation pass is exact and the run stops after it. Default: yes.
    fn follows_command(&self) -> bool {
        true
    }

    /// The TCP deflection the robot model does not predict at point `index` under `wrench` (the
    /// wrench this model returned there; position, world axes, m), known from a measured run;
    /// added to eq. 15's. `None` (the default): the model's deflection is all there is.
    fn unmodelled_deflection(&self, _index: usize, _wrench: &Wrench) -> Option<Vector3<f64>> {
        None
    }
}

/// A force along `direction` (unit, world) proportional to how deep the commanded TCP lies
/// below a plane: `f = k · max(0, h − n·p)` with `n = direction`, `h = surface_m`. With
/// `direction = +z` it is an upward push growing with the commanded depth under `z = h`. It
/// ignores the robot's compliance (the force follows the command, not the deflected tool), which
/// makes the compensation's fixed point closed-form: `c_n = (d_n − C_nn k h) / (1 − C_nn k)`
/// along the direction, and converges by plain iteration when `C_nn k < 1`.
#[derive(Clone, Debug, PartialEq)]
pub struct DepthProportional {
    /// Unit direction of the force and of the depth measure (world).
    pub direction: Vector3<f64>,
    /// Height of the surface along `direction` (m).
    pub surface_m: f64,
    /// Force per metre of depth (N/m).
    pub stiffness_n_m: f64,
}

impl ProcessModel for DepthProportional {
    fn name(&self) -> String {
        format!(
            "depth-proportional force, {:.1} N/mm",
            self.stiffness_n_m * 1e-3
        )
    }

    fn simulated(&self) -> bool {
        true
    }

    fn begin_pass(&mut self) {}

    fn wrench(&mut self, point: &ProcessPoint) -> Result<Wrench, ProcessError> {
        let depth = self.surface_m - self.direction.dot(&point.commanded.translation.vector);
        let f = self.direction * (self.stiffness_n_m * depth.max(0.0));
        if f.iter().all(|v| v.is_finite()) {
            Ok(Wrench::new(f.x, f.y, f.z, 0.0, 0.0, 0.0))
        } else {
            Err(ProcessError {
                model: self.name(),
                index: point.index,
                message: format!("non-finite force for depth {depth} m"),
            })
        }
    }
}

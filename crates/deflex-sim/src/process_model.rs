//! The twin's forming model as a process model for offline compensation
//! (`deflex_compensate::ProcessModel`), SIMULATED. A thin adapter over the public API of
//! [`crate::sheet::Sheet`]: the compensation gives it, point by point along the path, the
//! commanded TCP and the robot *model's* compliance there; it finds the quasi-static equilibrium
//! between that compliance and the sheet (the force at the tool's predicted position, the
//! predicted position under that force: the same bracketed root find on the vertical force as
//! the twin's cell, with the model instead of the plant), lets the sheet flow there, and returns
//! the contact wrench. A tool commanded deeper pushes harder, which is why the compensation
//! iterates.
//!
//! The path's waypoints can be far apart (5° on the cone, 1.3 mm); the sheet is stored on 1°
//! rays, so between two points the adapter walks the commanded segment in sub-steps and forms
//! the sheet at each, returning the wrench at the point itself. The number of sub-steps is the
//! *desired* segment's length over [`FormingProcess::max_step_m`] (rounded up).
//!
//! **The twin's law, state included.** Each sub-step does what the twin's cell does each robot
//! cycle (`Workpiece::commit` in [`crate::cell`]): the sheet flows at the tool's predicted
//! position, and, in contact, the pass is recorded ([`Sheet::observe_pass_at`]): the sheet's
//! per-sector memory of the last pass gives the *actual* step-down and wall angle, hence the
//! Aerens level, which grows with the actual depth ([`Sheet::flow_force`]). A tool predicted to
//! deflect upwards forms smaller steps at a lower level; a compensated one forms the programmed
//! steps at the programmed level and deeper, at a higher force, as in the twin. (Without the pass
//! record the level would stay at the programmed step-down and wall angle: the twin's law before
//! it learnt to push back, which over-predicts the uncompensated force and under-predicts the
//! compensated depth's growth.)
//!
//! **A discretisation the iterations share.** The compensation iterates on the command; the
//! sheet's discretisation must not move with it. Two parts of it did, and held long paths up:
//! * the pass record updates the Aerens level once per 1° sector, so along the path the level
//!   is a staircase (0.4–0.5 N a step in the cone's last contour, where it falls from 1310 to
//!   1264 N: about 1 µrad of the TX200's orientation compensation, the tolerance). Booked at the
//!   *predicted* tool's sector, each step sat wherever the current command put the tool: a
//!   point within a few µm of a sector boundary changed sides when its command moved by the
//!   last iteration's change, its force jumped by a step and its compensation by a tolerance.
//!   At 5.2 µm between points (1 M points on the cone) nearly every sector boundary has such a
//!   point; at 48.5 µm (100 000) few do: the million-point cone needed 8 iterations against 6,
//!   its unconverged points the sector-entry points of the last contour;
//! * the number of sub-steps came from the *commanded* segment's length, which crosses a
//!   multiple of `max_step_m` as the command changes: the sheet was formed once more or once
//!   less at that point, and the level stepped at another sub-step (on the twin cell's
//!   nominal robot with its 0.2 m tool one point alternated between 1 and 2 sub-steps for four
//!   iterations).
//!
//! So the sub-steps are counted on the desired segment and the pass is booked in the sector of
//! the desired path ([`Sheet::observe_pass_at`]), with the predicted tool's radius and depth:
//! where the level steps is fixed for every iteration, and the force depends on the command
//! only through the tool's predicted position, continuously. At the converged command the
//! predicted tool is on the desired path within the tolerance, so the booking differs from the
//! twin's only for a tool within that distance of a sector boundary.
//!
//! With the default [`crate::sheet::SheetConfig`] the process model *is* the twin's forming law:
//! an optimistic assumption that a real process model (FE, Aerens' formula, a previous run) does
//! not meet. Pass another `SheetConfig` to study a mismatched model. What it cannot share with
//! the twin is the plant: it deflects with the robot *model's* compliance (eq. 15), not the
//! twin's large-rotation spring chain with its unmodelled effects.
//!
//! Also here: [`tcp_path`] (a [`ToolPath`] in the part frame → a `TcpPath` in the world, tool
//! orientation fixed), [`compensated_tool_path`] (the way back: a compensation → the robot
//! program as a [`ToolPath`] the twin can run) and [`builtin_tool_path`] (the built-in paths by
//! name; a G-code file is read by the application layer, `deflex_app::load::gcode_file`).

use crate::cell_config::CellConfig;
use crate::error::SimError;
use crate::sheet::{ContactState, Sheet, SheetConfig};
use crate::toolpath::{ConeParams, PyramidParams, ToolPath};
use deflex_compensate::{ProcessError, ProcessModel, ProcessPoint, TcpPath};
use deflex_model::{Pose, Wrench};
use nalgebra::{Matrix6, Rotation3, Vector3};

/// The equilibrium's force tolerance (N): 0.01 N moves the predicted tool by about 25 nm on
/// the TX200 (compliance ≈ 2.5 µm/N), well below the compensation's 1 µm tolerance (0.05 N
/// left 0.12 µm of noise, which the largest of a million points' changes sees).
pub const FORCE_TOLERANCE_N: f64 = 0.01;

/// Most sub-steps between two path points (a longer segment is walked in longer steps).
pub const MAX_SUBSTEPS: usize = 100_000;

/// The forming process of the twin as a process model (see the module documentation).
#[derive(Clone, Debug)]
pub struct FormingProcess {
    flat: Sheet,
    sheet: Sheet,
    part: Pose,
    feed_ratio: f64,
    /// Longest step between sheet updates along a segment (m).
    pub max_step_m: f64,
    /// The previous point's commanded and desired positions (part frame).
    previous: Option<(Vector3<f64>, Vector3<f64>)>,
    last_force: f64,
}

impl FormingProcess {
    /// A flat sheet for `path` (its step-down and wall angle set the Aerens level, as in the
    /// twin), the part frame in the world, sheet updates every `max_step_m` at most.
    pub fn new(
        sheet: &SheetConfig,
        path: &ToolPath,
        part_frame: &Pose,
        max_step_m: f64,
    ) -> Result<FormingProcess, SimError> {
        if !(max_step_m.is_finite() && (1e-6..=0.01).contains(&max_step_m)) {
            return Err(SimError::config(
                "process.max_step_m",
                format!("expected 1e-6 ..= 0.01 m, got {max_step_m}"),
            ));
        }
        let flat = Sheet::new(
            sheet,
            path.step_down_mm.unwrap_or(sheet.default_step_down_mm),
            path.wall_angle_deg.unwrap_or(sheet.default_wall_angle_deg),
        )?;
        Ok(FormingProcess {
            sheet: flat.clone(),
            flat,
            part: *part_frame,
            feed_ratio: sheet.feed_ratio,
            max_step_m,
            previous: None,
            last_force: 0.0,
        })
    }

    /// The twin's own sheet and part placement (`config.sheet`, `config.part`), steps of 0.1 mm.
    pub fn from_cell(config: &CellConfig, path: &ToolPath) -> Result<FormingProcess, SimError> {
        FormingProcess::new(&config.sheet, path, &config.part_frame(), 1e-4)
    }

    /// Steady-state (Aerens) force level of this sheet (N).
    pub fn steady_force_n(&self) -> f64 {
        self.flat.steady_force_n()
    }

    /// The sheet as formed by the pass so far (its surface, pass memory and Aerens level).
    pub fn sheet(&self) -> &Sheet {
        &self.sheet
    }

    /// Quasi-static equilibrium at commanded position `p_cmd` (part frame) with compliance
    /// `compliance` (part axes): the vertical force `F = min(k δ(p(F)), F_flow(p(F)))`,
    /// `p(F) = p_cmd + (C · w(F))_p`, by a bracketed regula falsi (Illinois) on the increasing
    /// `g(F) = F − force(p(F))`, to [`FORCE_TOLERANCE_N`]. Returns the wrench (part axes), the tool's position and the
    /// contact state there.
    fn equilibrium(
        &self,
        p_cmd: &Vector3<f64>,
        compliance: &Matrix6<f64>,
        feed_dir: &Vector3<f64>,
    ) -> (Wrench, Vector3<f64>, ContactState) {
        let free = self.sheet.contact(p_cmd);
        if free.force_n <= 0.0 {
            return (Wrench::zeros(), *p_cmd, free);
        }
        let force = self.sheet.force_vector(p_cmd, 1.0, feed_dir, free.depth_m);
        let friction = -feed_dir * self.feed_ratio;
        let moment = Vector3::new(0.0, 0.0, -self.sheet.tool_radius_m()).cross(&friction);
        let unit = Wrench::new(force.x, force.y, force.z, moment.x, moment.y, moment.z);
        let unit_shift = (compliance * unit).fixed_rows::<3>(0).into_owned();
        let eval = |f: f64| -> (f64, Vector3<f64>, ContactState) {
            let p = p_cmd + unit_shift * f;
            let c = self.sheet.contact(&p);
            (f - c.force_n, p, c)
        };
        let (mut a, mut ga) = (0.0, -free.force_n);
        // Warm start from the previous point's force (the force changes little between
        // neighbouring points): often the answer, otherwise a bound.
        let mut upper = None;
        let guess = self.last_force;
        if guess > 0.0 && guess < free.force_n {
            let (g, p, c) = eval(guess);
            if g.abs() < FORCE_TOLERANCE_N {
                return (unit * guess, p, c);
            }
            if g < 0.0 {
                (a, ga) = (guess, g);
            } else {
                upper = Some((guess, g, p, c));
            }
        }
        let (mut b, mut gb, mut pb, mut cb) = match upper {
            Some(bound) => bound,
            None => {
                let (g, p, c) = eval(free.force_n);
                if g <= 0.0 {
                    return (unit * free.force_n, p, c);
                }
                (free.force_n, g, p, c)
            }
        };
        let mut side = 0i8;
        for _ in 0..60 {
            let x = (a * gb - b * ga) / (gb - ga);
            let (g, p, c) = eval(x);
            if g.abs() < FORCE_TOLERANCE_N || (b - a) < 1e-6 {
                return (unit * x, p, c);
            }
            if g < 0.0 {
                (a, ga) = (x, g);
                if side == -1 {
                    gb *= 0.5;
                }
                side = -1;
            } else {
                (b, gb, pb, cb) = (x, g, p, c);
                if side == 1 {
                    ga *= 0.5;
                }
                side = 1;
            }
        }
        (unit * b, pb, cb)
    }
}

impl ProcessModel for FormingProcess {
    fn name(&self) -> String {
        format!(
            "twin forming model (SIMULATED): Aerens level {:.0} N",
            self.flat.steady_force_n()
        )
    }

    fn simulated(&self) -> bool {
        true
    }

    fn begin_pass(&mut self) {
        self.sheet.clone_from(&self.flat);
        self.previous = None;
        self.last_force = 0.0;
    }

    fn wrench(&mut self, point: &ProcessPoint) -> Result<Wrench, ProcessError> {
        let r = self.part.rotation;
        let to_part = r.inverse();
        let p_cmd = to_part * (point.commanded.translation.vector - self.part.translation.vector);
        if !p_cmd.iter().all(|v| v.is_finite()) {
            return Err(ProcessError {
                model: self.name(),
                index: point.index,
                message: "commanded position is not finite".into(),
            });
        }
        // The compliance in part axes: blockdiag(Rᵀ, Rᵀ) · C · blockdiag(R, R).
        let mut rotate = Matrix6::zeros();
        rotate.fixed_view_mut::<3, 3>(0, 0).copy_from(r.matrix());
        rotate.fixed_view_mut::<3, 3>(3, 3).copy_from(r.matrix());
        let compliance = rotate.transpose() * point.compliance * rotate;
        let mut feed_dir = to_part * point.travel_direction;
        feed_dir.z = 0.0;
        let norm = feed_dir.norm();
        let feed_dir = if norm > 1e-9 {
            feed_dir / norm
        } else {
            Vector3::zeros()
        };
        let p_des = to_part * (point.desired.translation.vector - self.part.translation.vector);
        let (start, start_des) = self.previous.unwrap_or((p_cmd, p_des));
        // The sub-steps and the pass record follow the desired path, which every iteration
        // shares (see the module documentation: a discretisation that followed the command
        // moved with it and held long paths up).
        let length = (p_des - start_des).norm();
        let steps = ((length / self.max_step_m).ceil() as usize).clamp(1, MAX_SUBSTEPS);
        let mut wrench = Wrench::zeros();
        for k in 1..=steps {
            let f = k as f64 / steps as f64;
            let p = start + (p_cmd - start) * f;
            let booked = start_des + (p_des - start_des) * f;
            let (w, p_true, contact) = self.equilibrium(&p, &compliance, &feed_dir);
            // As the twin's cell does each cycle (`Workpiece::commit`): flow, then record the
            // pass, which sets the Aerens level at the actual step-down and wall angle.
            self.sheet.form(&p_true, &contact);
            if contact.force_n > 0.0 {
                self.sheet
                    .observe_pass_at(booked.y.atan2(booked.x), &p_true, contact.depth_m);
            }
            self.last_force = w[2];
            wrench = w;
        }
        self.previous = Some((p_cmd, p_des));
        let f = r * Vector3::new(wrench[0], wrench[1], wrench[2]);
        let m = r * Vector3::new(wrench[3], wrench[4], wrench[5]);
        Ok(Wrench::new(f.x, f.y, f.z, m.x, m.y, m.z))
    }
}

/// A tool path (part frame, mm) as TCP poses in the world: each waypoint placed with the part
/// frame, the tool held at `tool_rotation` (the twin holds the orientation of its seed
/// configuration); feeds in m/s, rapids at `rapid_feed_mm_s`.
pub fn tcp_path(
    path: &ToolPath,
    part_frame: &Pose,
    tool_rotation: &Rotation3<f64>,
    rapid_feed_mm_s: f64,
) -> Result<TcpPath, SimError> {
    path.validate()?;
    let poses = path.waypoints.iter().map(|w| {
        let p = part_frame * nalgebra::Point3::from(Vector3::from(w.p_mm) * 1e-3);
        (
            Pose::from_parts(p.coords.into(), *tool_rotation),
            w.feed_mm_s.map(|f| f * 1e-3),
        )
    });
    TcpPath::new(&path.name, poses, rapid_feed_mm_s * 1e-3)
        .map_err(|e| SimError::Path(e.to_string()))
}

/// The robot program of a compensation as a [`ToolPath`] the twin can run against `path` (its
/// reference, see [`crate::cell::Cell::with_reference`]): waypoint i is the commanded position
/// of point i (`points[i]`, world, m) in the part frame, mm, with the reference's feeds,
/// step-down and wall angle. The twin holds the tool orientation, so only positions are taken
/// (compensate position only for the twin). `points` must have one entry per waypoint.
pub fn compensated_tool_path(
    path: &ToolPath,
    commanded_m: &[Vector3<f64>],
    part_frame: &Pose,
) -> Result<ToolPath, SimError> {
    if commanded_m.len() != path.waypoints.len() {
        return Err(SimError::Path(format!(
            "{} compensated points for the {} waypoints of \"{}\"",
            commanded_m.len(),
            path.waypoints.len(),
            path.name
        )));
    }
    let to_part = part_frame.inverse();
    let waypoints = path
        .waypoints
        .iter()
        .zip(commanded_m)
        .map(|(w, c)| {
            let p = to_part * nalgebra::Point3::from(*c) * 1e3;
            crate::toolpath::Waypoint {
                p_mm: [p.x, p.y, p.z],
                feed_mm_s: w.feed_mm_s,
            }
        })
        .collect();
    let program = ToolPath {
        name: format!("{} (compensated)", path.name),
        waypoints,
        step_down_mm: path.step_down_mm,
        wall_angle_deg: path.wall_angle_deg,
    };
    program.validate()?;
    Ok(program)
}

/// A built-in path by name (`cone`: the paper's helical cone, `cone-contour`, `pyramid`);
/// `None` for any other name (a G-code file, read by the application layer:
/// `deflex_app::load::gcode_file::tool_path_by_name`).
pub fn builtin_tool_path(name: &str) -> Option<Result<ToolPath, SimError>> {
    match name {
        "cone" => Some(Ok(ToolPath::paper_cone())),
        "cone-contour" => Some(ToolPath::cone(&ConeParams {
            helical: false,
            ..ConeParams::default()
        })),
        "pyramid" => Some(ToolPath::pyramid(&PyramidParams::default())),
        _ => None,
    }
}

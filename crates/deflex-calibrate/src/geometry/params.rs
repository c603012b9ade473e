//! The error parameters of the elasto-geometric model and the state they act on.
//!
//! Every parameter is a small correction applied to an [`EgModel`] by [`EgModel::apply`]:
//! additive for DH rows, θ offsets, target offsets, compliances, lumped masses, harmonics and
//! backlash; on SO(3) for set-up rotations (`R ← R·exp(δφ)`, the increment in robot-world axes)
//! and target rotations (`R_t ← exp(δφ)·R_t`, the increment in flange axes). The LM
//! loop linearises around the current model, so every increment is small and every parameter
//! has a clear physical reading.

use deflex_model::{DhConvention, NamedPoint, NamedPose, Robot};
use nalgebra::{Rotation3, Vector3};

/// Which DH field a geometric parameter corrects.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum DhField {
    /// Joint offset θ (rad): the joint's `theta_offset`.
    Theta,
    /// Offset d along the joint axis (m).
    D,
    /// Length a (m).
    A,
    /// Twist α (rad).
    Alpha,
    /// Hayati tilt β about y (rad), for rows whose consecutive axes are parallel.
    Beta,
}

impl DhField {
    fn name(self) -> &'static str {
        match self {
            DhField::Theta => "theta",
            DhField::D => "d",
            DhField::A => "a",
            DhField::Alpha => "alpha",
            DhField::Beta => "beta",
        }
    }
}

/// One identifiable quantity (before reduction).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Param {
    /// Set-up `s`: rotation about robot-world axis `k` (0 = x, 1 = y, 2 = z) through the world
    /// origin (rad).
    SetupRotation(usize, usize),
    /// Set-up `s`: translation along robot-world axis `k` (m).
    SetupTranslation(usize, usize),
    /// Target `t`: coordinate `k` of its position in the flange frame (m).
    Target(usize, usize),
    /// Target `t`: rotation of its frame about flange axis `k` (rad; fitted from measured
    /// orientations only).
    TargetRotation(usize, usize),
    /// DH field of joint `j` (0-based).
    Dh(usize, DhField),
    /// Compliance 1/k of eDoF `e` (index in [`Robot::edofs`] order), rad/(N·m).
    Compliance(usize),
    /// Mass of body `b` (0-based joint index), kg.
    Mass(usize),
    /// First moment m·c of body `b` about axis `k` of its joint frame R_b (kg·m).
    FirstMoment(usize, usize),
    /// Joint-angle-dependent offset of joint `j`: `Δθ_j = a·cos(n q_j)` (`sine` false) or
    /// `b·sin(n q_j)`, order `n` (rad): encoder eccentricity (low orders) or a gear's
    /// transmission error (orders at the gear ratio and its multiples).
    Harmonic {
        /// Joint (0-based).
        joint: usize,
        /// Order n ≥ 1 (cycles per joint turn).
        order: u16,
        /// Sine (true) or cosine (false) term.
        sine: bool,
    },
    /// Direction-dependent offset of joint `j` (rad): `Δθ_j = b_j · sign(approach_j)`, half the
    /// lost motion (backlash, hysteresis) between approaching from below and from above.
    Backlash(usize),
    /// Nonlinear torsion of eDoF `edof` (index in [`Robot::edofs`] order): the coefficient
    /// a (rad/(N·m)) of `a · g(τ)` added to the eDoF's turn `c τ` ([`TorsionShape`]).
    Torsion {
        /// eDoF index.
        edof: usize,
        /// The shape g.
        shape: TorsionShape,
    },
}

impl Param {
    /// Set-up `s`'s six registration parameters: its rotations about x, y, z, then its
    /// translations along them.
    pub fn setup_pose(s: usize) -> [Param; 6] {
        [
            Param::SetupRotation(s, 0),
            Param::SetupRotation(s, 1),
            Param::SetupRotation(s, 2),
            Param::SetupTranslation(s, 0),
            Param::SetupTranslation(s, 1),
            Param::SetupTranslation(s, 2),
        ]
    }
}

/// Torque scale of the cubic torsion term (N·m): `g(τ) = τ³ / τ_ref²`, so that its coefficient
/// is the extra compliance at 100 N·m.
pub const CUBIC_TORQUE_SCALE_NM: f64 = 100.0;

/// The shape g(τ) of a nonlinear torsion term `a · g(τ)` of an eDoF whose linear turn is `c τ`:
/// a strain-wave gear's torsion curve is not a straight line (stiffer as the torque grows, with
/// a soft zone around zero torque where the flexspline's teeth come into mesh).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum TorsionShape {
    /// `g(τ) = τ³ / τ_ref²` ([`CUBIC_TORQUE_SCALE_NM`]): a hardening (a < 0) or softening
    /// (a > 0) torsion curve; its slope at τ_ref is `c + 3a`.
    Cubic,
    /// `g(τ) = T · tanh(τ / T)` with T in N·m: an extra compliance a at small torques that
    /// fades above T (a soft zone around zero torque; slope `c + a` at 0, `c` far from it).
    Soft(u16),
}

impl TorsionShape {
    /// `g(τ)` and `g'(τ)` (see the variants).
    pub fn value_slope(self, torque: f64) -> (f64, f64) {
        match self {
            TorsionShape::Cubic => {
                let s2 = CUBIC_TORQUE_SCALE_NM * CUBIC_TORQUE_SCALE_NM;
                (torque * torque * torque / s2, 3.0 * torque * torque / s2)
            }
            TorsionShape::Soft(t) => {
                let t = f64::from(t.max(1));
                let h = (torque / t).tanh();
                (t * h, 1.0 - h * h)
            }
        }
    }

    /// Name (`cubic`, `soft:T`), as `--steps torsion:…` takes it.
    pub fn name(self) -> String {
        match self {
            TorsionShape::Cubic => "cubic".into(),
            TorsionShape::Soft(t) => format!("soft:{t}"),
        }
    }
}

/// One nonlinear torsion term with its coefficient.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TorsionTerm {
    /// eDoF index ([`Robot::edofs`] order).
    pub edof: usize,
    /// Shape.
    pub shape: TorsionShape,
    /// Coefficient a (rad/(N·m)).
    pub value: f64,
}

/// Coarse groups, for tables and the identifiability reasons.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParamGroup {
    /// Tracker set-up registration.
    Setup,
    /// Target offset on the flange.
    Target,
    /// Kinematic (DH) error.
    Geometry,
    /// Compliance (gravity / load).
    Compliance,
    /// Lumped masses.
    Mass,
    /// Joint-angle harmonics (eccentricity, gear periodic error).
    Harmonic,
    /// Direction-dependent joint offsets (backlash, hysteresis).
    Backlash,
    /// Nonlinear torsion of the eDoFs.
    Torsion,
}

/// Physical unit of a parameter, for display.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unit {
    /// Metre (shown in mm).
    Metre,
    /// Radian (shown in mrad).
    Radian,
    /// rad/(N·m) (shown as µrad/(N·m)).
    Compliance,
    /// kg.
    Kilogram,
    /// kg·m.
    KilogramMetre,
}

impl Unit {
    /// Display factor and label: value × factor in label units.
    pub fn display(self) -> (f64, &'static str) {
        match self {
            Unit::Metre => (1e3, "mm"),
            Unit::Radian => (1e3, "mrad"),
            Unit::Compliance => (1e6, "µrad/(N·m)"),
            Unit::Kilogram => (1.0, "kg"),
            Unit::KilogramMetre => (1.0, "kg·m"),
        }
    }

    /// SI label.
    pub fn si(self) -> &'static str {
        match self {
            Unit::Metre => "m",
            Unit::Radian => "rad",
            Unit::Compliance => "rad/(N·m)",
            Unit::Kilogram => "kg",
            Unit::KilogramMetre => "kg·m",
        }
    }
}

const XYZ: [&str; 3] = ["x", "y", "z"];

/// Below this joint motion (rad) a reading's approach direction is unknown (sign 0).
pub const APPROACH_DEADBAND_RAD: f64 = 1e-6;

/// Sign of an approach motion: −1, 0 (within [`APPROACH_DEADBAND_RAD`]) or +1.
pub fn approach_sign(motion: f64) -> f64 {
    if motion > APPROACH_DEADBAND_RAD {
        1.0
    } else if motion < -APPROACH_DEADBAND_RAD {
        -1.0
    } else {
        0.0
    }
}

/// One joint-angle harmonic term with its coefficient.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HarmonicTerm {
    /// Joint (0-based).
    pub joint: usize,
    /// Order n ≥ 1.
    pub order: u16,
    /// Sine (true) or cosine (false).
    pub sine: bool,
    /// Coefficient (rad).
    pub value: f64,
}

/// The model being identified: a robot (DH rows, θ offsets, eDoFs) plus what absolute
/// measurements need besides it.
#[derive(Clone, Debug)]
pub struct EgModel {
    /// The robot; its DH rows and θ offsets carry the kinematic corrections.
    pub robot: Robot,
    /// Set-up registrations (`p_tracker = pose · p_world`).
    pub setups: Vec<NamedPose>,
    /// Targets in the flange frame.
    pub targets: Vec<NamedPoint>,
    /// Compliance of each eDoF of the robot ([`Robot::edofs`] order), rad/(N·m); 0 = rigid.
    pub compliance: Vec<f64>,
    /// Lumped gravity parameters of each body: mass (kg) and first moment m·c in R_b (kg·m).
    pub lumped: Vec<[f64; 4]>,
    /// Joint-angle harmonics.
    pub harmonics: Vec<HarmonicTerm>,
    /// Direction-dependent offset `b_j` of each joint (rad; 0 = none).
    pub backlash: Vec<f64>,
    /// Nonlinear torsion terms of the eDoFs: eDoF e turns by `c_e τ + Σ a g(τ)`.
    pub torsion: Vec<TorsionTerm>,
    /// Residual model on the joint angles, added to the predicted positions (world axes).
    pub residual: Option<crate::geometry::residual_model::ResidualModel>,
    /// Joint-angle error maps `Δθ_j(q_j)`, added to the joint values like the harmonics.
    pub joint_maps: Option<crate::geometry::joint_maps::JointMaps>,
}

impl EgModel {
    /// A model from a robot: compliances from its stiffnesses, lumped parameters from its
    /// masses, its set-ups and targets.
    pub fn from_robot(robot: &Robot) -> EgModel {
        let compliance = robot.edofs().map(|e| 1.0 / e.stiffness).collect();
        let lumped = robot
            .joints
            .iter()
            .map(|j| match j.inertia {
                Some(i) => [
                    i.mass_kg,
                    i.mass_kg * i.com.x,
                    i.mass_kg * i.com.y,
                    i.mass_kg * i.com.z,
                ],
                None => [0.0; 4],
            })
            .collect();
        EgModel {
            robot: robot.clone(),
            setups: robot.setups.clone(),
            targets: robot.targets.clone(),
            compliance,
            lumped,
            harmonics: Vec::new(),
            backlash: vec![0.0; robot.joint_count()],
            torsion: Vec::new(),
            residual: None,
            joint_maps: None,
        }
    }

    /// Joint values with the harmonic and direction-dependent offsets and the joint maps added
    /// (FK adds `θ_offset` to these): `q'_j = q_j + Σ_n (a_n cos(n q_j) + b_n sin(n q_j)) +
    /// b_j sign(approach_j) + Δθ_j(q_j)`.
    pub fn effective_q(&self, q: &[f64], approach: &[f64], out: &mut [f64]) {
        out[..q.len()].copy_from_slice(q);
        for h in &self.harmonics {
            let x = f64::from(h.order) * q[h.joint];
            out[h.joint] += h.value * if h.sine { x.sin() } else { x.cos() };
        }
        for (j, b) in self.backlash.iter().enumerate().take(q.len()) {
            out[j] += b * approach_sign(approach.get(j).copied().unwrap_or(0.0));
        }
        if let Some(maps) = &self.joint_maps {
            maps.add_offsets(q, out);
        }
    }

    /// Turn of eDoF `e` under torque `torque` and its slope: `(c τ + Σ a g(τ), c + Σ a g'(τ))`.
    pub fn edof_turn(&self, e: usize, torque: f64) -> (f64, f64) {
        let c = self.compliance[e];
        let (mut turn, mut slope) = (c * torque, c);
        for t in self.torsion.iter().filter(|t| t.edof == e) {
            let (g, dg) = t.shape.value_slope(torque);
            turn += t.value * g;
            slope += t.value * dg;
        }
        (turn, slope)
    }

    /// Whether any eDoF turns under a torque (a compliance or a torsion term is non-zero).
    pub fn is_elastic(&self) -> bool {
        self.compliance.iter().any(|c| *c != 0.0) || self.torsion.iter().any(|t| t.value != 0.0)
    }

    /// Index of a set-up by name.
    pub fn setup_index(&self, name: &str) -> Option<usize> {
        self.setups.iter().position(|s| s.name == name)
    }

    /// Index of a target by name.
    pub fn target_index(&self, name: &str) -> Option<usize> {
        self.targets.iter().position(|t| t.name == name)
    }

    /// Human-readable name of a parameter (ASCII, stable: used in JSON and CSV).
    pub fn param_name(&self, param: Param) -> String {
        let edof_label = |e: usize| {
            self.robot
                .edofs()
                .nth(e)
                .map_or_else(|| format!("edof{e}"), |edof| edof.label())
        };
        match param {
            Param::SetupRotation(s, k) => format!("setup[{}].r{}", self.setups[s].name, XYZ[k]),
            Param::SetupTranslation(s, k) => {
                format!("setup[{}].t{}", self.setups[s].name, XYZ[k])
            }
            Param::Target(t, k) => format!("target[{}].{}", self.targets[t].name, XYZ[k]),
            Param::TargetRotation(t, k) => {
                format!("target[{}].r{}", self.targets[t].name, XYZ[k])
            }
            Param::Backlash(j) => format!("J{}.backlash", j + 1),
            Param::Torsion { edof, shape } => format!("a[{}].{}", edof_label(edof), shape.name()),
            Param::Dh(j, f) => format!("J{}.{}", j + 1, f.name()),
            Param::Compliance(e) => format!("c[{}]", edof_label(e)),
            Param::Mass(b) => format!("body{}.m", b + 1),
            Param::FirstMoment(b, k) => format!("body{}.m{}", b + 1, XYZ[k]),
            Param::Harmonic { joint, order, sine } => format!(
                "J{}.{}{}",
                joint + 1,
                if sine { "sin" } else { "cos" },
                order
            ),
        }
    }

    /// Group of a parameter.
    pub fn group(param: Param) -> ParamGroup {
        match param {
            Param::SetupRotation(..) | Param::SetupTranslation(..) => ParamGroup::Setup,
            Param::Target(..) | Param::TargetRotation(..) => ParamGroup::Target,
            Param::Backlash(_) => ParamGroup::Backlash,
            Param::Torsion { .. } => ParamGroup::Torsion,
            Param::Dh(..) => ParamGroup::Geometry,
            Param::Compliance(_) => ParamGroup::Compliance,
            Param::Mass(_) | Param::FirstMoment(..) => ParamGroup::Mass,
            Param::Harmonic { .. } => ParamGroup::Harmonic,
        }
    }

    /// Unit of a parameter.
    pub fn unit(param: Param) -> Unit {
        match param {
            Param::SetupRotation(..)
            | Param::TargetRotation(..)
            | Param::Dh(_, DhField::Theta | DhField::Alpha | DhField::Beta)
            | Param::Harmonic { .. }
            | Param::Backlash(_) => Unit::Radian,
            Param::SetupTranslation(..) | Param::Target(..) | Param::Dh(_, _) => Unit::Metre,
            Param::Compliance(_) | Param::Torsion { .. } => Unit::Compliance,
            Param::Mass(_) => Unit::Kilogram,
            Param::FirstMoment(..) => Unit::KilogramMetre,
        }
    }

    /// Current value of a parameter (for set-up and target rotations: 0, they are increments).
    pub fn value(&self, param: Param) -> f64 {
        match param {
            Param::SetupRotation(..) | Param::TargetRotation(..) => 0.0,
            Param::Backlash(j) => self.backlash[j],
            Param::SetupTranslation(s, k) => {
                let pose = &self.setups[s].pose;
                (pose.rotation.inverse() * pose.translation.vector)[k]
            }
            Param::Target(t, k) => self.targets[t].position[k],
            Param::Dh(j, f) => {
                let joint = &self.robot.joints[j];
                let dh = joint.dh.unwrap_or_default();
                match f {
                    DhField::Theta => joint.theta_offset,
                    DhField::D => dh.d,
                    DhField::A => dh.a,
                    DhField::Alpha => dh.alpha,
                    DhField::Beta => dh.beta,
                }
            }
            Param::Compliance(e) => self.compliance[e],
            Param::Torsion { edof, shape } => self
                .torsion
                .iter()
                .find(|t| t.edof == edof && t.shape == shape)
                .map_or(0.0, |t| t.value),
            Param::Mass(b) => self.lumped[b][0],
            Param::FirstMoment(b, k) => self.lumped[b][1 + k],
            Param::Harmonic { joint, order, sine } => self
                .harmonics
                .iter()
                .find(|h| h.joint == joint && h.order == order && h.sine == sine)
                .map_or(0.0, |h| h.value),
        }
    }

    /// Apply the increments `delta[i]` to `params[i]` (see the module documentation) and
    /// rebuild the robot's placements.
    pub fn apply(&mut self, params: &[Param], delta: &[f64]) {
        let mut rotations = vec![Vector3::zeros(); self.setups.len()];
        let mut translations = vec![Vector3::zeros(); self.setups.len()];
        let mut target_rotations = vec![Vector3::zeros(); self.targets.len()];
        let mut geometry = false;
        for (&param, &d) in params.iter().zip(delta) {
            match param {
                Param::SetupRotation(s, k) => rotations[s][k] += d,
                Param::SetupTranslation(s, k) => translations[s][k] += d,
                Param::Target(t, k) => self.targets[t].position[k] += d,
                Param::TargetRotation(t, k) => target_rotations[t][k] += d,
                Param::Backlash(j) => self.backlash[j] += d,
                Param::Dh(j, f) => {
                    geometry = true;
                    let joint = &mut self.robot.joints[j];
                    if f == DhField::Theta {
                        joint.theta_offset += d;
                    } else {
                        let dh = joint.dh.get_or_insert_with(Default::default);
                        match f {
                            DhField::D => dh.d += d,
                            DhField::A => dh.a += d,
                            DhField::Alpha => dh.alpha += d,
                            DhField::Beta => dh.beta += d,
                            DhField::Theta => {}
                        }
                    }
                }
                Param::Compliance(e) => self.compliance[e] += d,
                Param::Torsion { edof, shape } => {
                    match self
                        .torsion
                        .iter_mut()
                        .find(|t| t.edof == edof && t.shape == shape)
                    {
                        Some(t) => t.value += d,
                        None => self.torsion.push(TorsionTerm {
                            edof,
                            shape,
                            value: d,
                        }),
                    }
                }
                Param::Mass(b) => self.lumped[b][0] += d,
                Param::FirstMoment(b, k) => self.lumped[b][1 + k] += d,
                Param::Harmonic { joint, order, sine } => {
                    match self
                        .harmonics
                        .iter_mut()
                        .find(|h| h.joint == joint && h.order == order && h.sine == sine)
                    {
                        Some(h) => h.value += d,
                        None => self.harmonics.push(HarmonicTerm {
                            joint,
                            order,
                            sine,
                            value: d,
                        }),
                    }
                }
            }
        }
        for (s, setup) in self.setups.iter_mut().enumerate() {
            let (phi, t) = (rotations[s], translations[s]);
            if phi != Vector3::zeros() || t != Vector3::zeros() {
                // p_t = R (exp(φ) p + δt) + t_s  →  R' = R exp(φ), t' = t_s + R δt.
                let r = setup.pose.rotation;
                setup.pose.translation.vector += r * t;
                setup.pose.rotation = r * Rotation3::from_scaled_axis(phi);
            }
        }
        for (target, phi) in self.targets.iter_mut().zip(target_rotations) {
            if phi != Vector3::zeros() {
                let r = target.rotation.unwrap_or_else(Rotation3::identity);
                target.rotation = Some(Rotation3::from_scaled_axis(phi) * r);
            }
        }
        if geometry {
            self.robot.rebuild_dh_geometry();
        }
    }

    /// Rotation of target `t`'s frame in the flange frame (identity when unknown).
    pub fn target_rotation(&self, t: usize) -> Rotation3<f64> {
        self.targets[t].rotation.unwrap_or_else(Rotation3::identity)
    }

    /// The candidate geometric parameters of a DH robot: θ, d, a, α of every joint, and β of
    /// the rows whose consecutive axes are parallel (|sin α| < 0.01; Hayati). Empty for a
    /// robot without a DH table.
    pub fn geometric_params(&self) -> Vec<Param> {
        let Some(convention) = self.robot.dh_convention else {
            return Vec::new();
        };
        let mut out = Vec::new();
        for (j, joint) in self.robot.joints.iter().enumerate() {
            out.push(Param::Dh(j, DhField::Theta));
            out.push(Param::Dh(j, DhField::D));
            out.push(Param::Dh(j, DhField::A));
            out.push(Param::Dh(j, DhField::Alpha));
            let parallel_row = match convention {
                // Standard DH: row j's α is the twist between axes j and j+1.
                DhConvention::Standard => j + 1 < self.robot.joints.len(),
                // Modified DH: row j's α is the twist between axes j−1 and j.
                DhConvention::Modified => j > 0,
            } && joint.dh.is_some_and(|dh| dh.alpha.sin().abs() < 0.01);
            if parallel_row {
                out.push(Param::Dh(j, DhField::Beta));
            }
        }
        out
    }

    /// Registration parameters of every set-up and target (target rotations too when
    /// `orientations`: they are seen only by measured orientations).
    pub fn registration_params(&self, orientations: bool) -> Vec<Param> {
        let mut out: Vec<Param> = (0..self.setups.len()).flat_map(Param::setup_pose).collect();
        for t in 0..self.targets.len() {
            for k in 0..3 {
                out.push(Param::Target(t, k));
            }
            if orientations {
                for k in 0..3 {
                    out.push(Param::TargetRotation(t, k));
                }
            }
        }
        out
    }

    /// Write the identified quantities back into a robot: DH rows and θ offsets (already
    /// there), stiffness = 1/compliance (an eDoF with compliance ≤ 0 becomes rigid), masses and
    /// centres of mass from the lumped parameters, set-ups and targets. Joint-angle terms
    /// (harmonics, backlash) have no place in a robot file: see [`crate::geometry::terms`].
    pub fn to_robot(&self) -> Robot {
        let mut robot = self.robot.clone();
        let edofs: Vec<_> = robot.edofs().collect();
        for (edof, &c) in edofs.iter().zip(&self.compliance) {
            let k = 1.0 / c;
            let stiffness = (c > 0.0 && k <= deflex_model::bounds::MAX_STIFFNESS)
                .then_some(k.max(deflex_model::bounds::MIN_STIFFNESS));
            robot.set_stiffness(edof.site, edof.axis, stiffness);
        }
        for (joint, lumped) in robot.joints.iter_mut().zip(&self.lumped) {
            if lumped[0] > 0.0 {
                joint.inertia = Some(deflex_model::LinkInertia {
                    mass_kg: lumped[0],
                    com: Vector3::new(lumped[1], lumped[2], lumped[3]) / lumped[0],
                });
            }
        }
        // The file writes centres of mass in the convention's link frame: for standard DH that
        // is L_i of the *calibrated* row (the model keeps them in R_i).
        if robot.dh_convention == Some(deflex_model::DhConvention::Standard) {
            for joint in &mut robot.joints {
                if let Some(dh) = &joint.dh {
                    joint.link_frame = deflex_model::dh::standard_dh_link(dh);
                }
            }
        }
        robot.setups = self.setups.clone();
        robot.targets = self.targets.clone();
        robot
    }
}

//! A stiff fixture for the second scenario: pressing, a press fit, a friction-stir plunge. The
//! tool (its hemispherical tip) meets a flat, stiff surface at the same height as the sheet's
//! top (z = −tool radius in R_p, so the TCP touches it at z = 0); the contact pushes back
//! elastically, `F = k_c · max(0, −z_tool)`, along +z of R_p, and nothing flows.
//!
//! This is the case where force-feedback correction is positive feedback (issue 11): with
//! ε = −ξ − δŝ, a correction that pushes into the fixture raises the force, which raises the
//! estimated deflection δŝ, which raises the correction. With true compliance C and model
//! compliance Ĉ along the contact normal, an exact correction (ξ = −Ĉ F) settles at
//! `F = k_c p₀ / (1 + k_c (C − Ĉ))` for a programmed interference p₀: the rigid-robot force
//! `k_c p₀`, i.e. `1 + k_c C` times the uncorrected force, and no equilibrium at all once the
//! model is softer than the robot by `1/k_c`.

use crate::sheet::ContactState;
use nalgebra::Vector3;

/// The fixture (positions in R_p, metres).
#[derive(Clone, Debug)]
pub struct Fixture {
    stiffness_n_m: f64,
    tool_radius_m: f64,
    deepest_m: f64,
}

impl Fixture {
    /// A fixture of contact stiffness `stiffness_n_m` (N/m) met by a ball of `tool_radius_m`.
    pub fn new(stiffness_n_m: f64, tool_radius_m: f64) -> Fixture {
        Fixture {
            stiffness_n_m,
            tool_radius_m,
            deepest_m: 0.0,
        }
    }

    /// Contact stiffness (N/m).
    pub fn stiffness_n_m(&self) -> f64 {
        self.stiffness_n_m
    }

    /// Tool radius (m).
    pub fn tool_radius_m(&self) -> f64 {
        self.tool_radius_m
    }

    /// Contact state for a tool centre at `p` (R_p, m).
    pub fn contact(&self, p: &Vector3<f64>) -> ContactState {
        let penetration = (-p.z).max(0.0);
        let force = self.stiffness_n_m * penetration;
        ContactState {
            penetration_m: penetration,
            depth_m: penetration,
            flow_n: force,
            force_n: force,
        }
    }

    /// Remember the deepest penetration (nothing flows).
    pub fn observe(&mut self, state: &ContactState) {
        self.deepest_m = self.deepest_m.max(state.penetration_m);
    }

    /// Deepest penetration so far (m).
    pub fn deepest_m(&self) -> f64 {
        self.deepest_m
    }
}

/// A force set along the path, whatever the depth (force-controlled forming, constant-pressure
/// finishing, a press fit): the tool meets the fixture's flat surface (z = 0 of R_p at the
/// TCP), which pushes back with `min(k_c · penetration, F_set(s))`, where `F_set` rises
/// linearly with the travel in contact `s` from 0 to the set force over the ramp and then holds.
/// Once the robot pushes deep enough, the force is the set one, and the depth the tool reaches
/// follows the arm's deflection under it, not the other way round: the case where a force–depth
/// law read from a log reverses cause and effect (issue 33).
#[derive(Clone, Debug)]
pub struct PrescribedForce {
    surface: Fixture,
    force_n: f64,
    ramp_m: f64,
    travelled_m: f64,
    last: Option<Vector3<f64>>,
}

impl PrescribedForce {
    /// A set force `force_n` (N) reached over `ramp_m` (m) of travel in contact, on a surface of
    /// stiffness `stiffness_n_m` met by a ball of `tool_radius_m`.
    pub fn new(force_n: f64, ramp_m: f64, stiffness_n_m: f64, tool_radius_m: f64) -> Self {
        PrescribedForce {
            surface: Fixture::new(stiffness_n_m, tool_radius_m),
            force_n,
            ramp_m,
            travelled_m: 0.0,
            last: None,
        }
    }

    /// The set force at the current travel (N).
    pub fn set_force_n(&self) -> f64 {
        if self.ramp_m <= 0.0 {
            self.force_n
        } else {
            self.force_n * (self.travelled_m / self.ramp_m).min(1.0)
        }
    }

    /// Travel in contact so far (m).
    pub fn travelled_m(&self) -> f64 {
        self.travelled_m
    }

    /// Contact state for a tool centre at `p` (R_p, m).
    pub fn contact(&self, p: &Vector3<f64>) -> ContactState {
        let mut state = self.surface.contact(p);
        if state.penetration_m > 0.0 {
            // The first contact touches with a small force, so the ramp can start.
            let set = self.set_force_n().max(1e-3 * self.force_n);
            state.flow_n = set;
            state.force_n = state.force_n.min(set);
        }
        state
    }

    /// The tool is at `p` with `state`: the travel in contact advances.
    pub fn observe(&mut self, p: &Vector3<f64>, state: &ContactState) {
        self.surface.observe(state);
        if state.force_n > 0.0 {
            if let Some(last) = self.last {
                self.travelled_m += (p - last).norm();
            }
            self.last = Some(*p);
        } else {
            self.last = None;
        }
    }

    /// Deepest penetration so far (m).
    pub fn deepest_m(&self) -> f64 {
        self.surface.deepest_m()
    }
}

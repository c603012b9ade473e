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

//! The sheet (1 mm AA5086 by default) and its elastic–plastic contact with the hemispherical tool.
//!
//! **State.** The formed surface is stored as radial profiles z(r) on `sectors` rays around the
//! part axis (R_p's z axis), r from 0 to the blank-holder radius. A cone has identical rays; a
//! pyramid or a CAM part is represented ray by ray (star-shaped parts around the axis).
//!
//! **Contact law.** The vertical contact force comes from the penetration δ of the tool's actual
//! (deflected) position into the current formed surface: along the ray through the tool centre,
//! δ = max_r [z_s(r) − z_tool(r)] with z_tool(r) the lower surface of the sphere. The sheet answers
//! elastically, F = k_c δ, until F reaches the flow level F_flow; then it flows plastically: the
//! surface under the tool is pushed down to the sphere plus the elastic springback F/k_c, and the
//! region inside the tool path (the floor of the frustum, which in SPIF moves down rigidly with
//! the tool) is lowered to the tool's lowest point. Hence a robot that deflects upwards leaves the
//! part shallower while the force stays at the flow level, and a tool that goes deeper meets a
//! higher force (the level grows with the formed depth, Fig. 18).
//!
//! **Force level** (Aerens et al. 2010, steady state):
//! `Fz = 0.0716 · Rm · t^1.57 · d^0.41 · Δh^0.09 · α · cos α` (Rm in MPa, t and d in mm, Δh the
//! scallop height in mm from the step-down and the wall angle, α in degrees), reached over the
//! first millimetres of depth: `F_flow = Fz · (1 − exp(−depth/λ))`. In-plane forces: `ρ_r Fz`
//! towards the part axis (building up with depth like the wall) and `ρ_f Fz` against the feed
//! (friction with the mineral-oil lubricant).

use crate::error::SimError;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Sheet, material and contact settings (hidden truth of the twin).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SheetConfig {
    /// Sheet thickness t (mm).
    pub thickness_mm: f64,
    /// Ultimate tensile strength Rm (MPa). AA5086 spans about 240 (O/H111) to 340 (H34); 320 here
    /// (a strain-hardened temper), which puts the Aerens level at the paper's 1.2–1.3 kN.
    pub rm_mpa: f64,
    /// Tool (ball) diameter d (mm).
    pub tool_diameter_mm: f64,
    /// Local elastic stiffness of the sheet under the tool (N/mm).
    pub contact_stiffness_n_mm: f64,
    /// Depth over which the vertical force level builds up (mm, 1/e length).
    pub buildup_depth_mm: f64,
    /// Depth over which the radial force builds up (mm, 1/e length).
    pub inplane_buildup_depth_mm: f64,
    /// Radial force towards the part axis as a fraction of Fz.
    pub radial_ratio: f64,
    /// Force against the feed as a fraction of Fz.
    pub feed_ratio: f64,
    /// Step-down (mm) and wall angle (deg) used for the Aerens level when the path does not say.
    pub default_step_down_mm: f64,
    /// Wall angle (deg) when the path does not say.
    pub default_wall_angle_deg: f64,
    /// Number of rays of the surface state.
    pub sectors: usize,
    /// Radial resolution (mm).
    pub radial_step_mm: f64,
    /// Free radius inside the blank holder (mm).
    pub blank_radius_mm: f64,
}

impl Default for SheetConfig {
    fn default() -> Self {
        SheetConfig {
            thickness_mm: 1.0,
            rm_mpa: 320.0,
            tool_diameter_mm: 15.0,
            contact_stiffness_n_mm: 2000.0,
            buildup_depth_mm: 2.5,
            inplane_buildup_depth_mm: 3.0,
            radial_ratio: 0.36,
            feed_ratio: 0.12,
            default_step_down_mm: 0.24,
            default_wall_angle_deg: 45.0,
            sectors: 360,
            radial_step_mm: 0.2,
            blank_radius_mm: 60.0,
        }
    }
}

impl SheetConfig {
    /// Check ranges.
    pub fn validate(&self) -> Result<(), SimError> {
        use crate::config::{non_negative, positive};
        positive("sheet.thickness_mm", self.thickness_mm)?;
        positive("sheet.rm_mpa", self.rm_mpa)?;
        positive("sheet.tool_diameter_mm", self.tool_diameter_mm)?;
        positive("sheet.contact_stiffness_n_mm", self.contact_stiffness_n_mm)?;
        positive("sheet.buildup_depth_mm", self.buildup_depth_mm)?;
        positive(
            "sheet.inplane_buildup_depth_mm",
            self.inplane_buildup_depth_mm,
        )?;
        non_negative("sheet.radial_ratio", self.radial_ratio)?;
        non_negative("sheet.feed_ratio", self.feed_ratio)?;
        positive("sheet.default_step_down_mm", self.default_step_down_mm)?;
        positive("sheet.radial_step_mm", self.radial_step_mm)?;
        positive("sheet.blank_radius_mm", self.blank_radius_mm)?;
        if !(self.default_wall_angle_deg > 0.0 && self.default_wall_angle_deg < 90.0) {
            return Err(SimError::config(
                "sheet.default_wall_angle_deg",
                "must be within (0, 90)",
            ));
        }
        if self.sectors < 8 {
            return Err(SimError::config("sheet.sectors", "at least 8"));
        }
        if self.blank_radius_mm <= self.tool_diameter_mm {
            return Err(SimError::config(
                "sheet.blank_radius_mm",
                "must exceed the tool diameter",
            ));
        }
        Ok(())
    }
}

/// Scallop height (mm) left by a ball of radius `tool_radius_mm` on a wall of angle
/// `wall_angle_deg` with vertical step-down `step_down_mm`: passes are `Δz / sin α` apart along
/// the wall, `Δh = R − √(R² − (s/2)²)`.
pub fn scallop_height_mm(tool_radius_mm: f64, step_down_mm: f64, wall_angle_deg: f64) -> f64 {
    let s = step_down_mm / wall_angle_deg.to_radians().sin();
    let half = (s / 2.0).min(tool_radius_mm);
    tool_radius_mm - (tool_radius_mm * tool_radius_mm - half * half).sqrt()
}

/// Aerens et al. (2010) steady-state vertical forming force (N):
/// `0.0716 · Rm · t^1.57 · d^0.41 · Δh^0.09 · α · cos α`.
pub fn aerens_fz(rm_mpa: f64, t_mm: f64, d_mm: f64, dh_mm: f64, alpha_deg: f64) -> f64 {
    0.0716
        * rm_mpa
        * t_mm.powf(1.57)
        * d_mm.powf(0.41)
        * dh_mm.powf(0.09)
        * alpha_deg
        * alpha_deg.to_radians().cos()
}

/// The sheet: its formed surface and the contact law. Positions in R_p, metres.
#[derive(Clone, Debug)]
pub struct Sheet {
    config: SheetConfig,
    sectors: usize,
    bins: usize,
    dr: f64,
    radius: f64,
    top: f64,
    k: f64,
    steady_fz: f64,
    /// `sectors × bins` surface heights (m), row-major by sector.
    surface: Vec<f64>,
}

/// What the contact does for a given tool position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactState {
    /// Penetration into the current surface (m, ≥ 0).
    pub penetration_m: f64,
    /// Depth of the tool's lowest point below the undeformed sheet (m, ≥ 0).
    pub depth_m: f64,
    /// Flow level at that depth (N).
    pub flow_n: f64,
    /// Vertical force on the tool (N): `min(k δ, flow)`.
    pub force_n: f64,
}

impl Sheet {
    /// A flat sheet, Aerens level computed for the given step-down (mm) and wall angle (deg).
    pub fn new(
        config: &SheetConfig,
        step_down_mm: f64,
        wall_angle_deg: f64,
    ) -> Result<Sheet, SimError> {
        config.validate()?;
        let tool_radius_mm = config.tool_diameter_mm / 2.0;
        let dh = scallop_height_mm(tool_radius_mm, step_down_mm, wall_angle_deg);
        let steady_fz = aerens_fz(
            config.rm_mpa,
            config.thickness_mm,
            config.tool_diameter_mm,
            dh,
            wall_angle_deg,
        );
        let dr = config.radial_step_mm * 1e-3;
        let radius = config.blank_radius_mm * 1e-3;
        let bins = (radius / dr).ceil() as usize + 1;
        let top = -tool_radius_mm * 1e-3;
        Ok(Sheet {
            config: config.clone(),
            sectors: config.sectors,
            bins,
            dr,
            radius: tool_radius_mm * 1e-3,
            top,
            k: config.contact_stiffness_n_mm * 1e3,
            steady_fz,
            surface: vec![top; config.sectors * bins],
        })
    }

    /// Steady-state Aerens level (N).
    pub fn steady_force_n(&self) -> f64 {
        self.steady_fz
    }

    /// Tool radius (m).
    pub fn tool_radius_m(&self) -> f64 {
        self.radius
    }

    /// Height of the undeformed sheet (m, R_p).
    pub fn top_m(&self) -> f64 {
        self.top
    }

    /// Flow level (N) at a depth (m).
    pub fn flow_force(&self, depth_m: f64) -> f64 {
        let lambda = self.config.buildup_depth_mm * 1e-3;
        self.steady_fz * (1.0 - (-depth_m.max(0.0) / lambda).exp())
    }

    fn sector_of(&self, theta: f64) -> (usize, usize, f64) {
        let u = theta.rem_euclid(2.0 * PI) / (2.0 * PI) * self.sectors as f64;
        let s0 = (u.floor() as usize) % self.sectors;
        let s1 = (s0 + 1) % self.sectors;
        (s0, s1, u - u.floor())
    }

    fn sector_angle(&self, s: usize) -> f64 {
        2.0 * PI * s as f64 / self.sectors as f64
    }

    /// Contact state for a tool centre at `p` (R_p, m).
    pub fn contact(&self, p: &Vector3<f64>) -> ContactState {
        let r_t = p.x.hypot(p.y);
        let (s0, s1, w) = self.sector_of(p.y.atan2(p.x));
        let rr = self.radius * self.radius;
        let lo = (((r_t - self.radius) / self.dr).floor().max(0.0)) as usize;
        let hi = (((r_t + self.radius) / self.dr).ceil() as usize).min(self.bins - 1);
        let row0 = &self.surface[s0 * self.bins..(s0 + 1) * self.bins];
        let row1 = &self.surface[s1 * self.bins..(s1 + 1) * self.bins];
        let mut penetration = f64::NEG_INFINITY;
        for i in lo..=hi {
            let d = i as f64 * self.dr - r_t;
            let dd = d * d;
            if dd >= rr {
                continue;
            }
            let surface = row0[i] + w * (row1[i] - row0[i]);
            let tool = p.z - (rr - dd).sqrt();
            penetration = penetration.max(surface - tool);
        }
        let penetration = penetration.max(0.0);
        let depth = (self.top - (p.z - self.radius)).max(0.0);
        let flow = self.flow_force(depth);
        ContactState {
            penetration_m: penetration,
            depth_m: depth,
            flow_n: flow,
            force_n: (self.k * penetration).min(flow),
        }
    }

    /// Plastic flow for a tool at `p` carrying vertical force `force_n`: if the elastic force
    /// would exceed the flow level, push the surface down to the tool plus the springback and
    /// lower the floor inside the tool path. Returns whether the sheet flowed.
    pub fn form(&mut self, p: &Vector3<f64>, state: &ContactState) -> bool {
        if self.k * state.penetration_m <= state.flow_n || state.penetration_m <= 0.0 {
            return false;
        }
        let springback = state.force_n / self.k;
        let r_t = p.x.hypot(p.y);
        let theta = p.y.atan2(p.x);
        let (s0, s1, _) = self.sector_of(theta);
        let rr = self.radius * self.radius;
        let floor = p.z - self.radius + springback;
        for s in [s0, s1] {
            let dtheta = self.sector_angle(s) - theta;
            let cos = dtheta.cos();
            let row = &mut self.surface[s * self.bins..(s + 1) * self.bins];
            let hi = (((r_t + self.radius) / self.dr).ceil() as usize).min(self.bins - 1);
            for (i, z) in row.iter_mut().enumerate().take(hi + 1) {
                let r = i as f64 * self.dr;
                let dd = r * r + r_t * r_t - 2.0 * r * r_t * cos;
                if dd < rr {
                    let tool = p.z - (rr - dd).sqrt() + springback;
                    if *z > tool {
                        *z = tool;
                    }
                } else if r < r_t && *z > floor {
                    *z = floor;
                }
            }
        }
        true
    }

    /// Vertical force with the in-plane components: `[Fx, Fy, Fz]` on the tool (R_p axes) for a
    /// tool at `p` moving along horizontal unit direction `feed_dir`.
    pub fn force_vector(
        &self,
        p: &Vector3<f64>,
        fz: f64,
        feed_dir: &Vector3<f64>,
        depth_m: f64,
    ) -> Vector3<f64> {
        let r = p.x.hypot(p.y);
        let inward = if r > 1e-9 {
            Vector3::new(-p.x / r, -p.y / r, 0.0)
        } else {
            Vector3::zeros()
        };
        let lambda = self.config.inplane_buildup_depth_mm * 1e-3;
        let radial = self.config.radial_ratio * (1.0 - (-depth_m / lambda).exp());
        inward * (radial * fz) - feed_dir * (self.config.feed_ratio * fz)
            + Vector3::new(0.0, 0.0, fz)
    }

    /// Deepest formed point below the undeformed sheet (m).
    pub fn max_depth_m(&self) -> f64 {
        self.top - self.surface.iter().copied().fold(f64::INFINITY, f64::min)
    }

    /// Radial profile of one ray at angle `theta` (rad): `(r, depth below the undeformed sheet)`,
    /// metres.
    pub fn profile(&self, theta: f64) -> Vec<(f64, f64)> {
        let (s0, _, _) = self.sector_of(theta);
        self.surface[s0 * self.bins..(s0 + 1) * self.bins]
            .iter()
            .enumerate()
            .map(|(i, z)| (i as f64 * self.dr, self.top - z))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aerens_numbers() {
        // The paper's cone: Rm 300 MPa, t = 1 mm, d = 15 mm, Δz = 0.24 mm, α = 45°.
        let dh = scallop_height_mm(7.5, 0.24, 45.0);
        let s: f64 = 0.24 / 45f64.to_radians().sin();
        assert!((dh - (7.5 - (56.25 - s * s / 4.0).sqrt())).abs() < 1e-15);
        assert!((dh - 1.92e-3).abs() < 2e-5, "{dh}");
        let fz = aerens_fz(300.0, 1.0, 15.0, dh, 45.0);
        // 0.0716·300·15^0.41·Δh^0.09·45·cos45 by hand: 21.48 · 3.035 · 0.5695 · 31.82 ≈ 1181 N.
        assert!((fz - 1181.0).abs() < 10.0, "{fz}");
        assert!((1100.0..1300.0).contains(&fz));
        // Force grows with thickness and strength, weakly with step-down.
        assert!(aerens_fz(300.0, 1.2, 15.0, dh, 45.0) > 1.3 * fz);
        let deeper_steps = aerens_fz(300.0, 1.0, 15.0, scallop_height_mm(7.5, 0.5, 45.0), 45.0);
        assert!(deeper_steps > fz && deeper_steps < 1.2 * fz);
    }

    #[test]
    fn pushing_deeper_raises_the_force() {
        let sheet = Sheet::new(&SheetConfig::default(), 0.24, 45.0).unwrap();
        let mut last = 0.0;
        for k in 1..40 {
            let z = -0.0002 * k as f64;
            let mut s = sheet.clone();
            let p = Vector3::new(0.015, 0.0, z);
            let c = s.contact(&p);
            s.form(&p, &c);
            assert!(
                c.force_n >= last,
                "force fell at z = {z}: {} < {last}",
                c.force_n
            );
            last = c.force_n;
        }
        assert!(last > 0.9 * sheet.steady_force_n());
    }

    #[test]
    fn a_plastic_pass_leaves_the_part_at_the_tool_depth_minus_springback() {
        let mut sheet = Sheet::new(&SheetConfig::default(), 0.24, 45.0).unwrap();
        let p = Vector3::new(0.015, 0.0, -0.005);
        let c = sheet.contact(&p);
        assert!(sheet.form(&p, &c));
        let after = sheet.contact(&p);
        assert!((after.penetration_m - c.force_n / 2.0e6).abs() < 1e-9);
        let depth = sheet.max_depth_m();
        assert!(
            (depth - (0.005 - c.force_n / 2.0e6)).abs() < 1e-6,
            "{depth}"
        );
        // Lifting the tool unloads it elastically.
        let lifted = sheet.contact(&Vector3::new(0.015, 0.0, -0.0049));
        assert!(lifted.force_n < c.force_n);
    }
}

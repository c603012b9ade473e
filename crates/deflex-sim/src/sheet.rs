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
//! scallop height in mm from the step-down and the wall angle, α in degrees). The step-down and
//! the wall angle are the ones the tool **actually** forms, not the programmed ones: the sheet
//! remembers, per angular sector, the depth and radius of the tool's last pass, and the
//! difference with the current pass gives the actual step-down Δz and radial step Δr (smoothed
//! over about a turn), hence α = atan(Δz/Δr). A robot that deflects more and more
//! as the force grows forms a shallower wall with smaller steps, at a lower force; a corrected
//! robot forms the programmed wall, at the programmed force. The level is reached over the first
//! millimetres of depth and keeps growing with the tool's actual depth, as the paper's forces do
//! towards the end of the cone ("the closer the tool is to the center of the frustum cone, the
//! higher the forming forces", Section 4.3, Fig. 18):
//! `F_flow = Fz(Δz, α) · (1 − exp(−depth/λ)) · (1 + κ (depth − d_ref))`.
//! In-plane forces: `ρ_r Fz` towards the part axis (building up with depth like the wall) and
//! `ρ_f Fz` against the feed (friction with the mineral-oil lubricant).

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
    /// Growth of the flow level with the tool's depth, κ (1/mm, 0–0.5): the paper's forces keep
    /// rising towards the end of the cone (Fig. 18).
    pub depth_growth_per_mm: f64,
    /// Depth at which the growth factor is 1, d_ref (mm).
    pub reference_depth_mm: f64,
    /// Take the Aerens level at the actual step-down and wall angle of the tool's passes
    /// (`false`: at the programmed ones).
    pub actual_geometry: bool,
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
            depth_growth_per_mm: 0.03,
            reference_depth_mm: 12.0,
            actual_geometry: true,
        }
    }
}

impl SheetConfig {
    /// Check ranges.
    pub fn validate(&self) -> Result<(), SimError> {
        use crate::range_check::bounded;
        bounded("sheet.thickness_mm", self.thickness_mm, 0.01, 20.0, "mm")?;
        bounded("sheet.rm_mpa", self.rm_mpa, 1.0, 3000.0, "MPa")?;
        bounded(
            "sheet.tool_diameter_mm",
            self.tool_diameter_mm,
            1.0,
            200.0,
            "mm",
        )?;
        bounded(
            "sheet.contact_stiffness_n_mm",
            self.contact_stiffness_n_mm,
            1e-2,
            1e6,
            "N/mm",
        )?;
        bounded(
            "sheet.buildup_depth_mm",
            self.buildup_depth_mm,
            1e-3,
            1e3,
            "mm",
        )?;
        bounded(
            "sheet.inplane_buildup_depth_mm",
            self.inplane_buildup_depth_mm,
            1e-3,
            1e3,
            "mm",
        )?;
        bounded("sheet.radial_ratio", self.radial_ratio, 0.0, 10.0, "")?;
        bounded("sheet.feed_ratio", self.feed_ratio, 0.0, 10.0, "")?;
        bounded(
            "sheet.default_step_down_mm",
            self.default_step_down_mm,
            1e-3,
            50.0,
            "mm",
        )?;
        bounded(
            "sheet.radial_step_mm",
            self.radial_step_mm,
            0.01,
            10.0,
            "mm",
        )?;
        bounded(
            "sheet.blank_radius_mm",
            self.blank_radius_mm,
            1.0,
            2000.0,
            "mm",
        )?;
        bounded(
            "sheet.depth_growth_per_mm",
            self.depth_growth_per_mm,
            0.0,
            0.5,
            "1/mm",
        )?;
        bounded(
            "sheet.reference_depth_mm",
            self.reference_depth_mm,
            0.0,
            500.0,
            "mm",
        )?;
        if !(self.default_wall_angle_deg > 0.0 && self.default_wall_angle_deg < 90.0) {
            return Err(SimError::config(
                "sheet.default_wall_angle_deg",
                format!(
                    "must be within (0, 90), got {}",
                    self.default_wall_angle_deg
                ),
            ));
        }
        if !(8..=3600).contains(&self.sectors) {
            return Err(SimError::config(
                "sheet.sectors",
                format!("must be within 8..3600, got {}", self.sectors),
            ));
        }
        if self.blank_radius_mm <= self.tool_diameter_mm {
            return Err(SimError::config(
                "sheet.blank_radius_mm",
                "must exceed the tool diameter",
            ));
        }
        let cells = self.sectors as f64 * (self.blank_radius_mm / self.radial_step_mm + 1.0);
        if cells > 4e6 {
            return Err(SimError::config(
                "sheet.radial_step_mm",
                format!(
                    "the surface state would hold {cells:.0} cells (sectors × blank_radius_mm / \
                     radial_step_mm); at most 4 million"
                ),
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
    /// Aerens level at the programmed step-down and wall angle (N).
    steady_fz: f64,
    /// Aerens level at the actual step-down and wall angle of the passes so far (N).
    level_fz: f64,
    design_step_mm: f64,
    design_angle_deg: f64,
    /// `sectors × bins` surface heights (m), row-major by sector.
    surface: Vec<f64>,
    passes: PassMemory,
}

/// The tool's last pass over each angular sector, and the smoothed actual step-down and radial
/// step between passes.
#[derive(Clone, Debug)]
struct PassMemory {
    depth_m: Vec<f64>,
    radius_m: Vec<f64>,
    visit: Vec<u64>,
    visits: u64,
    current: usize,
    step_m: f64,
    radial_m: f64,
    updates: u64,
}

/// Weight of one sector's new pass in the smoothed steps (about one turn of memory, so that
/// an in-plane deflection that depends on the direction of the force averages out).
const PASS_SMOOTHING_SECTORS: f64 = 360.0;

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
        if !(step_down_mm.is_finite() && step_down_mm > 0.0) {
            return Err(SimError::Path(format!(
                "step-down must be positive, got {step_down_mm} mm"
            )));
        }
        let n = config.sectors;
        Ok(Sheet {
            config: config.clone(),
            sectors: n,
            bins,
            dr,
            radius: tool_radius_mm * 1e-3,
            top,
            k: config.contact_stiffness_n_mm * 1e3,
            steady_fz,
            level_fz: steady_fz,
            design_step_mm: step_down_mm,
            design_angle_deg: wall_angle_deg,
            surface: vec![top; n * bins],
            passes: PassMemory {
                depth_m: vec![0.0; n],
                radius_m: vec![0.0; n],
                visit: vec![0; n],
                visits: 0,
                current: usize::MAX,
                step_m: step_down_mm * 1e-3,
                radial_m: step_down_mm * 1e-3 / wall_angle_deg.to_radians().tan(),
                updates: 0,
            },
        })
    }

    /// Steady-state Aerens level at the programmed step-down and wall angle (N).
    pub fn steady_force_n(&self) -> f64 {
        self.steady_fz
    }

    /// Aerens level at the actual step-down and wall angle of the passes so far (N).
    pub fn level_force_n(&self) -> f64 {
        self.level_fz
    }

    /// Smoothed actual step-down (mm) and wall angle (deg) of the tool's passes.
    pub fn actual_step_and_angle(&self) -> (f64, f64) {
        let p = &self.passes;
        (p.step_m * 1e3, p.step_m.atan2(p.radial_m).to_degrees())
    }

    /// Record where the tool actually is (R_p, m) in a contact cycle: compare with its last pass
    /// over this sector and update the actual step-down, wall angle and Aerens level.
    pub fn observe_pass(&mut self, p: &Vector3<f64>, depth_m: f64) {
        self.observe_pass_at(p.y.atan2(p.x), p, depth_m);
    }

    /// [`Sheet::observe_pass`] with the pass recorded in the sector at angle `theta` (rad, about
    /// the part axis) instead of the sector of `p`: the tool at `p` with depth `depth_m`, its
    /// radius `|p_xy|`, booked where a caller's fixed reference (the desired path) is. The
    /// offline process model books its passes on the desired path so that where the Aerens
    /// level steps (once per sector) does not move with the command it is iterating on.
    pub fn observe_pass_at(&mut self, theta: f64, p: &Vector3<f64>, depth_m: f64) {
        let s = ((theta.rem_euclid(2.0 * PI) / (2.0 * PI) * self.sectors as f64).round() as usize)
            % self.sectors;
        let r = p.x.hypot(p.y);
        let half_turn = (self.sectors / 2) as u64;
        let passes = &mut self.passes;
        if s != passes.current {
            passes.visits += 1;
            passes.current = s;
            if passes.visit[s] > 0 && passes.visits - passes.visit[s] >= half_turn {
                let step = depth_m - passes.depth_m[s];
                let radial = passes.radius_m[s] - r;
                if step.is_finite() && radial.is_finite() {
                    let w = 1.0 / PASS_SMOOTHING_SECTORS;
                    passes.step_m += w * (step - passes.step_m);
                    passes.radial_m += w * (radial - passes.radial_m);
                    passes.updates += 1;
                }
            }
        }
        passes.depth_m[s] = depth_m;
        passes.radius_m[s] = r;
        passes.visit[s] = passes.visits;
        if self.config.actual_geometry && passes.updates > 0 {
            let design_step = self.design_step_mm;
            let step_mm = (passes.step_m * 1e3).clamp(0.25 * design_step, 2.0 * design_step);
            let angle = (passes.step_m.max(1e-9))
                .atan2(passes.radial_m.max(1e-9))
                .to_degrees()
                .clamp(10.0, 80.0);
            let tool_radius_mm = self.config.tool_diameter_mm / 2.0;
            let dh = scallop_height_mm(tool_radius_mm, step_mm, angle);
            self.level_fz = aerens_fz(
                self.config.rm_mpa,
                self.config.thickness_mm,
                self.config.tool_diameter_mm,
                dh,
                angle,
            );
        }
    }

    /// Programmed wall angle (deg).
    pub fn design_wall_angle_deg(&self) -> f64 {
        self.design_angle_deg
    }

    /// Force against the feed as a fraction of Fz.
    pub fn feed_ratio(&self) -> f64 {
        self.config.feed_ratio
    }

    /// Tool radius (m).
    pub fn tool_radius_m(&self) -> f64 {
        self.radius
    }

    /// Height of the undeformed sheet (m, R_p).
    pub fn top_m(&self) -> f64 {
        self.top
    }

    /// Flow level (N) at a depth (m): the current Aerens level, built up over the first
    /// millimetres and growing with depth.
    pub fn flow_force(&self, depth_m: f64) -> f64 {
        let lambda = self.config.buildup_depth_mm * 1e-3;
        let depth = depth_m.max(0.0);
        let growth = (1.0
            + self.config.depth_growth_per_mm * (depth * 1e3 - self.config.reference_depth_mm))
            .max(0.1);
        self.level_fz * (1.0 - (-depth / lambda).exp()) * growth
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

    /// The **programmed** profile along the ray θ = 0 (`(r, depth below the undeformed sheet)`,
    /// metres, on the same radii as [`Sheet::profile`]): the surface a rigid robot following the
    /// tool-centre positions `tool_centres_m` (R_p) exactly would leave, without springback.
    /// Computed from geometry alone, not from the formed surface: the lower envelope of the
    /// tool sphere (radius [`Sheet::tool_radius_m`]) cut by the vertical half-plane of the ray,
    /// `depth(r) = max_p [d_p − R + √(R² − (r − x_p)² − y_p²)]` with `d_p = −z_p` the tool
    /// lowest point's depth (`−z_p` on the paths of [`crate::toolpath`], whose undeformed top is at z = −R), and, as [`Sheet::form`] does, the floor
    /// inside the tool's path lowered to the tool's lowest point (`depth = d_p` for `r < |p|`)
    /// when the tool is within one sector of the ray. Consecutive positions further apart than
    /// half a radial step are interpolated, so a logged path (50 Hz) gives the same envelope as
    /// the cycle-rate path.
    pub fn programmed_profile(&self, tool_centres_m: &[Vector3<f64>]) -> Vec<(f64, f64)> {
        let rr = self.radius * self.radius;
        let half_sector = 2.0 * PI / self.sectors as f64;
        let mut depth = vec![0.0f64; self.bins];
        let mut press = |p: &Vector3<f64>| {
            // Depth of the tool's lowest point below the undeformed top.
            let d = self.top - (p.z - self.radius);
            if p.y.abs() < self.radius && p.x > -self.radius {
                let reach = (rr - p.y * p.y).sqrt();
                let lo = ((p.x - reach) / self.dr).floor().max(0.0) as usize;
                let hi = (((p.x + reach) / self.dr).ceil().max(0.0) as usize).min(self.bins - 1);
                for (i, depth) in depth.iter_mut().enumerate().take(hi + 1).skip(lo) {
                    let u = i as f64 * self.dr - p.x;
                    let h = rr - u * u - p.y * p.y;
                    if h > 0.0 {
                        *depth = depth.max(d - self.radius + h.sqrt());
                    }
                }
            }
            let r_t = p.x.hypot(p.y);
            if p.x > 0.0 && p.y.atan2(p.x).abs() < half_sector {
                let inside = ((r_t / self.dr).ceil() as usize).min(self.bins);
                for depth in depth.iter_mut().take(inside) {
                    *depth = depth.max(d);
                }
            }
        };
        let step = 0.5 * self.dr;
        for (k, p) in tool_centres_m.iter().enumerate() {
            if !p.iter().all(|v| v.is_finite()) {
                continue;
            }
            if let Some(prev) = k.checked_sub(1).map(|j| tool_centres_m[j])
                && prev.iter().all(|v| v.is_finite())
            {
                let gap = (p - prev).norm();
                // Only the part of the path near the ray needs the fine steps.
                let near = prev.y.abs().min(p.y.abs()) < self.radius + gap;
                if near && gap > step {
                    let n = ((gap / step).ceil() as usize).min(100_000);
                    for j in 1..n {
                        press(&(prev + (p - prev) * (j as f64 / n as f64)));
                    }
                }
            }
            press(p);
        }
        depth
            .into_iter()
            .enumerate()
            .map(|(i, d)| (i as f64 * self.dr, d.max(0.0)))
            .collect()
    }
}

//! A process model identified from a previous run's log: the force follows the depth the tool
//! actually reaches, as the log shows it did.
//!
//! ## Why
//!
//! A log gives the wrench `w_log(s)` the process put on the tool along the path while the robot
//! was commanded to `c_log(s)` and deflected. Used as fixed wrenches, one compensation pass is
//! exact *for those wrenches*, but the compensated tool no longer deflects back: it reaches the
//! programmed depth, forms a deeper step and the sheet pushes harder (on an unseen plant,
//! 846 N uncorrected, 998 N compensated), so the compensation falls short by the deflection
//! under the difference. The log holds what is needed to predict that difference: along the
//! path the tool passed through many depths, and the force it met at each.
//!
//! ## The law
//!
//! Along the tool axis `t` (the desired pose's z axis, signed so that the logged force pushes
//! against it) let `F = −t·f` be the axial force and `u = t·p` the depth of the tool's *actual*
//! centre `p`. In the logged run, at path point `i`,
//!
//! `u_log,i = t·(c_log,i + δ_log,i)`, with `δ_log,i` the measured deflection `m_i − c_log,i` when
//! the log has the tool's measured place `m` (a laser tracker), else the robot model's
//! `(C_i w_log,i)_p` (eq. 15 at the desired pose).
//!
//! The process is taken to scale the whole logged wrench at a point with the depth reached
//! there: `w = ρ·w_log,i` (in incremental forming the radial and friction forces are fractions
//! of the axial one, and the Aerens level is a product of a geometric factor and a depth
//! factor, `F = A(place)·G(depth)`), with
//!
//! `ρ = G(u) / G(u_log,i)`.
//!
//! **Identification of G.** The points in contact (axial force above
//! [`LoggedProcessOptions::contact_fraction`] of the largest) are binned by depth (bins of a
//! tenth of [`LoggedProcessOptions::depth_window_m`]). At each bin centre a parabola in `u` is
//! fitted by least squares, weighted by each point's share of arc length, over the points whose
//! depth lies within ± the window (a straight line where the depths do not support a parabola:
//! two forming levels in the window), and `G` there is the fitted value (a straight line's
//! would be off by `G''·var(u)/2`: 15 % of a law saturating over 2 mm with a 1 mm window). Pooling by
//! depth rather than by place is what makes a multiplicative place factor cancel: the fit over a
//! window is `Ā·G(u)`, and only ratios of `G` are used. A slope within
//! [`LoggedProcessOptions::significance`] standard errors of zero is taken as zero (a process that
//! does not follow the depth, or noise); a bin with fewer than five points or a depth spread
//! (standard deviation) under 5 % of the window has no value. Between bins `G` is linear; beyond
//! the logged depths it continues along the end bins' fitted lines (extrapolation: the law is
//! not known there); the ratio is bounded to `[0, max_force_ratio]` (the points where the bound
//! acts are counted). When no bin has a slope, the logged wrenches are kept
//! ([`ProcessModel::follows_command`] is false) and one compensation pass is exact.
//!
//! **Equilibrium at a command.** The compensation asks for the wrench at a commanded pose `c`
//! with the robot model's compliance `C` there. With `w = ρ w_log` the tool deflects by
//! `ρ·d`, `d = (C w_log)_p + b_i`, where `b_i = δ_log,i − (C_i w_log,i)_p` is the deflection the
//! model missed in the logged run (zero without measured positions; it scales with the force,
//! as a missing compliance does, and the compensation adds it to eq. 15's through
//! [`ProcessModel::unmodelled_deflection`]). The depth is `u = t·c + ρ·a`, `a = t·d`, so `ρ`
//! solves `ρ = G(t·c + ρ a) / G(u_log,i)`, by bracketed regula falsi on `[0, max_force_ratio]`
//! (for a process pushing back, `a < 0` and `G` increasing, the left side minus the right is
//! increasing: one root). At the logged command (`c = c_log`, the same compliance) `ρ = 1`: the
//! log is reproduced. A compensated tool meets a larger force, but less than its programmed
//! advance alone would give: it still gives way under it.
//!
//! The first process pass of a compensation is at the desired path; when the logged run was not
//! compensated that is the logged command and the wrench is the log's.
//!
//! **Whether the log supports the law.** The law above takes the depth as the force's cause.
//! Where the force is set along the path (force control, constant pressure, a press fit) the
//! depth in the log follows the deflection instead, the fitted law falls with depth and the
//! fixed point does not contract. [`LawEvidence`] (module `evidence`) tests the log on itself —
//! the held-out force explained by the commanded depth against the path position, the loop gain
//! `|G'|·C_t`, the share of falling bins — and with
//! [`LoggedProcessOptions::require_evidence`] a law the log does not support is not used: the
//! logged wrenches are kept ([`ProcessModel::follows_command`] is false, one pass).
//! [`Identification::evidence`] and [`Identification::law_used`] report it.
//!
//! **What it cannot know**: a force where the log has none (a tool that touches earlier when
//! compensated), and the part of the deflection that is not proportional to the force (a
//! geometric error of the arm measured in `b` is scaled with it). Measured positions must be in
//! the world frame of the robot model, at the times of the rows (the tracker's lag and
//! registration error go into `b`).

mod evidence;

pub use evidence::{LawEvidence, MARGIN, MAX_FALLING_SHARE, MAX_LOOP_GAIN, MIN_R2};

use crate::error::ProcessError;
use crate::log::Resampled;
use crate::process::{ProcessModel, ProcessPoint};
use deflex_model::Wrench;
use nalgebra::{Matrix3, Vector3};

/// Settings of [`LoggedProcess`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoggedProcessOptions {
    /// Half width of the depth window of the local fit (m), 1e-5 ..= 0.1.
    pub depth_window_m: f64,
    /// Points whose axial force is below this fraction of the largest are out of contact,
    /// 0.001 ..= 0.5.
    pub contact_fraction: f64,
    /// A slope within this many standard errors of zero is not used, 0 ..= 10.
    pub significance: f64,
    /// Largest ratio of the predicted to the logged force, 1 ..= 10.
    pub max_force_ratio: f64,
    /// Use the log's measured TCP (tracker) when it has one.
    pub use_measured: bool,
    /// Use the law only when the log supports it as a cause ([`LawEvidence::supported`]);
    /// otherwise keep the logged wrenches (`--log-forces auto`). Off: the law whenever it has a
    /// slope (`--log-forces law`).
    pub require_evidence: bool,
    /// Off: never use the law, keep the logged wrenches (with the measured TCP's correction
    /// of what the model misses, when used): the fallback of a law that did not converge.
    pub use_law: bool,
}

impl Default for LoggedProcessOptions {
    fn default() -> Self {
        LoggedProcessOptions {
            depth_window_m: 1e-3,
            contact_fraction: 0.05,
            significance: 3.0,
            max_force_ratio: 2.0,
            use_measured: true,
            require_evidence: false,
            use_law: true,
        }
    }
}

/// An option of [`LoggedProcessOptions`] outside its range.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{name}: expected {lo} ..= {hi}, got {got}")]
pub struct LoggedOptionError {
    /// The option.
    pub name: &'static str,
    /// Smallest value accepted.
    pub lo: f64,
    /// Largest value accepted.
    pub hi: f64,
    /// The value given.
    pub got: f64,
}

impl LoggedProcessOptions {
    fn validate(&self) -> Result<(), LoggedOptionError> {
        let check = |name: &'static str, v: f64, lo: f64, hi: f64| {
            if v.is_finite() && (lo..=hi).contains(&v) {
                Ok(())
            } else {
                Err(LoggedOptionError {
                    name,
                    lo,
                    hi,
                    got: v,
                })
            }
        };
        check("depth_window_m", self.depth_window_m, 1e-5, 0.1)?;
        check("contact_fraction", self.contact_fraction, 1e-3, 0.5)?;
        check("significance", self.significance, 0.0, 10.0)?;
        check("max_force_ratio", self.max_force_ratio, 1.0, 10.0)
    }
}

/// What the observation of the desired path identified.
#[derive(Clone, Debug, PartialEq)]
pub struct Identification {
    /// Path points.
    pub points: usize,
    /// Points in contact in the log.
    pub contact_points: usize,
    /// Depth bins of the law with a value, and those with a slope.
    pub law_bins: usize,
    /// Bins with a (significant) slope.
    pub sloped_bins: usize,
    /// Depth of the tool along its axis in the logged run over the contact points (m, the world
    /// coordinate along the axis: only differences matter).
    pub depth_range_m: [f64; 2],
    /// `G` at the shallowest and the deepest bin with a value (N).
    pub force_range_n: [f64; 2],
    /// Smallest and largest relative slope `G'/G` over the bins (1/m).
    pub relative_slope_range_per_m: [f64; 2],
    /// Largest logged axial force (N).
    pub max_axial_force_n: f64,
    /// The measured TCP was used.
    pub measured: bool,
    /// Largest deflection the robot model missed in the logged run, |b| (m; 0 unmeasured).
    pub max_unmodelled_m: f64,
    /// Whether the log supports the law as a cause ([`evidence`](LawEvidence)); `None` without
    /// contact points.
    pub evidence: Option<LawEvidence>,
    /// The law is used: it has a slope and, with [`LoggedProcessOptions::require_evidence`],
    /// the evidence supports it.
    pub law_used: bool,
}

/// The force–depth law `G`: fitted lines at bin centres `x_k = (k + ½)·width` above `origin`.
#[derive(Clone, Debug, Default)]
struct Law {
    origin: f64,
    width: f64,
    /// `(value, slope)` at each bin centre (N, N/m); `None`: no value there.
    fits: Vec<Option<(f64, f64)>>,
    /// First and last bin with a value.
    first: usize,
    last: usize,
}

impl Law {
    /// `G(u)`: linear between the bin centres with values (gaps bridged), the end bins' lines
    /// beyond them.
    fn at(&self, u: f64) -> f64 {
        let x = (u - self.origin) / self.width - 0.5;
        let (first, last) = (self.first, self.last);
        let centre = |k: usize| k as f64;
        if x <= centre(first) {
            let (g, slope) = self.fits[first].expect("first has a value");
            return g + slope * self.width * (x - centre(first));
        }
        if x >= centre(last) {
            let (g, slope) = self.fits[last].expect("last has a value");
            return g + slope * self.width * (x - centre(last));
        }
        let k = (x.floor() as usize).clamp(first, last);
        let below = (first..=k)
            .rev()
            .find(|&j| self.fits[j].is_some())
            .unwrap_or(first);
        let above = (k + 1..=last)
            .find(|&j| self.fits[j].is_some())
            .unwrap_or(last);
        let (g0, _) = self.fits[below].expect("has a value");
        let (g1, _) = self.fits[above].expect("has a value");
        if above == below {
            return g0;
        }
        let f = (x - centre(below)) / (centre(above) - centre(below));
        g0 + (g1 - g0) * f
    }
}

/// The process law identified from a log (see the module documentation).
#[derive(Clone, Debug)]
pub struct LoggedProcess {
    label: String,
    simulated: bool,
    options: LoggedProcessOptions,
    /// Logged wrench at each path point.
    wrenches: Vec<Wrench>,
    /// Logged commanded and measured TCP (freed after the observation).
    commanded: Vec<Vector3<f64>>,
    measured: Option<Vec<Vector3<f64>>>,
    /// Per point, filled by the observation: axial force and depth (tool z axis, sign not yet
    /// fixed), arc length (freed after it).
    axial_force: Vec<f64>,
    depth: Vec<f64>,
    arc_length: Vec<f64>,
    /// Commanded depth `t·c_log` (the depth without the deflection) and the model's compliance
    /// along the tool axis `tᵀ C_ff t` at each point (freed after the observation).
    commanded_depth: Vec<f64>,
    axis_compliance: Vec<f64>,
    /// `b_i` (empty without measured positions).
    unmodelled: Vec<Vector3<f64>>,
    /// `G(u_log,i)` at the contact points, 0 elsewhere (the logged wrench is kept there).
    logged_level: Vec<f64>,
    law: Law,
    /// +1: the axis is the tool's z axis; −1: its opposite.
    sign: f64,
    identification: Option<Identification>,
    /// Points where the force ratio was bounded in the current pass.
    bounded: usize,
}

impl LoggedProcess {
    /// A process from a log resampled on the path (`label` names it in reports).
    pub fn new(
        label: &str,
        simulated: bool,
        resampled: Resampled,
        options: LoggedProcessOptions,
    ) -> Result<LoggedProcess, ProcessError> {
        let error = |message: String| ProcessError {
            model: format!("process identified from {label}"),
            index: 0,
            message,
        };
        options.validate().map_err(|e| error(e.to_string()))?;
        if resampled.commanded_m.len() != resampled.wrenches.len()
            || resampled
                .measured_m
                .as_ref()
                .is_some_and(|m| m.len() != resampled.wrenches.len())
        {
            return Err(error("the resampled columns differ in length".into()));
        }
        let measured = resampled.measured_m.filter(|_| options.use_measured);
        Ok(LoggedProcess {
            label: label.to_string(),
            simulated,
            options,
            wrenches: resampled.wrenches,
            commanded: resampled.commanded_m,
            measured,
            axial_force: Vec::new(),
            depth: Vec::new(),
            arc_length: Vec::new(),
            commanded_depth: Vec::new(),
            axis_compliance: Vec::new(),
            unmodelled: Vec::new(),
            logged_level: Vec::new(),
            law: Law::default(),
            sign: 1.0,
            identification: None,
            bounded: 0,
        })
    }

    /// What the observation identified (after a compensation has started).
    pub fn identification(&self) -> Option<&Identification> {
        self.identification.as_ref()
    }

    /// Points whose force ratio was bounded in the last pass.
    pub fn bounded_points(&self) -> usize {
        self.bounded
    }

    /// `G(u)` of the identified law (N; `u` the depth along the tool axis, m), once observed.
    pub fn law_force_n(&self, depth_m: f64) -> Option<f64> {
        (!self.law.fits.is_empty()).then(|| self.law.at(depth_m))
    }

    fn error(&self, index: usize, message: String) -> ProcessError {
        ProcessError {
            model: self.name(),
            index,
            message,
        }
    }

    /// The logged wrench's force ratio `w·w_log / |w_log|²` (1 for a zero log wrench).
    fn ratio(&self, index: usize, wrench: &Wrench) -> f64 {
        let w = &self.wrenches[index];
        let norm = w.norm_squared();
        if norm > 0.0 {
            wrench.dot(w) / norm
        } else {
            1.0
        }
    }

    /// Fit the law over the contact points (see the module documentation).
    fn fit_law(&self, contact: &[usize], weights: &[f64], lo: f64, hi: f64) -> Law {
        let h = self.options.depth_window_m;
        let width = (0.1 * h).max((hi - lo) / 1e6).max(1e-12);
        let bins = ((hi - lo) / width) as usize + 1;
        let centre = |k: usize| (k as f64 + 0.5) * width;
        let mut moments = vec![Moments::default(); bins];
        for &i in contact {
            let x = self.depth[i] - lo;
            let k = ((x / width) as usize).min(bins - 1);
            moments[k].push((x - centre(k)) / h, self.axial_force[i], weights[i]);
        }
        let reach = (h / width).round() as usize;
        let fits: Vec<Option<(f64, f64)>> = (0..bins)
            .map(|k| {
                let mut window = Moments::default();
                let first = k.saturating_sub(reach);
                let last = (k + reach).min(bins - 1);
                for (j, bin) in moments[first..=last].iter().enumerate() {
                    if bin.count > 0 {
                        window.add_shifted(bin, (centre(first + j) - centre(k)) / h);
                    }
                }
                // Slope per unit of h → per metre.
                window
                    .fit(self.options.significance)
                    .map(|(g, slope)| (g, slope / h))
            })
            .collect();
        let first = fits.iter().position(Option::is_some);
        let last = fits.iter().rposition(Option::is_some);
        match (first, last) {
            (Some(first), Some(last)) => Law {
                origin: lo,
                width,
                fits,
                first,
                last,
            },
            _ => Law::default(),
        }
    }
}

/// Weighted moments of the points of a depth bin about a centre `c`, in units of the window
/// `h`: `m_j = Σ w ((u − c)/h)^j` (j = 0 … 4), `t_j = Σ w ((u − c)/h)^j F` (j = 0 … 2),
/// `yy = Σ w F²`.
#[derive(Clone, Copy, Default)]
struct Moments {
    count: usize,
    m: [f64; 5],
    t: [f64; 3],
    yy: f64,
}

impl Moments {
    /// Add one point at `z = (u − c)/h`.
    fn push(&mut self, z: f64, y: f64, w: f64) {
        self.count += 1;
        let mut p = w;
        for j in 0..5 {
            self.m[j] += p;
            if j < 3 {
                self.t[j] += p * y;
            }
            p *= z;
        }
        self.yy += w * y * y;
    }

    /// Add `other`, whose centre lies `shift` (units of h) from this one's: the binomial
    /// expansion `(z + s)^j = Σ C(j, i) z^i s^(j−i)`.
    fn add_shifted(&mut self, other: &Moments, shift: f64) {
        const C: [[f64; 5]; 5] = [
            [1.0, 0.0, 0.0, 0.0, 0.0],
            [1.0, 1.0, 0.0, 0.0, 0.0],
            [1.0, 2.0, 1.0, 0.0, 0.0],
            [1.0, 3.0, 3.0, 1.0, 0.0],
            [1.0, 4.0, 6.0, 4.0, 1.0],
        ];
        let powers = [1.0, shift, shift * shift, shift.powi(3), shift.powi(4)];
        for j in 0..5 {
            let moment: f64 = (0..=j).map(|i| C[j][i] * other.m[i] * powers[j - i]).sum();
            self.m[j] += moment;
            if j < 3 {
                let t: f64 = (0..=j).map(|i| C[j][i] * other.t[i] * powers[j - i]).sum();
                self.t[j] += t;
            }
        }
        self.count += other.count;
        self.yy += other.yy;
    }

    /// `G` and `G'` (per unit of h) at the centre from these moments: the local quadratic fit
    /// (its value is unbiased by the law's curvature to second order, where a straight line's
    /// is off by `G''·var(u)/2`), a straight line where the depths do not support a parabola
    /// (two levels in the window). The slope is zero when the straight line's is within
    /// `significance` standard errors of zero; `None` for fewer than five points or a depth
    /// spread under 5 % of the window.
    fn fit(&self, significance: f64) -> Option<(f64, f64)> {
        let [s0, s1, s2, s3, s4] = self.m;
        let [t0, t1, t2] = self.t;
        if self.count < 5 || s0 <= 0.0 {
            return None;
        }
        let mean = s1 / s0;
        let sxx = s2 - s0 * mean * mean;
        if !(sxx > 0.0 && sxx / s0 >= 0.05 * 0.05) {
            return None;
        }
        let my = t0 / s0;
        let sxy = t1 - mean * t0;
        let syy = self.yy - s0 * my * my;
        let slope = sxy / sxx;
        // Standard error of the slope: SSR / ((n − 2) Sxx), invariant to the weights' scale.
        let ssr = (syy - slope * sxy).max(0.0);
        let se = (ssr / ((self.count - 2) as f64 * sxx)).sqrt();
        if slope.abs() <= significance * se {
            return Some((my, 0.0));
        }
        let normal = Matrix3::new(s0, s1, s2, s1, s2, s3, s2, s3, s4) / s0;
        let eigen = normal.symmetric_eigenvalues();
        let (lo, hi) = (eigen.min(), eigen.max());
        if self.count >= 8
            && lo > 1e-6 * hi
            && let Some(c) = normal
                .cholesky()
                .map(|ch| ch.solve(&(Vector3::new(t0, t1, t2) / s0)))
        {
            return Some((c[0], c[1]));
        }
        Some((my - slope * mean, slope))
    }
}

impl ProcessModel for LoggedProcess {
    fn name(&self) -> String {
        let law = match &self.identification {
            Some(id) if id.law_used => format!(
                "force along the tool axis × G(depth)/G(logged depth), G {:.0} … {:.0} N over {:.2} mm of depth",
                id.force_range_n[0],
                id.force_range_n[1],
                (id.depth_range_m[1] - id.depth_range_m[0]) * 1e3
            ),
            Some(id) if id.sloped_bins > 0 => {
                "the logged forces (the log does not support a force–depth law)".into()
            }
            Some(_) => "the logged forces (they do not follow the depth)".into(),
            None => "force–depth law".into(),
        };
        let measured = if self.measured.is_some() || !self.unmodelled.is_empty() {
            "; measured TCP"
        } else {
            ""
        };
        format!(
            "process identified from {}{}: {law}{measured}",
            if self.simulated { "SIMULATED " } else { "" },
            self.label
        )
    }

    fn simulated(&self) -> bool {
        self.simulated
    }

    fn begin_pass(&mut self) {
        self.bounded = 0;
    }

    fn observes_desired_path(&self) -> bool {
        true
    }

    fn observe_desired(&mut self, point: &ProcessPoint) -> Result<(), ProcessError> {
        let i = point.index;
        if i != self.axial_force.len() || i >= self.wrenches.len() {
            return Err(self.error(
                i,
                format!(
                    "observed out of order or beyond the log's {} points",
                    self.wrenches.len()
                ),
            ));
        }
        let t = point.desired.rotation * Vector3::z();
        let w = &self.wrenches[i];
        let force = w.fixed_rows::<3>(0);
        let model = (point.compliance * w).fixed_rows::<3>(0).into_owned();
        let c = self.commanded[i];
        let deflection = match &self.measured {
            Some(m) => {
                let d = m[i] - c;
                self.unmodelled.push(d - model);
                d
            }
            None => model,
        };
        self.axial_force.push(-t.dot(&force));
        self.depth.push(t.dot(&(c + deflection)));
        self.commanded_depth.push(t.dot(&c));
        let c_ff = point.compliance.fixed_view::<3, 3>(0, 0);
        self.axis_compliance.push(t.dot(&(c_ff * t)));
        self.arc_length.push(point.arc_length_m);
        Ok(())
    }

    fn finish_observation(&mut self) -> Result<(), ProcessError> {
        let n = self.wrenches.len();
        if self.axial_force.len() != n {
            return Err(self.error(
                self.axial_force.len(),
                format!(
                    "the path has {} points, the log {n}",
                    self.axial_force.len()
                ),
            ));
        }
        // Each point's share of arc length.
        let weights: Vec<f64> = (0..n)
            .map(|i| {
                let a = self.arc_length[i.saturating_sub(1)];
                let b = self.arc_length[(i + 1).min(n - 1)];
                0.5 * (b - a)
            })
            .collect();
        // The axis points into the part: the logged force pushes against it.
        let push: f64 = self
            .axial_force
            .iter()
            .zip(&weights)
            .map(|(f, w)| f * w)
            .sum();
        self.sign = if push < 0.0 { -1.0 } else { 1.0 };
        let sign = self.sign;
        self.axial_force.iter_mut().for_each(|f| *f *= sign);
        self.depth.iter_mut().for_each(|u| *u *= sign);
        self.commanded_depth.iter_mut().for_each(|u| *u *= sign);
        let max_force = self.axial_force.iter().copied().fold(0.0, f64::max);
        let threshold = self.options.contact_fraction * max_force;
        let contact: Vec<usize> = (0..n)
            .filter(|&i| max_force > 0.0 && self.axial_force[i] > threshold)
            .collect();
        let (lo, hi) = contact.iter().fold((f64::MAX, f64::MIN), |(lo, hi), &i| {
            (lo.min(self.depth[i]), hi.max(self.depth[i]))
        });
        self.law = if contact.is_empty() {
            Law::default()
        } else {
            self.fit_law(&contact, &weights, lo, hi)
        };
        self.logged_level = vec![0.0; n];
        let sloped = self
            .law
            .fits
            .iter()
            .flatten()
            .filter(|(_, slope)| *slope != 0.0)
            .count();
        let fits: Vec<(f64, f64)> = self.law.fits.iter().flatten().copied().collect();
        let evidence = (contact.len() >= 2 * evidence::BLOCKS).then(|| {
            let pick = |v: &[f64]| contact.iter().map(|&i| v[i]).collect::<Vec<f64>>();
            let sloped_fits: Vec<(f64, f64)> =
                fits.iter().copied().filter(|(_, s)| *s != 0.0).collect();
            LawEvidence::evaluate(
                &pick(&self.axial_force),
                &pick(&self.commanded_depth),
                &pick(&self.arc_length),
                &pick(&weights),
                &pick(&self.axis_compliance),
                &sloped_fits,
            )
        });
        let law_used = self.options.use_law
            && sloped > 0
            && (!self.options.require_evidence
                || evidence.as_ref().is_some_and(LawEvidence::supported));
        if law_used {
            for &i in &contact {
                let g = self.law.at(self.depth[i]);
                if g > threshold {
                    self.logged_level[i] = g;
                }
            }
        }
        let relative = fits
            .iter()
            .filter(|(g, _)| *g > 0.0)
            .map(|(g, slope)| slope / g)
            .fold(None, |r: Option<[f64; 2]>, k| {
                Some(r.map_or([k, k], |[a, b]| [a.min(k), b.max(k)]))
            })
            .unwrap_or([0.0; 2]);
        self.identification = Some(Identification {
            points: n,
            contact_points: contact.len(),
            law_bins: fits.len(),
            sloped_bins: sloped,
            depth_range_m: if contact.is_empty() {
                [0.0; 2]
            } else {
                [lo, hi]
            },
            force_range_n: match (fits.first(), fits.last()) {
                (Some(a), Some(b)) => [a.0, b.0],
                _ => [0.0; 2],
            },
            relative_slope_range_per_m: relative,
            max_axial_force_n: max_force,
            measured: !self.unmodelled.is_empty(),
            max_unmodelled_m: self.unmodelled.iter().map(|b| b.norm()).fold(0.0, f64::max),
            evidence,
            law_used,
        });
        // What the passes do not need any more.
        self.commanded = Vec::new();
        self.measured = None;
        self.arc_length = Vec::new();
        self.axial_force = Vec::new();
        self.commanded_depth = Vec::new();
        self.axis_compliance = Vec::new();
        Ok(())
    }

    fn follows_command(&self) -> bool {
        self.logged_level.iter().any(|g| *g > 0.0)
    }

    fn wrench(&mut self, point: &ProcessPoint) -> Result<Wrench, ProcessError> {
        let i = point.index;
        if i >= self.wrenches.len() || self.logged_level.len() != self.wrenches.len() {
            return Err(self.error(i, "called before the observation of the path".into()));
        }
        let w = self.wrenches[i];
        let level = self.logged_level[i];
        if level <= 0.0 {
            return Ok(w);
        }
        let t = point.desired.rotation * Vector3::z() * self.sign;
        let mut d = (point.compliance * w).fixed_rows::<3>(0).into_owned();
        if let Some(b) = self.unmodelled.get(i) {
            d += b;
        }
        let (a, tc) = (t.dot(&d), t.dot(&point.commanded.translation.vector));
        // g(ρ) = ρ − G(t·c + ρ a)/G(u_log): the ratio's root by regula falsi (Illinois) on
        // [0, max]; g(0) ≤ 0 for a law that is not negative.
        let g = |rho: f64| rho - self.law.at(tc + rho * a).max(0.0) / level;
        let max = self.options.max_force_ratio;
        let (mut lo, mut g_lo) = (0.0, g(0.0));
        let (mut hi, mut g_hi) = (max, g(max));
        let ratio = if g_lo >= 0.0 {
            0.0
        } else if g_hi <= 0.0 {
            self.bounded += 1;
            max
        } else {
            let mut side = 0i8;
            let mut x = 1.0;
            for _ in 0..100 {
                x = (lo * g_hi - hi * g_lo) / (g_hi - g_lo);
                let gx = g(x);
                if gx.abs() < 1e-12 || hi - lo < 1e-12 {
                    break;
                }
                if gx < 0.0 {
                    (lo, g_lo) = (x, gx);
                    if side == -1 {
                        g_hi *= 0.5;
                    }
                    side = -1;
                } else {
                    (hi, g_hi) = (x, gx);
                    if side == 1 {
                        g_lo *= 0.5;
                    }
                    side = 1;
                }
            }
            x
        };
        if !ratio.is_finite() {
            return Err(self.error(i, format!("non-finite force ratio {ratio}")));
        }
        Ok(w * ratio)
    }

    fn unmodelled_deflection(&self, index: usize, wrench: &Wrench) -> Option<Vector3<f64>> {
        self.unmodelled
            .get(index)
            .map(|b| b * self.ratio(index, wrench))
    }
}

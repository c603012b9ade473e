//! Checks of a parsed `CELL.toml`: every number finite and within sane bounds (documented in
//! `docs/cell.example.toml`), every name known; each error names the file and the field and says
//! what was expected. The bounds keep every duration, rate, size and count the runtime derives
//! from the file (sleep periods, buffer sizes, ramp lengths) finite and small enough to act on.

use super::{AXES, CellFile, ConfigError};

/// Bounds of every numeric field, `(field, lowest, highest, unit)`. A lowest bound written as
/// `f64::MIN_POSITIVE` means "strictly positive".
pub const BOUNDS: &[(&str, f64, f64, &str)] = &[
    ("robot.cycle_s", 0.0005, 0.1, "s"),
    ("robot.timeout_s", 0.001, 10.0, "s"),
    ("robot.egm_sensor_rpy_rad", -7.0, 7.0, "rad"),
    ("robot.egm_work_object_rpy_rad", -7.0, 7.0, "rad"),
    ("sensor.counts_per_force", 1e-3, 1e12, "counts/N"),
    ("sensor.counts_per_torque", 1e-3, 1e12, "counts/(N·m)"),
    ("sensor.timeout_s", 0.001, 10.0, "s"),
    ("sensor.range", 1e-3, 1e6, "N or N·m"),
    ("mounting.sensor_xyz_m", -10.0, 10.0, "m"),
    ("mounting.sensor_rpy_rad", -7.0, 7.0, "rad"),
    ("mounting.tool_mass_kg", 0.0, 1000.0, "kg"),
    ("mounting.tool_com_m", -10.0, 10.0, "m"),
    ("mounting.gravity_m_s2", -100.0, 100.0, "m/s²"),
    ("mounting.bias", -1e6, 1e6, "N or N·m"),
    ("mounting.tare_s", 0.0, 60.0, "s"),
    ("mounting.lowpass_hz", 0.01, 10_000.0, "Hz"),
    ("control.rate_hz", 1.0, 5000.0, "Hz"),
    ("control.kc", 0.0, 100.0, ""),
    ("control.ti_s", 0.0, 1000.0, "s"),
    ("control.td_s", 0.0, 100.0, "s"),
    ("control.derivative_filter_n", 0.0, 1000.0, ""),
    ("limits.max_correction_m", 0.0, 0.1, "m"),
    ("limits.max_correction_rad", 0.0, 0.5, "rad"),
    ("limits.max_rate_m_s", 0.0, 1.0, "m/s"),
    ("limits.max_rate_rad_s", 0.0, 5.0, "rad/s"),
    ("limits.ramp_in_s", 0.0, 10.0, "s"),
    ("limits.ramp_out_s", 0.0, 10.0, "s"),
    ("limits.max_force_n", 1e-3, 1e6, "N"),
    ("limits.max_torque_nm", 1e-3, 1e6, "N·m"),
    (
        "limits.max_joint_step_rad",
        1e-6,
        std::f64::consts::PI,
        "rad",
    ),
    ("limits.runaway_gain_limit", 0.01, 10.0, ""),
    ("limits.runaway_release_gain", 0.0, 10.0, ""),
    ("limits.runaway_window_s", 0.01, 10.0, "s"),
    ("limits.runaway_min_travel_m", 1e-7, 0.01, "m"),
    ("limits.runaway_confirm_cycles", 1.0, 1000.0, "cycles"),
    ("limits.runaway_withdraw_s", 0.01, 10.0, "s"),
    ("limits.runaway_release_rate_m_s", 1e-6, 0.1, "m/s"),
    ("log.ring_capacity", 16.0, 262_144.0, "records"),
    ("feedforward.lead_s", 0.0, 1.0, "s"),
    ("feedforward.max_offset_m", 1e-4, 0.1, "m"),
    ("feedforward.window_m", 1e-3, 1.0, "m"),
    ("feedforward.time_offset_s", 0.0, 1e6, "s"),
];

/// The bounds of `field` (as in [`BOUNDS`]).
pub fn bounds_of(field: &str) -> (f64, f64, &'static str) {
    BOUNDS
        .iter()
        .find(|(f, ..)| *f == field)
        .map(|(_, lo, hi, unit)| (*lo, *hi, *unit))
        .unwrap_or((f64::NEG_INFINITY, f64::INFINITY, ""))
}

impl CellFile {
    fn invalid(&self, field: &str, message: impl Into<String>) -> ConfigError {
        ConfigError::Invalid {
            path: self.origin.clone(),
            field: field.to_string(),
            message: message.into(),
        }
    }

    /// `value` within the bounds of `bounds_field`; errors name `field` (which may carry an
    /// index, e.g. `sensor.range[2]`).
    fn in_bounds(&self, bounds_field: &str, field: &str, value: f64) -> Result<(), ConfigError> {
        let (lo, hi, unit) = bounds_of(bounds_field);
        if value >= lo && value <= hi {
            Ok(())
        } else {
            let unit = if unit.is_empty() {
                String::new()
            } else {
                format!(" {unit}")
            };
            Err(self.invalid(
                field,
                format!("expected a number from {lo} to {hi}{unit}, got {value}"),
            ))
        }
    }

    fn check(&self, field: &str, value: f64) -> Result<(), ConfigError> {
        self.in_bounds(field, field, value)
    }

    fn check_all(&self, field: &str, values: &[f64]) -> Result<(), ConfigError> {
        for (i, v) in values.iter().enumerate() {
            self.in_bounds(field, &format!("{field}[{i}]"), *v)?;
        }
        Ok(())
    }

    fn one_of(&self, field: &str, value: &str, allowed: &[&str]) -> Result<(), ConfigError> {
        if allowed.contains(&value) {
            Ok(())
        } else {
            let list = allowed
                .iter()
                .map(|a| format!("\"{a}\""))
                .collect::<Vec<_>>()
                .join(", ");
            Err(self.invalid(field, format!("expected one of {list}, got \"{value}\"")))
        }
    }

    pub(super) fn validate(&self) -> Result<(), ConfigError> {
        let r = &self.robot;
        self.one_of(
            "robot.correction_mode",
            &r.correction_mode,
            &["absolute", "relative"],
        )?;
        if !deflex_io::rsi::valid_sen_type(&r.sen_type) {
            return Err(self.invalid(
                "robot.sen_type",
                format!(
                    "expected a plain name (letters, digits, _ - ., at most 64), got \"{}\"",
                    r.sen_type
                ),
            ));
        }
        self.one_of("robot.rsi_answer", &r.rsi_answer, &["cartesian", "joint"])?;
        self.one_of("robot.rsi_joint_tag", &r.rsi_joint_tag, &["AK", "AKorr"])?;
        self.one_of(
            "robot.egm_frame",
            &r.egm_frame,
            &["tool", "work-object", "base"],
        )?;
        self.check_all("robot.egm_sensor_rpy_rad", &r.egm_sensor_rpy_rad)?;
        self.check_all("robot.egm_work_object_rpy_rad", &r.egm_work_object_rpy_rad)?;
        self.check("robot.cycle_s", r.cycle_s)?;
        self.check("robot.timeout_s", r.timeout_s)?;
        if r.timeout_s < r.cycle_s {
            return Err(self.invalid(
                "robot.timeout_s",
                format!(
                    "must be at least one robot cycle (robot.cycle_s = {} s), got {} s",
                    r.cycle_s, r.timeout_s
                ),
            ));
        }
        let s = &self.sensor;
        self.check("sensor.counts_per_force", s.counts_per_force)?;
        self.check("sensor.counts_per_torque", s.counts_per_torque)?;
        self.check("sensor.timeout_s", s.timeout_s)?;
        self.check_all("sensor.range", &s.range)?;
        let m = &self.mounting;
        self.check_all("mounting.sensor_xyz_m", &m.sensor_xyz_m)?;
        self.check_all("mounting.sensor_rpy_rad", &m.sensor_rpy_rad)?;
        self.check("mounting.tool_mass_kg", m.tool_mass_kg)?;
        self.check_all("mounting.tool_com_m", &m.tool_com_m)?;
        self.check_all("mounting.gravity_m_s2", &m.gravity_m_s2)?;
        if let Some(b) = &m.bias {
            self.check_all("mounting.bias", b)?;
        }
        self.check("mounting.tare_s", m.tare_s)?;
        if let Some(f) = m.lowpass_hz {
            self.check("mounting.lowpass_hz", f)?;
        }
        if self.model.file.trim().is_empty() {
            return Err(self.invalid("model.file", "must name a model file or a built-in robot"));
        }
        let c = &self.control;
        self.check("control.rate_hz", c.rate_hz)?;
        self.check("control.kc", c.kc)?;
        self.check("control.ti_s", c.ti_s)?;
        self.check("control.td_s", c.td_s)?;
        self.check("control.derivative_filter_n", c.derivative_filter_n)?;
        for a in &c.axes {
            if !AXES.contains(&a.as_str()) {
                return Err(self.invalid(
                    "control.axes",
                    format!("unknown axis \"{a}\", expected some of x, y, z, rx, ry, rz"),
                ));
            }
        }
        let l = &self.limits;
        self.check("limits.max_correction_m", l.max_correction_m)?;
        self.check("limits.max_correction_rad", l.max_correction_rad)?;
        self.check("limits.max_rate_m_s", l.max_rate_m_s)?;
        self.check("limits.max_rate_rad_s", l.max_rate_rad_s)?;
        self.check("limits.ramp_in_s", l.ramp_in_s)?;
        self.check("limits.ramp_out_s", l.ramp_out_s)?;
        self.check("limits.max_force_n", l.max_force_n)?;
        self.check("limits.max_torque_nm", l.max_torque_nm)?;
        self.check("limits.max_joint_step_rad", l.max_joint_step_rad)?;
        self.one_of("limits.safe_action", &l.safe_action, &["zero", "hold"])?;
        self.check("limits.runaway_gain_limit", l.runaway_gain_limit)?;
        self.check("limits.runaway_release_gain", l.runaway_release_gain)?;
        if l.runaway_release_gain >= l.runaway_gain_limit {
            return Err(self.invalid(
                "limits.runaway_release_gain",
                format!(
                    "must be below limits.runaway_gain_limit ({}), got {}",
                    l.runaway_gain_limit, l.runaway_release_gain
                ),
            ));
        }
        self.check("limits.runaway_window_s", l.runaway_window_s)?;
        self.check("limits.runaway_min_travel_m", l.runaway_min_travel_m)?;
        self.check(
            "limits.runaway_confirm_cycles",
            f64::from(l.runaway_confirm_cycles),
        )?;
        self.check("limits.runaway_withdraw_s", l.runaway_withdraw_s)?;
        self.check(
            "limits.runaway_release_rate_m_s",
            l.runaway_release_rate_m_s,
        )?;
        self.one_of(
            "limits.runaway_action",
            &l.runaway_action,
            &["withdraw", "hold", "fault"],
        )?;
        if let Some(f) = &self.feedforward {
            if f.table.trim().is_empty() {
                return Err(self.invalid("feedforward.table", "must name a compensated_path.csv"));
            }
            self.one_of(
                "feedforward.mode",
                &f.mode,
                &["feed-forward", "precompensated"],
            )?;
            self.one_of("feedforward.index", &f.index, &["arc-length", "time"])?;
            self.check("feedforward.lead_s", f.lead_s)?;
            self.check("feedforward.max_offset_m", f.max_offset_m)?;
            self.check("feedforward.window_m", f.window_m)?;
            self.check("feedforward.time_offset_s", f.time_offset_s)?;
            if f.mode == "precompensated" && f.lead_s > 0.0 {
                return Err(self.invalid(
                    "feedforward.lead_s",
                    format!(
                        "a lead applies to mode = \"feed-forward\" only (the program applies \
                         its compensation itself), got {} s",
                        f.lead_s
                    ),
                ));
            }
        }
        if let Some(log) = &self.log {
            if log.path.trim().is_empty() {
                return Err(self.invalid("log.path", "must not be empty"));
            }
            self.check("log.ring_capacity", log.ring_capacity as f64)?;
        }
        Ok(())
    }
}

//! Checks of a parsed `CELL.toml`: every number in range, every name known; each error names
//! the file and the field.

use super::{AXES, CellFile, ConfigError};

impl CellFile {
    fn invalid(&self, field: &str, message: impl Into<String>) -> ConfigError {
        ConfigError::Invalid {
            path: self.origin.clone(),
            field: field.to_string(),
            message: message.into(),
        }
    }

    pub(super) fn validate(&self) -> Result<(), ConfigError> {
        let positive = |field: &str, v: f64| -> Result<(), ConfigError> {
            if v > 0.0 && v.is_finite() {
                Ok(())
            } else {
                Err(self.invalid(field, format!("must be a positive number, got {v}")))
            }
        };
        let non_negative = |field: &str, v: f64| -> Result<(), ConfigError> {
            if v >= 0.0 && v.is_finite() {
                Ok(())
            } else {
                Err(self.invalid(field, format!("must be ≥ 0, got {v}")))
            }
        };
        if !matches!(self.robot.correction_mode.as_str(), "absolute" | "relative") {
            return Err(self.invalid(
                "robot.correction_mode",
                format!(
                    "expected \"absolute\" or \"relative\", got \"{}\"",
                    self.robot.correction_mode
                ),
            ));
        }
        positive("robot.cycle_s", self.robot.cycle_s)?;
        positive("robot.timeout_s", self.robot.timeout_s)?;
        positive("sensor.counts_per_force", self.sensor.counts_per_force)?;
        positive("sensor.counts_per_torque", self.sensor.counts_per_torque)?;
        positive("sensor.timeout_s", self.sensor.timeout_s)?;
        for (i, v) in self.sensor.range.iter().enumerate() {
            positive(&format!("sensor.range[{i}]"), *v)?;
        }
        let m = &self.mounting;
        non_negative("mounting.tool_mass_kg", m.tool_mass_kg)?;
        non_negative("mounting.tare_s", m.tare_s)?;
        if let Some(f) = m.lowpass_hz {
            positive("mounting.lowpass_hz", f)?;
        }
        let finite3 = |field: &str, v: &[f64]| -> Result<(), ConfigError> {
            if v.iter().all(|x| x.is_finite()) {
                Ok(())
            } else {
                Err(self.invalid(field, "must be finite numbers"))
            }
        };
        finite3("mounting.sensor_xyz_m", &m.sensor_xyz_m)?;
        finite3("mounting.sensor_rpy_rad", &m.sensor_rpy_rad)?;
        finite3("mounting.tool_com_m", &m.tool_com_m)?;
        finite3("mounting.gravity_m_s2", &m.gravity_m_s2)?;
        if let Some(b) = &m.bias {
            finite3("mounting.bias", b)?;
        }
        if self.model.file.trim().is_empty() {
            return Err(self.invalid("model.file", "must name a model file or a built-in robot"));
        }
        let c = &self.control;
        positive("control.rate_hz", c.rate_hz)?;
        non_negative("control.kc", c.kc)?;
        non_negative("control.ti_s", c.ti_s)?;
        non_negative("control.td_s", c.td_s)?;
        non_negative("control.derivative_filter_n", c.derivative_filter_n)?;
        for a in &c.axes {
            if !AXES.contains(&a.as_str()) {
                return Err(self.invalid(
                    "control.axes",
                    format!("unknown axis \"{a}\", expected some of x, y, z, rx, ry, rz"),
                ));
            }
        }
        let l = &self.limits;
        non_negative("limits.max_correction_m", l.max_correction_m)?;
        non_negative("limits.max_correction_rad", l.max_correction_rad)?;
        non_negative("limits.max_rate_m_s", l.max_rate_m_s)?;
        non_negative("limits.max_rate_rad_s", l.max_rate_rad_s)?;
        non_negative("limits.ramp_in_s", l.ramp_in_s)?;
        non_negative("limits.ramp_out_s", l.ramp_out_s)?;
        positive("limits.max_force_n", l.max_force_n)?;
        positive("limits.max_torque_nm", l.max_torque_nm)?;
        positive("limits.max_joint_step_rad", l.max_joint_step_rad)?;
        if !matches!(l.safe_action.as_str(), "zero" | "hold") {
            return Err(self.invalid(
                "limits.safe_action",
                format!("expected \"zero\" or \"hold\", got \"{}\"", l.safe_action),
            ));
        }
        if let Some(log) = &self.log
            && log.path.trim().is_empty()
        {
            return Err(self.invalid("log.path", "must not be empty"));
        }
        Ok(())
    }
}

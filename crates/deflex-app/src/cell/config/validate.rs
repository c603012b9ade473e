//! Checks of a parsed `CELL.toml`: every number finite and within sane bounds (documented in
//! `docs/cell.example.toml`), every name known; each error names the file and the field and says
//! what was expected. The bounds keep every duration, rate, size and count the runtime derives
//! from the file (sleep periods, buffer sizes, ramp lengths) finite and small enough to act on.

use super::{CellFile, ConfigError, InvalidReason};
use super::{RobotKind, SensorKind};
use deflex_control::FeedForwardMode;

/// Bounds of every numeric field, `(field, lowest, highest, unit)`. A lowest bound written as
/// `f64::MIN_POSITIVE` means "strictly positive".
pub const BOUNDS: &[(&str, f64, f64, &str)] = &[
    ("robot.cycle_s", 0.0005, 0.1, "s"),
    ("robot.timeout_s", 0.001, 10.0, "s"),
    ("robot.stream_velocity_rad_s", 1e-3, 20.0, "rad/s"),
    ("robot.stream_acceleration_rad_s2", 1e-3, 500.0, "rad/s²"),
    ("robot.stream_jerk_rad_s3", 1e-3, 1e5, "rad/s³"),
    ("robot.stream_ramp_s", 0.01, 10.0, "s"),
    ("robot.rtde_register", 24.0, 42.0, ""),
    ("robot.ur_alpha_filter", 0.001, 1.0, ""),
    ("robot.stream_late_after_s", 0.001, 10.0, "s"),
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
    ("model_check.position_tolerance_m", 1e-4, 0.5, "m"),
    ("model_check.orientation_tolerance_rad", 1e-4, 0.5, "rad"),
    ("sensor.max_age_s", 0.001, 10.0, "s"),
    ("sensor.queue_depth", 1.0, 1024.0, "messages"),
    ("log.ring_capacity", 16.0, 262_144.0, "records"),
    ("ros2.domain_id", 0.0, 232.0, ""),
    ("ros2.depth", 1.0, 1000.0, "messages"),
    ("ros2.publish_rate_hz", 0.1, 1000.0, "Hz"),
    ("ros2.diagnostics_rate_hz", 0.1, 100.0, "Hz"),
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
    fn invalid(&self, field: &'static str, reason: InvalidReason) -> ConfigError {
        ConfigError::Invalid {
            path: self.origin.clone(),
            field,
            reason,
        }
    }

    /// `value` within the bounds of `bounds_field`; errors name `field` (which may carry an
    /// index, e.g. `sensor.range[2]`).
    fn in_bounds(&self, bounds_field: &str, field: String, value: f64) -> Result<(), ConfigError> {
        let (lowest, highest, unit) = bounds_of(bounds_field);
        if value >= lowest && value <= highest {
            Ok(())
        } else {
            Err(ConfigError::OutOfBounds {
                path: self.origin.clone(),
                field,
                value,
                lowest,
                highest,
                unit,
            })
        }
    }

    fn check(&self, field: &str, value: f64) -> Result<(), ConfigError> {
        self.in_bounds(field, field.to_string(), value)
    }

    fn check_all(&self, field: &str, values: &[f64]) -> Result<(), ConfigError> {
        for (i, v) in values.iter().enumerate() {
            self.in_bounds(field, format!("{field}[{i}]"), *v)?;
        }
        Ok(())
    }

    pub(super) fn validate(&self) -> Result<(), ConfigError> {
        self.validate_robot()?;
        self.validate_sensor_and_mounting()?;
        if self.model.file.trim().is_empty() {
            return Err(self.invalid(
                "model.file",
                InvalidReason::Empty("name a model file or a built-in robot"),
            ));
        }
        self.validate_control_and_limits()?;
        self.validate_feedforward_and_log()?;
        self.validate_ros2()
    }

    fn validate_ros2(&self) -> Result<(), ConfigError> {
        if self.sensor.kind == SensorKind::Ros2 {
            self.check("sensor.max_age_s", self.sensor.max_age_s)?;
            self.check("sensor.queue_depth", self.sensor.queue_depth as f64)?;
            if !valid_ros2_name(&self.sensor.topic, true) {
                return Err(self.invalid(
                    "sensor.topic",
                    InvalidReason::Ros2Name("absolute", self.sensor.topic.clone()),
                ));
            }
            if self.ros2.is_none() {
                return Err(self.invalid("sensor.kind", InvalidReason::Ros2SectionMissing));
            }
        }
        let Some(r) = &self.ros2 else {
            return Ok(());
        };
        self.check("ros2.domain_id", f64::from(r.domain_id))?;
        self.check("ros2.depth", r.depth as f64)?;
        self.check("ros2.publish_rate_hz", r.publish_rate_hz)?;
        self.check("ros2.diagnostics_rate_hz", r.diagnostics_rate_hz)?;
        if r.publish_rate_hz > self.control.rate_hz {
            return Err(self.invalid(
                "ros2.publish_rate_hz",
                InvalidReason::PublishAboveControlRate {
                    rate_hz: r.publish_rate_hz,
                    control_hz: self.control.rate_hz,
                },
            ));
        }
        if r.namespace != "/" && !valid_ros2_name(&r.namespace, true) {
            return Err(self.invalid(
                "ros2.namespace",
                InvalidReason::Ros2Name("absolute, or / alone", r.namespace.clone()),
            ));
        }
        if !valid_ros2_name(&r.node_name, false) || r.node_name.contains('/') {
            return Err(self.invalid(
                "ros2.node_name",
                InvalidReason::Ros2Name("one token", r.node_name.clone()),
            ));
        }
        for (field, frame) in [
            ("ros2.base_frame", &r.base_frame),
            ("ros2.sensor_frame", &r.sensor_frame),
            ("ros2.tcp_frame", &r.tcp_frame),
        ] {
            let ok = !frame.is_empty()
                && frame.len() <= 255
                && frame.chars().all(|c| c.is_ascii_graphic());
            if !ok {
                return Err(self.invalid(field, InvalidReason::FrameId(frame.clone())));
            }
        }
        Ok(())
    }

    fn validate_robot(&self) -> Result<(), ConfigError> {
        let r = &self.robot;
        if !deflex_io::rsi::valid_sen_type(&r.sen_type) {
            return Err(self.invalid("robot.sen_type", InvalidReason::SenType(r.sen_type.clone())));
        }
        self.check_all("robot.egm_sensor_rpy_rad", &r.egm_sensor_rpy_rad)?;
        self.check_all("robot.egm_work_object_rpy_rad", &r.egm_work_object_rpy_rad)?;
        self.check("robot.cycle_s", r.cycle_s)?;
        self.check("robot.timeout_s", r.timeout_s)?;
        self.check_all("robot.stream_velocity_rad_s", &r.stream_velocity_rad_s)?;
        self.check_all(
            "robot.stream_acceleration_rad_s2",
            &r.stream_acceleration_rad_s2,
        )?;
        self.check_all("robot.stream_jerk_rad_s3", &r.stream_jerk_rad_s3)?;
        self.check("robot.stream_ramp_s", r.stream_ramp_s)?;
        if let Some(late) = r.stream_late_after_s {
            self.check("robot.stream_late_after_s", late)?;
        }
        if r.kind == super::RobotKind::FanucStream {
            if r.peer.is_none() {
                return Err(self.invalid(
                    "robot.peer",
                    InvalidReason::Empty(
                        "give the controller's Stream Motion address (port 60015)",
                    ),
                ));
            }
            if r.stream_path.as_deref().is_none_or(|p| p.trim().is_empty()) {
                return Err(self.invalid(
                    "robot.stream_path",
                    InvalidReason::Empty("name the compensated_path.csv deflex streams"),
                ));
            }
        }
        if r.kind == RobotKind::UrRtde {
            // deflex connects to the controller: its address is required, nothing listens.
            self.check("robot.rtde_register", f64::from(r.rtde_register))?;
            self.check("robot.ur_alpha_filter", r.ur_alpha_filter)?;
            match r.peer {
                None => return Err(self.invalid("robot.peer", InvalidReason::RtdeNeedsPeer)),
                Some(p) if p.ip().is_unspecified() || p.ip().is_multicast() => {
                    return Err(self.invalid(
                        "robot.peer",
                        InvalidReason::Peer(deflex_io::PeerConfigError::NotAHost { peer: p }),
                    ));
                }
                Some(_) => {}
            }
        } else if let Err(e) = deflex_io::validate_peer(r.bind, r.peer, r.allow_any_peer) {
            let field = match e {
                deflex_io::PeerConfigError::NoPeerOnNetworkBind { .. } => "robot.bind",
                deflex_io::PeerConfigError::PeerAndAllowAny { .. } => "robot.allow_any_peer",
                _ => "robot.peer",
            };
            return Err(self.invalid(field, InvalidReason::Peer(e)));
        }
        if r.timeout_s < r.cycle_s {
            return Err(self.invalid(
                "robot.timeout_s",
                InvalidReason::TimeoutBelowCycle {
                    timeout_s: r.timeout_s,
                    cycle_s: r.cycle_s,
                },
            ));
        }
        Ok(())
    }

    fn validate_sensor_and_mounting(&self) -> Result<(), ConfigError> {
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
        Ok(())
    }

    fn validate_control_and_limits(&self) -> Result<(), ConfigError> {
        let c = &self.control;
        self.check("control.rate_hz", c.rate_hz)?;
        self.check("control.kc", c.kc)?;
        self.check("control.ti_s", c.ti_s)?;
        self.check("control.td_s", c.td_s)?;
        self.check("control.derivative_filter_n", c.derivative_filter_n)?;
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
        self.check("limits.runaway_gain_limit", l.runaway_gain_limit)?;
        self.check("limits.runaway_release_gain", l.runaway_release_gain)?;
        if l.runaway_release_gain >= l.runaway_gain_limit {
            return Err(self.invalid(
                "limits.runaway_release_gain",
                InvalidReason::ReleaseNotBelowLimit {
                    release: l.runaway_release_gain,
                    limit: l.runaway_gain_limit,
                },
            ));
        }
        self.check("limits.runaway_window_s", l.runaway_window_s)?;
        let m = &self.model_check;
        self.check("model_check.position_tolerance_m", m.position_tolerance_m)?;
        self.check(
            "model_check.orientation_tolerance_rad",
            m.orientation_tolerance_rad,
        )?;
        self.check("limits.runaway_min_travel_m", l.runaway_min_travel_m)?;
        self.check(
            "limits.runaway_confirm_cycles",
            f64::from(l.runaway_confirm_cycles),
        )?;
        self.check("limits.runaway_withdraw_s", l.runaway_withdraw_s)?;
        self.check(
            "limits.runaway_release_rate_m_s",
            l.runaway_release_rate_m_s,
        )
    }

    fn validate_feedforward_and_log(&self) -> Result<(), ConfigError> {
        if let Some(f) = &self.feedforward {
            if f.table.trim().is_empty() {
                return Err(self.invalid(
                    "feedforward.table",
                    InvalidReason::Empty("name a compensated_path.csv"),
                ));
            }
            self.check("feedforward.lead_s", f.lead_s)?;
            self.check("feedforward.max_offset_m", f.max_offset_m)?;
            self.check("feedforward.window_m", f.window_m)?;
            self.check("feedforward.time_offset_s", f.time_offset_s)?;
            if f.mode == FeedForwardMode::Precompensated && f.lead_s > 0.0 {
                return Err(self.invalid(
                    "feedforward.lead_s",
                    InvalidReason::LeadWithPrecompensated { lead_s: f.lead_s },
                ));
            }
        }
        if let Some(log) = &self.log {
            if log.path.trim().is_empty() {
                return Err(self.invalid("log.path", InvalidReason::Empty("not be empty")));
            }
            self.check("log.ring_capacity", log.ring_capacity as f64)?;
        }
        Ok(())
    }
}

/// A ROS 2 name (topic, namespace or node): tokens of letters, digits and `_`, not starting with
/// a digit, separated by single `/`, no trailing `/`, at most 255 characters; `absolute` names
/// start with `/`.
pub fn valid_ros2_name(name: &str, absolute: bool) -> bool {
    let body = match name.strip_prefix('/') {
        Some(rest) => rest,
        None if absolute => return false,
        None => name,
    };
    name.len() <= 255
        && !body.is_empty()
        && body.split('/').all(|token| {
            !token.is_empty()
                && !token.starts_with(|c: char| c.is_ascii_digit())
                && token.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
        })
}

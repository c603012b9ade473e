//! From a `CELL.toml` to the [`ControllerConfig`] of the correction law (gains of eq. 17,
//! limiter, wrench processing, safety).

use super::CellFile;
use super::choices::CorrectionAxis;
use deflex_control::{
    ControllerConfig, LimiterConfig, ModelCheckConfig, PidGains, RunawayConfig, SafetyConfig,
    WrenchConfig,
};
use deflex_model::ToolLoad;
use deflex_model::spatial::pose_from_xyz_rpy;

impl CellFile {
    /// The controller configuration this file describes.
    pub fn controller_config(&self) -> ControllerConfig {
        let m = &self.mounting;
        let c = &self.control;
        let l = &self.limits;
        let enabled = std::array::from_fn(|i| c.axes.contains(&CorrectionAxis::ALL[i]));
        ControllerConfig {
            period_s: 1.0 / c.rate_hz,
            gains: PidGains {
                kc: c.kc,
                ti_s: c.ti_s,
                td_s: c.td_s,
                derivative_filter_n: c.derivative_filter_n,
                tracking_time_s: None,
            },
            limiter: LimiterConfig {
                max_abs: [
                    l.max_correction_m,
                    l.max_correction_m,
                    l.max_correction_m,
                    l.max_correction_rad,
                    l.max_correction_rad,
                    l.max_correction_rad,
                ],
                max_rate: [
                    l.max_rate_m_s,
                    l.max_rate_m_s,
                    l.max_rate_m_s,
                    l.max_rate_rad_s,
                    l.max_rate_rad_s,
                    l.max_rate_rad_s,
                ],
                enabled,
                ramp_in_s: l.ramp_in_s,
                ramp_out_s: l.ramp_out_s,
            },
            wrench: WrenchConfig {
                sensor_in_flange: pose_from_xyz_rpy(m.sensor_xyz_m, m.sensor_rpy_rad),
                tool_in_sensor: ToolLoad {
                    mass_kg: m.tool_mass_kg,
                    centre_of_mass_m: nalgebra::Vector3::from(m.tool_com_m),
                },
                gravity_world: m.gravity_m_s2,
                lowpass_hz: m.lowpass_hz,
            },
            safety: SafetyConfig {
                max_force_n: l.max_force_n,
                max_torque_nm: l.max_torque_nm,
                sensor_timeout_s: self.sensor.timeout_s,
                robot_timeout_s: self.robot.timeout_s,
                sensor_range: self.sensor.range,
                max_joint_step_rad: l.max_joint_step_rad,
                joint_limit_margin_rad: SafetyConfig::default().joint_limit_margin_rad,
                safe_action: l.safe_action,
            },
            tare_s: m.tare_s,
            bias: m.bias,
            runaway: RunawayConfig {
                enabled: l.runaway_guard,
                gain_limit: l.runaway_gain_limit,
                release_gain: l.runaway_release_gain,
                window_s: l.runaway_window_s,
                min_travel_m: l.runaway_min_travel_m,
                confirm_cycles: l.runaway_confirm_cycles,
                withdraw_s: l.runaway_withdraw_s,
                release_rate_m_s: l.runaway_release_rate_m_s,
                action: l.runaway_action,
                ..RunawayConfig::default()
            },
            model_check: ModelCheckConfig {
                enabled: self.model_check.enabled,
                position_tolerance_m: self.model_check.position_tolerance_m,
                orientation_tolerance_rad: self.model_check.orientation_tolerance_rad,
            },
        }
    }
}

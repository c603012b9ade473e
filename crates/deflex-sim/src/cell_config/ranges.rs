//! The bounds of every twin setting: finite, within the documented range, the field named.

use super::CellConfig;
use crate::error::SimError;
use crate::range_check::{all_bounded, bounded, bounded_open};

impl CellConfig {
    /// Check physical ranges; every message names the field.
    pub fn validate(&self) -> Result<(), SimError> {
        self.validate_controller()?;
        self.validate_sensor()?;
        self.validate_tracker()?;
        self.validate_part()?;
        bounded(
            "process.fixture_stiffness_n_m",
            self.process.fixture_stiffness_n_m,
            1e4,
            1e9,
            "N/m",
        )?;
        bounded(
            "process.prescribed_force_n",
            self.process.prescribed_force_n,
            1.0,
            20_000.0,
            "N",
        )?;
        bounded(
            "process.prescribed_ramp_mm",
            self.process.prescribed_ramp_mm,
            0.0,
            10_000.0,
            "mm",
        )?;
        bounded("log.rate_hz", self.log.rate_hz, 0.1, 1000.0, "Hz")?;
        if self.log.rate_hz > self.controller.rate_hz {
            return Err(SimError::config(
                "log.rate_hz",
                format!(
                    "must not exceed controller.rate_hz ({} Hz), got {}",
                    self.controller.rate_hz, self.log.rate_hz
                ),
            ));
        }
        self.plant.validate()?;
        self.sheet.validate()?;
        Ok(())
    }

    /// The robot controller section.
    fn validate_controller(&self) -> Result<(), SimError> {
        let c = &self.controller;
        bounded("controller.rate_hz", c.rate_hz, 10.0, 10_000.0, "Hz")?;
        bounded(
            "controller.correction_delay_s",
            c.correction_delay_s,
            0.0,
            1.0,
            "s",
        )?;
        bounded(
            "controller.correction_filter_s",
            c.correction_filter_s,
            0.0,
            1.0,
            "s",
        )?;
        if c.servo_bandwidth_hz != 0.0 {
            bounded(
                "controller.servo_bandwidth_hz",
                c.servo_bandwidth_hz,
                0.5,
                c.rate_hz / 4.0,
                "Hz (0 = ideal; at most a quarter of controller.rate_hz)",
            )?;
        }
        bounded("controller.lookahead_s", c.lookahead_s, 0.0, 1.0, "s")?;
        bounded_open("controller.max_correction_m", c.max_correction_m, 0.1, "m")?;
        bounded_open(
            "controller.max_correction_rad",
            c.max_correction_rad,
            0.5,
            "rad",
        )?;
        bounded_open(
            "controller.max_correction_speed_m_s",
            c.max_correction_speed_m_s,
            1.0,
            "m/s",
        )?;
        bounded_open(
            "controller.max_correction_speed_rad_s",
            c.max_correction_speed_rad_s,
            10.0,
            "rad/s",
        )?;
        bounded(
            "controller.rapid_feed_mm_s",
            c.rapid_feed_mm_s,
            0.1,
            2000.0,
            "mm/s",
        )?;
        Ok(())
    }

    /// The F/T sensor section.
    fn validate_sensor(&self) -> Result<(), SimError> {
        let s = &self.sensor;
        bounded("sensor.rate_hz", s.rate_hz, 100.0, 7000.0, "Hz")?;
        all_bounded(
            "sensor.sensor_in_flange_xyz_m",
            &s.sensor_in_flange_xyz_m,
            2.0,
            "m",
        )?;
        all_bounded(
            "sensor.sensor_in_flange_rpy",
            &s.sensor_in_flange_rpy,
            7.0,
            "rad",
        )?;
        bounded("sensor.tool_mass_kg", s.tool_mass_kg, 0.0, 1000.0, "kg")?;
        all_bounded(
            "sensor.tool_com_in_sensor_m",
            &s.tool_com_in_sensor_m,
            2.0,
            "m",
        )?;
        for (i, v) in s.noise_sigma.iter().enumerate() {
            bounded(
                &format!("sensor.noise_sigma[{i}]"),
                *v,
                0.0,
                1000.0,
                "N or N·m",
            )?;
        }
        all_bounded("sensor.bias", &s.bias, 1e4, "N or N·m")?;
        for (i, v) in s.range.iter().enumerate() {
            bounded_open(&format!("sensor.range[{i}]"), *v, 1e6, "N or N·m")?;
        }
        bounded("sensor.gravity_m_s2", s.gravity_m_s2, 0.0, 30.0, "m/s²")?;
        all_bounded("sensor.gain_error", &s.gain_error, 0.5, "(relative)")?;
        all_bounded(
            "sensor.bias_drift_per_s",
            &s.bias_drift_per_s,
            10.0,
            "N/s or N·m/s",
        )?;
        all_bounded(
            "sensor.mounting_error_xyz_m",
            &s.mounting_error_xyz_m,
            0.05,
            "m",
        )?;
        all_bounded(
            "sensor.mounting_error_rpy",
            &s.mounting_error_rpy,
            0.1,
            "rad",
        )?;
        bounded(
            "sensor.tool_mass_error_kg",
            s.tool_mass_error_kg,
            -10.0,
            10.0,
            "kg",
        )?;
        all_bounded("sensor.tool_com_error_m", &s.tool_com_error_m, 0.1, "m")?;
        if s.tool_mass_kg + s.tool_mass_error_kg < 0.0 {
            return Err(SimError::config(
                "sensor.tool_mass_error_kg",
                "makes the true tool mass negative",
            ));
        }
        Ok(())
    }

    /// The laser tracker section.
    fn validate_tracker(&self) -> Result<(), SimError> {
        let t = &self.tracker;
        if !(t.rate_hz > 0.0 && t.rate_hz <= 50.0) {
            return Err(SimError::config(
                "tracker.rate_hz",
                format!("must be within (0, 50] Hz, got {}", t.rate_hz),
            ));
        }
        all_bounded("tracker.position_m", &t.position_m, 100.0, "m")?;
        bounded("tracker.sigma_const_m", t.sigma_const_m, 0.0, 0.01, "m")?;
        bounded("tracker.sigma_per_m", t.sigma_per_m, 0.0, 0.01, "m/m")?;
        if !(1..=1000).contains(&t.samples_per_reading) {
            return Err(SimError::config(
                "tracker.samples_per_reading",
                format!("must be within 1..1000, got {}", t.samples_per_reading),
            ));
        }
        all_bounded(
            "tracker.registration_error_xyz_m",
            &t.registration_error_xyz_m,
            0.01,
            "m",
        )?;
        all_bounded(
            "tracker.registration_error_rpy",
            &t.registration_error_rpy,
            0.01,
            "rad",
        )?;
        Ok(())
    }

    /// The part section: robot, placement, tool and pivot.
    fn validate_part(&self) -> Result<(), SimError> {
        let p = &self.part;
        if p.robot.trim().is_empty() {
            return Err(SimError::config("part.robot", "must name a robot"));
        }
        all_bounded("part.origin_mm", &p.origin_mm, 1e5, "mm")?;
        all_bounded("part.seed_q_deg", &p.seed_q_deg, 720.0, "deg")?;
        all_bounded("part.tool_xyz_m", &p.tool_xyz_m, 2.0, "m")?;
        all_bounded("part.tool_rpy", &p.tool_rpy, 7.0, "rad")?;
        if let Some(pivot) = &p.base_pivot_m {
            all_bounded("part.base_pivot_m", pivot, 5.0, "m")?;
        }
        Ok(())
    }
}

//! What a `deflex run` session did, for people ([`RunReport::summary_text`]) and for programs
//! ([`RunReport::summary_json`]). The front end adds what its own outlets did (the ROS 2 sensor
//! link and bridge, the live view: [`OutletLines`] and its own JSON keys) and the exit code.

use crate::cell::run_session::{Recording, RunReport};
use deflex_control::Fault;
use deflex_runtime::stats::StatsSummary;
use serde_json::json;

/// A cycle-time histogram's summary in JSON (µs).
pub fn stats_json(s: &StatsSummary) -> serde_json::Value {
    json!({"count": s.count, "p50_us": s.p50_us, "p99_us": s.p99_us, "max_us": s.max_us,
           "mean_us": s.mean_us, "deadline_misses": s.deadline_misses})
}

/// A latched fault in JSON: kind, channel, time, value against its limit and unit, text.
pub fn fault_json(f: &Fault) -> serde_json::Value {
    json!({"kind": f.kind.name(), "channel": f.channel.to_string(), "time_s": f.time_s,
           "value": f.value, "limit": f.limit, "unit": f.unit(), "text": f.to_string()})
}

/// The summary lines of what the front end attached to the session, where they belong.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OutletLines {
    /// After the sensor's line: the front end's links (the ROS 2 sensor link and bridge).
    pub links: Vec<String>,
    /// After the recording's line: the live view.
    pub view: Option<String>,
}

/// The largest of `values`, 0 for none.
fn largest(values: &[f64]) -> f64 {
    values.iter().fold(0.0f64, |m, v| m.max(*v))
}

impl RunReport {
    /// The summary `deflex run` prints, one line per part, each ending in a newline, with the
    /// front end's `outlets` in their places.
    pub fn summary_text(&self, outlets: &OutletLines) -> String {
        let s = &self.session.summary;
        let mut lines = vec![
            format!(
                "deflex run: {:.1} s, {} control cycles ({:.1} Hz), phase: {}",
                self.wall_s,
                s.cycles,
                s.cycles as f64 / self.wall_s.max(1e-9),
                s.phase_text()
            ),
            format!("  control cycle:     {}", s.control),
        ];
        if let Some(text) = &self.feedforward {
            lines.push(format!("  feed-forward:      {text}"));
        }
        lines.push(self.robot_line());
        lines.push(self.model_check_line());
        lines.push(format!(
            "  robot link: {} receive timeouts, {} malformed packets, {} errors, {} from other hosts or second connections refused{}; {} robot messages dropped as no new state ({} sequence not advancing, {} clock going back, {} joint count)",
            s.robot_timeouts,
            s.robot_bad_packets,
            s.robot_errors,
            s.robot_foreign,
            s.last_foreign
                .map(|a| format!(" (last {a})"))
                .unwrap_or_default(),
            s.robot_dropped,
            s.robot_link.dropped_sequence + s.robot_link.dropped_sequence_mismatch,
            s.robot_link.dropped_time,
            s.robot_link.dropped_joint_count,
        ));
        lines.push(format!(
            "  largest correction step sent: {:.4} mm (limit {:.4} mm per robot cycle)",
            largest(&s.max_step_sent[..3]) * 1e3,
            self.session.step_limit_m * 1e3
        ));
        lines.push(format!(
            "  sensor: {} samples, {} lost, {} flagged by the status word, {} malformed or failed, {} from other hosts refused",
            s.samples, s.sample_gaps, s.sensor_faults, s.sensor_errors, s.sensor_foreign
        ));
        lines.extend(outlets.links.iter().cloned());
        lines.push(format!(
            "  max force {:.1} N, max |ξp| {:.3} mm",
            s.max_force_n,
            s.max_xi_m * 1e3
        ));
        if let Some(f) = &s.first_runaway {
            lines.push(format!(
                "  warning: the runaway guard acted {} time(s); first: {f}",
                s.runaway_events
            ));
        }
        lines.push(self.fault_line());
        lines.extend(self.log_line());
        lines.extend(self.recording.as_ref().map(|r| self.recording_line(r)));
        lines.extend(outlets.view.iter().map(|v| format!("  live view: {v}")));
        lines.extend(s.warnings.iter().map(|w| format!("  warning: {w}")));
        lines.iter().map(|l| format!("{l}\n")).collect()
    }

    /// The robot link's reply latency and answers.
    fn robot_line(&self) -> String {
        let s = &self.session.summary;
        format!(
            "  {} ({} joints) reply latency: p50 {:.0} µs, p99 {:.0} µs, max {:.0} µs; {} telegrams answered, {} answered later than one robot cycle{}",
            self.session.robot_kind.name(),
            s.robot_joints,
            s.reply_latency.p50_us,
            s.reply_latency.p99_us,
            s.reply_latency.max_us,
            s.telegrams,
            s.reply_latency.deadline_misses,
            match s.robot_late {
                Some(l) => format!("; the robot counted {l} late answers (RSI Delay)"),
                None => String::new(),
            }
        )
    }

    /// The model check: the largest difference between the TCP pose the robot reported and the
    /// model's at the same joints, or why none was made.
    fn model_check_line(&self) -> String {
        let o = &self.session;
        let c = &o.model_check;
        let tolerance = format!(
            "tolerance {:.2} mm, {:.2} mrad",
            c.position_tolerance_m * 1e3,
            c.orientation_tolerance_rad * 1e3
        );
        match (&o.summary.pose_mismatch_max, c.enabled) {
            (_, false) => "  model check: off ([model_check] enabled = false)".to_string(),
            (Some(m), true) => format!(
                "  model check: largest difference between the robot's reported TCP and the \
                 model's at the same joints {:.3} mm, {:.3} mrad ({tolerance})",
                m.position_m * 1e3,
                m.orientation_rad * 1e3
            ),
            (None, true) => format!(
                "  model check: not made: the robot reported no TCP pose ({} carries none; KUKA \
                 RSI and ABB EGM do)",
                o.robot_kind.name()
            ),
        }
    }

    /// The latched fault, or none (a final silence of the robot explained).
    fn fault_line(&self) -> String {
        let s = &self.session.summary;
        match (&s.fault, &s.final_silence) {
            (Some(f), _) => format!("  fault: {f} — the correction was ramped to its safe value"),
            (None, Some(f)) => format!(
                "  fault: none — the {} latched at t {:.2} s (shown by the live line) was the robot's \
                 final silence: no telegram came after it, the end of its program",
                f.kind.name(),
                f.time_s
            ),
            (None, None) => "  fault: none".to_string(),
        }
    }

    /// The CSV log: written, not written and why (with `[log]`).
    fn log_line(&self) -> Option<String> {
        let o = &self.session;
        let p = o.log_path.as_ref()?;
        Some(if let Some(e) = &o.log_error {
            format!(
                "  log: NOT written: {e} ({} keeps what it held)",
                deflex_files::shown_path(p)
            )
        } else if o.log_committed {
            format!(
                "  log: {} ({} rows, {} dropped)",
                p.display(),
                o.log_rows,
                o.summary.log_dropped
            )
        } else {
            format!(
                "  log: not written, the run failed ({} keeps what it held)",
                p.display()
            )
        })
    }

    /// The MCAP recording: written (kept exactly when the log is), not written, or failed.
    fn recording_line(&self, recording: &Recording) -> String {
        let path = &recording.path;
        match &recording.result {
            Ok(r) if self.session.log_committed => format!(
                "  recording: {} (MCAP, {} cycles, {} lost, {:.1} MB)",
                path.display(),
                r.stats.recorded,
                r.lost,
                r.stats.bytes as f64 / 1e6
            ),
            Ok(_) => format!(
                "  recording: not written, the run failed ({} keeps what it held)",
                path.display()
            ),
            Err(e) => format!("  recording: failed: {e}"),
        }
    }

    /// The summary `deflex run --json` prints, without what the front end adds: its outlets'
    /// keys (`view`, `ros2_bridge`, `ros2_sensor`) and `exit_code`.
    pub fn summary_json(&self) -> serde_json::Value {
        let o = &self.session;
        let s = &o.summary;
        let link = &s.robot_link;
        let mut value = json!({
            "wall_s": self.wall_s, "cycles": s.cycles, "phase": s.end.name(),
            "phase_text": s.phase_text(), "controller_phase": s.phase.name(),
            "robot_protocol": o.robot_kind.name(), "robot_joints": s.robot_joints,
            "control_cycle": stats_json(&s.control), "reply_latency": stats_json(&s.reply_latency),
            "telegrams": s.telegrams,
            "late_replies": s.reply_latency.deadline_misses,
            "robot_reported_late": s.robot_late,
            "robot_timeouts": s.robot_timeouts,
            "robot_bad_packets": s.robot_bad_packets, "robot_errors": s.robot_errors,
            "robot_foreign": s.robot_foreign,
            "last_foreign": s.last_foreign.map(|a| a.to_string()),
            "max_step_sent_m": largest(&s.max_step_sent[..3]),
            "max_step_sent_rad": largest(&s.max_step_sent[3..]),
            "step_limit_m": o.step_limit_m,
            "feedforward": self.feedforward,
            "samples": s.samples, "sample_gaps": s.sample_gaps, "sensor_faults": s.sensor_faults,
            "sensor_errors": s.sensor_errors, "sensor_foreign": s.sensor_foreign,
            "fault": s.fault.as_ref().map(fault_json),
            "final_silence": s.final_silence.as_ref().map(fault_json),
            "log_error": o.log_error,
            "runaway_events": s.runaway_events,
            "first_runaway": s.first_runaway.as_ref().map(fault_json),
            "model_check": self.model_check_json(),
            "max_force_n": s.max_force_n, "max_correction_mm": s.max_xi_m * 1e3,
            "log_rows": o.log_rows, "log_committed": o.log_committed,
            "log_dropped": s.log_dropped, "warnings": s.warnings,
            "error": s.error.as_ref().map(ToString::to_string),
        });
        for (key, v) in [
            ("mcap", self.recording_json()),
            ("robot_dropped", json!(s.robot_dropped)),
            ("robot_starved", json!(s.robot_starved)),
            (
                "robot_dropped_sequence",
                json!(link.dropped_sequence + link.dropped_sequence_mismatch),
            ),
            ("robot_dropped_time", json!(link.dropped_time)),
            ("robot_dropped_joint_count", json!(link.dropped_joint_count)),
            (
                "robot_refused_connections",
                json!(link.refused_busy + link.refused_starving),
            ),
        ] {
            value[key] = v;
        }
        value
    }

    /// The model check, for `--json`: on or off, the tolerances and the largest difference
    /// seen (`null` when the robot reported no pose).
    fn model_check_json(&self) -> serde_json::Value {
        let c = &self.session.model_check;
        let m = self.session.summary.pose_mismatch_max;
        json!({"enabled": c.enabled, "position_tolerance_m": c.position_tolerance_m,
               "orientation_tolerance_rad": c.orientation_tolerance_rad,
               "max_position_m": m.map(|m| m.position_m),
               "max_orientation_rad": m.map(|m| m.orientation_rad)})
    }

    /// The recording, for `--json` (`null` without `[log]`).
    fn recording_json(&self) -> serde_json::Value {
        let Some(recording) = &self.recording else {
            return serde_json::Value::Null;
        };
        let ok = recording.result.as_ref().ok();
        json!({
            "path": recording.path,
            "committed": self.session.log_committed && ok.is_some(),
            "cycles": ok.map(|r| r.stats.recorded),
            "lost": ok.map(|r| r.lost),
            "bytes": ok.map(|r| r.stats.bytes),
            "error": recording.result.as_ref().err().map(ToString::to_string),
        })
    }
}

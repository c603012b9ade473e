//! The compensation of a set-up against its wrench source: the twin's process model, a log (its
//! force–depth law or its wrenches as they are) or given wrenches.

use super::{LogForces, Setup, WrenchSpec};
use crate::error::{Error, Result};
use crate::load::read_wrench_log;
use deflex_compensate::log::{ResampleOptions, resample_on_path};
use deflex_compensate::{
    Compensation, CompensationOptions, Identification, LoggedProcess, LoggedProcessOptions,
    TcpPath, WrenchSource,
};
use deflex_model::{Robot, Wrench};
use deflex_sim::FormingProcess;
use deflex_telemetry::Progress;
use serde_json::json;

/// A finished compensation with its set-up: what the table, the summaries and the programs need.
pub struct CompensationRun {
    /// The set-up.
    pub setup: Setup,
    /// The result.
    pub result: Compensation,
    /// Lines on the wrench source (log rows used, the law identified from a log, …).
    pub source_lines: Vec<String>,
    /// The force–depth law identified from a log (`summary.json`'s `log_law`), if any.
    pub log_law: Option<serde_json::Value>,
    /// Wall time of the compensation (s).
    pub elapsed_s: f64,
}

/// Compensate the set-up's path against its wrench source, reporting progress (a stage per
/// iteration, the points done) to `on_progress`.
pub fn compensate(
    setup: Setup,
    on_progress: &mut dyn FnMut(Progress<'_>),
) -> Result<CompensationRun> {
    let started = std::time::Instant::now();
    let mut source_lines = Vec::new();
    let mut log_law = None;
    let s = &setup;
    let run = |source: WrenchSource, on_progress: &mut dyn FnMut(Progress<'_>)| {
        iterate(&s.robot, &s.path, &s.seed, source, &s.options, on_progress)
    };
    let result = match &s.wrench {
        WrenchSpec::Process => {
            // `setup` refuses the process model for a robot without a cell.
            let config = s.config.as_ref().ok_or_else(|| {
                Error::invalid(
                    s.front.name("wrench"),
                    "the process model needs the robot's twin cell",
                )
            })?;
            let mut process =
                FormingProcess::from_cell(config, &s.tool_path).map_err(Error::ProcessModel)?;
            run(WrenchSource::Process(&mut process), on_progress)?
        }
        WrenchSpec::Log(file) => {
            let log = read_wrench_log(file, &s.robot, &s.part_frame)?;
            let resampled = resample_on_path(&log, &s.path, &ResampleOptions::default())?;
            let simulated = if log.simulated { "SIMULATED " } else { "" };
            source_lines.push(format!(
                "{simulated}{} {}: {} rows used, {} at a standstill (not used), {} skipped (flags), {} off the path (max offset {:.2} mm)",
                log.kind.name(),
                file.display(),
                resampled.used_rows,
                resampled.standstill_rows,
                log.skipped_rows,
                resampled.off_path_rows,
                resampled.max_offset_m * 1e3
            ));
            let fixed_label = format!("{simulated}{} {}", log.kind.name(), file.display());
            match s.log_forces {
                LogForces::Fixed => run(
                    WrenchSource::Fixed {
                        label: fixed_label,
                        simulated: log.simulated,
                        wrenches: &resampled.wrenches,
                    },
                    on_progress,
                )?,
                LogForces::Law | LogForces::Auto => {
                    let label = format!("{} {}", log.kind.name(), file.display());
                    let options = LoggedProcessOptions {
                        use_measured: s.use_measured_tcp,
                        require_evidence: s.log_forces == LogForces::Auto,
                        ..LoggedProcessOptions::default()
                    };
                    let mut process =
                        LoggedProcess::new(&label, log.simulated, resampled.clone(), options)
                            .map_err(deflex_compensate::CompensateError::from)?;
                    let result = run(WrenchSource::Process(&mut process), on_progress)?;
                    let bounded = process.bounded_points();
                    let mut json = process
                        .identification()
                        .map(|id| identification_json(id, bounded, s.log_forces));
                    if let Some(id) = process.identification() {
                        source_lines.push(identification_line(id, bounded));
                        source_lines.push(decision_line(id, s.log_forces));
                    }
                    let result = if result.converged || result.failure_count() > 0 {
                        result
                    } else {
                        // The law's iteration stopped contracting: the logged wrenches (one
                        // exact pass, with the measured TCP's correction) rather than nothing.
                        let last = result.iterations.last();
                        let warning = format!(
                            "warning: the compensation with the force-depth law did not converge in {} iterations (last change {:.4} mm); the logged wrenches were used instead, as --log-forces auto does when it rejects the law",
                            result.iterations.len(),
                            last.map_or(f64::NAN, |r| r.max_change_m * 1e3)
                        );
                        source_lines.push(warning.clone());
                        if let Some(serde_json::Value::Object(map)) = json.as_mut() {
                            map.insert("decision".into(), json!("rejected"));
                            map.insert("used".into(), json!("fixed"));
                            map.insert("fallback".into(), json!(warning));
                        }
                        let mut fixed = LoggedProcess::new(
                            &format!("{label} (fallback from the force-depth law)"),
                            log.simulated,
                            resampled,
                            LoggedProcessOptions {
                                use_law: false,
                                ..options
                            },
                        )
                        .map_err(deflex_compensate::CompensateError::from)?;
                        run(WrenchSource::Process(&mut fixed), on_progress)?
                    };
                    log_law = json;
                    result
                }
            }
        }
        WrenchSpec::Array(values) => {
            let wrenches = given_wrenches(values, s.path.len())?;
            run(
                WrenchSource::Fixed {
                    label: "wrenches given from Python".into(),
                    simulated: false,
                    wrenches: &wrenches,
                },
                on_progress,
            )?
        }
    };
    Ok(CompensationRun {
        setup,
        result,
        source_lines,
        log_law,
        elapsed_s: started.elapsed().as_secs_f64(),
    })
}

/// One call of the iteration.
fn iterate(
    robot: &Robot,
    path: &TcpPath,
    seed: &[f64],
    source: WrenchSource,
    options: &CompensationOptions,
    on_progress: &mut dyn FnMut(Progress<'_>),
) -> Result<Compensation> {
    Ok(deflex_compensate::compensate(
        robot,
        path,
        seed,
        source,
        options,
        on_progress,
    )?)
}

/// One wrench for every point (6 values) or one per point.
fn given_wrenches(values: &[f64], points: usize) -> Result<Vec<Wrench>> {
    if values.len() == 6 {
        Ok(vec![Wrench::from_row_slice(values); points])
    } else if values.len() == 6 * points {
        Ok(values.chunks(6).map(Wrench::from_row_slice).collect())
    } else {
        Err(Error::invalid(
            "wrench",
            format!(
                "{} wrenches for the {points} points of the path: give one (shape (6,)) or one per point (shape ({points}, 6))",
                values.len() / 6,
            ),
        ))
    }
}

/// The law identified from a log, for the summary text.
fn identification_line(id: &Identification, bounded: usize) -> String {
    if id.sloped_bins == 0 {
        return format!(
            "the logged forces do not follow the depth ({} of {} points in contact): used as they are",
            id.contact_points, id.points
        );
    }
    format!(
        "force-depth law from the log: {} of {} points in contact over {:.2} mm of actual depth, {:.0} … {:.0} N; {}; {} point(s) at the force-ratio bound",
        id.contact_points,
        id.points,
        (id.depth_range_m[1] - id.depth_range_m[0]) * 1e3,
        id.force_range_n[0],
        id.force_range_n[1],
        if id.measured {
            format!(
                "measured TCP used (the model missed up to {:.3} mm)",
                id.max_unmodelled_m * 1e3
            )
        } else {
            "no measured TCP (depths from the model's deflection)".to_string()
        },
        bounded
    )
}

/// Why the law is or is not used, for the summary text.
fn decision_line(id: &Identification, mode: LogForces) -> String {
    let figures = id.evidence.as_ref().map_or_else(
        || "too few points in contact to test the law".to_string(),
        |e| {
            format!(
                "held-out force explained {:.0} % by the commanded depth, {:.0} % by the path position (RMS {:.0} N / {:.0} N of a {:.0} N spread), loop gain {:.2}",
                e.r2_depth.max(-9.99) * 100.0,
                e.r2_position.max(-9.99) * 100.0,
                e.rms_depth_n,
                e.rms_position_n,
                e.force_std_n,
                e.loop_gain
            )
        },
    );
    let reason = id
        .evidence
        .as_ref()
        .and_then(deflex_compensate::LawEvidence::rejection)
        .unwrap_or_else(|| "the log supports it".into());
    match (id.law_used, mode) {
        (true, LogForces::Law) if id.evidence.as_ref().is_some_and(|e| !e.supported()) => {
            format!("log law: chosen (--log-forces law), although {reason}; {figures}")
        }
        (true, _) => format!("log law: chosen: {reason}; {figures}"),
        (false, _) if id.sloped_bins == 0 => {
            format!(
                "log law: rejected: the force does not follow the depth; the logged wrenches are used; {figures}"
            )
        }
        (false, _) => format!(
            "log law: rejected: {reason}; the logged wrenches are used by path position (--log-forces fixed); {figures}"
        ),
    }
}

/// The law identified from a log, for `summary.json`: `decision` `chosen` or `rejected`,
/// `reason`, `used` (`law` or `fixed`), the evidence's figures.
fn identification_json(id: &Identification, bounded: usize, mode: LogForces) -> serde_json::Value {
    let reason = match (&id.evidence, id.sloped_bins) {
        (_, 0) => "the force does not follow the depth".to_string(),
        (None, _) => "too few points in contact to test the law".to_string(),
        (Some(e), _) => e
            .rejection()
            .unwrap_or_else(|| "the log supports it".into()),
    };
    let evidence = id.evidence.as_ref().map(|e| {
        json!({
            "blocks": e.blocks,
            "evaluated_points": e.evaluated_points,
            "r2_commanded_depth": e.r2_depth,
            "r2_path_position": e.r2_position,
            "rms_commanded_depth_N": e.rms_depth_n,
            "rms_path_position_N": e.rms_position_n,
            "force_std_N": e.force_std_n,
            "commanded_depth_span_m": e.commanded_depth_span_m,
            "compliance_along_tool_axis_m_per_N": e.compliance_m_per_n,
            "steepest_slope_N_per_m": e.steepest_slope_n_per_m,
            "loop_gain": e.loop_gain,
            "falling_share": e.falling_share,
            "supported": e.supported(),
            "thresholds": {
                "min_r2": deflex_compensate::MIN_R2,
                "margin_r2": deflex_compensate::MARGIN,
                "max_loop_gain": deflex_compensate::MAX_LOOP_GAIN,
                "max_falling_share": deflex_compensate::MAX_FALLING_SHARE,
            },
        })
    });
    json!({
        "mode": match mode {
            LogForces::Auto => "auto",
            LogForces::Law => "law",
            LogForces::Fixed => "fixed",
        },
        "decision": if id.law_used { "chosen" } else { "rejected" },
        "used": if id.law_used { "law" } else { "fixed" },
        "reason": reason,
        "evidence": evidence,
        "points": id.points,
        "contact_points": id.contact_points,
        "law_bins": id.law_bins,
        "sloped_bins": id.sloped_bins,
        "depth_range_m": id.depth_range_m,
        "force_range_N": id.force_range_n,
        "relative_slope_range_per_m": id.relative_slope_range_per_m,
        "max_axial_force_N": id.max_axial_force_n,
        "measured_tcp": id.measured,
        "max_unmodelled_deflection_m": id.max_unmodelled_m,
        "points_at_force_ratio_bound": bounded,
    })
}

//! A registration of a new session or target (`deflex register`): text and JSON (SI).

use deflex_calibrate::geometry::params::Unit;
use deflex_calibrate::geometry::register::Registration;

fn display(unit: Unit, value: f64) -> String {
    let (factor, _) = unit.display();
    format!("{:+.4}", value * factor)
}

/// The registration as text: residual, the parameters with SE and independence, warnings.
pub fn text(result: &Registration, setup: &str, target: Option<&str>) -> String {
    let mut out = format!(
        "Registered set-up `{setup}`{} from {} readings, robot frozen.\n",
        target.map_or(String::new(), |t| format!(" and target `{t}`")),
        result.readings
    );
    let p = &result.position;
    out.push_str(&format!(
        "Residual (measured − predicted): RMS {:.3} mm, p95 {:.3} mm, max {:.3} mm",
        p.rms * 1e3,
        p.p95 * 1e3,
        p.max * 1e3
    ));
    if let Some(o) = &result.orientation {
        out.push_str(&format!(
            "; orientation RMS {:.3} mrad, max {:.3} mrad",
            o.rms * 1e3,
            o.max * 1e3
        ));
    }
    out.push_str(&format!("; χ²/dof {:.1}\n", result.chi2_per_dof));
    out.push_str("  parameter            unit       value         SE   independence\n");
    for r in &result.params {
        let (_, label) = r.unit.display();
        out.push_str(&format!(
            "  {:<20} {:<6} {:>11} {:>10} {:>14.2e}\n",
            r.name,
            label,
            display(r.unit, r.value),
            display(r.unit, r.standard_error).replace('+', ""),
            r.independence
        ));
    }
    for w in &result.warnings {
        out.push_str(&format!("WARNING: {w}\n"));
    }
    out
}

/// The registration in SI; `out` is the robot file written.
pub fn json(
    result: &Registration,
    setup: &str,
    target: Option<&str>,
    out: &std::path::Path,
) -> serde_json::Value {
    let stats = |s: &deflex_calibrate::stats::ErrorNormStats| serde_json::json!({"count": s.count, "rms": s.rms, "mean": s.mean, "p95": s.p95, "max": s.max});
    serde_json::json!({
        "setup": setup,
        "target": target,
        "readings": result.readings,
        "position_m": stats(&result.position),
        "orientation_rad": result.orientation.as_ref().map(stats),
        "chi2_per_dof": result.chi2_per_dof,
        "params": result.params.iter().map(|p| serde_json::json!({
            "name": p.name, "unit": p.unit.si(), "value": p.value,
            "standard_error": p.standard_error, "independence": p.independence,
        })).collect::<Vec<_>>(),
        "warnings": result.warnings.iter().map(|w| w.to_string()).collect::<Vec<_>>(),
        "out": out.display().to_string(),
    })
}

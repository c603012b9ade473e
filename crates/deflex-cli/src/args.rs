//! Shared argument parsing: joint values, wrenches, lengths, robot loading.

use crate::error::{CliError, UsageError};
use deflex_model::Robot;

/// A numeric flag within `[lo, hi]` (NaN and infinities refused), or an error naming the flag,
/// the bounds and the value.
pub fn check_flag(
    name: &str,
    value: f64,
    lo: f64,
    hi: f64,
    unit: &'static str,
) -> Result<(), UsageError> {
    bounded(name, value, lo, hi, unit).map(|_| ())
}

/// [`check_flag`] returning the value.
pub fn bounded(
    name: &str,
    value: f64,
    lo: f64,
    hi: f64,
    unit: &'static str,
) -> Result<f64, UsageError> {
    if value >= lo && value <= hi {
        Ok(value)
    } else {
        Err(UsageError::Range {
            flag: name.to_string(),
            lo,
            hi,
            unit,
            got: value,
        })
    }
}

/// A number flag within a range (no unit), named in the error.
pub fn check_range(flag: &str, value: f64, lo: f64, hi: f64) -> Result<(), UsageError> {
    check_flag(flag, value, lo, hi, "")
}

/// Parse a comma-separated list of finite numbers; `what` names the option in errors.
pub fn parse_list(text: &str, what: &str) -> Result<Vec<f64>, UsageError> {
    text.split(',')
        .map(|item| {
            let item = item.trim();
            item.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    UsageError::invalid(
                        what,
                        "comma-separated numbers",
                        format!("\"{item}\", which is not a finite number"),
                    )
                })
        })
        .collect()
}

/// Parse a fixed number of comma-separated values.
pub fn parse_fixed<const N: usize>(text: &str, what: &str) -> Result<[f64; N], UsageError> {
    let values = parse_list(text, what)?;
    values
        .try_into()
        .map_err(|v: Vec<f64>| UsageError::invalid(what, format!("{N} values"), v.len()))
}

/// A length with an optional unit suffix (`600mm`, `0.6m`); a bare number is in millimetres.
pub fn parse_length_mm_default(text: &str, what: &str) -> Result<f64, UsageError> {
    let text = text.trim();
    let (number, scale) = if let Some(n) = text.strip_suffix("mm") {
        (n, 1e-3)
    } else if let Some(n) = text.strip_suffix('m') {
        (n, 1.0)
    } else {
        (text, 1e-3)
    };
    number
        .trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .map(|v| v * scale)
        .ok_or_else(|| {
            UsageError::invalid(what, "a length like 600mm or 0.6m", format!("\"{text}\""))
        })
}

/// Largest joint value accepted on the command line (rad): two turns either way. A revolute
/// joint beyond it is a typo (`1e300`, `-1e6` degrees), not a configuration.
pub const MAX_JOINT_RAD: f64 = 4.0 * std::f64::consts::PI;

/// Largest force (N) and moment (N·m) component accepted on the command line: far above any
/// robot's payload; `1e300` would print an infinite deflection.
pub const MAX_WRENCH: f64 = 1e7;

/// Every joint value finite and within ±[`MAX_JOINT_RAD`] (`flag` names them; `degrees`: the
/// values were given in degrees and are shown so).
pub fn check_joint_values(flag: &str, q_rad: &[f64], degrees: bool) -> Result<(), UsageError> {
    let (scale, unit) = if degrees {
        (MAX_JOINT_RAD.to_degrees(), "deg")
    } else {
        (MAX_JOINT_RAD, "rad")
    };
    for (i, q) in q_rad.iter().enumerate() {
        let shown = if degrees { q.to_degrees() } else { *q };
        bounded(
            &format!("{flag} (joint {})", i + 1),
            shown,
            -scale,
            scale,
            unit,
        )?;
    }
    Ok(())
}

/// A wrench `fx,fy,fz,mx,my,mz` (N, N·m) with every component finite and within
/// ±[`MAX_WRENCH`].
pub fn parse_wrench(text: &str, flag: &str) -> Result<[f64; 6], UsageError> {
    let w = parse_fixed::<6>(text, flag)?;
    for (i, v) in w.iter().enumerate() {
        let unit = if i < 3 { "N" } else { "N·m" };
        let name = ["fx", "fy", "fz", "mx", "my", "mz"][i];
        bounded(
            &format!("{flag} ({name})"),
            *v,
            -MAX_WRENCH,
            MAX_WRENCH,
            unit,
        )?;
    }
    Ok(w)
}

/// Joint values from `--q-deg` or `--q-rad`, checked against the robot's joint count.
pub fn joint_values(
    robot: &Robot,
    q_deg: Option<&str>,
    q_rad: Option<&str>,
) -> Result<Vec<f64>, UsageError> {
    let q = match (q_deg, q_rad) {
        (Some(d), None) => parse_list(d, "--q-deg")?
            .into_iter()
            .map(f64::to_radians)
            .collect(),
        (None, Some(r)) => parse_list(r, "--q-rad")?,
        (Some(_), Some(_)) => {
            return Err(UsageError::NotBoth {
                first: "--q-deg",
                second: "--q-rad",
            });
        }
        (None, None) => {
            return Err(UsageError::Missing {
                what: "joint values needed",
                give: "--q-deg a,b,c,... or --q-rad a,b,c,...",
            });
        }
    };
    if q.len() != robot.joint_count() {
        return Err(UsageError::JointCount {
            robot: robot.name.clone(),
            joints: robot.joint_count(),
            given: q.len(),
        });
    }
    match (q_deg, q_rad) {
        (Some(_), _) => check_joint_values("--q-deg", &q, true)?,
        _ => check_joint_values("--q-rad", &q, false)?,
    }
    Ok(q)
}

/// Load a robot by built-in name or file path.
pub fn robot(spec: &str) -> Result<Robot, CliError> {
    Ok(deflex_app::robot::load(spec)?)
}

/// Print a JSON value, pretty, to stdout (the `--json` output of every command): a `Value`'s
/// alternate form, the text of `serde_json::to_string_pretty`, which cannot fail for a `Value`.
pub fn print_json(value: &serde_json::Value) {
    println!("{value:#}");
}

/// Print `text()`, or `value()` as JSON with `--json` (`json`): the two forms of a command's
/// report.
pub fn print_report(
    json: bool,
    text: impl FnOnce() -> String,
    value: impl FnOnce() -> serde_json::Value,
) {
    if json {
        print_json(&value());
    } else {
        print!("{}", text());
    }
}

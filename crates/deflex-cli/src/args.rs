//! Shared argument parsing: joint values, wrenches, lengths, robot loading.

use deflex_model::{Robot, load_robot};

/// Result type of every command: errors are user-facing messages.
pub type CliResult = Result<(), String>;

/// A numeric flag within `[lo, hi]` (NaN and infinities refused), or an error naming the flag,
/// the bounds and the value.
pub fn check_flag(name: &str, value: f64, lo: f64, hi: f64, unit: &str) -> Result<(), String> {
    bounded(name, value, lo, hi, unit).map(|_| ())
}

/// [`check_flag`] returning the value.
pub fn bounded(name: &str, value: f64, lo: f64, hi: f64, unit: &str) -> Result<f64, String> {
    if value >= lo && value <= hi {
        Ok(value)
    } else {
        let unit = if unit.is_empty() {
            String::new()
        } else {
            format!(" {unit}")
        };
        Err(format!(
            "{name}: expected a number from {} to {}{unit}, got {}",
            compact(lo),
            compact(hi),
            compact(value)
        ))
    }
}

/// A number for a message: plain when readable, in exponent form when very large or small
/// (`1e308`, not three hundred digits).
pub fn compact(value: f64) -> String {
    let magnitude = value.abs();
    if value.is_finite() && value != 0.0 && !(1e-3..1e6).contains(&magnitude) {
        format!("{value:e}")
    } else {
        format!("{value}")
    }
}

/// Parse a comma-separated list of finite numbers; `what` names the option in errors.
pub fn parse_list(text: &str, what: &str) -> Result<Vec<f64>, String> {
    text.split(',')
        .map(|item| {
            let item = item.trim();
            item.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("{what}: expected comma-separated numbers, \"{item}\" is not a finite number"))
        })
        .collect()
}

/// Parse a fixed number of comma-separated values.
pub fn parse_fixed<const N: usize>(text: &str, what: &str) -> Result<[f64; N], String> {
    let values = parse_list(text, what)?;
    values
        .try_into()
        .map_err(|v: Vec<f64>| format!("{what}: expected {N} values, got {}", v.len()))
}

/// A length with an optional unit suffix (`600mm`, `0.6m`); a bare number is in millimetres.
pub fn parse_length_mm_default(text: &str, what: &str) -> Result<f64, String> {
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
        .ok_or_else(|| format!("{what}: expected a length like 600mm or 0.6m, got \"{text}\""))
}

/// Joint values from `--q-deg` or `--q-rad`, checked against the robot's joint count.
pub fn joint_values(
    robot: &Robot,
    q_deg: Option<&str>,
    q_rad: Option<&str>,
) -> Result<Vec<f64>, String> {
    let q = match (q_deg, q_rad) {
        (Some(d), None) => parse_list(d, "--q-deg")?
            .into_iter()
            .map(f64::to_radians)
            .collect(),
        (None, Some(r)) => parse_list(r, "--q-rad")?,
        (Some(_), Some(_)) => return Err("give either --q-deg or --q-rad, not both".into()),
        (None, None) => {
            return Err("joint values needed: --q-deg a,b,c,... or --q-rad a,b,c,...".into());
        }
    };
    if q.len() != robot.joint_count() {
        return Err(format!(
            "robot \"{}\" has {} joints, but {} joint values were given",
            robot.name,
            robot.joint_count(),
            q.len()
        ));
    }
    Ok(q)
}

/// Load a robot by built-in name or file path.
pub fn robot(spec: &str) -> Result<Robot, String> {
    load_robot(spec).map_err(|e| e.to_string())
}

/// Print a JSON value, pretty, to stdout (the `--json` output of every command).
pub fn print_json(value: &serde_json::Value) {
    println!(
        "{}",
        serde_json::to_string_pretty(value).unwrap_or_default()
    );
}

/// Format a float with a fixed number of decimals for tables.
pub fn fixed(value: f64, decimals: usize) -> String {
    format!("{value:.decimals$}")
}

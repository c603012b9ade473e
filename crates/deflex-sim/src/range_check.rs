//! Range checks of settings: finite, within bounds, the field named in the error.

use crate::error::SimError;

/// `value` finite and within `[lo, hi]`, else an error naming `field` and the range.
pub(crate) fn bounded(
    field: &str,
    value: f64,
    lo: f64,
    hi: f64,
    unit: &str,
) -> Result<(), SimError> {
    if value.is_finite() && value >= lo && value <= hi {
        Ok(())
    } else {
        Err(SimError::config(
            field,
            format!("must be a finite number within {lo}..{hi} {unit}, got {value}"),
        ))
    }
}

/// `value` finite, > 0 and ≤ `hi`.
pub(crate) fn bounded_open(field: &str, value: f64, hi: f64, unit: &str) -> Result<(), SimError> {
    if value.is_finite() && value > 0.0 && value <= hi {
        Ok(())
    } else {
        Err(SimError::config(
            field,
            format!("must be a finite number within (0, {hi}] {unit}, got {value}"),
        ))
    }
}

/// Every entry finite with `|v| ≤ limit`; the message names the entry.
pub(crate) fn all_bounded(
    field: &str,
    values: &[f64],
    limit: f64,
    unit: &str,
) -> Result<(), SimError> {
    for (i, v) in values.iter().enumerate() {
        bounded(&format!("{field}[{i}]"), *v, -limit, limit, unit)?;
    }
    Ok(())
}

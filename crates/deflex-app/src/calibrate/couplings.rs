//! Off-diagonal joint compliances fitted once the structure is identified, together with the
//! eDoF compliances ([`deflex_calibrate::stiffness::fit_couplings`]; `deflex calibrate
//! --couplings J2.z:J3.z`), reported with their standard errors and correlations and written
//! into the calibrated robot file as `[[coupling]]`.
//!
//! Only the CLI asks for couplings: the messages name its `--couplings`.

use crate::error::{Error, Result};
use crate::report::calibration_tables::{
    COUPLING_HEADERS, REFIT_HEADERS, coupling_rows, coupling_summary, refit_rows,
};
use crate::report::text_table::render_table;
use deflex_calibrate::measurements::MeasurementRow;
pub use deflex_calibrate::stiffness::EdofPair;
use deflex_calibrate::stiffness::{CouplingFit, fit_couplings};
use deflex_model::{Axis, EdofSite, Robot};
pub use deflex_model::{MAX_COUPLINGS, parse_edof_label};
use serde_json::{Value, json};

/// One coupling asked for: the pair as the user wrote it and as parsed.
#[derive(Clone, Debug, PartialEq)]
pub struct CouplingRequest {
    /// The text of the pair (`J2.z:J3.z`), for messages.
    pub text: String,
    /// The two eDoFs.
    pub pair: EdofPair,
}

fn label((site, axis): (EdofSite, Axis)) -> String {
    format!("{site}.{}", axis.letter())
}

/// Fit the requested couplings on the calibrated (diagonal) `model`: each end must be an eDoF of
/// the identified structure (`structure`, its label), else the error names the pair and the
/// structure.
pub fn fit(
    model: &Robot,
    structure: &str,
    rows: &[MeasurementRow],
    requested: &[CouplingRequest],
) -> Result<CouplingFit> {
    for r in requested {
        for end in [r.pair.0, r.pair.1] {
            if model.stiffness(end.0, end.1).is_none() {
                return Err(Error::CouplingNotInStructure {
                    pair: r.text.clone(),
                    edof: label(end),
                    structure: structure.to_string(),
                });
            }
        }
    }
    let pairs: Vec<EdofPair> = requested.iter().map(|r| r.pair).collect();
    fit_couplings(model, rows, &pairs).map_err(|e| Error::in_context("--couplings")(e.into()))
}

/// The couplings and the refitted stiffnesses, as printed.
pub fn text(diagonal: &Robot, fit: &CouplingFit) -> String {
    let mut out = String::from("\nJoint-compliance couplings (written into the output model), ");
    out.push_str(&coupling_summary(fit));
    out.push_str(&render_table(&COUPLING_HEADERS, &coupling_rows(fit)));
    for (k, c) in fit.robot.couplings.iter().enumerate() {
        let (lo, hi) = fit.interval95(k);
        if lo <= 0.0 && hi >= 0.0 {
            out.push_str(&format!(
                "note: {}'s 95 % interval contains zero: these readings do not resolve this \
                 coupling (it is written as fitted; leave it out, or plan load cases that \
                 load both joints)\n",
                c.label()
            ));
        }
    }
    out.push_str("The output model's stiffnesses, refitted with the couplings:\n");
    out.push_str(&render_table(&REFIT_HEADERS, &refit_rows(diagonal, fit)));
    out
}

fn number(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}

/// `couplings` and `coupling_fit` of the JSON output.
pub fn json(fit: &CouplingFit) -> (Value, Value) {
    let couplings: Vec<Value> = fit
        .robot
        .couplings
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let (lo, hi) = fit.interval95(k);
            json!({
                "coupling": c.label(),
                "a": label(c.a),
                "b": label(c.b),
                "compliance_rad_per_Nm": c.compliance,
                "compliance_se": number(fit.coupling_se[k]),
                "interval95": [number(lo), number(hi)],
                "correlation": fit.correlations[k],
                "correlation_se": number(fit.correlation_se[k]),
            })
        })
        .collect();
    let edofs: Vec<Value> = fit
        .robot
        .edofs()
        .zip(&fit.compliance_se)
        .map(|(e, se)| {
            json!({
                "edof": e.label(),
                "stiffness_Nm_per_rad": e.stiffness,
                "compliance": 1.0 / e.stiffness,
                "compliance_se": number(*se),
            })
        })
        .collect();
    let summary = json!({
        "equations": fit.equations,
        "unknowns": fit.unknowns,
        "reduced_chi2_before": fit.reduced_chi2_before,
        "reduced_chi2": fit.reduced_chi2,
        "residual_rms_before_m": fit.rms_before_m,
        "residual_rms_m": fit.rms_m,
        "edofs": edofs,
    });
    (json!(couplings), summary)
}

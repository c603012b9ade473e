//! `deflex calibrate --couplings J2.z:J3.z[,A:B…]`: the pairs parsed (the fit, its text and JSON
//! are `deflex_app::calibrate::couplings`').

use crate::error::UsageError;
use deflex_app::calibrate::CouplingRequest;
use deflex_app::calibrate::couplings::{MAX_COUPLINGS, parse_edof_label};

const EXPECTED: &str = "pairs of eDoFs such as J2.z:J3.z, separated by commas (at most 8)";

/// Parse `--couplings`: `A:B[,A:B…]`, each end an eDoF label (`J2.z`, `base.x`), the two ends
/// different, no pair twice, at most [`MAX_COUPLINGS`].
pub fn parse(text: &str) -> Result<Vec<CouplingRequest>, UsageError> {
    let invalid = || UsageError::invalid("--couplings", EXPECTED, text);
    let mut out: Vec<CouplingRequest> = Vec::new();
    for item in text.split(',') {
        let item = item.trim();
        let (a, b) = item.split_once(':').ok_or_else(invalid)?;
        let end = |label: &str| {
            parse_edof_label(label).ok_or_else(|| {
                UsageError::invalid(
                    "--couplings",
                    format!("an eDoF label such as J2.z or base.x in {item}"),
                    label.trim(),
                )
            })
        };
        let pair = (end(a)?, end(b)?);
        if pair.0 == pair.1 {
            return Err(UsageError::invalid(
                "--couplings",
                "two different eDoFs in a pair",
                item,
            ));
        }
        if out
            .iter()
            .any(|r| r.pair == pair || r.pair == (pair.1, pair.0))
        {
            return Err(UsageError::invalid("--couplings", "each pair once", item));
        }
        out.push(CouplingRequest {
            text: item.to_string(),
            pair,
        });
    }
    if out.len() > MAX_COUPLINGS {
        return Err(invalid());
    }
    Ok(out)
}

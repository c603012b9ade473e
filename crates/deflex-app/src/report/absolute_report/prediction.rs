//! A prediction of absolute readings (`deflex predict`): the per-row CSV, the summary line and
//! its JSON (SI).

use deflex_calibrate::geometry::predict::Prediction;

fn mm(v: f64) -> String {
    format!("{:.3}", v * 1e3)
}

/// The prediction CSV: `line, setup, target, q…, predicted_x_m…, x_m…, error_m` and, when predicted, the
/// orientation columns. (An error only if a row had another number of fields than the header.)
pub fn prediction_csv(prediction: &Prediction) -> std::io::Result<String> {
    let n = prediction.rows.first().map_or(0, |r| r.row.q_rad.len());
    let with_rotation = prediction
        .rows
        .iter()
        .any(|r| r.predicted_rotation_rad.is_some());
    let mut header: Vec<String> = vec!["line".into(), "setup".into(), "target".into()];
    header.extend((1..=n).map(|i| format!("q{i}_rad")));
    header.extend(
        [
            "predicted_x_m",
            "predicted_y_m",
            "predicted_z_m",
            "x_m",
            "y_m",
            "z_m",
            "error_m",
        ]
        .map(String::from),
    );
    if with_rotation {
        header.extend(
            [
                "predicted_rx_rad",
                "predicted_ry_rad",
                "predicted_rz_rad",
                "orientation_error_rad",
            ]
            .map(String::from),
        );
    }
    let mut records = vec![header];
    for r in &prediction.rows {
        let mut record = vec![
            r.row.line.to_string(),
            r.row.setup.clone(),
            r.row.target.clone(),
        ];
        record.extend(r.row.q_rad.iter().map(|v| format!("{v:?}")));
        record.extend(r.predicted_m.iter().map(|v| format!("{v:?}")));
        record.extend(r.row.position_m.iter().map(|v| format!("{v:?}")));
        record.push(format!("{:e}", r.error_m));
        if with_rotation {
            match r.predicted_rotation_rad {
                Some(v) => record.extend(v.iter().map(|x| format!("{x:?}"))),
                None => record.extend([String::new(), String::new(), String::new()]),
            }
            record.push(
                r.orientation_error_rad
                    .map_or(String::new(), |e| format!("{e:e}")),
            );
        }
        records.push(record);
    }
    super::tables::csv_records(records.iter().map(Vec::as_slice))
}

/// The summary: error statistics of the rows (and orientations), mm and mrad.
pub fn prediction_text(prediction: &Prediction) -> String {
    let s = &prediction.position;
    let mut text = format!(
        "{} rows predicted{}; error norm (measured − predicted): RMS {} mm, mean {} mm, p95 {} mm, max {} mm\n",
        s.count,
        if prediction.fit_setup {
            " (set-up registration fitted on these rows)"
        } else {
            ""
        },
        mm(s.rms),
        mm(s.mean),
        mm(s.p95),
        mm(s.max)
    );
    if let Some(o) = &prediction.orientation {
        text.push_str(&format!(
            "orientation error: RMS {:.3} mrad, p95 {:.3} mrad, max {:.3} mrad\n",
            o.rms * 1e3,
            o.p95 * 1e3,
            o.max * 1e3
        ));
    }
    text
}

/// The summary in SI with the set-ups used (`xyz_m`, `rpy_rad`).
pub fn prediction_json(prediction: &Prediction) -> serde_json::Value {
    let s = &prediction.position;
    serde_json::json!({
        "rows": s.count, "fit_setup": prediction.fit_setup,
        "rms_m": s.rms, "mean_m": s.mean, "p95_m": s.p95, "max_m": s.max,
        "orientation_rms_rad": prediction.orientation.map(|o| o.rms),
        "orientation_p95_rad": prediction.orientation.map(|o| o.p95),
        "setups": prediction.setups.iter().map(|s| serde_json::json!({"name": s.name, "xyz_m": [s.pose.translation.vector.x, s.pose.translation.vector.y, s.pose.translation.vector.z], "rpy_rad": deflex_model::spatial::rpy_from_rotation(&s.pose.rotation)})).collect::<Vec<_>>(),
    })
}

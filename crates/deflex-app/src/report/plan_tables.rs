//! An experiment plan as tables: the expected standard errors of the stiffnesses and centre
//! shifts, and the technician's sheet.

use deflex_calibrate::stiffness::plan::Plan;

fn k_fmt(k: f64) -> String {
    if k.is_infinite() {
        "∞".into()
    } else {
        format!("{:.4e}", k)
    }
}

/// Expected standard errors of a plan.
pub fn expected_se_rows(plan: &Plan) -> Vec<Vec<String>> {
    plan.expected
        .iter()
        .map(|e| {
            let axis = plan
                .axis_cases
                .iter()
                .find(|a| a.id == e.id && e.identifiable())
                .map(|a| {
                    format!(
                        "{} ({:.0} % share, {:.0} σ)",
                        a.load_case,
                        100.0 * a.share,
                        a.snr
                    )
                })
                .unwrap_or_else(|| {
                    if e.identifiable() {
                        "none (seen jointly by the other cases)".into()
                    } else {
                        "-".into()
                    }
                });
            vec![
                e.label.clone(),
                k_fmt(e.nominal_k),
                k_fmt(e.se_k),
                if e.relative.is_finite() {
                    format!("{:.2}", 100.0 * e.relative)
                } else {
                    "not identifiable".into()
                },
                axis,
            ]
        })
        .collect()
}

/// The technician's sheet: one line per load case with the joint values in degrees (wrapped
/// into the limits by the planner), where and how the load acts, the force vector (world
/// axes), the points to measure and why the case is there (the eDoFs whose axis-by-axis case
/// it is, the same as in [`expected_se_rows`]).
pub fn technician_rows(plan: &Plan) -> Vec<Vec<String>> {
    let mut out: Vec<Vec<String>> = Vec::new();
    for row in &plan.rows {
        match out.last_mut() {
            Some(last) if last[0] == row.load_case => {
                last[4] = format!("{}, {}", last[4], row.point);
            }
            _ => {
                let q: Vec<String> = row
                    .q_rad
                    .iter()
                    .map(|q| format!("{:.1}", q.to_degrees()))
                    .collect();
                let f = row.wrench;
                let purpose = row.purpose.clone().unwrap_or_default();
                let (why, how) = match purpose.split_once("; ") {
                    Some((why, how)) => (why.to_string(), how.to_string()),
                    None => (purpose, String::new()),
                };
                let at = if how.ends_with("at the bracket") {
                    "BR"
                } else {
                    "TCP"
                };
                out.push(vec![
                    row.load_case.clone(),
                    q.join(", "),
                    format!("{} at {at}", how.trim_end_matches(" at the bracket")),
                    format!("({:.0}, {:.0}, {:.0})", f[0], f[1], f[2]),
                    row.point.clone(),
                    why,
                ]);
            }
        }
    }
    out
}

/// Headers of [`technician_rows`].
pub const TECHNICIAN_HEADERS: [&str; 6] =
    ["case", "q [deg]", "load", "force [N]", "measure", "why"];

/// Headers of [`expected_se_rows`].
pub const EXPECTED_SE_HEADERS: [&str; 5] = [
    "eDoF",
    "nominal k [N·m/rad]",
    "expected SE [N·m/rad]",
    "expected SE [%]",
    "axis-by-axis case",
];

/// Expected centre-shift precision of a plan as table rows (mm).
pub fn expected_shift_rows(plan: &Plan) -> Vec<Vec<String>> {
    plan.expected_shifts
        .iter()
        .map(|e| {
            vec![
                format!("δr{}", e.joint),
                format!("{:.1}", e.nominal_m * 1e3),
                if e.se_m.is_finite() {
                    format!("{:.2}", e.se_m * 1e3)
                } else {
                    "not identifiable".into()
                },
            ]
        })
        .collect()
}

/// Headers of [`expected_shift_rows`].
pub const EXPECTED_SHIFT_HEADERS: [&str; 3] = ["centre shift", "nominal [mm]", "expected SE [mm]"];

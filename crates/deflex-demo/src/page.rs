//! The report page (`index.html`): self-contained (figures embedded), every simulated quantity
//! labelled, the paper's numbers beside ours.

use crate::figures::Figure;
use crate::study::DemoSummary;
use crate::tables::paper_vs_deflex;
use deflex_calib::SearchResult;
use deflex_calib::plan::Plan;
use deflex_report::HtmlReport;
use std::path::Path;

/// What the page shows.
pub(crate) struct Page<'a> {
    pub summary: &'a DemoSummary,
    pub search: &'a SearchResult,
    pub plan: &'a Plan,
    pub grid_files: Vec<Figure>,
    pub spiral_files: Vec<Figure>,
    pub forming_files: Vec<Figure>,
}

fn fmt_k(v: Option<f64>, is_shift: bool) -> String {
    match v {
        None => "–".into(),
        Some(v) if v.is_infinite() => "∞".into(),
        Some(v) if is_shift => format!("{:.1} mm", v * 1e3),
        Some(v) => format!("{:.3}", v / 1e6),
    }
}

/// Write `index.html` into `out`.
pub(crate) fn write(out: &Path, page: &Page) -> Result<(), String> {
    let s = page.summary;
    let mut html = HtmlReport::new("deflex — the paper's study on the simulated TX200 cell");
    html.note(
        "SIMULATED: every deflex number on this page was measured on the built-in digital twin of \
         the paper's ISF cell (deflex-sim), not on a real robot. The paper's numbers are from \
         Johra et al., Robotics 2022, 11, 48.",
    );
    html.paragraph(format!(
        "Seed {}{}. Reproduce with: deflex demo --seed {}{}. Data behind every number: the CSV \
         files beside this page.",
        s.seed,
        if s.quick {
            ", shortened study (--quick)"
        } else {
            ""
        },
        s.seed,
        if s.quick { " --quick" } else { "" }
    ));

    html.section("Paper vs deflex");
    let rows: Vec<Vec<String>> = paper_vs_deflex(s)
        .into_iter()
        .map(|(q, paper, ours, unit)| {
            vec![
                q,
                format!("{paper}"),
                format!("{ours:.3}"),
                unit.to_string(),
            ]
        })
        .collect();
    html.table(
        &[
            "quantity",
            "paper (real TX200)",
            "deflex (SIMULATED cell)",
            "unit",
        ],
        &rows,
    );

    html.section("1. Calibration campaign plan");
    html.paragraph(format!(
        "{} load cases ({} measured points: the TCP, points on links 2 and 3 and a reflector on the \
         base casting, like the paper's M1–M3), chosen axis by axis and then D-optimally from random reachable poses and load \
         directions, loads up to 1400 N. Expected standard error of each stiffness at 15 µm tracker noise:",
        s.campaign_load_cases, s.campaign_rows
    ));
    html.table(
        &deflex_calib::report::EXPECTED_SE_HEADERS,
        &deflex_calib::report::expected_se_rows(page.plan),
    );
    if !page.plan.expected_shifts.is_empty() {
        html.table(
            &deflex_calib::report::EXPECTED_SHIFT_HEADERS,
            &deflex_calib::report::expected_shift_rows(page.plan),
        );
    }

    html.section("2–3. Identification (structure search, Section 3)");
    html.paragraph(format!(
        "Start: one z-eDoF per joint (the paper's start). Each step tries every refinement (an x/y \
         eDoF on any joint, a base tilt eDoF, a free centre shift) and keeps the one that lowers \
         BIC most. The last column is the cross-validated RMS: each of 5 folds of load cases \
         predicted by the model fitted on the other four. Stopped: {}. Result: {} (RMS residual \
         {:.1} µm, χ²/dof {:.2}).",
        s.search_stop_reason,
        s.identified_structure,
        s.identification_rms_um,
        s.identification_reduced_chi2
    ));
    html.table(
        &deflex_calib::report::ITERATION_HEADERS,
        &deflex_calib::report::iteration_rows(&page.search.steps),
    );
    let stiffness: Vec<Vec<String>> = s
        .stiffness
        .iter()
        .map(|r| {
            let shift = r.name.starts_with('δ');
            vec![
                r.name.clone(),
                fmt_k(r.identified, shift),
                fmt_k(r.se, shift),
                r.interval95
                    .map(|(lo, hi)| {
                        format!("[{}, {}]", fmt_k(Some(lo), shift), fmt_k(Some(hi), shift))
                    })
                    .unwrap_or_else(|| "–".into()),
                r.status.clone(),
                fmt_k(r.table1, shift),
                fmt_k(r.plant, shift),
            ]
        })
        .collect();
    html.paragraph(
        "Stiffnesses in 10⁶ N·m/rad (shifts in mm). \"Twin plant\" is the simulated robot's \
         hidden linear truth, shown only to judge the identification. The 95 % intervals account \
         for measurement noise, not for model-form error: the twin also has a J2/J3 coupling and \
         wrist lost motion that no VJM model represents, and a base tilt that TCP-side data \
         cannot separate from J1.x/y, so some identified values lie outside their interval \
         around the plant value while the model still predicts well (validation below).",
    );
    html.table(
        &[
            "eDoF",
            "identified",
            "SE",
            "95 % interval",
            "status",
            "paper Table 1",
            "twin plant (SIMULATED truth)",
        ],
        &stiffness,
    );

    html.section("4. Validation on the paper's grid and spiral (Section 3.2)");
    html.paragraph(
        "200 TCP poses on a 0.6 × 0.6 m grid at z = 0.1 m, tool down, 600 N and 1100 N dead \
         weights, measured by the simulated laser tracker (noise 10 µm + 5 µm/m). Errors are \
         measured − predicted, in mm. The one-eDoF model is calibrated on the same campaign; \
         \"paper Table 1\" is the paper's published model used as is.",
    );
    let validation: Vec<Vec<String>> = s
        .validation
        .iter()
        .map(|v| {
            vec![
                v.data.clone(),
                v.model.clone(),
                v.points.to_string(),
                format!("{:.3}", v.rms_z_mm),
                format!("{:.3}", v.max_z_mm),
                format!("{:.3}", v.rms_norm_mm),
                format!("{:.3}", v.max_norm_mm),
                format!("{:.3}", v.measured_rms_z_mm),
            ]
        })
        .collect();
    html.table(
        &[
            "data (SIMULATED)",
            "model",
            "points",
            "RMS δz err",
            "max |δz err|",
            "RMS |err|",
            "max |err|",
            "RMS measured δz",
        ],
        &validation,
    );
    for (path, caption) in page.grid_files.iter().chain(&page.spiral_files) {
        html.image(path, caption.clone());
    }

    html.section("5. Forming the paper's cone (Section 4)");
    let f = [
        (&s.forming_open, "without correction"),
        (&s.forming_closed, "with correction"),
    ];
    let forming: Vec<Vec<String>> = f
        .iter()
        .map(|(n, label)| {
            vec![
                label.to_string(),
                format!("{:.3}", n.max_error_norm_mm),
                format!("{:.3}", n.rms_error_norm_mm),
                format!("{:.0}", n.max_fz_N),
                format!("{:.0}", n.max_fxy_N),
                format!("{:.2} / {:.2}", n.final_part_depth_mm, n.target_depth_mm),
            ]
        })
        .collect();
    html.table(
        &[
            "run (SIMULATED)",
            "max |error| [mm]",
            "RMS |error| [mm]",
            "max Fz [N]",
            "max in-plane F [N]",
            "part depth / programmed [mm]",
        ],
        &forming,
    );
    html.paragraph(format!(
        "Improvement of the maximum error norm: {:.1} % (paper: 70 %). Controller: {}.",
        s.improvement_percent, s.controller_status
    ));
    for (path, caption) in &page.forming_files {
        html.image(path, caption.clone());
    }

    html.section("Run");
    let timings: Vec<Vec<String>> = s
        .stage_seconds
        .iter()
        .map(|(stage, seconds)| vec![stage.clone(), format!("{seconds:.2}")])
        .collect();
    html.table(&["stage", "wall time [s]"], &timings);
    html.write(&out.join("index.html"))
        .map_err(|e| e.to_string())
}

//! The numbers the study measured (`summary.json`): validation errors, stiffnesses beside the
//! paper's and the plant's, forming runs, stiff contact, sensitivity and compensation.

use deflex_sim::FormingRun;
use serde::Serialize;

/// Prediction error of one model on one data set (δz as in the paper's Figs. 10–13, and the
/// norm), mm.
#[derive(Clone, Debug, Default, Serialize)]
pub struct ModelErrorNumbers {
    /// Model name.
    pub model: String,
    /// Data set (`grid 600 N`, `grid 1100 N`, `spiral 600 N`).
    pub data: String,
    /// Points.
    pub points: usize,
    /// RMS of the δz error (mm).
    pub rms_z_mm: f64,
    /// Largest |δz error| (mm).
    pub max_z_mm: f64,
    /// RMS of the 3D error norm (mm).
    pub rms_norm_mm: f64,
    /// Largest 3D error norm (mm).
    pub max_norm_mm: f64,
    /// RMS of the measured δz, for scale (mm).
    pub measured_rms_z_mm: f64,
}

/// One identified stiffness beside the paper's Table 1 and the twin's (simulated) truth.
#[derive(Clone, Debug, Serialize)]
pub struct StiffnessRow {
    /// eDoF label (`J3.x`) or shift (`δr3`).
    pub name: String,
    /// Identified value (N·m/rad, or m for a shift).
    pub identified: Option<f64>,
    /// Standard error.
    pub se: Option<f64>,
    /// 95 % interval.
    pub interval95: Option<(f64, f64)>,
    /// Status from the calibration.
    pub status: String,
    /// The paper's Table 1 value.
    pub table1: Option<f64>,
    /// The twin plant's linear value (SIMULATED ground truth).
    pub plant: Option<f64>,
}

/// Numbers of one forming run.
#[derive(Clone, Debug, Default, Serialize)]
#[allow(non_snake_case)]
pub struct FormingNumbers {
    /// Largest TCP error norm (mm).
    pub max_error_norm_mm: f64,
    /// RMS TCP error norm (mm).
    pub rms_error_norm_mm: f64,
    /// Largest vertical force (N).
    pub max_fz_N: f64,
    /// Largest in-plane force (N).
    pub max_fxy_N: f64,
    /// Largest force norm (N).
    pub max_force_norm_N: f64,
    /// Deepest formed point (mm).
    pub final_part_depth_mm: f64,
    /// Programmed depth (mm).
    pub target_depth_mm: f64,
    /// Simulated duration (s).
    pub duration_s: f64,
}

impl FormingNumbers {
    /// The numbers of a run's summary.
    pub fn from_run(run: &FormingRun) -> Self {
        let s = &run.summary;
        FormingNumbers {
            max_error_norm_mm: s.max_error_norm_mm,
            rms_error_norm_mm: s.rms_error_norm_mm,
            max_fz_N: s.max_fz_N,
            max_fxy_N: s.max_fxy_N,
            max_force_norm_N: s.max_force_norm_N,
            final_part_depth_mm: s.final_part_depth_mm,
            target_depth_mm: s.target_depth_mm,
            duration_s: s.duration_s,
        }
    }
}

/// Everything the study measured (`summary.json`).
#[derive(Clone, Debug, Serialize)]
pub struct DemoSummary {
    /// Always true: the cell is the digital twin.
    pub simulated: bool,
    /// The robot the twin played (its description's name) and the spec it was given as.
    pub robot: String,
    /// The robot spec (`tx200`, `ur10e`, a file).
    pub robot_spec: String,
    /// The paper's comparisons apply (the TX200 cell).
    pub paper_comparison: bool,
    /// The error sources and effects of the twin, with their levels and whether they were on:
    /// `(source, level, on)`.
    pub conditions: Vec<(String, String, bool)>,
    /// Seed.
    pub seed: u64,
    /// Shortened study.
    pub quick: bool,
    /// Load cases and measured points of the campaign.
    pub campaign_load_cases: usize,
    /// Rows of the campaign file.
    pub campaign_rows: usize,
    /// Identified structure label.
    pub identified_structure: String,
    /// Search iterations accepted.
    pub search_steps: usize,
    /// Why the search stopped.
    pub search_stop_reason: String,
    /// RMS residual of the identification (µm, all components).
    pub identification_rms_um: f64,
    /// χ²/dof of the identification.
    pub identification_reduced_chi2: f64,
    /// Identified stiffnesses and shifts beside Table 1 and the plant.
    pub stiffness: Vec<StiffnessRow>,
    /// Validation errors (grid and spiral, every model).
    pub validation: Vec<ModelErrorNumbers>,
    /// The paper's Figs. 8–9 test (Fig. 7 configuration, lateral 1400 N): per point the
    /// SIMULATED measurement and each model's prediction. Empty for robots other than the TX200.
    pub fig7: Vec<crate::study::fig7::Fig7Point>,
    /// Forming without correction.
    pub forming_open: FormingNumbers,
    /// Forming with correction.
    pub forming_closed: FormingNumbers,
    /// `100 (1 − closed/open)` of the maximum error norm.
    pub improvement_percent: f64,
    /// Status line of the controller at the end of the corrected run.
    pub controller_status: String,
    /// The plunge into a stiff fixture (10⁷ N/m) without correction, with it unguarded and with
    /// the runaway guard.
    pub stiff_contact: crate::study::contact::StiffContactNumbers,
    /// The same plunge across fixture stiffnesses 10⁵–10⁸ N/m.
    pub stiff_contact_sweep: Vec<crate::study::contact::StiffContactNumbers>,
    /// The sensitivity study, when run.
    pub sensitivity: Option<crate::study::sensitivity::SensitivityResult>,
    /// Offline compensation, online correction and both, on the cone and a CAM part.
    pub compensation: crate::study::compensation::CompensationStudy,
    /// Wall time of each stage (s).
    pub stage_seconds: Vec<(String, f64)>,
}

impl DemoSummary {
    /// The validation numbers of one model on one data set.
    pub fn errors(&self, model: &str, data: &str) -> Option<&ModelErrorNumbers> {
        self.validation
            .iter()
            .find(|v| v.model == model && v.data == data)
    }
}

/// Model names used in the report.
pub const IDENTIFIED: &str = "identified (deflex)";
/// See [`IDENTIFIED`].
pub const BASELINE: &str = "one eDoF per joint";
/// See [`IDENTIFIED`].
pub const TABLE1: &str = "paper Table 1";

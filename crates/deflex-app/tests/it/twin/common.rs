//! Shared set-up: the model identified from the twin's own calibration campaign (seed 11), made
//! once for the whole test binary; a careful loaded campaign on a twin and its structure search.

use deflex_calibrate::measurements::MeasurementRow;
use deflex_calibrate::stiffness::plan::{PlanOptions, plan_experiments};
use deflex_calibrate::stiffness::search::{SearchOptions, SearchResult, search_structure};
use deflex_model::Robot;
use deflex_sim::CellConfig;
use std::sync::OnceLock;

/// The TX200 model identified from the default cell's campaign (never the plant).
pub fn calibrated_model() -> Robot {
    static MODEL: OnceLock<Robot> = OnceLock::new();
    MODEL
        .get_or_init(|| {
            deflex_app::twin::identify_from_twin_campaign(&CellConfig::default(), 11)
                .expect("identification from the twin's campaign")
        })
        .clone()
}

/// A careful static campaign on the twin of `cell`, planned for `nominal` (40 load cases, every
/// eDoF family; seed 1), each tracker reading the mean of 25 samples (0.5 s at 50 Hz, so the
/// white part of the tracker noise drops below the unmodelled effects), and the model structure
/// searched from it: the measurements and the search.
pub fn careful_campaign(nominal: &Robot, cell: &CellConfig) -> (Vec<MeasurementRow>, SearchResult) {
    let plan = plan_experiments(
        nominal,
        &PlanOptions {
            load_cases: 40,
            full_family: true,
            ..PlanOptions::default()
        },
    )
    .unwrap();
    let mut campaign_cell = cell.clone();
    campaign_cell.tracker.samples_per_reading = 25;
    let rows = deflex_sim::twin_campaign::run_campaign(&campaign_cell, &plan.rows, 1).unwrap();
    let search = search_structure(nominal, &rows, &SearchOptions::default(), &mut |_| {}).unwrap();
    (rows, search)
}

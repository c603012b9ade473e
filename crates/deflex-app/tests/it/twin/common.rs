//! Shared set-up: the model identified from the twin's own calibration campaign (seed 11), made
//! once for the whole test binary.

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

//! Why the study (or one of its parts) could not be run, with the values that explain it.

use thiserror::Error;

/// Why the study, or one of its parts, could not be run.
#[derive(Debug, Error)]
pub enum DemoError {
    /// The twin refused a cell, path or campaign.
    #[error(transparent)]
    Sim(#[from] deflex_sim::SimError),
    /// Planning, identification or prediction failed.
    #[error(transparent)]
    Calib(#[from] deflex_calibrate::stiffness::CalibError),
    /// The robot model refused a pose.
    #[error(transparent)]
    Model(#[from] deflex_model::ModelError),
    /// An offline compensation failed.
    #[error(transparent)]
    Compensate(#[from] deflex_compensate::CompensateError),
    /// A forming log could not be resampled on its path.
    #[error(transparent)]
    Log(#[from] deflex_compensate::LogError),
    /// A forming log could not be read back.
    #[error(transparent)]
    WrenchLog(#[from] crate::load::WrenchLogError),
    /// A compensation table could not be read back.
    #[error(transparent)]
    Table(#[from] deflex_compensate::table::TableError),
    /// The controller refused a feed-forward table.
    #[error(transparent)]
    FeedForward(#[from] deflex_control::FeedForwardError),
    /// The controller driving the twin could not be set up or run.
    #[error(transparent)]
    ClosedLoop(#[from] deflex_sim::twin::TwinError),
    /// The feed-forward table of a compensation could not be built.
    #[error(transparent)]
    FeedForwardTable(#[from] crate::cell::feedforward::TableLoadError),
    /// A sensitivity plan outside its ranges.
    #[error(transparent)]
    SensitivityPlan(#[from] crate::study::sensitivity::SensitivityPlanError),
    /// The Fig. 7 test needs a 6-joint arm.
    #[error("the Fig. 7 test needs a 6-joint arm; {robot} has {joints}")]
    Fig7Joints {
        /// The robot's name.
        robot: String,
        /// Its joints.
        joints: usize,
    },
    /// Points of a path the offline compensation could not compensate.
    #[error("{path}: {count} point(s) could not be compensated (first: point {first}, {code})")]
    Uncompensated {
        /// The path.
        path: String,
        /// Points that failed.
        count: usize,
        /// The first of them.
        first: usize,
        /// Why (its failure code).
        code: String,
    },
    /// A closed-loop run of a comparison latched a fault.
    #[error("{path}: the controller faulted: {fault}")]
    ControllerFault {
        /// The path.
        path: String,
        /// The latched fault.
        fault: deflex_control::Fault,
    },
    /// A worker thread of a parallel stage panicked, or a run did not finish.
    #[error("{what}")]
    Worker {
        /// What is missing.
        what: &'static str,
    },
}

//! The structure search's removal step, through its public entry point.

use deflex_calibrate::stiffness::search::{SearchOptions, search_structure};
use deflex_calibrate::stiffness::stiffness_fit::Structure;
use deflex_calibrate::stiffness::synthetic::{SyntheticOptions, measure, random_campaign};
use deflex_model::{Axis, EdofSite};

/// Removing the last x/y eDoF of a joint also clears its (now meaningless) centre shift, so
/// no stray δr reaches the written model.
///
/// The search starts from the robot's structure with δr3 freed at 0.37 m; the truth's J3.x is
/// 300 times stiffer than the TX200's, too stiff for this campaign to need it, so a single step
/// that may only remove (no addition is significant at an infinite BIC gain) removes J3.x.
#[test]
fn removing_the_last_xy_edof_of_a_joint_clears_its_shift() {
    let mut truth = deflex_model::builtin("tx200").unwrap();
    let j3x = (EdofSite::Joint(3), Axis::X);
    let k = truth.stiffness(j3x.0, j3x.1).unwrap();
    truth.set_stiffness(j3x.0, j3x.1, Some(300.0 * k));
    let plan = random_campaign(&truth, 20, (600.0, 1400.0), 3);
    let rows = measure(&truth, &plan, &SyntheticOptions::default()).unwrap();
    let mut start = Structure::from_robot(&truth);
    start.free_shift[2] = true;
    start.shifts_m[2] = 0.37;
    let options = SearchOptions {
        min_bic_gain: f64::INFINITY,
        max_steps: 1,
        report_folds: 0,
        start: Some(start),
        ..SearchOptions::default()
    };
    let result = search_structure(&truth, &rows, &options, &mut |_| {}).unwrap();
    let steps: Vec<(&str, &str)> = result
        .steps
        .iter()
        .map(|s| (s.change.as_str(), s.structure.as_str()))
        .collect();
    // The start keeps J3.x with its free shift; the one step removes J3.x, and δr3 with it.
    assert_eq!(
        steps,
        [
            ("start: given structure", "J1.z J2.z J3.xz δr3 J4.z J5.z"),
            ("− J3.x", "J1.z J2.z J3.z J4.z J5.z"),
        ]
    );
    let after = &result.calibration.structure;
    assert!(!after.edofs.contains(&j3x));
    assert_eq!(after.shifts_m[2], 0.0);
    assert!(!after.free_shift[2]);
    assert_eq!(
        result.calibration.to_robot(&truth).joints[2].center_shift,
        0.0
    );
}

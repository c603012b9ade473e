//! Stiff contact (issue 11): against a stiff fixture the paper's correction is positive feedback.
//! The twin plunges 1 mm into a fixture and traverses; with a model identified from the twin's
//! own campaign, the unguarded loop runs the force away until the controller's force limit trips,
//! while against a soft contact the same loop settles.

use deflex_demo::contact::stiff_contact;
use deflex_demo::twin_controller::identify_from_twin_campaign;
use deflex_sim::CellConfig;

#[test]
fn stiff_contact_runs_away_without_a_guard_and_a_soft_one_settles() {
    let cell = CellConfig::default();
    let model = identify_from_twin_campaign(&cell, 3).unwrap();
    let (stiff, _, closed) = stiff_contact(&cell, &model, 1e7, 1, &|_| {}).unwrap();
    eprintln!("1e7 N/m: {stiff:?}");
    // Without correction the robot takes most of the 1 mm interference: a few hundred newtons.
    assert!(
        (200.0..900.0).contains(&stiff.open_max_force_N),
        "{}",
        stiff.open_max_force_N
    );
    // With it the force runs away (doubles within seconds) until the 2500 N force limit trips.
    assert!(stiff.runaway_at_s.is_some());
    assert!(
        stiff.closed_max_force_N > 2500.0,
        "{}",
        stiff.closed_max_force_N
    );
    let fault = stiff.fault.clone().unwrap_or_default();
    assert!(fault.contains("force_over_limit"), "{fault}");
    assert!(closed.fault.is_some());
    // A soft contact (10⁵ N/m): static loop gain g = ĉ k/(1 + k c) ≈ 0.2, the force settles at
    // about 1/(1 − g) of the uncorrected one, far below the limit.
    let (soft, _, _) = stiff_contact(&cell, &model, 1e5, 1, &|_| {}).unwrap();
    eprintln!("1e5 N/m: {soft:?}");
    assert!(soft.fault.is_none(), "{:?}", soft.fault);
    let ratio = soft.closed_max_force_N / soft.open_max_force_N;
    assert!(ratio > 1.05 && ratio < 1.6, "{ratio}");
}

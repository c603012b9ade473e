//! Stiff contact (issue 11, item 4) in the twin, in simulated time: against a stiff fixture the
//! paper's correction is positive feedback. With a model identified from the twin's own
//! campaign, a short plunge (1 mm into the fixture, 10 mm traverse) runs away without the
//! controller's runaway guard at 10⁶–10⁸ N/m (the force multiplied, or the 2500 N force trip)
//! and stays within 1.1× the uncorrected force with it, reporting `contact_runaway`; against a
//! soft contact the guard does not act and the loop settles; on the paper's cone (every error
//! source on, seed 1) the guard changes nothing.

use deflex_app::study::contact::{StiffContactNumbers, stiff_contact_with};
use deflex_app::twin::identify_from_twin_campaign;
use deflex_model::Robot;
use deflex_sim::twin::{controller_config_for, run_closed_loop};
use deflex_sim::{CellConfig, PlungeParams, ToolPath};
use std::sync::OnceLock;

/// The stated bound: with the guard the largest contact force stays within this factor of the
/// largest force without correction.
const GUARDED_BOUND: f64 = 1.1;

fn model() -> &'static Robot {
    static MODEL: OnceLock<Robot> = OnceLock::new();
    MODEL.get_or_init(|| identify_from_twin_campaign(&CellConfig::default(), 3).unwrap())
}

/// A short plunge: 1 mm approach, 1 mm into the fixture at 0.5 mm/s, 10 mm traverse at 2 mm/s,
/// back up (about 13 s of simulated time).
fn short_plunge(stiffness_n_m: f64) -> StiffContactNumbers {
    let params = PlungeParams {
        approach_mm: 1.0,
        traverse_mm: 10.0,
        ..PlungeParams::default()
    };
    let cell = CellConfig::default();
    let (numbers, runs) =
        stiff_contact_with(&cell, model(), stiffness_n_m, &params, 1, &|_| {}).unwrap();
    assert!(runs.open.summary.max_force_norm_N > 0.0);
    eprintln!(
        "{stiffness_n_m:.0e} N/m: uncorrected {:.0} N; no guard {:.0} N ({:.2}×, {:?}); \
         guard {:.0} N ({:.3}×, {} warning(s), {:?}, fault {:?})",
        numbers.open_max_force_N,
        numbers.unguarded.max_force_N,
        numbers.unguarded.force_ratio_to_uncorrected,
        numbers.unguarded.fault,
        numbers.guarded.max_force_N,
        numbers.guarded.force_ratio_to_uncorrected,
        numbers.guarded.runaway_warnings,
        numbers.guarded.first_runaway,
        numbers.guarded.fault,
    );
    numbers
}

#[test]
fn stiff_contact_runs_away_without_the_guard_and_is_held_with_it() {
    for k in [1e6, 1e7, 1e8] {
        let n = short_plunge(k);
        // Without correction the robot takes most of the 1 mm interference: a few hundred newtons.
        assert!(
            (200.0..900.0).contains(&n.open_max_force_N),
            "{k:e}: {}",
            n.open_max_force_N
        );
        // (a) Unguarded: the force is multiplied (≥ 2.5×) or the 2500 N force limit trips.
        let u = &n.unguarded;
        let tripped = u
            .fault
            .as_deref()
            .is_some_and(|f| f.starts_with("force_over_limit"));
        assert!(
            u.force_ratio_to_uncorrected >= 2.5 || tripped,
            "{k:e}: no runaway without the guard: {u:?}"
        );
        assert!(u.runaway_at_s.is_some(), "{k:e}: {u:?}");
        assert_eq!(u.runaway_warnings, 0);
        // (b) Guarded: within the stated bound, `contact_runaway` reported, no fault.
        let g = &n.guarded;
        assert!(
            g.force_ratio_to_uncorrected <= GUARDED_BOUND,
            "{k:e}: guarded force {:.0} N = {:.3}× the uncorrected",
            g.max_force_N,
            g.force_ratio_to_uncorrected
        );
        assert_eq!(
            g.runaway_warnings, 1,
            "{k:e}: one report per episode: {g:?}"
        );
        let warning = g.first_runaway.as_deref().unwrap_or_default();
        assert!(warning.starts_with("contact_runaway"), "{warning}");
        assert!(g.fault.is_none(), "{k:e}: {:?}", g.fault);
        assert!(g.runaway_at_s.is_none());
    }
}

/// A soft contact (10⁵ N/m): static loop gain g = ĉ k/(1 + k c) ≈ 0.1, the force settles at
/// about 1/(1 − g) of the uncorrected one; the guard does not act, the runs are identical.
#[test]
fn soft_contact_settles_and_the_guard_does_not_act() {
    let n = short_plunge(1e5);
    assert!(n.unguarded.fault.is_none() && n.guarded.fault.is_none());
    let ratio = n.unguarded.force_ratio_to_uncorrected;
    assert!(ratio > 1.05 && ratio < 1.6, "{ratio}");
    assert_eq!(n.guarded.runaway_warnings, 0);
    assert_eq!(n.guarded.max_force_N, n.unguarded.max_force_N);
}

/// (c) Normal forming: the paper's cone, every error source on, seed 1: the guard does not act
/// and the max error and force are within 1 % of the unguarded run.
#[test]
fn the_guard_leaves_the_cone_unaffected() {
    let cell = CellConfig::default();
    let run = |guard: bool| {
        let mut config = controller_config_for(&cell);
        config.runaway.enabled = guard;
        run_closed_loop(
            &cell,
            ToolPath::paper_cone(),
            1,
            model().clone(),
            config,
            false,
            &mut |_| {},
        )
        .unwrap()
    };
    let (guarded, unguarded) = (run(true), run(false));
    let (g, u) = (&guarded.forming.summary, &unguarded.forming.summary);
    eprintln!(
        "cone: max error {:.4} mm guarded, {:.4} mm unguarded; max |F| {:.1} / {:.1} N; \
         guard events {}",
        g.max_error_norm_mm,
        u.max_error_norm_mm,
        g.max_force_norm_N,
        u.max_force_norm_N,
        guarded.runaway_events
    );
    assert_eq!(guarded.runaway_events, 0);
    assert!(guarded.fault.is_none() && unguarded.fault.is_none());
    assert!((g.max_error_norm_mm / u.max_error_norm_mm - 1.0).abs() <= 0.01);
    assert!((g.max_force_norm_N / u.max_force_norm_N - 1.0).abs() <= 0.01);
    // The correction did its job on both.
    assert!(u.max_error_norm_mm < 1.5, "{}", u.max_error_norm_mm);
}

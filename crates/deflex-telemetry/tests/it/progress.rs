//! The progress message of a long job: a fraction in per mille, and the fraction of a stage.

use deflex_telemetry::Progress;
use deflex_telemetry::progress::PER_MILLE;

#[test]
fn a_fraction_is_work_in_per_mille_clamped() {
    assert_eq!(
        Progress::per_mille(0.25),
        Progress::Work {
            done: 250,
            total: PER_MILLE
        }
    );
    assert_eq!(Progress::per_mille(-1.0), Progress::per_mille(0.0));
    assert_eq!(Progress::per_mille(7.0), Progress::per_mille(1.0));
    assert_eq!(Progress::per_mille(f64::NAN), Progress::per_mille(0.0));
    assert_eq!(Progress::Work { done: 3, total: 4 }.fraction(), Some(0.75));
    assert_eq!(Progress::Work { done: 9, total: 4 }.fraction(), Some(1.0));
    assert_eq!(Progress::Work { done: 0, total: 0 }.fraction(), None);
    assert_eq!(Progress::Done { note: "" }.fraction(), None);
}

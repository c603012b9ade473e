//! The twin engine ([`deflex_app::twin`]): a short open-loop run's log columns.

use deflex_app::twin::*;

#[test]
fn a_short_open_loop_run_logs_si_columns_of_equal_length() {
    let run = form(
        "cone",
        &FormOptions {
            seed: 1,
            length_m: Some(0.05),
            ..FormOptions::default()
        },
    )
    .unwrap();
    let columns = log_columns(&run);
    let rows = run.run.log.rows.len();
    assert!(rows > 10);
    assert!(columns.iter().all(|(_, c)| c.len() == rows));
    let err = &columns.iter().find(|(n, _)| *n == "err_norm_m").unwrap().1;
    // The open loop deviates by a fraction of a millimetre to millimetres: metres, not mm.
    assert!(err.iter().cloned().fold(0.0, f64::max) < 0.01);
    let e = form(
        "cone",
        &FormOptions {
            fixture_stiffness_n_m: Some(1e7),
            ..FormOptions::default()
        },
    )
    .err()
    .unwrap();
    assert!(e.to_string().contains("plunge"), "{e}");
}

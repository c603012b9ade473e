//! Fuzz target of the `CELL.toml` parser and its validation (`deflex_app::cell::config`), on the
//! shared mutation fuzzer ([`crate::fuzz::engine`]; the documented example and a minimal file as
//! the corpus, numbers replaced by hostile values such as `nan`, `1e308`, `2e18`): no input may
//! panic, and every file that is accepted must give a configuration the controller takes, with
//! finite durations, rates and sizes within the documented bounds. A quick count here; the full
//! count:
//!
//! ```sh
//! DEFLEX_FUZZ_COUNT=1000000 cargo test --release -p deflex --test it fuzz::cell_config -- --nocapture
//! ```

use crate::fuzz::engine::{count_from_env, fuzz};
use deflex_app::cell::config::{CellFile, bounds_of};
use deflex_control::Controller;
use std::path::PathBuf;

const EXAMPLE: &str = include_str!("../../../../../docs/cell.example.toml");
const MINIMAL: &str = "[robot]\nkind = \"kuka-rsi\"\nbind = \"127.0.0.1:59152\"\n\
[sensor]\nkind = \"netft\"\naddress = \"127.0.0.1:49152\"\n[model]\nfile = \"tx200\"\n\
[log]\npath = \"x.csv\"\nring_capacity = 100\n";

#[test]
fn cell_toml_never_panics_and_accepted_files_are_usable() {
    let model = deflex_model::builtin("tx200").unwrap();
    let corpus: &[&[u8]] = &[EXAMPLE.as_bytes(), MINIMAL.as_bytes()];
    let mut accepted = 0usize;
    let report = fuzz(corpus, count_from_env(20_000), 16_384, |input| {
        let text = String::from_utf8_lossy(input);
        let Ok(cell) = CellFile::parse(&text, "fuzz.toml", PathBuf::new()) else {
            return;
        };
        accepted += 1;
        let c = cell.controller_config();
        assert!(c.period_s.is_finite() && c.period_s > 0.0 && c.period_s <= 1.0);
        assert!(c.limiter.ramp_out_s <= 10.0 && c.tare_s <= 60.0);
        assert!(cell.robot.cycle_s >= 5e-4 && cell.robot.cycle_s <= 0.1);
        if let Some(log) = &cell.log {
            assert!(log.ring_capacity as f64 <= bounds_of("log.ring_capacity").1);
        }
        assert!(Controller::new(model.clone(), c).is_ok(), "{text}");
        let _ = (cell.egm_config(6), cell.rsi_config());
    });
    report.assert_no_panic("CELL.toml");
    println!(
        "CELL.toml: {} inputs, {accepted} accepted, no panic",
        report.inputs
    );
    assert!(accepted > 0);
}

//! Fuzz target of the `CELL.toml` parser and validation: mutations of the documented example
//! and of a minimal file (line deletions and duplications, values replaced by special numbers,
//! byte edits) must never panic, and every file that is accepted must give a controller
//! configuration the controller takes and whose durations, rates and sizes are finite and
//! within the documented bounds. `cargo test` runs [`QUICK_COUNT`] inputs; the full count is
//! `cargo run --release -p deflex-control --example fuzz_cell -- --count 1000000`.

use super::{BOUNDS, CellFile};
use crate::controller::Controller;
use deflex_io::fuzz::{Rng, mutate};
use std::path::PathBuf;

/// Inputs in `cargo test`.
pub const QUICK_COUNT: u64 = 20_000;

const EXAMPLE: &str = include_str!("../../../../docs/cell.example.toml");
const MINIMAL: &str = "[robot]\nkind = \"kuka-rsi\"\nbind = \"127.0.0.1:59152\"\n\
[sensor]\nkind = \"netft\"\naddress = \"127.0.0.1:49152\"\n[model]\nfile = \"tx200\"\n";
const VALUES: [&str; 18] = [
    "nan",
    "inf",
    "-inf",
    "1e300",
    "-1e300",
    "1e-300",
    "0",
    "-1",
    "0.001",
    "2e18",
    "2000000000000000000",
    "\"x\"",
    "[]",
    "[1.0]",
    "true",
    "\"abb-egm\"",
    "\"joint\"",
    "1",
];

/// One mutated file.
fn mutated(rng: &mut Rng) -> String {
    let base = if rng.chance(0.7) { EXAMPLE } else { MINIMAL };
    let mut lines: Vec<String> = base.lines().map(str::to_string).collect();
    for _ in 0..1 + rng.below(4) {
        if lines.is_empty() {
            break;
        }
        let i = rng.below(lines.len());
        match rng.below(5) {
            0 => {
                lines.remove(i);
            }
            1 => {
                let l = lines[i].clone();
                lines.insert(i, l);
            }
            2 | 3 => {
                // Replace the value of a `key = value` line.
                if let Some(eq) = lines[i].find('=') {
                    let v = VALUES[rng.below(VALUES.len())];
                    lines[i] = format!("{}= {v}", &lines[i][..eq]);
                }
            }
            _ => {
                let mut out = Vec::new();
                mutate(rng, lines[i].as_bytes(), b"[]=\"#.,-e0123456789 ", &mut out);
                lines[i] = String::from_utf8_lossy(&out).into_owned();
            }
        }
    }
    lines.join("\n")
}

/// Feeds `count` mutated files; returns how many were accepted. Panics on a violated promise.
pub fn run(count: u64, seed: u64) -> u64 {
    let mut rng = Rng::new(seed);
    let model = deflex_model::builtin("tx200").expect("built-in tx200");
    let mut accepted = 0;
    for _ in 0..count {
        let text = mutated(&mut rng);
        let Ok(cell) = CellFile::parse(&text, "fuzz.toml", PathBuf::new()) else {
            continue;
        };
        accepted += 1;
        let c = cell.controller_config();
        assert!(c.period_s.is_finite() && c.period_s > 0.0 && c.period_s <= 1.0);
        assert!(c.limiter.ramp_out_s <= 10.0 && c.tare_s <= 60.0);
        if let Some(log) = &cell.log {
            let (_, hi, _) = super::bounds_of("log.ring_capacity");
            assert!(log.ring_capacity as f64 <= hi);
        }
        assert!(cell.robot.cycle_s >= 5e-4 && cell.robot.cycle_s <= 0.1);
        assert!(
            Controller::new(model.clone(), c).is_ok(),
            "an accepted file was refused by the controller:\n{text}"
        );
        let _ = cell.egm_config(6);
        let _ = cell.rsi_config();
    }
    let _ = BOUNDS;
    accepted
}

#[cfg(test)]
mod tests {
    #[test]
    fn cell_toml_survives_the_quick_count() {
        let accepted = super::run(super::QUICK_COUNT, 0x5EED_CE11);
        assert!(accepted > 100, "{accepted}");
    }
}

//! Fill a plan CSV with synthetic measurements from a known model (SIMULATED data, for demos):
//! `cargo run --release -p deflex-calibrate --example synth -- TRUTH PLAN.csv OUT.csv [NOISE_UM] [SEED]`.
//! TRUTH is a built-in robot or a robot TOML without URDF; `tx200+base` is the TX200 of Table 1
//! plus a base tilt about y0 (6e6 N·m/rad).
use deflex_calibrate::measurements::{format_rows, parse_rows};
use deflex_calibrate::stiffness::synthetic::{SyntheticOptions, measure};
use deflex_model::{Axis, EdofSite, builtin, robot_from_toml_str};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 3 {
        return Err("usage: synth TRUTH PLAN.csv OUT.csv [NOISE_UM] [SEED]".into());
    }
    let truth = if args[0] == "tx200+base" {
        let mut r = builtin("tx200").ok_or("tx200 is built in")?;
        r.set_stiffness(EdofSite::Base, Axis::Y, Some(6.0e6));
        r
    } else if let Some(r) = builtin(&args[0]) {
        r
    } else {
        robot_from_toml_str(&std::fs::read_to_string(&args[0])?, &args[0], None)?
    };
    let plan = parse_rows(&std::fs::read_to_string(&args[1])?, &args[1], false)?;
    let noise_um: f64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(15.0);
    let seed: u64 = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(1);
    let rows = measure(
        &truth,
        &plan,
        &SyntheticOptions {
            noise_sigma_m: noise_um * 1e-6,
            seed,
            ..Default::default()
        },
    )?;
    std::fs::write(&args[2], format_rows(&rows))?;
    eprintln!(
        "wrote {} rows (SIMULATED, {noise_um} µm noise) to {}",
        rows.len(),
        args[2]
    );
    Ok(())
}

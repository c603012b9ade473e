//! Fill a plan CSV with synthetic measurements from a known model (SIMULATED data, for demos):
//! `cargo run --release -p deflex-stiffness --example synth -- TRUTH PLAN.csv OUT.csv [NOISE_UM] [SEED]`.
//! With TRUTH = `tx200+base` the TX200 of Table 1 plus a base tilt about y0 (6e6 N·m/rad).
use deflex_stiffness::synthetic::{SyntheticOptions, measure};
use deflex_model::{Axis, EdofSite, load_robot};

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 3 {
        return Err("usage: synth TRUTH PLAN.csv OUT.csv [NOISE_UM] [SEED]".into());
    }
    let truth = if args[0] == "tx200+base" {
        let mut r = load_robot("tx200").map_err(|e| e.to_string())?;
        r.set_stiffness(EdofSite::Base, Axis::Y, Some(6.0e6));
        r
    } else {
        load_robot(&args[0]).map_err(|e| e.to_string())?
    };
    let plan =
        deflex_stiffness::read_plan(std::path::Path::new(&args[1])).map_err(|e| e.to_string())?;
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
    )
    .map_err(|e| e.to_string())?;
    deflex_stiffness::write_rows(std::path::Path::new(&args[2]), &rows).map_err(|e| e.to_string())?;
    eprintln!(
        "wrote {} rows (SIMULATED, {noise_um} µm noise) to {}",
        rows.len(),
        args[2]
    );
    Ok(())
}

//! Stiffness identification from a measurement CSV (Section 3 of the paper): the automatic
//! structure search from one eDoF per joint, then the identified stiffnesses with their standard
//! errors.
//!
//! `cargo run -p deflex --example calibrate_csv [MEASUREMENTS.csv]`
//!
//! The CSV is deflex's measurement format (columns `load_case`, `q1_rad`…, `fx_N`…, `dx_m`…; see
//! `deflex::calibrate::measurements`), for the TX200. Without a file, a SIMULATED campaign of 40 random
//! load cases on the paper's TX200 (Table 1) with 15 µm tracker noise is written to a temporary
//! CSV first and read back, so the search has a known truth to find.
use deflex::builtin;
use deflex::calibrate::stiffness::synthetic::{SyntheticOptions, measure, random_campaign};
use deflex::calibrate::stiffness::{SearchOptions, search_structure};
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let robot = builtin("tx200").ok_or("tx200 is a built-in robot")?;
    let path = match std::env::args_os().nth(1) {
        Some(p) => PathBuf::from(p),
        None => {
            let plan = random_campaign(&robot, 40, (300.0, 1500.0), 7);
            let rows = measure(&robot, &plan, &SyntheticOptions::default())?;
            let path = std::env::temp_dir().join(format!(
                "deflex-example-measurements-{}.csv",
                std::process::id()
            ));
            let text = deflex::calibrate::measurements::format_rows_for(
                &robot,
                &rows,
                &["SIMULATED: the TX200 of Table 1, 15 µm tracker noise"],
            );
            std::fs::write(&path, text)?;
            println!("wrote a SIMULATED campaign: {}", path.display());
            path
        }
    };
    let rows = deflex::app::load::read_measurements(&path);
    if std::env::args_os().nth(1).is_none() {
        // Our own temporary file: gone once read.
        let _ = std::fs::remove_file(&path);
    }
    let rows = rows?;
    println!("{} rows read from {}", rows.len(), path.display());
    let result = search_structure(&robot, &rows, &SearchOptions::default(), &mut |_| {})?;
    let calibration = &result.calibration;
    println!(
        "structure {} after {} steps ({}); χ²/dof {:.2}, RMS residual {:.1} µm",
        calibration.structure.label(),
        result.steps.len(),
        result.stop_reason,
        calibration.reduced_chi2,
        calibration.residuals.position.norm.rms * 1e6
    );
    for edof in &calibration.edofs {
        let truth = robot.stiffness(edof.id.0, edof.id.1);
        match (edof.stiffness, edof.stiffness_se) {
            (Some(k), Some(se)) => println!(
                "  {:6} k = {:10.3e} ± {:.1e} N·m/rad{}",
                edof.label,
                k,
                se,
                truth
                    .map(|t| format!("  (Table 1: {t:.3e})"))
                    .unwrap_or_default()
            ),
            _ => println!("  {:6} not identifiable: {:?}", edof.label, edof.status),
        }
    }
    Ok(())
}

//! The paper's uncorrected cone run on the twin (SIMULATED), with the acceptance numbers.
//! `cargo run --release -p deflex-sim --example cone_open_loop [OUT_DIR]` (`log.csv`,
//! `summary.json` and `profile.csv` into OUT_DIR; `deflex sim isf` also draws the plots).
use deflex_sim::{CellConfig, ToolPath, run_forming};

fn main() {
    let config = CellConfig::default();
    let run = run_forming(&config, ToolPath::paper_cone(), 1, None).expect("run");
    let summary = run.summary_json().expect("summary.json");
    println!("{summary}");
    let s = &run.summary;
    println!(
        "max error {:.3} mm (paper 3.84, band 2.88–4.80), RMS {:.3} mm, max Fz {:.0} N, max Fxy {:.0} N, \
         part depth {:.2} of {:.1} mm, wall time {:.3} s for {:.0} s simulated",
        s.max_error_norm_mm,
        s.rms_error_norm_mm,
        s.max_fz_N,
        s.max_fxy_N,
        s.final_part_depth_mm,
        s.target_depth_mm,
        run.wall_time_s,
        s.duration_s
    );
    if let Some(dir) = std::env::args().nth(1) {
        let dir = std::path::Path::new(&dir);
        std::fs::create_dir_all(dir).expect("output folder");
        for (name, text) in [
            ("log.csv", run.log.to_csv()),
            ("summary.json", summary),
            ("profile.csv", run.profile_csv()),
        ] {
            std::fs::write(dir.join(name), text).expect("output file");
            println!("wrote {}", dir.join(name).display());
        }
    }
}

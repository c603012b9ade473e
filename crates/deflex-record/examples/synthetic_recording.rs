//! Writes a recording of the SIMULATED synthetic stream (not the twin, not a robot):
//! `cargo run -p deflex-record --example synthetic_recording -- OUT.mcap [SECONDS] [twin|cell]`.
//! Used by the independent Python reader test (`crates/deflex-record/tests/python`).

use deflex_record::{McapSink, RecordOptions};
use deflex_telemetry::synthetic::SyntheticCell;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(out) = args.first() else {
        eprintln!("usage: synthetic_recording OUT.mcap [SECONDS] [twin|cell]");
        return ExitCode::from(2);
    };
    let seconds: f64 = match args.get(1).map(|s| s.parse()) {
        None => 10.0,
        Some(Ok(v)) if (0.01..=3600.0).contains(&v) => v,
        Some(_) => {
            eprintln!("SECONDS: a number of seconds in 0.01..=3600");
            return ExitCode::from(2);
        }
    };
    let twin = args.get(2).is_none_or(|s| s == "twin");
    let mut cell = SyntheticCell::new(0.01, 1, twin);
    let info = cell.session_info();
    let result = (|| {
        let file = deflex_files::AtomicFile::create(out).map_err(|e| format!("{out}: {e}"))?;
        let mut sink = McapSink::new(file, out.as_str(), &info, RecordOptions::default())
            .map_err(|e| e.to_string())?;
        for _ in 0..(seconds / 0.01).round() as usize {
            sink.write(&cell.next_sample()).map_err(|e| e.to_string())?;
        }
        let (file, stats) = sink.finish().map_err(|e| e.to_string())?;
        file.commit().map_err(|e| format!("{out}: {e}"))?;
        Ok::<_, String>(stats)
    })();
    match result {
        Ok(stats) => {
            println!(
                "{out}: SIMULATED synthetic stream, {} cycles, {} messages, {} bytes",
                stats.recorded, stats.messages, stats.bytes
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

//! Serves the live view of the SIMULATED synthetic stream (not the twin, not a robot: signals of
//! the right shape, see `deflex_telemetry::synthetic`) so that the page can be seen:
//!
//! ```text
//! cargo run --release -p deflex-view --example synthetic -- [ADDR] [--rate-hz 100] [--stop] [--prefill-s S]
//! ```
//!
//! ADDR defaults to 127.0.0.1:8765. `--stop` gives the page a stop button whose callback only
//! prints (there is no robot). `--prefill-s` publishes S seconds at once before going live, to
//! see a full window.

use deflex_telemetry::synthetic::SyntheticCell;
use deflex_telemetry::{CycleSample, broadcast};
use std::process::ExitCode;
use std::sync::Arc;
use std::time::{Duration, Instant};

fn main() -> ExitCode {
    let mut addr = "127.0.0.1:8765".to_string();
    let mut rate_hz = 100.0;
    let mut stop = false;
    let mut prefill_s = 0.0;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--rate-hz" => match args.next().and_then(|v| v.parse().ok()) {
                Some(v) if (1.0..=1000.0).contains(&v) => rate_hz = v,
                _ => return usage("--rate-hz: a number in 1..=1000"),
            },
            "--prefill-s" => match args.next().and_then(|v| v.parse().ok()) {
                Some(v) if (0.0..=600.0).contains(&v) => prefill_s = v,
                _ => return usage("--prefill-s: seconds in 0..=600"),
            },
            "--stop" => stop = true,
            _ if !a.starts_with('-') => addr = a,
            _ => return usage(&format!("unknown option {a}")),
        }
    }
    let Ok(addr) = addr.parse() else {
        return usage("ADDR: an address such as 127.0.0.1:8765");
    };
    let period = 1.0 / rate_hz;
    let mut cell = SyntheticCell::new(period, 1, true);
    let info = Arc::new(cell.session_info());
    let (mut publisher, ring) = broadcast::<CycleSample>(120_000);
    for _ in 0..(prefill_s * rate_hz) as usize {
        publisher.publish(&cell.next_sample());
    }
    let callback: Option<deflex_view::StopCallback> = if stop {
        Some(Box::new(|| {
            eprintln!("stop requested from the page (SIMULATED: nothing to stop)")
        }))
    } else {
        None
    };
    let view = match deflex_view::serve(addr, ring.clone(), info, callback) {
        Ok(v) => v,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    println!(
        "SIMULATED synthetic stream at {rate_hz} Hz: open {}",
        view.url()
    );
    let start = Instant::now();
    let mut n: u64 = 0;
    loop {
        publisher.publish(&cell.next_sample());
        n += 1;
        let due = start + Duration::from_secs_f64(n as f64 * period);
        if let Some(wait) = due.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
        if n.is_multiple_of(10 * rate_hz as u64) {
            let s = view.stats();
            eprintln!(
                "{n} samples published; view: {} pages, {} received, {} lost, {} messages dropped",
                s.clients, s.samples_received, s.samples_lost, s.frames_dropped
            );
        }
    }
}

fn usage(message: &str) -> ExitCode {
    eprintln!("error: {message}\nusage: synthetic [ADDR] [--rate-hz 100] [--stop] [--prefill-s S]");
    ExitCode::from(2)
}

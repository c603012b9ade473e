//! The full fuzz count of the `CELL.toml` parser (see `deflex_control::config::fuzz`):
//!
//! ```sh
//! cargo run --release -p deflex-control --example fuzz_cell -- --count 1000000 [--seed N]
//! ```

use std::process::ExitCode;
use std::time::Instant;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let Ok(count) = value("--count").unwrap_or("1000000".into()).parse::<u64>() else {
        eprintln!("--count: expected a positive integer");
        return ExitCode::FAILURE;
    };
    let Ok(seed) = value("--seed").unwrap_or("1".into()).parse::<u64>() else {
        eprintln!("--seed: expected an unsigned integer");
        return ExitCode::FAILURE;
    };
    let start = Instant::now();
    match std::panic::catch_unwind(|| deflex_control::config::fuzz::run(count, seed)) {
        Ok(accepted) => {
            println!(
                "cell.toml  {count} inputs, {accepted} accepted, no panic ({:.1} s)",
                start.elapsed().as_secs_f64()
            );
            ExitCode::SUCCESS
        }
        Err(_) => {
            println!("cell.toml  FAILED (seed {seed})");
            ExitCode::FAILURE
        }
    }
}

//! The full fuzz count of deflex-io's wire parsers (see `deflex_io::fuzz`):
//!
//! ```sh
//! cargo run --release -p deflex-io --example fuzz -- --count 1000000 [--seed N] [--target rsi]
//! ```
//!
//! Prints, per target, the inputs fed, how many a parser accepted and the time; exits non-zero
//! (naming the target and the panic) if a parser panicked or broke a promise.

use deflex_io::fuzz::{Target, run};
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
    let count: u64 = match value("--count").map(|v| v.parse()) {
        None => 1_000_000,
        Some(Ok(n)) if n > 0 => n,
        Some(_) => {
            eprintln!("--count: expected a positive integer");
            return ExitCode::FAILURE;
        }
    };
    let seed: u64 = match value("--seed").map(|v| v.parse()) {
        None => 1,
        Some(Ok(n)) => n,
        Some(Err(_)) => {
            eprintln!("--seed: expected an unsigned integer");
            return ExitCode::FAILURE;
        }
    };
    let targets: Vec<Target> = match value("--target") {
        None => Target::ALL.to_vec(),
        Some(name) => match Target::from_name(&name) {
            Some(t) => vec![t],
            None => {
                eprintln!(
                    "--target: expected one of rsi, egm, staubli, simple-udp, simple-tcp, netft"
                );
                return ExitCode::FAILURE;
            }
        },
    };
    let mut failed = false;
    for target in targets {
        let start = Instant::now();
        match std::panic::catch_unwind(|| run(target, count, seed)) {
            Ok(r) => println!(
                "{:10} {} inputs, {} accepted, no panic ({:.1} s)",
                target.name(),
                r.inputs,
                r.accepted,
                start.elapsed().as_secs_f64()
            ),
            Err(_) => {
                println!("{:10} FAILED (seed {seed})", target.name());
                failed = true;
            }
        }
    }
    if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    }
}

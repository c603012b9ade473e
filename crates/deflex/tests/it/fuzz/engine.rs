//! A small, deterministic mutation fuzzer for deflex's parsers (robot files, URDF, measurement
//! CSV, G-code, cell configuration, wire protocols). Every parser gets the same treatment: a
//! corpus of valid inputs, then random bytes and mutations of the corpus (bit flips, byte
//! insertions and deletions, truncation, splices between corpus entries, duplicated chunks, and
//! numbers replaced by hostile values such as `nan`, `1e308`, `-0`, `5e-324`), fed to the
//! target, which must return — an `Err` is fine, a panic is a finding.
//!
//! Not coverage-guided (that needs `cargo fuzz` and a nightly toolchain); it is cheap enough to
//! run a quick count inside `cargo test` and ≥ 10⁶ inputs per parser from the command line:
//!
//! ```sh
//! DEFLEX_FUZZ_COUNT=1000000 cargo test --release -p deflex --test it fuzz:: -- --nocapture
//! ```
//!
//! The seed is fixed unless `DEFLEX_FUZZ_SEED` is set, so a finding reproduces.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::panic::{AssertUnwindSafe, catch_unwind};

/// Values substituted for numbers found in an input.
const HOSTILE_NUMBERS: &[&str] = &[
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "1e309",
    "5e-324",
    "-0",
    "-0.0",
    "0",
    "1e-300",
    "1e300",
    "18446744073709551616",
    "-9223372036854775809",
    "2e18",
    "1e12",
    "0.000000001",
    "4294967296",
    "",
    "1.",
    ".",
    "-",
    "1e",
    "0x10",
    "１",
];

/// What a fuzz run did.
#[derive(Debug, Clone)]
pub struct FuzzReport {
    /// Inputs fed to the target.
    pub inputs: usize,
    /// The first input that made the target panic, and the panic message.
    pub finding: Option<(Vec<u8>, String)>,
}

impl FuzzReport {
    /// Panics with the finding, shown as text (lossy) and its length, if there is one.
    pub fn assert_no_panic(&self, name: &str) {
        if let Some((input, message)) = &self.finding {
            panic!(
                "{name}: a fuzz input of {} bytes made the parser panic ({message}):\n{}",
                input.len(),
                String::from_utf8_lossy(&input[..input.len().min(2000)])
            );
        }
    }
}

/// Number of inputs: `DEFLEX_FUZZ_COUNT` when set, else `quick`.
pub fn count_from_env(quick: usize) -> usize {
    std::env::var("DEFLEX_FUZZ_COUNT")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(quick)
}

/// The run's seed: `DEFLEX_FUZZ_SEED` when set, else a fixed one.
fn seed_from_env() -> u64 {
    std::env::var("DEFLEX_FUZZ_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0x00de_f1e5)
}

/// Feed `count` inputs (random and mutated from `corpus`, each at most `max_len` bytes) to
/// `target`; stops at the first panic. The default panic hook is silenced during the run.
pub fn fuzz(
    corpus: &[&[u8]],
    count: usize,
    max_len: usize,
    mut target: impl FnMut(&[u8]),
) -> FuzzReport {
    let mut rng = ChaCha8Rng::seed_from_u64(seed_from_env());
    let previous_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let mut report = FuzzReport {
        inputs: 0,
        finding: None,
    };
    let mut input = Vec::with_capacity(max_len);
    for _ in 0..count {
        make_input(&mut rng, corpus, max_len, &mut input);
        report.inputs += 1;
        if let Err(payload) = catch_unwind(AssertUnwindSafe(|| target(&input))) {
            let message = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "non-string panic".into());
            report.finding = Some((input.clone(), message));
            break;
        }
    }
    std::panic::set_hook(previous_hook);
    report
}

/// One input: one time in eight random bytes, otherwise a corpus entry with 1–4 mutations.
fn make_input(rng: &mut ChaCha8Rng, corpus: &[&[u8]], max_len: usize, out: &mut Vec<u8>) {
    out.clear();
    if corpus.is_empty() || rng.gen_ratio(1, 8) {
        let len = rng.gen_range(0..=max_len.min(256));
        out.extend((0..len).map(|_| rng.r#gen::<u8>()));
        return;
    }
    out.extend_from_slice(corpus[rng.gen_range(0..corpus.len())]);
    for _ in 0..rng.gen_range(1..=4) {
        mutate(rng, corpus, out);
    }
    out.truncate(max_len);
}

fn mutate(rng: &mut ChaCha8Rng, corpus: &[&[u8]], data: &mut Vec<u8>) {
    let len = data.len();
    match rng.gen_range(0..8) {
        0 if len > 0 => {
            let i = rng.gen_range(0..len);
            data[i] ^= 1 << rng.gen_range(0..8);
        }
        1 => {
            let i = rng.gen_range(0..=len);
            data.insert(i, rng.r#gen());
        }
        2 if len > 0 => {
            let i = rng.gen_range(0..len);
            let n = rng.gen_range(1..=(len - i).min(16));
            data.drain(i..i + n);
        }
        3 if len > 0 => data.truncate(rng.gen_range(0..len)),
        4 => {
            // Splice a piece of another corpus entry in.
            let other = corpus[rng.gen_range(0..corpus.len())];
            if !other.is_empty() {
                let a = rng.gen_range(0..other.len());
                let b = rng.gen_range(a..=other.len());
                let at = rng.gen_range(0..=len);
                data.splice(at..at, other[a..b].iter().copied());
            }
        }
        5 if len > 0 => {
            // Duplicate a chunk (repeated sections, keys, elements).
            let a = rng.gen_range(0..len);
            let b = rng.gen_range(a..=len.min(a + 64));
            let chunk: Vec<u8> = data[a..b].to_vec();
            for _ in 0..rng.gen_range(1..4) {
                data.splice(b..b, chunk.iter().copied());
            }
        }
        _ => replace_number(rng, data),
    }
}

/// Replace one number (a run of digits, signs, dots, exponents) by a hostile value.
fn replace_number(rng: &mut ChaCha8Rng, data: &mut Vec<u8>) {
    let starts: Vec<usize> = (0..data.len())
        .filter(|&i| data[i].is_ascii_digit() && (i == 0 || !data[i - 1].is_ascii_digit()))
        .collect();
    if starts.is_empty() {
        return;
    }
    let mut a = starts[rng.gen_range(0..starts.len())];
    while a > 0 && matches!(data[a - 1], b'-' | b'+' | b'.') {
        a -= 1;
    }
    let mut b = a;
    while b < data.len() && matches!(data[b], b'0'..=b'9' | b'.' | b'e' | b'E' | b'-' | b'+') {
        b += 1;
    }
    let value = HOSTILE_NUMBERS[rng.gen_range(0..HOSTILE_NUMBERS.len())];
    data.splice(a..b, value.bytes());
}

/// The engine finds a panic and is deterministic.
mod tests {
    use super::*;

    #[test]
    fn a_panicking_target_is_found_and_a_tolerant_one_is_not() {
        let corpus: &[&[u8]] = &[b"x = 1.5\ny = 2\n"];
        let report = fuzz(corpus, 5000, 64, |input| {
            assert!(
                !input.windows(3).any(|w| w == b"nan"),
                "nan reached the parser"
            );
        });
        let (input, message) = report.finding.expect("hostile numbers include nan");
        assert!(String::from_utf8_lossy(&input).contains("nan"));
        assert!(message.contains("nan reached"));
        let report = fuzz(corpus, 5000, 64, |input| {
            let _ = std::str::from_utf8(input).map(|t| t.parse::<f64>());
        });
        assert!(report.finding.is_none());
        assert_eq!(report.inputs, 5000);
    }

    #[test]
    fn inputs_are_deterministic_and_bounded() {
        let corpus: &[&[u8]] = &[b"<robot><joint name=\"a\"/></robot>"];
        let collect = || {
            let mut seen = Vec::new();
            fuzz(corpus, 200, 40, |input| {
                assert!(input.len() <= 40);
                seen.push(input.to_vec());
            });
            seen
        };
        assert_eq!(collect(), collect());
    }
}

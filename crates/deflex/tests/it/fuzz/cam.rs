//! Fuzzing the CAM readers (`deflex_cam`): the G-code reader over mutations of a valid program
//! gives a path or an error with a line, never a panic; an accepted path is finite and bounded.
//! Its own small deterministic mutator (xorshift over a G-code alphabet), as in the old
//! `deflex-gcode` test.

use deflex_cam::gcode::{ReadOptions, read};

#[test]
fn random_bytes_never_panic() {
    // A small deterministic fuzz (xorshift) over mutations of a valid program: Ok or an error
    // with a line, never a panic; accepted paths are finite and bounded.
    let seed = "%\nO1\nG17 G21 G90 G54\nG0 X10 Y0 Z2\nG1 Z0 F300\nG3 X10 Y0 I-10 J0\nG2 X0 Y10 R10\nG18 G3 X5 Z1 I-2.5 K0.5\nM30\n%\n";
    let alphabet = b"GXYZIJKRPFMNTS0123456789.-+ ()%;/\n";
    let mut state: u64 = 0x9e3779b97f4a7c15;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let mut accepted = 0;
    for _ in 0..20_000 {
        let mut bytes = seed.as_bytes().to_vec();
        for _ in 0..(next() % 6 + 1) {
            let at = (next() as usize) % bytes.len();
            let c = alphabet[(next() as usize) % alphabet.len()];
            match next() % 3 {
                0 => bytes[at] = c,
                1 => bytes.insert(at, c),
                _ => {
                    bytes.remove(at);
                }
            }
        }
        let text = String::from_utf8_lossy(&bytes);
        let options = ReadOptions {
            max_points: 200_000,
            ..ReadOptions::default()
        };
        if let Ok(p) = read(&text, &options) {
            accepted += 1;
            assert!(p.points.len() >= 2 && p.points.len() <= 200_000);
            assert!(
                p.points
                    .iter()
                    .all(|q| q.p_mm.iter().all(|v| v.is_finite() && v.abs() <= 10_000.0))
            );
        }
    }
    assert!(accepted > 20, "{accepted}");
}

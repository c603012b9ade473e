//! The protocol-independent types. The rotation maths they once carried (Euler angles,
//! rotation vectors, quaternions) is the model's (`deflex_model::conventions`) and is tested
//! there; here: a correction's rotation vector and the KUKA angles RSI puts on the wire.

use deflex_io::link::*;
use deflex_io::rsi::{correction_to_rkorr, rkorr_to_correction};

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn small_rotation_maps_to_abc_componentwise() {
    let c = Correction {
        dp_m: [0.0; 3],
        dphi_rad: [1e-4, -2e-4, 3e-4],
    };
    let rkorr = correction_to_rkorr(&c);
    let abc = [rkorr[3], rkorr[4], rkorr[5]];
    assert!(close(abc[0], 3e-4, 1e-7));
    assert!(close(abc[1], -2e-4, 1e-7));
    assert!(close(abc[2], 1e-4, 1e-7));
    let back = rkorr_to_correction(&[c.dp_m[0], c.dp_m[1], c.dp_m[2], abc[0], abc[1], abc[2]]);
    for i in 0..3 {
        assert!(close(back.dphi_rad[i], c.dphi_rad[i], 1e-15));
    }
}

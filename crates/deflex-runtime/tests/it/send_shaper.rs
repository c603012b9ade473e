//! The last limiter before the wire ([`deflex_runtime::send_shaper`]).

use deflex_runtime::send_shaper::{LinkDirective, SendShaper, SendShaperConfig};

fn config() -> SendShaperConfig {
    SendShaperConfig::new([0.02; 6], [0.008; 6], 0.004, 0.5)
}

#[test]
fn steps_never_exceed_rate_times_cycle_whatever_the_target() {
    let mut s = SendShaper::new(config());
    let targets = [0.008, -0.008, f64::NAN, 1.0, 0.0, -0.003];
    let mut prev = [0.0; 6];
    for k in 0..2000 {
        let t = [targets[k % targets.len()]; 6];
        let d = [
            LinkDirective::Follow,
            LinkDirective::RampOut,
            LinkDirective::Hold,
        ][k / 300 % 3];
        let out = s.next(&t, d);
        for i in 0..6 {
            assert!((out[i] - prev[i]).abs() <= 0.02 * 0.004 + 1e-18);
            assert!(out[i].abs() <= 0.008);
        }
        prev = out;
    }
}

#[test]
fn ramp_out_is_counted_in_answers_and_smooth() {
    let mut s = SendShaper::new(SendShaperConfig::new([1.0; 6], [0.01; 6], 0.004, 0.2));
    for _ in 0..100 {
        s.next(&[0.001; 6], LinkDirective::Follow);
    }
    assert_eq!(s.last(), [0.001; 6]);
    // 0.2 s / 4 ms = 50 answers, whatever wall time passes between them.
    let mut n = 0;
    let mut prev = 0.001;
    while !s.is_zero() {
        let v = s.next(&[0.005; 6], LinkDirective::RampOut)[0];
        assert!(v <= prev + 1e-18, "ramp-out grew");
        prev = v;
        n += 1;
        assert!(n <= 50);
    }
    assert_eq!(n, 50);
    // Smoothstep: the first step is tiny.
    let mut s2 = SendShaper::new(SendShaperConfig::new([1.0; 6], [0.01; 6], 0.004, 0.2));
    s2.next(&[0.001; 6], LinkDirective::Follow);
    let first = s2.next(&[0.0; 6], LinkDirective::RampOut)[0];
    assert!(0.001 - first < 0.001 * 0.002, "{first}");
}

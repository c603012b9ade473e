//! Decimation, the p99 and the wire format ([`deflex_view::frame`]), against separately written
//! computations.

use deflex_telemetry::CycleSample;
use deflex_telemetry::synthetic::SyntheticCell;
use deflex_view::frame::{self, BUCKET_S, Decimator, FIELDS, NFIELDS, P99_WINDOW};

fn index(name: &str) -> usize {
    FIELDS.iter().position(|f| *f == name).unwrap()
}

#[test]
fn buckets_keep_the_last_value_and_the_peaks() {
    let mut cell = SyntheticCell::new(0.01, 3, true);
    let samples: Vec<CycleSample> = (0..1000).map(|_| cell.next_sample()).collect();
    let mut d = Decimator::default();
    let mut buckets = Vec::new();
    for s in &samples {
        if let Some(b) = d.push(s, 0) {
            buckets.push(b);
        }
    }
    buckets.extend(d.flush());
    // 10 s at 0.04 s a bucket.
    assert!((249..=251).contains(&buckets.len()), "{}", buckets.len());
    let total: f64 = buckets.iter().map(|b| b[index("samples")]).sum();
    assert_eq!(total, 1000.0);
    // Each bucket: the samples whose time lies in [start, start + BUCKET_S).
    let mut k = 0;
    for b in &buckets {
        let n = b[index("samples")] as usize;
        let group = &samples[k..k + n];
        k += n;
        assert!(group.last().unwrap().time_s - group[0].time_s < BUCKET_S);
        let last = group.last().unwrap();
        assert_eq!(b[index("t_s")], last.time_s);
        assert_eq!(b[index("fz_n")], last.wrench_tcp[2]);
        assert_eq!(b[index("xi_z_m")], last.correction[2]);
        let peak = group
            .iter()
            .map(|s| {
                let f = &s.wrench_tcp;
                (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt()
            })
            .fold(f64::MIN, f64::max);
        assert!((b[index("f_norm_max_n")] - peak).abs() < 1e-9);
        let slowest = group
            .iter()
            .map(|s| s.cycle_time_s)
            .fold(f64::MIN, f64::max);
        assert_eq!(b[index("cycle_time_max_s")], slowest);
        let flags = group.iter().fold(0u32, |a, s| a | s.flags);
        assert_eq!(b[index("flags")] as u32, flags);
        let p = last.program_position_m();
        assert_eq!(b[index("prog_x_m")], p.x);
    }
}

#[test]
fn p99_is_the_nearest_rank_over_the_last_cycles() {
    let mut d = Decimator::default();
    let mut times = Vec::new();
    let mut last = None;
    for i in 0..2500u64 {
        // A scrambled sequence with rare spikes.
        let t = 1e-4 * ((i * 7919) % 1000) as f64 + if i % 97 == 0 { 5e-3 } else { 0.0 };
        times.push(t);
        let s = CycleSample {
            time_s: i as f64 * 0.01,
            cycle_time_s: t,
            ..CycleSample::default()
        };
        d.push(&s, 0);
        last = d.flush();
    }
    let window = &times[times.len() - P99_WINDOW..];
    let mut sorted = window.to_vec();
    sorted.sort_by(f64::total_cmp);
    let expected = sorted[(0.99f64 * P99_WINDOW as f64).ceil() as usize - 1];
    assert_eq!(last.unwrap()[index("cycle_time_p99_s")], expected);
}

#[test]
fn a_message_is_a_header_and_little_endian_values() {
    let mut b = [0.0; NFIELDS];
    for (i, v) in b.iter_mut().enumerate() {
        *v = i as f64 * 0.5;
    }
    b[3] = f64::NAN;
    let mut m = frame::encode(frame::KIND_LIVE, &[b, b], 7);
    assert_eq!(m.len(), 16 + 2 * NFIELDS * 8);
    assert_eq!(&m[0..4], &2u32.to_le_bytes());
    assert_eq!(&m[4..8], &2u32.to_le_bytes());
    assert_eq!(&m[8..12], &(NFIELDS as u32).to_le_bytes());
    assert_eq!(&m[12..16], &7u32.to_le_bytes());
    let at = |m: &[u8], k: usize| f64::from_le_bytes(m[16 + 8 * k..24 + 8 * k].try_into().unwrap());
    assert_eq!(at(&m, 5), 2.5);
    assert!(at(&m, 3).is_nan());
    assert_eq!(at(&m, NFIELDS + 1), 0.5);
    frame::set_dropped(&mut m, u64::MAX);
    assert_eq!(&m[12..16], &u32::MAX.to_le_bytes());
}

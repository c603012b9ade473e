#![allow(clippy::needless_range_loop)]

use deflex_io::error::LinkError;
use deflex_io::link::{Correction, RobotLink, RobotSideLink, RobotState};
use deflex_io::staubli::*;
use deflex_model::conventions::{rotation_from_staubli_rxryrz_rad, staubli_rxryrz_rad};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::time::{Duration, Instant};

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn fletcher16_reference_vectors() {
    assert_eq!(fletcher16(b"abcde"), 0xC8F0);
    assert_eq!(fletcher16(b"abcdef"), 0x2057);
    assert_eq!(fletcher16(b"abcdefgh"), 0x0627);
    assert_eq!(fletcher16(b""), 0);
}

#[test]
fn correction_known_layout() {
    let m = CorrectionMsg {
        header: StaubliHeader {
            flags: FLAG_ACTIVE,
            seq: 0x0102_0304,
            ack: 7,
            timestamp_s: 1.5,
        },
        values: [0.001, -0.002, 0.0, 0.0, 0.0, 0.25],
    };
    let mut b = [0u8; 128];
    assert_eq!(encode_correction(&m, &mut b).unwrap(), 74);
    assert_eq!(&b[0..8], b"DFLX\x01\x01\x01\x00");
    assert_eq!(&b[8..16], &[4, 3, 2, 1, 7, 0, 0, 0]);
    assert_eq!(&b[16..24], &1.5f64.to_le_bytes());
    assert_eq!(&b[24..32], &0.001f64.to_le_bytes());
    assert_eq!(&b[64..72], &0.25f64.to_le_bytes());
    let c = fletcher16(&b[..72]).to_le_bytes();
    assert_eq!(&b[72..74], &c);
    assert_eq!(decode_correction(&b[..74]).unwrap(), m);
    assert!(encode_correction(&m, &mut b[..73]).is_err());
}

#[test]
fn state_round_trip_and_errors() {
    let m = StateMsg {
        header: StaubliHeader {
            flags: 0,
            seq: 99,
            ack: 98,
            timestamp_s: 12.25,
        },
        q_rad: [0.1, -0.2, 0.3, -0.4, 0.5, -0.6],
        status: STATUS_ALTER_ACTIVE | STATUS_LIMITED,
    };
    let mut b = [0u8; STATE_LEN];
    encode_state(&m, &mut b).unwrap();
    assert_eq!(decode_state(&b).unwrap(), m);
    // Wrong type, truncation, corruption, trailing bytes.
    assert!(decode_correction(&b).is_err());
    assert!(matches!(
        decode_state(&b[..40]),
        Err(LinkError::Truncated { .. })
    ));
    let mut c = b;
    c[30] ^= 0x10;
    assert!(matches!(decode_state(&c), Err(LinkError::Checksum { .. })));
    let mut c = b;
    c[4] = 2;
    assert!(decode_state(&c).is_err());
    let mut long = b.to_vec();
    long.push(0);
    assert!(decode_state(&long).is_err());
    let nan = StateMsg {
        q_rad: [f64::NAN; 6],
        ..m
    };
    assert!(encode_state(&nan, &mut b).is_err());
}

#[test]
fn euler_xyz_matches_staubli_convention() {
    let mut rng = StdRng::seed_from_u64(5);
    for _ in 0..200 {
        let v = [
            rng.gen_range(-3.0..3.0),
            rng.gen_range(-1.5..1.5),
            rng.gen_range(-3.0..3.0),
        ];
        let back = staubli_rxryrz_rad(&rotation_from_staubli_rxryrz_rad(v), None);
        for i in 0..3 {
            assert!(close(v[i], back[i], 1e-9));
        }
    }
    // Small rotations: Euler angles ≈ rotation vector components.
    let c = Correction {
        dp_m: [0.0; 3],
        dphi_rad: [1e-4, 2e-4, -3e-4],
    };
    let w = correction_to_wire(&c);
    assert!(close(w[3], 1e-4, 1e-7) && close(w[5], -3e-4, 1e-7));
    let back = wire_to_correction(&w);
    for i in 0..3 {
        assert!(close(back.dphi_rad[i], c.dphi_rad[i], 1e-15));
    }
}

#[test]
fn fuzz_decoders_never_panic() {
    let mut rng = StdRng::seed_from_u64(0x5EED_0003);
    let mut valid = [0u8; STATE_LEN];
    encode_state(&StateMsg::default(), &mut valid).unwrap();
    let mut buf = Vec::new();
    for i in 0..30_000 {
        buf.clear();
        if i % 2 == 0 {
            buf.extend((0..rng.gen_range(0..100)).map(|_| rng.r#gen::<u8>()));
            if rng.gen_bool(0.5) && buf.len() >= 6 {
                buf[..4].copy_from_slice(&MAGIC);
                buf[4] = VERSION;
                buf[5] = rng.gen_range(1..3);
            }
        } else {
            buf.extend_from_slice(&valid);
            let j = rng.gen_range(0..buf.len());
            // Fletcher-16 (sums mod 255) cannot see a byte changing by 255
            // (0x00 <-> 0xFF); every other single-byte change is detected.
            buf[j] = buf[j].wrapping_add(rng.gen_range(1..255));
        }
        assert!(decode_state(&buf).is_err());
        assert!(decode_correction(&buf).is_err());
    }
}

#[test]
fn loopback_exchange_and_watchdog() {
    let mut pc = StaubliLink::bind("127.0.0.1:0").unwrap();
    let mut robot = StaubliRobotEndpoint::new(
        "127.0.0.1:0",
        pc.local_addr().unwrap(),
        Duration::from_millis(50),
    )
    .unwrap();
    let t = Duration::from_secs(2);
    assert!(pc.send_correction(&Correction::ZERO).is_err());
    for k in 1..=10u64 {
        let s = RobotState {
            cycle_id: k,
            robot_time_s: Some(0.004 * k as f64),
            status: STATUS_ALTER_ACTIVE,
            ..RobotState::with_joints(&[0.01 * k as f64; 6])
        };
        robot.send_state(&s).unwrap();
        let got = pc.receive(t).unwrap().unwrap();
        assert_eq!((got.cycle_id, got.status), (k, STATUS_ALTER_ACTIVE));
        assert_eq!(got.q_rad, s.q_rad);
        assert_eq!(got.robot_time_s, s.robot_time_s);
        let c = Correction {
            dp_m: [1e-4 * k as f64, 0.0, -1e-3],
            dphi_rad: [0.0, 1e-3, 0.0],
        };
        pc.send_correction(&c).unwrap();
        let rc = robot.receive_correction(t).unwrap().unwrap();
        assert_eq!(rc.cycle_id, k);
        for i in 0..3 {
            assert!(close(rc.correction.dp_m[i], c.dp_m[i], 1e-15));
            assert!(close(rc.correction.dphi_rad[i], c.dphi_rad[i], 1e-12));
        }
        assert_eq!(robot.current_correction(Instant::now()), rc.correction);
    }
    assert_eq!(
        robot.current_correction(Instant::now() + Duration::from_millis(200)),
        Correction::ZERO
    );
    pc.send_inactive().unwrap();
    let rc = robot.receive_correction(t).unwrap().unwrap();
    assert_eq!(rc.correction, Correction::ZERO);
    assert_eq!(robot.current_correction(Instant::now()), Correction::ZERO);
}

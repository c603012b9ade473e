use deflex_io::link::{Correction, RobotLink, RobotSideLink, RobotState};
use deflex_io::simple_udp::*;
use deflex_model::MAX_JOINTS;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::time::Duration;

#[test]
fn known_lines() {
    let mut b = [0u8; LINE_BUFFER];
    let n = format_joints_line(&[0.0, -1.5, 2.0, 0.25, 1e-10, -3.0], &mut b).unwrap();
    assert!(format_joints_line(&[], &mut b).is_err());
    assert!(format_joints_line(&[0.0; 9], &mut b).is_err());
    assert_eq!(
        std::str::from_utf8(&b[..n]).unwrap(),
        "q 0.000000000 -1.500000000 2.000000000 0.250000000 0.000000000 -3.000000000\n"
    );
    let c = Correction {
        dp_m: [0.001, 0.0, -0.5],
        dphi_rad: [0.0, 0.1, 0.0],
    };
    let n = format_correction_line(&c, ReplyStyle::Tuple, &mut b).unwrap();
    assert_eq!(
        std::str::from_utf8(&b[..n]).unwrap(),
        "(0.001000000,0.000000000,-0.500000000,0.000000000,0.100000000,0.000000000)\n"
    );
    assert_eq!(parse_correction_line(&b[..n]).unwrap(), c);
    let n = format_correction_line(&c, ReplyStyle::Keyword, &mut b).unwrap();
    assert!(b.starts_with(b"corr 0.001000000 "));
    assert_eq!(parse_correction_line(&b[..n]).unwrap(), c);
    assert!(format_correction_line(&c, ReplyStyle::Keyword, &mut b[..10]).is_err());
}

#[test]
fn tolerant_parsing_and_errors() {
    let (q, n) = parse_joints_line(b"q [0.1, -1.57, 1.2, 0, 3.25, -6]\r\n").unwrap();
    assert_eq!(&q[..n], &[0.1, -1.57, 1.2, 0.0, 3.25, -6.0]);
    assert_eq!(parse_joints_line(b"Q 1 2 3 4 5 6").unwrap().0[5], 6.0);
    // Any joint count from 1 to 8: a 4-axis palletiser, a 7-axis arm.
    assert_eq!(parse_joints_line(b"q 1 2 3 4").unwrap().1, 4);
    assert_eq!(parse_joints_line(b"q 1 2 3 4 5 6 7").unwrap().1, 7);
    assert_eq!(parse_joints_line(b"q 1 2 3 4 5 6 7 8").unwrap().1, 8);
    for bad in [
        &b"q"[..],
        b"q 1 2 3 4 5 6 7 8 9",
        b"1 2 3 4 5 6",
        b"qq 1 2 3 4 5 6",
        b"q 1 2 3 4 5 nan",
        b"q 1 2 3 4 5 1e999",
        b"q 1 2 3 4 5 x",
        b"",
        &[0xff, 0xfe],
    ] {
        assert!(parse_joints_line(bad).unwrap_err().is_bad_packet());
    }
    assert!(parse_correction_line(b"corrx 1 2 3 4 5 6").is_err());
    assert!(parse_correction_line(b"corr 1 2 3 4 5").is_err());
    assert!(parse_correction_line(b"corr 1 2 3 4 5 6 7").is_err());
}

#[test]
fn fuzz_never_panics() {
    let mut rng = StdRng::seed_from_u64(0x5EED_0005);
    let alphabet = b"qcor ()[],.-+eE0123456789\n\t";
    for i in 0..20_000 {
        let len = rng.gen_range(0..80);
        let b: Vec<u8> = if i % 2 == 0 {
            (0..len).map(|_| rng.r#gen()).collect()
        } else {
            (0..len)
                .map(|_| alphabet[rng.gen_range(0..alphabet.len())])
                .collect()
        };
        if let Ok((q, n)) = parse_joints_line(&b) {
            assert!((1..=MAX_JOINTS).contains(&n) && q.iter().all(|x| x.is_finite()));
        }
        let _ = parse_correction_line(&b);
    }
}

#[test]
fn loopback_exchange() {
    for style in [ReplyStyle::Keyword, ReplyStyle::Tuple] {
        let mut pc = SimpleUdpLink::bind("127.0.0.1:0", style).unwrap();
        let mut robot =
            SimpleUdpRobotEndpoint::new("127.0.0.1:0", pc.local_addr().unwrap()).unwrap();
        let t = Duration::from_secs(2);
        assert!(pc.send_correction(&Correction::ZERO).is_err());
        for k in 1..=5u64 {
            let s = RobotState::with_joints(&[0.123456789 * k as f64; 6]);
            robot.send_state(&s).unwrap();
            let got = pc.receive(t).unwrap().unwrap();
            assert_eq!(got.cycle_id, k);
            assert_eq!(got.joint_count, 6);
            assert!((got.q_rad[0] - s.q_rad[0]).abs() < 1e-9);
            let c = Correction {
                dp_m: [1e-4, 2e-4, 3e-4],
                dphi_rad: [1e-5, 0.0, -1e-5],
            };
            pc.send_correction(&c).unwrap();
            let rc = robot.receive_correction(t).unwrap().unwrap();
            assert_eq!(rc.correction, c);
            assert_eq!(rc.cycle_id, k);
        }
    }
}

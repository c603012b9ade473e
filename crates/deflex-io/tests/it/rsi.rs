#![allow(clippy::needless_range_loop)]

use deflex_io::error::LinkError;
use deflex_io::link::{Correction, RobotLink, RobotSideLink, RobotState};
use deflex_io::rsi::*;
use deflex_model::Pose;
use deflex_model::conventions::{kuka_abc_rad, rotation_from_kuka_abc_rad};
use nalgebra::Translation3;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::time::Duration;

const SAMPLE: &[u8] = br#"<Rob Type="KUKA">
<RIst X="1200.5000" Y="-35.2500" Z="845.1000" A="90.0000" B="-12.5000" C="179.0000"/>
<RSol X="1200.0000" Y="-35.0000" Z="845.0000" A="90.0000" B="-12.0000" C="179.5000"/>
<AIPos A1="10.0000" A2="-90.0000" A3="95.5000" A4="0.0000" A5="45.0000" A6="-180.0000"/>
<Delay D="3"/>
<IPOC>4208138482</IPOC>
</Rob>"#;

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn parses_known_telegram_into_si() {
    let t = parse_rob(SAMPLE).unwrap();
    assert_eq!(t.ipoc, 4208138482);
    assert_eq!(t.delay, 3);
    let p = t.actual_pose.unwrap();
    let abc = kuka_abc_rad(&p.rotation, None);
    assert!(close(p.translation.x, 1.2005, 1e-12));
    assert!(close(p.translation.y, -0.03525, 1e-12));
    assert!(close(abc[0], std::f64::consts::FRAC_PI_2, 1e-12));
    assert!(close(abc[2], 179f64.to_radians(), 1e-12));
    let q = t.q_rad.unwrap();
    assert!(close(q[1], -std::f64::consts::FRAC_PI_2, 1e-12));
    assert!(close(q[5], -std::f64::consts::PI, 1e-12));
    assert!(close(
        kuka_abc_rad(&t.setpoint_pose.unwrap().rotation, None)[1],
        (-12f64).to_radians(),
        1e-12
    ));
}

#[test]
fn names_are_case_insensitive() {
    let doc = br#"<rob type="KUKA"><rist x="1" y="2" z="3" a="4" b="5" c="6"/><aipos a1="1" A2="2" a3="3" A4="4" a5="5" a6="6"/><ipoc>7</ipoc></ROB>"#;
    // End tag case differs from start tag: the scanner requires exact match.
    assert!(parse_rob(doc).is_err());
    let doc = br#"<rob type="KUKA"><rist x="1" y="2" z="3" a="4" b="5" c="6"/><aipos a1="1" A2="2" a3="3" A4="4" a5="5" a6="6"/><ipoc>7</ipoc></rob>"#;
    let t = parse_rob(doc).unwrap();
    assert_eq!(t.ipoc, 7);
    assert!(close(t.actual_pose.unwrap().translation.z, 0.003, 1e-15));
    assert!(close(t.q_rad.unwrap()[3], 4f64.to_radians(), 1e-15));
}

#[test]
fn unknown_elements_and_attributes_are_ignored() {
    let doc = br#"<?xml version="1.0"?><Rob Type="KUKA"><Digin>12</Digin><RIst X="1" Y="2" Z="3" A="4" B="5" C="6" E1="0"/><Tech C11="1"/><IPOC>9</IPOC></Rob>"#;
    let t = parse_rob(doc).unwrap();
    assert_eq!(t.ipoc, 9);
    assert!(t.q_rad.is_none());
}

#[test]
fn rejects_bad_telegrams() {
    for doc in [
        &br#"<Rob Type="KUKA"><RIst X="1" Y="2" Z="3" A="4" B="5" C="6"/></Rob>"#[..],
        br#"<Rob><IPOC>-1</IPOC></Rob>"#,
        br#"<Rob><IPOC>12a</IPOC></Rob>"#,
        br#"<Rob><IPOC/></Rob>"#,
        br#"<Sen><IPOC>1</IPOC></Sen>"#,
        br#"<Rob><RIst X="1" Y="2" Z="3" A="4" B="5"/><IPOC>1</IPOC></Rob>"#,
        br#"<Rob><RIst X="nan" Y="2" Z="3" A="4" B="5" C="6"/><IPOC>1</IPOC></Rob>"#,
        br#"<Rob><RIst X="1e999" Y="2" Z="3" A="4" B="5" C="6"/><IPOC>1</IPOC></Rob>"#,
        br#"<Rob><Delay D="99999999999"/><IPOC>1</IPOC></Rob>"#,
        br#"<Rob><IPOC>1</IPOC>"#,
        b"",
        b"garbage",
    ] {
        let e = parse_rob(doc).unwrap_err();
        assert!(e.is_bad_packet(), "{e}");
    }
    assert!(parse_sen(br#"<Sen Type="x"><IPOC>1</IPOC></Sen>"#).is_err());
}

#[test]
fn rob_round_trip_within_printed_precision() {
    let mut rng = StdRng::seed_from_u64(7);
    let mut buf = [0u8; TX_BUFFER];
    for _ in 0..500 {
        let mut t = RobTelegram {
            actual_pose: Some(Pose::from_parts(
                Translation3::new(
                    rng.gen_range(-3.0..3.0),
                    rng.gen_range(-3.0..3.0),
                    rng.gen_range(-3.0..3.0),
                ),
                rotation_from_kuka_abc_rad([
                    rng.gen_range(-3.0..3.0),
                    rng.gen_range(-1.5..1.5),
                    rng.gen_range(-3.0..3.0),
                ]),
            )),
            setpoint_pose: None,
            q_rad: Some([0.0; 6].map(|_: f64| rng.gen_range(-6.0..6.0))),
            delay: rng.r#gen(),
            ipoc: rng.r#gen(),
        };
        if rng.gen_bool(0.3) {
            t.setpoint_pose = t.actual_pose;
        }
        let n = format_rob(&t, &mut buf).unwrap();
        let back = parse_rob(&buf[..n]).unwrap();
        assert_eq!(back.ipoc, t.ipoc);
        assert_eq!(back.delay, t.delay);
        assert_eq!(back.setpoint_pose.is_some(), t.setpoint_pose.is_some());
        let (a, b) = (t.actual_pose.unwrap(), back.actual_pose.unwrap());
        let (a_abc, b_abc) = (
            kuka_abc_rad(&a.rotation, None),
            kuka_abc_rad(&b.rotation, None),
        );
        for i in 0..3 {
            assert!(close(
                a.translation.vector[i],
                b.translation.vector[i],
                0.51e-7
            ));
            assert!(close(a_abc[i], b_abc[i], 0.51e-4f64.to_radians()));
        }
        for (x, y) in t.q_rad.unwrap().iter().zip(back.q_rad.unwrap()) {
            assert!(close(*x, y, 0.51e-4f64.to_radians()));
        }
    }
}

#[test]
fn sen_known_bytes_and_round_trip() {
    let mut buf = [0u8; TX_BUFFER];
    let rk = [
        0.001,
        -0.0005,
        0.0,
        1f64.to_radians(),
        0.0,
        -0.5f64.to_radians(),
    ];
    let n = format_sen(&rk, 42, "ImFree", Some("deflex"), &mut buf).unwrap();
    assert_eq!(
        std::str::from_utf8(&buf[..n]).unwrap(),
        r#"<Sen Type="ImFree"><EStr>deflex</EStr><RKorr X="1.0000" Y="-0.5000" Z="0.0000" A="1.0000" B="0.0000" C="-0.5000"/><IPOC>42</IPOC></Sen>"#
    );
    let back = parse_sen(&buf[..n]).unwrap();
    assert_eq!(back.ipoc, 42);
    let rkorr = back.rkorr.unwrap();
    for i in 0..6 {
        assert!(close(rkorr[i], rk[i], 1e-12));
    }
    assert!(format_sen(&rk, 1, "Im Free", None, &mut buf).is_err());
    assert!(format_sen(&rk, 1, "ImFree", Some("<x>"), &mut buf).is_err());
    assert!(format_sen(&[f64::NAN; 6], 1, "ImFree", None, &mut buf).is_err());
    assert!(matches!(
        format_sen(&rk, 1, "ImFree", None, &mut buf[..20]),
        Err(LinkError::BufferTooSmall { .. })
    ));
}

fn mutate(rng: &mut StdRng, src: &[u8], out: &mut Vec<u8>) {
    out.clear();
    out.extend_from_slice(src);
    for _ in 0..rng.gen_range(1..6) {
        if out.is_empty() {
            break;
        }
        let i = rng.gen_range(0..out.len());
        match rng.gen_range(0..5) {
            0 => out[i] = rng.r#gen(),
            1 => {
                out.remove(i);
            }
            2 => out.insert(i, b"<>\"'/=!?-[]0123456789.eE"[rng.gen_range(0..24)]),
            3 => out.truncate(i),
            _ => {
                let j = rng.gen_range(i..out.len());
                let chunk: Vec<u8> = out[i..j].to_vec();
                out.splice(i..i, chunk);
            }
        }
    }
}

#[test]
fn fuzz_random_and_mutated_telegrams_never_panic() {
    let mut rng = StdRng::seed_from_u64(0x5EED_0001);
    let mut sen = [0u8; TX_BUFFER];
    let n = format_sen(&[0.001; 6], 77, "ImFree", Some("hi"), &mut sen).unwrap();
    let sen = &sen[..n];
    let mut buf = Vec::new();
    let mut ok = 0;
    for i in 0..30_000 {
        if i % 3 == 0 {
            buf.clear();
            let len = rng.gen_range(0..300);
            buf.extend((0..len).map(|_| rng.r#gen::<u8>()));
        } else if i % 3 == 1 {
            mutate(&mut rng, SAMPLE, &mut buf);
        } else {
            mutate(&mut rng, sen, &mut buf);
        }
        match parse_rob(&buf) {
            Ok(t) => {
                ok += 1;
                assert!(t.q_rad.is_none_or(|q| q.iter().all(|x| x.is_finite())));
            }
            Err(e) => assert!(e.is_bad_packet()),
        }
        if let Err(e) = parse_sen(&buf) {
            assert!(e.is_bad_packet());
        }
    }
    // Some mutations (e.g. of whitespace) keep the telegram valid.
    assert!(ok > 0);
}

#[test]
fn loopback_exchange_absolute_and_relative() {
    for mode in [CorrectionMode::Absolute, CorrectionMode::Relative] {
        let cfg = RsiConfig {
            mode,
            estr: Some("ok".into()),
            ..RsiConfig::default()
        };
        let mut pc = RsiLink::bind("127.0.0.1:0", cfg).unwrap();
        let mut robot =
            RsiRobotEndpoint::new("127.0.0.1:0", pc.local_addr().unwrap(), mode).unwrap();
        let timeout = Duration::from_secs(2);
        assert!(matches!(
            pc.send_correction(&Correction::ZERO),
            Err(LinkError::NoPeer { .. })
        ));
        let mut last = Correction::ZERO;
        for k in 0..20u64 {
            let mut state = RobotState::with_joints(&[0.1 * k as f64, -1.0, 1.2, 0.0, 0.5, -0.3]);
            state.tcp_pose = Some(Pose::from_parts(
                Translation3::new(1.0, 0.0, 0.8),
                rotation_from_kuka_abc_rad([0.0, 0.1, 3.0]),
            ));
            state.cycle_id = 1000 + k;
            robot.send_state(&state).unwrap();
            let got = pc.receive(timeout).unwrap().unwrap();
            assert_eq!(got.cycle_id, 1000 + k);
            assert!(close(got.q_rad[0], state.q_rad[0], 1e-6));
            let kf = k as f64;
            let c = Correction {
                dp_m: [1e-4 * kf, -2e-5 * kf, 3e-6],
                dphi_rad: [1e-4 * kf, 0.0, -2e-4],
            };
            pc.send_correction(&c).unwrap();
            let rc = robot.receive_correction(timeout).unwrap().unwrap();
            assert_eq!(rc.cycle_id, 1000 + k);
            for i in 0..3 {
                assert!(
                    close(rc.correction.dp_m[i], c.dp_m[i], 1e-7),
                    "{mode:?} {rc:?} {c:?}"
                );
                assert!(close(rc.correction.dphi_rad[i], c.dphi_rad[i], 3e-6));
            }
            last = rc.correction;
        }
        assert!(close(last.dp_m[0], 19e-4, 1e-7));
        assert!(
            robot
                .receive_correction(Duration::from_millis(5))
                .unwrap()
                .is_none()
        );
    }
}

#[test]
fn malformed_datagram_is_an_error_and_link_survives() {
    let mut pc = RsiLink::bind("127.0.0.1:0", RsiConfig::default()).unwrap();
    let sock = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    sock.send_to(b"<Rob><IPOC>oops</IPOC></Rob>", pc.local_addr().unwrap())
        .unwrap();
    let e = pc.receive(Duration::from_secs(2)).unwrap_err();
    assert!(e.is_bad_packet());
    sock.send_to(SAMPLE, pc.local_addr().unwrap()).unwrap();
    let s = pc.receive(Duration::from_secs(2)).unwrap().unwrap();
    assert_eq!(s.cycle_id, 4208138482);
    assert_eq!(s.late_answers, Some(3));
    pc.send_correction(&Correction::ZERO).unwrap();
    let mut b = [0u8; 512];
    sock.set_read_timeout(Some(Duration::from_secs(2))).unwrap();
    let n = sock.recv(&mut b).unwrap();
    assert_eq!(parse_sen(&b[..n]).unwrap().ipoc, 4208138482);
}

/// The `X="…"` attribute of element `tag` in `text`, parsed by hand (no
/// deflex parser involved).
fn attr(text: &str, tag: &str, name: &str) -> f64 {
    let start = text.find(&format!("<{tag} ")).expect("tag present");
    let rest = &text[start..];
    let at = rest
        .find(&format!(" {name}=\""))
        .expect("attribute present")
        + name.len()
        + 3;
    let end = rest[at..].find('"').unwrap();
    rest[at..at + end].parse().unwrap()
}

#[test]
fn no_negative_zero_is_ever_printed() {
    let mut buf = [0u8; TX_BUFFER];
    let tiny = [-1e-9, -4.9e-8, 1e-9, -0.0, -4.99e-7f64.to_radians(), 0.0];
    let n = format_sen(&tiny, 1, "ImFree", None, &mut buf).unwrap();
    let text = std::str::from_utf8(&buf[..n]).unwrap();
    assert!(!text.contains("-0.0000"), "{text}");
    assert_eq!(
        text,
        r#"<Sen Type="ImFree"><RKorr X="0.0000" Y="0.0000" Z="0.0000" A="0.0000" B="0.0000" C="0.0000"/><IPOC>1</IPOC></Sen>"#
    );
    // The smallest value that prints non-zero keeps its sign.
    let n = format_sen(
        &[-6e-8, 0.0, 0.0, 0.0, 0.0, 0.0],
        1,
        "ImFree",
        None,
        &mut buf,
    )
    .unwrap();
    assert!(
        std::str::from_utf8(&buf[..n])
            .unwrap()
            .contains(r#"X="-0.0001""#)
    );
    let n = format_sen_joints(JointTag::Ak, &[-1e-12; 6], 1, "ImFree", None, &mut buf).unwrap();
    assert!(!std::str::from_utf8(&buf[..n]).unwrap().contains("-0.0000"));
    let t = RobTelegram {
        q_rad: Some([-1e-10; 6]),
        ipoc: 3,
        ..Default::default()
    };
    let n = format_rob(&t, &mut buf).unwrap();
    assert!(!std::str::from_utf8(&buf[..n]).unwrap().contains("-0.0000"));
}

#[test]
fn joint_answers_known_bytes() {
    let mut buf = [0u8; TX_BUFFER];
    let dq = [1.0, -0.5, 0.0, 2.25, 0.0, -10.0].map(f64::to_radians);
    let n = format_sen_joints(JointTag::Ak, &dq, 7, "ImFree", None, &mut buf).unwrap();
    assert_eq!(
        std::str::from_utf8(&buf[..n]).unwrap(),
        r#"<Sen Type="ImFree"><AK A1="1.0000" A2="-0.5000" A3="0.0000" A4="2.2500" A5="0.0000" A6="-10.0000"/><IPOC>7</IPOC></Sen>"#
    );
    let back = parse_sen(&buf[..n]).unwrap();
    assert!(back.rkorr.is_none());
    let j = back.joints_rad.unwrap();
    for i in 0..6 {
        assert!(close(j[i], dq[i], 1e-12));
    }
    let n = format_sen_joints(JointTag::AKorr, &dq, 7, "ImFree", None, &mut buf).unwrap();
    assert!(
        std::str::from_utf8(&buf[..n])
            .unwrap()
            .contains("<AKorr A1=")
    );
    assert!(parse_sen(&buf[..n]).unwrap().joints_rad.is_some());
    assert!(parse_sen(b"<Sen Type=\"ImFree\"><IPOC>1</IPOC></Sen>").is_err());
}

/// A KUKA emulator in relative mode that discards some answers (as RSI does
/// with a late answer) and counts them in `Delay`: the robot's accumulated
/// correction still ends on the controller's total. The robot side here is
/// written with the socket and a hand parser, not with deflex's endpoint.
#[test]
fn relative_mode_does_not_drift_when_answers_are_lost() {
    let cfg = RsiConfig {
        mode: CorrectionMode::Relative,
        ..RsiConfig::default()
    };
    let mut pc = RsiLink::bind("127.0.0.1:0", cfg).unwrap();
    let robot = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    robot
        .set_read_timeout(Some(Duration::from_secs(2)))
        .unwrap();
    let to = pc.local_addr().unwrap();
    let dropped_at = [17u64, 18, 50, 51, 52, 120];
    let (mut delay, mut applied_mm, mut lost_mm) = (0u32, 0.0f64, 0.0f64);
    let mut total_mm = 0.0;
    let mut rb = [0u8; 1024];
    for k in 1..=200u64 {
        let telegram = format!(
            "<Rob Type=\"KUKA\"><AIPos A1=\"0\" A2=\"-90\" A3=\"90\" A4=\"0\" A5=\"0\" A6=\"0\"/>\
             <Delay D=\"{delay}\"/><IPOC>{k}</IPOC></Rob>"
        );
        robot.send_to(telegram.as_bytes(), to).unwrap();
        let s = pc.receive(Duration::from_secs(2)).unwrap().unwrap();
        assert_eq!(s.late_answers, Some(delay));
        // A wavy total correction, in metres.
        let total = 1e-3 * (0.02 * k as f64).sin() + 1e-5 * k as f64;
        total_mm = total * 1e3;
        pc.send_correction(&Correction {
            dp_m: [total, 0.0, 0.0],
            dphi_rad: [0.0; 3],
        })
        .unwrap();
        let n = robot.recv(&mut rb).unwrap();
        let answer = std::str::from_utf8(&rb[..n]).unwrap();
        let x = attr(answer, "RKorr", "X");
        if dropped_at.contains(&k) {
            delay += 1;
            lost_mm += x;
        } else {
            applied_mm += x;
        }
    }
    assert!(
        lost_mm.abs() > 0.01,
        "the dropped answers must matter: {lost_mm} mm"
    );
    // Equal up to the printing of the last total (four decimals of a mm).
    assert!(
        (applied_mm - total_mm).abs() <= 0.5e-4 + 1e-9,
        "robot accumulated {applied_mm} mm, controller total {total_mm} mm"
    );
    assert_eq!(pc.rolled_back(), dropped_at.len() as u64);
}

/// Only the robot's datagrams are answered: a stranger is refused, counted
/// and never becomes the peer.
#[test]
fn stray_sender_is_refused_and_not_answered() {
    let mut pc = RsiLink::bind("127.0.0.1:0", RsiConfig::default()).unwrap();
    let to = pc.local_addr().unwrap();
    let robot = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let stranger = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    for s in [&robot, &stranger] {
        s.set_read_timeout(Some(Duration::from_millis(200)))
            .unwrap();
    }
    robot.send_to(SAMPLE, to).unwrap();
    assert!(pc.receive(Duration::from_secs(2)).unwrap().is_some());
    stranger.send_to(SAMPLE, to).unwrap();
    let e = pc.receive(Duration::from_secs(2)).unwrap_err();
    assert!(e.is_foreign(), "{e}");
    // The answer still goes to the robot, echoing the robot's IPOC.
    pc.send_correction(&Correction::ZERO).unwrap();
    let mut b = [0u8; 512];
    let n = robot.recv(&mut b).unwrap();
    assert_eq!(parse_sen(&b[..n]).unwrap().ipoc, 4208138482);
    assert!(stranger.recv(&mut b).is_err(), "the stranger got an answer");
    assert_eq!(pc.peers().foreign(), 1);
    assert_eq!(
        pc.peers().last_foreign(),
        Some(stranger.local_addr().unwrap())
    );
    // With a configured robot address, even the first sender must match.
    let mut pc = RsiLink::bind("127.0.0.1:0", RsiConfig::default()).unwrap();
    pc.expect_peer(robot.local_addr().unwrap());
    stranger.send_to(SAMPLE, pc.local_addr().unwrap()).unwrap();
    assert!(pc.receive(Duration::from_secs(2)).unwrap_err().is_foreign());
    robot.send_to(SAMPLE, pc.local_addr().unwrap()).unwrap();
    assert!(pc.receive(Duration::from_secs(2)).unwrap().is_some());
}

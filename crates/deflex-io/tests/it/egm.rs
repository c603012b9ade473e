#![allow(clippy::needless_range_loop)]

use deflex_io::egm::*;
use deflex_io::error::LinkError;
use deflex_io::link::{Correction, RobotLink, RobotSideLink, RobotState};
use deflex_model::Pose;
use deflex_model::conventions::{kuka_abc_rad, rotation_from_kuka_abc_rad};
use nalgebra::{Matrix3, Rotation3, Translation3, Vector3};
use prost::Message;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::time::Duration;

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn path_corr_known_bytes() {
    let mut buf = [0u8; 128];
    let n = encode_path_corr(1, 2, [0.001, 0.0, -0.0025], 4, &mut buf).unwrap();
    let mut want = vec![
        0x0a, 0x06, 0x08, 0x01, 0x10, 0x02, 0x18, 0x04, 0x12, 0x1f, 0x0a, 0x1b, 0x09,
    ];
    want.extend_from_slice(&1.0f64.to_le_bytes());
    want.push(0x11);
    want.extend_from_slice(&0.0f64.to_le_bytes());
    want.push(0x19);
    want.extend_from_slice(&(-2.5f64).to_le_bytes());
    want.extend_from_slice(&[0x10, 0x04]);
    assert_eq!(&buf[..n], &want[..]);
    let f = decode_path_corr(&buf[..n]).unwrap();
    assert_eq!(f.seqno, Some(1));
    assert_eq!(f.tm_ms, Some(2));
    assert_eq!(f.age_ms, 4);
    assert!(close(f.dp_m[0], 0.001, 1e-15) && close(f.dp_m[2], -0.0025, 1e-15));
    assert!(matches!(
        encode_path_corr(1, 2, [0.0; 3], 4, &mut buf[..10]),
        Err(LinkError::BufferTooSmall { .. })
    ));
    assert!(encode_path_corr(1, 2, [f64::INFINITY, 0.0, 0.0], 4, &mut buf).is_err());
}

#[test]
fn robot_known_bytes_decoded_by_hand_walker() {
    // header {seqno: 5, tm: 300, mtype: DATA}, feedBack {joints {90, -45 (unpacked)}}
    let mut b = vec![
        0x0a, 0x07, 0x08, 0x05, 0x10, 0xac, 0x02, 0x18, 0x02, 0x12, 0x14, 0x0a, 0x12, 0x09,
    ];
    b.extend_from_slice(&90.0f64.to_le_bytes());
    b.push(0x09);
    b.extend_from_slice(&(-45.0f64).to_le_bytes());
    let f = decode_robot(&b).unwrap();
    assert_eq!(
        (f.seqno, f.tm_ms, f.mtype, f.n_joints),
        (Some(5), Some(300), Some(2), 2)
    );
    assert!(close(f.q_rad[0], std::f64::consts::FRAC_PI_2, 1e-15));
    assert!(close(f.q_rad[1], -std::f64::consts::FRAC_PI_4, 1e-15));
    // Same joints, packed encoding (wire type 2).
    let mut p = vec![0x12, 0x14, 0x0a, 0x12, 0x0a, 0x10];
    p.extend_from_slice(&90.0f64.to_le_bytes());
    p.extend_from_slice(&(-45.0f64).to_le_bytes());
    let g = decode_robot(&p).unwrap();
    assert_eq!(g.n_joints, 2);
    assert_eq!(g.q_rad, f.q_rad);
}

fn random_state(rng: &mut StdRng) -> RobotState {
    let mut s = RobotState::with_joints(&[0.0; 6].map(|_: f64| rng.gen_range(-3.0..3.0)));
    s.tcp_pose = rng.gen_bool(0.8).then(|| {
        let position_m = [0.0; 3].map(|_: f64| rng.gen_range(-2.0..2.0));
        Pose::from_parts(
            Translation3::from(position_m),
            rotation_from_kuka_abc_rad([
                rng.gen_range(-3.0..3.0),
                rng.gen_range(-1.5..1.5),
                rng.gen_range(-3.0..3.0),
            ]),
        )
    });
    s.cycle_id = u64::from(rng.r#gen::<u32>());
    s.robot_time_s = Some(f64::from(rng.gen_range(0u32..1_000_000)) * 1e-3);
    s
}

#[test]
fn hand_walker_agrees_with_prost_and_round_trips() {
    let mut rng = StdRng::seed_from_u64(11);
    let mut m = msg::EgmRobot::default();
    for _ in 0..500 {
        let s = random_state(&mut rng);
        let tm = (s.robot_time_s.unwrap() * 1e3).round() as u32;
        fill_robot_msg(&mut m, &s, s.cycle_id as u32, tm, false);
        m.utilization_rate = rng.gen_bool(0.5).then_some(12.5);
        m.planned = rng.gen_bool(0.5).then(|| m.feed_back.clone().unwrap());
        let bytes = m.encode_to_vec();
        let f = decode_robot(&bytes).unwrap();
        let p = msg::EgmRobot::decode(&bytes[..]).unwrap();
        assert_eq!(f.seqno, p.header.as_ref().unwrap().seqno);
        assert_eq!(f.tm_ms, Some(tm));
        let pj = &p
            .feed_back
            .as_ref()
            .unwrap()
            .joints
            .as_ref()
            .unwrap()
            .joints;
        assert_eq!(f.n_joints, pj.len());
        for i in 0..6 {
            assert!(close(f.q_rad[i], pj[i].to_radians(), 1e-15));
            assert!(close(f.q_rad[i], s.q_rad[i], 1e-12));
        }
        match (s.tcp_pose, f.tcp_pose) {
            (None, None) => {}
            (Some(a), Some(b)) => {
                let (a_zyx, b_zyx) = (
                    kuka_abc_rad(&a.rotation, None),
                    kuka_abc_rad(&b.rotation, None),
                );
                for i in 0..3 {
                    assert!(close(
                        a.translation.vector[i],
                        b.translation.vector[i],
                        1e-12
                    ));
                    assert!(close(a_zyx[i], b_zyx[i], 1e-9), "{a:?} {b:?}");
                }
            }
            other => panic!("{other:?}"),
        }
    }
}

#[test]
fn euler_orientation_is_zyx_degrees() {
    let m = msg::EgmRobot {
        header: None,
        feed_back: Some(msg::EgmFeedBack {
            joints: None,
            cartesian: Some(msg::EgmPose {
                pos: Some(msg::EgmCartesian {
                    x: 1.0,
                    y: 2.0,
                    z: 3.0,
                }),
                orient: None,
                euler: Some(msg::EgmEuler {
                    x: 10.0,
                    y: 20.0,
                    z: 30.0,
                }),
            }),
            external_joints: None,
            time: None,
        }),
        planned: None,
        utilization_rate: None,
    };
    let f = decode_robot(&m.encode_to_vec()).unwrap();
    let p = f.tcp_pose.unwrap();
    let zyx = kuka_abc_rad(&p.rotation, None);
    assert!(close(zyx[0], 30f64.to_radians(), 1e-15));
    assert!(close(zyx[2], 10f64.to_radians(), 1e-15));
    assert!(close(p.translation.z, 0.003, 1e-15));
}

#[test]
fn rejects_malformed() {
    for b in [
        &[0x0a, 0x05, 0x08][..],       // header longer than the buffer
        &[0x08][..],                   // truncated varint
        &[0x00, 0x01][..],             // field 0
        &[0x0b][..],                   // group wire type
        &[0x0a, 0x02, 0x09, 0x01][..], // seqno with fixed64 wire type, truncated
        &[0xff; 11][..],               // over-long varint
        &[0x12, 0x03, 0x0a, 0x01, 0x0d][..],
    ] {
        assert!(decode_robot(b).unwrap_err().is_bad_packet(), "{b:?}");
    }
    // Seven joints in `joints` (EGM carries at most six there).
    let m = msg::EgmRobot {
        feed_back: Some(msg::EgmFeedBack {
            joints: Some(msg::EgmJoints {
                joints: vec![0.0; 7],
            }),
            ..Default::default()
        }),
        ..Default::default()
    };
    assert!(decode_robot(&m.encode_to_vec()).is_err());
    // NaN joint.
    let m = msg::EgmRobot {
        feed_back: Some(msg::EgmFeedBack {
            joints: Some(msg::EgmJoints {
                joints: vec![f64::NAN],
            }),
            ..Default::default()
        }),
        ..Default::default()
    };
    assert!(decode_robot(&m.encode_to_vec()).is_err());
    assert!(decode_path_corr(&[]).is_err()); // no pathCorr
    assert!(decode_path_corr(&[0x12, 0x40]).is_err());
}

#[test]
fn fuzz_decoders_never_panic() {
    let mut rng = StdRng::seed_from_u64(0x5EED_0002);
    let mut m = msg::EgmRobot::default();
    fill_robot_msg(&mut m, &random_state(&mut rng), 1, 2, false);
    let valid_robot = m.encode_to_vec();
    let mut pc = [0u8; 128];
    let n = encode_path_corr(3, 4, [0.001, 0.002, 0.003], 5, &mut pc).unwrap();
    let valid_pc = pc[..n].to_vec();
    let mut buf = Vec::new();
    let mut ok = 0usize;
    for i in 0..30_000 {
        buf.clear();
        match i % 3 {
            0 => buf.extend((0..rng.gen_range(0..200)).map(|_| rng.r#gen::<u8>())),
            1 => buf.extend_from_slice(&valid_robot),
            _ => buf.extend_from_slice(&valid_pc),
        }
        if i % 3 != 0 {
            for _ in 0..rng.gen_range(1..4) {
                let j = rng.gen_range(0..buf.len());
                match rng.gen_range(0..3) {
                    0 => buf[j] = rng.r#gen(),
                    1 => buf.truncate(j),
                    _ => buf.insert(j, rng.r#gen()),
                }
                if buf.is_empty() {
                    break;
                }
            }
        }
        if decode_robot(&buf).is_ok() {
            ok += 1;
        }
        let _ = decode_path_corr(&buf);
        let _ = msg::EgmRobot::decode(&buf[..]);
    }
    assert!(ok > 0);
}

#[test]
fn loopback_exchange() {
    let cfg = EgmConfig {
        frame: EgmFrame::Base,
        age_ms: 8,
        ..EgmConfig::default()
    };
    let mut pc = EgmLink::bind("127.0.0.1:0", cfg).unwrap();
    let mut robot = EgmRobotEndpoint::new("127.0.0.1:0", pc.local_addr().unwrap()).unwrap();
    let t = Duration::from_secs(2);
    assert!(matches!(
        pc.send_correction(&Correction::ZERO),
        Err(LinkError::NoPeer { .. })
    ));
    let mut rng = StdRng::seed_from_u64(3);
    for k in 0..20u64 {
        let mut s = random_state(&mut rng);
        // A robot's clock and sequence number advance (the link drops messages whose do not).
        s.cycle_id = k;
        s.robot_time_s = Some(0.004 * k as f64);
        robot.send_state(&s).unwrap();
        let got = pc.receive(t).unwrap().unwrap();
        assert_eq!(got.cycle_id, k);
        for i in 0..6 {
            assert!(close(got.q_rad[i], s.q_rad[i], 1e-12));
        }
        let c = Correction {
            dp_m: [1e-4 * k as f64, -2e-4, 3e-5],
            dphi_rad: [0.1, 0.0, 0.0],
        };
        pc.send_correction(&c).unwrap();
        let rc = robot.receive_correction(t).unwrap().unwrap();
        assert_eq!(rc.cycle_id, k + 1);
        for i in 0..3 {
            assert!(close(rc.correction.dp_m[i], c.dp_m[i], 1e-15));
        }
        assert_eq!(rc.correction.dphi_rad, [0.0; 3]);
    }
    assert_eq!(pc.last_frame().unwrap().mtype, Some(MTYPE_DATA));
}

/// A minimal protobuf reader written for this test from the field numbers
/// of ABB's official egm.proto (EgmSensorPathCorr: header = 1, pathCorr = 2;
/// EgmPathCorr: pos = 1, age = 2; EgmCartesian: x = 1, y = 2, z = 3, all
/// doubles), independent of deflex's encoder and decoders.
fn hand_decode_path_corr_pos(b: &[u8]) -> [f64; 3] {
    fn varint(b: &[u8], i: &mut usize) -> u64 {
        let (mut v, mut shift) = (0u64, 0);
        loop {
            let byte = b[*i];
            *i += 1;
            v |= u64::from(byte & 0x7f) << shift;
            if byte & 0x80 == 0 {
                return v;
            }
            shift += 7;
        }
    }
    /// The body of length-delimited field `want` of message `b`.
    fn field(b: &[u8], want: u64) -> &[u8] {
        let mut i = 0;
        while i < b.len() {
            let key = varint(b, &mut i);
            let (num, wire) = (key >> 3, key & 7);
            match wire {
                0 => {
                    varint(b, &mut i);
                }
                1 => i += 8,
                5 => i += 4,
                2 => {
                    let len = varint(b, &mut i) as usize;
                    if num == want {
                        return &b[i..i + len];
                    }
                    i += len;
                }
                w => panic!("wire type {w}"),
            }
        }
        panic!("field {want} missing");
    }
    let pos = field(field(b, 2), 1);
    let mut out = [f64::NAN; 3];
    let mut i = 0;
    while i < pos.len() {
        let key = varint(pos, &mut i);
        assert_eq!(key & 7, 1, "doubles are fixed64");
        let v = f64::from_le_bytes(pos[i..i + 8].try_into().unwrap());
        out[(key >> 3) as usize - 1] = v;
        i += 8;
    }
    out
}

/// Tool pointing down (the TCP frame is the base frame turned 180° about x):
/// a correction of (1, 2, −3) mm in base axes is (1, −2, +3) mm in the tool
/// (sensor) frame, the frame egm.proto says `pathCorr.pos` is in; with the
/// sensor frame turned 90° about the tool's z it is (−2, −1, +3) mm. Checked
/// on the bytes with the hand decoder above.
#[test]
fn path_correction_is_sent_in_the_tool_frame_with_the_right_sign() {
    let tool_down = rotation_rows([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]]);
    let rz90 = rotation_rows([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]);
    for (sensor_in_tool, frame, want) in [
        (
            EgmConfig::default().sensor_in_tool,
            EgmFrame::Tool,
            [1.0, -2.0, 3.0],
        ),
        (rz90, EgmFrame::Tool, [-2.0, -1.0, 3.0]),
        (rz90, EgmFrame::Base, [1.0, 2.0, -3.0]),
    ] {
        let cfg = EgmConfig {
            frame,
            sensor_in_tool,
            ..EgmConfig::default()
        };
        let mut pc = EgmLink::bind("127.0.0.1:0", cfg).unwrap();
        let robot = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
        robot
            .set_read_timeout(Some(Duration::from_secs(2)))
            .unwrap();
        let mut m = msg::EgmRobot::default();
        fill_robot_msg(&mut m, &RobotState::with_joints(&[0.0; 6]), 1, 4, false);
        robot
            .send_to(&m.encode_to_vec(), pc.local_addr().unwrap())
            .unwrap();
        pc.receive(Duration::from_secs(2)).unwrap().unwrap();
        pc.set_tcp_rotation(&tool_down);
        pc.send_correction(&Correction {
            dp_m: [1e-3, 2e-3, -3e-3],
            dphi_rad: [0.0; 3],
        })
        .unwrap();
        let mut b = [0u8; 256];
        let n = robot.recv(&mut b).unwrap();
        let pos = hand_decode_path_corr_pos(&b[..n]);
        for i in 0..3 {
            assert!(
                close(pos[i], want[i], 1e-12),
                "{frame:?}: {pos:?} vs {want:?}"
            );
        }
    }
}

/// The work-object frame uses the configured work-object orientation, not
/// the tool's.
#[test]
fn work_object_frame_ignores_the_tool() {
    let wobj = rotation_rows([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]);
    let cfg = EgmConfig {
        frame: EgmFrame::WorkObject,
        work_object_in_base: wobj,
        ..EgmConfig::default()
    };
    let r = cfg.correction_frame(&rotation_rows([
        [1.0, 0.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, -1.0],
    ]));
    assert_eq!(r, wobj);
    // Base x (1, 0, 0) is the work object's −y.
    let v = r.inverse_transform_vector(&Vector3::new(1.0, 0.0, 0.0));
    assert!(close(v[0], 0.0, 1e-15) && close(v[1], -1.0, 1e-15));
}

/// A rotation from its rows, as the tests above write them.
fn rotation_rows(rows: [[f64; 3]; 3]) -> Rotation3<f64> {
    Rotation3::from_matrix_unchecked(Matrix3::from_fn(|i, j| rows[i][j]))
}

/// EGM carries as many robot joints as the arm has (a 4-axis palletiser
/// sends 4), and ABB's seven-axis arms send axis 3 as the first external
/// joint: both arrive in chain order.
#[test]
fn joint_counts_other_than_six() {
    let mut b = [0u8; 256];
    for (seven, q) in [
        (false, vec![0.1, -0.2, 0.3, 0.4]),
        (true, vec![0.1, -0.2, 0.7, 0.3, 0.4, -0.5, 0.6]),
    ] {
        let cfg = EgmConfig {
            seven_axis: seven,
            ..EgmConfig::default()
        };
        let mut pc = EgmLink::bind("127.0.0.1:0", cfg).unwrap();
        let mut robot = EgmRobotEndpoint::new("127.0.0.1:0", pc.local_addr().unwrap()).unwrap();
        robot.set_seven_axis(seven);
        robot.send_state(&RobotState::with_joints(&q)).unwrap();
        let s = pc.receive(Duration::from_secs(2)).unwrap().unwrap();
        assert_eq!(s.joint_count, q.len());
        for (a, b) in s.joints().iter().zip(&q) {
            assert!(close(*a, *b, 1e-12), "{:?} vs {q:?}", s.joints());
        }
        if seven {
            // On the wire: six joints, axis 3 as external joint 1.
            let mut m = msg::EgmRobot::default();
            fill_robot_msg(&mut m, &RobotState::with_joints(&q), 1, 1, true);
            let fb = m.feed_back.unwrap();
            assert_eq!(fb.joints.unwrap().joints.len(), 6);
            assert!(close(
                fb.external_joints.unwrap().joints[0],
                0.7f64.to_degrees(),
                1e-12
            ));
        }
    }
    // A seven-axis configuration refuses a message without the external joint.
    let mut pc = EgmLink::bind(
        "127.0.0.1:0",
        EgmConfig {
            seven_axis: true,
            ..EgmConfig::default()
        },
    )
    .unwrap();
    let mut m = msg::EgmRobot::default();
    fill_robot_msg(&mut m, &RobotState::with_joints(&[0.0; 6]), 1, 1, false);
    let n = {
        let mut w = &mut b[..];
        m.encode(&mut w).unwrap();
        256 - w.len()
    };
    let sock = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    sock.send_to(&b[..n], pc.local_addr().unwrap()).unwrap();
    assert!(
        pc.receive(Duration::from_secs(2))
            .unwrap_err()
            .is_bad_packet()
    );
}

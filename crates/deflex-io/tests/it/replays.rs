//! Issue 18, item 11 and "the same rules for RSI, Stäubli and simple UDP": a message from the
//! locked robot is dropped unanswered, and counted by reason, when its joint count differs from
//! the session's, its sequence number (EGM `seqno`, KUKA `IPOC`, Stäubli `seq`, the simple
//! line's `seq=`) does not advance, or its robot time (EGM `tm`, Stäubli timestamp) goes back;
//! deflex's own EGM `seqno` (and Stäubli `seq`) advances only with answers actually sent.
//!
//! Each test plays the robot on a raw UDP socket and answers every state the link returns, as
//! the runtime does: a message the link failed to drop would be answered and show up in the
//! outcomes, the counters and the robot's received answers. EGM messages are built twice, with
//! the crate's prost messages and with protobuf bytes assembled by hand here from ABB's
//! `egm.proto` field numbers; the answers' `seqno` is read by hand too.

use deflex_io::egm::{EgmConfig, EgmFrame, EgmLink, fill_robot_msg, msg};
use deflex_io::rsi::{CorrectionMode, RsiConfig, RsiLink};
use deflex_io::simple_udp::{ReplyStyle, SimpleUdpLink, parse_correction_line};
use deflex_io::staubli::{StateMsg, StaubliHeader, StaubliLink, decode_correction, encode_state};
use deflex_io::{Correction, DropReason, LinkError, RobotLink, RobotState};
use std::net::{SocketAddr, UdpSocket};
use std::time::Duration;

const T: Duration = Duration::from_secs(5);

#[derive(Debug, PartialEq)]
enum Outcome {
    /// Answered; the state's cycle id.
    Answered(u64),
    Dropped(DropReason),
}
use Outcome::{Answered, Dropped};

/// Receives one message and answers it as the runtime would.
fn serve(pc: &mut dyn RobotLink, c: &Correction) -> Outcome {
    match pc.receive(T) {
        Ok(Some(s)) => {
            pc.send_correction(c).unwrap();
            Answered(s.cycle_id)
        }
        Err(LinkError::Dropped { reason, .. }) => Dropped(reason),
        other => panic!("{other:?}"),
    }
}

fn robot_socket() -> UdpSocket {
    let s = UdpSocket::bind("127.0.0.1:0").unwrap();
    s.set_read_timeout(Some(T)).unwrap();
    s
}

/// Every datagram waiting on `sock`: the first `n` with the hang guard, then whatever else
/// arrives within 200 ms (nothing, when the link answered only what it should).
fn datagrams(sock: &UdpSocket, n: usize) -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    let mut b = [0u8; 2048];
    sock.set_read_timeout(Some(T)).unwrap();
    for _ in 0..n {
        let k = sock.recv(&mut b).expect("an expected answer is missing");
        out.push(b[..k].to_vec());
    }
    sock.set_read_timeout(Some(Duration::from_millis(200)))
        .unwrap();
    while let Ok(k) = sock.recv(&mut b) {
        out.push(b[..k].to_vec());
    }
    out
}

// ------------------------------------------------------------------ ABB EGM

/// `EgmRobot` with header {seqno, tm, mtype = DATA} and feedBack.joints (degrees), through the
/// crate's prost messages.
fn egm_prost(seqno: u32, tm: u32, q_rad: &[f64]) -> Vec<u8> {
    let mut m = msg::EgmRobot::default();
    fill_robot_msg(&mut m, &RobotState::with_joints(q_rad), seqno, tm, false);
    prost::Message::encode_to_vec(&m)
}

fn varint(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push((v as u8) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

/// The same message assembled by hand from egm.proto: EgmRobot.header = 1, .feedBack = 2;
/// EgmHeader.seqno = 1, .tm = 2, .mtype = 3 (varints, DATA = 2); EgmFeedBack.joints = 1;
/// EgmJoints.joints = 1 (repeated double, proto2: one fixed64 field per value).
fn egm_hand(seqno: u32, tm: u32, q_rad: &[f64]) -> Vec<u8> {
    let mut header = Vec::new();
    header.push(0x08);
    varint(&mut header, u64::from(seqno));
    header.push(0x10);
    varint(&mut header, u64::from(tm));
    header.extend_from_slice(&[0x18, 0x02]);
    let mut joints = Vec::new();
    for q in q_rad {
        joints.push(0x09);
        joints.extend_from_slice(&q.to_degrees().to_le_bytes());
    }
    let mut feedback = vec![0x0a];
    varint(&mut feedback, joints.len() as u64);
    feedback.extend_from_slice(&joints);
    let mut m = vec![0x0a];
    varint(&mut m, header.len() as u64);
    m.extend_from_slice(&header);
    m.push(0x12);
    varint(&mut m, feedback.len() as u64);
    m.extend_from_slice(&feedback);
    m
}

/// The header `seqno` of an `EgmSensorPathCorr` (header = field 1, seqno = its field 1), read
/// by hand.
fn answer_seqno(b: &[u8]) -> u32 {
    fn read_varint(b: &[u8], i: &mut usize) -> u64 {
        let mut v = 0;
        for shift in (0..64).step_by(7) {
            let byte = b[*i];
            *i += 1;
            v |= u64::from(byte & 0x7f) << shift;
            if byte & 0x80 == 0 {
                break;
            }
        }
        v
    }
    assert_eq!(b[0], 0x0a, "header first");
    let mut i = 1;
    let len = read_varint(b, &mut i) as usize;
    let header = &b[i..i + len];
    let mut j = 0;
    while j < header.len() {
        let key = read_varint(header, &mut j);
        let v = read_varint(header, &mut j);
        if key == 0x08 {
            return v as u32;
        }
    }
    panic!("no seqno in the answer's header");
}

fn egm_session(build: fn(u32, u32, &[f64]) -> Vec<u8>) {
    let cfg = EgmConfig {
        frame: EgmFrame::Base,
        ..EgmConfig::default()
    };
    let mut pc = EgmLink::bind("127.0.0.1:0", cfg).unwrap();
    let to = pc.local_addr().unwrap();
    let robot = robot_socket();
    let six = [0.1, -0.5, 0.9, 0.0, 0.4, 0.2];
    let five = &six[..5];
    let c = Correction {
        dp_m: [1e-3, 0.0, 0.0],
        dphi_rad: [0.0; 3],
    };
    let script: [(u32, u32, &[f64], Outcome); 8] = [
        (1, 4, &six, Answered(1)),
        (2, 8, &six, Answered(2)),
        (
            3,
            12,
            five,
            Dropped(DropReason::JointCount { got: 5, session: 6 }),
        ),
        // The replay of the previous seqno with tm going back to 0 (the message).
        (
            2,
            0,
            &six,
            Dropped(DropReason::SequenceNotAdvancing { got: 2, last: 2 }),
        ),
        (
            2,
            8,
            &six,
            Dropped(DropReason::SequenceNotAdvancing { got: 2, last: 2 }),
        ),
        (
            1,
            4,
            &six,
            Dropped(DropReason::SequenceNotAdvancing { got: 1, last: 2 }),
        ),
        (
            4,
            0,
            &six,
            Dropped(DropReason::TimeWentBack {
                got_s: 0.0,
                last_s: 0.008,
            }),
        ),
        (5, 16, &six, Answered(5)),
    ];
    for (seqno, tm, q, want) in script {
        robot.send_to(&build(seqno, tm, q), to).unwrap();
        assert_eq!(serve(&mut pc, &c), want, "seqno {seqno} tm {tm}");
    }
    // A correction that cannot be sent does not use up a seqno.
    robot.send_to(&build(6, 20, &six), to).unwrap();
    assert!(pc.receive(T).unwrap().is_some());
    let nan = Correction {
        dp_m: [f64::NAN, 0.0, 0.0],
        dphi_rad: [0.0; 3],
    };
    assert!(pc.send_correction(&nan).is_err());
    pc.send_correction(&c).unwrap();

    let answers = datagrams(&robot, 4);
    let seqnos: Vec<u32> = answers.iter().map(|a| answer_seqno(a)).collect();
    assert_eq!(
        seqnos,
        [1, 2, 3, 4],
        "deflex's own seqno: one per answer, no gap"
    );
    let k = pc.counters();
    assert_eq!(
        (
            k.accepted,
            k.answers,
            k.dropped_joint_count,
            k.dropped_sequence,
            k.dropped_time,
            k.dropped()
        ),
        (4, 4, 1, 3, 1, 5)
    );
}

#[test]
fn egm_drops_joint_count_changes_replays_and_time_going_back_prost_bytes() {
    egm_session(egm_prost);
}

#[test]
fn egm_drops_joint_count_changes_replays_and_time_going_back_hand_bytes() {
    egm_session(egm_hand);
}

/// The two builders agree: the hand-assembled bytes are what prost writes, field for field.
#[test]
fn egm_hand_bytes_equal_prost_bytes() {
    for (seqno, tm, q) in [
        (1u32, 4u32, &[0.1, -0.5, 0.9, 0.0, 0.4, 0.2][..]),
        (300, 70_000, &[1.0, 2.0, 3.0, 4.0, 5.0][..]),
        (u32::MAX, u32::MAX, &[-3.0][..]),
    ] {
        assert_eq!(egm_hand(seqno, tm, q), egm_prost(seqno, tm, q));
    }
}

// ------------------------------------------------------------------ KUKA RSI

/// A `<Rob>` telegram written by hand (AIPos in degrees, Delay, IPOC).
fn rob(ipoc: u64, delay: u32) -> Vec<u8> {
    format!(
        "<Rob Type=\"KUKA\"><AIPos A1=\"0\" A2=\"-90\" A3=\"90\" A4=\"0\" A5=\"10\" A6=\"0\"/>\
         <Delay D=\"{delay}\"/><IPOC>{ipoc}</IPOC></Rob>"
    )
    .into_bytes()
}

/// `X` of the answer's `RKorr` (mm) and its `IPOC`, read by hand.
fn rkorr_x_and_ipoc(b: &[u8]) -> (f64, u64) {
    let t = std::str::from_utf8(b).unwrap();
    let x = t.split("X=\"").nth(1).unwrap().split('"').next().unwrap();
    let ipoc = t.split("<IPOC>").nth(1).unwrap().split('<').next().unwrap();
    (x.parse().unwrap(), ipoc.parse().unwrap())
}

/// RSI in relative mode: a duplicate `IPOC` and a replay of an older telegram with a lower
/// `Delay` are dropped. Answered, the replay's `Delay` would have looked like a new RSI session
/// and reset the book of what the robot accumulated, so the robot's sum of increments would no
/// longer equal the controller's total.
#[test]
fn rsi_drops_ipoc_that_does_not_advance() {
    let cfg = RsiConfig {
        mode: CorrectionMode::Relative,
        ..RsiConfig::default()
    };
    let mut pc = RsiLink::bind("127.0.0.1:0", cfg).unwrap();
    let to = pc.local_addr().unwrap();
    let robot = robot_socket();
    let mut total_mm = 0.0;
    let script = [
        (1000, 5, Answered(1000)),
        (1004, 5, Answered(1004)),
        (
            1004,
            5,
            Dropped(DropReason::SequenceNotAdvancing {
                got: 1004,
                last: 1004,
            }),
        ),
        (
            1000,
            0,
            Dropped(DropReason::SequenceNotAdvancing {
                got: 1000,
                last: 1004,
            }),
        ),
        (1008, 5, Answered(1008)),
    ];
    for (ipoc, delay, want) in script {
        robot.send_to(&rob(ipoc, delay), to).unwrap();
        // The controller's total grows by 1 mm per telegram it sees.
        total_mm += 1.0;
        let c = Correction {
            dp_m: [total_mm * 1e-3, 0.0, 0.0],
            dphi_rad: [0.0; 3],
        };
        assert_eq!(serve(&mut pc, &c), want, "IPOC {ipoc}");
    }
    let answers: Vec<(f64, u64)> = datagrams(&robot, 3)
        .iter()
        .map(|a| rkorr_x_and_ipoc(a))
        .collect();
    let ipocs: Vec<u64> = answers.iter().map(|a| a.1).collect();
    assert_eq!(ipocs, [1000, 1004, 1008]);
    let applied: f64 = answers.iter().map(|a| a.0).sum();
    assert!(
        (applied - total_mm).abs() < 1e-9,
        "robot accumulated {applied} mm, controller total {total_mm} mm"
    );
    let k = pc.counters();
    assert_eq!((k.accepted, k.answers, k.dropped_sequence), (3, 3, 2));
}

/// A 32-bit IPOC that wraps keeps advancing.
#[test]
fn rsi_ipoc_wrapping_at_32_bits_advances() {
    let mut pc = RsiLink::bind("127.0.0.1:0", RsiConfig::default()).unwrap();
    let to = pc.local_addr().unwrap();
    let robot = robot_socket();
    let c = Correction::ZERO;
    for ipoc in [u64::from(u32::MAX) - 3, u64::from(u32::MAX), 3, 7] {
        robot.send_to(&rob(ipoc, 0), to).unwrap();
        assert_eq!(serve(&mut pc, &c), Answered(ipoc));
    }
    robot.send_to(&rob(u64::from(u32::MAX), 0), to).unwrap();
    assert!(matches!(
        serve(&mut pc, &c),
        Dropped(DropReason::SequenceNotAdvancing { .. })
    ));
}

// ------------------------------------------------------------------ Stäubli

fn state(seq: u32, t: f64) -> Vec<u8> {
    let m = StateMsg {
        header: StaubliHeader {
            flags: 0,
            seq,
            ack: 0,
            timestamp_s: t,
        },
        q_rad: [0.1, -1.0, 1.2, 0.0, 0.5, 3.0],
        status: 1,
    };
    let mut b = [0u8; deflex_io::staubli::STATE_LEN];
    let n = encode_state(&m, &mut b).unwrap();
    b[..n].to_vec()
}

#[test]
fn staubli_drops_sequence_replays_and_time_going_back() {
    let mut pc = StaubliLink::bind("127.0.0.1:0").unwrap();
    let to = pc.local_addr().unwrap();
    let robot = robot_socket();
    let c = Correction {
        dp_m: [0.0, 0.0, 2e-4],
        dphi_rad: [0.0; 3],
    };
    let script = [
        (1, 0.004, Answered(1)),
        (2, 0.008, Answered(2)),
        (
            2,
            0.008,
            Dropped(DropReason::SequenceNotAdvancing { got: 2, last: 2 }),
        ),
        (
            1,
            0.004,
            Dropped(DropReason::SequenceNotAdvancing { got: 1, last: 2 }),
        ),
        (
            3,
            0.0,
            Dropped(DropReason::TimeWentBack {
                got_s: 0.0,
                last_s: 0.008,
            }),
        ),
        (4, 0.016, Answered(4)),
    ];
    for (seq, t, want) in script {
        robot.send_to(&state(seq, t), to).unwrap();
        assert_eq!(serve(&mut pc, &c), want, "seq {seq} t {t}");
    }
    let answers: Vec<(u32, u32)> = datagrams(&robot, 3)
        .iter()
        .map(|a| {
            let m = decode_correction(a).unwrap();
            (m.header.seq, m.header.ack)
        })
        .collect();
    // deflex's own seq counts its answers; ack names the state answered.
    assert_eq!(answers, [(1, 1), (2, 2), (3, 4)]);
    let k = pc.counters();
    assert_eq!(
        (k.accepted, k.answers, k.dropped_sequence, k.dropped_time),
        (3, 3, 2, 1)
    );
}

// ------------------------------------------------------------------ simple UDP

#[test]
fn simple_udp_drops_joint_count_changes_and_seq_replays() {
    let mut pc = SimpleUdpLink::bind("127.0.0.1:0", ReplyStyle::Keyword).unwrap();
    let to: SocketAddr = pc.local_addr().unwrap();
    let robot = robot_socket();
    let c = Correction {
        dp_m: [0.0, 3e-4, 0.0],
        dphi_rad: [0.0; 3],
    };
    let script: [(&str, Outcome); 7] = [
        ("q 0 0 0 0 0 0 seq=1", Answered(1)),
        ("q 0.1 0 0 0 0 0 seq=2", Answered(2)),
        (
            "q 0.1 0 0 0 0 0 seq=2",
            Dropped(DropReason::SequenceNotAdvancing { got: 2, last: 2 }),
        ),
        (
            "q 0 0 0 0 0 0 seq=1",
            Dropped(DropReason::SequenceNotAdvancing { got: 1, last: 2 }),
        ),
        (
            "q 0.2 0 0 0 0 seq=3",
            Dropped(DropReason::JointCount { got: 5, session: 6 }),
        ),
        (
            "q 0.2 0 0 0 0 0",
            Dropped(DropReason::SequenceMismatch {
                message_has_one: false,
            }),
        ),
        ("q 0.2 0 0 0 0 0 seq=3", Answered(3)),
    ];
    for (line, want) in script {
        robot.send_to(line.as_bytes(), to).unwrap();
        assert_eq!(serve(&mut pc, &c), want, "{line}");
    }
    let answers = datagrams(&robot, 3);
    assert_eq!(answers.len(), 3);
    for a in &answers {
        assert_eq!(parse_correction_line(a).unwrap(), c);
    }
    let k = pc.counters();
    assert_eq!(
        (
            k.accepted,
            k.answers,
            k.dropped_sequence,
            k.dropped_joint_count,
            k.dropped_sequence_mismatch
        ),
        (3, 3, 2, 1, 1)
    );
}

/// A robot that does not number its lines: the joint count still holds (a duplicate cannot be
/// told from the next cycle, as documented), and a numbered line is then foreign to the session.
#[test]
fn simple_udp_without_seq_keeps_the_joint_count_rule() {
    let mut pc = SimpleUdpLink::bind("127.0.0.1:0", ReplyStyle::Keyword).unwrap();
    let to = pc.local_addr().unwrap();
    let robot = robot_socket();
    let c = Correction::ZERO;
    for (line, want) in [
        ("q 1 2 3 4", Answered(1)),
        ("q 1 2 3 4", Answered(2)),
        (
            "q 1 2 3 4 5 6",
            Dropped(DropReason::JointCount { got: 6, session: 4 }),
        ),
        (
            "q 1 2 3 4 seq=9",
            Dropped(DropReason::SequenceMismatch {
                message_has_one: true,
            }),
        ),
        ("q 1 2 3 4", Answered(3)),
    ] {
        robot.send_to(line.as_bytes(), to).unwrap();
        assert_eq!(serve(&mut pc, &c), want, "{line}");
    }
    assert_eq!(datagrams(&robot, 3).len(), 3);
}

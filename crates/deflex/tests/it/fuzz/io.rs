//! Fuzzing deflex's io parsers: one target per wire parser (KUKA RSI, ABB EGM, FANUC Stream
//! Motion, Stäubli, simple UDP lines, the simple TCP stream framing + lines, ATI Net F/T), on
//! the shared mutation fuzzer
//! ([`crate::fuzz::engine`]): random bytes and mutations of valid messages must never make a
//! parser panic, and whatever a parser accepts must keep its promises (finite values, counts in
//! range, a message that formats again). The session rules (`deflex_io::guard`) are fuzzed on
//! streams of messages: each protocol's parsed messages fed in order to a `SessionGuard`, whose
//! every verdict must match an oracle written here from the rules (not from the guard's code).
//! A quick count here; the full count:
//!
//! ```sh
//! DEFLEX_FUZZ_COUNT=1000000 cargo test --release -p deflex --test it fuzz::io -- --nocapture
//! ```

use crate::fuzz::engine::{count_from_env, fuzz};
use deflex_io::egm::{EgmConfig, decode_path_corr, decode_robot, fill_robot_msg};
use deflex_io::guard::{SessionGuard, Stamp};
use deflex_io::rsi::{JointTag, format_rob, format_sen, format_sen_joints, parse_rob, parse_sen};
use deflex_io::simple_tcp::LineBuf;
use deflex_io::simple_udp::{
    format_joints_line, format_state_line, parse_correction_line, parse_joints_line,
    parse_state_line,
};
use deflex_io::{LinkError, RobotState};
use deflex_model::conventions::rotation_from_kuka_abc_rad;
use deflex_model::{MAX_JOINTS, Pose};
use nalgebra::Translation3;

const QUICK: usize = 30_000;

fn finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// A parser's error must describe the packet, not a socket.
fn packet_error(e: &LinkError) {
    assert!(
        e.is_bad_packet(),
        "a parser returned a non-packet error: {e}"
    );
}

fn run(name: &str, corpus: &[Vec<u8>], max_len: usize, target: impl FnMut(&[u8])) {
    let corpus: Vec<&[u8]> = corpus.iter().map(Vec::as_slice).collect();
    let report = fuzz(&corpus, count_from_env(QUICK), max_len, target);
    report.assert_no_panic(name);
    println!("{name}: {} inputs, no panic", report.inputs);
}

#[test]
fn rsi_parsers() {
    let mut rob = [0u8; 1024];
    let t = deflex_io::rsi::RobTelegram {
        actual_pose: Some(Pose::from_parts(
            Translation3::new(1.2, -0.03, 0.8),
            rotation_from_kuka_abc_rad([1.5, -0.2, 3.1]),
        )),
        setpoint_pose: None,
        q_rad: Some([0.1, -1.5, 1.6, 0.0, 0.7, -3.0]),
        delay: 3,
        ipoc: 4_208_138_482,
    };
    let n = format_rob(&t, &mut rob).unwrap();
    let mut sen = [0u8; 1024];
    let m = format_sen(&[0.001; 6], 77, "ImFree", Some("deflex"), &mut sen).unwrap();
    let mut ak = [0u8; 1024];
    let k = format_sen_joints(JointTag::Ak, &[0.01; 6], 78, "ImFree", None, &mut ak).unwrap();
    let corpus = [rob[..n].to_vec(), sen[..m].to_vec(), ak[..k].to_vec()];
    run("KUKA RSI", &corpus, 2048, |b| {
        match parse_rob(b) {
            Ok(t) => {
                assert!(t.q_rad.is_none_or(|q| finite(&q)));
                for p in [t.actual_pose, t.setpoint_pose].into_iter().flatten() {
                    assert!(
                        finite(p.translation.vector.as_slice())
                            && finite(p.rotation.matrix().as_slice())
                    );
                }
                // Values that parse format again (huge ones may not fit the buffer: an error).
                let mut out = [0u8; 4096];
                if let Err(e) = format_rob(&t, &mut out) {
                    assert!(matches!(e, LinkError::BufferTooSmall { .. }), "{e}");
                }
            }
            Err(e) => packet_error(&e),
        }
        match parse_sen(b) {
            Ok(s) => {
                assert!(s.rkorr.is_some() || s.joints_rad.is_some());
                assert!(s.rkorr.is_none_or(|v| finite(&v)));
                assert!(s.joints_rad.is_none_or(|v| finite(&v)));
            }
            Err(e) => packet_error(&e),
        }
    });
}

#[test]
fn egm_decoders() {
    use prost::Message;
    let mut m = deflex_io::egm::msg::EgmRobot::default();
    let mut s = RobotState::with_joints(&[0.1, -0.5, 1.0, 0.0, 0.4, 3.0]);
    s.tcp_pose = Some(Pose::from_parts(
        Translation3::new(1.0, 0.5, 0.3),
        rotation_from_kuka_abc_rad([0.3, -0.2, 2.9]),
    ));
    fill_robot_msg(&mut m, &s, 7, 1234, false);
    let robot = m.encode_to_vec();
    fill_robot_msg(
        &mut m,
        &RobotState::with_joints(&[0.1, -0.5, 0.7, 1.0, 0.0, 0.4, 3.0]),
        8,
        1238,
        true,
    );
    let seven = m.encode_to_vec();
    let mut pc = [0u8; 256];
    let n = deflex_io::egm::encode_path_corr(3, 4, [0.001, -0.002, 0.003], 10, &mut pc).unwrap();
    run("ABB EGM", &[robot, seven, pc[..n].to_vec()], 1024, |b| {
        match decode_robot(b) {
            Ok(f) => {
                assert!(f.n_joints <= 6 && f.n_external <= 6);
                assert!(finite(&f.q_rad[..f.n_joints]));
                assert!(
                    f.tcp_pose
                        .is_none_or(|p| finite(p.translation.vector.as_slice()))
                );
                // The allocation-free walker agrees with prost on the joints.
                if let Ok(p) = deflex_io::egm::msg::EgmRobot::decode(b)
                    && let Some(j) = p.feed_back.and_then(|fb| fb.joints)
                    && j.joints.len() == f.n_joints
                {
                    for (a, q) in j.joints.iter().zip(&f.q_rad) {
                        assert!((a.to_radians() - q).abs() <= 1e-12 * q.abs().max(1.0));
                    }
                }
                for seven_axis in [false, true] {
                    let cfg = EgmConfig {
                        seven_axis,
                        ..EgmConfig::default()
                    };
                    if let Ok((q, n)) = cfg.chain_joints(&f) {
                        assert!((1..=MAX_JOINTS).contains(&n) && finite(&q));
                    }
                }
            }
            Err(e) => packet_error(&e),
        }
        match decode_path_corr(b) {
            Ok(p) => assert!(finite(&p.dp_m)),
            Err(e) => packet_error(&e),
        }
    });
}

#[test]
fn staubli_decoders() {
    use deflex_io::staubli::*;
    let mut a = [0u8; STATE_LEN];
    encode_state(
        &StateMsg {
            header: StaubliHeader {
                flags: 0,
                seq: 9,
                ack: 8,
                timestamp_s: 1.5,
            },
            q_rad: [0.1, -1.0, 1.2, 0.0, 0.5, 3.0],
            status: STATUS_ALTER_ACTIVE,
        },
        &mut a,
    )
    .unwrap();
    let mut c = [0u8; CORRECTION_LEN];
    encode_correction(
        &CorrectionMsg {
            header: StaubliHeader {
                flags: FLAG_ACTIVE,
                seq: 10,
                ack: 9,
                timestamp_s: 1.504,
            },
            values: [1e-3, -2e-3, 5e-4, 1e-3, 0.0, -1e-3],
        },
        &mut c,
    )
    .unwrap();
    run("Staubli", &[a.to_vec(), c.to_vec()], 256, |b| {
        match decode_state(b) {
            Ok(m) => assert!(finite(&m.q_rad) && m.header.timestamp_s.is_finite()),
            Err(e) => packet_error(&e),
        }
        match decode_correction(b) {
            Ok(m) => assert!(finite(&m.values)),
            Err(e) => packet_error(&e),
        }
    });
}

fn line_corpus() -> Vec<Vec<u8>> {
    vec![
        b"q 0.1 -1.57 1.2 0 3.25 -6\n".to_vec(),
        b"q [0.1, -1.57, 1.2, 0.0, 3.25, -6.0, 0.5]\r\n".to_vec(),
        b"corr 0.001 0 -0.0005 0 0.0001 0\n".to_vec(),
        b"(0.001000000,0.000000000,-0.500000000,0.000000000,0.100000000,0.000000000)\n".to_vec(),
    ]
}

fn check_joints_line(line: &[u8]) {
    match parse_joints_line(line) {
        Ok((q, n)) => {
            assert!((1..=MAX_JOINTS).contains(&n) && finite(&q));
            // Plausible joint values format again (huge ones need more digits than a line
            // holds: an error, not a panic).
            let mut out = [0u8; 512];
            let formatted = format_joints_line(&q[..n], &mut out);
            assert!(formatted.is_ok() || q[..n].iter().any(|v| v.abs() >= 1e6));
        }
        Err(e) => packet_error(&e),
    }
}

#[test]
fn simple_udp_lines() {
    run("simple UDP", &line_corpus(), 1024, |b| {
        check_joints_line(b);
        match parse_correction_line(b) {
            Ok(c) => assert!(c.is_finite()),
            Err(e) => packet_error(&e),
        }
    });
}

/// The TCP stream: the input cut into chunks whose sizes come from the input's own bytes (as
/// TCP reads may cut it anywhere), assembled into lines, each line parsed.
#[test]
fn simple_tcp_stream() {
    let mut stream = Vec::new();
    for l in line_corpus() {
        stream.extend_from_slice(&l);
    }
    let mut corpus = line_corpus();
    corpus.push(stream);
    run("simple TCP", &corpus, 4096, |b| {
        let mut lines = LineBuf::new();
        let mut fed = 0;
        while fed < b.len() {
            while let Some(r) = lines.take_line() {
                let line = lines.line(r.clone());
                assert_eq!(line.len(), r.len());
                assert!(!line.contains(&b'\n'));
                check_joints_line(line);
            }
            match lines.space() {
                Ok(space) => {
                    let chunk = 1 + usize::from(b[fed]) % 64;
                    let k = chunk.min(space.len()).min(b.len() - fed);
                    space[..k].copy_from_slice(&b[fed..fed + k]);
                    lines.commit(k);
                    fed += k;
                }
                Err(e) => packet_error(&e),
            }
        }
    });
}

#[test]
fn netft_decoders() {
    use deflex_io::netft::*;
    let rec = encode_record(&RdtRecord {
        rdt_sequence: 5,
        ft_sequence: 900,
        status: 0,
        counts: [1_000_000, -2_000_000, 3, 4, -5, 6],
    });
    let mut two = rec.to_vec();
    two.extend_from_slice(&rec);
    let req = encode_request(&RdtRequest {
        command: RdtCommand::StartRealtime,
        sample_count: 0,
    });
    let xml = b"<netft><cfgcpf>1000000</cfgcpf><cfgcpt>1000</cfgcpt><scfgfu>N</scfgfu>\
<scfgtu>N-m</scfgtu></netft>"
        .to_vec();
    run(
        "ATI Net F/T",
        &[rec.to_vec(), two, req.to_vec(), xml],
        1500,
        |b| {
            match decode_records(b) {
                Ok(records) => {
                    let cal = NetFtCalibration::default();
                    for r in records {
                        assert!(finite(cal.to_wrench(&r.counts).as_slice()));
                    }
                }
                Err(e) => packet_error(&e),
            }
            if let Err(e) = decode_record(b) {
                packet_error(&e);
            }
            let _ = decode_request(b);
            if let Ok(text) = std::str::from_utf8(b)
                && let Ok(c) = NetFtCalibration::from_netftapi2_xml(text)
            {
                assert!(c.counts_per_force > 0.0 && c.counts_per_force.is_finite());
                assert!(c.counts_per_torque > 0.0 && c.counts_per_torque.is_finite());
            }
        },
    );
}

// ------------------------------------------------------------- session rules

/// The session rules, written again from their statement: joint count equal to the first
/// accepted message's; sequence number present iff the first accepted message's was, and then
/// ahead of the last accepted one (for two 32-bit values: (new − last) mod 2³² in 1..2³¹,
/// computed here in i128; otherwise new > last); robot time not before the last accepted
/// (32-bit ms: (t − l) mod 2³² < 2³¹; seconds: t ≥ l).
#[derive(Default)]
struct Oracle {
    first: Option<(usize, bool)>,
    seq: Option<u64>,
    time: Option<Stamp>,
}

impl Oracle {
    fn verdict(&mut self, joints: usize, seq: Option<u64>, time: Option<Stamp>) -> bool {
        let ok = match self.first {
            None => true,
            Some((n, has_seq)) => {
                let seq_ok = match (has_seq, seq, self.seq) {
                    (false, None, _) => true,
                    (true, Some(new), Some(last)) => {
                        if new <= u64::from(u32::MAX) && last <= u64::from(u32::MAX) {
                            let d = (i128::from(new) - i128::from(last)).rem_euclid(1 << 32);
                            d > 0 && d < 1 << 31
                        } else {
                            new > last
                        }
                    }
                    _ => false,
                };
                let time_ok = match (time, self.time) {
                    (Some(Stamp::Millis32(t)), Some(Stamp::Millis32(l))) => {
                        (i128::from(t) - i128::from(l)).rem_euclid(1 << 32) < 1 << 31
                    }
                    (Some(Stamp::Seconds(t)), Some(Stamp::Seconds(l))) => t >= l,
                    _ => true,
                };
                joints == n && seq_ok && time_ok
            }
        };
        if ok {
            self.first.get_or_insert((joints, seq.is_some()));
            self.seq = seq;
            if time.is_some() {
                self.time = time;
            }
        }
        ok
    }
}

/// Feeds the frames of `b` (each prefixed by its length, one byte) through `parse` and the
/// guard, checking every verdict against the oracle and the counters at the end.
fn check_stream(b: &[u8], parse: impl Fn(&[u8]) -> Option<(usize, Option<u64>, Option<Stamp>)>) {
    let (mut guard, mut oracle) = (SessionGuard::new(), Oracle::default());
    let (mut rest, mut admitted) = (b, 0u64);
    while let [len, tail @ ..] = rest {
        let n = usize::from(*len).min(tail.len());
        let (frame, next) = tail.split_at(n);
        rest = next;
        let Some((joints, seq, time)) = parse(frame) else {
            continue;
        };
        admitted += 1;
        let got = guard.admit(joints, seq, time);
        let want = oracle.verdict(joints, seq, time);
        assert_eq!(got.is_ok(), want, "{joints} {seq:?} {time:?}: {got:?}");
    }
    let mut c = deflex_io::LinkCounters::default();
    guard.add_to(&mut c);
    assert_eq!(c.accepted + c.dropped(), admitted);
}

/// Frames each message with its length byte.
fn framed(messages: &[Vec<u8>]) -> Vec<u8> {
    let mut out = Vec::new();
    for m in messages {
        out.push(m.len() as u8);
        out.extend_from_slice(m);
    }
    out
}

#[test]
fn session_rules_on_egm_streams() {
    let msg = |seq: u32, tm: u32, n: usize| {
        let mut m = deflex_io::egm::msg::EgmRobot::default();
        fill_robot_msg(
            &mut m,
            &RobotState::with_joints(&[0.1; 6][..n]),
            seq,
            tm,
            false,
        );
        prost::Message::encode_to_vec(&m)
    };
    let corpus = [
        framed(&[
            msg(1, 4, 6),
            msg(2, 8, 6),
            msg(2, 0, 6),
            msg(3, 12, 5),
            msg(9, 40, 6),
        ]),
        framed(&[msg(u32::MAX, u32::MAX, 6), msg(0, 3, 6), msg(1, 2, 6)]),
    ];
    run("EGM session rules", &corpus, 1024, |b| {
        check_stream(b, |f| {
            let r = decode_robot(f).ok()?;
            let (_, n) = EgmConfig::default().chain_joints(&r).ok()?;
            Some((
                n,
                Some(u64::from(r.seqno?)),
                Some(Stamp::Millis32(r.tm_ms?)),
            ))
        });
    });
}

#[test]
fn session_rules_on_rsi_streams() {
    let rob = |ipoc: u64| {
        format!(
            "<Rob><AIPos A1=\"0\" A2=\"0\" A3=\"0\" A4=\"0\" A5=\"0\" A6=\"0\"/><IPOC>{ipoc}</IPOC></Rob>"
        )
        .into_bytes()
    };
    let corpus = [
        framed(&[rob(1000), rob(1004), rob(1004), rob(1000), rob(1008)]),
        framed(&[
            rob(4_294_967_292),
            rob(0),
            rob(4),
            rob(8_589_934_592),
            rob(3),
        ]),
    ];
    run("RSI session rules", &corpus, 1024, |b| {
        check_stream(b, |f| {
            let t = parse_rob(f).ok()?;
            t.q_rad?;
            Some((6, Some(t.ipoc), None))
        });
    });
}

#[test]
fn session_rules_on_staubli_streams() {
    use deflex_io::staubli::*;
    let state = |seq: u32, t: f64| {
        let mut b = [0u8; STATE_LEN];
        encode_state(
            &StateMsg {
                header: StaubliHeader {
                    seq,
                    timestamp_s: t,
                    ..StaubliHeader::default()
                },
                ..StateMsg::default()
            },
            &mut b,
        )
        .unwrap();
        b.to_vec()
    };
    let corpus = [framed(&[
        state(1, 0.004),
        state(2, 0.008),
        state(2, 0.008),
        state(3, 0.0),
        state(4, 0.016),
    ])];
    run("Staubli session rules", &corpus, 1024, |b| {
        check_stream(b, |f| {
            let m = decode_state(f).ok()?;
            Some((
                6,
                Some(u64::from(m.header.seq)),
                Some(Stamp::Seconds(m.header.timestamp_s)),
            ))
        });
    });
}

#[test]
fn session_rules_on_simple_line_streams() {
    let lines: Vec<Vec<u8>> = [
        "q 0 0 0 0 0 0 seq=1",
        "q 0 0 0 0 0 0 seq=2",
        "q 0 0 0 0 0 0 seq=2",
        "q 0 0 0 0 0 seq=3",
        "q 0 0 0 0 0 0",
        "q 1 1 1 1 1 1 seq=18446744073709551615",
        "q 1 1 1 1 1 1 seq=4294967296",
    ]
    .iter()
    .map(|l| l.as_bytes().to_vec())
    .collect();
    run("simple line session rules", &[framed(&lines)], 1024, |b| {
        check_stream(b, |f| {
            let l = parse_state_line(f).ok()?;
            Some((l.joint_count, l.seq, None))
        });
    });
}

/// `parse_state_line`: what parses formats again and parses to the same line.
#[test]
fn simple_state_lines() {
    let mut corpus = line_corpus();
    corpus.push(b"q 0.1 -1.57 1.2 0 3.25 -6 seq=42\n".to_vec());
    corpus.push(b"q [0.1, 0.2] SEQ=18446744073709551615".to_vec());
    run(
        "simple UDP state lines",
        &corpus,
        1024,
        |b| match parse_state_line(b) {
            Ok(l) => {
                assert!((1..=MAX_JOINTS).contains(&l.joint_count) && finite(&l.q_rad));
                let mut out = [0u8; 512];
                if let Ok(n) = format_state_line(&l.q_rad[..l.joint_count], l.seq, &mut out) {
                    let again = parse_state_line(&out[..n]).unwrap();
                    assert_eq!((again.joint_count, again.seq), (l.joint_count, l.seq));
                } else {
                    assert!(l.q_rad.iter().any(|v| v.abs() >= 1e6));
                }
            }
            Err(e) => packet_error(&e),
        },
    );
}

#[test]
fn fanuc_stream_parsers() {
    use deflex_io::fanuc_stream::*;
    let mut status = [0u8; STATUS_LEN];
    let mut joints = [0.0f32; MAX_AXES];
    joints[..6].copy_from_slice(&[10.0, -20.0, 30.0, 0.5, 45.0, -170.0]);
    let s = Status {
        version: VERSION,
        sequence: 77,
        status: STATUS_READY | STATUS_SYSRDY,
        joints_deg: joints,
        safety_scale: 1.0,
        ..Status::default()
    };
    format_status(&s, &mut status).unwrap();
    let mut command = [0u8; COMMAND_LEN];
    let c = Command {
        version: VERSION,
        sequence: 77,
        is_last: false,
        joints_deg: [12.5; MAX_AXES],
    };
    format_command(&c, &mut command).unwrap();
    let mut table = [0u8; THRESHOLD_TABLE_LEN];
    let t = ThresholdTable {
        version: VERSION,
        axis: 2,
        kind: ThresholdKind::Jerk,
        max_cartesian_speed: 2000,
        interval: 100,
        no_payload: [900.0; THRESHOLD_ENTRIES],
        full_payload: [800.0; THRESHOLD_ENTRIES],
    };
    format_threshold_table(&t, &mut table).unwrap();
    let mut start = [0u8; CONTROL_LEN];
    format_start(VERSION, &mut start).unwrap();
    let corpus = [
        status.to_vec(),
        command.to_vec(),
        table.to_vec(),
        start.to_vec(),
    ];
    run("fanuc_stream", &corpus, 600, |b| {
        match parse_status(b) {
            Ok(s) => {
                let all = s.joints_deg.iter().chain(&s.position).chain(&s.current);
                assert!(all.chain([&s.safety_scale]).all(|v| v.is_finite()));
                let mut out = [0u8; STATUS_LEN];
                format_status(&s, &mut out).unwrap();
            }
            Err(e) => packet_error(&e),
        }
        match parse_command(b) {
            Ok(c) => {
                assert!(finite(&c.joints_deg));
                let mut out = [0u8; COMMAND_LEN];
                assert_eq!(format_command(&c, &mut out).unwrap(), COMMAND_LEN);
                // Byte for byte up to the I/O block (deflex writes no I/O; the parser ignores it).
                assert_eq!(&out[..88], &b[..88], "a command reads back byte for byte");
            }
            Err(e) => packet_error(&e),
        }
        match parse_threshold_table(b) {
            Ok(t) => assert!(t.tightest() > 0.0 && t.tightest().is_finite()),
            Err(e) => packet_error(&e),
        }
        if let Err(e) = parse_threshold_request(b) {
            packet_error(&e);
        }
        if let Err(e) = parse_control(b) {
            packet_error(&e);
        }
    });
}

/// UR RTDE: the package framing, data packages of a recipe, recipe answers, text messages and
/// the controller side's requests never panic; an accepted data package has finite doubles and
/// re-encodes to the same bytes.
#[test]
fn rtde_parsers() {
    use deflex_io::rtde::client::{Next, PackageBuf};
    use deflex_io::rtde::*;
    let recipe = Recipe::new(
        1,
        &[
            Variable::Timestamp,
            Variable::ActualQ,
            Variable::RobotMode,
            Variable::RuntimeState,
        ],
    )
    .unwrap();
    let mut valid = [0u8; 256];
    let values = [
        Value::F64(1.5),
        Value::V6([0.1, -0.2, 0.3, 0.0, 1.0, -3.0]),
        Value::I32(7),
        Value::U32(2),
    ];
    let n = encode_data(&mut valid, &recipe, &values).unwrap();
    let corpus = vec![
        valid[..n].to_vec(),
        b"\x00\x08M\x02hi\x00\x03".to_vec(),
        b"\x00\x14O\x01DOUBLE,VECTOR6D".to_vec(),
    ];
    run("rtde", &corpus, 600, |b| {
        let mut buf = PackageBuf::new();
        let take = b.len().min(buf.space().len());
        buf.space()[..take].copy_from_slice(&b[..take]);
        buf.commit(take);
        while let Ok(next) = buf.next_package() {
            let Next::Package(t, size) = next else {
                if next == Next::Incomplete {
                    break;
                }
                continue;
            };
            let payload = &buf.package(size)[3..];
            let mut out = [Value::default(); MAX_FIELDS];
            match t {
                PackageType::DataPackage => match decode_data(payload, &recipe, &mut out) {
                    Ok(()) => {
                        let mut again = [0u8; 256];
                        let m = encode_data(&mut again, &recipe, &out[..4]).unwrap();
                        assert_eq!(&again[3..m], payload);
                    }
                    Err(e) => packet_error(&e),
                },
                PackageType::TextMessage => {
                    let _ = decode_text_message(payload);
                }
                PackageType::SetupOutputs => {
                    let _ = decode_recipe_answer(payload, recipe.variables());
                    if let Ok((f, names)) = decode_setup_outputs(payload) {
                        assert!(f.is_finite() && f > 0.0);
                        let _ = for_each_name(names, |_, _| Ok(()));
                    }
                }
                _ => {
                    let _ = decode_accepted(payload);
                    let _ = decode_controller_version(payload);
                    let _ = decode_protocol_request(payload);
                }
            }
            buf.consume(size);
        }
    });
}

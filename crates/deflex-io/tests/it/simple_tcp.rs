//! Loopback tests of [`deflex_io::simple_tcp`]: 127.0.0.1 and ephemeral ports only.

use deflex_io::DropReason;
use deflex_io::error::LinkError;
use deflex_io::link::{Correction, RobotLink, RobotSideLink, RobotState};
use deflex_io::simple_tcp::*;
use deflex_io::simple_udp::{LINE_BUFFER, format_joints_line, parse_joints_line};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::io::{ErrorKind, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::time::Duration;

const T: Duration = Duration::from_secs(2);
const SHORT: Duration = Duration::from_millis(30);

fn pc() -> SimpleTcpLink {
    SimpleTcpLink::bind("127.0.0.1:0").unwrap()
}

fn raw_robot(pc: &SimpleTcpLink) -> TcpStream {
    let s = TcpStream::connect(pc.local_addr().unwrap()).unwrap();
    s.set_nodelay(true).unwrap();
    s
}

fn robot(pc: &SimpleTcpLink) -> SimpleTcpRobotEndpoint {
    SimpleTcpRobotEndpoint::connect(pc.local_addr().unwrap(), T).unwrap()
}

fn state(q: [f64; 6]) -> RobotState {
    RobotState::with_joints(&q)
}

/// Receives with a timeout and expects a six-joint state.
fn recv_q(pc: &mut SimpleTcpLink) -> [f64; 6] {
    let s = pc.receive(T).unwrap().expect("timeout");
    assert_eq!(s.joint_count, 6);
    std::array::from_fn(|i| s.q_rad[i])
}

#[test]
fn round_trip() {
    let mut pc = pc();
    assert!(pc.local_addr().unwrap().ip().is_loopback());
    assert!(matches!(
        pc.send_correction(&Correction::ZERO),
        Err(LinkError::NoPeer { .. })
    ));
    assert!(pc.receive(Duration::ZERO).unwrap().is_none());
    assert!(pc.receive(SHORT).unwrap().is_none());
    assert!(!pc.is_connected());

    let mut robot = robot(&pc);
    for k in 1..=20u64 {
        let s = state([0.123456789 * k as f64, -1.5, 2.0, 0.0, 1e-3, -3.0]);
        robot.send_state(&s).unwrap();
        let got = pc.receive(T).unwrap().unwrap();
        assert_eq!(got.cycle_id, k);
        for (a, b) in got.q_rad.iter().zip(s.q_rad) {
            assert!((a - b).abs() < 1e-9);
        }
        let c = Correction {
            dp_m: [1e-4 * k as f64, -2e-4, 3e-4],
            dphi_rad: [1e-5, 0.0, -1e-5],
        };
        pc.send_correction(&c).unwrap();
        let rc = robot.receive_correction(T).unwrap().unwrap();
        // 9 decimals on the wire: 1 nm, 1 nrad.
        let (got, want) = (rc.correction, c);
        for (a, b) in got
            .dp_m
            .iter()
            .chain(&got.dphi_rad)
            .zip(want.dp_m.iter().chain(&want.dphi_rad))
        {
            assert!((a - b).abs() < 1e-9, "{got:?} vs {want:?}");
        }
        assert_eq!(rc.cycle_id, k);
    }
    assert!(pc.is_connected());
    assert_eq!(pc.connections(), 1);
    assert_eq!(pc.peer_addr(), Some(robot.local_addr().unwrap()));
    // Nothing pending on either side.
    assert!(pc.receive(Duration::ZERO).unwrap().is_none());
    assert!(robot.receive_correction(Duration::ZERO).unwrap().is_none());
    // Non-finite corrections are refused before anything is written.
    let nan = Correction {
        dp_m: [f64::NAN, 0.0, 0.0],
        dphi_rad: [0.0; 3],
    };
    assert!(pc.send_correction(&nan).is_err());
    assert!(pc.is_connected());
}

#[test]
fn reply_is_in_urscript_read_ascii_float_format() {
    let mut pc = pc();
    let mut raw = raw_robot(&pc);
    // URScript prints a list as "[a, b, ...]"; socket_send_line appends "\n".
    raw.write_all(b"q [0.1, -1.57, 1.2, 0, 3.25, -6]\r\n")
        .unwrap();
    assert_eq!(recv_q(&mut pc), [0.1, -1.57, 1.2, 0.0, 3.25, -6.0]);
    let c = Correction {
        dp_m: [0.001, 0.0, -0.5],
        dphi_rad: [0.0, 0.1, -0.000123456],
    };
    pc.send_correction(&c).unwrap();
    let want = b"(0.001000000,0.000000000,-0.500000000,0.000000000,0.100000000,-0.000123456)\n";
    let mut got = [0u8; 128];
    let mut n = 0;
    raw.set_read_timeout(Some(T)).unwrap();
    while n < want.len() {
        let k = raw.read(&mut got[n..]).unwrap();
        assert!(k > 0);
        n += k;
    }
    assert_eq!(&got[..n], &want[..]);
}

#[test]
fn partial_lines_split_across_writes() {
    let mut pc = pc();
    let mut raw = raw_robot(&pc);
    // Byte by byte: nothing before the newline, the line after it.
    let line = b"q 0.5 -0.25 1 2 3 4\n";
    for (i, b) in line.iter().enumerate() {
        raw.write_all(&[*b]).unwrap();
        if i + 1 < line.len() {
            assert!(pc.receive(Duration::ZERO).unwrap().is_none(), "byte {i}");
        }
    }
    assert_eq!(recv_q(&mut pc), [0.5, -0.25, 1.0, 2.0, 3.0, 4.0]);

    // A partial line survives a timeout; a chunk may end one line and start
    // the next; CR LF is accepted.
    raw.write_all(b"q 1 2 3").unwrap();
    assert!(pc.receive(SHORT).unwrap().is_none());
    raw.write_all(b" 4 5 6\nq 7 8").unwrap();
    assert_eq!(recv_q(&mut pc), [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
    assert!(pc.receive(SHORT).unwrap().is_none());
    raw.write_all(b" 9 10 11 12\r\n").unwrap();
    assert_eq!(recv_q(&mut pc), [7.0, 8.0, 9.0, 10.0, 11.0, 12.0]);

    // Several lines (and blank lines) in one write come out one per call.
    raw.write_all(b"q 1 1 1 1 1 1\n\n\r\nq 2 2 2 2 2 2\nq 3 3 3 3 3 3\n")
        .unwrap();
    for k in 1..=3 {
        assert_eq!(recv_q(&mut pc), [k as f64; 6]);
    }
    assert!(pc.receive(Duration::ZERO).unwrap().is_none());

    // A malformed line is an error, the next line is fine.
    raw.write_all(b"q 1 2 x\nq 4 4 4 4 4 4\n").unwrap();
    let e = pc.receive(T).unwrap_err();
    assert!(matches!(e, LinkError::Malformed { .. }), "{e}");
    assert_eq!(recv_q(&mut pc), [4.0; 6]);
    assert_eq!(pc.receive(Duration::ZERO).unwrap(), None);
    assert_eq!(pc.connections(), 1);
}

#[test]
fn robot_side_reassembles_partial_lines() {
    let server = TcpListener::bind("127.0.0.1:0").unwrap();
    let mut robot = SimpleTcpRobotEndpoint::connect(server.local_addr().unwrap(), T).unwrap();
    let (mut raw, _) = server.accept().unwrap();
    raw.set_nodelay(true).unwrap();
    raw.write_all(b"(0.1,0.2,").unwrap();
    assert!(robot.receive_correction(SHORT).unwrap().is_none());
    raw.write_all(b"0.3,0.4,0.5,0.6)\ncorr 1 2 3 4 5 6\n")
        .unwrap();
    let rc = robot.receive_correction(T).unwrap().unwrap();
    assert_eq!(rc.correction.dp_m, [0.1, 0.2, 0.3]);
    assert_eq!(rc.correction.dphi_rad, [0.4, 0.5, 0.6]);
    let rc = robot.receive_correction(T).unwrap().unwrap();
    assert_eq!(rc.correction.dphi_rad, [4.0, 5.0, 6.0]);
    assert_eq!(rc.cycle_id, 2);
    robot.send_state(&state([0.25; 6])).unwrap();
    let mut buf = [0u8; 128];
    raw.set_read_timeout(Some(T)).unwrap();
    let n = raw.read(&mut buf).unwrap();
    let (q, count) = parse_joints_line(&buf[..n]).unwrap();
    assert_eq!(&q[..count], &[0.25; 6]);
    // The PC going away is an error on the robot side, every time.
    drop(raw);
    for _ in 0..2 {
        let e = robot.receive_correction(T).unwrap_err();
        assert!(matches!(e, LinkError::Io(ref io) if io.kind() == ErrorKind::UnexpectedEof));
    }
}

#[test]
fn overlong_line_is_an_error_not_a_panic() {
    let mut pc = pc();
    let mut raw = raw_robot(&pc);
    // The longest accepted line: LINE_BUFFER - 1 bytes plus the newline.
    let mut longest = b"q 1 2 3 4 5 6".to_vec();
    longest.resize(LINE_BUFFER - 1, b' ');
    longest.push(b'\n');
    raw.write_all(&longest).unwrap();
    assert_eq!(recv_q(&mut pc), [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);

    // One byte more is rejected once, then the link resynchronises on the
    // next newline, however long the line is.
    for len in [LINE_BUFFER, LINE_BUFFER + 1, 3 * LINE_BUFFER + 17, 100_000] {
        let mut long = b"q 1 2 3 4 5 6".to_vec();
        long.resize(len, b'7');
        long.extend_from_slice(b"\nq 6 5 4 3 2 1\n");
        raw.write_all(&long).unwrap();
        let e = pc.receive(T).unwrap_err();
        assert!(
            matches!(e, LinkError::Oversize { capacity, .. } if capacity == LINE_BUFFER),
            "{e}"
        );
        assert!(e.is_bad_packet());
        assert_eq!(recv_q(&mut pc), [6.0, 5.0, 4.0, 3.0, 2.0, 1.0], "len {len}");
        assert!(pc.receive(Duration::ZERO).unwrap().is_none());
    }
    assert!(pc.is_connected());

    // The overlong line may also arrive in small pieces, across timeouts.
    for _ in 0..(2 * LINE_BUFFER / 64) {
        raw.write_all(&[b'9'; 64]).unwrap();
        match pc.receive(SHORT) {
            Ok(None) => {}
            Err(LinkError::Oversize { .. }) => {}
            other => panic!("{other:?}"),
        }
    }
    raw.write_all(b"\nq 0 0 0 0 0 1\n").unwrap();
    assert_eq!(recv_q(&mut pc), [0.0, 0.0, 0.0, 0.0, 0.0, 1.0]);
}

#[test]
fn reconnect_after_the_robot_drops() {
    let mut pc = pc();
    let mut r1 = robot(&pc);
    r1.send_state(&state([1.0; 6])).unwrap();
    assert_eq!(pc.receive(T).unwrap().unwrap().cycle_id, 1);
    pc.send_correction(&Correction::ZERO).unwrap();
    r1.receive_correction(T).unwrap().unwrap();
    let first_peer = pc.peer_addr().unwrap();

    // The robot goes away in the middle of a line.
    let mut raw = raw_robot(&pc);
    drop(r1);
    // (raw is pending in the backlog; it takes over once r1 is gone)
    assert!(pc.receive(SHORT).unwrap().is_none());
    assert_eq!(pc.connections(), 2);
    raw.write_all(b"q 9 9 9").unwrap();
    assert!(pc.receive(SHORT).unwrap().is_none());
    drop(raw);
    assert!(pc.receive(SHORT).unwrap().is_none());
    assert!(!pc.is_connected());
    assert!(matches!(
        pc.send_correction(&Correction::ZERO),
        Err(LinkError::NoPeer { .. })
    ));

    // A new robot connection: the partial line of the old one is gone, the
    // cycle count goes on.
    let mut r2 = robot(&pc);
    r2.send_state(&state([2.0; 6])).unwrap();
    let s = pc.receive(T).unwrap().unwrap();
    assert_eq!(s.joints(), &[2.0; 6]);
    assert_eq!(s.cycle_id, 2);
    assert_eq!(pc.connections(), 3);
    assert_ne!(pc.peer_addr(), Some(first_peer));
    let c = Correction {
        dp_m: [0.0, 0.0, 1e-3],
        dphi_rad: [0.0; 3],
    };
    pc.send_correction(&c).unwrap();
    assert_eq!(r2.receive_correction(T).unwrap().unwrap().correction, c);

    // The PC may drop the robot too; the robot sees it, a new one is served.
    pc.disconnect();
    assert!(r2.receive_correction(T).is_err());
    let mut r3 = robot(&pc);
    r3.send_state(&state([3.0; 6])).unwrap();
    assert_eq!(recv_q(&mut pc), [3.0; 6]);
}

/// A second connection never takes over, not even from the robot's host while the holder is
/// silent (the old behaviour handed the session to it when a receive timed out): it is closed
/// unanswered and reported, and the holder keeps the session.
#[test]
fn a_second_connection_never_takes_over() {
    let mut pc = pc();
    let mut r1 = robot(&pc);
    r1.send_state(&state([1.0; 6])).unwrap();
    assert_eq!(recv_q(&mut pc), [1.0; 6]);
    let holder = r1.local_addr().unwrap();
    // r1 stays open but silent; another client of the same host connects and sends.
    let mut r2 = robot(&pc);
    r2.send_state(&state([2.0; 6])).unwrap();
    let mut refusals = 0;
    for _ in 0..50 {
        match pc.receive(SHORT) {
            Ok(None) => {}
            Err(LinkError::SecondConnection {
                from,
                holder: h,
                starving,
                ..
            }) => {
                assert_eq!(from, r2.local_addr().unwrap());
                assert_eq!(h, holder);
                // The holder's last line may be older than STARVE_SILENCE by now, or not.
                let _ = starving;
                refusals += 1;
                break;
            }
            other => panic!("{other:?}"),
        }
    }
    assert_eq!(refusals, 1);
    assert_eq!(pc.connections(), 1);
    assert_eq!(pc.peer_addr(), Some(holder));
    assert_eq!(pc.counters().refused_busy, 1);
    // The refused client gets nothing but the close.
    assert!(r2.receive_correction(T).is_err());
    // The holder is still served.
    r1.send_state(&state([3.0; 6])).unwrap();
    assert_eq!(recv_q(&mut pc), [3.0; 6]);
    pc.send_correction(&Correction::ZERO).unwrap();
    assert!(r1.receive_correction(T).unwrap().is_some());
}

/// A client that connects first and sends nothing holds the session; the robot that connects
/// next is refused with `starving`; after the idle timeout the squatter is closed and the
/// robot's next connection is served.
#[test]
fn a_squatter_is_reported_as_starving_and_times_out() {
    let mut pc = pc();
    pc.set_idle_timeout(Duration::from_millis(50)).unwrap();
    assert!(pc.set_idle_timeout(Duration::from_millis(1)).is_err());
    assert!(pc.set_idle_timeout(Duration::from_secs(601)).is_err());
    let squatter = raw_robot(&pc);
    // The squatter becomes the holder (no line: the receive times out).
    assert!(pc.receive(SHORT).unwrap().is_none());
    assert_eq!(pc.peer_addr(), Some(squatter.local_addr().unwrap()));
    let mut robot1 = robot(&pc);
    robot1.send_state(&state([1.0; 6])).unwrap();
    let e = loop {
        match pc.receive(SHORT) {
            Ok(None) => {}
            Err(e) => break e,
            Ok(Some(s)) => panic!("the squatter's session served {s:?}"),
        }
    };
    assert!(e.is_starving() && e.is_foreign(), "{e}");
    assert!(robot1.receive_correction(T).is_err());
    let c = pc.counters();
    assert_eq!((c.refused_busy, c.refused_starving), (1, 1));
    assert!(c.robot_starved());
    // Idle for longer than the idle timeout: closed at the next receive, the robot's new
    // connection is served.
    std::thread::sleep(Duration::from_millis(60));
    let mut robot2 = robot(&pc);
    robot2.send_state(&state([2.0; 6])).unwrap();
    assert_eq!(recv_q(&mut pc), [2.0; 6]);
    assert_eq!(pc.counters().idle_closed, 1);
    assert_eq!(pc.connections(), 2);
    let mut buf = [0u8; 8];
    let mut squatter = squatter;
    squatter.set_read_timeout(Some(T)).unwrap();
    assert!(matches!(squatter.read(&mut buf), Ok(0) | Err(_)));
    pc.send_correction(&Correction::ZERO).unwrap();
    assert!(robot2.receive_correction(T).unwrap().is_some());
    assert_eq!(pc.counters().answers, 1);
}

/// Over TCP as over UDP, a line whose joint count differs from the session's is dropped, and
/// an optional `seq=` must advance within the connection.
#[test]
fn session_rules_over_tcp() {
    let mut pc = pc();
    let mut raw = raw_robot(&pc);
    raw.write_all(b"q 1 2 3 4 5 6 seq=7\nq 1 2 3 4 5 seq=8\nq 1 2 3 4 5 6 seq=7\nq 1 2 3 4 5 6\nq 6 5 4 3 2 1 seq=9\n")
        .unwrap();
    assert_eq!(pc.receive(T).unwrap().unwrap().cycle_id, 7);
    for want in [
        DropReason::JointCount { got: 5, session: 6 },
        DropReason::SequenceNotAdvancing { got: 7, last: 7 },
        DropReason::SequenceMismatch {
            message_has_one: false,
        },
    ] {
        match pc.receive(T) {
            Err(LinkError::Dropped { reason, .. }) => assert_eq!(reason, want),
            other => panic!("{other:?}"),
        }
    }
    let s = pc.receive(T).unwrap().unwrap();
    assert_eq!(
        (s.cycle_id, s.joints()),
        (9, &[6.0, 5.0, 4.0, 3.0, 2.0, 1.0][..])
    );
    let c = pc.counters();
    assert_eq!((c.accepted, c.dropped()), (2, 3));
    // A new connection restarts the count (not the joint count).
    drop(raw);
    let mut raw = raw_robot(&pc);
    raw.write_all(b"q 0 0 0 0 0 0 seq=1\n").unwrap();
    let s = loop {
        if let Some(s) = pc.receive(T).unwrap() {
            break s;
        }
    };
    assert_eq!(s.cycle_id, 1);
}

#[test]
fn zero_and_huge_timeouts() {
    let mut pc = pc();
    let mut robot = robot(&pc);
    // Polling (non-blocking reads) then a blocking write, then back.
    for k in 0..5 {
        robot.send_state(&state([k as f64; 6])).unwrap();
        let s = loop {
            if let Some(s) = pc.receive(Duration::ZERO).unwrap() {
                break s;
            }
            std::thread::yield_now();
        };
        assert_eq!(s.joints(), &[k as f64; 6]);
        pc.send_correction(&Correction::ZERO).unwrap();
        assert!(robot.receive_correction(T).unwrap().is_some());
        robot.send_state(&state([0.5; 6])).unwrap();
        assert_eq!(
            pc.receive(Duration::MAX).unwrap().unwrap().joints(),
            &[0.5; 6]
        );
        pc.send_correction(&Correction::ZERO).unwrap();
        assert!(robot.receive_correction(Duration::MAX).unwrap().is_some());
    }
    pc.set_write_timeout(Duration::ZERO).unwrap();
    pc.set_write_timeout(Duration::from_millis(20)).unwrap();
    pc.send_correction(&Correction::ZERO).unwrap();
}

/// Pure line assembly, in memory: any byte sequence cut anywhere.
#[test]
fn line_buffer_fuzz() {
    let mut rng = StdRng::seed_from_u64(0x5EED_7C90);
    let mut lb = LineBuf::new();
    let alphabet = b"q (),.-e0123456789\n\r\t";
    let mut lines = 0u64;
    for _ in 0..100_000 {
        let len = rng.gen_range(0..3 * LINE_BUFFER / 2);
        let mut fed = 0;
        while fed < len {
            if let Some(r) = lb.take_line() {
                assert!(r.end <= LINE_BUFFER && r.start <= r.end);
                assert!(!lb.line(r).contains(&b'\n'));
                lines += 1;
                continue;
            }
            let Ok(space) = lb.space() else {
                continue;
            };
            assert!(!space.is_empty());
            let k = rng.gen_range(1..=space.len().min(len - fed));
            for b in &mut space[..k] {
                *b = if rng.gen_bool(0.5) {
                    rng.r#gen()
                } else {
                    alphabet[rng.gen_range(0..alphabet.len())]
                };
            }
            lb.commit(k);
            fed += k;
        }
    }
    assert!(lines > 1000);
}

/// Random bytes over a real loopback connection, in random chunks: the
/// link never panics, reports only packet errors and stays usable.
#[test]
fn random_bytes_fuzz_never_panics() {
    let mut rng = StdRng::seed_from_u64(0x5EED_0007);
    let mut pc = pc();
    let mut raw = raw_robot(&pc);
    let alphabet = b"q ()[],.-+eE0123456789\n\r\t";
    let mut chunk = Vec::with_capacity(4 * LINE_BUFFER);
    let (mut ok, mut bad) = (0u32, 0u32);
    for i in 0..10_000 {
        chunk.clear();
        let len = match i % 10 {
            0 => rng.gen_range(LINE_BUFFER / 2..2 * LINE_BUFFER),
            _ => rng.gen_range(0..60),
        };
        for _ in 0..len {
            chunk.push(match i % 3 {
                0 => rng.r#gen(),
                _ => alphabet[rng.gen_range(0..alphabet.len())],
            });
        }
        if i % 7 == 0 {
            let q: [f64; 6] = core::array::from_fn(|_| rng.gen_range(-7.0..7.0));
            let mut b = [0u8; LINE_BUFFER];
            let n = format_joints_line(&q, &mut b).unwrap();
            chunk.push(b'\n');
            chunk.extend_from_slice(&b[..n]);
        }
        raw.write_all(&chunk).unwrap();
        loop {
            match pc.receive(Duration::ZERO) {
                Ok(Some(s)) => {
                    assert!(s.q_rad.iter().all(|x| x.is_finite()));
                    ok += 1;
                }
                Ok(None) => break,
                Err(e) => {
                    assert!(e.is_bad_packet(), "{e}");
                    bad += 1;
                }
            }
        }
    }
    assert!(ok > 100 && bad > 100, "ok {ok} bad {bad}");
    // Still in sync after a newline.
    raw.write_all(b"\nq 1 2 3 4 5 6\n").unwrap();
    let last = loop {
        match pc.receive(T) {
            Ok(Some(s)) => break s,
            Ok(None) => panic!("timeout"),
            Err(e) => assert!(e.is_bad_packet()),
        }
    };
    assert_eq!(last.joints(), &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
    assert_eq!(pc.connections(), 1);
    pc.send_correction(&Correction::ZERO).unwrap();
}

/// The same on the robot side, fed by a raw PC.
#[test]
fn robot_side_random_bytes_fuzz() {
    let mut rng = StdRng::seed_from_u64(0x5EED_0008);
    let server = TcpListener::bind("127.0.0.1:0").unwrap();
    let mut robot = SimpleTcpRobotEndpoint::connect(server.local_addr().unwrap(), T).unwrap();
    let (mut raw, _) = server.accept().unwrap();
    raw.set_nodelay(true).unwrap();
    let alphabet = b"corr ()[],.-+eE0123456789\n\r\t";
    let mut chunk = Vec::new();
    for i in 0..10_000 {
        chunk.clear();
        let len = if i % 10 == 0 {
            rng.gen_range(0..2 * LINE_BUFFER)
        } else {
            rng.gen_range(0..60)
        };
        for _ in 0..len {
            chunk.push(if i % 2 == 0 {
                rng.r#gen()
            } else {
                alphabet[rng.gen_range(0..alphabet.len())]
            });
        }
        raw.write_all(&chunk).unwrap();
        loop {
            match robot.receive_correction(Duration::ZERO) {
                Ok(Some(rc)) => assert!(rc.correction.is_finite()),
                Ok(None) => break,
                Err(e) => assert!(e.is_bad_packet(), "{e}"),
            }
        }
    }
    raw.write_all(b"\n(1,2,3,4,5,6)\n").unwrap();
    let last = loop {
        match robot.receive_correction(T) {
            Ok(Some(rc)) => break rc,
            Ok(None) => panic!("timeout"),
            Err(e) => assert!(e.is_bad_packet()),
        }
    };
    assert_eq!(last.correction.dp_m, [1.0, 2.0, 3.0]);
}

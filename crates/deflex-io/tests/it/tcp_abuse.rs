//! Issue 18, item 9: the simple TCP link serves exactly one robot connection. While a
//! well-behaved robot runs, a second connection from the robot's own host that sends an endless
//! line, one that sends valid lines, and 120 idle connections are each refused (closed
//! unanswered, counted): the robot gets every answer, in order, and no abuser gets a byte. A
//! client that holds the session without serving robot lines is reported as starving the robot.
//!
//! No timing luck: the robot and the PC exchange lines in lockstep, the PC's "robot silent"
//! phase is an explicit pause of the robot thread (the old link handed the session to a pending
//! connection exactly then), and the refusals are awaited by count; timeouts are hang guards.

use deflex_io::simple_tcp::{SimpleTcpLink, SimpleTcpRobotEndpoint};
use deflex_io::{Correction, LinkError, RobotLink, RobotSideLink, RobotState};
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::sync::mpsc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Hang guard of every blocking wait.
const GUARD: Duration = Duration::from_secs(30);
/// Robot cycles in the session.
const CYCLES: u64 = 300;
/// The robot pauses after this cycle (the PC polls while it is silent).
const PAUSE_AFTER: u64 = 100;
const IDLE_ABUSERS: usize = 120;

/// Joint 1 of line `k` and the correction that answers it: the answer names its line.
fn q_of(k: u64) -> f64 {
    k as f64 * 1e-3
}
fn answer_for(q1: f64) -> Correction {
    Correction {
        dp_m: [q1 * 1e-3, 0.0, 0.0],
        dphi_rad: [0.0; 3],
    }
}

/// Reads what the PC sent on a refused connection: must be nothing (end of stream or reset).
fn bytes_received(mut s: TcpStream) -> usize {
    s.set_read_timeout(Some(GUARD)).unwrap();
    let mut buf = [0u8; 256];
    let mut total = 0;
    loop {
        match s.read(&mut buf) {
            Ok(0) | Err(_) => return total,
            Ok(n) => total += n,
        }
    }
}

/// A client that writes `chunk` until the PC closes it, then reports what it received.
fn writer_abuser(pc: SocketAddr, chunk: &'static [u8]) -> JoinHandle<(usize, usize)> {
    let s = TcpStream::connect(pc).unwrap();
    std::thread::spawn(move || {
        let mut w = s.try_clone().unwrap();
        w.set_write_timeout(Some(GUARD)).unwrap();
        let mut written = 0;
        // Bounded: the PC closes the connection long before (a hang guard, not a duration).
        for _ in 0..1_000_000 {
            match w.write(chunk) {
                Ok(n) => written += n,
                Err(_) => break,
            }
        }
        (written, bytes_received(s))
    })
}

/// The robot: connects, then sends line k and waits for its answer, `CYCLES` times; pauses
/// after `PAUSE_AFTER` until released. Returns the answers' joint-1 values.
fn robot_thread(
    mut ep: SimpleTcpRobotEndpoint,
    first: u64,
    release: mpsc::Receiver<()>,
) -> JoinHandle<Vec<f64>> {
    std::thread::spawn(move || {
        let mut got = Vec::new();
        for k in first..=CYCLES {
            if k == PAUSE_AFTER + 1 {
                release.recv_timeout(GUARD).unwrap();
            }
            ep.send_state(&RobotState::with_joints(&[
                q_of(k),
                0.0,
                0.0,
                0.0,
                0.0,
                0.0,
            ]))
            .unwrap();
            let c = ep.receive_correction(GUARD).unwrap().expect("hang guard");
            got.push(c.correction.dp_m[0] * 1e3);
        }
        got
    })
}

/// Serves one robot line, answering it; refusals on the way are counted.
fn serve_one(pc: &mut SimpleTcpLink, refusals: &mut u64) -> f64 {
    let start = Instant::now();
    loop {
        assert!(start.elapsed() < GUARD, "hang guard");
        match pc.receive(Duration::from_millis(10)) {
            Ok(Some(s)) => {
                pc.send_correction(&answer_for(s.q_rad[0])).unwrap();
                return s.q_rad[0];
            }
            Ok(None) => {}
            Err(LinkError::SecondConnection { .. }) => *refusals += 1,
            Err(e) => panic!("{e}"),
        }
    }
}

#[test]
fn abusive_second_connections_get_nothing_and_the_robot_gets_every_answer() {
    let mut pc = SimpleTcpLink::bind("127.0.0.1:0").unwrap();
    let addr = pc.local_addr().unwrap();
    let mut refusals = 0u64;

    // The robot connects and its first line is served: it holds the session.
    let mut ep = SimpleTcpRobotEndpoint::connect(addr, GUARD).unwrap();
    ep.send_state(&RobotState::with_joints(&[
        q_of(1),
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
    ]))
    .unwrap();
    assert_eq!(serve_one(&mut pc, &mut refusals), q_of(1));
    assert_eq!(
        ep.receive_correction(GUARD).unwrap().unwrap().correction,
        answer_for(q_of(1))
    );

    // The abusers, all from the robot's host.
    let endless = writer_abuser(addr, &[b'7'; 4096]);
    let valid = writer_abuser(addr, b"q 1 2 3 4 5 6\n");
    let idle: Vec<TcpStream> = (0..IDLE_ABUSERS)
        .map(|_| TcpStream::connect(addr).unwrap())
        .collect();
    let abusers = IDLE_ABUSERS as u64 + 2;

    let (release, wait) = mpsc::channel();
    let robot = robot_thread(ep, 2, wait);
    let mut served = vec![q_of(1)];
    for _ in 2..=PAUSE_AFTER {
        served.push(serve_one(&mut pc, &mut refusals));
    }
    // The robot is silent now: the PC polls; nothing else may take the session.
    let start = Instant::now();
    loop {
        assert!(start.elapsed() < GUARD, "hang guard");
        match pc.receive(Duration::from_millis(10)) {
            Ok(None) => break,
            Ok(Some(s)) => panic!("a stranger was served: {s:?}"),
            Err(LinkError::SecondConnection { .. }) => refusals += 1,
            Err(e) => panic!("{e}"),
        }
    }
    release.send(()).unwrap();
    for _ in PAUSE_AFTER + 1..=CYCLES {
        served.push(serve_one(&mut pc, &mut refusals));
    }
    let answers = robot.join().unwrap();

    // Every refusal, counted (the last ones may still be pending in the backlog).
    let start = Instant::now();
    while pc.counters().refused_busy < abusers {
        assert!(start.elapsed() < GUARD, "refused {refusals}");
        match pc.receive(Duration::from_millis(10)) {
            Ok(None) => {}
            Err(LinkError::SecondConnection { .. }) => refusals += 1,
            other => panic!("{other:?}"),
        }
    }

    // The robot got every answer, each to its own line, in order.
    let want: Vec<f64> = (2..=CYCLES).map(q_of).collect();
    assert_eq!(answers.len() as u64, CYCLES - 1);
    for (a, w) in answers.iter().zip(&want) {
        assert!((a - w).abs() < 1e-9, "answer {a} to line {w}");
    }
    assert_eq!(served.len() as u64, CYCLES);
    // The abusers got nothing.
    let (written, got) = endless.join().unwrap();
    assert!(written > 0);
    assert_eq!(got, 0, "the endless-line client received bytes");
    let (_, got) = valid.join().unwrap();
    assert_eq!(got, 0, "the valid-line client received bytes");
    for s in idle {
        assert_eq!(bytes_received(s), 0, "an idle client received bytes");
    }
    let c = pc.counters();
    assert_eq!(refusals, abusers);
    assert_eq!(
        (
            c.connections,
            c.accepted,
            c.answers,
            c.refused_busy,
            c.foreign
        ),
        (1, CYCLES, CYCLES, abusers, 0)
    );
    assert!(pc.is_connected());
}

/// A client that connects first and streams an endless line holds the session without serving
/// robot lines: the robot's connection is refused, flagged `starving`, and the counters say the
/// robot was starved, so the runtime can end the session as faulted.
#[test]
fn a_robot_kept_out_by_a_squatter_is_reported_starving() {
    let mut pc = SimpleTcpLink::bind("127.0.0.1:0").unwrap();
    let addr = pc.local_addr().unwrap();
    let mut squatter = TcpStream::connect(addr).unwrap();
    squatter.write_all(&[b'9'; 2048]).unwrap();
    // The squatter holds the session: overlong line, no valid line.
    let start = Instant::now();
    while !pc.is_connected() {
        assert!(start.elapsed() < GUARD);
        match pc.receive(Duration::from_millis(10)) {
            Ok(None) | Err(LinkError::Oversize { .. }) => {}
            other => panic!("{other:?}"),
        }
    }
    let mut robot = SimpleTcpRobotEndpoint::connect(addr, GUARD).unwrap();
    robot
        .send_state(&RobotState::with_joints(&[0.1; 6]))
        .unwrap();
    let start = Instant::now();
    let e = loop {
        assert!(start.elapsed() < GUARD);
        match pc.receive(Duration::from_millis(10)) {
            Ok(None) | Err(LinkError::Oversize { .. }) => {}
            Err(e) => break e,
            Ok(Some(s)) => panic!("served the second connection: {s:?}"),
        }
    };
    assert!(e.is_starving(), "{e}");
    assert!(e.to_string().contains("starved"), "{e}");
    assert!(robot.receive_correction(GUARD).is_err());
    let c = pc.counters();
    assert!(c.robot_starved());
    assert_eq!((c.refused_busy, c.refused_starving, c.accepted), (1, 1, 0));
}

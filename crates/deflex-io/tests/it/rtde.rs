//! Universal Robots RTDE: the codec's packages against hand-written bytes (the layout of UR's RTDE
//! guide, written out here byte by byte, not by the encoder under test), both sides of a session
//! over loopback (deflex's robot and sensor links against the twin's controller), the URScript
//! program's path offset, and hostile controllers and clients: oversized, truncated, of an
//! unknown type, of another recipe id, non-finite, a second client asking for the registers
//! (`IN_USE`), a controller without the flange sensor (`NOT_FOUND`) or too old for path_offset.
//!
//! No timing luck: the twin's controller runs in a thread that answers in lockstep; every wait is
//! a hang guard (30 s), never a synchronisation.

use deflex_io::rtde::client::PackageBuf;
use deflex_io::rtde::server::{CONTROLLER_PERIOD_S, OutputValues};
use deflex_io::rtde::*;
use deflex_io::{Correction, ForceSensorLink, LinkError, RobotLink, RobotSideLink, RobotState};
use deflex_model::Wrench;
use deflex_model::conventions::rotation_from_rotation_vector;
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, mpsc};
use std::time::{Duration, Instant};

const GUARD: Duration = Duration::from_secs(30);

/// A package written out by hand: size (u16, header included), type, payload.
fn package(code: u8, payload: &[u8]) -> Vec<u8> {
    let mut v = ((payload.len() + 3) as u16).to_be_bytes().to_vec();
    v.push(code);
    v.extend_from_slice(payload);
    v
}

#[test]
fn client_requests_are_the_guide_s_bytes() {
    let mut out = [0u8; 256];
    let n = encode_request_protocol_version(&mut out, 2).unwrap();
    assert_eq!(&out[..n], &[0, 5, b'V', 0, 2]);
    let n = encode_empty(&mut out, PackageType::GetUrControlVersion).unwrap();
    assert_eq!(&out[..n], &[0, 3, b'v']);
    let n = encode_setup_outputs(
        &mut out,
        500.0,
        &[Variable::Timestamp, Variable::OutputIntRegister(24)],
    )
    .unwrap();
    let mut expected = 500.0f64.to_be_bytes().to_vec();
    expected.extend_from_slice(b"timestamp,output_int_register_24");
    assert_eq!(&out[..n], package(b'O', &expected).as_slice());
    let n = encode_setup_inputs(
        &mut out,
        &[
            Variable::InputDoubleRegister(47),
            Variable::InputIntRegister(9),
        ],
    )
    .unwrap();
    assert_eq!(
        &out[..n],
        package(b'I', b"input_double_register_47,input_int_register_9").as_slice()
    );
    let recipe = Recipe::new(
        3,
        &[
            Variable::InputDoubleRegister(24),
            Variable::InputIntRegister(24),
        ],
    )
    .unwrap();
    let n = encode_data(&mut out, &recipe, &[Value::F64(-0.5), Value::I32(-7)]).unwrap();
    let mut expected = vec![3u8];
    expected.extend_from_slice(&(-0.5f64).to_be_bytes());
    expected.extend_from_slice(&(-7i32).to_be_bytes());
    assert_eq!(&out[..n], package(b'U', &expected).as_slice());
    // Refused before sending: a NaN, a value of another type, another count.
    for values in [
        &[Value::F64(f64::NAN), Value::I32(1)][..],
        &[Value::I32(1), Value::I32(1)][..],
        &[Value::F64(1.0)][..],
    ] {
        assert!(matches!(
            encode_data(&mut out, &recipe, values),
            Err(LinkError::InvalidValue { .. })
        ));
    }
}

#[test]
fn every_variable_name_reads_back_and_unknown_names_do_not() {
    let mut buf = [0u8; 64];
    let mut all = vec![
        Variable::Timestamp,
        Variable::ActualQ,
        Variable::ActualTcpPose,
        Variable::ActualTcpForce,
        Variable::FtRawWrench,
        Variable::RobotMode,
        Variable::SafetyStatus,
        Variable::RuntimeState,
    ];
    for r in 0..48u8 {
        all.extend([
            Variable::OutputIntRegister(r),
            Variable::OutputDoubleRegister(r),
            Variable::InputDoubleRegister(r),
            Variable::InputIntRegister(r),
        ]);
    }
    for v in all {
        let mut w = Writer::new(&mut buf);
        v.write_name(&mut w).unwrap();
        let n = w.len();
        assert_eq!(Variable::from_name(&buf[..n]), Some(v), "{v}");
        assert_eq!(std::str::from_utf8(&buf[..n]).unwrap(), v.to_string());
    }
    for bad in [
        &b"input_double_register_48"[..],
        b"input_double_register_024",
        b"input_double_register_",
        b"input_double_register_2x",
        b"actual_tcp_pose",
        b"",
    ] {
        assert_eq!(Variable::from_name(bad), None);
    }
}

#[test]
fn controller_answers_decode_and_refusals_name_the_variable() {
    assert!(decode_accepted(&[1]).unwrap());
    assert!(!decode_accepted(&[0]).unwrap());
    assert!(decode_accepted(&[]).is_err() && decode_accepted(&[1, 1]).is_err());
    let mut v = Vec::new();
    for x in [5u32, 16, 2, 1234] {
        v.extend_from_slice(&x.to_be_bytes());
    }
    assert_eq!(decode_controller_version(&v).unwrap(), [5, 16, 2, 1234]);
    assert!(decode_controller_version(&v[..15]).is_err());

    let asked = [Variable::Timestamp, Variable::FtRawWrench];
    let r = decode_recipe_answer(b"\x01DOUBLE,VECTOR6D", &asked).unwrap();
    assert_eq!((r.id, r.variables()), (1, &asked[..]));
    assert_eq!(r.payload_len(), 1 + 8 + 48);
    let refusal = |payload: &[u8], asked: &[Variable]| match decode_recipe_answer(payload, asked) {
        Err(LinkError::SetupRefused { refusal, .. }) => refusal,
        other => panic!("{other:?}"),
    };
    assert_eq!(
        refusal(b"\x00DOUBLE,NOT_FOUND", &asked),
        SetupRefusal::NotFound {
            variable: Variable::FtRawWrench
        }
    );
    let msg = LinkError::SetupRefused {
        protocol: deflex_io::Protocol::Rtde,
        refusal: SetupRefusal::NotFound {
            variable: Variable::FtRawWrench,
        },
    }
    .to_string();
    assert!(
        msg.contains("ft_raw_wrench") && msg.contains("CB3"),
        "{msg}"
    );
    let inputs = [
        Variable::InputDoubleRegister(24),
        Variable::InputIntRegister(24),
    ];
    assert_eq!(
        refusal(b"\x00DOUBLE,IN_USE", &inputs),
        SetupRefusal::InUse {
            variable: Variable::InputIntRegister(24)
        }
    );
    assert_eq!(
        refusal(b"\x01DOUBLE", &asked),
        SetupRefusal::FieldCount {
            asked: 2,
            answered: 1
        }
    );
    assert_eq!(
        refusal(b"\x01INT32,VECTOR6D", &asked),
        SetupRefusal::WrongType {
            variable: Variable::Timestamp,
            answered: FieldType::Int32
        }
    );
    assert!(decode_recipe_answer(b"\x01DOUBLE,VECTOR7D", &asked).is_err());
    assert!(decode_recipe_answer(b"", &asked).is_err());

    // Text message, version 2: length, message, length, source, level.
    let m = decode_text_message(b"\x05hello\x04RTDE\x02").unwrap();
    assert_eq!(
        (m.message, m.source, m.level),
        (&b"hello"[..], &b"RTDE"[..], 2)
    );
    assert_eq!(m.level_name(), "warning");
    for bad in [
        &b"\x09hello\x04RTDE\x02"[..],
        b"\x05hello\x04RTDE",
        b"\x05hello\x04RTDE\x02\x02",
        b"",
    ] {
        assert!(decode_text_message(bad).is_err(), "{bad:?}");
    }
}

#[test]
fn data_packages_are_checked_field_by_field() {
    let recipe = Recipe::new(
        2,
        &[
            Variable::Timestamp,
            Variable::ActualQ,
            Variable::RuntimeState,
        ],
    )
    .unwrap();
    let mut payload = vec![2u8];
    payload.extend_from_slice(&12.5f64.to_be_bytes());
    for k in 0..6 {
        payload.extend_from_slice(&(k as f64 * 0.25 - 1.0).to_be_bytes());
    }
    payload.extend_from_slice(&2u32.to_be_bytes());
    let mut out = [Value::default(); MAX_FIELDS];
    decode_data(&payload, &recipe, &mut out).unwrap();
    assert_eq!(out[0], Value::F64(12.5));
    assert_eq!(out[1], Value::V6([-1.0, -0.75, -0.5, -0.25, 0.0, 0.25]));
    assert_eq!(out[2], Value::U32(2));

    let mut other_id = payload.clone();
    other_id[0] = 1;
    assert!(matches!(
        decode_data(&other_id, &recipe, &mut out),
        Err(LinkError::Malformed { reason, .. }) if reason.contains("recipe id")
    ));
    assert!(matches!(
        decode_data(&payload[..payload.len() - 1], &recipe, &mut out),
        Err(LinkError::Truncated {
            expected: 61,
            got: 60,
            ..
        })
    ));
    let mut longer = payload.clone();
    longer.push(0);
    assert!(decode_data(&longer, &recipe, &mut out).is_err());
    let mut nan = payload.clone();
    nan[9..17].copy_from_slice(&f64::NAN.to_be_bytes());
    assert!(matches!(
        decode_data(&nan, &recipe, &mut out),
        Err(LinkError::Malformed { reason, .. }) if reason.contains("non-finite")
    ));

    // Headers: below 3, above the bound, an unknown type.
    assert!(decode_header(&[0, 2, b'U']).is_err());
    assert!(matches!(
        decode_header(&[0x10, 0, b'U']),
        Err(LinkError::Oversize {
            capacity: MAX_PACKAGE,
            ..
        })
    ));
    assert!(decode_header(&[0, 3, b'X']).is_err());
    assert_eq!(
        decode_header(&[0, 3, b'S']).unwrap(),
        (3, PackageType::Start)
    );
    assert_eq!(
        split_package(&[0, 4, b'V', 1]).unwrap(),
        (PackageType::RequestProtocolVersion, &[1u8][..])
    );
    assert!(split_package(&[0, 5, b'V', 1]).is_err());
}

#[test]
fn the_package_buffer_frames_a_stream_cut_anywhere() {
    let mut stream = package(b'V', &[1]);
    stream.extend(package(b'X', &[9, 9]));
    stream.extend(package(b'S', &[1]));
    for cut in 0..stream.len() {
        let mut b = PackageBuf::new();
        let mut seen = Vec::new();
        for part in [&stream[..cut], &stream[cut..]] {
            let space = b.space();
            space[..part.len()].copy_from_slice(part);
            b.commit(part.len());
            loop {
                match b.next_package().unwrap() {
                    client::Next::Package(t, size) => {
                        seen.push(Some(t));
                        b.consume(size);
                    }
                    client::Next::UnknownType(c) => {
                        seen.push(None.filter(|_: &PackageType| c == 0))
                    }
                    client::Next::Incomplete => break,
                }
            }
        }
        assert_eq!(
            seen,
            vec![
                Some(PackageType::RequestProtocolVersion),
                None,
                Some(PackageType::Start)
            ],
            "cut at {cut}"
        );
    }
    let mut b = PackageBuf::new();
    b.space()[..3].copy_from_slice(&[0xff, 0xff, b'U']);
    b.commit(3);
    assert!(b.next_package().is_err());
}

#[test]
fn the_path_offset_is_limited_filtered_and_ramped_out_by_its_watchdog() {
    let mut m = PathOffsetModel::new(0.5, 0.002, 0.01, 3);
    // 3 mm along x and 20 mrad about z: limited to 2 mm and 10 mrad.
    let target = [0.003, 0.0, 0.0, 0.0, 0.0, 0.02];
    let a = m.step(target, 1);
    assert!(
        (a[0] - 0.001).abs() < 1e-15 && (a[5] - 0.005).abs() < 1e-15,
        "{a:?}"
    );
    let a = m.step(target, 2);
    assert!((a[0] - 0.0015).abs() < 1e-15, "{a:?}");
    // The sequence stops: three more cycles hold the target, then it is zero.
    for _ in 0..3 {
        m.step(target, 2);
    }
    let held = m.applied()[0];
    let after = m.step(target, 2)[0];
    assert!((after - 0.5 * held).abs() < 1e-15, "{held} {after}");
    // A non-finite target is no target.
    let mut m = PathOffsetModel::new(1.0, 1.0, 1.0, 10);
    assert_eq!(m.step([f64::NAN, 0.0, 0.0, 0.0, 0.0, 0.0], 1), [0.0; 6]);
}

/// The twin's controller in a thread: each cycle it sends the state of cycle k and waits (hang
/// guard) for the answer, until told to stop; reports every correction it applied.
struct Controller {
    addr: SocketAddr,
    stop: Arc<AtomicBool>,
    applied: mpsc::Receiver<(u64, [f64; 6])>,
    thread: Option<std::thread::JoinHandle<(RtdeServerCounters, Vec<OutputValues>)>>,
}

fn q_of(k: u64) -> [f64; 6] {
    std::array::from_fn(|j| 0.1 * j as f64 - 0.3 + k as f64 * 1e-4)
}

fn pose_of(k: u64) -> deflex_model::Pose {
    let r = rotation_from_rotation_vector([3.0, 0.1 + k as f64 * 1e-5, -0.2]);
    deflex_model::Pose::from_parts(
        nalgebra::Translation3::new(0.7, -0.1, 0.2 + k as f64 * 1e-6),
        r,
    )
}

fn wrench_of(k: u64) -> Wrench {
    Wrench::from([1.0, -2.0, 30.0 + k as f64 * 0.01, 0.1, -0.2, 0.03])
}

impl Controller {
    fn start(version: Option<[u32; 4]>) -> Controller {
        let mut ep = RtdeRobotEndpoint::bind(
            "127.0.0.1:0",
            24,
            PathOffsetModel::new(1.0, 0.01, 0.1, 1000),
        )
        .unwrap();
        if let Some(v) = version {
            ep.server().set_controller_version(v);
        }
        ep.server().set_recording(true);
        let addr = ep.server().local_addr().unwrap();
        let stop = Arc::new(AtomicBool::new(false));
        let (tx, applied) = mpsc::channel();
        let flag = stop.clone();
        let thread = std::thread::spawn(move || {
            let mut k = 0u64;
            while !flag.load(Ordering::SeqCst) {
                k += 1;
                ep.set_flange_wrench(&wrench_of(k));
                let state = RobotState {
                    tcp_pose: Some(pose_of(k)),
                    ..RobotState::with_joints(&q_of(k))
                };
                ep.send_state(&state).unwrap();
                if let Ok(Some(r)) = ep.receive_correction(Duration::from_millis(5)) {
                    let _ = tx.send((r.cycle_id, r.correction.to_array()));
                }
            }
            let counters = ep.server().counters();
            (counters, ep.server().take_recorded())
        });
        Controller {
            addr,
            stop,
            applied,
            thread: Some(thread),
        }
    }

    fn finish(mut self) -> (RtdeServerCounters, Vec<OutputValues>) {
        self.stop.store(true, Ordering::SeqCst);
        self.thread.take().unwrap().join().unwrap()
    }
}

fn config() -> RtdeLinkConfig {
    RtdeLinkConfig {
        register: 24,
        connect_wait: GUARD,
    }
}

fn receive(link: &mut RtdeLink) -> RobotState {
    let start = Instant::now();
    loop {
        assert!(start.elapsed() < GUARD, "no state");
        if let Some(s) = link.receive(Duration::from_millis(20)).unwrap() {
            return s;
        }
    }
}

#[test]
fn deflex_reads_the_twin_s_state_and_its_corrections_reach_the_registers() {
    let controller = Controller::start(None);
    let mut link = RtdeLink::connect(controller.addr, config()).unwrap();
    assert_eq!(link.status().controller_version, [5, 16, 0, 0]);
    assert_eq!(link.period_s(), CONTROLLER_PERIOD_S);
    let mut states = Vec::new();
    for i in 0..200u64 {
        let s = receive(&mut link);
        let c = Correction::from_array([i as f64 * 1e-5, -1e-4, 2e-4, 1e-3, 0.0, -2e-3]);
        link.send_correction(&c).unwrap();
        states.push((s, c));
    }
    // The controller applies each correction (alpha 1: exactly) with its sequence number.
    let mut applied = Vec::new();
    while applied.len() < 150 {
        applied.push(controller.applied.recv_timeout(GUARD).unwrap());
    }
    let counters_link = link.counters();
    drop(link);
    let (counters, published) = controller.finish();
    for (seq, a) in &applied {
        let (_, sent) = states[*seq as usize - 1];
        assert_eq!(*a, sent.to_array(), "sequence {seq}");
    }
    // Each state is the controller's: joints, pose (rotation vector), time.
    for (s, _) in &states {
        let t = s.robot_time_s.unwrap();
        let k = (t / CONTROLLER_PERIOD_S).round() as u64;
        assert!((t - published[k as usize - 1].timestamp).abs() < 1e-12);
        assert_eq!(s.joints(), &q_of(k)[..]);
        let pose = s.tcp_pose.unwrap();
        let want = pose_of(k);
        assert!((pose.translation.vector - want.translation.vector).norm() < 1e-15);
        assert!(
            deflex_model::conventions::rotation_distance(&pose.rotation, &want.rotation) < 1e-12
        );
    }
    assert!(states.windows(2).all(|w| w[1].0.cycle_id > w[0].0.cycle_id));
    assert_eq!(counters_link.answers, 200);
    assert_eq!(counters_link.bad_packets, 0);
    // At least the 150 applications awaited above (the last packages may be unread at the stop).
    assert!(
        counters.input_packages >= 150 && counters.clients == 1,
        "{counters:?}"
    );
    assert_eq!(
        (counters.in_use, counters.not_found, counters.closed_bad),
        (0, 0, 0)
    );
}

#[test]
fn the_flange_sensor_streams_on_its_own_connection_beside_the_robot() {
    let controller = Controller::start(None);
    let mut link = RtdeLink::connect(controller.addr, config()).unwrap();
    let mut sensor = RtdeSensor::connect(controller.addr, GUARD).unwrap();
    sensor.start().unwrap();
    let mut samples = Vec::new();
    let start = Instant::now();
    while samples.len() < 50 {
        assert!(start.elapsed() < GUARD);
        if let Some(s) = link.receive(Duration::from_millis(5)).unwrap() {
            link.send_correction(&Correction::ZERO).unwrap();
            let _ = s;
        }
        if let Some(w) = sensor.receive(Duration::from_millis(5)).unwrap() {
            samples.push(w);
        }
    }
    // The raw wrench of some cycle k: fz = 30 + 0.01 k.
    for w in &samples {
        let k = ((w.wrench[2] - 30.0) / 0.01).round() as u64;
        assert!((w.wrench - wrench_of(k)).norm() < 1e-12, "{:?}", w.wrench);
        assert_eq!(w.status, 0);
    }
    assert!(
        samples
            .windows(2)
            .all(|p| p[1].sequence == p[0].sequence + 1)
    );
    // Software bias: the next sample becomes zero.
    sensor.bias().unwrap();
    let start = Instant::now();
    let biased = loop {
        assert!(start.elapsed() < GUARD);
        if let Some(s) = link.receive(Duration::from_millis(5)).unwrap() {
            link.send_correction(&Correction::ZERO).unwrap();
            let _ = s;
        }
        if let Some(w) = sensor.receive(Duration::from_millis(5)).unwrap() {
            break w;
        }
    };
    assert_eq!(biased.wrench, Wrench::zeros());
    sensor.stop().unwrap();
    drop((link, sensor));
    let (counters, _) = controller.finish();
    assert_eq!(counters.clients, 2);
}

#[test]
fn a_second_client_asking_for_the_registers_is_refused_in_use() {
    let controller = Controller::start(None);
    let first = RtdeLink::connect(controller.addr, config()).unwrap();
    let second = RtdeLink::connect(controller.addr, config()).unwrap_err();
    let text = second.to_string();
    assert!(
        matches!(
            second,
            LinkError::SetupRefused {
                refusal: SetupRefusal::InUse {
                    variable: Variable::InputDoubleRegister(24)
                },
                ..
            }
        ),
        "{text}"
    );
    assert!(
        text.contains("IN_USE") && text.contains("input_double_register_24"),
        "{text}"
    );
    // Other registers are free.
    let third = RtdeLink::connect(
        controller.addr,
        RtdeLinkConfig {
            register: 30,
            ..config()
        },
    );
    assert!(third.is_ok());
    drop((first, third));
    let (counters, _) = controller.finish();
    assert!(counters.in_use >= 1, "{counters:?}");
}

#[test]
fn controllers_too_old_for_path_offset_are_refused_with_the_fallback_named() {
    for (version, text) in [([3, 15, 8, 0], "3.15.8"), ([5, 5, 1, 0], "5.5.1")] {
        let controller = Controller::start(Some(version));
        let e = RtdeLink::connect(controller.addr, config()).unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains(text) && msg.contains("5.6") && msg.contains("simple-tcp"),
            "{msg}"
        );
        controller.finish();
    }
}

/// A hostile controller: answers the set-up like a real one (the robot recipe), then sends
/// `stream` after one good data package, and reports what it read.
fn hostile_controller(
    stream: Vec<u8>,
    ft_found: bool,
) -> (SocketAddr, std::thread::JoinHandle<()>) {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap();
    let thread = std::thread::spawn(move || {
        let (mut s, _) = listener.accept().unwrap();
        s.set_read_timeout(Some(GUARD)).unwrap();
        // The client may close after a refusal: the end of its stream ends the controller.
        let read_package = |s: &mut TcpStream| {
            let mut h = [0u8; 3];
            s.read_exact(&mut h).ok()?;
            let n = u16::from_be_bytes([h[0], h[1]]) as usize - 3;
            let mut p = vec![0u8; n];
            s.read_exact(&mut p).ok()?;
            Some((h[2], p))
        };
        while let Some((t, p)) = read_package(&mut s) {
            let answer = match t {
                b'V' => package(b'V', &[1]),
                b'v' => {
                    let mut v = Vec::new();
                    for x in [5u32, 12, 0, 0] {
                        v.extend_from_slice(&x.to_be_bytes());
                    }
                    package(b'v', &v)
                }
                b'O' => {
                    let names = &p[8..];
                    let types: Vec<&str> = names
                        .split(|&b| b == b',')
                        .map(|n| {
                            let v = Variable::from_name(n).unwrap();
                            if v == Variable::FtRawWrench && !ft_found {
                                "NOT_FOUND"
                            } else {
                                v.field_type().name()
                            }
                        })
                        .collect();
                    let mut a = vec![1u8];
                    a.extend_from_slice(types.join(",").as_bytes());
                    package(b'O', &a)
                }
                b'I' => {
                    let n = p.split(|&b| b == b',').count();
                    let mut a = vec![2u8];
                    a.extend_from_slice(
                        [&["DOUBLE"; 6][..], &["INT32"][..]].concat()[..n]
                            .join(",")
                            .as_bytes(),
                    );
                    package(b'I', &a)
                }
                b'S' => {
                    s.write_all(&package(b'S', &[1])).unwrap();
                    s.write_all(&good_robot_package(1, 0.002)).unwrap();
                    s.write_all(&stream).unwrap();
                    // Then a good one, so the link shows it is still usable.
                    s.write_all(&good_robot_package(1, 0.004)).unwrap();
                    let mut rest = Vec::new();
                    let _ = s.read_to_end(&mut rest);
                    return;
                }
                _ => return,
            };
            s.write_all(&answer).unwrap();
        }
    });
    (addr, thread)
}

/// The robot recipe's data package (7 fields) with recipe id `id` at time `t`.
fn good_robot_package(id: u8, t: f64) -> Vec<u8> {
    let mut p = vec![id];
    p.extend_from_slice(&t.to_be_bytes());
    for k in 0..12 {
        p.extend_from_slice(&(k as f64 * 0.01).to_be_bytes());
    }
    p.extend_from_slice(&7i32.to_be_bytes());
    p.extend_from_slice(&1i32.to_be_bytes());
    p.extend_from_slice(&2u32.to_be_bytes());
    p.extend_from_slice(&5i32.to_be_bytes());
    package(b'U', &p)
}

#[test]
fn a_hostile_controller_s_bad_packages_are_refused_counted_and_the_link_goes_on() {
    let good = good_robot_package(1, 0.003);
    let mut truncated = good.clone();
    truncated.truncate(good.len() - 4);
    let size = (truncated.len() as u16).to_be_bytes();
    truncated[..2].copy_from_slice(&size);
    let mut other_recipe = good.clone();
    other_recipe[3] = 9;
    let mut nan = good.clone();
    nan[4..12].copy_from_slice(&f64::NAN.to_be_bytes());
    let unknown = package(b'X', &[1, 2, 3]);
    let text = package(b'M', b"\x04oops\x04RTDE\x01");
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("truncated", truncated),
        ("other recipe id", other_recipe),
        ("non-finite", nan),
        ("unknown type", unknown),
    ];
    for (name, bad) in cases {
        let mut stream = text.clone();
        stream.extend(bad);
        let (addr, thread) = hostile_controller(stream, true);
        let mut link = RtdeLink::connect(addr, config()).unwrap();
        let first = receive(&mut link);
        assert_eq!(first.robot_time_s, Some(0.002));
        let e = loop {
            match link.receive(Duration::from_millis(50)) {
                Err(e) => break e,
                Ok(None) => continue,
                Ok(Some(s)) => panic!("{name}: took {s:?}"),
            }
        };
        assert!(e.is_bad_packet(), "{name}: {e}");
        let next = receive(&mut link);
        assert_eq!(next.robot_time_s, Some(0.004), "{name}");
        assert_eq!(link.counters().bad_packets, 1, "{name}");
        assert_eq!(link.status().text_messages, 1, "{name}");
        drop(link);
        thread.join().unwrap();
    }
    // Oversized: a size the stream cannot carry ends the session (the framing is lost).
    let (addr, thread) = hostile_controller(vec![0xff, 0xff, b'U', 0, 0, 0], true);
    let mut link = RtdeLink::connect(addr, config()).unwrap();
    receive(&mut link);
    let e = loop {
        match link.receive(Duration::from_millis(50)) {
            Err(e) => break e,
            Ok(_) => continue,
        }
    };
    assert!(
        matches!(
            e,
            LinkError::Oversize {
                capacity: MAX_PACKAGE,
                ..
            }
        ),
        "{e}"
    );
    assert!(!link.is_connected());
    assert_eq!(link.counters().bad_packets, 1);
    drop(link);
    thread.join().unwrap();
}

#[test]
fn a_controller_without_the_flange_sensor_is_refused_not_found() {
    let (addr, thread) = hostile_controller(Vec::new(), false);
    let e = RtdeSensor::connect(addr, GUARD).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("ft_raw_wrench") && msg.contains("NOT_FOUND") && msg.contains("external"),
        "{msg}"
    );
    thread.join().unwrap();
}

#[test]
fn hostile_clients_of_the_twin_s_controller_are_closed_or_answered_and_counted() {
    let mut server = RtdeServer::bind("127.0.0.1:0").unwrap();
    let addr = server.local_addr().unwrap();
    let poll_until = |server: &mut RtdeServer, what: &dyn Fn(&RtdeServerCounters) -> bool| {
        let start = Instant::now();
        while !what(&server.counters()) {
            assert!(start.elapsed() < GUARD, "{:?}", server.counters());
            server.poll_wait(Duration::from_millis(5), 24);
        }
    };
    // Oversized: closed.
    let mut a = TcpStream::connect(addr).unwrap();
    a.write_all(&[0xff, 0xff, b'V']).unwrap();
    poll_until(&mut server, &|c| c.closed_bad == 1);
    // Unknown type, input data before an input recipe, a text message: answered with a warning.
    let mut b = TcpStream::connect(addr).unwrap();
    b.write_all(&package(b'X', &[])).unwrap();
    b.write_all(&package(b'U', &[1, 2, 3])).unwrap();
    b.write_all(&package(b'M', b"\x00\x00\x00")).unwrap();
    poll_until(&mut server, &|c| c.bad_packages == 3);
    b.set_read_timeout(Some(GUARD)).unwrap();
    let mut h = [0u8; 3];
    b.read_exact(&mut h).unwrap();
    assert_eq!(h[2], b'M');
    // Unknown names: NOT_FOUND with recipe id 0.
    b.write_all(&package(b'I', b"input_double_register_24,no_such_thing"))
        .unwrap();
    poll_until(&mut server, &|c| c.not_found == 1);
    // A trailing comma (as SDU's ur_rtde sends) is no extra name.
    let mut c = TcpStream::connect(addr).unwrap();
    c.write_all(&package(
        b'O',
        &[&500.0f64.to_be_bytes()[..], b"timestamp,actual_q,"].concat(),
    ))
    .unwrap();
    c.set_read_timeout(Some(GUARD)).unwrap();
    let start = Instant::now();
    let mut answer = Vec::new();
    while answer.len() < 3 || answer.len() < u16::from_be_bytes([answer[0], answer[1]]) as usize {
        assert!(start.elapsed() < GUARD);
        server.poll_wait(Duration::from_millis(5), 24);
        let mut buf = [0u8; 64];
        c.set_nonblocking(true).unwrap();
        if let Ok(n) = c.read(&mut buf) {
            answer.extend_from_slice(&buf[..n]);
        }
    }
    assert_eq!(answer, package(b'O', b"\x01DOUBLE,VECTOR6D"));
    assert_eq!(server.counters().not_found, 1);
    drop(c);
    // Too many clients: refused.
    let extra: Vec<TcpStream> = (0..10).map(|_| TcpStream::connect(addr).unwrap()).collect();
    poll_until(&mut server, &|c| c.refused_full >= 3);
    assert!(server.client_count() <= server::MAX_CLIENTS);
    drop((a, b, extra));
}

/// When deflex falls silent the twin's URScript program keeps running its cycles on the
/// registers: after the sequence watchdog the offset ramps out through the alpha filter.
#[test]
fn the_twin_s_program_ramps_the_offset_out_when_deflex_falls_silent() {
    let mut ep =
        RtdeRobotEndpoint::bind("127.0.0.1:0", 24, PathOffsetModel::new(0.5, 0.01, 0.1, 5))
            .unwrap();
    assert!(ep.unanswered_cycle().is_none(), "no registers written yet");
    let addr = ep.server().local_addr().unwrap();
    let client = std::thread::spawn(move || {
        let mut link = RtdeLink::connect(addr, config()).unwrap();
        for _ in 0..30 {
            receive(&mut link);
            link.send_correction(&Correction::from_array([0.002, 0.0, -0.001, 0.0, 0.0, 0.0]))
                .unwrap();
        }
        link
    });
    // Serve until 30 corrections were applied (hang guard).
    let start = Instant::now();
    let mut applied = 0;
    let mut last = [0.0; 6];
    while applied < 30 {
        assert!(start.elapsed() < GUARD);
        ep.send_state(&RobotState::with_joints(&q_of(1))).unwrap();
        if let Some(r) = ep.receive_correction(Duration::from_millis(5)).unwrap() {
            applied += 1;
            last = r.correction.to_array();
        }
    }
    let link = client.join().unwrap();
    assert!((last[0] - 0.002).abs() < 1e-6, "{last:?}");
    // deflex silent (the link is alive but sends nothing): 5 cycles held, then the ramp-out.
    let mut held = Vec::new();
    for _ in 0..40 {
        held.push(ep.unanswered_cycle().unwrap().to_array()[0]);
    }
    assert!(
        held[..5].iter().all(|x| (x - 0.002).abs() < 1e-6),
        "{held:?}"
    );
    assert!(held[39] < 0.002 * 1e-9, "{held:?}");
    assert!(held.windows(2).skip(5).all(|w| w[1] < w[0]), "{held:?}");
    drop(link);
}

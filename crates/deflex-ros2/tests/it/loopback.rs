//! The bridge and the sensor link talking to themselves over loopback DDS (RustDDS on both
//! ends; the independent check of the bytes is the Python cyclonedds test in tests/python).
//! Deterministic: every wait for discovery is bounded, and the counted messages are sent only
//! once a first one got through, at reliable QoS with a history deeper than the batch.

use crate::dds::{domain, now_ns, publisher, sensor_settings, subscriber, wait_until, wrench};
use deflex_io::ForceSensorLink;
use deflex_ros2::{
    BridgeSettings, Refusal, Ros2Bridge, Ros2SensorLink, bridge, join, message_type, topic_name,
};
use deflex_telemetry::ros::cycle::STATUS_NAME;
use deflex_telemetry::ros::{
    DiagnosticArrayMsg, JointStateMsg, Ros2Qos, Ros2Topic, WrenchStampedMsg,
};
use deflex_telemetry::{CycleSample, SessionInfo, StreamSource, broadcast};
use std::sync::Arc;
use std::time::{Duration, Instant};

fn sample(cycle: u64) -> CycleSample {
    let mut s = CycleSample {
        time_s: 0.01 * cycle as f64,
        cycle,
        phase_code: 2,
        ..CycleSample::default()
    };
    s.set_q(&[0.1 * cycle as f64, -0.5, 1.0, 0.0, 0.3, cycle as f64 * 1e-3]);
    s.wrench_raw = [1.0, 2.0, 3.0 + cycle as f64, 0.1, 0.2, 0.3];
    s.wrench_tcp = [0.0, 0.0, -(cycle as f64), 0.0, 0.0, 0.0];
    s.correction = [1e-4 * cycle as f64, 0.0, 0.0, 0.0, 0.0, 0.0];
    s.set_tcp_rotation(&nalgebra::Rotation3::identity());
    s
}

#[test]
fn topic_and_type_names_are_ros2_names() {
    assert_eq!(
        topic_name("/deflex", "joint_states"),
        "/deflex/joint_states"
    );
    assert_eq!(topic_name("/", "joint_states"), "/joint_states");
    assert_eq!(
        message_type::<JointStateMsg>().dds_msg_type(),
        "sensor_msgs::msg::dds_::JointState_"
    );
    assert_eq!(
        message_type::<DiagnosticArrayMsg>().dds_msg_type(),
        "diagnostic_msgs::msg::dds_::DiagnosticArray_"
    );
}

/// The bridge publishes every due cycle of the stream, decimated by session time, with the
/// sample's values, the frames of the session and stamps one session-time step apart.
#[test]
fn bridge_publishes_the_stream_over_loopback_dds() {
    let d = domain(0);
    let (mut tx, ring) = broadcast::<CycleSample>(1024);
    let mut info = SessionInfo::new(
        StreamSource::Runtime,
        "tx200",
        (1..=6).map(|i| format!("joint_{i}")).collect(),
    );
    info.sensor_frame = "ati_ft".into();
    let settings = BridgeSettings {
        domain_id: d,
        namespace: "/deflex_test".into(),
        node_name: "bridge".into(),
        qos: Ros2Qos::Reliable,
        depth: 200,
        publish_rate_hz: 50.0,
        diagnostics_rate_hz: 1.0,
        topics: Ros2Topic::ALL.to_vec(),
    };
    let bridge = Ros2Bridge::spawn(&settings, ring.subscribe(), Arc::new(info)).unwrap();
    assert!(
        bridge
            .topics()
            .contains(&"/deflex_test/wrench_raw".to_string())
    );
    let mut node = join(d, "/", "listener").unwrap();
    let joints =
        subscriber::<JointStateMsg>(&mut node, "/deflex_test/joint_states", Ros2Qos::Reliable);
    let raw =
        subscriber::<WrenchStampedMsg>(&mut node, "/deflex_test/wrench_raw", Ros2Qos::Reliable);
    let diag =
        subscriber::<DiagnosticArrayMsg>(&mut node, "/deflex_test/diagnostics", Ros2Qos::Reliable);
    // Warm-up: one sample at a time (cycles 1, 2, … at 0.01 s, each due at 50 Hz since they are
    // 2 cycles apart) until the listener hears one on every topic.
    let mut cycle = 0;
    let (mut heard_joints, mut heard_raw, mut heard_diag) = (false, false, false);
    wait_until("first messages", || {
        cycle += 2;
        tx.publish(&sample(cycle));
        std::thread::sleep(Duration::from_millis(20));
        heard_joints |= std::iter::from_fn(|| joints.take().unwrap()).count() > 0;
        heard_raw |= std::iter::from_fn(|| raw.take().unwrap()).count() > 0;
        heard_diag |= std::iter::from_fn(|| diag.take().unwrap()).count() > 0;
        heard_joints && heard_raw && heard_diag
    });
    // The counted batch: 60 cycles at 100 Hz of session time, of which every second is due
    // at 50 Hz.
    let first = cycle + 1;
    for c in first..first + 60 {
        tx.publish(&sample(c));
        std::thread::sleep(Duration::from_millis(1));
    }
    let mut got_joints = Vec::new();
    let mut got_raw = Vec::new();
    wait_until("the batch", || {
        got_joints.extend(std::iter::from_fn(|| joints.take().unwrap()).map(|m| m.0));
        got_raw.extend(std::iter::from_fn(|| raw.take().unwrap()).map(|m| m.0));
        got_joints.len() >= 30 && got_raw.len() >= 30
    });
    std::thread::sleep(Duration::from_millis(100));
    got_joints.extend(std::iter::from_fn(|| joints.take().unwrap()).map(|m| m.0));
    assert_eq!(got_joints.len(), 30, "one JointState per due cycle");
    // Cycles first+1, first+3, … (0.02 s after the last warm-up cycle, then every 0.02 s).
    let base_stamp = got_joints[0].header.stamp.to_nanos();
    for (k, (j, w)) in got_joints.iter().zip(&got_raw).enumerate() {
        let c = first + 1 + 2 * k as u64;
        let s = sample(c);
        assert_eq!(j.position, s.q().to_vec(), "cycle {c}");
        assert_eq!(j.name[5], "joint_6");
        assert_eq!(w.header.frame_id, "ati_ft");
        assert_eq!(w.wrench.force.z, s.wrench_raw[2]);
        assert_eq!(w.header.stamp, j.header.stamp);
        let dt = j.header.stamp.to_nanos() as i64 - base_stamp as i64;
        assert!(
            (dt - 20_000_000 * k as i64).abs() <= 1,
            "stamp step {dt} at {k}"
        );
    }
    let report = bridge.finish().unwrap();
    assert_eq!(report.lost, 0);
    assert_eq!(report.write_errors, 0);
    assert!(
        report.cycles_read >= 60 && report.cycles_published >= 30,
        "{report:?}"
    );
    // Diagnostics: the controller's status with the bridge's own count.
    let d: Vec<_> = std::iter::from_fn(|| diag.take().unwrap())
        .map(|m| m.0)
        .collect();
    if let Some(last) = d.last() {
        assert_eq!(last.status[0].name, STATUS_NAME);
        assert_eq!(last.status[0].value("phase"), Some("running"));
        assert_eq!(last.status[0].value(bridge::BRIDGE_LOST), Some("0"));
    }
}

/// Good readings reach `receive` with their values; NaN, wrong frame, stale, future and
/// going-back stamps are refused, counted by reason and reported once each as errors.
#[test]
fn sensor_link_takes_good_wrenches_and_refuses_bad_ones() {
    let d = domain(1);
    let mut link = Ros2SensorLink::open(&sensor_settings(d, 64, Ros2Qos::Reliable)).unwrap();
    let mut node = join(d, "/", "driver").unwrap();
    let tx = publisher::<WrenchStampedMsg>(&mut node, "/ati/wrench", Ros2Qos::Reliable);
    // Warm-up until a first reading gets through.
    wait_until("a first reading", || {
        tx.publish(wrench("ati_ft", now_ns(), -1.0)).unwrap();
        matches!(link.receive(Duration::from_millis(20)), Ok(Some(_)))
    });
    while let Ok(Some(_)) = link.receive(Duration::from_millis(50)) {}
    let before = link.counts();
    let t = now_ns();
    let good = [10.0, 20.0, 30.0];
    tx.publish(wrench("ati_ft", t, good[0])).unwrap();
    tx.publish(wrench("ati_ft", t, f64::NAN)).unwrap();
    tx.publish(wrench("tool0", t, 5.0)).unwrap();
    tx.publish(wrench("ati_ft", t - 2_000_000_000, 5.0))
        .unwrap();
    tx.publish(wrench("ati_ft", t + 2_000_000_000, 5.0))
        .unwrap();
    tx.publish(wrench("ati_ft", t + 1_000_000, good[1]))
        .unwrap();
    tx.publish(wrench("ati_ft", t + 500_000, 5.0)).unwrap(); // goes back
    tx.publish(wrench("ati_ft", t + 2_000_000, good[2]))
        .unwrap();
    let mut readings = Vec::new();
    let mut errors = 0;
    wait_until("the batch", || {
        match link.receive(Duration::from_millis(10)) {
            Ok(Some(s)) => readings.push(s),
            Ok(None) => {}
            Err(e) => {
                assert!(e.is_bad_packet(), "{e}");
                errors += 1;
            }
        }
        readings.len() == 3 && errors == 5
    });
    assert_eq!(
        readings.iter().map(|s| s.wrench[2]).collect::<Vec<_>>(),
        good.to_vec()
    );
    assert_eq!(readings[0].wrench.as_slice()[..2], [1.0, -2.0]);
    assert_eq!(readings[0].wrench.as_slice()[3..], [0.1, 0.2, 0.3]);
    let c = link.counts();
    for r in [
        Refusal::NonFinite,
        Refusal::WrongFrame,
        Refusal::Stale,
        Refusal::Future,
        Refusal::OutOfOrder,
    ] {
        assert_eq!(c.refused_for(r) - before.refused_for(r), 1, "{r:?}: {c:?}");
    }
    assert_eq!(c.accepted - before.accepted, 3);
    assert_eq!(c.overflow, 0);
}

/// A flood (thousands of messages as fast as the driver can send) is bounded by the queue: the
/// sensor thread reading slowly gets at most `queue_depth` readings waiting, the rest counted as
/// dropped, and `receive` stays immediate.
#[test]
fn a_flood_is_bounded_and_counted() {
    let d = domain(2);
    let mut link = Ros2SensorLink::open(&sensor_settings(d, 8, Ros2Qos::SensorData)).unwrap();
    let mut node = join(d, "/", "flood").unwrap();
    let tx = publisher::<WrenchStampedMsg>(&mut node, "/ati/wrench", Ros2Qos::SensorData);
    let mut popped = 0u64;
    wait_until("a first reading", || {
        tx.publish(wrench("ati_ft", now_ns(), -1.0)).unwrap();
        let got = matches!(link.receive(Duration::from_millis(20)), Ok(Some(_)));
        popped += u64::from(got);
        got
    });
    for burst in 0..50 {
        for i in 0..100 {
            let _ = tx.publish(wrench("ati_ft", now_ns(), (burst * 100 + i) as f64));
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    // Let the reader take what arrived (bounded by the DDS history and the queue).
    std::thread::sleep(Duration::from_millis(200));
    let t = Instant::now();
    let mut waiting = 0;
    loop {
        match link.receive(Duration::ZERO) {
            Ok(Some(_)) => waiting += 1,
            Ok(None) => break,
            Err(e) => panic!("{e}"),
        }
    }
    assert!(t.elapsed() < Duration::from_millis(100));
    assert!(waiting <= 8, "{waiting} readings waited in a queue of 8");
    popped += waiting;
    // Every accepted reading was either handed over or dropped and counted.
    let c = link.counts();
    assert!(c.received > 1 && c.received <= 5000 + 1000, "{c:?}");
    assert_eq!(c.accepted, popped + c.overflow, "{c:?}");
}

/// The link locks to the writer of its first accepted message: a second driver publishing on
/// the same topic (another participant, valid messages) is refused and counted as
/// `other_writer`, and its values never reach `receive`; the first writer goes on.
#[test]
fn a_second_writer_is_refused_and_counted() {
    let d = domain(3);
    let mut link = Ros2SensorLink::open(&sensor_settings(d, 64, Ros2Qos::Reliable)).unwrap();
    let mut first = join(d, "/", "driver").unwrap();
    let tx = publisher::<WrenchStampedMsg>(&mut first, "/ati/wrench", Ros2Qos::Reliable);
    wait_until("a first reading", || {
        tx.publish(wrench("ati_ft", now_ns(), -1.0)).unwrap();
        matches!(link.receive(Duration::from_millis(20)), Ok(Some(_)))
    });
    let mut second = join(d, "/", "intruder").unwrap();
    let intruder = publisher::<WrenchStampedMsg>(&mut second, "/ati/wrench", Ros2Qos::Reliable);
    let mut values = Vec::new();
    let mut errors = 0u64;
    wait_until("the intruder's messages refused", || {
        intruder.publish(wrench("ati_ft", now_ns(), 999.0)).unwrap();
        tx.publish(wrench("ati_ft", now_ns(), -1.0)).unwrap();
        loop {
            match link.receive(Duration::from_millis(5)) {
                Ok(Some(s)) => values.push(s.wrench[2]),
                Ok(None) => break,
                Err(e) => {
                    assert!(e.is_bad_packet(), "{e}");
                    errors += 1;
                }
            }
        }
        link.counts().refused_for(Refusal::OtherWriter) >= 5
    });
    let c = link.counts();
    assert!(values.iter().all(|&fz| fz == -1.0), "{values:?}");
    assert!(!values.is_empty());
    assert_eq!(
        c.refused_total(),
        c.refused_for(Refusal::OtherWriter),
        "{c:?}"
    );
    assert!(errors <= c.refused_total());
}

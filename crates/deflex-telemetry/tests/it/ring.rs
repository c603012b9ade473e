//! The ring under a concurrent publisher: no torn sample, in order, nothing lost without being
//! counted (that publishing allocates nothing is the facade's `no_alloc::telemetry`). No
//! assertion depends on scheduling: whatever the interleaving, received + lost equals
//! published, and every sample is internally consistent. Also the sample's accessors and the
//! sources' phase names.

use deflex_telemetry::{CycleSample, SeqCell, broadcast};

/// A sample whose every number is derived from `i`: a torn read would mix two of them.
fn stamped(i: u64) -> CycleSample {
    let x = i as f64;
    let mut s = CycleSample {
        time_s: x,
        cycle: i,
        ..CycleSample::default()
    };
    s.q_rad = [x; 8];
    s.wrench_tcp = [x; 6];
    s.correction = [-x; 6];
    s.tcp_position_m = [x; 3];
    s.fault = (i % 7) as u32;
    s
}

fn consistent(s: &CycleSample) -> bool {
    let x = s.cycle as f64;
    s.time_s == x
        && s.q_rad.iter().all(|v| *v == x)
        && s.wrench_tcp.iter().all(|v| *v == x)
        && s.correction.iter().all(|v| *v == -x)
        && s.tcp_position_m.iter().all(|v| *v == x)
        && s.fault == (s.cycle % 7) as u32
}

#[test]
fn concurrent_reader_sees_whole_samples_in_order_and_counts_losses() {
    const N: u64 = 200_000;
    let (mut publisher, ring) = broadcast::<CycleSample>(64);
    let mut sub = ring.subscribe();
    let reader = std::thread::spawn(move || {
        let mut last = None;
        loop {
            match sub.try_next() {
                Some(s) => {
                    assert!(consistent(&s), "torn sample at cycle {}", s.cycle);
                    if let Some(prev) = last {
                        assert!(s.cycle > prev, "out of order: {} after {prev}", s.cycle);
                    }
                    last = Some(s.cycle);
                }
                None if sub.is_finished() => break,
                None => std::thread::yield_now(),
            }
        }
        (sub.received(), sub.lost(), last)
    });
    for i in 0..N {
        publisher.publish(&stamped(i));
    }
    drop(publisher);
    let (received, lost, last) = reader.join().unwrap();
    assert_eq!(received + lost, N, "received {received} lost {lost}");
    assert_eq!(last, Some(N - 1), "the newest sample is never lost");
}

#[test]
fn slow_subscriber_loses_the_oldest_and_keeps_the_newest() {
    let (mut publisher, ring) = broadcast::<CycleSample>(8);
    let mut sub = ring.subscribe();
    for i in 0..20 {
        publisher.publish(&stamped(i));
    }
    let got: Vec<u64> = std::iter::from_fn(|| sub.try_next())
        .map(|s| s.cycle)
        .collect();
    assert_eq!(got, (12..20).collect::<Vec<_>>());
    assert_eq!(sub.lost(), 12);
    // A late joiner sees only what follows; from_oldest sees what the ring still holds.
    let mut late = ring.subscribe();
    assert!(late.try_next().is_none());
    let mut oldest = ring.subscribe_from_oldest();
    assert_eq!(oldest.try_next().map(|s| s.cycle), Some(12));
    assert!(!sub.is_finished());
    drop(publisher);
    assert!(sub.is_finished());
}

#[test]
fn latest_is_the_newest_whole_sample() {
    let (mut publisher, ring) = broadcast::<CycleSample>(4);
    assert!(ring.latest().is_none());
    for i in 0..10 {
        publisher.publish(&stamped(i));
        assert_eq!(ring.latest().map(|s| s.cycle), Some(i));
    }
    // Under a concurrent publisher: always whole, never older than what was seen before.
    let reader = {
        let ring = ring.clone();
        std::thread::spawn(move || {
            let mut last = 0;
            while !ring.is_closed() {
                let s = ring.latest().expect("published");
                assert!(
                    consistent(&s) && s.cycle >= last,
                    "{} after {last}",
                    s.cycle
                );
                last = s.cycle;
            }
        })
    };
    for i in 10..100_000 {
        publisher.publish(&stamped(i));
    }
    drop(publisher);
    reader.join().unwrap();
}

#[test]
fn seqcell_concurrent_reads_are_never_torn() {
    let cell = std::sync::Arc::new(SeqCell::<CycleSample>::new());
    assert!(cell.latest().is_none());
    let done = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let reader = {
        let (cell, done) = (cell.clone(), done.clone());
        std::thread::spawn(move || {
            let mut reads = 0u64;
            while !done.load(std::sync::atomic::Ordering::Acquire) {
                let (s, version) = cell.read();
                if version > 0 {
                    assert!(consistent(&s));
                    reads += 1;
                }
            }
            reads
        })
    };
    for i in 0..100_000 {
        cell.write(&stamped(i));
    }
    done.store(true, std::sync::atomic::Ordering::Release);
    reader.join().unwrap();
    assert_eq!(cell.version(), 100_000);
    assert_eq!(cell.latest().map(|s| s.cycle), Some(99_999));
}

#[test]
fn sample_accessors() {
    let mut s = CycleSample::default();
    assert!(s.loop_gain.is_nan() && s.fault_kind().is_none());
    s.set_q(&[0.1, 0.2, 0.3]);
    assert_eq!(s.q(), &[0.1, 0.2, 0.3]);
    s.fault = CycleSample::fault_to_code(Some(deflex_telemetry::FaultKind::JointJump));
    assert_eq!(s.fault_kind(), Some(deflex_telemetry::FaultKind::JointJump));
    s.phase_code = CycleSample::phase_to_code(deflex_telemetry::Phase::Faulted);
    assert_eq!(s.phase(), deflex_telemetry::Phase::Faulted);
    let r = nalgebra::Rotation3::from_euler_angles(0.1, -0.2, 0.3);
    s.set_tcp_rotation(&r);
    assert!((s.tcp_rotation().matrix() - r.matrix()).norm() < 1e-15);
    s.tcp_position_m = [1.0, 2.0, 3.0];
    s.correction = [0.001, 0.0, -0.002, 0.0, 0.0, 0.0];
    assert_eq!(
        s.program_position_m(),
        nalgebra::Vector3::new(0.999, 2.0, 3.002)
    );
}

#[test]
fn sources_name_their_phases() {
    use deflex_telemetry::{CellState, StreamSource};
    assert_eq!(
        [
            StreamSource::Runtime,
            StreamSource::Twin,
            StreamSource::TwinCell
        ]
        .map(StreamSource::key),
        ["runtime", "twin", "twin-cell"]
    );
    // A controller's stream names the controller's phases, the twin's own its cell's states,
    // by the same codes.
    for source in [StreamSource::Runtime, StreamSource::Twin] {
        for phase in [
            deflex_telemetry::Phase::Taring,
            deflex_telemetry::Phase::Faulted,
        ] {
            assert_eq!(
                source.phase_name(CycleSample::phase_to_code(phase)),
                phase.name()
            );
        }
    }
    for state in CellState::ALL {
        assert_eq!(
            StreamSource::TwinCell.phase_name(state.code()),
            state.name()
        );
    }
    assert_eq!(StreamSource::TwinCell.phase_name(99), "-");
    let info = deflex_telemetry::SessionInfo::new(StreamSource::TwinCell, "tx200", vec![]);
    assert!(info.simulated, "the twin's own stream is SIMULATED");
}

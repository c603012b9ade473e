//! The robot-link thread's per-answer work: the send shaper (rate limit per robot cycle), the
//! correction command read from its sequence cell and the joint map applied (RSI `AK`
//! answers); and the control thread's telemetry publish.

use criterion::{Criterion, black_box, criterion_group, criterion_main};
use deflex_control::JointCorrectionMap;
use deflex_runtime::messages::CorrectionCommand;
use deflex_runtime::send_shaper::{LinkDirective, SendShaper, SendShaperConfig};
use deflex_telemetry::{CycleSample, SeqCell, broadcast};
use nalgebra::{Rotation3, Vector6};

fn bench_answer(c: &mut Criterion) {
    let mut shaper = SendShaper::new(SendShaperConfig::new([0.02; 6], [0.008; 6], 0.004, 0.5));
    let mut k = 0u64;
    c.bench_function("send_shaper_next", |b| {
        b.iter(|| {
            k += 1;
            let t = [(k % 7) as f64 * 1e-3; 6];
            black_box(shaper.next(black_box(&t), LinkDirective::Follow))
        })
    });
    let cell = SeqCell::<CorrectionCommand>::new();
    cell.write(&CorrectionCommand {
        xi: Vector6::repeat(1e-3),
        tcp_rotation: Rotation3::from_euler_angles(0.1, 0.2, 0.3),
        joint_map: JointCorrectionMap::from_fn(|i, j| (i * 6 + j) as f64 * 1e-2),
        directive: 0,
    });
    c.bench_function("command_read_and_joint_map", |b| {
        b.iter(|| {
            let (command, _) = black_box(&cell).read();
            black_box(command.joint_map * command.xi)
        })
    });
}

fn bench_publish(c: &mut Criterion) {
    let (mut publisher, ring) = broadcast::<CycleSample>(8192);
    let mut sink = ring.subscribe();
    let mut sample = CycleSample::default();
    c.bench_function("telemetry_publish", |b| {
        b.iter(|| {
            sample.cycle += 1;
            publisher.publish(black_box(&sample));
            // A sink keeping up, so the ring is read as in a session.
            if sample.cycle % 64 == 0 {
                sink.drain(|s| {
                    black_box(s);
                });
            }
        })
    });
}

criterion_group!(benches, bench_answer, bench_publish);
criterion_main!(benches);

//! What a subscriber costs the publisher: `Publisher::publish` of one cycle sample with no
//! subscriber, with three subscribers that never read, and with three real sinks reading the
//! same ring on their own threads — the live view with a connected page that never reads (its
//! socket fills, its messages are dropped and counted), the MCAP recorder writing a file, and a
//! subscriber that never reads at all. The publisher runs flat out here (millions of samples a
//! second, not 100–250), so the active sinks read the very cache lines it is writing: the
//! worst case of the coherence traffic between them.
//!
//! `cargo bench -p deflex --features bench --bench publish`

use criterion::{Criterion, criterion_group, criterion_main};
use deflex_record::synthetic::SyntheticCell;
use deflex_telemetry::{CycleSample, broadcast};
use std::hint::black_box;
use std::io::Write;
use std::net::TcpStream;
use std::sync::Arc;

const RING: usize = 4096;

fn samples() -> Vec<CycleSample> {
    let mut cell = SyntheticCell::new(0.004, 1, true);
    (0..1024).map(|_| cell.next_sample()).collect()
}

fn publish(c: &mut Criterion) {
    let samples = samples();
    let mut group = c.benchmark_group("publish");

    let (mut publisher, _ring) = broadcast::<CycleSample>(RING);
    let mut i = 0;
    group.bench_function("no subscriber", |b| {
        b.iter(|| {
            i = (i + 1) % samples.len();
            publisher.publish(black_box(&samples[i]));
        })
    });

    // Three subscribers that never read (an absent sink): the publisher never looks at them.
    let (mut publisher, ring) = broadcast::<CycleSample>(RING);
    let absent: Vec<_> = (0..3).map(|_| ring.subscribe()).collect();
    let mut i = 0;
    group.bench_function("3 subscribers that never read", |b| {
        b.iter(|| {
            i = (i + 1) % samples.len();
            publisher.publish(black_box(&samples[i]));
        })
    });
    drop(absent);

    let (mut publisher, ring) = broadcast::<CycleSample>(RING);
    let info = Arc::new(SyntheticCell::new(0.004, 1, true).session_info());
    let view = deflex_view::serve(
        "127.0.0.1:0".parse().unwrap(),
        ring.clone(),
        info.clone(),
        None,
    )
    .expect("view");
    // A page that connects and then never reads: its socket buffer fills up.
    let mut page = TcpStream::connect(view.local_addr()).expect("connect");
    write!(
        page,
        "GET /ws HTTP/1.1\r\nHost: {}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
         Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n",
        view.local_addr()
    )
    .unwrap();
    let dir = std::env::temp_dir().join(format!("deflex-view-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let recorder =
        deflex_record::McapRecorder::spawn(dir.join("bench.mcap"), &ring, info).expect("recorder");
    let idle = ring.subscribe();
    let mut i = 0;
    group.bench_function(
        "3 sinks: view with a stalled page, MCAP recorder, idle subscriber",
        |b| {
            b.iter(|| {
                i = (i + 1) % samples.len();
                publisher.publish(black_box(&samples[i]));
            })
        },
    );
    group.finish();
    let stats = view.stats();
    eprintln!(
        "view: {} samples received, {} lost; {} messages made, {} dropped for the stalled page",
        stats.samples_received, stats.samples_lost, stats.frames_sent, stats.frames_dropped
    );
    drop(publisher);
    match recorder.finish() {
        Ok(r) => eprintln!(
            "recorder: {} cycles recorded, {} lost (the publisher ran flat out)",
            r.stats.recorded, r.lost
        ),
        Err(e) => eprintln!("recorder: {e}"),
    }
    eprintln!("idle subscriber: {} received", idle.received());
    view.shutdown();
    drop(page);
    let _ = std::fs::remove_dir_all(dir);
}

criterion_group!(benches, publish);
criterion_main!(benches);

#![allow(clippy::needless_range_loop)]

use deflex_io::link::ForceSensorLink;
use deflex_io::netft::*;
use deflex_model::Wrench;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::time::Duration;

#[test]
fn request_known_bytes() {
    let b = encode_request(&RdtRequest {
        command: RdtCommand::StartRealtime,
        sample_count: 0,
    });
    assert_eq!(b, [0x12, 0x34, 0x00, 0x02, 0, 0, 0, 0]);
    let b = encode_request(&RdtRequest {
        command: RdtCommand::SetSoftwareBias,
        sample_count: 0x0102_0304,
    });
    assert_eq!(b, [0x12, 0x34, 0x00, 0x42, 1, 2, 3, 4]);
    let r = decode_request(&b).unwrap();
    assert_eq!(r.command, RdtCommand::SetSoftwareBias);
    assert_eq!(r.sample_count, 0x0102_0304);
    assert_eq!(
        decode_request(&[0x12, 0x34, 0, 3, 0, 0, 0, 9])
            .unwrap()
            .command,
        RdtCommand::StartBuffered
    );
    assert_eq!(
        decode_request(&[0x12, 0x34, 0, 0, 0, 0, 0, 0])
            .unwrap()
            .command,
        RdtCommand::Stop
    );
    assert_eq!(
        decode_request(&[0x12, 0x34, 0, 7, 0, 0, 0, 0])
            .unwrap()
            .command,
        RdtCommand::Other(7)
    );
    assert!(decode_request(&[0x43, 0x21, 0, 2, 0, 0, 0, 0]).is_err());
    assert!(decode_request(&[0x12, 0x34, 0, 2]).is_err());
}

#[test]
fn record_known_bytes_to_si() {
    // rdt 1, ft 2, status 0, Fx = 1 500 000 counts, Fy = -250 000,
    // Fz = 0, Tx = 1 000 000, Ty = -1, Tz = 2^31 - 1.
    let b: [u8; 36] = [
        0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0, 0, //
        0x00, 0x16, 0xE3, 0x60, // 1 500 000
        0xFF, 0xFC, 0x2F, 0x70, // -250 000
        0, 0, 0, 0, //
        0x00, 0x0F, 0x42, 0x40, // 1 000 000
        0xFF, 0xFF, 0xFF, 0xFF, // -1
        0x7F, 0xFF, 0xFF, 0xFF,
    ];
    let r = decode_record(&b).unwrap();
    assert_eq!((r.rdt_sequence, r.ft_sequence, r.status), (1, 2, 0));
    let w = NetFtCalibration::default().to_wrench(&r.counts);
    assert_eq!(w[0], 1.5);
    assert_eq!(w[1], -0.25);
    assert_eq!(w[3], 1.0);
    assert_eq!(w[4], -1e-6);
    assert!((w[5] - 2147.483647).abs() < 1e-9);
    assert_eq!(encode_record(&r), b);
    assert!(decode_record(&b[..35]).is_err());
    assert!(decode_records(&b[..35]).is_err());
    assert!(decode_records(&[]).is_err());
    let two = [b, b].concat();
    assert_eq!(decode_records(&two).unwrap().count(), 2);
    let c = NetFtCalibration {
        counts_per_force: 1e6,
        counts_per_torque: 1e6,
    };
    assert!(
        c.to_counts(&Wrench::new(3000.0, 0.0, 0.0, 0.0, 0.0, 0.0))
            .is_err()
    );
    assert!(
        c.to_counts(&Wrench::new(f64::NAN, 0.0, 0.0, 0.0, 0.0, 0.0))
            .is_err()
    );
}

#[test]
fn calibration_from_netftapi2_xml() {
    let xml = r#"<?xml version="1.0" encoding="utf-8"?>
<netft><setserial>FT12345</setserial><cfgnam>Omega160</cfgnam>
<cfgcpf>1000000</cfgcpf><cfgcpt>1000000</cfgcpt><scfgfu>N</scfgfu><scfgtu>N-m</scfgtu>
<comrdtrate>1000</comrdtrate></netft>"#;
    let c = NetFtCalibration::from_netftapi2_xml(xml).unwrap();
    assert_eq!(c, NetFtCalibration::default());
    // Units other than SI: counts per lbf and per lbf-in.
    let xml = "<netft><cfgcpf>4448.2216152605</cfgcpf><cfgcpt>1129.848290276167</cfgcpt><scfgfu>lbf</scfgfu><scfgtu>lbf-in</scfgtu></netft>";
    let c = NetFtCalibration::from_netftapi2_xml(xml).unwrap();
    assert!((c.counts_per_force - 1000.0).abs() < 1e-6);
    assert!((c.counts_per_torque - 10000.0).abs() < 1e-6);
    let xml = "<netft><cfgcpf>1000</cfgcpf><cfgcpt>10</cfgcpt><scfgfu>kN</scfgfu><scfgtu>N-mm</scfgtu></netft>";
    let c = NetFtCalibration::from_netftapi2_xml(xml).unwrap();
    assert!((c.counts_per_force - 1.0).abs() < 1e-12);
    assert!((c.counts_per_torque - 10_000.0).abs() < 1e-9);
    for bad in [
        "<netft><cfgcpt>1</cfgcpt></netft>",
        "<netft><cfgcpf>x</cfgcpf><cfgcpt>1</cfgcpt></netft>",
        "<netft><cfgcpf>0</cfgcpf><cfgcpt>1</cfgcpt></netft>",
        "<netft><cfgcpf>1</cfgcpf><cfgcpt>1</cfgcpt><scfgfu>furlong</scfgfu></netft>",
        "<netft><cfgcpf>1</cfgcpf>",
    ] {
        assert!(NetFtCalibration::from_netftapi2_xml(bad).is_err(), "{bad}");
    }
}

#[test]
fn sequence_tracker_counts_gaps() {
    let mut t = SequenceTracker::default();
    assert_eq!(t.update(10), 0);
    assert_eq!(t.update(11), 0);
    assert_eq!(t.update(14), 2);
    assert_eq!(t.update(13), 0);
    assert_eq!(t.update(14), 0);
    assert_eq!((t.gaps, t.lost, t.out_of_order), (1, 2, 2));
    let mut t = SequenceTracker::default();
    t.update(u32::MAX);
    assert_eq!(t.update(1), 1);
}

#[test]
fn fuzz_decoders_never_panic() {
    let mut rng = StdRng::seed_from_u64(0x5EED_0004);
    let mut ok = 0;
    for _ in 0..20_000 {
        let len = rng.gen_range(0..80);
        let b: Vec<u8> = (0..len).map(|_| rng.r#gen()).collect();
        if decode_record(&b).is_ok() {
            assert_eq!(b.len(), RECORD_LEN);
            ok += 1;
        }
        let _ = decode_records(&b).map(|it| it.count());
        let _ = decode_request(&b);
        let s = String::from_utf8_lossy(&b);
        let _ = NetFtCalibration::from_netftapi2_xml(&s);
    }
    assert!(ok > 0);
}

#[test]
fn loopback_stream_bias_gap_and_fault() {
    let cal = NetFtCalibration::default();
    let mut sensor = NetFtSensorServer::bind("127.0.0.1:0", cal).unwrap();
    let mut client = NetFtClient::new("127.0.0.1:0", sensor.local_addr().unwrap(), cal).unwrap();
    let t = Duration::from_secs(2);
    // Not streaming yet.
    assert!(!sensor.send_sample(&Wrench::repeat(1.0), 0).unwrap());
    client.start().unwrap();
    assert_eq!(
        sensor.poll_request(t).unwrap().unwrap().command,
        RdtCommand::StartRealtime
    );
    assert!(sensor.streaming());
    let w = Wrench::new(10.0, -20.0, 30.5, 1.25, -0.5, 0.0);
    assert!(sensor.send_sample(&w, 0).unwrap());
    let s = client.receive(t).unwrap().unwrap();
    assert_eq!((s.sequence, s.gap, s.is_fault()), (1, 0, false));
    for i in 0..6 {
        assert!((s.wrench[i] - w[i]).abs() < 1e-6);
    }
    // Bias: the last raw wrench is subtracted from then on.
    client.bias().unwrap();
    assert_eq!(
        sensor.poll_request(t).unwrap().unwrap().command,
        RdtCommand::SetSoftwareBias
    );
    sensor
        .send_sample(&Wrench::new(11.0, -20.0, 30.5, 1.25, -0.5, 0.0), 0)
        .unwrap();
    let s = client.receive(t).unwrap().unwrap();
    assert!((s.wrench[0] - 1.0).abs() < 1e-6 && s.wrench[1].abs() < 1e-6);
    // Two lost records, then a faulty one.
    sensor.lose_sample();
    sensor.lose_sample();
    sensor.send_sample(&w, 0x8000_0000).unwrap();
    let s = client.receive(t).unwrap().unwrap();
    assert_eq!((s.sequence, s.gap, s.is_fault()), (5, 2, true));
    let st = client.stats();
    assert_eq!(
        (st.records, st.faults, st.sequence.gaps, st.sequence.lost),
        (3, 1, 1, 2)
    );
    client.stop().unwrap();
    assert_eq!(
        sensor.poll_request(t).unwrap().unwrap().command,
        RdtCommand::Stop
    );
    assert!(!sensor.send_sample(&w, 0).unwrap());
    assert!(client.receive(Duration::from_millis(5)).unwrap().is_none());
    // Finite sample count.
    client
        .send_request(&RdtRequest {
            command: RdtCommand::StartRealtime,
            sample_count: 2,
        })
        .unwrap();
    sensor.poll_request(t).unwrap();
    assert!(sensor.send_sample(&w, 0).unwrap());
    assert!(sensor.send_sample(&w, 0).unwrap());
    assert!(!sensor.send_sample(&w, 0).unwrap());
    // A datagram from a stranger is rejected.
    let stranger = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    client.receive(t).unwrap().unwrap();
    client.receive(t).unwrap().unwrap();
    stranger
        .send_to(
            &encode_record(&RdtRecord::default()),
            client.local_addr().unwrap(),
        )
        .unwrap();
    assert!(client.receive(t).unwrap_err().is_foreign());
}

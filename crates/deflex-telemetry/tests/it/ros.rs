//! Encodings checked against bytes written out by hand from the CDR rules (XCDR1, LE, alignment
//! from the end of the encapsulation header), and the definitions checked for completeness.

use deflex_telemetry::ros::*;

fn le_f64(v: f64) -> [u8; 8] {
    v.to_le_bytes()
}

#[test]
fn vector3_stamped_matches_hand_written_bytes() {
    let msg = Vector3StampedMsg {
        header: HeaderMsg {
            stamp: TimeMsg {
                sec: 1,
                nanosec: 500_000_000,
            },
            frame_id: "base".into(),
        },
        vector: Vector3Msg {
            x: 1.0,
            y: -2.5,
            z: 3.25,
        },
    };
    let mut expected = vec![0, 1, 0, 0]; // CDR_LE encapsulation
    expected.extend([1, 0, 0, 0]); // sec at 0
    expected.extend(500_000_000u32.to_le_bytes()); // nanosec at 4
    expected.extend([5, 0, 0, 0]); // string length with NUL, at 8
    expected.extend(b"base\0"); // 12..17
    expected.extend([0; 7]); // pad to 24 (f64 alignment)
    for v in [1.0, -2.5, 3.25] {
        expected.extend(le_f64(v));
    }
    let bytes = encode(&msg).unwrap();
    assert_eq!(bytes, expected);
    assert_eq!(decode::<Vector3StampedMsg>(&bytes).unwrap(), msg);
}

#[test]
fn diagnostic_array_matches_hand_written_bytes() {
    let msg = DiagnosticArrayMsg {
        header: HeaderMsg::default(),
        status: vec![DiagnosticStatusMsg {
            level: DiagnosticStatusMsg::ERROR,
            name: "a".into(),
            message: String::new(),
            hardware_id: String::new(),
            values: vec![KeyValueMsg {
                key: "k".into(),
                value: "v".into(),
            }],
        }],
    };
    let mut e = vec![0, 1, 0, 0];
    e.extend([0; 8]); // stamp 0..8
    e.extend([1, 0, 0, 0, 0]); // frame_id "" (length 1, NUL) 8..13
    e.extend([0; 3]); // pad to 16
    e.extend([1, 0, 0, 0]); // one status 16..20
    e.push(2); // level (octet) 20
    e.extend([0; 3]); // pad to 24
    e.extend([2, 0, 0, 0]);
    e.extend(b"a\0"); // name 24..30
    e.extend([0; 2]); // pad to 32
    e.extend([1, 0, 0, 0, 0]); // message 32..37
    e.extend([0; 3]); // pad to 40
    e.extend([1, 0, 0, 0, 0]); // hardware_id 40..45
    e.extend([0; 3]); // pad to 48
    e.extend([1, 0, 0, 0]); // one key-value 48..52
    e.extend([2, 0, 0, 0]);
    e.extend(b"k\0"); // 52..58
    e.extend([0; 2]); // pad to 60
    e.extend([2, 0, 0, 0]);
    e.extend(b"v\0"); // 60..66
    let bytes = encode(&msg).unwrap();
    assert_eq!(bytes, e);
    assert_eq!(decode::<DiagnosticArrayMsg>(&bytes).unwrap(), msg);
}

#[test]
fn joint_state_round_trips_and_truncation_is_an_error() {
    let msg = JointStateMsg {
        header: HeaderMsg {
            stamp: TimeMsg::from_nanos(12_345_678_901),
            frame_id: String::new(),
        },
        name: vec!["joint_1".into(), "joint_2".into()],
        position: vec![0.1, -0.2],
        velocity: vec![],
        effort: vec![],
    };
    let bytes = encode(&msg).unwrap();
    assert_eq!(decode::<JointStateMsg>(&bytes).unwrap(), msg);
    for cut in [0, 3, 4, 10, bytes.len() - 1] {
        let err = decode::<JointStateMsg>(&bytes[..cut]).unwrap_err();
        assert!(
            err.to_string().contains("sensor_msgs/msg/JointState"),
            "{err}"
        );
    }
}

#[test]
fn a_huge_sequence_length_is_refused_without_allocating_it() {
    // JointState with its name count set to 2³¹: the bound on the input length stops it.
    let msg = JointStateMsg::default();
    let mut bytes = encode(&msg).unwrap();
    // stamp (8) + frame_id length and NUL (5) + pad (3): the name count is at 4 + 16.
    bytes[20..24].copy_from_slice(&(1u32 << 31).to_le_bytes());
    assert!(decode::<JointStateMsg>(&bytes).is_err());
    let big = vec![0u8; MAX_MESSAGE_BYTES + 1];
    assert!(matches!(
        decode::<JointStateMsg>(&big),
        Err(CdrError::TooLarge { .. })
    ));
}

#[test]
fn time_converts_nanoseconds_both_ways() {
    let t = TimeMsg::from_nanos(1_700_000_000_123_456_789);
    assert_eq!(t.sec, 1_700_000_000);
    assert_eq!(t.nanosec, 123_456_789);
    assert_eq!(t.to_nanos(), 1_700_000_000_123_456_789);
}

/// Every type a definition uses is a ROS primitive or has its own `MSG:` section, and each
/// section appears once: what a schema reader needs to resolve the message.
fn check_definition(name: &str, text: &str) {
    const PRIMITIVES: [&str; 15] = [
        "bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16", "int32",
        "uint32", "int64", "uint64", "string", "wstring",
    ];
    let sep = "=".repeat(80);
    let mut sections: Vec<(String, Vec<String>)> = Vec::new();
    let own_package = name.split('/').next().unwrap().to_string();
    let mut current = (format!("{own_package}/self"), Vec::new());
    for line in text.lines() {
        if line == sep {
            sections.push(std::mem::take(&mut current));
        } else if let Some(dep) = line.strip_prefix("MSG: ") {
            current.0 = dep.to_string();
        } else {
            current.1.push(line.to_string());
        }
    }
    sections.push(current);
    let names: Vec<&str> = sections.iter().map(|(n, _)| n.as_str()).collect();
    for (i, n) in names.iter().enumerate() {
        assert!(!names[i + 1..].contains(n), "{name}: {n} twice");
    }
    for (section, lines) in &sections {
        let package = section.split('/').next().unwrap();
        for line in lines {
            let ty = line.split_whitespace().next().unwrap();
            let base = ty.trim_end_matches("[]");
            if PRIMITIVES.contains(&base) {
                continue;
            }
            let full = if base.contains('/') {
                base.to_string()
            } else {
                format!("{package}/{base}")
            };
            assert!(names.contains(&full.as_str()), "{name}: {full} undefined");
        }
    }
}

#[test]
fn every_definition_resolves() {
    for (name, text) in [
        (Vector3StampedMsg::NAME, Vector3StampedMsg::DEFINITION),
        (PoseStampedMsg::NAME, PoseStampedMsg::DEFINITION),
        (WrenchStampedMsg::NAME, WrenchStampedMsg::DEFINITION),
        (TwistStampedMsg::NAME, TwistStampedMsg::DEFINITION),
        (JointStateMsg::NAME, JointStateMsg::DEFINITION),
        (DiagnosticArrayMsg::NAME, DiagnosticArrayMsg::DEFINITION),
        (HeaderMsg::NAME, HeaderMsg::DEFINITION),
    ] {
        check_definition(name, text);
    }
    assert!(WrenchStampedMsg::DEFINITION.starts_with("std_msgs/Header header\nWrench wrench\n"));
}

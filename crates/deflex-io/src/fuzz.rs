//! Fuzz targets, one per wire parser: random bytes, structure-aware random text and mutations
//! of valid messages (bit flips, deletions, insertions, truncations, duplicated spans, special
//! numbers) are fed to each parser, which must never panic, and whatever it accepts must satisfy
//! the parser's promises (finite values, counts in range, a message that formats again).
//!
//! `cargo test -p deflex-io` runs [`QUICK_COUNT`] inputs per target with a fixed seed; the full
//! count is `cargo run --release -p deflex-io --example fuzz -- --count 1000000` (every target,
//! or `--target rsi|egm|staubli|simple-udp|simple-tcp|netft`, `--seed N`).

use crate::egm::{decode_path_corr, decode_robot};
use crate::netft::{Calibration, decode_record, decode_records, decode_request};
use crate::rsi::{format_rob, format_sen, format_sen_joints, parse_rob, parse_sen};
use crate::simple_tcp::LineBuf;
use crate::simple_udp::{parse_correction_line, parse_joints_line};
use crate::staubli::{decode_correction, decode_state};
use crate::{LinkError, MAX_JOINTS};

/// Inputs per target in `cargo test`.
pub const QUICK_COUNT: u64 = 30_000;

/// A parser under test.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// KUKA RSI `<Rob>` and `<Sen>` XML.
    Rsi,
    /// ABB EGM `EgmRobot` (hand walker and prost) and `EgmSensorPathCorr`.
    Egm,
    /// deflex/Stäubli binary state and correction messages.
    Staubli,
    /// Simple line protocol datagrams (`q …`, `corr …`, `(…)`).
    SimpleUdp,
    /// The same lines as a TCP byte stream cut into random chunks (line assembly + parsing).
    SimpleTcp,
    /// ATI Net F/T RDT requests, records and `netftapi2.xml`.
    NetFt,
}

impl Target {
    /// Every target.
    pub const ALL: [Target; 6] = [
        Target::Rsi,
        Target::Egm,
        Target::Staubli,
        Target::SimpleUdp,
        Target::SimpleTcp,
        Target::NetFt,
    ];

    /// Command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Target::Rsi => "rsi",
            Target::Egm => "egm",
            Target::Staubli => "staubli",
            Target::SimpleUdp => "simple-udp",
            Target::SimpleTcp => "simple-tcp",
            Target::NetFt => "netft",
        }
    }

    /// From [`Target::name`].
    pub fn from_name(name: &str) -> Option<Target> {
        Target::ALL.into_iter().find(|t| t.name() == name)
    }
}

/// What a fuzz run did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FuzzReport {
    /// The target.
    pub target: Target,
    /// Inputs fed.
    pub inputs: u64,
    /// Inputs some parser of the target accepted.
    pub accepted: u64,
}

/// SplitMix64: a small deterministic generator (fuzzing needs reproducible streams, not
/// statistical quality).
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// A stream from `seed`.
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }
    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in `0..n` (`n > 0`).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }
    /// True with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64 <= p
    }
    /// A random byte.
    pub fn byte(&mut self) -> u8 {
        self.next_u64() as u8
    }
}

/// Text fragments that make parsers work hard: special numbers and separators.
const SPECIALS: [&str; 16] = [
    "nan",
    "inf",
    "-inf",
    "1e308",
    "1e309",
    "-0",
    "0x10",
    "",
    " ",
    "\"",
    "<",
    ">",
    "/>",
    "18446744073709551616",
    "-1",
    "1e-320",
];

/// Mutates `src` into `out`: a few random edits.
pub fn mutate(rng: &mut Rng, src: &[u8], alphabet: &[u8], out: &mut Vec<u8>) {
    out.clear();
    out.extend_from_slice(src);
    for _ in 0..1 + rng.below(6) {
        if out.is_empty() {
            out.push(rng.byte());
            continue;
        }
        let i = rng.below(out.len());
        match rng.below(8) {
            0 => out[i] ^= 1 << rng.below(8),
            1 => out[i] = rng.byte(),
            2 => {
                out.remove(i);
            }
            3 => out.insert(i, alphabet[rng.below(alphabet.len())]),
            4 => out.truncate(i),
            5 => {
                let j = i + rng.below(out.len() - i + 1);
                let chunk: Vec<u8> = out[i..j].to_vec();
                let at = rng.below(out.len() + 1);
                out.splice(at..at, chunk);
            }
            6 => {
                let s = SPECIALS[rng.below(SPECIALS.len())].as_bytes();
                let j = (i + 1 + rng.below(8)).min(out.len());
                out.splice(i..j, s.iter().copied());
            }
            _ => {
                let j = (i + 1 + rng.below(4)).min(out.len());
                out.drain(i..j);
            }
        }
    }
}

/// One input: random bytes, random text over `alphabet`, or a mutation of a seed.
fn input(rng: &mut Rng, seeds: &[Vec<u8>], alphabet: &[u8], max_len: usize, out: &mut Vec<u8>) {
    match rng.below(4) {
        0 => {
            out.clear();
            let n = rng.below(max_len);
            out.extend((0..n).map(|_| rng.byte()));
        }
        1 => {
            out.clear();
            let n = rng.below(max_len);
            out.extend((0..n).map(|_| alphabet[rng.below(alphabet.len())]));
        }
        _ => {
            let seed = &seeds[rng.below(seeds.len())];
            mutate(rng, seed, alphabet, out);
        }
    }
}

fn finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// Whatever a parser returns as an error must be a packet error, not a socket one.
fn bad(e: &LinkError) {
    assert!(
        e.is_bad_packet(),
        "a parser returned a non-packet error: {e}"
    );
}

fn rsi_seeds() -> Vec<Vec<u8>> {
    let mut rob = [0u8; 1024];
    let t = crate::rsi::RobTelegram {
        actual_pose: Some(crate::Pose6 {
            position_m: [1.2, -0.03, 0.8],
            zyx_rad: [1.5, -0.2, 3.1],
        }),
        setpoint_pose: None,
        q_rad: Some([0.1, -1.5, 1.6, 0.0, 0.7, -3.0]),
        delay: 3,
        ipoc: 4_208_138_482,
    };
    let n = format_rob(&t, &mut rob).expect("seed");
    let mut sen = [0u8; 1024];
    let m = format_sen(&[0.001; 6], 77, "ImFree", Some("deflex"), &mut sen).expect("seed");
    let mut ak = [0u8; 1024];
    let k = format_sen_joints(
        crate::rsi::JointTag::Ak,
        &[0.01; 6],
        78,
        "ImFree",
        None,
        &mut ak,
    )
    .expect("seed");
    vec![rob[..n].to_vec(), sen[..m].to_vec(), ak[..k].to_vec()]
}

fn egm_seeds() -> Vec<Vec<u8>> {
    use prost::Message;
    let mut m = crate::egm::msg::EgmRobot::default();
    let mut s = crate::RobotState::with_joints(&[0.1, -0.5, 1.0, 0.0, 0.4, 3.0]);
    s.tcp_pose = Some(crate::Pose6 {
        position_m: [1.0, 0.5, 0.3],
        zyx_rad: [0.3, -0.2, 2.9],
    });
    crate::egm::fill_robot_msg(&mut m, &s, 7, 1234, false);
    let robot = m.encode_to_vec();
    let seven = {
        let s = crate::RobotState::with_joints(&[0.1, -0.5, 0.7, 1.0, 0.0, 0.4, 3.0]);
        crate::egm::fill_robot_msg(&mut m, &s, 8, 1238, true);
        m.encode_to_vec()
    };
    let mut pc = [0u8; 256];
    let n = crate::egm::encode_path_corr(3, 4, [0.001, -0.002, 0.003], 10, &mut pc).expect("seed");
    vec![robot, seven, pc[..n].to_vec()]
}

fn staubli_seeds() -> Vec<Vec<u8>> {
    use crate::staubli::*;
    let mut a = [0u8; STATE_LEN];
    encode_state(
        &StateMsg {
            header: Header {
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
    .expect("seed");
    let mut b = [0u8; CORRECTION_LEN];
    encode_correction(
        &CorrectionMsg {
            header: Header {
                flags: FLAG_ACTIVE,
                seq: 10,
                ack: 9,
                timestamp_s: 1.504,
            },
            values: [1e-3, -2e-3, 5e-4, 1e-3, 0.0, -1e-3],
        },
        &mut b,
    )
    .expect("seed");
    vec![a.to_vec(), b.to_vec()]
}

fn line_seeds() -> Vec<Vec<u8>> {
    vec![
        b"q 0.1 -1.57 1.2 0 3.25 -6\n".to_vec(),
        b"q [0.1, -1.57, 1.2, 0.0, 3.25, -6.0, 0.5]\r\n".to_vec(),
        b"corr 0.001 0 -0.0005 0 0.0001 0\n".to_vec(),
        b"(0.001000000,0.000000000,-0.500000000,0.000000000,0.100000000,0.000000000)\n".to_vec(),
    ]
}

fn netft_seeds() -> Vec<Vec<u8>> {
    use crate::netft::*;
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
    vec![rec.to_vec(), two, req.to_vec(), xml]
}

/// Feeds `count` inputs to `target`'s parsers (seeded by `seed`). Panics on a violated promise
/// (or a panicking parser): run it under `catch_unwind` to report.
pub fn run(target: Target, count: u64, seed: u64) -> FuzzReport {
    let mut rng = Rng::new(seed ^ (target as u64).wrapping_mul(0x1000_0000_01B3));
    let mut buf = Vec::with_capacity(4096);
    let mut accepted = 0u64;
    match target {
        Target::Rsi => {
            let seeds = rsi_seeds();
            let alphabet = b"<>/=\" RobSenRIstKorrAIPosAKDelayIPOCXYZABC0123456789.-eE\n";
            for _ in 0..count {
                input(&mut rng, &seeds, alphabet, 600, &mut buf);
                match parse_rob(&buf) {
                    Ok(t) => {
                        accepted += 1;
                        assert!(t.q_rad.is_none_or(|q| finite(&q)));
                        for p in [t.actual_pose, t.setpoint_pose].into_iter().flatten() {
                            assert!(finite(&p.position_m) && finite(&p.zyx_rad));
                        }
                        // What parses formats again.
                        let mut out = [0u8; 2048];
                        assert!(format_rob(&t, &mut out).is_ok());
                    }
                    Err(e) => bad(&e),
                }
                match parse_sen(&buf) {
                    Ok(s) => {
                        accepted += 1;
                        assert!(s.rkorr.is_some() || s.joints_rad.is_some());
                        assert!(s.rkorr.is_none_or(|v| finite(&v)));
                        assert!(s.joints_rad.is_none_or(|v| finite(&v)));
                    }
                    Err(e) => bad(&e),
                }
            }
        }
        Target::Egm => {
            use prost::Message;
            let seeds = egm_seeds();
            let alphabet = &[
                0x08, 0x09, 0x0a, 0x10, 0x12, 0x18, 0x1a, 0x80, 0xff, 0x00, 0x7f,
            ];
            for _ in 0..count {
                input(&mut rng, &seeds, alphabet, 300, &mut buf);
                match decode_robot(&buf) {
                    Ok(f) => {
                        accepted += 1;
                        assert!(f.n_joints <= 6 && f.n_external <= 6);
                        assert!(finite(&f.q_rad[..f.n_joints]));
                        if let Some(p) = f.tcp_pose {
                            assert!(finite(&p.position_m));
                        }
                        // The hand walker never accepts less than prost would decode, and
                        // agrees with it on the joints when both succeed.
                        if let Ok(p) = crate::egm::msg::EgmRobot::decode(&buf[..])
                            && let Some(j) = p.feed_back.and_then(|fb| fb.joints)
                            && j.joints.len() == f.n_joints
                        {
                            for (a, b) in j.joints.iter().zip(&f.q_rad) {
                                assert!((a.to_radians() - b).abs() <= 1e-12 * b.abs().max(1.0));
                            }
                        }
                        for seven in [false, true] {
                            let cfg = crate::egm::EgmConfig {
                                seven_axis: seven,
                                ..Default::default()
                            };
                            if let Ok((q, n)) = cfg.chain_joints(&f) {
                                assert!((1..=MAX_JOINTS).contains(&n) && finite(&q));
                            }
                        }
                    }
                    Err(e) => bad(&e),
                }
                match decode_path_corr(&buf) {
                    Ok(p) => {
                        accepted += 1;
                        assert!(finite(&p.dp_m));
                    }
                    Err(e) => bad(&e),
                }
            }
        }
        Target::Staubli => {
            let seeds = staubli_seeds();
            let alphabet = b"DFLX\x01\x02\x00\xff";
            for _ in 0..count {
                input(&mut rng, &seeds, alphabet, 120, &mut buf);
                match decode_state(&buf) {
                    Ok(m) => {
                        accepted += 1;
                        assert!(finite(&m.q_rad) && m.header.timestamp_s.is_finite());
                    }
                    Err(e) => bad(&e),
                }
                match decode_correction(&buf) {
                    Ok(m) => {
                        accepted += 1;
                        assert!(finite(&m.values));
                    }
                    Err(e) => bad(&e),
                }
            }
        }
        Target::SimpleUdp => {
            let seeds = line_seeds();
            let alphabet = b"qcor ()[],.-+eE0123456789\n\r\tnaif";
            for _ in 0..count {
                input(&mut rng, &seeds, alphabet, 200, &mut buf);
                match parse_joints_line(&buf) {
                    Ok((q, n)) => {
                        accepted += 1;
                        assert!((1..=MAX_JOINTS).contains(&n) && finite(&q));
                        // Plausible joint values format again (huge ones need more digits than a
                        // line holds: an error, not a panic).
                        let mut out = [0u8; 512];
                        let formatted = crate::simple_udp::format_joints_line(&q[..n], &mut out);
                        assert!(formatted.is_ok() || q[..n].iter().any(|v| v.abs() >= 1e6));
                    }
                    Err(e) => bad(&e),
                }
                match parse_correction_line(&buf) {
                    Ok(c) => {
                        accepted += 1;
                        assert!(c.is_finite());
                    }
                    Err(e) => bad(&e),
                }
            }
        }
        Target::SimpleTcp => {
            let seeds = line_seeds();
            let alphabet = b"qcor ()[],.-+eE0123456789\n\n\n\r\t";
            let mut lines = LineBuf::new();
            for _ in 0..count {
                input(&mut rng, &seeds, alphabet, 1500, &mut buf);
                // The stream arrives in chunks of random size, as TCP reads do.
                let mut fed = 0;
                while fed < buf.len() {
                    while let Some(r) = lines.take_line() {
                        assert!(r.start <= r.end && r.end <= lines.buf.len());
                        assert!(!lines.buf[r.clone()].contains(&b'\n'));
                        match parse_joints_line(&lines.buf[r]) {
                            Ok((q, n)) => {
                                accepted += 1;
                                assert!((1..=MAX_JOINTS).contains(&n) && finite(&q));
                            }
                            Err(e) => bad(&e),
                        }
                    }
                    match lines.space() {
                        Ok(space) => {
                            let k = (1 + rng.below(64)).min(space.len()).min(buf.len() - fed);
                            space[..k].copy_from_slice(&buf[fed..fed + k]);
                            lines.commit(k);
                            fed += k;
                        }
                        Err(e) => bad(&e),
                    }
                }
            }
        }
        Target::NetFt => {
            let seeds = netft_seeds();
            let alphabet = b"\x12\x34\x00\x02\x42\xff<>/cfgcpfN-m0123456789.";
            for _ in 0..count {
                input(&mut rng, &seeds, alphabet, 400, &mut buf);
                match decode_records(&buf) {
                    Ok(records) => {
                        accepted += 1;
                        let cal = Calibration::default();
                        for r in records {
                            assert!(finite(&cal.to_wrench(&r.counts)));
                        }
                    }
                    Err(e) => bad(&e),
                }
                if let Err(e) = decode_record(&buf) {
                    bad(&e);
                }
                if decode_request(&buf).is_ok() {
                    accepted += 1;
                }
                if let Ok(text) = std::str::from_utf8(&buf)
                    && let Ok(c) = Calibration::from_netftapi2_xml(text)
                {
                    accepted += 1;
                    assert!(c.counts_per_force > 0.0 && c.counts_per_force.is_finite());
                    assert!(c.counts_per_torque > 0.0 && c.counts_per_torque.is_finite());
                }
            }
        }
    }
    FuzzReport {
        target,
        inputs: count,
        accepted,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The quick count of every target: no panic, some inputs accepted (the mutations are
    /// not all rejections), deterministic.
    #[test]
    fn every_parser_survives_the_quick_count() {
        for target in Target::ALL {
            let report = run(target, QUICK_COUNT, 0x5EED_F022);
            assert_eq!(report.inputs, QUICK_COUNT);
            assert!(report.accepted > 0, "{target:?}: nothing accepted");
            assert_eq!(report, run(target, QUICK_COUNT, 0x5EED_F022), "{target:?}");
        }
    }
}

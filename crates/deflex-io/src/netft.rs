//! ATI Net F/T Raw Data Transfer (RDT) over UDP, port [`PORT`].
//!
//! * Request (client → sensor), 8 bytes big-endian: header `0x1234` (u16),
//!   command (u16: `0x0000` stop, `0x0002` start high-speed real-time,
//!   `0x0003` start high-speed buffered, `0x0042` set software bias), sample
//!   count (u32, 0 = infinite).
//! * Record (sensor → client), 36 bytes big-endian: `rdt_sequence` (u32,
//!   incremented per record sent), `ft_sequence` (u32, internal sample
//!   counter), `status` (u32, non-zero = fault), then Fx Fy Fz Tx Ty Tz as
//!   i32 **counts**. Buffered mode packs several records in one datagram.
//!
//! Counts are converted with the calibration's counts per force and counts
//! per torque ([`NetFtCalibration`], default 1 000 000 counts per N and per N·m,
//! the Net F/T factory setting), which can be read from the sensor's
//! `/netftapi2.xml` page (`cfgcpf`, `cfgcpt`, with units `scfgfu`,
//! `scfgtu`) by [`NetFtCalibration::from_netftapi2_xml`] — a pure parser, the
//! HTTP fetch is the caller's business. The client tracks `rdt_sequence`
//! gaps ([`SequenceTracker`]) and status faults ([`NetFtStats`]).

use crate::error::{LinkError, Protocol};
use crate::link::{ForceSensorLink, WrenchSample};
use crate::udp::{UdpEndpoint, parse_f64};
use crate::xml::{XmlEvent, XmlScanner, name_eq};
use deflex_model::Wrench;
use std::net::{SocketAddr, ToSocketAddrs};
use std::time::Duration;

/// RDT UDP port of the sensor.
pub const PORT: u16 = 49152;
/// Request header.
pub const REQUEST_HEADER: u16 = 0x1234;
/// Request length.
pub const REQUEST_LEN: usize = 8;
/// Record length.
pub const RECORD_LEN: usize = 36;
/// Net F/T factory counts per force unit and per torque unit.
pub const DEFAULT_COUNTS: f64 = 1_000_000.0;

const P: Protocol = Protocol::NetFt;
const fn bad(reason: &'static str) -> LinkError {
    LinkError::malformed(P, reason)
}

/// An RDT command.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RdtCommand {
    /// `0x0000`: stop streaming.
    Stop,
    /// `0x0002`: start high-speed real-time streaming.
    StartRealtime,
    /// `0x0003`: start high-speed buffered streaming.
    StartBuffered,
    /// `0x0042`: set software bias.
    SetSoftwareBias,
    /// Any other command code.
    Other(u16),
}

impl RdtCommand {
    /// Wire code.
    pub fn code(self) -> u16 {
        match self {
            RdtCommand::Stop => 0x0000,
            RdtCommand::StartRealtime => 0x0002,
            RdtCommand::StartBuffered => 0x0003,
            RdtCommand::SetSoftwareBias => 0x0042,
            RdtCommand::Other(c) => c,
        }
    }
    /// From a wire code.
    pub fn from_code(c: u16) -> Self {
        match c {
            0x0000 => RdtCommand::Stop,
            0x0002 => RdtCommand::StartRealtime,
            0x0003 => RdtCommand::StartBuffered,
            0x0042 => RdtCommand::SetSoftwareBias,
            c => RdtCommand::Other(c),
        }
    }
}

/// An RDT request.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RdtRequest {
    /// Command.
    pub command: RdtCommand,
    /// Number of samples to send (0 = infinite).
    pub sample_count: u32,
}

/// Encodes a request.
pub fn encode_request(r: &RdtRequest) -> [u8; REQUEST_LEN] {
    let mut b = [0u8; REQUEST_LEN];
    b[0..2].copy_from_slice(&REQUEST_HEADER.to_be_bytes());
    b[2..4].copy_from_slice(&r.command.code().to_be_bytes());
    b[4..8].copy_from_slice(&r.sample_count.to_be_bytes());
    b
}

/// Decodes a request (sensor side).
pub fn decode_request(b: &[u8]) -> Result<RdtRequest, LinkError> {
    if b.len() != REQUEST_LEN {
        return Err(LinkError::Truncated {
            protocol: P,
            expected: REQUEST_LEN,
            got: b.len(),
        });
    }
    if u16::from_be_bytes([b[0], b[1]]) != REQUEST_HEADER {
        return Err(bad("request header is not 0x1234"));
    }
    Ok(RdtRequest {
        command: RdtCommand::from_code(u16::from_be_bytes([b[2], b[3]])),
        sample_count: u32::from_be_bytes([b[4], b[5], b[6], b[7]]),
    })
}

/// One RDT record, raw.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RdtRecord {
    /// Record sequence number.
    pub rdt_sequence: u32,
    /// Internal sample sequence number.
    pub ft_sequence: u32,
    /// Status word (non-zero = fault).
    pub status: u32,
    /// Fx Fy Fz Tx Ty Tz in counts.
    pub counts: [i32; 6],
}

/// Encodes a record.
pub fn encode_record(r: &RdtRecord) -> [u8; RECORD_LEN] {
    let mut b = [0u8; RECORD_LEN];
    b[0..4].copy_from_slice(&r.rdt_sequence.to_be_bytes());
    b[4..8].copy_from_slice(&r.ft_sequence.to_be_bytes());
    b[8..12].copy_from_slice(&r.status.to_be_bytes());
    for (i, c) in r.counts.iter().enumerate() {
        b[12 + 4 * i..16 + 4 * i].copy_from_slice(&c.to_be_bytes());
    }
    b
}

fn be32(b: &[u8], i: usize) -> [u8; 4] {
    [b[i], b[i + 1], b[i + 2], b[i + 3]]
}

/// Decodes exactly one 36-byte record.
pub fn decode_record(b: &[u8]) -> Result<RdtRecord, LinkError> {
    if b.len() != RECORD_LEN {
        return Err(LinkError::Truncated {
            protocol: P,
            expected: RECORD_LEN,
            got: b.len(),
        });
    }
    let mut counts = [0i32; 6];
    for (i, c) in counts.iter_mut().enumerate() {
        *c = i32::from_be_bytes(be32(b, 12 + 4 * i));
    }
    Ok(RdtRecord {
        rdt_sequence: u32::from_be_bytes(be32(b, 0)),
        ft_sequence: u32::from_be_bytes(be32(b, 4)),
        status: u32::from_be_bytes(be32(b, 8)),
        counts,
    })
}

/// Splits a datagram of one or more records (buffered mode).
pub fn decode_records(b: &[u8]) -> Result<impl Iterator<Item = RdtRecord> + '_, LinkError> {
    if b.is_empty() || !b.len().is_multiple_of(RECORD_LEN) {
        return Err(bad("datagram length is not a positive multiple of 36"));
    }
    Ok(b.chunks_exact(RECORD_LEN)
        .filter_map(|c| decode_record(c).ok()))
}

/// Conversion between counts and SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NetFtCalibration {
    /// Counts per newton.
    pub counts_per_force: f64,
    /// Counts per newton-metre.
    pub counts_per_torque: f64,
}

impl Default for NetFtCalibration {
    fn default() -> Self {
        NetFtCalibration {
            counts_per_force: DEFAULT_COUNTS,
            counts_per_torque: DEFAULT_COUNTS,
        }
    }
}

/// Newtons per force unit named as in `scfgfu`.
pub fn force_unit_to_newton(u: &str) -> Option<f64> {
    Some(match u.trim().to_ascii_lowercase().as_str() {
        "n" => 1.0,
        "kn" => 1000.0,
        "lbf" | "lb" => 4.448_221_615_260_5,
        "klbf" => 4_448.221_615_260_5,
        "g" | "gf" => 0.009_806_65,
        "kg" | "kgf" => 9.806_65,
        _ => return None,
    })
}

/// Newton-metres per torque unit named as in `scfgtu`.
pub fn torque_unit_to_newton_metre(u: &str) -> Option<f64> {
    Some(match u.trim().to_ascii_lowercase().as_str() {
        "n-m" | "nm" | "n·m" => 1.0,
        "n-mm" | "nmm" => 1e-3,
        "kn-m" => 1000.0,
        "lbf-in" | "lb-in" => 0.112_984_829_027_616_7,
        "lbf-ft" | "lb-ft" => 1.355_817_948_331_400_4,
        "klbf-in" => 112.984_829_027_616_7,
        "kgf-cm" | "kg-cm" => 0.098_066_5,
        "gf-cm" | "g-cm" => 9.806_65e-5,
        _ => return None,
    })
}

impl NetFtCalibration {
    /// Counts → `[Fx Fy Fz]` N, `[Tx Ty Tz]` N·m.
    pub fn to_wrench(&self, counts: &[i32; 6]) -> Wrench {
        let mut w = Wrench::zeros();
        for i in 0..6 {
            let k = if i < 3 {
                self.counts_per_force
            } else {
                self.counts_per_torque
            };
            w[i] = f64::from(counts[i]) / k;
        }
        w
    }

    /// SI wrench → counts (rounded); error if a value does not fit in i32.
    pub fn to_counts(&self, w: &Wrench) -> Result<[i32; 6], LinkError> {
        let mut c = [0i32; 6];
        for i in 0..6 {
            let k = if i < 3 {
                self.counts_per_force
            } else {
                self.counts_per_torque
            };
            let v = (w[i] * k).round();
            if !(v >= f64::from(i32::MIN) && v <= f64::from(i32::MAX)) {
                return Err(LinkError::InvalidValue {
                    protocol: P,
                    reason: "wrench out of the i32 count range",
                });
            }
            c[i] = v as i32;
        }
        Ok(c)
    }

    /// Reads `cfgcpf` and `cfgcpt` (and the units `scfgfu`, `scfgtu`, which
    /// default to N and N-m) from the text of the sensor's `/netftapi2.xml`.
    pub fn from_netftapi2_xml(xml: &str) -> Result<Self, LinkError> {
        let mut sc = XmlScanner::new(xml.as_bytes());
        let (mut cpf, mut cpt) = (None, None);
        let (mut fu, mut tu) = (1.0, 1.0);
        let mut current: &[u8] = b"";
        while let Some(ev) = sc.next()? {
            match ev {
                XmlEvent::Start { name, .. } => current = name,
                XmlEvent::End { .. } => current = b"",
                XmlEvent::Text(t) => {
                    let text = std::str::from_utf8(t).map_err(|_| bad("non-UTF-8 text"))?;
                    if name_eq(current, "cfgcpf") {
                        cpf = Some(parse_f64(t).ok_or(bad("cfgcpf is not a number"))?);
                    } else if name_eq(current, "cfgcpt") {
                        cpt = Some(parse_f64(t).ok_or(bad("cfgcpt is not a number"))?);
                    } else if name_eq(current, "scfgfu") {
                        fu = force_unit_to_newton(text).ok_or(bad("unknown force unit scfgfu"))?;
                    } else if name_eq(current, "scfgtu") {
                        tu = torque_unit_to_newton_metre(text)
                            .ok_or(bad("unknown torque unit scfgtu"))?;
                    }
                }
            }
        }
        let cpf = cpf.ok_or(bad("no cfgcpf element"))?;
        let cpt = cpt.ok_or(bad("no cfgcpt element"))?;
        if !(cpf > 0.0 && cpt > 0.0) {
            return Err(bad("counts per unit must be positive"));
        }
        Ok(NetFtCalibration {
            counts_per_force: cpf / fu,
            counts_per_torque: cpt / tu,
        })
    }
}

/// Detects gaps and reordering in a u32 sequence (wrapping).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SequenceTracker {
    last: Option<u32>,
    /// Number of gaps seen.
    pub gaps: u64,
    /// Total number of missing sequence numbers.
    pub lost: u64,
    /// Number of duplicated or older sequence numbers seen.
    pub out_of_order: u64,
}

impl SequenceTracker {
    /// Records `seq`; returns how many numbers were skipped before it
    /// (0 if contiguous, duplicated or older).
    pub fn update(&mut self, seq: u32) -> u32 {
        let Some(last) = self.last else {
            self.last = Some(seq);
            return 0;
        };
        let d = seq.wrapping_sub(last);
        if d == 0 || d > u32::MAX / 2 {
            self.out_of_order += 1;
            return 0;
        }
        self.last = Some(seq);
        let gap = d - 1;
        if gap > 0 {
            self.gaps += 1;
            self.lost += u64::from(gap);
        }
        gap
    }
    /// Forgets the last sequence number (after a restart of streaming).
    pub fn reset(&mut self) {
        self.last = None;
    }
}

/// Counters of the client.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct NetFtStats {
    /// Records received.
    pub records: u64,
    /// Records with a non-zero status word.
    pub faults: u64,
    /// Sequence tracking.
    pub sequence: SequenceTracker,
}

/// Controller-side client of a Net F/T sensor.
#[derive(Debug)]
pub struct NetFtClient {
    ep: UdpEndpoint,
    sensor: SocketAddr,
    calibration: NetFtCalibration,
    rx: [u8; 1500],
    stats: NetFtStats,
    buffered: bool,
}

impl NetFtClient {
    /// Binds to `local` and talks to `sensor` (normally `<sensor-ip>:49152`).
    pub fn new(
        local: impl ToSocketAddrs,
        sensor: SocketAddr,
        calibration: NetFtCalibration,
    ) -> Result<Self, LinkError> {
        let mut ep = UdpEndpoint::bind(local, P)?;
        ep.set_peer(sensor);
        Ok(NetFtClient {
            ep,
            sensor,
            calibration,
            rx: [0; 1500],
            stats: NetFtStats::default(),
            buffered: false,
        })
    }
    /// Local socket address.
    pub fn local_addr(&self) -> Result<SocketAddr, LinkError> {
        self.ep.local_addr()
    }
    /// Counters.
    pub fn stats(&self) -> NetFtStats {
        self.stats
    }
    /// Calibration in use.
    pub fn calibration(&self) -> NetFtCalibration {
        self.calibration
    }
    /// Use buffered mode (`0x0003`) instead of real-time on `start`.
    pub fn set_buffered(&mut self, buffered: bool) {
        self.buffered = buffered;
    }
    /// Sends any request.
    pub fn send_request(&mut self, r: &RdtRequest) -> Result<(), LinkError> {
        self.ep.send(&encode_request(r))
    }
}

impl ForceSensorLink for NetFtClient {
    fn start(&mut self) -> Result<(), LinkError> {
        self.stats.sequence.reset();
        let command = if self.buffered {
            RdtCommand::StartBuffered
        } else {
            RdtCommand::StartRealtime
        };
        self.send_request(&RdtRequest {
            command,
            sample_count: 0,
        })
    }
    fn bias(&mut self) -> Result<(), LinkError> {
        self.send_request(&RdtRequest {
            command: RdtCommand::SetSoftwareBias,
            sample_count: 0,
        })
    }
    /// Returns the newest record of the datagram; `gap` covers every record
    /// missing since the previous datagram.
    fn receive(&mut self, timeout: Duration) -> Result<Option<WrenchSample>, LinkError> {
        let Some((n, from)) = self.ep.recv(&mut self.rx, timeout)? else {
            return Ok(None);
        };
        if from != self.sensor {
            return Err(LinkError::ForeignSender { protocol: P, from });
        }
        let mut last = None;
        let mut gap = 0u32;
        for r in decode_records(&self.rx[..n])? {
            self.stats.records += 1;
            if r.status != 0 {
                self.stats.faults += 1;
            }
            gap = gap.saturating_add(self.stats.sequence.update(r.rdt_sequence));
            last = Some(r);
        }
        let r = last.ok_or(bad("empty datagram"))?;
        Ok(Some(WrenchSample {
            wrench: self.calibration.to_wrench(&r.counts),
            sequence: r.rdt_sequence,
            status: r.status,
            gap,
        }))
    }
    fn stop(&mut self) -> Result<(), LinkError> {
        self.send_request(&RdtRequest {
            command: RdtCommand::Stop,
            sample_count: 0,
        })
    }
}

/// Sensor side (simulated cell): answers RDT requests and streams records.
#[derive(Debug)]
pub struct NetFtSensorServer {
    ep: UdpEndpoint,
    calibration: NetFtCalibration,
    client: Option<SocketAddr>,
    remaining: Option<u32>,
    rdt_sequence: u32,
    ft_sequence: u32,
    bias: Wrench,
    last_raw: Wrench,
}

impl NetFtSensorServer {
    /// Binds to `local` (port 49152 on a real sensor; `127.0.0.1:0` in tests).
    pub fn bind(
        local: impl ToSocketAddrs,
        calibration: NetFtCalibration,
    ) -> Result<Self, LinkError> {
        Ok(NetFtSensorServer {
            ep: UdpEndpoint::bind(local, P)?,
            calibration,
            client: None,
            remaining: None,
            rdt_sequence: 0,
            ft_sequence: 0,
            bias: Wrench::zeros(),
            last_raw: Wrench::zeros(),
        })
    }
    /// Local socket address.
    pub fn local_addr(&self) -> Result<SocketAddr, LinkError> {
        self.ep.local_addr()
    }
    /// True while a client asked for samples that are still due.
    pub fn streaming(&self) -> bool {
        self.client.is_some() && self.remaining != Some(0)
    }
    /// Waits up to `timeout` for one request and applies it: start
    /// (remembers the client and the count; restarts `rdt_sequence` at 1),
    /// stop, or bias (the last raw wrench becomes the bias). Returns it.
    pub fn poll_request(&mut self, timeout: Duration) -> Result<Option<RdtRequest>, LinkError> {
        let mut buf = [0u8; 64];
        let Some((n, from)) = self.ep.recv(&mut buf, timeout)? else {
            return Ok(None);
        };
        let r = decode_request(&buf[..n])?;
        match r.command {
            RdtCommand::StartRealtime | RdtCommand::StartBuffered => {
                self.client = Some(from);
                self.ep.set_peer(from);
                self.remaining = (r.sample_count != 0).then_some(r.sample_count);
                self.rdt_sequence = 0;
            }
            RdtCommand::Stop => self.client = None,
            RdtCommand::SetSoftwareBias => self.bias = self.last_raw,
            RdtCommand::Other(_) => {}
        }
        Ok(Some(r))
    }
    /// Produces one sample of `raw_wrench` (SI, before bias): it is sent if
    /// streaming; returns whether it was.
    pub fn send_sample(&mut self, raw_wrench: &Wrench, status: u32) -> Result<bool, LinkError> {
        self.last_raw = *raw_wrench;
        self.ft_sequence = self.ft_sequence.wrapping_add(1);
        if !self.streaming() {
            return Ok(false);
        }
        let mut w = *raw_wrench;
        for (x, b) in w.iter_mut().zip(self.bias.iter()) {
            *x -= b;
        }
        self.rdt_sequence = self.rdt_sequence.wrapping_add(1);
        let rec = RdtRecord {
            rdt_sequence: self.rdt_sequence,
            ft_sequence: self.ft_sequence,
            status,
            counts: self.calibration.to_counts(&w)?,
        };
        if let Some(r) = &mut self.remaining {
            *r -= 1;
        }
        self.ep.send(&encode_record(&rec))?;
        Ok(true)
    }
    /// Simulates a record lost on the network: consumes a sequence number
    /// without sending.
    pub fn lose_sample(&mut self) {
        self.rdt_sequence = self.rdt_sequence.wrapping_add(1);
        self.ft_sequence = self.ft_sequence.wrapping_add(1);
    }
}

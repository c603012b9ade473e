//! KUKA Robot Sensor Interface (RSI) over UDP/XML.
//!
//! The robot controller sends one telegram per interpolation cycle (4 ms or
//! 12 ms) to the sensor PC, by default on UDP port [`DEFAULT_PORT`]:
//!
//! ```text
//! <Rob Type="KUKA"><RIst X=".." Y=".." Z=".." A=".." B=".." C=".."/>
//!   <RSol X=".." .../><AIPos A1=".." ... A6=".."/><Delay D="0"/><IPOC>123456</IPOC></Rob>
//! ```
//!
//! * `RIst` / `RSol`: actual / set-point TCP pose, X Y Z in **mm**, A B C in
//!   **degrees**, KUKA ZYX Euler angles (A about z, B about y, C about x);
//! * `AIPos`: actual axis positions A1…A6 in **degrees**;
//! * `Delay D`: number of late answers counted by the robot;
//! * `IPOC`: cycle time stamp, which the answer must echo.
//!
//! The sensor PC answers within the cycle with
//!
//! ```text
//! <Sen Type="ImFree"><EStr>...</EStr><RKorr X=".." Y=".." Z=".." A=".." B=".." C=".."/><IPOC>same</IPOC></Sen>
//! ```
//!
//! (`Type` must match the RSI configuration; `EStr` is an optional message
//! shown on the pendant). `RKorr` is in mm and degrees, printed with four
//! decimals. In [`CorrectionMode::Absolute`] it is the total correction of
//! the path; in [`CorrectionMode::Relative`] it is the increment since the
//! previous answer, which the robot accumulates (a lost answer then loses its
//! increment, so absolute mode is preferred). Element and attribute names are
//! case-insensitive. Internally everything is SI ([`Correction`] rotation
//! vectors are converted exactly to and from A B C).
//!
//! Parsing uses the allocation-free scanner of [`crate::xml`]; formatting
//! writes into caller-provided byte slices.

use crate::error::{LinkError, Protocol};
use crate::link::{Correction, Pose6, ReceivedCorrection, RobotLink, RobotSideLink, RobotState};
use crate::udp::{SliceWriter, UdpEndpoint, parse_f64, parse_u64};
use crate::xml::{Attributes, XmlEvent, XmlScanner, name_eq};
use core::fmt::Write;
use std::net::{SocketAddr, ToSocketAddrs};
use std::time::Duration;

/// Default RSI UDP port.
pub const DEFAULT_PORT: u16 = 59152;
/// Receive buffer size; RSI telegrams are well below 1 kB.
pub const RX_BUFFER: usize = 4096;
/// Transmit buffer size.
pub const TX_BUFFER: usize = 1024;

const P: Protocol = Protocol::Rsi;
const fn bad(reason: &'static str) -> LinkError {
    LinkError::malformed(P, reason)
}

/// How `RKorr` values are interpreted by the robot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CorrectionMode {
    /// `RKorr` is the total correction (RSI `AKorr`-style absolute mode).
    #[default]
    Absolute,
    /// `RKorr` is the increment since the previous answer.
    Relative,
}

/// A parsed robot → sensor telegram, in SI units.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RobTelegram {
    /// Actual TCP pose (`RIst`).
    pub actual_pose: Option<Pose6>,
    /// Set-point TCP pose (`RSol`).
    pub setpoint_pose: Option<Pose6>,
    /// Actual axis positions (`AIPos`) in radians.
    pub q_rad: Option<[f64; 6]>,
    /// Late-answer counter (`Delay D`), 0 if absent.
    pub delay: u32,
    /// Interpolation cycle stamp (`IPOC`).
    pub ipoc: u64,
}

/// A parsed sensor → robot answer, in SI units.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SenTelegram {
    /// `RKorr` as `[x, y, z]` in metres then `[a, b, c]` ZYX Euler angles in
    /// radians (total or increment depending on the [`CorrectionMode`]).
    pub rkorr: [f64; 6],
    /// Echoed cycle stamp.
    pub ipoc: u64,
}

const POSE_ATTRS: [&str; 6] = ["X", "Y", "Z", "A", "B", "C"];
const AXIS_ATTRS: [&str; 6] = ["A1", "A2", "A3", "A4", "A5", "A6"];

fn read6(
    attrs: Attributes<'_>,
    names: &[&str; 6],
    what: &'static str,
) -> Result<[f64; 6], LinkError> {
    let mut out = [0.0; 6];
    let mut seen = [false; 6];
    for a in attrs {
        let (n, v) = a?;
        if let Some(i) = names.iter().position(|x| name_eq(n, x)) {
            out[i] = parse_f64(v).ok_or(bad("attribute is not a finite number"))?;
            seen[i] = true;
        }
    }
    if seen.iter().all(|s| *s) {
        Ok(out)
    } else {
        Err(bad(what))
    }
}

fn pose_from_mm_deg(v: [f64; 6]) -> Pose6 {
    Pose6 {
        position_m: [v[0] * 1e-3, v[1] * 1e-3, v[2] * 1e-3],
        zyx_rad: [v[3].to_radians(), v[4].to_radians(), v[5].to_radians()],
    }
}

/// Walks a telegram whose root must be `root`, calling `on_start` for every
/// start tag and returning the IPOC.
fn walk<'a>(
    buf: &'a [u8],
    root: &str,
    mut on_start: impl FnMut(&'a [u8], Attributes<'a>) -> Result<(), LinkError>,
) -> Result<u64, LinkError> {
    let mut sc = XmlScanner::new(buf);
    let mut ipoc = None;
    let mut in_ipoc = false;
    let mut first = true;
    while let Some(ev) = sc.next()? {
        match ev {
            XmlEvent::Start {
                name,
                attrs,
                self_closing,
            } => {
                if first {
                    if !name_eq(name, root) {
                        return Err(bad("unexpected root element"));
                    }
                    first = false;
                    continue;
                }
                if name_eq(name, "IPOC") {
                    if self_closing {
                        return Err(bad("empty IPOC element"));
                    }
                    in_ipoc = true;
                } else {
                    on_start(name, attrs)?;
                }
            }
            XmlEvent::Text(t) if in_ipoc => {
                ipoc = Some(parse_u64(t).ok_or(bad("IPOC is not an unsigned integer"))?);
            }
            XmlEvent::Text(_) => {}
            XmlEvent::End { name } => {
                if name_eq(name, "IPOC") {
                    in_ipoc = false;
                }
            }
        }
    }
    ipoc.ok_or(bad("telegram has no IPOC"))
}

/// Parses a robot → sensor `<Rob>` telegram.
pub fn parse_rob(buf: &[u8]) -> Result<RobTelegram, LinkError> {
    let mut t = RobTelegram::default();
    t.ipoc = walk(buf, "Rob", |name, attrs| {
        if name_eq(name, "RIst") {
            t.actual_pose = Some(pose_from_mm_deg(read6(
                attrs,
                &POSE_ATTRS,
                "RIst lacks one of X Y Z A B C",
            )?));
        } else if name_eq(name, "RSol") {
            t.setpoint_pose = Some(pose_from_mm_deg(read6(
                attrs,
                &POSE_ATTRS,
                "RSol lacks one of X Y Z A B C",
            )?));
        } else if name_eq(name, "AIPos") {
            let a = read6(attrs, &AXIS_ATTRS, "AIPos lacks one of A1..A6")?;
            t.q_rad = Some(a.map(f64::to_radians));
        } else if name_eq(name, "Delay") {
            let d = attrs.get("D")?.ok_or(bad("Delay lacks D"))?;
            let d = parse_u64(d).ok_or(bad("Delay D is not an unsigned integer"))?;
            t.delay = u32::try_from(d).map_err(|_| bad("Delay D out of range"))?;
        }
        Ok(())
    })?;
    Ok(t)
}

/// Parses a sensor → robot `<Sen>` answer.
pub fn parse_sen(buf: &[u8]) -> Result<SenTelegram, LinkError> {
    let mut rkorr = None;
    let ipoc = walk(buf, "Sen", |name, attrs| {
        if name_eq(name, "RKorr") {
            let v = read6(attrs, &POSE_ATTRS, "RKorr lacks one of X Y Z A B C")?;
            rkorr = Some([
                v[0] * 1e-3,
                v[1] * 1e-3,
                v[2] * 1e-3,
                v[3].to_radians(),
                v[4].to_radians(),
                v[5].to_radians(),
            ]);
        }
        Ok(())
    })?;
    Ok(SenTelegram {
        rkorr: rkorr.ok_or(bad("answer has no RKorr"))?,
        ipoc,
    })
}

fn check_finite(v: &[f64]) -> Result<(), LinkError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(LinkError::InvalidValue {
            protocol: P,
            reason: "non-finite value",
        })
    }
}

fn write_pose(w: &mut SliceWriter<'_>, tag: &str, v: [f64; 6]) -> core::fmt::Result {
    write!(w, "<{tag}")?;
    for (n, x) in POSE_ATTRS.iter().zip(v) {
        write!(w, " {n}=\"{x:.4}\"")?;
    }
    w.push_bytes(b"/>")
}

fn pose_mm_deg(p: &Pose6) -> [f64; 6] {
    [
        p.position_m[0] * 1e3,
        p.position_m[1] * 1e3,
        p.position_m[2] * 1e3,
        p.zyx_rad[0].to_degrees(),
        p.zyx_rad[1].to_degrees(),
        p.zyx_rad[2].to_degrees(),
    ]
}

/// Formats a `<Rob Type="KUKA">` telegram into `out`, returning its length.
/// Poses and axes that are `None` are omitted.
pub fn format_rob(t: &RobTelegram, out: &mut [u8]) -> Result<usize, LinkError> {
    let ist = t.actual_pose.as_ref().map(pose_mm_deg);
    let sol = t.setpoint_pose.as_ref().map(pose_mm_deg);
    let q = t.q_rad.map(|q| q.map(f64::to_degrees));
    for v in [&ist, &sol, &q].into_iter().flatten() {
        check_finite(v)?;
    }
    let cap = out.len();
    let mut w = SliceWriter::new(out);
    let r = (|| {
        w.push_bytes(b"<Rob Type=\"KUKA\">")?;
        if let Some(v) = ist {
            write_pose(&mut w, "RIst", v)?;
        }
        if let Some(v) = sol {
            write_pose(&mut w, "RSol", v)?;
        }
        if let Some(q) = q {
            w.push_bytes(b"<AIPos")?;
            for (n, x) in AXIS_ATTRS.iter().zip(q) {
                write!(w, " {n}=\"{x:.4}\"")?;
            }
            w.push_bytes(b"/>")?;
        }
        write!(w, "<Delay D=\"{}\"/><IPOC>{}</IPOC></Rob>", t.delay, t.ipoc)
    })();
    r.map_err(|_| LinkError::BufferTooSmall {
        protocol: P,
        capacity: cap,
    })?;
    Ok(w.len())
}

/// Checks that a `Sen Type` value is a plain name.
pub fn valid_sen_type(s: &str) -> bool {
    !s.is_empty()
        && s.len() <= 64
        && s.bytes()
            .all(|b| b.is_ascii_alphanumeric() || matches!(b, b'_' | b'-' | b'.'))
}

/// Checks that an `EStr` message needs no escaping.
pub fn valid_estr(s: &str) -> bool {
    s.len() <= 128
        && s.bytes()
            .all(|b| (b' '..=b'~').contains(&b) && !matches!(b, b'<' | b'>' | b'&'))
}

/// Formats a `<Sen>` answer into `out`, returning its length. `rkorr` is in
/// SI (`[x, y, z]` m, `[a, b, c]` rad); `sen_type` and `estr` must pass
/// [`valid_sen_type`] and [`valid_estr`].
pub fn format_sen(
    rkorr: &[f64; 6],
    ipoc: u64,
    sen_type: &str,
    estr: Option<&str>,
    out: &mut [u8],
) -> Result<usize, LinkError> {
    if !valid_sen_type(sen_type) {
        return Err(LinkError::InvalidValue {
            protocol: P,
            reason: "Sen Type must be a plain name",
        });
    }
    if estr.is_some_and(|e| !valid_estr(e)) {
        return Err(LinkError::InvalidValue {
            protocol: P,
            reason: "EStr must be printable ASCII without < > &",
        });
    }
    check_finite(rkorr)?;
    let cap = out.len();
    let mut w = SliceWriter::new(out);
    let v = [
        rkorr[0] * 1e3,
        rkorr[1] * 1e3,
        rkorr[2] * 1e3,
        rkorr[3].to_degrees(),
        rkorr[4].to_degrees(),
        rkorr[5].to_degrees(),
    ];
    let r = (|| {
        write!(w, "<Sen Type=\"{sen_type}\">")?;
        if let Some(e) = estr {
            write!(w, "<EStr>{e}</EStr>")?;
        }
        write_pose(&mut w, "RKorr", v)?;
        write!(w, "<IPOC>{ipoc}</IPOC></Sen>")
    })();
    r.map_err(|_| LinkError::BufferTooSmall {
        protocol: P,
        capacity: cap,
    })?;
    Ok(w.len())
}

/// Total correction as RKorr values in SI: `[x, y, z]` m, `[a, b, c]` rad.
pub fn correction_to_rkorr(c: &Correction) -> [f64; 6] {
    let abc = c.zyx_rad();
    [c.dp_m[0], c.dp_m[1], c.dp_m[2], abc[0], abc[1], abc[2]]
}

/// Inverse of [`correction_to_rkorr`].
pub fn rkorr_to_correction(v: &[f64; 6]) -> Correction {
    Correction::from_zyx([v[0], v[1], v[2]], [v[3], v[4], v[5]])
}

/// Configuration of the sensor-PC (controller) side.
#[derive(Debug, Clone, PartialEq)]
pub struct RsiConfig {
    /// `Type` attribute of the `<Sen>` root (must match the robot's RSI
    /// configuration), default `"ImFree"`.
    pub sen_type: String,
    /// Optional `EStr` message.
    pub estr: Option<String>,
    /// Absolute or relative `RKorr`.
    pub mode: CorrectionMode,
}

impl Default for RsiConfig {
    fn default() -> Self {
        RsiConfig {
            sen_type: "ImFree".into(),
            estr: None,
            mode: CorrectionMode::Absolute,
        }
    }
}

/// Sensor-PC side of RSI: receives `<Rob>` telegrams and answers `<Sen>`.
///
/// [`RobotLink::send_correction`] answers the most recently received
/// telegram (echoing its IPOC) to the address it came from.
#[derive(Debug)]
pub struct RsiLink {
    ep: UdpEndpoint,
    cfg: RsiConfig,
    rx: Box<[u8; RX_BUFFER]>,
    tx: Box<[u8; TX_BUFFER]>,
    last: Option<RobTelegram>,
    last_sent: [f64; 6],
}

impl RsiLink {
    /// Binds to `local` (e.g. `"0.0.0.0:59152"`).
    pub fn bind(local: impl ToSocketAddrs, cfg: RsiConfig) -> Result<Self, LinkError> {
        if !valid_sen_type(&cfg.sen_type) || cfg.estr.as_deref().is_some_and(|e| !valid_estr(e)) {
            return Err(LinkError::InvalidValue {
                protocol: P,
                reason: "invalid Sen Type or EStr",
            });
        }
        Ok(RsiLink {
            ep: UdpEndpoint::bind(local, P)?,
            cfg,
            rx: Box::new([0; RX_BUFFER]),
            tx: Box::new([0; TX_BUFFER]),
            last: None,
            last_sent: [0.0; 6],
        })
    }

    /// Local socket address.
    pub fn local_addr(&self) -> Result<SocketAddr, LinkError> {
        self.ep.local_addr()
    }

    /// The last valid telegram received (with `RSol`, `Delay`...).
    pub fn last_telegram(&self) -> Option<&RobTelegram> {
        self.last.as_ref()
    }
}

impl RobotLink for RsiLink {
    fn receive(&mut self, timeout: Duration) -> Result<Option<RobotState>, LinkError> {
        let Some((n, from)) = self.ep.recv(&mut self.rx[..], timeout)? else {
            return Ok(None);
        };
        let t = parse_rob(&self.rx[..n])?;
        let q = t.q_rad.ok_or(bad("telegram has no AIPos"))?;
        self.ep.set_peer(from);
        self.last = Some(t);
        Ok(Some(RobotState {
            q_rad: q,
            tcp_pose: t.actual_pose,
            cycle_id: t.ipoc,
            robot_time_s: None,
            status: t.delay,
        }))
    }

    fn send_correction(&mut self, c: &Correction) -> Result<(), LinkError> {
        let ipoc = self
            .last
            .as_ref()
            .ok_or(LinkError::NoPeer { protocol: P })?
            .ipoc;
        if !c.is_finite() {
            return Err(LinkError::InvalidValue {
                protocol: P,
                reason: "non-finite correction",
            });
        }
        let total = correction_to_rkorr(c);
        let mut sent = total;
        if self.cfg.mode == CorrectionMode::Relative {
            for (s, l) in sent.iter_mut().zip(self.last_sent) {
                *s -= l;
            }
        }
        let n = format_sen(
            &sent,
            ipoc,
            &self.cfg.sen_type,
            self.cfg.estr.as_deref(),
            &mut self.tx[..],
        )?;
        self.ep.send(&self.tx[..n])?;
        // Relative mode: the robot accumulates what was printed, so track the
        // rounded value to avoid drift from rounding.
        if self.cfg.mode == CorrectionMode::Relative {
            let printed = parse_sen(&self.tx[..n])?.rkorr;
            for (l, p) in self.last_sent.iter_mut().zip(printed) {
                *l += p;
            }
        }
        Ok(())
    }
}

/// Robot side of RSI (used by the simulated cell): sends `<Rob>` telegrams
/// to the sensor PC and reads `<Sen>` answers.
#[derive(Debug)]
pub struct RsiRobotEndpoint {
    ep: UdpEndpoint,
    mode: CorrectionMode,
    rx: Box<[u8; RX_BUFFER]>,
    tx: Box<[u8; TX_BUFFER]>,
    accumulated: [f64; 6],
}

impl RsiRobotEndpoint {
    /// Binds to `local` and sends to `sensor_pc`.
    pub fn new(
        local: impl ToSocketAddrs,
        sensor_pc: SocketAddr,
        mode: CorrectionMode,
    ) -> Result<Self, LinkError> {
        let mut ep = UdpEndpoint::bind(local, P)?;
        ep.set_peer(sensor_pc);
        Ok(RsiRobotEndpoint {
            ep,
            mode,
            rx: Box::new([0; RX_BUFFER]),
            tx: Box::new([0; TX_BUFFER]),
            accumulated: [0.0; 6],
        })
    }

    /// Local socket address.
    pub fn local_addr(&self) -> Result<SocketAddr, LinkError> {
        self.ep.local_addr()
    }

    /// Resets the accumulated correction of relative mode.
    pub fn reset(&mut self) {
        self.accumulated = [0.0; 6];
    }
}

impl RobotSideLink for RsiRobotEndpoint {
    fn send_state(&mut self, s: &RobotState) -> Result<(), LinkError> {
        let t = RobTelegram {
            actual_pose: s.tcp_pose,
            setpoint_pose: None,
            q_rad: Some(s.q_rad),
            delay: s.status,
            ipoc: s.cycle_id,
        };
        let n = format_rob(&t, &mut self.tx[..])?;
        self.ep.send(&self.tx[..n])
    }

    fn receive_correction(
        &mut self,
        timeout: Duration,
    ) -> Result<Option<ReceivedCorrection>, LinkError> {
        let Some((n, _)) = self.ep.recv(&mut self.rx[..], timeout)? else {
            return Ok(None);
        };
        let t = parse_sen(&self.rx[..n])?;
        let total = match self.mode {
            CorrectionMode::Absolute => t.rkorr,
            CorrectionMode::Relative => {
                for (a, d) in self.accumulated.iter_mut().zip(t.rkorr) {
                    *a += d;
                }
                self.accumulated
            }
        };
        Ok(Some(ReceivedCorrection {
            correction: rkorr_to_correction(&total),
            cycle_id: t.ipoc,
        }))
    }
}

#[cfg(test)]
#[path = "rsi_tests.rs"]
mod tests;

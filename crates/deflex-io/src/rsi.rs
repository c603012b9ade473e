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
//!   **degrees**, KUKA's Z-Y'-X'' angles (A about z, B about y, C about x;
//!   [`deflex_model::conventions::kuka_abc_deg`]);
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
//! decimals (a value that rounds to zero is printed `0.0000`, never
//! `-0.0000`). In [`CorrectionMode::Absolute`] it is the total correction of
//! the path; in [`CorrectionMode::Relative`] it is the increment since the
//! previous answer, which the robot accumulates. Element and attribute names
//! are case-insensitive. Internally everything is SI ([`Correction`] rotation
//! vectors are converted exactly to and from A B C).
//!
//! **Joint-space answers.** RSI configurations built around an axis
//! correction object (`AXISCORR`, as the ROS-Industrial `kuka_rsi_hw_interface`
//! set-ups use) read `<AK A1=".." … A6=".."/>` (degrees) instead of `RKorr`;
//! [`RsiAnswer::Joint`] answers that way (tag `AK`, or `AKorr`), with a joint
//! correction the caller computes from the Cartesian one
//! ([`RobotLink::send_joint_correction`]).
//!
//! **Relative mode without drift.** `Delay D` is the robot's cumulative count
//! of answers that did not arrive in time (KUKA's `DEF_Delay`); RSI does not
//! apply an answer that misses its cycle. When `D` grows between two
//! telegrams, the answer to the previous telegram was not applied, so
//! [`RsiLink`] takes its increment back out of what it believes the robot has
//! accumulated and the next increment re-sends it: a lost or late answer
//! delays the correction by one cycle instead of offsetting it for the rest
//! of the session. A counter that goes backwards means a new RSI session
//! (the robot's accumulated correction restarts at zero).
//!
//! **Peer.** [`RsiLink`] answers only the robot it is locked to: the
//! configured address ([`RsiLink::expect_peer`], [`RsiLink::set_peer_policy`]) or the first
//! valid sender of the session ([`crate::peer`]).
//!
//! **Session rules.** A telegram from that robot whose `IPOC` does not advance over the last
//! accepted one (a duplicate or a replay; 32-bit serial arithmetic, see [`crate::guard`]) is
//! dropped unanswered ([`LinkError::Dropped`], counted in [`RobotLink::counters`]) before it
//! touches anything: the answer still echoes the last accepted `IPOC`, and in relative mode
//! its `Delay` does not enter the book (a replayed lower `Delay` would otherwise look like a
//! new RSI session and reset the accumulated correction).
//!
//! Parsing uses the allocation-free scanner of [`crate::xml`]; formatting
//! writes into caller-provided byte slices.

use crate::error::{LinkError, Protocol};
use crate::guard::{LinkCounters, SessionGuard};
use crate::link::{Correction, ReceivedCorrection, RobotLink, RobotSideLink, RobotState};
use crate::peer::{PeerLock, PeerPolicy};
use crate::udp::{SliceWriter, UdpEndpoint, parse_f64, parse_u64};
use crate::xml::{Attributes, XmlEvent, XmlScanner, name_eq};
use core::fmt::Write;
use deflex_model::Pose;
use deflex_model::conventions::{
    kuka_abc_deg, kuka_abc_rad, rotation_from_kuka_abc_deg, rotation_from_kuka_abc_rad,
    rotation_from_rotation_vector, rotation_vector,
};
use nalgebra::Translation3;
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
    pub actual_pose: Option<Pose>,
    /// Set-point TCP pose (`RSol`).
    pub setpoint_pose: Option<Pose>,
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
    /// `RKorr` as `[x, y, z]` in metres then `[a, b, c]` KUKA angles in
    /// radians (total or increment depending on the [`CorrectionMode`]), when
    /// the answer is Cartesian.
    pub rkorr: Option<[f64; 6]>,
    /// `AK` / `AKorr` axis corrections A1…A6 in radians, when the answer is
    /// in joint space.
    pub joints_rad: Option<[f64; 6]>,
    /// Echoed cycle stamp.
    pub ipoc: u64,
}

/// The element a joint-space answer uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum JointTag {
    /// `<AK A1=".." … A6=".."/>` (the ROS-Industrial RSI set-ups).
    #[default]
    Ak,
    /// `<AKorr A1=".." … A6=".."/>`.
    AKorr,
}

impl JointTag {
    /// The element name.
    pub fn name(self) -> &'static str {
        match self {
            JointTag::Ak => "AK",
            JointTag::AKorr => "AKorr",
        }
    }
}

/// What the answers carry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RsiAnswer {
    /// Cartesian `RKorr` (mm, degrees).
    #[default]
    Cartesian,
    /// Joint corrections A1…A6 (degrees) in the given element.
    Joint(JointTag),
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

fn pose_from_mm_deg(v: [f64; 6]) -> Pose {
    Pose::from_parts(
        Translation3::new(v[0] * 1e-3, v[1] * 1e-3, v[2] * 1e-3),
        rotation_from_kuka_abc_deg([v[3], v[4], v[5]]),
    )
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

/// Parses a sensor → robot `<Sen>` answer (`RKorr`, or `AK` / `AKorr`).
pub fn parse_sen(buf: &[u8]) -> Result<SenTelegram, LinkError> {
    let mut rkorr = None;
    let mut joints = None;
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
        } else if name_eq(name, "AK") || name_eq(name, "AKorr") {
            let v = read6(attrs, &AXIS_ATTRS, "AK lacks one of A1..A6")?;
            joints = Some(v.map(f64::to_radians));
        }
        Ok(())
    })?;
    if rkorr.is_none() && joints.is_none() {
        return Err(bad("answer has neither RKorr nor AK"));
    }
    Ok(SenTelegram {
        rkorr,
        joints_rad: joints,
        ipoc,
    })
}

/// The value printed with four decimals, without a negative zero: anything
/// that rounds to zero prints `0.0000`.
#[inline]
fn four_decimals(x: f64) -> f64 {
    if x.abs() < 5e-5 { 0.0 } else { x }
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

fn write_six(
    w: &mut SliceWriter<'_>,
    tag: &str,
    names: &[&str; 6],
    v: [f64; 6],
) -> core::fmt::Result {
    write!(w, "<{tag}")?;
    for (n, x) in names.iter().zip(v) {
        write!(w, " {n}=\"{:.4}\"", four_decimals(x))?;
    }
    w.push_bytes(b"/>")
}

fn pose_mm_deg(p: &Pose) -> [f64; 6] {
    let t = p.translation.vector;
    let [a, b, c] = kuka_abc_deg(&p.rotation, None);
    [t.x * 1e3, t.y * 1e3, t.z * 1e3, a, b, c]
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
            write_six(&mut w, "RIst", &POSE_ATTRS, v)?;
        }
        if let Some(v) = sol {
            write_six(&mut w, "RSol", &POSE_ATTRS, v)?;
        }
        if let Some(q) = q {
            write_six(&mut w, "AIPos", &AXIS_ATTRS, q)?;
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
    let v = [
        rkorr[0] * 1e3,
        rkorr[1] * 1e3,
        rkorr[2] * 1e3,
        rkorr[3].to_degrees(),
        rkorr[4].to_degrees(),
        rkorr[5].to_degrees(),
    ];
    format_sen_body("RKorr", &POSE_ATTRS, rkorr, v, ipoc, sen_type, estr, out)
}

/// Formats a joint-space `<Sen>` answer (`<AK A1=".." … A6=".."/>` or
/// `AKorr`, degrees) into `out`, returning its length. `dq_rad` is in rad.
pub fn format_sen_joints(
    tag: JointTag,
    dq_rad: &[f64; 6],
    ipoc: u64,
    sen_type: &str,
    estr: Option<&str>,
    out: &mut [u8],
) -> Result<usize, LinkError> {
    let v = dq_rad.map(f64::to_degrees);
    format_sen_body(
        tag.name(),
        &AXIS_ATTRS,
        dq_rad,
        v,
        ipoc,
        sen_type,
        estr,
        out,
    )
}

#[allow(clippy::too_many_arguments)] // one private formatter behind the two public ones
fn format_sen_body(
    tag: &str,
    names: &[&str; 6],
    si: &[f64; 6],
    printed: [f64; 6],
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
    check_finite(si)?;
    check_finite(&printed)?;
    let cap = out.len();
    let mut w = SliceWriter::new(out);
    let r = (|| {
        write!(w, "<Sen Type=\"{sen_type}\">")?;
        if let Some(e) = estr {
            write!(w, "<EStr>{e}</EStr>")?;
        }
        write_six(&mut w, tag, names, printed)?;
        write!(w, "<IPOC>{ipoc}</IPOC></Sen>")
    })();
    r.map_err(|_| LinkError::BufferTooSmall {
        protocol: P,
        capacity: cap,
    })?;
    Ok(w.len())
}

/// Total correction as RKorr values in SI: `[x, y, z]` m, `[a, b, c]` rad (the KUKA angles of
/// the correction's rotation vector).
pub fn correction_to_rkorr(c: &Correction) -> [f64; 6] {
    let abc = kuka_abc_rad(&rotation_from_rotation_vector(c.dphi_rad), None);
    [c.dp_m[0], c.dp_m[1], c.dp_m[2], abc[0], abc[1], abc[2]]
}

/// Inverse of [`correction_to_rkorr`].
pub fn rkorr_to_correction(v: &[f64; 6]) -> Correction {
    Correction {
        dp_m: [v[0], v[1], v[2]],
        dphi_rad: rotation_vector(&rotation_from_kuka_abc_rad([v[3], v[4], v[5]]), None),
    }
}

/// Configuration of the sensor-PC (controller) side.
#[derive(Debug, Clone, PartialEq)]
pub struct RsiConfig {
    /// `Type` attribute of the `<Sen>` root (must match the robot's RSI
    /// configuration), default `"ImFree"`.
    pub sen_type: String,
    /// Optional `EStr` message.
    pub estr: Option<String>,
    /// Absolute or relative corrections.
    pub mode: CorrectionMode,
    /// Cartesian `RKorr` or joint `AK` answers.
    pub answer: RsiAnswer,
}

impl Default for RsiConfig {
    fn default() -> Self {
        RsiConfig {
            sen_type: "ImFree".into(),
            estr: None,
            mode: CorrectionMode::Absolute,
            answer: RsiAnswer::Cartesian,
        }
    }
}

/// What [`RsiLink`] believes the robot has accumulated in relative mode.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct RelativeBook {
    /// Sum of the printed increments the robot applied (RKorr or AK units in
    /// SI), as far as `Delay` tells.
    applied: [f64; 6],
    /// The increment sent in answer to the latest telegram, until the next
    /// telegram's `Delay` confirms or refutes it.
    unconfirmed: Option<[f64; 6]>,
    /// `Delay D` of the latest telegram.
    last_delay: Option<u32>,
    /// Answers taken back because `Delay` grew.
    rolled_back: u64,
}

impl RelativeBook {
    /// Books the `Delay D` of a new telegram.
    fn on_telegram(&mut self, delay: u32) {
        match self.last_delay {
            Some(prev) if delay > prev => {
                if let Some(inc) = self.unconfirmed {
                    for (a, i) in self.applied.iter_mut().zip(inc) {
                        *a -= i;
                    }
                    self.rolled_back += 1;
                }
            }
            Some(prev) if delay < prev => {
                // A new RSI session: the robot's accumulation restarts at zero.
                self.applied = [0.0; 6];
            }
            _ => {}
        }
        self.unconfirmed = None;
        self.last_delay = Some(delay);
    }

    /// Books an increment that was sent.
    fn on_sent(&mut self, increment: [f64; 6]) {
        for (a, i) in self.applied.iter_mut().zip(increment) {
            *a += i;
        }
        self.unconfirmed = Some(increment);
    }
}

/// Sensor-PC side of RSI: receives `<Rob>` telegrams and answers `<Sen>`.
///
/// [`RobotLink::send_correction`] (or, with [`RsiAnswer::Joint`],
/// [`RobotLink::send_joint_correction`]) answers the most recently received
/// telegram (echoing its IPOC) to the robot the link is locked to.
#[derive(Debug)]
pub struct RsiLink {
    ep: UdpEndpoint,
    cfg: RsiConfig,
    rx: Box<[u8; RX_BUFFER]>,
    tx: Box<[u8; TX_BUFFER]>,
    last: Option<RobTelegram>,
    peers: PeerLock,
    relative: RelativeBook,
    guard: SessionGuard,
    answers: u64,
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
            peers: PeerLock::first_sender(),
            relative: RelativeBook::default(),
            guard: SessionGuard::new(),
            answers: 0,
        })
    }

    /// Sets the peer policy (see [`crate::peer::validate_peer`]).
    pub fn set_peer_policy(&mut self, policy: PeerPolicy) {
        self.peers.set_policy(policy);
    }

    /// Accepts telegrams only from `peer` (port 0: any port of that IP)
    /// instead of locking to the first sender.
    pub fn expect_peer(&mut self, peer: SocketAddr) {
        self.peers.set_configured(Some(peer));
    }

    /// The sender lock (locked address, refused packets).
    pub fn peers(&self) -> &PeerLock {
        &self.peers
    }

    /// Local socket address.
    pub fn local_addr(&self) -> Result<SocketAddr, LinkError> {
        self.ep.local_addr()
    }

    /// The last valid telegram received (with `RSol`, `Delay`...).
    pub fn last_telegram(&self) -> Option<&RobTelegram> {
        self.last.as_ref()
    }

    /// Relative mode: answers whose increment was taken back because the
    /// robot's `Delay` counter showed they were not applied.
    pub fn rolled_back(&self) -> u64 {
        self.relative.rolled_back
    }

    fn current_ipoc(&self) -> Result<u64, LinkError> {
        Ok(self
            .last
            .as_ref()
            .ok_or(LinkError::NoPeer { protocol: P })?
            .ipoc)
    }

    /// Formats and sends one answer: `total` is the total correction in the
    /// answer's units (RKorr SI or joint rad); relative mode sends the
    /// increment over what the robot has applied.
    fn answer(&mut self, total: [f64; 6], joint: Option<JointTag>) -> Result<(), LinkError> {
        let ipoc = self.current_ipoc()?;
        check_finite(&total).map_err(|_| LinkError::InvalidValue {
            protocol: P,
            reason: "non-finite correction",
        })?;
        let relative = self.cfg.mode == CorrectionMode::Relative;
        let mut sent = total;
        if relative {
            for (s, a) in sent.iter_mut().zip(self.relative.applied) {
                *s -= a;
            }
        }
        let estr = self.cfg.estr.as_deref();
        let n = match joint {
            None => format_sen(&sent, ipoc, &self.cfg.sen_type, estr, &mut self.tx[..])?,
            Some(tag) => {
                format_sen_joints(tag, &sent, ipoc, &self.cfg.sen_type, estr, &mut self.tx[..])?
            }
        };
        self.ep.send(&self.tx[..n])?;
        self.answers += 1;
        if relative {
            // The robot accumulates what was printed: book the rounded value
            // so that rounding does not drift either.
            let printed = parse_sen(&self.tx[..n])?;
            let inc = printed
                .rkorr
                .or(printed.joints_rad)
                .ok_or(bad("formatted answer has no body"))?;
            self.relative.on_sent(inc);
        }
        Ok(())
    }
}

impl RobotLink for RsiLink {
    fn receive(&mut self, timeout: Duration) -> Result<Option<RobotState>, LinkError> {
        let Some((n, from)) = self.ep.recv(&mut self.rx[..], timeout)? else {
            return Ok(None);
        };
        self.peers.check(P, from)?;
        let t = parse_rob(&self.rx[..n])?;
        let q = t.q_rad.ok_or(bad("telegram has no AIPos"))?;
        self.guard
            .admit(q.len(), Some(t.ipoc), None)
            .map_err(|reason| LinkError::Dropped {
                protocol: P,
                reason,
            })?;
        self.peers.lock(from);
        self.ep.set_peer(from);
        self.relative.on_telegram(t.delay);
        self.last = Some(t);
        let mut state = RobotState::with_joints(&q);
        state.tcp_pose = t.actual_pose;
        state.cycle_id = t.ipoc;
        state.late_answers = Some(t.delay);
        Ok(Some(state))
    }

    fn send_correction(&mut self, c: &Correction) -> Result<(), LinkError> {
        if let RsiAnswer::Joint(_) = self.cfg.answer {
            return Err(LinkError::InvalidValue {
                protocol: P,
                reason: "this RSI link answers joint corrections (AK)",
            });
        }
        if !c.is_finite() {
            return Err(LinkError::InvalidValue {
                protocol: P,
                reason: "non-finite correction",
            });
        }
        self.answer(correction_to_rkorr(c), None)
    }

    fn answers_in_joint_space(&self) -> bool {
        matches!(self.cfg.answer, RsiAnswer::Joint(_))
    }

    fn counters(&self) -> LinkCounters {
        let mut c = LinkCounters {
            answers: self.answers,
            foreign: self.peers.foreign(),
            ..LinkCounters::default()
        };
        self.guard.add_to(&mut c);
        c
    }

    /// Sends `<AK A1..A6>` (degrees on the wire) from `dq_rad` (the first six
    /// values; missing ones are zero).
    fn send_joint_correction(&mut self, dq_rad: &[f64]) -> Result<(), LinkError> {
        let RsiAnswer::Joint(tag) = self.cfg.answer else {
            return Err(LinkError::InvalidValue {
                protocol: P,
                reason: "this RSI link answers Cartesian corrections (RKorr)",
            });
        };
        let mut dq = [0.0; 6];
        let n = dq_rad.len().min(6);
        dq[..n].copy_from_slice(&dq_rad[..n]);
        self.answer(dq, Some(tag))
    }

    fn protocol(&self) -> Protocol {
        P
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
    /// Sends `AIPos` (the first six joint values), `RIst` when known and
    /// `Delay D` = [`RobotState::late_answers`] (0 when absent).
    fn send_state(&mut self, s: &RobotState) -> Result<(), LinkError> {
        let mut q = [0.0; 6];
        let n = s.joint_count.min(6);
        q[..n].copy_from_slice(&s.q_rad[..n]);
        let t = RobTelegram {
            actual_pose: s.tcp_pose,
            setpoint_pose: None,
            q_rad: Some(q),
            delay: s.late_answers.unwrap_or(0),
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
        let body = t.rkorr.or(t.joints_rad).unwrap_or_default();
        let total = match self.mode {
            CorrectionMode::Absolute => body,
            CorrectionMode::Relative => {
                for (a, d) in self.accumulated.iter_mut().zip(body) {
                    *a += d;
                }
                self.accumulated
            }
        };
        Ok(Some(match t.rkorr {
            Some(_) => ReceivedCorrection {
                correction: rkorr_to_correction(&total),
                cycle_id: t.ipoc,
                joint_correction_rad: None,
            },
            None => ReceivedCorrection {
                correction: Correction::ZERO,
                cycle_id: t.ipoc,
                joint_correction_rad: Some(total),
            },
        }))
    }
}

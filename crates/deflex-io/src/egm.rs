//! ABB Externally Guided Motion (EGM), path-correction mode, protobuf over UDP.
//!
//! The robot controller streams `EgmRobot` messages (header with sequence
//! number `seqno`, controller time `tm` in ms and `mtype` = DATA, then
//! `feedBack` with the joints in **degrees** and the Cartesian TCP pose with
//! position in **mm** and orientation as a quaternion) every 4 ms to the
//! sensor. In path-correction mode (RAPID `EGMActMove` + `EGMMoveL`), the
//! sensor answers `EgmSensorPathCorr` messages: header (`mtype` =
//! PATH_CORRECTION) and `pathCorr { pos {x, y, z} in mm, age in ms }`. EGM
//! path correction is **position only** (the rotation part of a
//! [`Correction`] is ignored) and absolute (offset from the programmed path).
//!
//! **Frame.** egm.proto documents `pathCorr.pos` as "relative the sensor tool
//! coordinate system": the sensor frame given to `EGMActMove` (`SensorFrame`,
//! a pose relative to the tool). [`EgmLink`] takes the correction in robot
//! base axes and rotates it into the frame chosen by [`EgmFrame`]:
//! [`EgmFrame::Tool`] (default) uses the TCP orientation the runtime passes
//! with [`RobotLink::set_tcp_rotation`] (the model's forward kinematics at
//! the reported joints) times the sensor frame's orientation in the tool;
//! [`EgmFrame::WorkObject`] a fixed work-object orientation (for set-ups
//! whose sensor frame keeps the work object's axes, e.g. a tool whose
//! orientation never changes); [`EgmFrame::Base`] sends base axes unchanged.
//! The RAPID set-up is in `docs/abb/`.
//!
//! **Joints.** `feedBack.joints` carries the robot's own axes (up to six:
//! 4-, 5- and 6-axis arms send as many). ABB's seven-axis arms (IRB 14000)
//! send six there and the arm angle, physically the third axis, as the first
//! external joint; [`EgmConfig::seven_axis`] maps them back to chain order.
//!
//! **Peer.** [`EgmLink`] answers only the robot it is locked to (configured
//! address, or the first valid sender; see [`crate::peer`]).
//!
//! **Session rules.** A message from that robot is dropped unanswered
//! ([`LinkError::Dropped`], counted in [`RobotLink::counters`]) when its joint count differs
//! from the session's, its header `seqno` does not advance (a duplicate or a replay) or its
//! `tm` goes back ([`crate::guard`]); a message without `seqno` or `tm` is malformed. deflex's
//! own `seqno` counts the answers actually sent: it advances only when a path correction left
//! the socket, so the robot sees 1, 2, 3… without gaps.
//!
//! The message structs of [`msg`] are written by hand with
//! `#[derive(prost::Message)]` and the field numbers of ABB's `egm.proto`
//! (only the fields deflex needs; unknown fields are skipped when decoding).
//! On the sensor-side hot path, `EgmRobot` is decoded by
//! [`decode_robot`], a small allocation-free protobuf walker (prost would
//! allocate the repeated `joints` field), cross-checked against prost in
//! the tests.

use crate::error::{LinkError, Protocol};
use crate::guard::{LinkCounters, SessionGuard, Stamp};
use crate::link::{Correction, ReceivedCorrection, RobotLink, RobotSideLink, RobotState};
use crate::peer::{PeerLock, PeerPolicy};
use crate::udp::UdpEndpoint;
use deflex_model::conventions::{
    abb_quaternion, rotation_from_abb_quaternion, rotation_from_kuka_abc_deg,
};
use deflex_model::{MAX_JOINTS, Pose};
use nalgebra::{Rotation3, Translation3, Vector3};
use prost::Message;
use std::net::{SocketAddr, ToSocketAddrs};
use std::time::{Duration, Instant};

/// Buffer size of the EGM endpoints (EGM messages are a few hundred bytes).
pub const BUFFER: usize = 2048;
/// `EgmHeader.MessageType` value for robot data.
pub const MTYPE_DATA: i32 = 2;
/// `EgmHeader.MessageType` value for a sensor path correction.
pub const MTYPE_PATH_CORRECTION: i32 = 4;

const P: Protocol = Protocol::Egm;
const fn bad(reason: &'static str) -> LinkError {
    LinkError::malformed(P, reason)
}

#[path = "egm_msg.rs"]
pub mod msg;

/// The part of an `EgmRobot` message deflex uses, in SI units.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RobotFrame {
    /// Header sequence number.
    pub seqno: Option<u32>,
    /// Header time stamp (ms).
    pub tm_ms: Option<u32>,
    /// Header message type.
    pub mtype: Option<i32>,
    /// Feedback joints in rad (first `n_joints` valid).
    pub q_rad: [f64; 6],
    /// Number of feedback joints present (0 if none).
    pub n_joints: usize,
    /// Feedback external joints (rotating axes in rad; linear axes come in
    /// mm and are reported ×π/180, as they are not used as robot joints).
    pub external_rad: [f64; 6],
    /// Number of external joints present.
    pub n_external: usize,
    /// Feedback TCP pose (m): the orientation from `euler` (`z, y, x` in degrees, KUKA's
    /// Z-Y'-X'' angles) when present, else from the quaternion `orient` (ABB's convention),
    /// else the identity.
    pub tcp_pose: Option<Pose>,
}

/// A decoded path correction, in SI units.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PathCorrFrame {
    /// Header sequence number.
    pub seqno: Option<u32>,
    /// Header time stamp (ms).
    pub tm_ms: Option<u32>,
    /// Correction (m), path frame.
    pub dp_m: [f64; 3],
    /// Measurement age (ms).
    pub age_ms: u32,
}

struct Reader<'a> {
    b: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    fn new(b: &'a [u8]) -> Self {
        Reader { b, pos: 0 }
    }
    fn varint(&mut self) -> Result<u64, LinkError> {
        let mut v = 0u64;
        for i in 0..10 {
            let byte = *self.b.get(self.pos).ok_or(bad("truncated varint"))?;
            self.pos += 1;
            v |= u64::from(byte & 0x7f) << (7 * i);
            if byte & 0x80 == 0 {
                return Ok(v);
            }
        }
        Err(bad("varint longer than 10 bytes"))
    }
    /// Next `(field, wire type)`, `None` at the end.
    fn key(&mut self) -> Result<Option<(u64, u8)>, LinkError> {
        if self.pos >= self.b.len() {
            return Ok(None);
        }
        let k = self.varint()?;
        let field = k >> 3;
        if field == 0 {
            return Err(bad("field number 0"));
        }
        Ok(Some((field, (k & 7) as u8)))
    }
    fn take(&mut self, n: usize) -> Result<&'a [u8], LinkError> {
        let end = self
            .pos
            .checked_add(n)
            .filter(|e| *e <= self.b.len())
            .ok_or(bad("truncated field"))?;
        let s = &self.b[self.pos..end];
        self.pos = end;
        Ok(s)
    }
    fn bytes(&mut self) -> Result<&'a [u8], LinkError> {
        let n = self.varint()?;
        self.take(usize::try_from(n).map_err(|_| bad("length overflow"))?)
    }
    fn f64(&mut self) -> Result<f64, LinkError> {
        let s = self.take(8)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(s);
        Ok(f64::from_le_bytes(a))
    }
    fn skip(&mut self, wire: u8) -> Result<(), LinkError> {
        match wire {
            0 => self.varint().map(|_| ()),
            1 => self.take(8).map(|_| ()),
            2 => self.bytes().map(|_| ()),
            5 => self.take(4).map(|_| ()),
            _ => Err(bad("unsupported wire type")),
        }
    }
    fn expect(wire: u8, want: u8) -> Result<(), LinkError> {
        if wire == want {
            Ok(())
        } else {
            Err(bad("wrong wire type for a known field"))
        }
    }
}

fn finite(v: f64) -> Result<f64, LinkError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(bad("non-finite number"))
    }
}

fn doubles<const N: usize>(b: &[u8]) -> Result<([f64; N], usize), LinkError> {
    let mut r = Reader::new(b);
    let mut out = [0.0; N];
    let mut seen = 0usize;
    while let Some((f, w)) = r.key()? {
        if (1..=N as u64).contains(&f) {
            Reader::expect(w, 1)?;
            out[(f - 1) as usize] = finite(r.f64()?)?;
            seen |= 1 << (f - 1);
        } else {
            r.skip(w)?;
        }
    }
    Ok((out, seen))
}

fn joints(b: &[u8], q: &mut [f64; 6], n: &mut usize) -> Result<(), LinkError> {
    let mut r = Reader::new(b);
    let mut push = |v: f64, n: &mut usize| -> Result<(), LinkError> {
        if *n >= 6 {
            return Err(bad("more than 6 joints"));
        }
        q[*n] = finite(v)?.to_radians();
        *n += 1;
        Ok(())
    };
    *n = 0;
    while let Some((f, w)) = r.key()? {
        match (f, w) {
            (1, 1) => push(r.f64()?, n)?,
            (1, 2) => {
                let mut p = Reader::new(r.bytes()?);
                if !p.b.len().is_multiple_of(8) {
                    return Err(bad("packed doubles not a multiple of 8 bytes"));
                }
                while p.pos < p.b.len() {
                    push(p.f64()?, n)?;
                }
            }
            (1, _) => return Err(bad("wrong wire type for joints")),
            _ => r.skip(w)?,
        }
    }
    Ok(())
}

fn pose(b: &[u8]) -> Result<Option<Pose>, LinkError> {
    let mut r = Reader::new(b);
    let (mut pos, mut quat, mut euler) = (None, None, None);
    while let Some((f, w)) = r.key()? {
        match f {
            1 => {
                Reader::expect(w, 2)?;
                pos = Some(doubles::<3>(r.bytes()?)?.0);
            }
            2 => {
                Reader::expect(w, 2)?;
                quat = Some(doubles::<4>(r.bytes()?)?.0);
            }
            3 => {
                Reader::expect(w, 2)?;
                euler = Some(doubles::<3>(r.bytes()?)?.0);
            }
            _ => r.skip(w)?,
        }
    }
    let Some(p) = pos else { return Ok(None) };
    let position_m = Translation3::new(p[0] * 1e-3, p[1] * 1e-3, p[2] * 1e-3);
    let rotation = match (euler, quat) {
        (Some(e), _) => rotation_from_kuka_abc_deg([e[2], e[1], e[0]]),
        (None, Some(q)) => rotation_from_abb_quaternion(q),
        (None, None) => Rotation3::identity(),
    };
    Ok(Some(Pose::from_parts(position_m, rotation)))
}

/// Decodes the header and `feedBack` of an `EgmRobot` message without
/// allocating. Unknown fields are skipped; malformed input is an error.
pub fn decode_robot(buf: &[u8]) -> Result<RobotFrame, LinkError> {
    let mut out = RobotFrame::default();
    let mut r = Reader::new(buf);
    while let Some((f, w)) = r.key()? {
        match f {
            1 => {
                Reader::expect(w, 2)?;
                let mut h = Reader::new(r.bytes()?);
                while let Some((hf, hw)) = h.key()? {
                    match hf {
                        1..=3 => {
                            Reader::expect(hw, 0)?;
                            let v = h.varint()?;
                            match hf {
                                1 => out.seqno = Some(v as u32),
                                2 => out.tm_ms = Some(v as u32),
                                _ => out.mtype = Some(v as i32),
                            }
                        }
                        _ => h.skip(hw)?,
                    }
                }
            }
            2 => {
                Reader::expect(w, 2)?;
                let mut fb = Reader::new(r.bytes()?);
                while let Some((ff, fw)) = fb.key()? {
                    match ff {
                        1 => {
                            Reader::expect(fw, 2)?;
                            joints(fb.bytes()?, &mut out.q_rad, &mut out.n_joints)?;
                        }
                        3 => {
                            Reader::expect(fw, 2)?;
                            joints(fb.bytes()?, &mut out.external_rad, &mut out.n_external)?;
                        }
                        2 => {
                            Reader::expect(fw, 2)?;
                            out.tcp_pose = pose(fb.bytes()?)?;
                        }
                        _ => fb.skip(fw)?,
                    }
                }
            }
            _ => r.skip(w)?,
        }
    }
    Ok(out)
}

/// Encodes an `EgmSensorPathCorr` (position correction `dp_m` in metres,
/// converted to mm) into `out`, returning the length. Does not allocate.
pub fn encode_path_corr(
    seqno: u32,
    tm_ms: u32,
    dp_m: [f64; 3],
    age_ms: u32,
    out: &mut [u8],
) -> Result<usize, LinkError> {
    if !dp_m.iter().all(|v| v.is_finite()) {
        return Err(LinkError::InvalidValue {
            protocol: P,
            reason: "non-finite correction",
        });
    }
    let m = msg::EgmSensorPathCorr {
        header: Some(msg::EgmHeader {
            seqno: Some(seqno),
            tm: Some(tm_ms),
            mtype: Some(MTYPE_PATH_CORRECTION),
        }),
        path_corr: Some(msg::EgmPathCorr {
            pos: msg::EgmCartesian {
                x: dp_m[0] * 1e3,
                y: dp_m[1] * 1e3,
                z: dp_m[2] * 1e3,
            },
            age: age_ms,
        }),
    };
    let cap = out.len();
    let mut w = &mut out[..];
    m.encode(&mut w).map_err(|_| LinkError::BufferTooSmall {
        protocol: P,
        capacity: cap,
    })?;
    Ok(cap - w.len())
}

/// Decodes an `EgmSensorPathCorr` (robot side). Requires `pathCorr`.
pub fn decode_path_corr(buf: &[u8]) -> Result<PathCorrFrame, LinkError> {
    let m = msg::EgmSensorPathCorr::decode(buf)
        .map_err(|_| bad("protobuf decoding of EgmSensorPathCorr failed"))?;
    let pc = m
        .path_corr
        .ok_or(bad("EgmSensorPathCorr without pathCorr"))?;
    let h = m.header.unwrap_or_default();
    if h.mtype.is_some_and(|t| t != MTYPE_PATH_CORRECTION) {
        return Err(bad("header mtype is not PATH_CORRECTION"));
    }
    let dp_m = [
        finite(pc.pos.x)? * 1e-3,
        finite(pc.pos.y)? * 1e-3,
        finite(pc.pos.z)? * 1e-3,
    ];
    Ok(PathCorrFrame {
        seqno: h.seqno,
        tm_ms: h.tm,
        dp_m,
        age_ms: pc.age,
    })
}

/// Fills a reusable `EgmRobot` from a state (joints in deg, position in mm,
/// quaternion); reuses the joints vectors' capacity. With `seven_axis` the
/// third of seven joints goes to the first external joint (ABB's layout).
pub fn fill_robot_msg(
    m: &mut msg::EgmRobot,
    s: &RobotState,
    seqno: u32,
    tm_ms: u32,
    seven_axis: bool,
) {
    m.header = Some(msg::EgmHeader {
        seqno: Some(seqno),
        tm: Some(tm_ms),
        mtype: Some(MTYPE_DATA),
    });
    let fb = m.feed_back.get_or_insert_with(Default::default);
    let j = fb.joints.get_or_insert_with(Default::default);
    j.joints.clear();
    let q = s.joints();
    if seven_axis && q.len() == 7 {
        j.joints.extend(
            [q[0], q[1], q[3], q[4], q[5], q[6]]
                .iter()
                .map(|v| v.to_degrees()),
        );
        let e = fb.external_joints.get_or_insert_with(Default::default);
        e.joints.clear();
        e.joints.push(q[2].to_degrees());
    } else {
        j.joints.extend(q.iter().map(|v| v.to_degrees()));
        fb.external_joints = None;
    }
    fb.cartesian = s.tcp_pose.map(|p| {
        let q = abb_quaternion(&p.rotation, None);
        let t = p.translation.vector;
        msg::EgmPose {
            pos: Some(msg::EgmCartesian {
                x: t.x * 1e3,
                y: t.y * 1e3,
                z: t.z * 1e3,
            }),
            orient: Some(msg::EgmQuaternion {
                u0: q[0],
                u1: q[1],
                u2: q[2],
                u3: q[3],
            }),
            euler: None,
        }
    });
}

/// The frame `pathCorr.pos` is expressed in (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum EgmFrame {
    /// The sensor frame of `EGMActMove`, attached to the tool (egm.proto's
    /// "sensor tool coordinate system").
    #[default]
    Tool,
    /// A fixed work-object orientation.
    WorkObject,
    /// Robot base axes, unchanged.
    Base,
}

/// Settings of [`EgmLink`] (and of the simulated robot's endpoint).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EgmConfig {
    /// Frame of the correction.
    pub frame: EgmFrame,
    /// Orientation of `EGMActMove`'s sensor frame relative to the tool, for
    /// [`EgmFrame::Tool`].
    pub sensor_in_tool: Rotation3<f64>,
    /// Orientation of the work object in the robot base frame, for
    /// [`EgmFrame::WorkObject`].
    pub work_object_in_base: Rotation3<f64>,
    /// Age (ms) reported in `pathCorr.age`.
    pub age_ms: u32,
    /// The robot is one of ABB's seven-axis arms: axis 3 arrives as the first
    /// external joint.
    pub seven_axis: bool,
}

impl Default for EgmConfig {
    fn default() -> Self {
        EgmConfig {
            frame: EgmFrame::Tool,
            sensor_in_tool: Rotation3::identity(),
            work_object_in_base: Rotation3::identity(),
            age_ms: 10,
            seven_axis: false,
        }
    }
}

impl EgmConfig {
    /// Orientation, in robot base axes, of the frame `pathCorr.pos` is
    /// expressed in, given the TCP orientation in base axes.
    pub fn correction_frame(&self, tcp_in_base: &Rotation3<f64>) -> Rotation3<f64> {
        match self.frame {
            EgmFrame::Tool => tcp_in_base * self.sensor_in_tool,
            EgmFrame::WorkObject => self.work_object_in_base,
            EgmFrame::Base => Rotation3::identity(),
        }
    }

    /// Joint values in chain order from a decoded feedback (at most
    /// [`MAX_JOINTS`]); an error when the message does not carry what the
    /// configuration needs.
    pub fn chain_joints(&self, f: &RobotFrame) -> Result<([f64; MAX_JOINTS], usize), LinkError> {
        let mut q = [0.0; MAX_JOINTS];
        if self.seven_axis {
            if f.n_joints != 6 || f.n_external < 1 {
                return Err(bad(
                    "seven-axis robot: feedback needs 6 joints and the arm angle as first external joint",
                ));
            }
            let j = &f.q_rad;
            q[..7].copy_from_slice(&[j[0], j[1], f.external_rad[0], j[2], j[3], j[4], j[5]]);
            Ok((q, 7))
        } else {
            if f.n_joints == 0 {
                return Err(bad("EgmRobot feedback carries no joints"));
            }
            q[..f.n_joints].copy_from_slice(&f.q_rad[..f.n_joints]);
            Ok((q, f.n_joints))
        }
    }
}

/// Sensor side of EGM (the deflex controller): receives `EgmRobot`, sends
/// `EgmSensorPathCorr` to the robot the link is locked to.
#[derive(Debug)]
pub struct EgmLink {
    ep: UdpEndpoint,
    rx: Box<[u8; BUFFER]>,
    tx: Box<[u8; BUFFER]>,
    seqno: u32,
    epoch: Instant,
    cfg: EgmConfig,
    tcp_in_base: Rotation3<f64>,
    last: Option<RobotFrame>,
    peers: PeerLock,
    guard: SessionGuard,
    answers: u64,
}

impl EgmLink {
    /// Binds to `local` (the UDP port configured in the robot's EGM
    /// transmission settings).
    pub fn bind(local: impl ToSocketAddrs, cfg: EgmConfig) -> Result<Self, LinkError> {
        Ok(EgmLink {
            ep: UdpEndpoint::bind(local, P)?,
            rx: Box::new([0; BUFFER]),
            tx: Box::new([0; BUFFER]),
            seqno: 0,
            epoch: Instant::now(),
            cfg,
            tcp_in_base: Rotation3::identity(),
            last: None,
            peers: PeerLock::first_sender(),
            guard: SessionGuard::new(),
            answers: 0,
        })
    }
    /// Accepts messages only from `peer` (port 0: any port of that IP).
    pub fn expect_peer(&mut self, peer: SocketAddr) {
        self.peers.set_configured(Some(peer));
    }
    /// Sets the peer policy (see [`crate::peer::validate_peer`]).
    pub fn set_peer_policy(&mut self, policy: PeerPolicy) {
        self.peers.set_policy(policy);
    }
    /// The sender lock.
    pub fn peers(&self) -> &PeerLock {
        &self.peers
    }
    /// Local socket address.
    pub fn local_addr(&self) -> Result<SocketAddr, LinkError> {
        self.ep.local_addr()
    }
    /// Last valid robot message.
    pub fn last_frame(&self) -> Option<&RobotFrame> {
        self.last.as_ref()
    }
    /// Settings.
    pub fn config(&self) -> &EgmConfig {
        &self.cfg
    }
}

impl RobotLink for EgmLink {
    fn receive(&mut self, timeout: Duration) -> Result<Option<RobotState>, LinkError> {
        let Some((n, from)) = self.ep.recv(&mut self.rx[..], timeout)? else {
            return Ok(None);
        };
        self.peers.check(P, from)?;
        let f = decode_robot(&self.rx[..n])?;
        let (q, count) = self.cfg.chain_joints(&f)?;
        let (Some(seqno), Some(tm)) = (f.seqno, f.tm_ms) else {
            return Err(bad("EgmRobot header lacks seqno or tm"));
        };
        self.guard
            .admit(count, Some(u64::from(seqno)), Some(Stamp::Millis32(tm)))
            .map_err(|reason| LinkError::Dropped {
                protocol: P,
                reason,
            })?;
        self.peers.lock(from);
        self.ep.set_peer(from);
        self.last = Some(f);
        Ok(Some(RobotState {
            q_rad: q,
            joint_count: count,
            tcp_pose: f.tcp_pose,
            cycle_id: u64::from(seqno),
            robot_time_s: Some(f64::from(tm) * 1e-3),
            status: 0,
            late_answers: None,
        }))
    }

    /// Sends `correction.dp_m` rotated from base axes into the configured
    /// frame; the rotation part is ignored. The answer's `seqno` is deflex's
    /// count of answers sent, including this one: it advances only when the
    /// datagram was sent.
    fn send_correction(&mut self, c: &Correction) -> Result<(), LinkError> {
        if self.ep.peer().is_none() {
            return Err(LinkError::NoPeer { protocol: P });
        }
        let frame = self.cfg.correction_frame(&self.tcp_in_base);
        let dp: [f64; 3] = frame
            .inverse_transform_vector(&Vector3::from(c.dp_m))
            .into();
        let seqno = self.seqno.wrapping_add(1);
        let tm = self.epoch.elapsed().as_millis() as u32;
        let n = encode_path_corr(seqno, tm, dp, self.cfg.age_ms, &mut self.tx[..])?;
        self.ep.send(&self.tx[..n])?;
        self.seqno = seqno;
        self.answers += 1;
        Ok(())
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

    fn set_tcp_rotation(&mut self, rotation: &Rotation3<f64>) {
        if rotation.matrix().iter().all(|v| v.is_finite()) {
            self.tcp_in_base = *rotation;
        }
    }

    fn protocol(&self) -> Protocol {
        P
    }
}

/// Robot side of EGM (used by the simulated cell).
#[derive(Debug)]
pub struct EgmRobotEndpoint {
    ep: UdpEndpoint,
    msg: msg::EgmRobot,
    rx: Box<[u8; BUFFER]>,
    tx: Box<[u8; BUFFER]>,
    seven_axis: bool,
    frame: Rotation3<f64>,
}

impl EgmRobotEndpoint {
    /// Binds to `local` and sends to `sensor`.
    pub fn new(local: impl ToSocketAddrs, sensor: SocketAddr) -> Result<Self, LinkError> {
        let mut ep = UdpEndpoint::bind(local, P)?;
        ep.set_peer(sensor);
        let mut msg = msg::EgmRobot::default();
        fill_robot_msg(&mut msg, &RobotState::default(), 0, 0, false);
        Ok(EgmRobotEndpoint {
            ep,
            msg,
            rx: Box::new([0; BUFFER]),
            tx: Box::new([0; BUFFER]),
            seven_axis: false,
            frame: Rotation3::identity(),
        })
    }
    /// Sends the third of seven joints as the first external joint (ABB's
    /// seven-axis arms).
    pub fn set_seven_axis(&mut self, seven_axis: bool) {
        self.seven_axis = seven_axis;
    }
    /// Orientation in base axes of the frame the corrections arrive in
    /// ([`EgmConfig::correction_frame`]); received corrections are rotated
    /// back to base axes with it.
    pub fn set_correction_frame(&mut self, frame: &Rotation3<f64>) {
        self.frame = *frame;
    }
    /// Local socket address.
    pub fn local_addr(&self) -> Result<SocketAddr, LinkError> {
        self.ep.local_addr()
    }
}

impl RobotSideLink for EgmRobotEndpoint {
    /// `cycle_id` becomes `seqno` (truncated to 32 bits), `robot_time_s` `tm`.
    fn send_state(&mut self, s: &RobotState) -> Result<(), LinkError> {
        let tm = (s.robot_time_s.unwrap_or(0.0) * 1e3) as u32;
        fill_robot_msg(&mut self.msg, s, s.cycle_id as u32, tm, self.seven_axis);
        let cap = self.tx.len();
        let mut w = &mut self.tx[..];
        self.msg
            .encode(&mut w)
            .map_err(|_| LinkError::BufferTooSmall {
                protocol: P,
                capacity: cap,
            })?;
        let n = cap - w.len();
        self.ep.send(&self.tx[..n])
    }

    /// The correction in base axes (rotated back from the configured frame).
    fn receive_correction(
        &mut self,
        timeout: Duration,
    ) -> Result<Option<ReceivedCorrection>, LinkError> {
        let Some((n, _)) = self.ep.recv(&mut self.rx[..], timeout)? else {
            return Ok(None);
        };
        let f = decode_path_corr(&self.rx[..n])?;
        let dp_m: [f64; 3] = (self.frame * Vector3::from(f.dp_m)).into();
        Ok(Some(ReceivedCorrection {
            correction: Correction {
                dp_m,
                dphi_rad: [0.0; 3],
            },
            cycle_id: u64::from(f.seqno.unwrap_or(0)),
            joint_correction_rad: None,
        }))
    }
}

//! The robot side of Stream Motion: a FANUC controller running `IBGN start[*]`, as the
//! simulated cell plays it ([`FanucStreamRobotEndpoint`]).
//!
//! It waits for a start packet (the first sender of one becomes the session's device), answers
//! threshold requests with its limit tables, sends a status packet each cycle
//! ([`RobotSideLink::send_state`]: ready, system ready, command received, in motion; the error
//! bit once latched), and takes the command answering it ([`RobotSideLink::receive_correction`]).
//! Like a real controller it refuses a command that steps beyond its velocity, acceleration or
//! jerk thresholds: it latches its error bit, holds its last accepted command and reports the
//! error until a new start. A status left unanswered holds the last command for that cycle:
//! the next command's step is checked over the cycles since the last accepted one (up to four).
//! A command with `is_last_command` ends the motion; a stop packet
//! ends the session.

use super::motion::{AXES, StreamLimits};
use super::{
    Command, Control, MAX_AXES, ROBOT_ERROR, STATUS_COMMAND_RECEIVED, STATUS_IN_MOTION,
    STATUS_READY, STATUS_SYSRDY, Status, THRESHOLD_ENTRIES, TYPE_COMMAND, TYPE_START, TYPE_STOP,
    TYPE_THRESHOLD, ThresholdKind, ThresholdTable, VERSION, format_status, format_threshold_table,
    packet_type, parse_command, parse_control, parse_threshold_request,
};
use crate::error::{LinkError, Protocol};
use crate::link::{Correction, ReceivedCorrection, RobotSideLink, RobotState};
use crate::udp::UdpEndpoint;
use std::net::{SocketAddr, ToSocketAddrs};
use std::time::{Duration, Instant};

const P: Protocol = Protocol::FanucStream;

/// Relative tolerance of the robot side's threshold checks (rounding of the wire's degrees).
const CHECK_TOLERANCE: f64 = 1e-6;

/// The most cycles a command's step may span when the statuses before it went unanswered
/// ([`FanucStreamRobotEndpoint`]'s threshold check).
const MAX_HELD_CYCLES: u32 = 4;

/// Why the simulated controller latched its error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThresholdFault {
    /// Axis (1-based).
    pub axis: usize,
    /// `velocity`, `acceleration` or `jerk`.
    pub what: &'static str,
    /// What the command needed (rad/s, rad/s², rad/s³).
    pub value: f64,
    /// The threshold.
    pub limit: f64,
}

/// A simulated FANUC controller serving Stream Motion (see the module documentation).
#[derive(Debug)]
pub struct FanucStreamRobotEndpoint {
    ep: UdpEndpoint,
    period_s: f64,
    limits: StreamLimits,
    rx: Box<[u8; 1024]>,
    tx: Box<[u8; 512]>,
    device: Option<SocketAddr>,
    streaming: bool,
    sequence: u32,
    answered: bool,
    error: Option<ThresholdFault>,
    /// Last accepted command, its velocity and acceleration (rad, rad/s, rad/s²).
    command: Option<([f64; AXES], [f64; AXES], [f64; AXES])>,
    /// The sequence number the last accepted command answered.
    command_sequence: u32,
    reported: [f64; AXES],
    last_command_seen: bool,
    stopped: bool,
    accepted: u64,
    refused: u64,
    foreign: u64,
    started_at: Option<Instant>,
}

impl FanucStreamRobotEndpoint {
    /// Binds the controller's Stream Motion port at `local` (port 60015 on a real controller;
    /// any on loopback), with cycle `period_s` and the thresholds `limits` it reports and
    /// enforces.
    pub fn bind(
        local: impl ToSocketAddrs,
        period_s: f64,
        limits: StreamLimits,
    ) -> Result<Self, LinkError> {
        if !(limits.is_valid() && period_s.is_finite() && period_s > 0.0) {
            return Err(LinkError::InvalidValue {
                protocol: P,
                reason: "period and thresholds must be finite and positive",
            });
        }
        Ok(FanucStreamRobotEndpoint {
            ep: UdpEndpoint::bind(local, P)?,
            period_s,
            limits,
            rx: Box::new([0; 1024]),
            tx: Box::new([0; 512]),
            device: None,
            streaming: false,
            sequence: 0,
            answered: false,
            error: None,
            command: None,
            command_sequence: 0,
            reported: [0.0; AXES],
            last_command_seen: false,
            stopped: false,
            accepted: 0,
            refused: 0,
            foreign: 0,
            started_at: None,
        })
    }

    /// Local socket address (where the device sends).
    pub fn local_addr(&self) -> Result<SocketAddr, LinkError> {
        self.ep.local_addr()
    }

    /// The device streaming to this controller, once a start packet came.
    pub fn device(&self) -> Option<SocketAddr> {
        self.device
    }

    /// Streaming: a start packet came, no stop packet and no last command since.
    pub fn streaming(&self) -> bool {
        self.streaming
    }

    /// The last command carried `is_last_command`.
    pub fn saw_last_command(&self) -> bool {
        self.last_command_seen
    }

    /// A stop packet came.
    pub fn stopped(&self) -> bool {
        self.stopped
    }

    /// The sequence number of the last status packet sent (its command must echo it).
    pub fn sequence(&self) -> u32 {
        self.sequence
    }

    /// The latched threshold fault.
    pub fn fault(&self) -> Option<ThresholdFault> {
        self.error
    }

    /// The joints the robot is commanded to (rad): the last accepted command.
    pub fn commanded_rad(&self) -> Option<[f64; AXES]> {
        self.command.map(|c| c.0)
    }

    /// Commands accepted and refused (beyond a threshold), datagrams from others than the
    /// device.
    pub fn counts(&self) -> (u64, u64, u64) {
        (self.accepted, self.refused, self.foreign)
    }

    /// Handles one control packet or threshold request from `from`; returns true for a
    /// command packet (left in the buffer, `n` bytes).
    fn handle(&mut self, n: usize, from: SocketAddr) -> Result<bool, LinkError> {
        let kind = packet_type(&self.rx[..n])?;
        if let Some(device) = self.device
            && device != from
            && kind != TYPE_START
        {
            self.foreign += 1;
            return Ok(false);
        }
        match kind {
            TYPE_START | TYPE_STOP => match parse_control(&self.rx[..n])? {
                Control::Start { .. } => {
                    if self.device.is_some_and(|d| d != from) && self.streaming {
                        // Another device while one streams: refused.
                        self.foreign += 1;
                        return Ok(false);
                    }
                    self.device = Some(from);
                    self.streaming = true;
                    self.stopped = false;
                    self.last_command_seen = false;
                    self.error = None;
                    self.command = None;
                    self.sequence = 0;
                    self.answered = false;
                    self.started_at = Some(Instant::now());
                }
                Control::Stop { .. } => {
                    self.streaming = false;
                    self.stopped = true;
                }
            },
            TYPE_THRESHOLD => {
                let r = parse_threshold_request(&self.rx[..n])?;
                let i = r.axis as usize - 1;
                let value = if i < AXES {
                    match r.kind {
                        ThresholdKind::Velocity => self.limits.velocity[i],
                        ThresholdKind::Acceleration => self.limits.acceleration[i],
                        ThresholdKind::Jerk => self.limits.jerk[i],
                    }
                } else {
                    self.limits.velocity[0]
                };
                let v = value.to_degrees() as f32;
                let table = ThresholdTable {
                    version: VERSION,
                    axis: r.axis,
                    kind: r.kind,
                    max_cartesian_speed: 2000,
                    interval: 100,
                    no_payload: [v; THRESHOLD_ENTRIES],
                    full_payload: [v; THRESHOLD_ENTRIES],
                };
                let len = format_threshold_table(&table, &mut self.tx[..])?;
                self.ep.send_to(&self.tx[..len], from)?;
            }
            TYPE_COMMAND => return Ok(true),
            _ => return Err(LinkError::malformed(P, "unknown packet type")),
        }
        Ok(false)
    }

    /// Handles every datagram waiting (control packets, threshold requests); commands that
    /// were not awaited are dropped.
    pub fn poll(&mut self) -> Result<(), LinkError> {
        while let Some((n, from)) = self.ep.recv(&mut self.rx[..], Duration::ZERO)? {
            let _ = self.handle(n, from);
        }
        Ok(())
    }

    /// Checks a command against the thresholds; accepts it or latches the error.
    fn take(&mut self, c: &Command) {
        // A status left unanswered (its command came too late and was dropped) held the last
        // command for that cycle: the next command's step spans the cycles since the last one
        // accepted, up to [`MAX_HELD_CYCLES`] (a longer gap is checked as one cycle's step).
        let gap = c.sequence.wrapping_sub(self.command_sequence);
        let cycles = if self.command.is_some() && (1..=MAX_HELD_CYCLES).contains(&gap) {
            f64::from(gap)
        } else {
            1.0
        };
        let t = self.period_s * cycles;
        let q: [f64; AXES] = std::array::from_fn(|i| c.joints_deg[i].to_radians());
        let (q0, v0, a0) = self
            .command
            .unwrap_or((self.reported, [0.0; AXES], [0.0; AXES]));
        let mut v = [0.0; AXES];
        let mut a = [0.0; AXES];
        for i in 0..AXES {
            v[i] = (q[i] - q0[i]) / t;
            a[i] = (v[i] - v0[i]) / t;
            let j = (a[i] - a0[i]) / t;
            let checks = [
                ("velocity", v[i], self.limits.velocity[i]),
                ("acceleration", a[i], self.limits.acceleration[i]),
                ("jerk", j, self.limits.jerk[i]),
            ];
            for (what, value, limit) in checks {
                if value.abs() > limit * (1.0 + CHECK_TOLERANCE) {
                    self.error = Some(ThresholdFault {
                        axis: i + 1,
                        what,
                        value: value.abs(),
                        limit,
                    });
                    self.refused += 1;
                    return;
                }
            }
        }
        self.command = Some((q, v, a));
        self.command_sequence = c.sequence;
        self.accepted += 1;
        if c.is_last {
            self.last_command_seen = true;
            self.streaming = false;
        }
    }
}

impl RobotSideLink for FanucStreamRobotEndpoint {
    /// Sends the cycle's status packet with the state's joints (nothing before a start packet
    /// or after the stream ended).
    fn send_state(&mut self, state: &RobotState) -> Result<(), LinkError> {
        self.poll()?;
        let q = state.joints();
        for (i, r) in self.reported.iter_mut().enumerate() {
            *r = q.get(i).copied().unwrap_or(0.0);
        }
        let Some(device) = self.device else {
            return Ok(());
        };
        if !self.streaming && !self.last_command_seen {
            return Ok(());
        }
        if self.stopped {
            return Ok(());
        }
        self.sequence = self.sequence.wrapping_add(1);
        let mut joints_deg = [0.0f32; MAX_AXES];
        for (o, v) in joints_deg.iter_mut().zip(&self.reported) {
            *o = v.to_degrees() as f32;
        }
        let moving = self
            .command
            .is_some_and(|(_, v, _)| v.iter().any(|x| x.abs() > 1e-6));
        let mut status = STATUS_SYSRDY;
        if self.error.is_none() && self.streaming {
            status |= STATUS_READY;
        }
        if self.answered {
            status |= STATUS_COMMAND_RECEIVED;
        }
        if moving {
            status |= STATUS_IN_MOTION;
        }
        let elapsed = self.started_at.map_or(0.0, |t| t.elapsed().as_secs_f64());
        let s = Status {
            version: VERSION,
            sequence: self.sequence,
            status,
            robot_status: if self.error.is_some() { ROBOT_ERROR } else { 0 },
            contact_stop: 0,
            time_ms: (elapsed * 1e3) as u32,
            joints_deg,
            safety_scale: 1.0,
            ..Status::default()
        };
        self.answered = false;
        let n = format_status(&s, &mut self.tx[..])?;
        self.ep.send_to(&self.tx[..n], device)
    }

    /// Waits up to `timeout` for the command answering the last status; returns it as the joint
    /// step from the reported joints (`joint_correction_rad`: commanded − reported), whether
    /// accepted or not (a refused command leaves [`Self::commanded_rad`] unchanged).
    fn receive_correction(
        &mut self,
        timeout: Duration,
    ) -> Result<Option<ReceivedCorrection>, LinkError> {
        let deadline = Instant::now() + timeout;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            let Some((n, from)) = self.ep.recv(&mut self.rx[..], left)? else {
                return Ok(None);
            };
            if !self.handle(n, from)? {
                if left.is_zero() {
                    return Ok(None);
                }
                continue;
            }
            let c = parse_command(&self.rx[..n])?;
            if c.sequence != self.sequence || self.answered {
                // Not this cycle's answer: dropped.
                continue;
            }
            self.answered = true;
            if self.error.is_none() && (self.streaming || self.last_command_seen) {
                self.take(&c);
            }
            let target = self.command.map_or(self.reported, |c| c.0);
            let dq = std::array::from_fn(|i| target[i] - self.reported[i]);
            return Ok(Some(ReceivedCorrection {
                correction: Correction::ZERO,
                cycle_id: u64::from(c.sequence),
                joint_correction_rad: Some(dq),
            }));
        }
    }
}

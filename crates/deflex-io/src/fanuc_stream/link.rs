//! The controller side of Stream Motion: deflex streams the path's joint targets with the
//! online correction added ([`FanucStreamLink`], a [`RobotLink`] that answers in joint space).
//!
//! **What is streamed.** A [`StreamTrajectory`] planned before the session (the compensated
//! path's joints, time-parametrised at the program's feed, starting and ending at rest with
//! jerk-limited ramps). At the first status the link plans an [`Approach`] from the joints the
//! controller reports to the trajectory's first point (a minimum-jerk move within the limits;
//! refused when the robot stands further than [`FanucStreamConfig::max_approach_rad`] from it),
//! then streams `trajectory[k] + Δq` where Δq is the runtime's joint correction (the Cartesian
//! correction through the model's Jacobian, clamped to
//! [`FanucStreamConfig::max_correction_rad`] per axis and passed through a [`CorrectionFilter`]),
//! then holds the last point until the command is at rest and sends it with `is_last_command`,
//! and a stop packet after it.
//!
//! **Limits.** The limits are the configured ones, tightened by the controller's own tables
//! ([`FanucStreamLink::query_thresholds`], scaled by [`FanucStreamConfig::threshold_margin`])
//! when the controller answers them. They are shared: the path must keep within
//! `1 − correction_share` of them (checked when the motion starts, else the stream stops with
//! [`StopReason::PathBeyondLimits`] before moving), the filtered correction keeps within the
//! rest whatever its input, so their sum keeps within the limits, jerk included. Every target
//! then passes a [`MotionLimiter`] as a last guard: whatever the network or the correction did,
//! no command steps faster than the velocity limit or changes its velocity faster than the
//! acceleration limit.
//!
//! **Safety.** The link stops the stream ([`StopReason`]) on a status that comes later than
//! [`FanucStreamConfig::late_after`] after the previous one, on a status whose error or
//! emergency-stop bit is set (or that no longer reports ready), on a datagram from anyone but
//! the controller (refused unanswered, [`LinkError::ForeignSender`]), on a non-finite
//! correction, and on silence longer than [`FanucStreamConfig::lost_after`]. A stop answers the
//! following status packets with a braking to rest within the acceleration and jerk limits,
//! then `is_last_command` and a stop packet; when the link is lost altogether only the stop
//! packet can be sent (the controller's own watchdog then stops the robot).
//!
//! The hot path (`receive`, `send_joint_correction`) allocates nothing: fixed buffers, fixed
//! arrays.

use super::motion::{
    AXES, Approach, CorrectionFilter, MotionLimiter, StreamLimits, StreamTrajectory,
    TrajectoryError,
};
use super::{
    Command, MAX_AXES, Status, TYPE_THRESHOLD, ThresholdKind, ThresholdRequest, VERSION,
    format_command, format_start, format_stop, format_threshold_request, packet_type, parse_status,
    parse_threshold_table,
};
use crate::error::{LinkError, Protocol};
use crate::guard::{LinkCounters, SessionGuard};
use crate::link::{Correction, RobotLink, RobotState};
use crate::peer::{PeerLock, PeerPolicy};
use crate::udp::UdpEndpoint;
use std::net::{SocketAddr, ToSocketAddrs};
use std::time::{Duration, Instant};

const P: Protocol = Protocol::FanucStream;
/// Receive buffer: larger than every packet, so a datagram that fills it is refused as oversize.
const RX: usize = 1024;
/// Transmit buffer.
const TX: usize = 512;

/// The share of the limits the correction may use by default
/// ([`FanucStreamConfig::correction_share`]).
pub const DEFAULT_CORRECTION_SHARE: f64 = 0.25;

/// Settings of the controller side.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FanucStreamConfig {
    /// The controller's Stream Motion address (its IP, port 60015).
    pub controller: SocketAddr,
    /// The controller's cycle (s): 0.004 or 0.008.
    pub period_s: f64,
    /// The configured limits (an upper bound: the controller's tables may tighten them).
    pub limits: StreamLimits,
    /// The fraction of the controller's reported thresholds the stream uses (0 < m ≤ 1).
    pub threshold_margin: f64,
    /// A status arriving later than this after the previous one stops the stream.
    pub late_after: Duration,
    /// No status for this long: the link is lost (stop packet sent, stream over).
    pub lost_after: Duration,
    /// The robot may stand at most this far (rad, any axis) from the path's start.
    pub max_approach_rad: f64,
    /// Per-axis bound of the joint correction added to the path (rad).
    pub max_correction_rad: f64,
    /// The share of the limits the correction may use (0 < s < 1): the path must keep within
    /// the rest, the correction is filtered to keep within its share
    /// ([`CorrectionFilter`]).
    pub correction_share: f64,
}

impl FanucStreamConfig {
    /// Defaults for a controller at `controller` with cycle `period_s`: default limits, 90 % of
    /// the controller's thresholds, late after 5 cycles, lost after 0.5 s, approach up to
    /// 0.35 rad, corrections up to 0.02 rad using a quarter of the limits.
    pub fn new(controller: SocketAddr, period_s: f64) -> Self {
        FanucStreamConfig {
            controller,
            period_s,
            limits: StreamLimits::default(),
            threshold_margin: 0.9,
            late_after: Duration::from_secs_f64(5.0 * period_s),
            lost_after: Duration::from_millis(500),
            max_approach_rad: 0.35,
            max_correction_rad: 0.02,
            correction_share: DEFAULT_CORRECTION_SHARE,
        }
    }
}

/// Why the stream stopped (or is stopping).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StopReason {
    /// The path was streamed to its end.
    Finished,
    /// A status came `gap_s` after the previous one.
    LateStatus {
        /// The gap (s).
        gap_s: f64,
    },
    /// The controller reported an error, an emergency stop or lost its ready bit.
    ControllerError {
        /// Its status bits.
        status: u8,
        /// Its robot-status bits.
        robot_status: u8,
    },
    /// A datagram came from someone other than the controller.
    ForeignStatus {
        /// The sender.
        from: SocketAddr,
    },
    /// No status for `silent_s`.
    LostLink {
        /// The silence (s).
        silent_s: f64,
    },
    /// The robot stood too far from the path's start.
    StartTooFar {
        /// Axis (1-based).
        axis: usize,
        /// Distance (rad).
        distance_rad: f64,
    },
    /// The correction was not finite.
    InvalidCorrection,
    /// The path needs more than its share of the limits (after the controller's tables
    /// tightened them).
    PathBeyondLimits {
        /// Axis (1-based).
        axis: usize,
        /// `rad/s`, `rad/s²`, `rad/s³`.
        what: &'static str,
        /// What the path needs.
        needed: f64,
        /// Its share of the limit.
        limit: f64,
    },
}

impl StopReason {
    /// True for every reason but [`StopReason::Finished`].
    pub fn is_fault(&self) -> bool {
        !matches!(self, StopReason::Finished)
    }
}

/// Where the stream stands.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StreamPhase {
    /// Nothing sent yet.
    Idle,
    /// Start packet sent, no command yet.
    Starting,
    /// Moving from the robot's position to the path's start.
    Approach,
    /// Streaming the path.
    Path,
    /// Path done: bringing the command to rest at its last point.
    Settling,
    /// Braking to rest after a fault.
    Stopping,
    /// The last command was sent.
    LastSent,
    /// The stop packet was sent: the stream is over.
    Done,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Phase {
    Idle,
    Starting,
    Approach { approach: Approach, k: u64 },
    Path { k: usize },
    Settling,
    Stopping,
    LastSent,
    Done,
}

/// The controller side of FANUC Stream Motion (see the module documentation).
#[derive(Debug)]
pub struct FanucStreamLink {
    ep: UdpEndpoint,
    cfg: FanucStreamConfig,
    trajectory: StreamTrajectory,
    limits: StreamLimits,
    thresholds_from_controller: bool,
    limiter: MotionLimiter,
    filter: CorrectionFilter,
    settle_dq: [f64; AXES],
    phase: Phase,
    stop: Option<StopReason>,
    rx: Box<[u8; RX]>,
    tx: Box<[u8; TX]>,
    peers: PeerLock,
    guard: SessionGuard,
    version: u32,
    last_status: Option<Status>,
    last_status_at: Option<Instant>,
    answered: bool,
    start_sent_at: Option<Instant>,
    answers: u64,
    superseded: u64,
    largest_step_rad: [f64; AXES],
}

impl FanucStreamLink {
    /// Binds to `local` to stream `trajectory` to the controller of `cfg`. The limits must be
    /// valid and the trajectory's period the controller's.
    pub fn bind(
        local: impl ToSocketAddrs,
        cfg: FanucStreamConfig,
        trajectory: StreamTrajectory,
    ) -> Result<Self, LinkError> {
        let invalid = |reason| LinkError::InvalidValue {
            protocol: P,
            reason,
        };
        if !cfg.limits.is_valid() {
            return Err(invalid("stream limits must be finite and positive"));
        }
        if (trajectory.period_s() - cfg.period_s).abs() > 1e-9 {
            return Err(invalid("the trajectory's period is not the controller's"));
        }
        let margin_ok = cfg.threshold_margin > 0.0
            && cfg.threshold_margin <= 1.0
            && cfg.correction_share > 0.0
            && cfg.correction_share < 1.0;
        let bounds_ok = cfg.max_approach_rad.is_finite()
            && cfg.max_approach_rad >= 0.0
            && cfg.max_correction_rad.is_finite()
            && cfg.max_correction_rad >= 0.0;
        if !margin_ok || !bounds_ok {
            return Err(invalid(
                "threshold margin in (0, 1], correction share in (0, 1), approach and correction \
                 bounds finite",
            ));
        }
        let mut ep = UdpEndpoint::bind(local, P)?;
        ep.set_peer(cfg.controller);
        let mut peers = PeerLock::first_sender();
        peers.set_policy(PeerPolicy::Fixed(cfg.controller));
        let start = trajectory.points()[0];
        Ok(FanucStreamLink {
            ep,
            limits: cfg.limits,
            limiter: MotionLimiter::new(cfg.period_s, cfg.limits, start),
            filter: CorrectionFilter::for_share(
                cfg.period_s,
                &cfg.limits,
                cfg.correction_share,
                cfg.max_correction_rad,
            ),
            settle_dq: [0.0; AXES],
            cfg,
            trajectory,
            thresholds_from_controller: false,
            phase: Phase::Idle,
            stop: None,
            rx: Box::new([0; RX]),
            tx: Box::new([0; TX]),
            peers,
            guard: SessionGuard::new(),
            version: VERSION,
            last_status: None,
            last_status_at: None,
            answered: true,
            start_sent_at: None,
            answers: 0,
            superseded: 0,
            largest_step_rad: [0.0; AXES],
        })
    }

    /// Local socket address.
    pub fn local_addr(&self) -> Result<SocketAddr, LinkError> {
        self.ep.local_addr()
    }

    /// The limits the stream keeps (configured, tightened by the controller's tables).
    pub fn limits(&self) -> &StreamLimits {
        &self.limits
    }

    /// Whether the controller's threshold tables were read ([`Self::query_thresholds`]).
    pub fn thresholds_from_controller(&self) -> bool {
        self.thresholds_from_controller
    }

    /// Where the stream stands.
    pub fn phase(&self) -> StreamPhase {
        match self.phase {
            Phase::Idle => StreamPhase::Idle,
            Phase::Starting => StreamPhase::Starting,
            Phase::Approach { .. } => StreamPhase::Approach,
            Phase::Path { .. } => StreamPhase::Path,
            Phase::Settling => StreamPhase::Settling,
            Phase::Stopping => StreamPhase::Stopping,
            Phase::LastSent => StreamPhase::LastSent,
            Phase::Done => StreamPhase::Done,
        }
    }

    /// Why the stream stopped or is stopping, once it does.
    pub fn stop_reason(&self) -> Option<StopReason> {
        self.stop
    }

    /// The last commanded joints (rad).
    pub fn commanded_rad(&self) -> [f64; AXES] {
        self.limiter.position()
    }

    /// The largest step between two consecutive commands so far, per axis (rad).
    pub fn largest_step_rad(&self) -> [f64; AXES] {
        self.largest_step_rad
    }

    /// The trajectory streamed.
    pub fn trajectory(&self) -> &StreamTrajectory {
        &self.trajectory
    }

    /// Asks the controller for its velocity, acceleration and jerk tables of the first six axes
    /// (before the start; blocking, up to `wait` per table) and tightens the limits to
    /// [`FanucStreamConfig::threshold_margin`] of their tightest entries. Returns whether the
    /// controller answered every table; when it did not, the configured limits stay.
    pub fn query_thresholds(&mut self, wait: Duration) -> Result<bool, LinkError> {
        if self.phase != Phase::Idle {
            return Err(LinkError::InvalidValue {
                protocol: P,
                reason: "thresholds are read before the stream starts",
            });
        }
        let mut reported = self.cfg.limits;
        for axis in 1..=AXES as u32 {
            for kind in ThresholdKind::ALL {
                let request = ThresholdRequest {
                    version: self.version,
                    axis,
                    kind,
                };
                let n = format_threshold_request(&request, &mut self.tx[..])?;
                self.ep.send(&self.tx[..n])?;
                let Some(tightest) = self.await_table(axis, kind, wait)? else {
                    return Ok(false);
                };
                let value = tightest.to_radians() * self.cfg.threshold_margin;
                let i = axis as usize - 1;
                let slot = match kind {
                    ThresholdKind::Velocity => &mut reported.velocity[i],
                    ThresholdKind::Acceleration => &mut reported.acceleration[i],
                    ThresholdKind::Jerk => &mut reported.jerk[i],
                };
                *slot = slot.min(value);
            }
        }
        self.limits = reported;
        self.limiter = MotionLimiter::new(self.cfg.period_s, reported, self.trajectory.points()[0]);
        self.filter = CorrectionFilter::for_share(
            self.cfg.period_s,
            &reported,
            self.cfg.correction_share,
            self.cfg.max_correction_rad,
        );
        self.thresholds_from_controller = true;
        Ok(true)
    }

    fn await_table(
        &mut self,
        axis: u32,
        kind: ThresholdKind,
        wait: Duration,
    ) -> Result<Option<f64>, LinkError> {
        let deadline = Instant::now() + wait;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Ok(None);
            }
            let Some((n, from)) = self.ep.recv(&mut self.rx[..], left)? else {
                return Ok(None);
            };
            if !self.peers.policy().admits(from) {
                continue;
            }
            if packet_type(&self.rx[..n]).ok() != Some(TYPE_THRESHOLD) {
                continue;
            }
            if let Ok(t) = parse_threshold_table(&self.rx[..n])
                && t.axis == axis
                && t.kind == kind
            {
                return Ok(Some(t.tightest()));
            }
        }
    }

    fn streaming(&self) -> bool {
        matches!(
            self.phase,
            Phase::Approach { .. } | Phase::Path { .. } | Phase::Settling | Phase::Stopping
        )
    }

    /// Stops the stream for `reason` (the first reason is kept).
    fn begin_stop(&mut self, reason: StopReason) {
        if self.stop.is_none() {
            self.stop = Some(reason);
        }
        match self.phase {
            Phase::Idle | Phase::Starting => {
                // No command sent yet: the first answer is a hold and the last.
                self.phase = Phase::Stopping;
            }
            Phase::Approach { .. } | Phase::Path { .. } | Phase::Settling => {
                self.phase = Phase::Stopping;
            }
            Phase::Stopping | Phase::LastSent | Phase::Done => {}
        }
    }

    fn send_stop_packet(&mut self) -> Result<(), LinkError> {
        self.phase = Phase::Done;
        let n = format_stop(self.version, &mut self.tx[..])?;
        self.ep.send(&self.tx[..n])
    }

    /// The target of this cycle and whether it is the last command.
    fn next_command(&mut self, dq: &[f64; AXES]) -> ([f64; AXES], bool) {
        match self.phase {
            Phase::Idle | Phase::Starting => {
                // Unreachable in practice (the first answer sets the phase), hold.
                (self.limiter.brake(), false)
            }
            Phase::Approach { approach, k } => {
                let k = k + 1;
                self.phase = if k >= approach.cycles() {
                    Phase::Path { k: 0 }
                } else {
                    Phase::Approach { approach, k }
                };
                (self.limiter.step_towards(&approach.at(k)), false)
            }
            Phase::Path { k } => {
                let f = self.filter.step(dq);
                let points = self.trajectory.points();
                let p = points[k.min(points.len() - 1)];
                let target = std::array::from_fn(|i| p[i] + f[i]);
                self.phase = if k + 1 >= points.len() {
                    // The correction is frozen at its last value while the command settles.
                    self.settle_dq = *dq;
                    Phase::Settling
                } else {
                    Phase::Path { k: k + 1 }
                };
                (self.limiter.step_towards(&target), false)
            }
            Phase::Settling => {
                let f = self.filter.step(&self.settle_dq);
                let p = self.trajectory.points()[self.trajectory.len() - 1];
                let target: [f64; AXES] = std::array::from_fn(|i| p[i] + f[i]);
                let before = self.limiter.position();
                let q = self.limiter.step_towards(&target);
                let settled = (0..AXES).all(|i| {
                    (q[i] - self.settle_dq[i] - p[i]).abs() < 1e-7
                        && (q[i] - before[i]).abs() < 1e-6 * self.cfg.period_s
                });
                let last = settled;
                if last {
                    self.stop.get_or_insert(StopReason::Finished);
                }
                (q, last)
            }
            Phase::Stopping => {
                let q = self.limiter.brake();
                (q, self.limiter.at_rest())
            }
            Phase::LastSent | Phase::Done => (self.limiter.position(), true),
        }
    }

    /// At the first status: the limiter starts at the reported joints, the approach is planned
    /// (or refused when the robot stands too far from the path's start).
    fn begin_motion(&mut self, q: [f64; AXES]) {
        self.limiter = MotionLimiter::new(self.cfg.period_s, self.limits, q);
        let path_share = self.limits.scaled(1.0 - self.cfg.correction_share);
        if let Err(TrajectoryError::BeyondLimit {
            axis,
            what,
            needed,
            limit,
            ..
        }) = self.trajectory.check(&path_share)
        {
            self.begin_stop(StopReason::PathBeyondLimits {
                axis,
                what,
                needed,
                limit,
            });
            return;
        }
        let start = self.trajectory.points()[0];
        for i in 0..AXES {
            let d = (start[i] - q[i]).abs();
            if d > self.cfg.max_approach_rad {
                self.begin_stop(StopReason::StartTooFar {
                    axis: i + 1,
                    distance_rad: d,
                });
                return;
            }
        }
        self.phase = Phase::Approach {
            approach: Approach::new(q, start, self.cfg.period_s, &self.limits),
            k: 0,
        };
    }

    /// One datagram: from the controller (else refused, and the stream stops), a status
    /// packet, a new one (its sequence number advances).
    fn take_datagram(&mut self, n: usize, from: SocketAddr) -> Result<Status, LinkError> {
        if let Err(e) = self.peers.check(P, from) {
            if self.streaming() || self.phase == Phase::Starting {
                self.begin_stop(StopReason::ForeignStatus { from });
            }
            return Err(e);
        }
        let status = parse_status(&self.rx[..n])?;
        self.guard
            .admit(AXES, Some(u64::from(status.sequence)), None)
            .map_err(|reason| LinkError::Dropped {
                protocol: P,
                reason,
            })?;
        Ok(status)
    }

    /// Statuses superseded by a newer one waiting behind them (not answered).
    pub fn superseded(&self) -> u64 {
        self.superseded
    }

    fn answer(&mut self, dq_rad: &[f64]) -> Result<(), LinkError> {
        let status = self.last_status.ok_or(LinkError::NoPeer { protocol: P })?;
        if self.answered {
            return Err(LinkError::InvalidValue {
                protocol: P,
                reason: "this status packet was already answered",
            });
        }
        if matches!(self.phase, Phase::LastSent | Phase::Done) {
            return Ok(());
        }
        let mut dq = [0.0; AXES];
        let n = dq_rad.len().min(AXES);
        dq[..n].copy_from_slice(&dq_rad[..n]);
        if !dq.iter().all(|v| v.is_finite()) {
            dq = [0.0; AXES];
            self.begin_stop(StopReason::InvalidCorrection);
        }
        let bound = self.cfg.max_correction_rad;
        for v in &mut dq {
            *v = v.clamp(-bound, bound);
        }
        if self.phase == Phase::Starting {
            let q = std::array::from_fn(|i| f64::from(status.joints_deg[i]).to_radians());
            if !status.accepts_commands() {
                // Not ready yet (the TP program has not reached IBGN start): hold where the
                // robot stands until it is.
                self.limiter = MotionLimiter::new(self.cfg.period_s, self.limits, q);
                return self.send_command(status.sequence, q, false);
            }
            self.begin_motion(q);
        } else if self.phase == Phase::Stopping && self.answers == 0 {
            // Stopped before the first command: hold where the robot stands.
            let q = std::array::from_fn(|i| f64::from(status.joints_deg[i]).to_radians());
            self.limiter = MotionLimiter::new(self.cfg.period_s, self.limits, q);
        }
        let before = self.limiter.position();
        let (q, last) = self.next_command(&dq);
        for i in 0..AXES {
            self.largest_step_rad[i] = self.largest_step_rad[i].max((q[i] - before[i]).abs());
        }
        self.send_command(status.sequence, q, last)
    }

    /// Sends the command `q` (rad) answering status `sequence`.
    fn send_command(&mut self, sequence: u32, q: [f64; AXES], last: bool) -> Result<(), LinkError> {
        let mut joints_deg = [0.0; MAX_AXES];
        for i in 0..AXES {
            joints_deg[i] = q[i].to_degrees();
        }
        let command = Command {
            version: self.version,
            sequence,
            is_last: last,
            joints_deg,
        };
        let n = format_command(&command, &mut self.tx[..])?;
        self.ep.send(&self.tx[..n])?;
        self.answered = true;
        self.answers += 1;
        if last {
            self.phase = Phase::LastSent;
        }
        Ok(())
    }
}

impl RobotLink for FanucStreamLink {
    /// Sends the start packet on the first call (again every [`FanucStreamConfig::lost_after`]
    /// until the controller streams), then waits for the next status packet.
    fn receive(&mut self, timeout: Duration) -> Result<Option<RobotState>, LinkError> {
        let now = Instant::now();
        let resend = self
            .start_sent_at
            .is_none_or(|t| now.duration_since(t) > self.cfg.lost_after);
        if matches!(self.phase, Phase::Idle | Phase::Starting)
            && self.last_status.is_none()
            && resend
        {
            let n = format_start(self.version, &mut self.tx[..])?;
            self.ep.send(&self.tx[..n])?;
            self.start_sent_at = Some(now);
            self.phase = Phase::Starting;
        }
        let Some((n, from)) = self.ep.recv(&mut self.rx[..], timeout)? else {
            if let Some(at) = self.last_status_at {
                let silent = at.elapsed();
                let live = self.streaming() || self.phase == Phase::LastSent;
                if live && silent > self.cfg.lost_after {
                    self.begin_stop(StopReason::LostLink {
                        silent_s: silent.as_secs_f64(),
                    });
                    self.send_stop_packet()?;
                }
            }
            return Ok(None);
        };
        // The newest status waiting is the one answered: statuses queued behind a stall are
        // superseded (answering each would send commands back to back).
        let arrived = Instant::now();
        let mut latest = None;
        let mut first_error = None;
        let mut next = Some((n, from));
        while let Some((n, from)) = next {
            match self.take_datagram(n, from) {
                Ok(status) => {
                    if latest.is_some() {
                        self.superseded += 1;
                    }
                    latest = Some(status);
                }
                Err(e) => {
                    first_error.get_or_insert(e);
                }
            }
            next = self.ep.recv(&mut self.rx[..], Duration::ZERO)?;
        }
        let Some(status) = latest else {
            return Err(first_error.unwrap_or(LinkError::NoPeer { protocol: P }));
        };
        let now = arrived;
        if let Some(at) = self.last_status_at {
            let gap = now.duration_since(at);
            if self.streaming() && gap > self.cfg.late_after {
                self.begin_stop(StopReason::LateStatus {
                    gap_s: gap.as_secs_f64(),
                });
            }
        }
        if status.in_error() || (self.streaming() && !status.accepts_commands()) {
            self.begin_stop(StopReason::ControllerError {
                status: status.status,
                robot_status: status.robot_status,
            });
        }
        if self.phase == Phase::LastSent {
            self.send_stop_packet()?;
        }
        self.version = status.version;
        self.last_status = Some(status);
        self.last_status_at = Some(now);
        self.answered = false;
        let mut q = [0.0; AXES];
        for (o, v) in q.iter_mut().zip(&status.joints_deg) {
            *o = f64::from(*v).to_radians();
        }
        let mut state = RobotState::with_joints(&q);
        state.cycle_id = u64::from(status.sequence);
        state.robot_time_s = Some(f64::from(status.time_ms) * 1e-3);
        state.status = u32::from(status.status) | u32::from(status.robot_status) << 8;
        Ok(Some(state))
    }

    fn send_correction(&mut self, _correction: &Correction) -> Result<(), LinkError> {
        Err(LinkError::InvalidValue {
            protocol: P,
            reason: "Stream Motion answers joint targets (send_joint_correction)",
        })
    }

    fn answers_in_joint_space(&self) -> bool {
        true
    }

    /// Answers the last status with the next joint target: the path's point plus `dq_rad`
    /// (rad, axis 1 first), or the braking of a stop.
    fn send_joint_correction(&mut self, dq_rad: &[f64]) -> Result<(), LinkError> {
        self.answer(dq_rad)
    }

    fn protocol(&self) -> Protocol {
        P
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
}

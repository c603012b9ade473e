//! The telemetry stream of a session ([`deflex_telemetry`]): the control thread publishes one
//! [`CycleSample`] per cycle into a lossy broadcast ring, without waiting or allocating; any
//! number of sinks subscribe before or during the session (the CSV log of
//! `deflex_record::csv_log`, a live view, a recorder, a bridge) and read at their own pace, each counting what it lost.
//!
//! A [`Telemetry`] is made before the threads start, so a sink that subscribes to it then sees
//! every sample; [`crate::session::spawn`] hands its publisher to the control thread and the
//! ring and the [`SessionInfo`] stay reachable through [`crate::session::Runtime`].

pub use deflex_telemetry::{
    Broadcast, CycleSample, Publisher, SessionInfo, StreamSource, Subscriber, broadcast,
};

use deflex_control::Controller;
use std::sync::Arc;

/// Samples the ring holds by default: 82 s at 100 Hz.
pub const DEFAULT_CAPACITY: usize = 8192;

/// The telemetry of one session: the publisher the control thread will own, the ring sinks
/// subscribe to, and the session's description.
#[derive(Debug)]
pub struct Telemetry {
    publisher: Publisher<CycleSample>,
    ring: Arc<Broadcast<CycleSample>>,
    info: Arc<SessionInfo>,
}

impl Telemetry {
    /// A ring of `capacity` samples (at least 2) for the session `info`. Allocates here, once.
    pub fn new(info: SessionInfo, capacity: usize) -> Self {
        let (publisher, ring) = broadcast::<CycleSample>(capacity);
        Telemetry {
            publisher,
            ring,
            info: Arc::new(info),
        }
    }

    /// The ring, to subscribe to now or later.
    pub fn ring(&self) -> &Arc<Broadcast<CycleSample>> {
        &self.ring
    }

    /// A subscriber that will read every sample published from now on.
    pub fn subscribe(&self) -> Subscriber<CycleSample> {
        self.ring.subscribe()
    }

    /// The session's description.
    pub fn info(&self) -> &Arc<SessionInfo> {
        &self.info
    }

    /// The parts: the publisher, the ring and the description.
    pub fn into_parts(
        self,
    ) -> (
        Publisher<CycleSample>,
        Arc<Broadcast<CycleSample>>,
        Arc<SessionInfo>,
    ) {
        (self.publisher, self.ring, self.info)
    }
}

/// The description of a session of `controller` (its model, rates and limits) whose robot speaks
/// `protocol` with an interpolation cycle of `robot_cycle_s`.
pub fn session_info(
    controller: &Controller,
    source: StreamSource,
    protocol: &str,
    robot_cycle_s: f64,
) -> SessionInfo {
    let robot = controller.robot();
    let config = controller.config();
    let mut info = SessionInfo::new(
        source,
        robot.name.clone(),
        robot.joints.iter().map(|j| j.name.clone()).collect(),
    );
    info.protocol = protocol.to_string();
    info.control_period_s = config.period_s;
    info.robot_cycle_s = robot_cycle_s;
    info.correction_limit = config.limiter.max_abs;
    info.correction_rate_limit = config.limiter.max_rate;
    info.force_limit_n = config.safety.max_force_n;
    info
}

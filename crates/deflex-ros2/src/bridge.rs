//! [`Ros2Bridge`]: the telemetry stream on the ROS 2 graph. A thread of its own drains a
//! telemetry [`Subscriber`] (it never slows the control thread: a bridge that falls behind
//! loses samples and counts them) and publishes, for each cycle due at `publish_rate_hz` of
//! session time, the messages of [`deflex_telemetry::ros::cycle::CycleMessages`] on the enabled topics,
//! and the diagnostics at `diagnostics_rate_hz` and on every change of phase, flags or fault.

use crate::{BridgeSettings, Ros2Error, join, message_type, qos_profile, ros_name, topic_name};
use deflex_telemetry::ros::Ros2Topic;
use deflex_telemetry::ros::cycle::{CycleMessages, DiagnosticsPacer, diagnostics, seconds_to_ns};
use deflex_telemetry::ros::{
    DiagnosticArrayMsg, JointStateMsg, PoseStampedMsg, RosMessage, TimeMsg, TwistStampedMsg,
    Vector3StampedMsg, WrenchStampedMsg,
};
use deflex_telemetry::{CycleSample, SessionInfo, Subscriber};
use ros2_client::{Node, Publisher};
use serde::Serialize;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;
use std::time::Duration;

/// How often the bridge thread looks for new samples when it has caught up.
pub const POLL: Duration = Duration::from_millis(2);

/// Key of the diagnostics value: samples the bridge lost (overwritten in the telemetry ring
/// before it read them).
pub const BRIDGE_LOST: &str = "bridge_lost";

/// What a bridge did (also readable while it runs, [`Ros2Bridge::report`]).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct BridgeReport {
    /// Cycles read from the telemetry stream.
    pub cycles_read: u64,
    /// Cycles published (due at the publishing rate).
    pub cycles_published: u64,
    /// Diagnostics messages published.
    pub diagnostics: u64,
    /// Messages published, all topics.
    pub messages: u64,
    /// Writes the DDS refused (a reliable reader's full window, a closed participant).
    pub write_errors: u64,
    /// Samples lost: overwritten in the telemetry ring before the bridge read them.
    pub lost: u64,
}

#[derive(Debug, Default)]
struct Counters {
    cycles_read: AtomicU64,
    cycles_published: AtomicU64,
    diagnostics: AtomicU64,
    messages: AtomicU64,
    write_errors: AtomicU64,
    lost: AtomicU64,
}

impl Counters {
    fn report(&self) -> BridgeReport {
        let get = |c: &AtomicU64| c.load(Ordering::Relaxed);
        BridgeReport {
            cycles_read: get(&self.cycles_read),
            cycles_published: get(&self.cycles_published),
            diagnostics: get(&self.diagnostics),
            messages: get(&self.messages),
            write_errors: get(&self.write_errors),
            lost: get(&self.lost),
        }
    }
}

/// The bridge's thread. Dropping it (or [`Ros2Bridge::finish`]) publishes what was published
/// before, then leaves the graph.
pub struct Ros2Bridge {
    stop: Arc<AtomicBool>,
    counters: Arc<Counters>,
    handle: Option<JoinHandle<()>>,
    topics: Vec<String>,
}

/// One publisher per enabled topic.
struct Publishers {
    joint_states: Option<Publisher<JointStateMsg>>,
    wrench_raw: Option<Publisher<WrenchStampedMsg>>,
    wrench_sensor: Option<Publisher<WrenchStampedMsg>>,
    wrench_tcp: Option<Publisher<WrenchStampedMsg>>,
    tcp_pose: Option<Publisher<PoseStampedMsg>>,
    program_pose: Option<Publisher<PoseStampedMsg>>,
    deflection: Option<Publisher<TwistStampedMsg>>,
    correction: Option<Publisher<TwistStampedMsg>>,
    error: Option<Publisher<TwistStampedMsg>>,
    feedforward: Option<Publisher<TwistStampedMsg>>,
    path_error: Option<Publisher<Vector3StampedMsg>>,
    diagnostics: Option<Publisher<DiagnosticArrayMsg>>,
}

fn publisher<T: RosMessage>(
    node: &mut Node,
    settings: &BridgeSettings,
    topic: Ros2Topic,
) -> Result<Option<Publisher<T>>, Ros2Error> {
    if !settings.topics.contains(&topic) {
        return Ok(None);
    }
    let full = topic_name(&settings.namespace, topic.name());
    let qos = qos_profile(settings.qos, settings.depth);
    let error = |e: String| Ros2Error::Topic {
        topic: full.clone(),
        message: e,
    };
    let t = node
        .create_topic(&ros_name(&full)?, message_type::<T>(), &qos)
        .map_err(|e| error(format!("{e:?}")))?;
    node.create_publisher(&t, Some(qos))
        .map(Some)
        .map_err(|e| error(format!("{e:?}")))
}

impl Publishers {
    fn new(node: &mut Node, s: &BridgeSettings) -> Result<Publishers, Ros2Error> {
        use Ros2Topic as T;
        Ok(Publishers {
            joint_states: publisher(node, s, T::JointStates)?,
            wrench_raw: publisher(node, s, T::WrenchRaw)?,
            wrench_sensor: publisher(node, s, T::WrenchSensor)?,
            wrench_tcp: publisher(node, s, T::WrenchTcp)?,
            tcp_pose: publisher(node, s, T::TcpPose)?,
            program_pose: publisher(node, s, T::ProgramPose)?,
            deflection: publisher(node, s, T::Deflection)?,
            correction: publisher(node, s, T::Correction)?,
            error: publisher(node, s, T::Error)?,
            feedforward: publisher(node, s, T::Feedforward)?,
            path_error: publisher(node, s, T::PathError)?,
            diagnostics: publisher(node, s, T::Diagnostics)?,
        })
    }
}

fn put<T: Serialize>(p: &Option<Publisher<T>>, msg: T, counters: &Counters) {
    if let Some(p) = p {
        let counter = match p.publish(msg) {
            Ok(()) => &counters.messages,
            Err(_) => &counters.write_errors,
        };
        counter.fetch_add(1, Ordering::Relaxed);
    }
}

/// The thread's state.
struct Publishing {
    publishers: Publishers,
    info: Arc<SessionInfo>,
    period_s: f64,
    /// Half a control period (s): the tolerance of the publishing grid.
    half_cycle_s: f64,
    /// Session time at which the next cycle is due (s).
    next_due_s: f64,
    pacer: DiagnosticsPacer,
    epoch_ns: Option<u64>,
    counters: Arc<Counters>,
}

fn unix_now_ns() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos().min(u128::from(u64::MAX)) as u64)
}

impl Publishing {
    /// The ROS time of session time `t_s`: the epoch of session time 0 (fixed at the first
    /// sample) plus `t_s`.
    fn stamp(&mut self, t_s: f64) -> TimeMsg {
        let epoch = *self
            .epoch_ns
            .get_or_insert_with(|| unix_now_ns().saturating_sub(seconds_to_ns(t_s)));
        TimeMsg::from_nanos(epoch.saturating_add(seconds_to_ns(t_s)))
    }

    fn cycle(&mut self, s: &CycleSample, lost: u64) {
        self.counters.cycles_read.fetch_add(1, Ordering::Relaxed);
        let stamp = self.stamp(s.time_s);
        let c = &self.counters;
        if self.pacer.due(s) && self.publishers.diagnostics.is_some() {
            let extra = [(BRIDGE_LOST, lost.to_string())];
            put(
                &self.publishers.diagnostics,
                diagnostics(&self.info, s, stamp, &extra),
                c,
            );
            c.diagnostics.fetch_add(1, Ordering::Relaxed);
        }
        // On a grid of session time: the first cycle at or past each grid point (within half a
        // control period, the cycles' own jitter) is due, so the average rate is the configured
        // one whatever the cycles' jitter; after a gap (or time going back) the grid restarts at
        // the cycle, never sending a burst.
        if s.time_s + self.half_cycle_s < self.next_due_s
            && s.time_s + self.period_s >= self.next_due_s
        {
            return;
        }
        self.next_due_s += self.period_s;
        if self.next_due_s <= s.time_s || self.next_due_s > s.time_s + 2.0 * self.period_s {
            self.next_due_s = s.time_s + self.period_s;
        }
        let p = &self.publishers;
        let m = CycleMessages::new(&self.info, s, stamp);
        put(&p.joint_states, m.joint_states, c);
        put(&p.wrench_raw, m.wrench_raw, c);
        put(&p.wrench_sensor, m.wrench_sensor, c);
        put(&p.wrench_tcp, m.wrench_tcp, c);
        put(&p.tcp_pose, m.tcp_pose, c);
        put(&p.program_pose, m.program_pose, c);
        put(&p.deflection, m.deflection, c);
        put(&p.correction, m.correction, c);
        put(&p.error, m.error, c);
        put(&p.feedforward, m.feedforward, c);
        if let Some(v) = m.path_error {
            put(&p.path_error, v, c);
        }
        c.cycles_published.fetch_add(1, Ordering::Relaxed);
    }
}

impl Ros2Bridge {
    /// Joins the graph with `settings` and publishes the samples of `subscriber` (a session
    /// described by `info`) until the stream ends or [`Ros2Bridge::finish`]. Returns once the
    /// node and its publishers exist (errors name the domain, node or topic).
    pub fn spawn(
        settings: &BridgeSettings,
        mut subscriber: Subscriber<CycleSample>,
        info: Arc<SessionInfo>,
    ) -> Result<Ros2Bridge, Ros2Error> {
        let stop = Arc::new(AtomicBool::new(false));
        let counters = Arc::new(Counters::default());
        let (ready_tx, ready_rx) = std::sync::mpsc::sync_channel(1);
        let thread_settings = settings.clone();
        let (thread_stop, thread_counters) = (stop.clone(), counters.clone());
        let handle = std::thread::Builder::new()
            .name("deflex-ros2".into())
            .spawn(move || {
                crate::lower_priority();
                let s = &thread_settings;
                let joined = join(s.domain_id, &s.namespace, &s.node_name).and_then(|mut node| {
                    let publishers = Publishers::new(&mut node, s)?;
                    Ok((node, publishers))
                });
                let (_node, publishers) = match joined {
                    Ok(x) => {
                        let _ = ready_tx.send(Ok(()));
                        x
                    }
                    Err(e) => {
                        let _ = ready_tx.send(Err(e));
                        return;
                    }
                };
                let mut publishing = Publishing {
                    publishers,
                    half_cycle_s: 0.5 * info.control_period_s,
                    info,
                    period_s: 1.0 / s.publish_rate_hz,
                    next_due_s: f64::NEG_INFINITY,
                    pacer: DiagnosticsPacer::new(1.0 / s.diagnostics_rate_hz),
                    epoch_ns: None,
                    counters: thread_counters,
                };
                loop {
                    // Read the flag before draining: what was published before `finish` set it
                    // is drained below.
                    let stopping = thread_stop.load(Ordering::Acquire);
                    while let Some(sample) = subscriber.try_next() {
                        publishing.cycle(&sample, subscriber.lost());
                    }
                    publishing
                        .counters
                        .lost
                        .store(subscriber.lost(), Ordering::Relaxed);
                    if stopping || subscriber.is_finished() {
                        break;
                    }
                    std::thread::sleep(POLL);
                }
            })
            .map_err(|e| Ros2Error::Thread {
                what: "starting the bridge thread",
                message: e.to_string(),
            })?;
        match ready_rx.recv() {
            Ok(Ok(())) => {}
            Ok(Err(e)) => {
                let _ = handle.join();
                return Err(e);
            }
            Err(_) => {
                let _ = handle.join();
                return Err(Ros2Error::Thread {
                    what: "the bridge thread",
                    message: "ended before joining the graph (panicked)".into(),
                });
            }
        }
        Ok(Ros2Bridge {
            stop,
            counters,
            handle: Some(handle),
            topics: settings
                .topics
                .iter()
                .map(|t| topic_name(&settings.namespace, t.name()))
                .collect(),
        })
    }

    /// The ROS names of the topics published.
    pub fn topics(&self) -> &[String] {
        &self.topics
    }

    /// What the bridge did so far.
    pub fn report(&self) -> BridgeReport {
        self.counters.report()
    }

    /// Publishes what was published on the stream up to now, then leaves the graph.
    pub fn finish(mut self) -> Result<BridgeReport, Ros2Error> {
        self.stop.store(true, Ordering::Release);
        let joined = self.handle.take().map(JoinHandle::join);
        match joined {
            Some(Err(_)) => Err(Ros2Error::Thread {
                what: "the bridge thread",
                message: "panicked".into(),
            }),
            _ => Ok(self.counters.report()),
        }
    }
}

impl Drop for Ros2Bridge {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}

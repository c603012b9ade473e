//! [`Ros2SensorLink`]: `[sensor] kind = "ros2"`, the wrench of any ROS 2 F/T driver as a
//! [`ForceSensorLink`].
//!
//! A DDS reader thread of its own takes the `geometry_msgs/WrenchStamped` messages of
//! `sensor.topic` and checks each one ([`Refusal`]): it must decode, carry six finite values,
//! the frame id `ros2.sensor_frame`, a stamp within `sensor.max_age_s` of this machine's clock
//! (in the past or the future) and not older than the last accepted one, and come from the
//! session's writer. Accepted readings go
//! into a bounded [`Handover`] queue of `sensor.queue_depth` (the oldest dropped and counted
//! when full); the runtime's sensor thread pops them in [`ForceSensorLink::receive`] as it reads
//! a Net F/T socket.
//!
//! Bounds: the subscription's history keeps the last `queue_depth` messages (a flood overwrites
//! its own backlog inside the DDS reader); the reader thread wakes every [`POLL`] and takes at
//! most `4 × queue_depth` messages per wake, so a flood costs it a bounded amount of work per
//! millisecond and never reaches the control thread, which only ever reads the runtime's own
//! wrench cell. A sample's size is bounded by the DDS transport (a UDP datagram, 64 KiB, unless
//! fragmented) and its frame id is compared, never kept.
//!
//! **One writer per session**, as every link of the runtime locks to its first valid peer
//! ([`deflex_io::PeerPolicy`], `robot.allow_any_peer`): the DDS writer (its GID) of the first
//! accepted message is the sensor for the rest of the session; messages of any other writer on
//! the topic are refused and counted ([`Refusal::OtherWriter`]), so a second driver, a replayed
//! bag or a stray `ros2 topic pub` cannot mix its wrench into the loop. Which hosts may join
//! the DDS domain is the DDS domain's business (`ros2.domain_id`, the network): the link does
//! not filter by address.
//!
//! The driver's bias and the tool's weight are removed by deflex (the tare at start and the tool
//! gravity of `[mounting]`): publish the raw reading, not a zeroed one. [`ForceSensorLink::bias`]
//! does nothing (ROS 2 has no standard bias request), start and stop neither.

use crate::handover::Handover;
use crate::{Ros2Error, SensorSettings, join, message_type, qos_profile, ros_name};
use deflex_io::{ForceSensorLink, LinkError, Protocol, WrenchSample};
use deflex_model::Wrench;
use deflex_telemetry::ros::WrenchStampedMsg;
use ros2_client::Gid;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

/// How often the reader thread takes what the DDS reader holds.
pub const POLL: Duration = Duration::from_millis(1);

/// Why a message was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Refusal {
    /// Not a CDR `WrenchStamped` (truncated, bad encapsulation, bad length).
    Malformed,
    /// A force or torque that is NaN or infinite, or a stamp with `nanosec` ≥ 10⁹.
    NonFinite,
    /// Another `header.frame_id` than `ros2.sensor_frame`.
    WrongFrame,
    /// A stamp older than `sensor.max_age_s` on this machine's clock.
    Stale,
    /// A stamp more than `sensor.max_age_s` ahead of this machine's clock.
    Future,
    /// A stamp older than the last accepted one.
    OutOfOrder,
    /// Another DDS writer than the one the link locked to (the writer of the first accepted
    /// message).
    OtherWriter,
}

/// Number of [`Refusal`] reasons.
pub const REFUSALS: usize = Refusal::ALL.len();

impl Refusal {
    /// Every reason, in counter order.
    pub const ALL: [Refusal; 7] = [
        Refusal::Malformed,
        Refusal::NonFinite,
        Refusal::WrongFrame,
        Refusal::Stale,
        Refusal::Future,
        Refusal::OutOfOrder,
        Refusal::OtherWriter,
    ];

    /// Snake-case name (summaries, JSON).
    pub fn name(self) -> &'static str {
        match self {
            Refusal::Malformed => "malformed",
            Refusal::NonFinite => "non_finite",
            Refusal::WrongFrame => "wrong_frame",
            Refusal::Stale => "stale",
            Refusal::Future => "future",
            Refusal::OutOfOrder => "out_of_order",
            Refusal::OtherWriter => "other_writer",
        }
    }

    /// What the runtime's sensor thread is told (its count of sensor errors).
    fn reason(self) -> &'static str {
        match self {
            Refusal::Malformed => "refused a WrenchStamped that does not decode",
            Refusal::NonFinite => "refused a WrenchStamped with a non-finite value or stamp",
            Refusal::WrongFrame => {
                "refused a WrenchStamped in another frame than ros2.sensor_frame"
            }
            Refusal::Stale => "refused a WrenchStamped older than sensor.max_age_s",
            Refusal::Future => {
                "refused a WrenchStamped stamped ahead by more than sensor.max_age_s"
            }
            Refusal::OutOfOrder => "refused a WrenchStamped older than the previous one",
            Refusal::OtherWriter => {
                "refused a WrenchStamped from another writer than the session's sensor"
            }
        }
    }
}

/// What the link received, accepted and refused so far.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SensorCounts {
    /// Messages taken from the DDS reader.
    pub received: u64,
    /// Messages accepted.
    pub accepted: u64,
    /// Refused, by [`Refusal`] (in [`Refusal::ALL`] order).
    pub refused: [u64; REFUSALS],
    /// Accepted readings dropped because the handover queue was full (the sensor thread did
    /// not keep up).
    pub overflow: u64,
}

impl SensorCounts {
    /// Refused for `reason`.
    pub fn refused_for(&self, reason: Refusal) -> u64 {
        self.refused[reason as usize]
    }

    /// Refused, all reasons.
    pub fn refused_total(&self) -> u64 {
        self.refused.iter().sum()
    }
}

#[derive(Debug, Default)]
struct Counters {
    received: AtomicU64,
    accepted: AtomicU64,
    refused: [AtomicU64; REFUSALS],
}

/// One accepted reading.
#[derive(Clone, Copy, Debug)]
struct Reading {
    wrench: Wrench,
}

/// The checks of one message against the settings and the last accepted stamp.
#[derive(Debug)]
struct Checker {
    frame_id: String,
    max_age_ns: i128,
    last_stamp_ns: Option<i128>,
    /// The writer the link locked to (the writer of the first accepted message).
    writer: Option<Gid>,
}

impl Checker {
    fn check(
        &mut self,
        msg: &WrenchStampedMsg,
        writer: Gid,
        now_ns: i128,
    ) -> Result<Reading, Refusal> {
        if self.writer.is_some_and(|w| w != writer) {
            return Err(Refusal::OtherWriter);
        }
        let w = &msg.wrench;
        let wrench = Wrench::new(
            w.force.x, w.force.y, w.force.z, w.torque.x, w.torque.y, w.torque.z,
        );
        let stamp = msg.header.stamp;
        if !wrench.iter().all(|v| v.is_finite()) || stamp.nanosec >= 1_000_000_000 {
            return Err(Refusal::NonFinite);
        }
        if msg.header.frame_id != self.frame_id {
            return Err(Refusal::WrongFrame);
        }
        let stamp_ns = i128::from(stamp.sec) * 1_000_000_000 + i128::from(stamp.nanosec);
        let age = now_ns - stamp_ns;
        if age > self.max_age_ns {
            return Err(Refusal::Stale);
        }
        if -age > self.max_age_ns {
            return Err(Refusal::Future);
        }
        if self.last_stamp_ns.is_some_and(|last| stamp_ns < last) {
            return Err(Refusal::OutOfOrder);
        }
        self.last_stamp_ns = Some(stamp_ns);
        self.writer = Some(writer);
        Ok(Reading { wrench })
    }
}

fn unix_now_ns() -> i128 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as i128)
}

/// The ROS 2 F/T sensor link (see the module documentation).
pub struct Ros2SensorLink {
    queue: Arc<Handover<Reading>>,
    counters: Arc<Counters>,
    stop: Arc<AtomicBool>,
    handle: Option<JoinHandle<()>>,
    /// Refusals already reported to the runtime, by reason.
    reported: [u64; REFUSALS],
    dropped_reported: u64,
    sequence: u32,
    topic: String,
}

/// A cheap handle on a link's counters, readable after the link moved into the runtime.
#[derive(Clone, Debug)]
pub struct SensorCountsHandle {
    counters: Arc<Counters>,
    queue: Arc<Handover<Reading>>,
}

impl SensorCountsHandle {
    /// The counts now.
    pub fn counts(&self) -> SensorCounts {
        let get = |c: &AtomicU64| c.load(Ordering::Relaxed);
        SensorCounts {
            received: get(&self.counters.received),
            accepted: get(&self.counters.accepted),
            refused: std::array::from_fn(|i| get(&self.counters.refused[i])),
            overflow: self.queue.dropped(),
        }
    }
}

impl Ros2SensorLink {
    /// Joins the graph with `settings` and subscribes to the wrench topic; the reader thread
    /// runs until the link is dropped. Returns once the subscription exists.
    pub fn open(settings: &SensorSettings) -> Result<Ros2SensorLink, Ros2Error> {
        let queue = Arc::new(Handover::new(settings.queue_depth));
        let counters = Arc::new(Counters::default());
        let stop = Arc::new(AtomicBool::new(false));
        let (ready_tx, ready_rx) = std::sync::mpsc::sync_channel(1);
        let s = settings.clone();
        let (q, c, st) = (queue.clone(), counters.clone(), stop.clone());
        let handle = std::thread::Builder::new()
            .name("deflex-ros2-ft".into())
            .spawn(move || {
                // Not lowered (unlike the bridge): this thread and the DDS threads it starts
                // are the sensor's path, and a starved sensor times the loop out. Its work per
                // wake is bounded (see the module documentation).
                let subscribed =
                    join(s.domain_id, &s.namespace, &s.node_name).and_then(|mut node| {
                        let error = |e: String| Ros2Error::Topic {
                            topic: s.topic.clone(),
                            message: e,
                        };
                        let qos = qos_profile(s.qos, s.queue_depth);
                        let topic = node
                            .create_topic(
                                &ros_name(&s.topic)?,
                                message_type::<WrenchStampedMsg>(),
                                &qos,
                            )
                            .map_err(|e| error(format!("{e:?}")))?;
                        let sub = node
                            .create_subscription::<WrenchStampedMsg>(&topic, Some(qos))
                            .map_err(|e| error(format!("{e:?}")))?;
                        Ok((node, sub))
                    });
                let (_node, sub) = match subscribed {
                    Ok(x) => {
                        let _ = ready_tx.send(Ok(()));
                        x
                    }
                    Err(e) => {
                        let _ = ready_tx.send(Err(e));
                        return;
                    }
                };
                let mut checker = Checker {
                    frame_id: s.frame_id.clone(),
                    max_age_ns: s.max_age.as_nanos() as i128,
                    last_stamp_ns: None,
                    writer: None,
                };
                let per_wake = 4 * s.queue_depth.max(1);
                while !st.load(Ordering::Acquire) {
                    for _ in 0..per_wake {
                        let taken = match sub.take() {
                            Ok(Some((msg, info))) => Ok((msg, info.publisher_gid())),
                            Ok(None) => break,
                            Err(_) => Err(Refusal::Malformed),
                        };
                        c.received.fetch_add(1, Ordering::Relaxed);
                        let checked = taken
                            .and_then(|(msg, writer)| checker.check(&msg, writer, unix_now_ns()));
                        match checked {
                            Ok(reading) => {
                                c.accepted.fetch_add(1, Ordering::Relaxed);
                                q.push(reading);
                            }
                            Err(reason) => {
                                c.refused[reason as usize].fetch_add(1, Ordering::Relaxed);
                            }
                        }
                    }
                    std::thread::sleep(POLL);
                }
                q.close();
            })
            .map_err(|e| Ros2Error::Thread {
                what: "starting the ROS 2 sensor reader",
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
                    what: "the ROS 2 sensor reader",
                    message: "ended before subscribing (panicked)".into(),
                });
            }
        }
        Ok(Ros2SensorLink {
            queue,
            counters,
            stop,
            handle: Some(handle),
            reported: [0; REFUSALS],
            dropped_reported: 0,
            sequence: 0,
            topic: settings.topic.clone(),
        })
    }

    /// The topic subscribed to.
    pub fn topic(&self) -> &str {
        &self.topic
    }

    /// A handle on the counters, readable after the link moved into the runtime.
    pub fn counts_handle(&self) -> SensorCountsHandle {
        SensorCountsHandle {
            counters: self.counters.clone(),
            queue: self.queue.clone(),
        }
    }

    /// The counts now.
    pub fn counts(&self) -> SensorCounts {
        self.counts_handle().counts()
    }

    /// A refusal not yet reported to the runtime, counting it as reported.
    fn next_unreported(&mut self) -> Option<Refusal> {
        Refusal::ALL.into_iter().find(|r| {
            let i = *r as usize;
            let total = self.counters.refused[i].load(Ordering::Relaxed);
            let pending = total > self.reported[i];
            if pending {
                self.reported[i] += 1;
            }
            pending
        })
    }
}

impl ForceSensorLink for Ros2SensorLink {
    fn start(&mut self) -> Result<(), LinkError> {
        Ok(())
    }

    fn bias(&mut self) -> Result<(), LinkError> {
        Ok(())
    }

    /// The oldest accepted reading waiting; readings come first, then each refused message is
    /// reported once as a [`LinkError::Malformed`] (so the runtime's count of sensor errors is
    /// the count of refused messages); `gap` counts the readings dropped from the full queue
    /// since the previous one.
    fn receive(&mut self, timeout: Duration) -> Result<Option<WrenchSample>, LinkError> {
        let reading = match self.queue.pop(Duration::ZERO) {
            Some(r) => Some(r),
            None => {
                if let Some(refusal) = self.next_unreported() {
                    return Err(LinkError::Malformed {
                        protocol: Protocol::Ros2,
                        reason: refusal.reason(),
                    });
                }
                self.queue.pop(timeout)
            }
        };
        let Some(reading) = reading else {
            return Ok(None);
        };
        self.sequence = self.sequence.wrapping_add(1);
        let dropped = self.queue.dropped();
        let gap = dropped - self.dropped_reported;
        self.dropped_reported = dropped;
        Ok(Some(WrenchSample {
            wrench: reading.wrench,
            sequence: self.sequence,
            status: 0,
            gap: gap.min(u64::from(u32::MAX)) as u32,
        }))
    }

    fn stop(&mut self) -> Result<(), LinkError> {
        Ok(())
    }
}

impl Drop for Ros2SensorLink {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}

//! The robot-link thread: answers every telegram at once with the latest correction command,
//! shaped per answer ([`SendShaper`]), and publishes the telegram's joint values.

use super::{DRAIN_S, ExitGuard, RuntimeOptions, Shared};
use crate::clock::Clock;
use crate::messages::{JointSample, LATE_UNKNOWN};
use crate::rt::try_realtime;
use crate::send_shaper::{LinkDirective, SendShaper, SendShaperConfig};
use crate::stats::CycleStats;
use deflex_io::{Correction, LinkCounters, LinkError, RobotLink, RobotState};
use deflex_model::MAX_JOINTS;
use nalgebra::Vector6;
use std::sync::PoisonError;
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

/// What the robot-link thread reports at its end.
pub(super) struct RobotReport {
    pub(super) latency: CycleStats,
    pub(super) warnings: Vec<String>,
    pub(super) max_step: [f64; 6],
    pub(super) counters: LinkCounters,
}

/// The thread's state between telegrams.
struct Answering {
    shaper: SendShaper,
    latency: CycleStats,
    deadline: Duration,
    max_step: [f64; 6],
}

impl Answering {
    /// Publishes the telegram's joints, then answers it with the shaped correction (allocation
    /// free).
    fn answer<C: Clock>(
        &mut self,
        link: &mut dyn RobotLink,
        state: &RobotState,
        shared: &Shared,
        clock: &C,
    ) {
        let received = Instant::now();
        let joints = JointSample {
            q_rad: state.q_rad,
            time_s: clock.now(),
            joint_count: state.joint_count.min(MAX_JOINTS) as u64,
            robot_late: state.late_answers.map_or(LATE_UNKNOWN, u64::from),
            tcp_pose: state.tcp_pose.unwrap_or_default(),
            tcp_pose_known: u64::from(state.tcp_pose.is_some()),
        };
        shared.joints.write(&joints);
        shared
            .last_telegram_s
            .store(joints.time_s.to_bits(), Ordering::Release);
        if let Some(late) = state.late_answers {
            shared.note_robot_late(u64::from(late));
        }
        let (command, _) = shared.command.read();
        let directive = if shared.control_failed.load(Ordering::Acquire) {
            LinkDirective::RampOut
        } else {
            command.directive()
        };
        let before = self.shaper.last();
        let sent = self.shaper.next(&command.xi.into(), directive);
        let result = if link.answers_in_joint_space() {
            let dq = command.joint_map * Vector6::from(sent);
            let n = joints.q().len().max(1);
            link.send_joint_correction(&dq.as_slice()[..n])
        } else {
            link.set_tcp_rotation(&command.tcp_rotation);
            link.send_correction(&Correction::from_array(sent))
        };
        match result {
            Ok(()) => {
                let latency = received.elapsed();
                self.latency.record(latency);
                if latency > self.deadline {
                    shared.late_answers.fetch_add(1, Ordering::Relaxed);
                }
                shared.telegrams.fetch_add(1, Ordering::Relaxed);
                for i in 0..6 {
                    self.max_step[i] = self.max_step[i].max((sent[i] - before[i]).abs());
                }
            }
            Err(_) => {
                shared.robot_errors.fetch_add(1, Ordering::Relaxed);
            }
        }
    }
}

/// Counts a receive that brought no telegram.
fn count_failed_receive(result: Result<(), LinkError>, shared: &Shared) {
    match result {
        Ok(()) => {
            shared.robot_timeouts.fetch_add(1, Ordering::Relaxed);
        }
        Err(e) if e.is_foreign() => {
            // A host other than the robot, or a second connection while the robot holds the
            // session: refused unanswered. A refusal while the connection holding the session
            // serves no robot lines means the robot itself may be locked out: the session
            // ends as faulted.
            shared.robot_foreign.fetch_add(1, Ordering::Relaxed);
            if e.is_starving() {
                shared.robot_starved.store(true, Ordering::Relaxed);
            }
            if let Some(from) = e.foreign_source() {
                *shared
                    .last_foreign
                    .lock()
                    .unwrap_or_else(PoisonError::into_inner) = Some(from);
            }
        }
        Err(e) if e.is_dropped() => {
            // From the robot, but not a new state (replay, joint count, time going back).
            shared.robot_dropped.fetch_add(1, Ordering::Relaxed);
        }
        Err(e) if e.is_bad_packet() => {
            shared.robot_bad_packets.fetch_add(1, Ordering::Relaxed);
        }
        Err(_) => {
            shared.robot_errors.fetch_add(1, Ordering::Relaxed);
            std::thread::sleep(Duration::from_millis(1));
        }
    }
}

pub(super) fn robot_loop<C: Clock>(
    mut link: Box<dyn RobotLink + Send>,
    shared: &Shared,
    clock: &C,
    shaper: SendShaperConfig,
    options: RuntimeOptions,
) -> RobotReport {
    let _guard = ExitGuard {
        shared,
        control: false,
        release: None,
    };
    let warnings = if options.realtime {
        try_realtime(80, false).warnings()
    } else {
        Vec::new()
    };
    let deadline = Duration::from_secs_f64(options.robot_cycle_s.clamp(1e-6, 10.0));
    let mut answering = Answering {
        shaper: SendShaper::new(shaper),
        latency: CycleStats::new(deadline),
        deadline,
        max_step: [0.0; 6],
    };
    let mut ended_at: Option<Instant> = None;
    loop {
        if shared.done.load(Ordering::Acquire) {
            // The control thread has ended: keep answering until what was sent is zero
            // (bounded), ramping it out in robot cycles if the control thread failed; unless
            // the robot has been silent past the idle exit (its program ended: nobody would
            // hear the drain).
            let since = *ended_at.get_or_insert_with(Instant::now);
            let last_telegram_s = f64::from_bits(shared.last_telegram_s.load(Ordering::Acquire));
            let robot_gone = options
                .idle_exit_s
                .is_some_and(|idle_s| clock.now() - last_telegram_s > idle_s);
            if answering.shaper.is_zero() || robot_gone || since.elapsed().as_secs_f64() > DRAIN_S {
                break;
            }
        }
        match link.receive(Duration::from_millis(10)) {
            Ok(Some(state)) => answering.answer(link.as_mut(), &state, shared, clock),
            Ok(None) => count_failed_receive(Ok(()), shared),
            Err(e) => count_failed_receive(Err(e), shared),
        }
    }
    RobotReport {
        latency: answering.latency,
        warnings,
        max_step: answering.max_step,
        counters: link.counters(),
    }
}

//! Session rules every robot message must pass after its sender was accepted, and the counters
//! a link exposes to its caller.
//!
//! A message from the locked robot is still dropped, unanswered, when it cannot be this
//! session's next cycle ([`SessionGuard::admit`]):
//!
//! * its **joint count** differs from the session's (the count of the first accepted message):
//!   [`DropReason::JointCount`];
//! * its **sequence number does not advance** over the last accepted one (a duplicate or a
//!   replay): [`DropReason::SequenceNotAdvancing`]. ABB EGM `seqno`, KUKA RSI `IPOC`, the
//!   Stäubli header `seq` and the simple line protocol's optional `seq=` count;
//! * its **robot time goes back** (ABB EGM `tm`, the Stäubli timestamp): an equal time is
//!   accepted (a robot may stamp two cycles in one millisecond), an earlier one is not:
//!   [`DropReason::TimeWentBack`];
//! * it carries a sequence number where the session's messages do not, or lacks one where they
//!   do (the simple line protocol, whose `seq=` is optional): [`DropReason::SequenceMismatch`].
//!
//! **Advancing** is serial-number arithmetic (RFC 1982) for values that fit 32 bits, the
//! widths of EGM `seqno` and of the Stäubli `seq` (and in practice of KUKA's `IPOC`, a
//! millisecond stamp): `new` is after `last` when `new − last` (mod 2³²) lies in `1 .. 2³¹`, so
//! a counter that wraps after 49.7 days of 1 ms stamps (or 2³² messages) keeps advancing, and
//! anything up to 2³¹ behind is a replay. Wider values (only the text protocol's `seq=`) compare
//! as plain integers. Robot time going back uses the same arithmetic for EGM's 32-bit
//! millisecond `tm`.
//!
//! A robot that restarts its counters (a new EGM or RSI session on the controller) is therefore
//! refused until the deflex session is restarted: a new robot session is a new deflex session.
//!
//! Every check is a few integer comparisons on fixed-size state: nothing allocates.

use std::fmt;

/// Why a message from the locked robot was dropped unanswered.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DropReason {
    /// The joint count differs from the session's.
    JointCount {
        /// Joint values in the message.
        got: usize,
        /// Joint values in the session's messages.
        session: usize,
    },
    /// The sequence number (or KUKA IPOC) does not advance: a duplicate or a replay.
    SequenceNotAdvancing {
        /// The message's number.
        got: u64,
        /// The last accepted number.
        last: u64,
    },
    /// The robot's clock went back.
    TimeWentBack {
        /// The message's time (s).
        got_s: f64,
        /// The last accepted time (s).
        last_s: f64,
    },
    /// A sequence number where the session has none, or none where it has one.
    SequenceMismatch {
        /// True: the message carries one (the session's messages do not).
        message_has_one: bool,
    },
}

impl fmt::Display for DropReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            DropReason::JointCount { got, session } => write!(
                f,
                "{got} joint values where the session's messages carry {session}"
            ),
            DropReason::SequenceNotAdvancing { got, last } => write!(
                f,
                "sequence number {got} does not advance over the last accepted {last} \
                 (duplicate or replay)"
            ),
            DropReason::TimeWentBack { got_s, last_s } => write!(
                f,
                "robot time {got_s:.3} s goes back from the last accepted {last_s:.3} s"
            ),
            DropReason::SequenceMismatch { message_has_one } => {
                if message_has_one {
                    f.write_str("a sequence number where the session's messages carry none")
                } else {
                    f.write_str("no sequence number where the session's messages carry one")
                }
            }
        }
    }
}

/// A robot clock reading, in the protocol's own representation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Stamp {
    /// Milliseconds in 32 bits, wrapping (ABB EGM `tm`).
    Millis32(u32),
    /// Seconds (the Stäubli timestamp, f64; finite by the parser).
    Seconds(f64),
}

impl Stamp {
    /// In seconds (for messages).
    pub fn seconds(self) -> f64 {
        match self {
            Stamp::Millis32(ms) => f64::from(ms) * 1e-3,
            Stamp::Seconds(s) => s,
        }
    }

    /// True if `self` is earlier than `last` (same representation): the 32-bit millisecond
    /// counter by serial arithmetic (up to 2³¹ ms, 24.8 days, behind is earlier, so a counter
    /// that wrapped is later), seconds as numbers; stamps of the two kinds are never ordered.
    pub fn before(self, last: Stamp) -> bool {
        match (self, last) {
            // Serial arithmetic: up to 2³¹ ms (24.8 days) behind is "before".
            (Stamp::Millis32(t), Stamp::Millis32(l)) => (t.wrapping_sub(l) as i32) < 0,
            (Stamp::Seconds(t), Stamp::Seconds(l)) => t < l,
            // One protocol never mixes them; a mixture cannot be ordered: not "before".
            _ => false,
        }
    }
}

/// True if sequence number `new` comes after `last`: serial arithmetic modulo 2³² when both
/// fit 32 bits (`new − last` in `1 .. 2³¹`), plain comparison otherwise.
pub fn advances(new: u64, last: u64) -> bool {
    match (u32::try_from(new), u32::try_from(last)) {
        (Ok(n), Ok(l)) => {
            let d = n.wrapping_sub(l);
            d != 0 && d < 1 << 31
        }
        _ => new > last,
    }
}

/// What a link has refused, dropped, accepted and answered since it was created: the
/// counters a runtime reads ([`crate::RobotLink::counters`]) to show the session's health and
/// to end it as faulted when the robot was starved.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct LinkCounters {
    /// Messages accepted as the robot's (each one may be answered).
    pub accepted: u64,
    /// Answers sent (for ABB EGM, the number of deflex's last `seqno`, modulo 2³²).
    pub answers: u64,
    /// Datagrams (TCP: connections) from a sender the peer policy or lock refused.
    pub foreign: u64,
    /// Robot messages dropped: joint count different from the session's.
    pub dropped_joint_count: u64,
    /// Robot messages dropped: sequence number not advancing (duplicates, replays).
    pub dropped_sequence: u64,
    /// Robot messages dropped: robot time going back.
    pub dropped_time: u64,
    /// Robot messages dropped: sequence number present where the session has none or absent
    /// where it has one.
    pub dropped_sequence_mismatch: u64,
    /// TCP: connections served (one at a time).
    pub connections: u64,
    /// TCP: connections refused because another one held the session.
    pub refused_busy: u64,
    /// TCP: of those, refused while the holder was not serving robot lines (it had sent no
    /// valid line yet, or none for [`crate::simple_tcp::STARVE_SILENCE`]): a robot kept out.
    pub refused_starving: u64,
    /// TCP: held connections closed after the idle timeout without a valid line.
    pub idle_closed: u64,
    /// UR RTDE: packages refused as malformed (unknown type, another recipe id, another size, a
    /// non-finite double, a size the stream cannot carry), each also returned as an error.
    pub bad_packets: u64,
}

impl LinkCounters {
    /// Robot messages dropped for any reason.
    pub fn dropped(&self) -> u64 {
        self.dropped_joint_count
            + self.dropped_sequence
            + self.dropped_time
            + self.dropped_sequence_mismatch
    }

    /// True if a connection was refused while the session's holder was not serving robot
    /// lines: the robot may have been kept out, so a session that ends must end as faulted.
    pub fn robot_starved(&self) -> bool {
        self.refused_starving > 0
    }
}

/// The state of the current robot session's messages (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SessionGuard {
    joints: Option<usize>,
    seq: SeqState,
    time: Option<Stamp>,
    accepted: u64,
    dropped: [u64; 4],
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
enum SeqState {
    /// No message accepted yet.
    #[default]
    Unknown,
    /// The session's messages carry no sequence number.
    Absent,
    /// The last accepted number.
    Last(u64),
}

impl SessionGuard {
    /// A new session: the first message sets the joint count and whether sequence numbers are
    /// carried.
    pub const fn new() -> Self {
        SessionGuard {
            joints: None,
            seq: SeqState::Unknown,
            time: None,
            accepted: 0,
            dropped: [0; 4],
        }
    }

    /// Checks a message against the session: on success the message becomes the session's
    /// latest (its joint count, sequence number and time are remembered); otherwise nothing
    /// changes but the count of its [`DropReason`].
    pub fn admit(
        &mut self,
        joints: usize,
        seq: Option<u64>,
        time: Option<Stamp>,
    ) -> Result<(), DropReason> {
        let verdict = self.judge(joints, seq, time);
        match verdict {
            Ok(()) => {
                self.joints = Some(joints);
                self.seq = seq.map_or(SeqState::Absent, SeqState::Last);
                if time.is_some() {
                    self.time = time;
                }
                self.accepted += 1;
            }
            Err(reason) => self.dropped[slot(&reason)] += 1,
        }
        verdict
    }

    fn judge(
        &self,
        joints: usize,
        seq: Option<u64>,
        time: Option<Stamp>,
    ) -> Result<(), DropReason> {
        if let Some(session) = self.joints
            && joints != session
        {
            return Err(DropReason::JointCount {
                got: joints,
                session,
            });
        }
        match (self.seq, seq) {
            (SeqState::Unknown, _) | (SeqState::Absent, None) => {}
            (SeqState::Absent, Some(_)) => {
                return Err(DropReason::SequenceMismatch {
                    message_has_one: true,
                });
            }
            (SeqState::Last(_), None) => {
                return Err(DropReason::SequenceMismatch {
                    message_has_one: false,
                });
            }
            (SeqState::Last(last), Some(got)) => {
                if !advances(got, last) {
                    return Err(DropReason::SequenceNotAdvancing { got, last });
                }
            }
        }
        if let (Some(last), Some(t)) = (self.time, time)
            && t.before(last)
        {
            return Err(DropReason::TimeWentBack {
                got_s: t.seconds(),
                last_s: last.seconds(),
            });
        }
        Ok(())
    }

    /// Forgets the sequence number and time (not the joint count): a new stream of the same
    /// session, e.g. a new TCP connection of the robot, whose counter restarts.
    pub fn restart_stream(&mut self) {
        self.seq = SeqState::Unknown;
        self.time = None;
    }

    /// The session's joint count, once a message was accepted.
    pub fn joint_count(&self) -> Option<usize> {
        self.joints
    }

    /// Adds the guard's counts (accepted, dropped by reason) to `c`.
    pub fn add_to(&self, c: &mut LinkCounters) {
        c.accepted += self.accepted;
        c.dropped_joint_count += self.dropped[0];
        c.dropped_sequence += self.dropped[1];
        c.dropped_time += self.dropped[2];
        c.dropped_sequence_mismatch += self.dropped[3];
    }
}

fn slot(r: &DropReason) -> usize {
    match r {
        DropReason::JointCount { .. } => 0,
        DropReason::SequenceNotAdvancing { .. } => 1,
        DropReason::TimeWentBack { .. } => 2,
        DropReason::SequenceMismatch { .. } => 3,
    }
}

//! # deflex-telemetry
//!
//! The one telemetry stream of a deflex session. The control thread publishes one typed
//! [`CycleSample`] per control cycle into a [`Broadcast`] ring: wait-free, allocation-free and
//! never waiting for a reader. Any number of non-real-time sinks (the CSV log, the live view, the
//! MCAP recorder, the ROS 2 bridge, a Python caller) each hold a [`Subscriber`] and read at their
//! own pace; a sink that falls more than the ring's capacity behind loses the oldest samples and
//! counts them ([`Subscriber::lost`]), it never slows the publisher.
//!
//! [`SeqCell`] is the same mechanism for one value: the latest state handed from one thread to
//! others (the runtime's joint, wrench and correction messages).
//!
//! Both carry any [`bytemuck::Pod`] type, stored as relaxed atomic words under a sequence
//! number, so a reader never sees a torn value and the code has no data race (no `unsafe`).
//!
//! [`SessionInfo`] is what does not change during a session (robot, joint names, limits, rates,
//! frame names); it is built once before the threads start and shared by `Arc`.
//!
//! [`Progress`] is the message of a long job (a structure search, a compensation, the study):
//! one display for all of them in each front end ([`progress`]).

#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod broadcast;
pub mod progress;
pub mod ros;
mod sample;
mod seqcell;
mod state;
pub mod synthetic;
mod words;

pub use broadcast::{Broadcast, Publisher, Subscriber, broadcast};
pub use progress::{OnProgress, Progress};
pub use sample::{CellState, CycleSample, FAULT_NONE, LATE_UNKNOWN, SessionInfo, StreamSource};
pub use seqcell::SeqCell;
pub use state::{FAULT_KINDS, FaultKind, Flags, Phase};

/// Re-exported so that users can derive [`bytemuck::Pod`] for their own messages.
pub use bytemuck;

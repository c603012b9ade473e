//! # deflex-record
//!
//! Every deflex session recorded in an [MCAP](https://mcap.dev) file that the robotics tool
//! chain opens as it is (Foxglove, Lichtblick, PlotJuggler, rerun, `ros2 bag`): ROS 2 message
//! definitions (schema encoding `ros2msg`, message encoding `cdr`, from [`deflex_telemetry::ros`]) on the
//! channels listed in [`channels`].
//!
//! * [`McapRecorder`]: a thread that drains a telemetry [`deflex_telemetry::Subscriber`] into a
//!   file written aside and renamed at the end (a failed recording leaves an earlier file
//!   whole), bounded in size ([`RecordOptions::max_bytes`]); it never slows the publisher: a
//!   recorder that falls behind loses samples and counts them.
//! * [`McapSink`]: the same writing, synchronous, into any writer (the twin's own loop, tests).
//! * [`for_each_cycle`]: reads a recording back, streaming, into cycle samples.
//! * [`run_log`]: the run log, the controller's state one row per control cycle: its columns
//!   with their units and its writer, the one definition `deflex run`'s CSV log ([`csv_log`]),
//!   the study's controller log and every reader use; [`isf_log`]: the columns of the twin's
//!   `deflex sim isf` log; [`log_reader`]: the one reader of both (bounded, every error naming
//!   the file, the line and the column).
//! * [`trace`]: any run log (a recording, a `deflex run` CSV log, a `deflex sim isf` log) as the
//!   plain columns `deflex plot` draws ([`trace::RunTrace`]).

#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod channels;
pub mod csv_log;
pub mod isf_log;
pub mod log_reader;
mod read;
mod recorder;
pub mod run_log;
mod session;
pub mod trace;
mod write;

/// The SIMULATED synthetic telemetry stream (defined in [`deflex_telemetry::synthetic`], below
/// the outlets, so that the live view's tests use it too), kept at its old path.
pub use deflex_telemetry::synthetic;
pub use read::{MAX_RECORD_BYTES, MCAP_MAGIC, RecordingSummary, for_each_cycle, is_mcap};
pub use recorder::{McapRecorder, RecordReport};
pub use session::{SESSION_JSON_SCHEMA, SessionRecord};
pub use write::{
    CHUNK_BYTES, DEFAULT_MAX_BYTES, MIN_MAX_BYTES, McapSink, RecordOptions, RecordStats,
};

use deflex_files::FileIoError;

/// Why a recording failed. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// The file (its temporary sibling) could not be created, or the thread not started: the
    /// destination with the context `cannot start the recording`.
    #[error(transparent)]
    Create(FileIoError),
    /// The disk (or the user's quota) is full: the recording is discarded, an earlier file at
    /// the destination is left whole.
    #[error(
        "{path}: disk full after {bytes_written} bytes of recording; the recording was discarded (free space, or record elsewhere)"
    )]
    DiskFull {
        /// The destination.
        path: String,
        /// Bytes written before the failure.
        bytes_written: u64,
    },
    /// Writing failed otherwise.
    #[error("{path}: write failed after {bytes_written} bytes: {source}")]
    Write {
        /// The destination.
        path: String,
        /// Bytes written before the failure.
        bytes_written: u64,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The MCAP writer refused a record.
    #[error("{path}: MCAP writer: {message}")]
    Mcap {
        /// The destination.
        path: String,
        /// The writer's message.
        message: String,
    },
    /// A message could not be encoded.
    #[error("{path}: {source}")]
    Encode {
        /// The destination.
        path: String,
        /// The cause.
        #[source]
        source: deflex_telemetry::ros::CdrError,
    },
    /// The recorder thread panicked.
    #[error("{path}: the recorder thread panicked")]
    Panicked {
        /// The destination.
        path: String,
    },
}

impl RecordError {
    pub(crate) fn from_io(path: &str, bytes_written: u64, e: std::io::Error) -> RecordError {
        if e.kind() == std::io::ErrorKind::StorageFull
            || e.kind() == std::io::ErrorKind::QuotaExceeded
        {
            RecordError::DiskFull {
                path: path.to_string(),
                bytes_written,
            }
        } else {
            RecordError::Write {
                path: path.to_string(),
                bytes_written,
                source: e,
            }
        }
    }

    pub(crate) fn from_mcap(path: &str, bytes_written: u64, e: mcap::McapError) -> RecordError {
        match e {
            mcap::McapError::Io(io) => RecordError::from_io(path, bytes_written, io),
            other => RecordError::Mcap {
                path: path.to_string(),
                message: other.to_string(),
            },
        }
    }
}

/// Why a recording could not be read. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The file could not be opened or read.
    #[error(transparent)]
    Io(#[from] FileIoError),
    /// The file does not start with the MCAP magic bytes.
    #[error(
        "{path}: not an MCAP file (it does not start with the MCAP magic bytes 89 4D 43 41 50 30 0D 0A)"
    )]
    NotMcap {
        /// The file.
        path: String,
    },
    /// The MCAP structure is broken (truncated, bad CRC, oversized record).
    #[error("{path}: damaged MCAP file: {message}")]
    Mcap {
        /// The file.
        path: String,
        /// The reader's message.
        message: String,
    },
    /// An MCAP file, but not a deflex recording.
    #[error("{path}: an MCAP file without deflex's channels (it has: {})", if topics.is_empty() { "no messages".to_string() } else { topics.join(", ") })]
    Foreign {
        /// The file.
        path: String,
        /// Topics found (at most 64).
        topics: Vec<String>,
    },
    /// A deflex topic with another message type.
    #[error("{path}: channel {topic} has schema {found}, expected {expected}")]
    WrongSchema {
        /// The file.
        path: String,
        /// The topic.
        topic: String,
        /// The type deflex writes there.
        expected: &'static str,
        /// The type found.
        found: String,
    },
    /// A message that does not decode as its type.
    #[error("{path}: message {index} on {topic}: {source}")]
    Decode {
        /// The file.
        path: String,
        /// The topic.
        topic: String,
        /// 1-based index of the message in the file.
        index: u64,
        /// The cause.
        #[source]
        source: deflex_telemetry::ros::CdrError,
    },
}

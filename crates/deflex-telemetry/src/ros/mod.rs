//! # The ROS 2 forms of the messages (`deflex_telemetry::ros`)
//!
//! The ROS 2 messages deflex writes (to MCAP files and on the ROS 2 graph): plain serde
//! structs whose field names, types and order are exactly those of the `.msg` definitions in
//! `ros2/common_interfaces` and `ros2/rcl_interfaces` (`builtin_interfaces/Time`), each with its
//! full concatenated definition ([`RosMessage::DEFINITION`], the `ros2msg` schema of an MCAP
//! channel) and its CDR encoding ([`encode`], [`decode`]).
//!
//! Each struct is named after its ROS 2 message type with the suffix `Msg`
//! ([`WrenchStampedMsg`] is `geometry_msgs/msg/WrenchStamped`, [`TimeMsg`] is
//! `builtin_interfaces/msg/Time`): the suffix marks a ROS 2 message type, apart from the
//! workspace's own types of the same name (nalgebra's `Vector3`, `deflex_model::Pose` and
//! `deflex_model::Wrench`, the DDS crates' types).
//!
//! CDR here is XCDR1 little-endian with the 4-byte RTPS encapsulation header `00 01 00 00`
//! (what ROS 2's default middleware sends and rosbag2 records, MCAP message encoding `cdr`):
//! primitives aligned to their size from the end of the header, strings as a `u32` length that
//! counts the terminating NUL, then the bytes and the NUL, sequences as a `u32` count then the
//! elements. ROS `byte` is an octet (`u8`).
//!
//! [`cycle`] is the one mapping of a telemetry [`crate::CycleSample`] to these
//! messages (topics, frames, diagnostics keys), shared by the recorder and the bridge.
//!
//! ```
//! use deflex_telemetry::ros::{HeaderMsg, TimeMsg, Vector3Msg, Vector3StampedMsg, decode, encode};
//! let msg = Vector3StampedMsg {
//!     header: HeaderMsg { stamp: TimeMsg::from_nanos(1_500_000_000), frame_id: "base".into() },
//!     vector: Vector3Msg { x: 1.0, y: 2.0, z: 3.0 },
//! };
//! let bytes = encode(&msg).unwrap();
//! assert_eq!(&bytes[..4], &[0, 1, 0, 0]);
//! assert_eq!(decode::<Vector3StampedMsg>(&bytes).unwrap(), msg);
//! ```

#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod cycle;
mod topics;
pub use topics::{Ros2Qos, Ros2Topic};
mod definitions;
mod messages;

pub use messages::*;

use serde::Serialize;
use serde::de::DeserializeOwned;

/// Largest encoded message [`decode`] accepts (bytes): bounds what a malformed length field can
/// make it read or allocate.
pub const MAX_MESSAGE_BYTES: usize = 16 << 20;

/// A ROS 2 message type: its name and its `.msg` definition with every dependency.
pub trait RosMessage: Serialize + DeserializeOwned {
    /// Full type name, e.g. `geometry_msgs/msg/WrenchStamped` (the MCAP schema name).
    const NAME: &'static str;
    /// The definition followed by its dependencies, each after a line of 80 `=` and a
    /// `MSG: package/Type` line (the `ros2msg` schema encoding, as rosbag2 writes it).
    const DEFINITION: &'static str;
}

/// Why a message could not be encoded or decoded.
#[derive(Debug, thiserror::Error)]
pub enum CdrError {
    /// The CDR serializer failed (a string or sequence longer than CDR can carry).
    #[error("{type_name}: CDR encoding failed: {message}")]
    Encode {
        /// The message type.
        type_name: &'static str,
        /// The serializer's message.
        message: String,
    },
    /// The bytes are not a CDR encoding of the type (truncated, wrong header, bad length).
    #[error("{type_name}: not a CDR encoding of this type ({len} bytes): {message}")]
    Decode {
        /// The message type.
        type_name: &'static str,
        /// Length of the input.
        len: usize,
        /// The deserializer's message.
        message: String,
    },
    /// The input is longer than [`MAX_MESSAGE_BYTES`].
    #[error("{type_name}: {len} bytes, more than the {max} a message may have")]
    TooLarge {
        /// The message type.
        type_name: &'static str,
        /// Length of the input.
        len: usize,
        /// [`MAX_MESSAGE_BYTES`].
        max: usize,
    },
}

/// The CDR (XCDR1, little-endian, with encapsulation header) encoding of `msg`.
pub fn encode<T: RosMessage>(msg: &T) -> Result<Vec<u8>, CdrError> {
    cdr::serialize::<_, _, cdr::CdrLe>(msg, cdr::Infinite).map_err(|e| CdrError::Encode {
        type_name: T::NAME,
        message: e.to_string(),
    })
}

/// Decodes a CDR encoding (big- or little-endian, by its encapsulation header) of a `T`.
pub fn decode<T: RosMessage>(bytes: &[u8]) -> Result<T, CdrError> {
    if bytes.len() > MAX_MESSAGE_BYTES {
        return Err(CdrError::TooLarge {
            type_name: T::NAME,
            len: bytes.len(),
            max: MAX_MESSAGE_BYTES,
        });
    }
    // The bound makes the deserializer refuse any length field that would read past the input.
    cdr::deserialize_from::<_, T, _>(bytes, cdr::Bounded(bytes.len() as u64)).map_err(|e| {
        CdrError::Decode {
            type_name: T::NAME,
            len: bytes.len(),
            message: e.to_string(),
        }
    })
}

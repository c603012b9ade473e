//! # deflex-io
//!
//! Wire protocols between the deflex controller, industrial robot
//! controllers and a force/torque sensor, each with **both sides**
//! implemented so that a simulated cell can play the robot or the sensor over
//! loopback UDP (or TCP) with the very same code:
//!
//! | module | protocol | units on the wire |
//! |---|---|---|
//! | [`rsi`] | KUKA RSI, XML over UDP (port 59152) | mm, degrees |
//! | [`egm`] | ABB EGM path correction, protobuf over UDP | mm, degrees |
//! | [`staubli`] | deflex binary protocol for a Stäubli VAL3 `alter` program | m, rad |
//! | [`fanuc_stream`] | FANUC Stream Motion (J519), binary UDP (port 60015); deflex streams the joints | degrees |
//! | [`netft`] | ATI Net F/T RDT, binary UDP (port 49152) | sensor counts |
//! | [`simple_udp`] | text lines over UDP, for other controllers | m, rad |
//! | [`simple_tcp`] | the same text lines over TCP (port 50161), for UR URScript | m, rad |
//! | [`rtde`] | Universal Robots RTDE, binary over TCP (port 30004; deflex is the client) | m, rad, N, N·m |
//!
//! Inside the crate and at its API everything is SI: metres, radians,
//! newtons, newton-metres, with the model's spatial types (`deflex_model::Pose`,
//! `deflex_model::Wrench`) and its vendor orientation conventions
//! (`deflex_model::conventions`) ([`link`]). Each protocol module offers pure
//! parse/format functions on byte slices (no I/O) plus UDP endpoints (TCP for
//! [`simple_tcp`], whose robot is a TCP client) for the controller side
//! ([`RobotLink`], [`ForceSensorLink`]) and the robot/sensor side
//! ([`RobotSideLink`], [`netft::NetFtSensorServer`]).
//!
//! The controller-side hot path (`receive` / `send_correction`) does not
//! allocate after construction: buffers are fixed and reused. Network input
//! never causes a panic; every malformed packet is a [`LinkError`] (see
//! [`LinkError::is_bad_packet`]) and the endpoint stays usable.

#![warn(missing_docs)]

pub mod egm;
pub mod error;
pub mod fanuc_stream;
pub mod guard;
pub mod link;
pub mod netft;
pub mod peer;
pub mod robot_side;
pub mod rsi;
pub mod rtde;
pub mod simple_tcp;
pub mod simple_udp;
pub mod staubli;
pub mod udp;
pub mod xml;

pub use error::{LinkError, Protocol};
pub use guard::{DropReason, LinkCounters};
pub use link::{
    Correction, ForceSensorLink, ReceivedCorrection, RobotLink, RobotSideLink, RobotState,
    WrenchSample,
};
pub use peer::{PeerConfigError, PeerPolicy, PeerWarning, validate_peer};
pub use robot_side::{RobotEndpoint, RobotKind, RobotSide, StreamSide};

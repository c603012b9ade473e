//! # deflex-control
//!
//! The force-feedback correction **law** of Johra et al. (2022), *Robotics* 11, 48, Sections 2.1
//! and 4.2: the tool path is corrected online from a 6-axis force/torque sensor and the
//! calibrated elasto-geometrical model, without any external pose measurement. Pure maths on
//! the model of `deflex-model`: no threads, clock, files, sockets or configuration format, so
//! any runtime (`deflex-runtime`'s real-time threads, the in-process digital twin of
//! `deflex_sim::twin`, a Python binding) drives the same law.
//!
//! One control cycle ([`Controller::cycle`]) does, allocation-free:
//!
//! 1. **wrench path** ([`wrench`]): raw sensor reading − bias (tare taken out of contact) − tool
//!    gravity for the current sensor orientation (flange × sensor-in-flange from forward
//!    kinematics), optional first-order low-pass, then the wrench `w` (eq. 2) at the TCP; one
//!    type, [`deflex_model::Wrench`], from the reading to the estimate;
//! 2. **estimate** ([`estimate::tcp_deflection_in_base`]): δŝ = J K_θ⁻¹ Jᵀ w (eq. 15) at the
//!    robot's reported joint values, in the robot's base axes (those of ξ);
//! 3. **tracking error** ε = s_des − ŝ_real = −ξ − δŝ (eq. 5–7, with ŝ_real = s_com + δŝ and
//!    s_com = s_des + ξ), so the loop needs only q and w;
//! 4. **PID** of eq. 17 per axis ([`pid`]), derivative on a filtered signal, anti-windup by
//!    back-calculation;
//! 5. **limiter** ([`limiter`]): size and rate per axis, per-axis enable, smooth ramp in/out;
//! 6. **safety** ([`safety`]): latched faults (force over limit, sensor silent, robot link lost,
//!    non-finite or out-of-range values) freeze the integrator and ramp ξ to the safe value;
//!    the **runaway guard** ([`runaway`]) withdraws a correction that a stiff contact turns into
//!    positive feedback; the **model check** ([`model_check`]) latches a fault when the TCP pose
//!    the robot reports leaves the model's at the same joints.
//!
//! With an offline compensation (`deflex compensate`), [`feedforward`] adds the predicted
//! correction as a feed-forward, or accounts for the compensation a pre-compensated program
//! already applies, so the feedback corrects only the residual. The table comes in as data
//! ([`FeedForwardPoint`]); reading `compensated_path.csv` is the runtime's job.
//!
//! What moved out (issue 19): the threads, clock, real-time scheduling, `CELL.toml`, the link
//! factory, the send shaper, the CSV log and the telemetry stream are `deflex-runtime`'s; the
//! controller↔twin glue is `deflex_sim::twin`'s.
//!
//! Sign conventions: SI units; ξ = [δp (m); δφ (rad)] in robot base axes; s_com = s_des + ξ.

#![warn(missing_docs)]
// Six-axis loops index several arrays in lockstep; an index is the clearest form.
#![allow(clippy::needless_range_loop)]

pub mod controller;
pub mod estimate;
pub mod feedforward;
pub mod limiter;
pub mod model_check;
pub mod pid;
pub mod runaway;
pub mod safety;
pub mod telemetry;
pub mod wrench;

pub use controller::{
    ControlError, Controller, ControllerConfig, CycleInput, CycleOutput, JOINT_MAP_DAMPING,
    JointCorrectionMap,
};
pub use estimate::{DeflectionEstimate, tcp_deflection_in_base};
pub use feedforward::{
    FeedForward, FeedForwardColumn, FeedForwardConfig, FeedForwardError, FeedForwardMode,
    FeedForwardPoint, FeedForwardTable, PathIndex,
};
pub use limiter::{Limiter, LimiterConfig};
pub use model_check::{ModelCheckConfig, PoseMismatch, tcp_pose_mismatch};
pub use pid::{Pid, PidGains};
pub use runaway::{RunawayAction, RunawayConfig, RunawayGuard};
pub use safety::{Channel, Fault, SafeAction, Safety, SafetyConfig};
pub use telemetry::RecordCycle;
pub use wrench::{WrenchConfig, WrenchProcessor};

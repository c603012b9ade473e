//! # deflex-control
//!
//! The real-time force-feedback correction controller of Johra et al. (2022), *Robotics* 11, 48,
//! Sections 2.1 and 4.2: the tool path is corrected online from a 6-axis force/torque sensor and
//! the calibrated elasto-geometrical model, without any external pose measurement.
//!
//! One control cycle ([`Controller::cycle`]) does, allocation-free:
//!
//! 1. **wrench path** ([`wrench`]): raw sensor reading − bias (tare taken out of contact) − tool
//!    gravity for the current sensor orientation (flange × sensor-in-flange from forward
//!    kinematics), optional first-order low-pass, then the wrench `w` (eq. 2) at the TCP in base
//!    axes;
//! 2. **estimate** δŝ = J K_θ⁻¹ Jᵀ w (eq. 15) at the robot's reported joint values;
//! 3. **tracking error** ε = s_des − ŝ_real = −ξ − δŝ (eq. 5–7, with ŝ_real = s_com + δŝ and
//!    s_com = s_des + ξ), so the loop needs only q and w;
//! 4. **PID** of eq. 17 per axis ([`pid`]), derivative on a filtered signal, anti-windup by
//!    back-calculation;
//! 5. **limiter** ([`limiter`]): size and rate per axis, per-axis enable, smooth ramp in/out;
//! 6. **safety** ([`safety`]): latched faults (force over limit, sensor silent, robot link lost,
//!    non-finite or out-of-range values) freeze the integrator and ramp ξ to the safe value.
//!
//! With an offline compensation (`deflex compensate`), [`feedforward`] adds the predicted
//! correction as a feed-forward, or accounts for the compensation a pre-compensated program
//! already applies, so the feedback corrects only the residual.
//!
//! Around it: [`clock`] (injectable wall/simulated time), [`rt`] (SCHED_FIFO, mlockall),
//! [`log`] (lock-free ring buffer → CSV writer thread), [`stats`] (cycle-time histogram),
//! [`config`] (`CELL.toml`) and [`runtime`] (robot-link, sensor and control threads).
//!
//! Sign conventions: SI units; ξ = [δp (m); δφ (rad)] in robot base axes; s_com = s_des + ξ.

#![warn(missing_docs)]
// Six-axis loops index several arrays in lockstep; an index is the clearest form.
#![allow(clippy::needless_range_loop)]

pub mod clock;
pub mod config;
pub mod controller;
pub mod feedforward;
pub mod limiter;
pub mod log;
pub mod pid;
pub mod rt;
pub mod runaway;
pub mod runtime;
pub mod safety;
pub mod send_shaper;
pub mod slot;
pub mod stats;
pub mod wrench;

pub use clock::{Clock, SimClock, WallClock};
pub use config::{CellFile, ConfigError};
pub use controller::{Controller, ControllerConfig, CycleInput, CycleOutput, Phase};
pub use feedforward::{
    FeedForward, FeedForwardConfig, FeedForwardError, FeedForwardMode, FeedForwardTable, PathIndex,
};
pub use limiter::{Limiter, LimiterConfig};
pub use pid::{Pid, PidGains};
pub use runaway::{RunawayAction, RunawayConfig, RunawayGuard};
pub use safety::{Channel, Fault, FaultKind, Flags, SafeAction, Safety, SafetyConfig};
pub use wrench::{ToolLoad, WrenchConfig, WrenchProcessor};

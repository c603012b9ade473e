//! The control law's test set-up: the built-in TX200 at the paper's cone centre configuration, a
//! controller with a known bias and a tool, and the raw sensor readings for a TCP wrench.
//!
//! One definition for every test binary that runs this controller: deflex-runtime's sessions
//! (its `common` module) and the facade's no-allocation tests compile this file by `#[path]`,
//! so it uses nothing but deflex-control, deflex-model and nalgebra, which they all have.
#![allow(dead_code)]

use deflex_control::wrench::WrenchProcessor;
use deflex_control::{Controller, ControllerConfig, WrenchConfig};
use deflex_model::ToolLoad;
use deflex_model::spatial::pose_from_xyz_rpy;
use deflex_model::{Data, Robot, TX200_FORMING_Q_DEG, Wrench, builtin};

/// The sensor bias of [`config`] (N, N·m), in every reading of [`raw_reading`].
pub const BIAS: [f64; 6] = [4.0, -3.0, 7.0, 0.2, -0.1, 0.05];

/// The paper's forming configuration of the TX200 (rad).
pub fn q0() -> [f64; 6] {
    TX200_FORMING_Q_DEG.map(f64::to_radians)
}

/// A controller configuration with the known bias [`BIAS`], a sensor 4 cm off the flange
/// (turned 0.3 rad about z) and a 5 kg tool.
pub fn config() -> ControllerConfig {
    ControllerConfig {
        bias: Some(BIAS),
        wrench: WrenchConfig {
            sensor_in_flange: pose_from_xyz_rpy([0.0, 0.0, 0.04], [0.0, 0.0, 0.3]),
            tool_in_sensor: ToolLoad {
                mass_kg: 5.0,
                centre_of_mass_m: nalgebra::Vector3::new(0.0, 0.01, 0.12),
            },
            ..WrenchConfig::default()
        },
        ..ControllerConfig::default()
    }
}

/// The built-in TX200.
pub fn robot() -> Robot {
    builtin("tx200").expect("built-in tx200")
}

/// A controller of [`robot`] with `config`.
pub fn controller(config: ControllerConfig) -> Controller {
    Controller::new(robot(), config).expect("controller")
}

/// What the sensor reads at joint values `q` for the environment wrench `w_tcp_world` at the
/// TCP (world axes): [`BIAS`] + the tool's weight + that wrench, under the mounting and tool of
/// `config` (its own `bias` aside: a controller that tares finds [`BIAS`]).
pub fn raw_reading(config: &ControllerConfig, q: &[f64], w_tcp_world: [f64; 6]) -> Wrench {
    let mut data = Data::new();
    robot().forward_kinematics(&mut data, q).unwrap();
    let mut path = WrenchProcessor::new(config.wrench);
    path.set_bias(Wrench::from(BIAS));
    path.raw_reading(&Wrench::from(w_tcp_world), &data)
}

/// Runs `seconds` of the law against a rigid-environment-free plant (constant wrench), returns
/// the controller time reached.
pub fn run_steady(ctrl: &mut Controller, raw: &Wrench, q: &[f64], t0: f64, seconds: f64) -> f64 {
    let mut t = t0;
    let steps = (seconds / 0.01).round() as usize;
    for _ in 0..steps {
        t += 0.01;
        ctrl.cycle(t, q, raw);
    }
    t
}

//! Shared set-up: the built-in TX200 at the paper's cone centre configuration, a controller with
//! a known bias and a tool, and raw sensor readings synthesised for a TCP wrench.
#![allow(dead_code)]

use deflex_control::{Controller, ControllerConfig, WrenchConfig};
use deflex_model::ToolLoad;
use deflex_model::spatial::pose_from_xyz_rpy;
use deflex_model::wrench_transport::world_wrench_in_sensor;
use deflex_model::{Data, Robot, TX200_FORMING_Q_DEG, Wrench, builtin};

pub const BIAS: [f64; 6] = [4.0, -3.0, 7.0, 0.2, -0.1, 0.05];

pub fn q0() -> [f64; 6] {
    TX200_FORMING_Q_DEG.map(f64::to_radians)
}

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

pub fn robot() -> Robot {
    builtin("tx200").expect("built-in tx200")
}

pub fn controller(config: ControllerConfig) -> Controller {
    Controller::new(robot(), config).expect("controller")
}

/// What the sensor reads (bias + tool weight + environment wrench `w_tcp_world` at the TCP).
pub fn raw_reading(config: &ControllerConfig, q: &[f64], w_tcp_world: [f64; 6]) -> Wrench {
    let robot = robot();
    let mut data = Data::new();
    robot.forward_kinematics(&mut data, q).unwrap();
    let sensor = data.flange * config.wrench.sensor_in_flange;
    let env = world_wrench_in_sensor(&Wrench::from(w_tcp_world), &data.tcp_position(), &sensor);
    let g = config.wrench.gravity_world;
    let m = config.wrench.tool_in_sensor.mass_kg;
    let f =
        sensor.rotation.matrix().transpose() * nalgebra::Vector3::new(g[0] * m, g[1] * m, g[2] * m);
    let c = config.wrench.tool_in_sensor.centre_of_mass_m;
    let mg = c.cross(&f);
    let grav = [f.x, f.y, f.z, mg.x, mg.y, mg.z];
    Wrench::from_fn(|i, _| BIAS[i] + grav[i] + env[i])
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

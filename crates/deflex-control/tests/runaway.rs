//! Stiff contact against the real [`Controller`] (TX200 model at the forming pose), with a scalar
//! contact written here: a spring of stiffness k_c under the tool along world z, in series with
//! a robot whose true compliance along z is the model's divided by ρ; the robot applies the
//! correction two control periods late and reports the joints it is commanded to. Without the
//! guard the loop multiplies the force (or runs to the correction limit); with it the force stays
//! below 2.5× the force the program alone gives. A forming-like contact (the force set by the
//! material's flow, hardening 4 N/mm, the tool circling in the plane, sensor noise) never trips
//! the guard and gives the same correction as without it.
#![allow(clippy::needless_range_loop)] // per-axis loops over several arrays

mod common;

use deflex_control::{Controller, ControllerConfig, FaultKind, Flags, RunawayAction};
use deflex_model::{Data, Robot, Wrench};
use nalgebra::{DMatrix, DVector};
use rand::{Rng, SeedableRng};
use std::collections::VecDeque;

const DELAY_CYCLES: usize = 2;

/// The model's compliance along world z at the pose (m/N), from eq. 15 with a unit force.
fn model_compliance_z(robot: &Robot, q: &[f64]) -> f64 {
    let mut data = Data::new();
    robot.forward_kinematics(&mut data, q).unwrap();
    robot.tcp_deflection(&data, &Wrench::from([0.0, 0.0, 1.0, 0.0, 0.0, 0.0]))[2]
}

/// Joint values that move the TCP by `xi` (world axes, [δp; δφ]) from `q0`: Jacobian
/// pseudo-inverse at `q0` (the test's robot controller).
struct Kinematics {
    robot: Robot,
    q0: Vec<f64>,
    pinv: DMatrix<f64>,
}

impl Kinematics {
    fn new(q0: &[f64]) -> Self {
        let robot = common::robot();
        let mut data = Data::new();
        robot.forward_kinematics(&mut data, q0).unwrap();
        let j = robot.geometric_jacobian(&data, &data.tcp_position());
        let pinv = j.pseudo_inverse(1e-12).unwrap();
        Kinematics {
            robot,
            q0: q0.to_vec(),
            pinv,
        }
    }
    fn q_for(&self, xi: &[f64; 6]) -> Vec<f64> {
        let dq = &self.pinv * DVector::from_column_slice(xi);
        self.q0.iter().zip(dq.iter()).map(|(a, b)| a + b).collect()
    }
    fn tcp_z(&self, q: &[f64]) -> f64 {
        let mut data = Data::new();
        self.robot.forward_kinematics(&mut data, q).unwrap();
        data.tcp_position().z
    }
}

struct Outcome {
    max_force: f64,
    max_xi_z: f64,
    runaway_events: u64,
    fault: Option<deflex_control::Fault>,
    held: bool,
}

/// Presses the tool down on a contact of stiffness `k_c` with the force `f0` the program alone
/// gives, for `seconds`, with a model `rho` times as compliant as the robot.
fn press(k_c: f64, rho: f64, f0: f64, config: ControllerConfig, seconds: f64) -> Outcome {
    assert_eq!(
        common::robot().base.rotation,
        nalgebra::UnitQuaternion::identity().into(),
        "the test works in base = world axes"
    );
    let q0 = common::q0();
    let kin = Kinematics::new(&q0);
    let c_model = model_compliance_z(&kin.robot, &q0);
    assert!(c_model > 1e-7, "{c_model}");
    let c_robot = c_model / rho;
    let k_eff = 1.0 / (c_robot + 1.0 / k_c);
    // The surface sits where the programmed tool position gives f0.
    let z_surface = kin.tcp_z(&q0) + f0 / k_eff;
    let mut ctrl = Controller::new(kin.robot.clone(), config).unwrap();
    ctrl.start(0.0);
    let mut applied: VecDeque<[f64; 6]> = VecDeque::from(vec![[0.0; 6]; DELAY_CYCLES]);
    let mut out = Outcome {
        max_force: 0.0,
        max_xi_z: 0.0,
        runaway_events: 0,
        fault: None,
        held: false,
    };
    let mut t = 0.0;
    while t < seconds {
        t += 0.01;
        let xi_a = applied.pop_front().unwrap();
        let q = kin.q_for(&xi_a);
        // Commanded position → contact force (spring in series with the robot).
        let force = (k_eff * (z_surface - kin.tcp_z(&q))).max(0.0);
        let raw = common::raw_reading(ctrl.config(), &q, [0.0, 0.0, force, 0.0, 0.0, 0.0]);
        let o = ctrl.cycle(t, &q, &raw);
        applied.push_back(o.xi);
        out.max_force = out.max_force.max(force);
        out.max_xi_z = out.max_xi_z.max(-o.xi[2]);
        out.held |= o.flags.has(Flags::RUNAWAY_HOLD);
    }
    out.runaway_events = ctrl.runaway_events();
    out.fault = ctrl.fault();
    out
}

fn config(guard: bool) -> ControllerConfig {
    let mut c = common::config();
    c.safety.max_force_n = 1e6;
    c.safety.max_torque_nm = 1e6;
    c.safety.sensor_range = [1e7; 6];
    c.runaway.enabled = guard;
    c
}

#[test]
fn stiff_contact_runs_away_without_the_guard_and_is_held_with_it() {
    let f0 = 800.0;
    let max_abs = common::config().limiter.max_abs[2];
    let c_r = model_compliance_z(&common::robot(), &common::q0());
    eprintln!(
        "model compliance along z at the forming pose: {:.3} µm/N",
        c_r * 1e6
    );
    for k_c in [1e5, 1e6, 1e7, 1e8] {
        for rho in [1.0, 1.3] {
            let g = deflex_control::runaway::static_loop_gain(c_r, c_r / rho, k_c);
            let free = press(k_c, rho, f0, config(false), 10.0);
            let guarded = press(k_c, rho, f0, config(true), 10.0);
            eprintln!(
                "k_c {k_c:.0e} N/m, ρ {rho}: g {g:.3}; without guard max F {:.0} N, ξz {:.3} mm; \
                 with guard max F {:.0} N, ξz {:.3} mm, events {}",
                free.max_force,
                free.max_xi_z * 1e3,
                guarded.max_force,
                guarded.max_xi_z * 1e3,
                guarded.runaway_events
            );
            if g >= 0.7 {
                // Runaway: the force multiplied, or the correction at its limit.
                assert!(
                    free.max_force >= 3.0 * f0 || free.max_xi_z >= max_abs - 1e-9,
                    "k_c {k_c} ρ {rho}: no runaway without the guard ({} N)",
                    free.max_force
                );
                assert!(
                    guarded.runaway_events >= 1 && guarded.held,
                    "k_c {k_c} ρ {rho}"
                );
            }
            // The stated bound: the force stays below 2.5 F0 with the guard.
            assert!(
                guarded.max_force <= 2.5 * f0,
                "k_c {k_c} ρ {rho}: guarded max force {} N",
                guarded.max_force
            );
            assert!(guarded.fault.is_none(), "{:?}", guarded.fault);
        }
    }
}

#[test]
fn fault_action_latches_contact_runaway_and_ramps_out() {
    let mut c = config(true);
    c.runaway.action = RunawayAction::Fault;
    let o = press(1e8, 1.3, 800.0, c, 10.0);
    let f = o.fault.expect("a fault");
    assert_eq!(f.kind, FaultKind::ContactRunaway);
    assert!(
        f.to_string()
            .starts_with("contact_runaway: estimated loop gain"),
        "{f}"
    );
    assert!(o.max_force <= 2.5 * 800.0, "{}", o.max_force);
}

/// A forming-like contact: the tool circles at 10 mm/s on a 40 mm radius while the program steps
/// down at 0.05 mm/s; the vertical force is the material's flow level with 4 N/mm hardening, the
/// in-plane force 0.3 of it, pointing to the centre; the sensor adds 0.3 N of noise. The guard
/// must not act, and the correction must be the same as without it.
#[test]
fn forming_like_contact_does_not_trip_the_guard() {
    let q0 = common::q0();
    let kin = Kinematics::new(&q0);
    let run = |guard: bool| {
        let mut ctrl = Controller::new(kin.robot.clone(), config(guard)).unwrap();
        ctrl.start(0.0);
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let mut applied: VecDeque<[f64; 6]> = VecDeque::from(vec![[0.0; 6]; DELAY_CYCLES]);
        let z0 = kin.tcp_z(&q0);
        let mut t = 0.0f64;
        let mut last = [0.0; 6];
        let mut events = 0;
        while t < 20.0 {
            t += 0.01;
            let xi_a = applied.pop_front().unwrap();
            let (r, w) = (0.04f64, 0.25f64);
            let program = [
                r * (w * t).cos() - r,
                r * (w * t).sin(),
                -0.05e-3 * t,
                0.0,
                0.0,
                0.0,
            ];
            let cmd: [f64; 6] = std::array::from_fn(|i| program[i] + xi_a[i]);
            let q = kin.q_for(&cmd);
            let depth = z0 - kin.tcp_z(&q);
            let fz = 1000.0 + 4e3 * depth;
            let (c, s) = ((w * t).cos(), (w * t).sin());
            let noise = |rng: &mut rand::rngs::StdRng| rng.gen_range(-0.5..0.5) * 0.6;
            let env = [
                -0.3 * fz * c + noise(&mut rng),
                -0.3 * fz * s + noise(&mut rng),
                fz + noise(&mut rng),
                0.0,
                0.0,
                0.0,
            ];
            let raw = common::raw_reading(ctrl.config(), &q, env);
            let o = ctrl.cycle(t, &q, &raw);
            applied.push_back(o.xi);
            last = o.xi;
            events = ctrl.runaway_events();
        }
        (last, events, ctrl.fault())
    };
    let (with, events, fault) = run(true);
    let (without, _, _) = run(false);
    assert_eq!(events, 0, "the guard acted on a forming contact");
    assert!(fault.is_none(), "{fault:?}");
    assert!(with[2] < -0.5e-3, "the correction was active: {with:?}");
    for i in 0..6 {
        assert!(
            (with[i] - without[i]).abs() < 1e-12,
            "{with:?} vs {without:?}"
        );
    }
}

//! No allocation on deflex-control's per-cycle path: this binary's counting global allocator
//! proves that a control cycle (wrench path, eq. 15, eq. 17, limiter, safety, runaway guard,
//! feed-forward) and the frames the robot links need per answer (joint-correction map, TCP
//! orientation) allocate nothing. It counts only its own thread's allocations. The runtime's
//! whole control-thread path (messages, telemetry publish, send shaper) is proven in
//! `no_alloc::runtime`.

use super::setup::{config, controller, q0, raw_reading, robot};
use deflex_model::{Data, Wrench};

#[test]
fn control_cycle_allocates_nothing() {
    let mut config = config();
    config.bias = None; // exercise the tare path too
    config.wrench.lowpass_hz = Some(30.0);
    let mut ctrl = controller(config);
    let q = q0();
    let raw_free = raw_reading(&config, &q, [0.0; 6]);
    let raw_load = raw_reading(&config, &q, [300.0, -200.0, 900.0, 1.0, 2.0, -1.0]);
    ctrl.start(0.0);
    // Warm-up outside the measurement (first use of lazily initialised statics, if any).
    ctrl.cycle(0.01, &q, &raw_free);
    let before = super::allocations();
    let mut t = 0.01;
    for k in 0..5000 {
        t += 0.01;
        let raw = if k < 30 { &raw_free } else { &raw_load };
        let out = ctrl.cycle(t, &q, raw);
        // What a robot link needs per answer: the joint map and the TCP orientation.
        let dq = ctrl.joint_correction_map() * nalgebra::Vector6::from(out.xi);
        std::hint::black_box((dq, ctrl.tcp_rotation_in_base()));
    }
    // Faults and the ramp to the safe value must not allocate either.
    let nan = Wrench::repeat(f64::NAN);
    for _ in 0..100 {
        t += 0.01;
        std::hint::black_box(ctrl.cycle(t, &q, &nan));
    }
    let after = super::allocations();
    assert!(ctrl.fault().is_some());
    assert_eq!(
        after - before,
        0,
        "{} allocations in 5100 cycles",
        after - before
    );
    // The counter itself works.
    let v: Vec<u8> = Vec::with_capacity(std::hint::black_box(64));
    drop(v);
    assert!(super::allocations() > after);
}

/// The model check ([`deflex_control::model_check`]) on every cycle allocates nothing: the
/// reported TCP pose compared with the model's (the session's largest kept), then a jump of it
/// that latches `model_mismatch`, and the ramp-out; the free function too.
#[test]
fn model_check_allocates_nothing() {
    use deflex_control::CycleInput;
    let config = config();
    let mut ctrl = controller(config);
    let q = q0();
    let raw = raw_reading(&config, &q, [300.0, -200.0, 900.0, 1.0, 2.0, -1.0]);
    let model = robot();
    let pose = model.base.inverse() * model.tcp_pose(&q).unwrap();
    let mut jumped = pose;
    jumped.translation.vector.z += 0.02;
    let input = |t: f64, pose| CycleInput {
        now_s: t,
        q_rad: &q,
        q_age_s: 0.0,
        wrench_sensor: raw,
        wrench_age_s: 0.0,
        wrench_fresh: true,
        sensor_status: 0,
        tcp_pose: Some(pose),
    };
    ctrl.start(0.0);
    ctrl.cycle_input(&input(0.01, pose));
    let mut data = Data::new();
    let before = super::allocations();
    let mut t = 0.01;
    for k in 0..1000 {
        t += 0.01;
        let reported = if k < 500 { pose } else { jumped };
        std::hint::black_box(ctrl.cycle_input(&input(t, reported)));
        std::hint::black_box(
            deflex_control::tcp_pose_mismatch(&model, &mut data, &q, &reported).unwrap(),
        );
    }
    let after = super::allocations();
    assert_eq!(
        ctrl.fault().map(|f| f.kind),
        Some(deflex_telemetry::FaultKind::ModelMismatch)
    );
    assert_eq!(after - before, 0, "{} allocations", after - before);
}

/// The runaway guard's whole cycle (estimate, trip, withdrawal, latched hold, release at its rate)
/// allocates nothing: a press on a 10⁷ N/m contact that trips it, then the contact goes away.
/// Only the controller's cycles are counted (the test's plant is outside).
#[test]
fn runaway_guard_allocates_nothing() {
    use deflex_control::runaway::HoldPhase;
    let config = {
        let mut c = config();
        c.safety.max_force_n = 1e6;
        c.safety.sensor_range = [1e7; 6];
        c
    };
    let mut ctrl = controller(config);
    let robot = robot();
    let q0 = q0();
    let mut data = Data::new();
    robot.forward_kinematics(&mut data, &q0).unwrap();
    // Joint motion for a TCP motion ξ: the Jacobian's inverse at q0 (6 joints, fixed size).
    let j = robot.geometric_jacobian(&data, &data.tcp_position());
    let j6 = nalgebra::Matrix6::from_fn(|r, c| j[(r, c)]);
    let inverse = j6.try_inverse().expect("regular pose");
    let k_eff = 1.0 / (1.0e-6 + 1.0 / 1e7);
    let mut phases = [false; 3];
    let mut delayed = [[0.0; 6]; 2];
    ctrl.start(0.0);
    let mut allocations = 0;
    let mut t = 0.0f64;
    for k in 0..800 {
        t += 0.01;
        let xi = delayed[k % 2];
        let dq = inverse * nalgebra::Vector6::from(xi);
        let q: [f64; 6] = std::array::from_fn(|i| q0[i] + dq[i]);
        // 800 N from the program; the surface goes away from t = 5 s.
        let surface = 800.0 / k_eff - 2e-3 * (t - 5.0).clamp(0.0, 1.0);
        let force = (k_eff * (surface - xi[2])).max(0.0);
        let raw = raw_reading(&config, &q, [0.0, 0.0, force, 0.0, 0.0, 0.0]);
        let before = super::allocations();
        let out = ctrl.cycle(t, &q, &raw);
        let hold = ctrl.runaway_hold();
        allocations += super::allocations() - before;
        delayed[k % 2] = out.xi;
        if let Some(h) = hold {
            phases[match h.phase {
                HoldPhase::Withdrawing => 0,
                HoldPhase::Holding => 1,
                HoldPhase::Releasing => 2,
            }] = true;
        }
    }
    assert!(ctrl.runaway_events() >= 1);
    assert_eq!(phases, [true; 3], "every phase of the hold was exercised");
    assert!(ctrl.runaway_hold().is_none(), "released at the end");
    assert_eq!(
        allocations, 0,
        "{allocations} allocations in the guard's cycles"
    );
}

/// Joint values along a short arc of joint 1 and the table of that path (TCP by forward
/// kinematics, a deflection growing along it).
fn path_and_table() -> (Vec<[f64; 6]>, deflex_control::FeedForwardTable) {
    use deflex_control::FeedForwardPoint;
    use deflex_model::{Data, Displacement};
    let robot = robot();
    let q0 = q0();
    let qs: Vec<[f64; 6]> = (0..3000)
        .map(|k| {
            let mut q = q0;
            q[0] += k as f64 * 5e-6;
            q
        })
        .collect();
    let mut data = Data::new();
    let mut s = 0.0;
    let mut previous: Option<nalgebra::Vector3<f64>> = None;
    let rows: Vec<FeedForwardPoint> = qs
        .iter()
        .step_by(10)
        .enumerate()
        .map(|(i, q)| {
            robot.forward_kinematics(&mut data, q).unwrap();
            let p = data.tcp_position();
            if let Some(prev) = previous {
                s += (p - prev).norm();
            }
            previous = Some(p);
            let d = Displacement::new(0.0, 0.0, s * 0.01, 0.0, 0.0, s * 0.001);
            FeedForwardPoint {
                arc_length_m: s,
                time_s: i as f64 * 0.1,
                desired_m: data.tcp_position(),
                compensation: Displacement::new(0.0, 0.0, -s * 0.01, 0.0, 0.0, 0.0),
                deflection: d,
            }
        })
        .collect();
    let table = deflex_control::FeedForwardTable::from_points(&rows, &robot).unwrap();
    (qs, table)
}

#[test]
fn control_cycle_with_feedforward_allocates_nothing() {
    use deflex_control::{FeedForward, FeedForwardConfig, FeedForwardMode, PathIndex};
    use deflex_telemetry::Flags;
    let (qs, table) = path_and_table();
    let config = config();
    let settings = [
        (FeedForwardMode::FeedForward, PathIndex::ArcLength, 0.03),
        (FeedForwardMode::Precompensated, PathIndex::ArcLength, 0.0),
        (FeedForwardMode::FeedForward, PathIndex::Time, 0.02),
    ];
    for (mode, index, lead_s) in settings {
        let mut ctrl = controller(config);
        let ff = FeedForward::new(
            table.clone(),
            FeedForwardConfig {
                mode,
                index,
                lead_s,
                ..FeedForwardConfig::default()
            },
        )
        .unwrap();
        ctrl.set_feedforward(Some(ff));
        ctrl.start(0.0);
        let raw = raw_reading(&config, &qs[0], [0.0, 0.0, 800.0, 0.0, 0.0, 0.0]);
        ctrl.cycle(0.0, &qs[0], &raw);
        let before = super::allocations();
        let mut on_path = 0;
        for (k, q) in qs.iter().enumerate().skip(1) {
            let out = ctrl.cycle(k as f64 * 0.01, q, &raw);
            if !out.flags.has(Flags::FEEDFORWARD_OFF_PATH) {
                on_path += 1;
            }
        }
        let after = super::allocations();
        assert_eq!(after - before, 0, "{mode:?} {index:?}");
        // The work was done: the robot was on the path.
        assert!(on_path > 2900, "{mode:?} {index:?}: {on_path}");
    }
}

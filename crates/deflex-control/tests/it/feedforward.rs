//! Feed-forward plus feedback against the real [`Controller`] (TX200 model at the forming pose)
//! in closed loop with a robot written here: it moves its TCP 40 mm along world x at 10 mm/s,
//! applies the correction two control periods late, reports the joints it is commanded to
//! (inverse kinematics of the commanded pose), and deflects as the model says (eq. 15) under a
//! process force that ramps from 0 to 1000 N down on the tool between 10 and 12 mm of the path
//! (a forming-like, flow-limited force: it does not depend on the tool's position). The offline
//! table predicts that force (exactly, or 20 % low).
//!
//! Checked: the fixed point of the module documentation (total correction → −δŝ, the feedback
//! carrying only the residual δ_pred − δŝ), no double correction with a pre-compensated program
//! (and the double correction without telling the controller), and the lag at the ramp.

use crate::common;

use deflex_control::{
    Controller, ControllerConfig, FeedForward, FeedForwardConfig, FeedForwardMode,
    FeedForwardPoint, FeedForwardTable,
};
use deflex_model::{Data, Displacement, IkOptions, Pose, Robot, Wrench};
use deflex_telemetry::Flags;
use nalgebra::Vector3;
use std::collections::VecDeque;

const DELAY_CYCLES: usize = 2;
const FORCE_N: f64 = 1000.0;

/// A straight path: direction (world), feed, length, and where the force ramps (arc length of
/// its start, length of the ramp).
#[derive(Clone, Copy)]
struct Line {
    direction: [f64; 3],
    feed_m_s: f64,
    length_m: f64,
    ramp_m: (f64, f64),
}

/// 40 mm along x at 10 mm/s, the force ramping between 10 and 12 mm.
const ALONG_X: Line = Line {
    direction: [1.0, 0.0, 0.0],
    feed_m_s: 0.01,
    length_m: 0.04,
    ramp_m: (0.010, 0.002),
};

/// A plunge: 4 mm down at 2 mm/s, the force ramping over 0.6 mm from 1 mm down (the path runs
/// along the correction).
const PLUNGE: Line = Line {
    direction: [0.0, 0.0, -1.0],
    feed_m_s: 0.002,
    length_m: 0.004,
    ramp_m: (0.001, 0.0006),
};

const LENGTH_M: f64 = ALONG_X.length_m;

impl Line {
    /// The process force at arc length `s` (world axes, on the tool: pushes up).
    fn force(&self, s: f64, scale: f64) -> Wrench {
        let f = FORCE_N * scale * ((s - self.ramp_m.0) / self.ramp_m.1).clamp(0.0, 1.0);
        Wrench::new(0.0, 0.0, f, 0.0, 0.0, 0.0)
    }
}

struct Robotic {
    robot: Robot,
    start: Pose,
    data: Data,
    q: Vec<f64>,
    line: Line,
}

impl Robotic {
    fn along(line: Line) -> Self {
        let robot = common::robot();
        let q = common::q0().to_vec();
        let start = robot.tcp_pose(&q).unwrap();
        Robotic {
            robot,
            start,
            data: Data::new(),
            q,
            line,
        }
    }

    fn desired(&self, s: f64) -> Pose {
        let mut p = self.start;
        p.translation.vector += Vector3::from(self.line.direction) * s.min(self.line.length_m);
        p
    }

    /// Joints for a commanded pose (warm-started IK); the model's deflection there under `w`.
    fn command(&mut self, pose: &Pose, w: &Wrench) -> Displacement {
        self.q = self
            .robot
            .inverse_kinematics(pose, &self.q, &IkOptions::default())
            .unwrap()
            .q;
        self.robot
            .forward_kinematics(&mut self.data, &self.q)
            .unwrap();
        self.robot.tcp_deflection(&self.data, w)
    }
}

/// The offline table: the path every 0.5 mm with the deflection predicted for `scale` × the
/// force, compensation = −deflection (position only, as for the twin).
fn table(scale: f64) -> Vec<FeedForwardPoint> {
    table_along(ALONG_X, scale, 80)
}

fn table_along(line: Line, scale: f64, points: usize) -> Vec<FeedForwardPoint> {
    let mut robotic = Robotic::along(line);
    let step = line.length_m / points as f64;
    (0..=points)
        .map(|i| {
            let s = i as f64 * step;
            let desired = robotic.desired(s);
            let w = line.force(s, scale);
            // Deflection at the compensated configuration (one fixed-point step is enough
            // at this size).
            let d0 = robotic.command(&desired, &w);
            let mut commanded = desired;
            commanded.translation.vector -= Vector3::new(d0[0], d0[1], d0[2]);
            let d = robotic.command(&commanded, &w);
            FeedForwardPoint {
                arc_length_m: s,
                time_s: s / line.feed_m_s,
                desired_m: desired.translation.vector,
                compensation: Displacement::new(-d[0], -d[1], -d[2], 0.0, 0.0, 0.0),
                deflection: d,
            }
        })
        .collect()
}

fn feedforward(scale: f64, mode: FeedForwardMode, lead_s: f64) -> FeedForward {
    feedforward_along(table(scale), mode, lead_s)
}

fn feedforward_along(
    rows: Vec<FeedForwardPoint>,
    mode: FeedForwardMode,
    lead_s: f64,
) -> FeedForward {
    let table = FeedForwardTable::from_points(&rows, &common::robot()).unwrap();
    FeedForward::new(
        table,
        FeedForwardConfig {
            mode,
            lead_s,
            ..FeedForwardConfig::default()
        },
    )
    .unwrap()
}

#[derive(Debug, Default)]
struct Run {
    /// Largest |error| (m) after the ramp-in, and its integral over the second from the ramp.
    max_error_m: f64,
    ramp_error_integral_m_s: f64,
    /// At the end: total offset of the robot (program + correction) along z, the estimate δŝ_z,
    /// the feedback part ξ_fb,z = ξ_z − sent_z (sent = −δ_pred in feed-forward mode) and the
    /// table's prior.
    offset_z: f64,
    delta_s_hat_z: f64,
    feedback_z: f64,
    prior_z: f64,
    final_error_m: f64,
    off_path_cycles: usize,
    path_s_m: f64,
    /// Largest |tracked − true arc length| while on the path (m).
    max_tracking_error_m: f64,
}

/// One run along the path: `program` is the compensated program (`Some(table rows)`) or the
/// original; `ff` the controller's feed-forward.
fn run(
    config: ControllerConfig,
    ff: Option<FeedForward>,
    program: Option<&[FeedForwardPoint]>,
) -> Run {
    run_along(ALONG_X, config, ff, program)
}

fn run_along(
    line: Line,
    config: ControllerConfig,
    ff: Option<FeedForward>,
    program: Option<&[FeedForwardPoint]>,
) -> Run {
    let mut robotic = Robotic::along(line);
    let mut ctrl = Controller::new(robotic.robot.clone(), config).unwrap();
    ctrl.set_feedforward(ff);
    ctrl.start(0.0);
    let mut applied: VecDeque<[f64; 6]> = VecDeque::from(vec![[0.0; 6]; DELAY_CYCLES]);
    let mut out = Run::default();
    let mut t = 0.0;
    let mut last_xi = [0.0; 6];
    let ramp_t = line.ramp_m.0 / line.feed_m_s;
    while t < line.length_m / line.feed_m_s + 1.5 {
        t += 0.01;
        let s = (t * line.feed_m_s).min(line.length_m);
        let desired = robotic.desired(s);
        let xi = applied.pop_front().unwrap();
        // The program's compensation (interpolated between the table's points).
        let c = program.map_or(Vector3::zeros(), |rows| {
            let step = rows[1].arc_length_m;
            let k = ((s / step) as usize).min(rows.len() - 2);
            let u = (s - rows[k].arc_length_m) / step;
            let (a, b) = (&rows[k].compensation, &rows[k + 1].compensation);
            Vector3::new(
                a[0] + u * (b[0] - a[0]),
                a[1] + u * (b[1] - a[1]),
                a[2] + u * (b[2] - a[2]),
            )
        });
        let mut commanded = desired;
        commanded.translation.vector += c + Vector3::new(xi[0], xi[1], xi[2]);
        commanded.rotation =
            nalgebra::Rotation3::from_scaled_axis(Vector3::new(xi[3], xi[4], xi[5]))
                * commanded.rotation;
        let w = line.force(s, 1.0);
        let d = robotic.command(&commanded, &w);
        let error = (commanded.translation.vector + Vector3::new(d[0], d[1], d[2])
            - desired.translation.vector)
            .norm();
        let raw = common::raw_reading(ctrl.config(), &robotic.q, w.into());
        let o = ctrl.cycle(t, &robotic.q, &raw);
        applied.push_back(o.xi);
        last_xi = o.xi;
        if t > 0.6 {
            out.max_error_m = out.max_error_m.max(error);
        }
        if (ramp_t..ramp_t + 1.0).contains(&t) {
            out.ramp_error_integral_m_s += error * 0.01;
        }
        if o.flags.has(Flags::FEEDFORWARD_OFF_PATH) {
            out.off_path_cycles += 1;
        }
        out.offset_z = c.z + xi[2];
        out.delta_s_hat_z = o.delta_s_hat[2];
        out.prior_z = o.feedforward[2];
        out.feedback_z = o.xi[2]
            - if program.is_none() {
                o.feedforward[2]
            } else {
                0.0
            };
        out.final_error_m = error;
        out.path_s_m = o.path_s_m;
        // The robot is where it was commanded DELAY_CYCLES ago: s of the cycle that sent it.
        if o.path_s_m.is_finite() && s < line.length_m {
            let lag = DELAY_CYCLES as f64 * 0.01 * line.feed_m_s;
            out.max_tracking_error_m = out.max_tracking_error_m.max((o.path_s_m - s).abs() - lag);
        }
    }
    assert!(last_xi.iter().all(|v| v.is_finite()));
    assert_eq!(ctrl.fault(), None);
    out
}

fn config() -> ControllerConfig {
    let mut c = common::config();
    c.runaway.enabled = false;
    c
}

#[test]
fn feed_forward_leaves_the_feedback_only_the_residual() {
    // The prediction is 20 % low: the feedback carries the rest.
    let ff = run(
        config(),
        Some(feedforward(0.8, FeedForwardMode::FeedForward, 0.0)),
        None,
    );
    let online = run(config(), None, None);
    let open = {
        let mut c = config();
        c.limiter.enabled = [false; 6];
        run(c, None, None)
    };
    eprintln!("open {open:?}\nonline {online:?}\nfeed-forward {ff:?}");
    assert!(open.max_error_m > 0.3e-3, "{open:?}");
    // Fixed point: the total correction cancels the estimated deflection, as online alone.
    assert!((ff.offset_z + ff.delta_s_hat_z).abs() < 1e-6, "{ff:?}");
    assert!((online.offset_z + online.delta_s_hat_z).abs() < 1e-6);
    assert!((ff.offset_z - online.offset_z).abs() < 1e-6);
    // The feedback carries only the residual δ_pred − δŝ = −0.2 δŝ (the prior is −δ_pred).
    assert!(
        (ff.feedback_z - (-ff.prior_z - ff.delta_s_hat_z)).abs() < 1e-6,
        "{ff:?}"
    );
    assert!((ff.feedback_z + 0.2 * ff.delta_s_hat_z).abs() < 0.01 * ff.delta_s_hat_z.abs());
    // And the transient: the error over the second after the ramp is smaller.
    assert!(
        ff.ramp_error_integral_m_s < 0.5 * online.ramp_error_integral_m_s,
        "{} vs {}",
        ff.ramp_error_integral_m_s,
        online.ramp_error_integral_m_s
    );
    assert!(ff.max_error_m < online.max_error_m);
    // The controller followed the path by arc length to its end (within the feedback's own
    // offset along the path: 0.2 × the deflection's x, 56 µm measured).
    assert_eq!(ff.off_path_cycles, 0);
    assert!((ff.path_s_m - LENGTH_M).abs() < 0.1e-3, "{}", ff.path_s_m);
}

#[test]
fn a_precompensated_program_is_not_corrected_twice() {
    let rows = table(1.0);
    let told = run(
        config(),
        Some(feedforward(1.0, FeedForwardMode::Precompensated, 0.0)),
        Some(&rows),
    );
    let untold = run(config(), None, Some(&rows));
    let offline = {
        let mut c = config();
        c.limiter.enabled = [false; 6];
        run(c, None, Some(&rows))
    };
    eprintln!("offline only {offline:?}\ntold {told:?}\nuntold {untold:?}");
    // The offline compensation alone is exact here (the table's force is the true one).
    assert!(offline.final_error_m < 5e-6, "{offline:?}");
    // Told: the total offset settles at −δŝ and the error stays small; the feedback is ~0.
    assert!(
        (told.offset_z + told.delta_s_hat_z).abs() < 1e-6,
        "{told:?}"
    );
    assert!(told.final_error_m < 5e-6, "{told:?}");
    assert!(told.feedback_z.abs() < 1e-6);
    // Untold: the controller adds −δŝ on top of the program's −δ: the error is the deflection
    // again, in the other direction.
    assert!(
        (untold.offset_z - 2.0 * untold.delta_s_hat_z.abs() * untold.offset_z.signum()).abs()
            < 0.02 * untold.offset_z.abs(),
        "{untold:?}"
    );
    assert!(
        untold.final_error_m > 0.9 * untold.delta_s_hat_z.abs(),
        "{untold:?}"
    );
}

#[test]
fn a_lead_covers_the_robots_delay() {
    let no_lead = run(
        config(),
        Some(feedforward(1.0, FeedForwardMode::FeedForward, 0.0)),
        None,
    );
    let lead = run(
        config(),
        Some(feedforward(1.0, FeedForwardMode::FeedForward, 0.03)),
        None,
    );
    eprintln!("no lead {no_lead:?}\nlead 30 ms {lead:?}");
    assert!(lead.ramp_error_integral_m_s < no_lead.ramp_error_integral_m_s);
    assert!(lead.max_error_m < no_lead.max_error_m);
}

/// A plunge along the correction's direction: the arc length is tracked from the robot's place
/// on its program (the TCP minus the controller's own correction), so the feed-forward does not
/// feed back into the arc length it is read at, and the ramp is taken without lag.
#[test]
fn a_plunge_into_a_force_ramp_is_tracked_and_fed_forward() {
    let rows = table_along(PLUNGE, 1.0, 40);
    let ff = run_along(
        PLUNGE,
        config(),
        Some(feedforward_along(
            rows.clone(),
            FeedForwardMode::FeedForward,
            0.0,
        )),
        None,
    );
    let online = run_along(PLUNGE, config(), None, None);
    let pre = run_along(
        PLUNGE,
        config(),
        Some(feedforward_along(
            rows.clone(),
            FeedForwardMode::Precompensated,
            0.0,
        )),
        Some(&rows),
    );
    eprintln!("plunge: online {online:?}\nfeed-forward {ff:?}\npre-compensated {pre:?}");
    // Arc length within 20 µm of the truth (the robot's delay taken out), with 3.3 mm of
    // deflection along the path.
    assert!(ff.max_tracking_error_m < 20e-6, "{ff:?}");
    assert!(pre.max_tracking_error_m < 20e-6, "{pre:?}");
    assert!(ff.delta_s_hat_z > 1e-3, "{ff:?}");
    assert!(ff.ramp_error_integral_m_s < 0.5 * online.ramp_error_integral_m_s);
    assert!(pre.ramp_error_integral_m_s < 0.5 * online.ramp_error_integral_m_s);
    assert!(ff.max_error_m < online.max_error_m && pre.max_error_m < online.max_error_m);
}

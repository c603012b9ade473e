//! A previous run's log as the compensation's wrench source: read through the recorder's log
//! reader ([`deflex_app::load::wrench_log`]) and resampled on arc length by the compensation,
//! against hand-made logs whose forces are known functions of the arc length.

use deflex_app::load::{WrenchLogError, parse_wrench_log};
use deflex_compensate::LogError;
use deflex_compensate::TcpPath;
use deflex_compensate::log::{LogKind, ResampleOptions, resample_on_path};
use deflex_model::{IkOptions, Pose, TX200_FORMING_Q_DEG, builtin};
use deflex_record::run_log::RUN_LOG_SKIP_FLAGS;
use nalgebra::{Translation3, Vector3};
use std::fmt::Write as _;

fn part() -> Pose {
    Pose::translation(1.5, 0.0, -0.183)
}

/// A straight path along x in the part frame, 0 … 10 mm, 1 mm apart.
fn straight_path() -> TcpPath {
    let down = builtin("tx200")
        .unwrap()
        .tcp_pose(&TX200_FORMING_Q_DEG.map(f64::to_radians))
        .unwrap()
        .rotation;
    let poses = (0..=10).map(|i| {
        let p = part() * nalgebra::Point3::new(0.001 * i as f64, 0.0, 0.0);
        (
            Pose::from_parts(Translation3::from(p.coords), down),
            Some(0.01),
        )
    });
    TcpPath::new("straight", poses, 0.05).unwrap()
}

/// A `sim isf` log with rows every 0.1 mm along the path; fz = 100 N per mm of arc length,
/// fx = 7 N, my = 0.5 N·m; positions in the part frame (mm) with a 0.05 mm lateral offset.
fn isf_log(rows: usize) -> String {
    let mut s = String::from(
        "# SIMULATED deflex digital twin forming log (not a measurement). path: test\n# units\n\
         time_s,des_x_mm,des_y_mm,des_z_mm,err_x_mm,fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm,contact\n",
    );
    for i in 0..rows {
        let x = 0.1 * i as f64;
        let _ = writeln!(
            s,
            "{:.2},{x:.4},0.05,0.0,0.0,7.0,0.0,{:.4},0.0,0.5,0.0,1",
            0.01 * i as f64,
            100.0 * x
        );
    }
    s
}

#[test]
fn a_sim_isf_log_resamples_to_the_known_force_profile() {
    let robot = builtin("tx200").unwrap();
    let log = parse_wrench_log(&isf_log(101), "log.csv", &robot, &part()).unwrap();
    assert_eq!(log.kind, LogKind::SimIsf);
    assert!(log.simulated);
    assert_eq!(log.samples.len(), 101);
    // Positions are mapped to the world with the part frame.
    assert!((log.samples[10].position_m - Vector3::new(1.501, 0.00005, -0.183)).norm() < 1e-12);
    let path = straight_path();
    // 0.45 mm: rows every 0.1 mm never sit on the window's edges (rounding would decide).
    for half_width in [0.0, 0.00045] {
        let options = ResampleOptions {
            half_width_m: half_width,
            ..ResampleOptions::default()
        };
        let r = resample_on_path(&log, &path, &options).unwrap();
        assert_eq!(r.used_rows, 101);
        assert_eq!(r.off_path_rows, 0);
        assert!((r.max_offset_m - 0.05e-3).abs() < 1e-12);
        for (point, w) in path.points().iter().zip(&r.wrenches) {
            let s_mm = point.arc_length_m * 1e3;
            // A symmetric box over evenly spaced rows of a linear profile is exact, except
            // where the window is cut by the ends of the log.
            let interior = s_mm > 0.6 && s_mm < 9.4;
            if half_width == 0.0 || interior {
                assert!((w[2] - 100.0 * s_mm).abs() < 1e-6, "s {s_mm} mm: {}", w[2]);
            }
            assert!((w[0] - 7.0).abs() < 1e-9 && (w[4] - 0.5).abs() < 1e-9);
        }
    }
}

#[test]
fn a_deflex_run_log_uses_forward_kinematics_and_skips_flagged_rows() {
    let robot = builtin("tx200").unwrap();
    let path = straight_path();
    let mut text = String::from("time_s,q1_rad,q2_rad,q3_rad,q4_rad,q5_rad,q6_rad,");
    text.push_str("raw_fx_n,w_fx_n,w_fy_n,w_fz_n,w_mx_nm,w_my_nm,w_mz_nm,cycle_us,flags,status\n");
    let mut q = TX200_FORMING_Q_DEG.map(f64::to_radians).to_vec();
    let options = IkOptions::default();
    for i in 0..=100 {
        // 0.1 mm steps along the path, the joints from the model's IK.
        let s = 1e-4 * i as f64;
        let (k, f) = path.locate(s);
        let a = path.points()[k].pose;
        let b = path.points()[k + 1].pose;
        let p = a.translation.vector + (b.translation.vector - a.translation.vector) * f;
        let target = Pose::from_parts(Translation3::from(p), a.rotation);
        q = robot.inverse_kinematics(&target, &q, &options).unwrap().q;
        let qs: Vec<String> = q.iter().map(|v| format!("{v:.12}")).collect();
        let _ = writeln!(
            text,
            "{:.3},{},1.0,0.0,0.0,{:.3},0.0,0.0,0.0,12.5,4096,active",
            0.01 * i as f64,
            qs.join(","),
            -500.0 - 1000.0 * s
        );
        // A taring row at the same place with an absurd wrench: must be skipped.
        if i % 10 == 5 {
            let _ = writeln!(
                text,
                "{:.3},{},1.0,0.0,0.0,99999.0,0.0,0.0,0.0,12.5,{},taring",
                0.01 * i as f64 + 0.001,
                qs.join(","),
                1u32 << 21
            );
        }
    }
    let log = parse_wrench_log(&text, "run.csv", &robot, &part()).unwrap();
    assert_eq!(log.kind, LogKind::DeflexRun);
    assert!(!log.simulated);
    assert_eq!(log.skipped_rows, 10);
    assert_eq!(log.samples.len(), 101);
    let options = ResampleOptions {
        half_width_m: 0.00045,
        ..ResampleOptions::default()
    };
    let r = resample_on_path(&log, &path, &options).unwrap();
    assert!(
        r.max_offset_m < 1e-9,
        "FK of the IK'd joints lies on the path"
    );
    for (point, w) in path.points().iter().zip(&r.wrenches) {
        let s = point.arc_length_m;
        let interior = s > 0.6e-3 && s < 9.4e-3;
        if interior {
            assert!((w[2] - (-500.0 - 1000.0 * s)).abs() < 1e-6, "{}", w[2]);
        }
    }
    assert_eq!(RUN_LOG_SKIP_FLAGS & (1 << 12), 0, "active rows are used");
}

#[test]
fn a_helix_logged_millimetres_off_the_path_keeps_its_turn() {
    // Paper-like helix: 20 mm radius, 0.24 mm per turn, 3 turns, 2° steps. The log is the path
    // shifted 3 mm down and 1 mm outwards (a compensated command is deeper): the later, deeper
    // turns are then closer than the right one, and only the window keeps the projection on its
    // turn (with a window over the whole path it jumps ahead; checked below).
    let robot = builtin("tx200").unwrap();
    let down = robot
        .tcp_pose(&TX200_FORMING_Q_DEG.map(f64::to_radians))
        .unwrap()
        .rotation;
    let steps = 3 * 180;
    let at = |k: usize| {
        let a = (k as f64) * 2f64.to_radians();
        Vector3::new(
            0.020 * a.cos(),
            0.020 * a.sin(),
            -0.00024 * a / std::f64::consts::TAU,
        )
    };
    let path = TcpPath::new(
        "helix",
        (0..=steps).map(|k| {
            (
                Pose::from_parts(
                    Translation3::from((part() * nalgebra::Point3::from(at(k))).coords),
                    down,
                ),
                Some(0.01),
            )
        }),
        0.05,
    )
    .unwrap();
    let mut text =
        String::from("# SIMULATED\ndes_x_mm,des_y_mm,des_z_mm,fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm\n");
    for k in 0..=4 * steps {
        // Four rows per path segment, at quarter points.
        let (j, f) = (k / 4, (k % 4) as f64 / 4.0);
        let p = if j >= steps {
            at(steps)
        } else {
            at(j) + (at(j + 1) - at(j)) * f
        };
        let radial = Vector3::new(p.x, p.y, 0.0).normalize();
        let shifted = p + radial * 0.001 - Vector3::new(0.0, 0.0, 0.003);
        // The force encodes the arc length: fz = s in mm.
        let s_mm = path.points()[j.min(steps)].arc_length_m * 1e3
            + if j >= steps {
                0.0
            } else {
                f * (path.points()[j + 1].arc_length_m - path.points()[j].arc_length_m) * 1e3
            };
        let _ = writeln!(
            text,
            "{:.6},{:.6},{:.6},0,0,{s_mm:.6},0,0,0",
            shifted.x * 1e3,
            shifted.y * 1e3,
            shifted.z * 1e3
        );
    }
    let log = parse_wrench_log(&text, "helix.csv", &robot, &part()).unwrap();
    let options = ResampleOptions {
        half_width_m: 0.0,
        ..ResampleOptions::default()
    };
    let r = resample_on_path(&log, &path, &options).unwrap();
    assert_eq!(r.off_path_rows, 0);
    let mut worst: f64 = 0.0;
    for (point, w) in path.points().iter().zip(&r.wrenches) {
        worst = worst.max((w[2] - point.arc_length_m * 1e3).abs());
    }
    // A wrong turn would be ≈ 126 mm away; the chords of the 2° polyline leave a few µm.
    assert!(worst < 0.01, "largest arc-length error {worst} mm");
    let unwindowed = ResampleOptions {
        window_m: 1.0,
        ..options
    };
    // Without the window the first row already lands on the deepest turn's end.
    match resample_on_path(&log, &path, &unwindowed) {
        Err(e) => assert!(matches!(e, LogError::PartialCoverage { .. }), "{e}"),
        Ok(r) => {
            let worst = path
                .points()
                .iter()
                .zip(&r.wrenches)
                .map(|(p, w)| (w[2] - p.arc_length_m * 1e3).abs())
                .fold(0.0, f64::max);
            assert!(
                worst > 50.0,
                "without the window the projection jumps turns: {worst} mm"
            );
        }
    }
}

#[test]
fn bad_logs_are_refused_with_file_line_and_column() {
    let robot = builtin("tx200").unwrap();
    let e = parse_wrench_log("a,b,c\n1,2,3\n", "x.csv", &robot, &part()).unwrap_err();
    assert!(matches!(e, WrenchLogError::UnknownKind { .. }), "{e}");
    assert!(
        e.to_string()
            .contains("x.csv: not a deflex run or sim isf log"),
        "{e}"
    );
    let mut text = isf_log(5);
    text.push_str("0.9,1.0,0.0,0.0,0.0,7.0,0.0,nan,0.0,0.5,0.0,1\n");
    let e = parse_wrench_log(&text, "x.csv", &robot, &part()).unwrap_err();
    assert_eq!(
        e.to_string(),
        "x.csv:9: column `fz_N`: expected a number, got \"nan\""
    );
    let e = parse_wrench_log(
        "time_s,q1_rad,q2_rad,w_fx_n,w_fy_n,w_fz_n,w_mx_nm,w_my_nm,w_mz_nm,flags\n",
        "r.csv",
        &robot,
        &part(),
    )
    .unwrap_err();
    assert!(
        matches!(
            e,
            WrenchLogError::JointCount {
                log: 2,
                robot: 6,
                ..
            }
        ),
        "{e}"
    );
    // A log covering only the first half of the path.
    let log = parse_wrench_log(&isf_log(51), "half.csv", &robot, &part()).unwrap();
    let e = resample_on_path(&log, &straight_path(), &ResampleOptions::default()).unwrap_err();
    assert!(
        matches!(
            e,
            LogError::PartialCoverage {
                first_uncovered: 7,
                ..
            }
        ),
        "{e}"
    );
    assert!(
        e.to_string()
            .contains("covers arc length 0.0 … 5.0 mm of the path's 10.0 mm"),
        "{e}"
    );
    // A log of another place.
    let far = parse_wrench_log(
        &isf_log(5),
        "far.csv",
        &robot,
        &Pose::translation(0.0, 1.0, 0.0),
    )
    .unwrap();
    let e = resample_on_path(&far, &straight_path(), &ResampleOptions::default()).unwrap_err();
    assert!(matches!(e, LogError::NoRowNearPath { rows: 5, .. }), "{e}");
}

/// A path whose first segment (a 15 mm rapid, as CAM programs start) is longer than the
/// resampling window, then 1 mm moves at right angles: the rows of the later segments are found
/// (the window runs ahead of the last row's arc length, not of its segment's start).
#[test]
fn a_segment_longer_than_the_window_does_not_hide_the_next_ones() {
    let down = builtin("tx200")
        .unwrap()
        .tcp_pose(&TX200_FORMING_Q_DEG.map(f64::to_radians))
        .unwrap()
        .rotation;
    let corners: Vec<[f64; 2]> = std::iter::once([0.0, 0.0])
        .chain((0..=10).map(|i| [15.0, i as f64]))
        .collect();
    let poses = corners.iter().map(|[x, y]| {
        let p = part() * nalgebra::Point3::new(x * 1e-3, y * 1e-3, 0.0);
        (
            Pose::from_parts(Translation3::from(p.coords), down),
            Some(0.01),
        )
    });
    let path = TcpPath::new("rapid then moves", poses, 0.05).unwrap();
    // Rows every 0.5 mm along the polyline; fz = 10 N per mm of arc length.
    let mut text = String::from(
        "# SIMULATED\ntime_s,des_x_mm,des_y_mm,des_z_mm,fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm\n",
    );
    for i in 0..=50 {
        let s = 0.5 * i as f64;
        let (x, y) = if s <= 15.0 {
            (s, 0.0)
        } else {
            (15.0, s - 15.0)
        };
        let _ = writeln!(
            text,
            "{:.2},{x},{y},0,0,0,{},0,0,0",
            0.05 * i as f64,
            10.0 * s
        );
    }
    let robot = builtin("tx200").unwrap();
    let log = parse_wrench_log(&text, "log.csv", &robot, &part()).unwrap();
    let options = ResampleOptions {
        half_width_m: 0.0,
        ..ResampleOptions::default()
    };
    let r = resample_on_path(&log, &path, &options).unwrap();
    assert_eq!(r.used_rows, 51, "{r:?}");
    for (point, w) in path.points().iter().zip(&r.wrenches) {
        let expected = 10.0 * point.arc_length_m * 1e3;
        assert!((w[2] - expected).abs() < 1e-6, "{} vs {expected}", w[2]);
    }
}

/// The case: a pass whose last millimetre has a dozen moving rows, then 200 rows logged
/// at rest at the end with the force fading, and a mid-path dwell with the force dropping. The
/// rows are weighted by path advance: the standstills do not count, every point gets the pass's
/// force (a time average would give the last points about half of it).
#[test]
fn standstill_rows_do_not_swamp_the_pass() {
    let robot = builtin("tx200").unwrap();
    let mut text = String::from(
        "time_s,des_x_mm,des_y_mm,des_z_mm,err_x_mm,fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm,contact\n",
    );
    let mut t = 0.0;
    let mut row = |x: f64, fz: f64, text: &mut String| {
        t += 0.004;
        let _ = writeln!(text, "{t:.3},{x:.6},0,0,0,0,0,{fz:.3},0,0,0,1");
    };
    // 12 rows per mm along the 10 mm path at 1000 N …
    for i in 0..=120 {
        let x = i as f64 / 12.0;
        row(x, 1000.0, &mut text);
        // … a 1 s dwell at 5 mm with the force sagging to 200 N …
        if i == 60 {
            for k in 0..250 {
                row(x, 1000.0 - 3.2 * k as f64, &mut text);
            }
        }
    }
    // … and 200 rows at rest at the end, the force fading out.
    for k in 0..200 {
        row(10.0, 1000.0 * (1.0 - k as f64 / 200.0), &mut text);
    }
    let log = parse_wrench_log(&text, "dwell.csv", &robot, &part()).unwrap();
    let path = straight_path();
    let r = resample_on_path(&log, &path, &ResampleOptions::default()).unwrap();
    assert_eq!(r.used_rows, 121, "{r:?}");
    assert_eq!(r.standstill_rows, 450);
    for (point, w) in path.points().iter().zip(&r.wrenches) {
        assert!(
            (w[2] - 1000.0).abs() < 1e-6,
            "s {} mm: {} N",
            point.arc_length_m * 1e3,
            w[2]
        );
    }
}

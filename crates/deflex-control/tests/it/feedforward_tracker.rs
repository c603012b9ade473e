//! The feed-forward tracker and its table ([`deflex_control::feedforward`]): arc length along a helix, acquiring and off-path states, the time index with lead, the pre-compensated mode, tables rotated into base axes and checked.

use deflex_control::feedforward::*;
use deflex_model::{Displacement, Pose, Robot};
use nalgebra::Vector3;
use nalgebra::{Rotation3, Translation3};
use std::f64::consts::PI;

/// A table point at `p` (world, m) with deflection `defl` and compensation −defl (position).
fn row(s: f64, t: f64, p: Vector3<f64>, defl: [f64; 6]) -> FeedForwardPoint {
    FeedForwardPoint {
        arc_length_m: s,
        time_s: t,
        desired_m: p,
        compensation: Displacement::new(-defl[0], -defl[1], -defl[2], 0.0, 0.0, 0.0),
        deflection: Displacement::from_row_slice(&defl),
    }
}

/// Points along a polyline at 10 mm/s; the deflection's z is the point's arc length (a
/// marker: 1 m of arc length ↦ 1 m of "deflection", scaled by 1e-3 to stay in bounds).
fn rows_along(points: &[Vector3<f64>]) -> Vec<FeedForwardPoint> {
    let mut s = 0.0;
    let mut out = Vec::new();
    for (i, p) in points.iter().enumerate() {
        if i > 0 {
            s += (p - points[i - 1]).norm();
        }
        out.push(row(s, s / 0.01, *p, [0.0, 0.0, s * 1e-3, 0.0, 0.0, 0.0]));
    }
    out
}

/// A helix of radius 20 mm, 0.24 mm down per turn, 5° steps: two turns.
fn helix() -> Vec<Vector3<f64>> {
    (0..=144)
        .map(|i| {
            let a = (i as f64 * 5.0).to_radians();
            Vector3::new(0.02 * a.cos(), 0.02 * a.sin(), -0.24e-3 * a / (2.0 * PI))
        })
        .collect()
}

fn robot() -> Robot {
    deflex_model::builtin("tx200").unwrap()
}

fn tracker(points: &[Vector3<f64>], config: FeedForwardConfig) -> FeedForward {
    let table = FeedForwardTable::from_points(&rows_along(points), &robot()).unwrap();
    FeedForward::new(table, config).unwrap()
}

/// Arc length of the helix at angle `a` (rad).
fn helix_s(a: f64) -> f64 {
    let pitch = 0.24e-3 / (2.0 * PI);
    a * (0.02f64.powi(2) + pitch * pitch).sqrt()
}

#[test]
fn tracking_follows_the_turn_it_is_on_even_far_below_it() {
    // The TCP runs the helix 2 mm below it (a compensated robot pushing into the sheet): the
    // next turn is 0.24 mm further down, far closer than the path, yet the arc length
    // follows the turn the robot is on.
    let points = helix();
    let mut ff = tracker(&points, FeedForwardConfig::default());
    let mut previous = f64::NEG_INFINITY;
    for k in 0..=700 {
        let a = k as f64 * 0.5f64.to_radians() * 1.02;
        let a = a.min(4.0 * PI);
        let p = Vector3::new(0.02 * a.cos(), 0.02 * a.sin(), -0.24e-3 * a / (2.0 * PI))
            + Vector3::new(0.0, 0.0, -2e-3);
        let step = ff.update(&p, k as f64 * 0.01);
        assert_eq!(step.state, TrackState::OnPath, "{k}");
        // Between chord and arc: within the 5° polyline's sagitta (15 µm) plus the chord's
        // shortening of the arc length (2 µm per 5°).
        let expected = helix_s(a);
        assert!(
            (step.path_s_m - expected).abs() < 0.05e-3,
            "{k}: {} vs {expected}",
            step.path_s_m
        );
        assert!(step.path_s_m >= previous);
        previous = step.path_s_m;
        // Feed-forward mode: the prior is minus the deflection there (the marker).
        assert!((step.prior[2] + step.path_s_m * 1e-3).abs() < 1e-9);
        assert_eq!(step.prior, step.sent);
    }
}

#[test]
fn acquiring_off_the_path_and_after_the_end() {
    let points = helix();
    let config = FeedForwardConfig {
        max_offset_m: 1e-3,
        ..FeedForwardConfig::default()
    };
    let mut ff = tracker(&points, config);
    // An approach from 30 mm above: acquiring, no prior.
    let above = points[0] + Vector3::new(0.0, 0.0, 0.03);
    let step = ff.update(&above, 0.0);
    assert_eq!(step.state, TrackState::Acquiring);
    assert_eq!(step.prior, [0.0; 6]);
    assert!(step.path_s_m.is_nan());
    // A point of the path's second turn is not where the path starts: still acquiring.
    let step = ff.update(&points[80], 0.01);
    assert_eq!(step.state, TrackState::Acquiring);
    // At the start: locked.
    let step = ff.update(&(points[0] + Vector3::new(0.0, 0.0, 0.5e-3)), 0.02);
    assert_eq!(step.state, TrackState::OnPath);
    assert!(step.path_s_m < 1e-6);
    // Along the first points, then 3 mm off: off the path, the arc length is kept.
    let mut s = 0.0;
    for p in &points[1..5] {
        s = ff.update(p, 0.03).path_s_m;
    }
    let off = ff.update(&(points[5] + Vector3::new(0.003, 0.0, 0.0)), 0.04);
    assert_eq!(off.state, TrackState::OffPath);
    assert_eq!(off.prior, [0.0; 6]);
    assert_eq!(off.path_s_m, s);
    // Back on: locks on again.
    let back = ff.update(&points[6], 0.05);
    assert_eq!(back.state, TrackState::OnPath);
    assert!((back.path_s_m - helix_s(6.0 * 5f64.to_radians())).abs() < 0.05e-3);
    // Run to the end and beyond along the tangent.
    for p in &points[7..] {
        ff.update(p, 0.06);
    }
    let end = *points.last().unwrap();
    let length = ff.table().length_m();
    let near = ff.update(&(end + Vector3::new(0.0, 0.5e-3, 0.0)), 0.07);
    assert_eq!(near.state, TrackState::OnPath);
    assert!((near.path_s_m - length).abs() < 1e-12);
    assert!((near.prior[2] + length * 1e-3).abs() < 1e-12);
    let gone = ff.update(&(end + Vector3::new(0.0, 5e-3, 0.0)), 0.08);
    assert_eq!(gone.state, TrackState::OffPath);
    assert_eq!(gone.prior, [0.0; 6]);
}

#[test]
fn time_index_lead_and_precompensated_mode() {
    let line: Vec<Vector3<f64>> = (0..=20)
        .map(|i| Vector3::new(1.5 + i as f64 * 1e-3, 0.0, -0.18))
        .collect();
    // Time index from the start at t0 = 2 s, table time offset 0.1 s: at controller time
    // 2.5 s the table is at 0.6 s, i.e. 6 mm along.
    let config = FeedForwardConfig {
        index: PathIndex::Time,
        time_offset_s: 0.1,
        lead_s: 0.3,
        ..FeedForwardConfig::default()
    };
    let mut ff = tracker(&line, config);
    assert_eq!(
        ff.update(&line[0], 1.0).state,
        TrackState::Acquiring,
        "not started"
    );
    ff.start(2.0);
    ff.start(3.0); // only the first start sets the origin
    let p = Vector3::new(1.506, 0.0, -0.18);
    let step = ff.update(&p, 2.5);
    assert_eq!(step.state, TrackState::OnPath);
    assert!((step.path_s_m - 0.006).abs() < 1e-12);
    assert!((step.prior[2] + 0.006e-3).abs() < 1e-15);
    // The feed-forward sent is 0.3 s (3 mm) ahead.
    assert!((step.sent[2] + 0.009e-3).abs() < 1e-15);
    // A robot that stopped: the time runs on, the TCP is left behind → off the path.
    assert_eq!(ff.update(&p, 3.5).state, TrackState::OffPath);
    // Pre-compensated: the prior is the program's compensation, nothing is sent.
    let mut pre = tracker(
        &line,
        FeedForwardConfig {
            mode: FeedForwardMode::Precompensated,
            ..FeedForwardConfig::default()
        },
    );
    let step = pre.update(&Vector3::new(1.5035, 0.0, -0.18), 0.0);
    // (the commanded polyline is 3.5 µm below the desired one there)
    assert!((step.path_s_m - 0.0035).abs() < 1e-7, "{step:?}");
    // compensation = −deflection (the rows above)
    assert!((step.prior[2] + 0.0035e-3).abs() < 1e-10);
    assert_eq!(step.sent, [0.0; 6]);
}

#[test]
fn time_lookup_from_any_hint_matches_a_plain_search() {
    // Times with repeats (zero-length moves) and uneven steps.
    let line: Vec<Vector3<f64>> = (0..200)
        .map(|i| {
            Vector3::new(
                1.5 + (i / 2) as f64 * 1e-3 * (1.0 + (i % 7) as f64),
                0.0,
                0.0,
            )
        })
        .collect();
    let ff = tracker(&line, FeedForwardConfig::default());
    let t = ff.table().times_s();
    let plain = |ts: f64| {
        let last = t.len() - 1;
        t.partition_point(|v| *v <= ts).clamp(1, last) - 1
    };
    let duration = ff.table().duration_s();
    for j in 0..400 {
        let ts = -1.0 + (duration + 2.0) * j as f64 / 399.0;
        for hint in [0, 1, 17, 100, 198, 199, 500] {
            let (k, u) = ff.table().locate_time(ts, hint);
            assert_eq!(k, plain(ts), "t {ts} hint {hint}");
            assert!((0.0..=1.0).contains(&u));
        }
    }
    assert_eq!(ff.table().locate_time(f64::NAN, 50), (0, 0.0));
}

#[test]
fn tables_are_rotated_into_base_axes_and_checked() {
    let line: Vec<Vector3<f64>> = (0..=4)
        .map(|i| Vector3::new(i as f64 * 1e-3, 0.0, 0.0))
        .collect();
    let mut rows = rows_along(&line);
    rows[2].deflection = Displacement::new(1e-3, 0.0, 0.0, 0.0, 0.0, 2e-3);
    // A base turned 90° about z: world x is base −y... base axes = R_baseᵀ · world.
    let mut turned = robot();
    turned.base = Pose::from_parts(
        Translation3::new(0.0, 0.0, 0.0),
        Rotation3::from_axis_angle(&Vector3::z_axis(), PI / 2.0),
    );
    let table = FeedForwardTable::from_points(&rows, &turned).unwrap();
    let d = table.deflections()[2];
    assert!((d[0]).abs() < 1e-15 && (d[1] + 1e-3).abs() < 1e-15, "{d:?}");
    assert!((d[5] - 2e-3).abs() < 1e-15);
    // Each failure names the point and the quantity (the runtime turns them into the file's
    // line and column: deflex-runtime's feed-forward loading tests).
    let fails =
        |rows: Vec<FeedForwardPoint>| FeedForwardTable::from_points(&rows, &robot()).unwrap_err();
    let mut bad = rows_along(&line);
    bad[3].time_s = 0.0;
    assert_eq!(
        fails(bad),
        FeedForwardError::NotMonotone {
            point: 3,
            column: FeedForwardColumn::Time,
            value: 0.0,
            previous: 0.2
        }
    );
    let mut bad = rows_along(&line);
    bad[1].deflection[4] = 0.5;
    let e = fails(bad);
    assert!(
        matches!(e, FeedForwardError::OutOfBounds { point: 1, column: FeedForwardColumn::Deflection(4), value, .. } if value == 0.5),
        "{e:?}"
    );
    assert!(e.to_string().contains("point 1: deflection ry"), "{e}");
    let mut bad = rows_along(&line);
    bad[1].compensation[0] = -0.2;
    assert!(matches!(
        fails(bad),
        FeedForwardError::OutOfBounds {
            point: 1,
            column: FeedForwardColumn::Compensation(0),
            ..
        }
    ));
    let e = fails(rows_along(&line[..1]));
    assert!(e.to_string().contains("at least two rows"), "{e}");
    let config = FeedForwardConfig {
        window_m: 0.0,
        ..FeedForwardConfig::default()
    };
    let table = FeedForwardTable::from_points(&rows_along(&line), &robot()).unwrap();
    let e = FeedForward::new(table, config).unwrap_err().to_string();
    assert!(e.contains("feedforward.window_m"), "{e}");
}

use deflex_app::report::{MAX_POINTS, thin_series, write_run_figures};
use deflex_record::trace::{RunTrace, Xyz};

fn trace(label: &str, n: usize, speed: f64) -> RunTrace {
    let time_s: Vec<f64> = (0..n).map(|i| i as f64 * 0.02).collect();
    let s: Vec<f64> = time_s.iter().map(|t| t * speed).collect();
    let wave = |k: f64| s.iter().map(|s| (s * k).sin()).collect::<Vec<f64>>();
    RunTrace {
        label: label.into(),
        file: format!("{label}.csv"),
        kind: "test".into(),
        simulated: true,
        path_s_m: Some(s.clone()),
        force_n: Xyz {
            x: wave(100.0),
            y: wave(50.0),
            z: wave(20.0).iter().map(|v| -500.0 + 100.0 * v).collect(),
        },
        axes: "base axes".into(),
        correction_m: Some(Xyz {
            x: vec![0.0; n],
            y: vec![0.0; n],
            z: wave(10.0).iter().map(|v| v * 1e-3).collect(),
        }),
        deflection_m: None,
        path_error_m: Some(Xyz {
            x: vec![1e-4; n],
            y: vec![0.0; n],
            z: vec![f64::NAN; n],
        }),
        states: vec![("running".into(), (0..n).map(|i| i > n / 10).collect())],
        cycle_time_s: None,
        time_s,
    }
}

#[test]
fn two_runs_overlay_on_path_position_in_one_page() {
    let dir = std::env::temp_dir().join(format!("deflex-run-figures-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // Same path at two speeds: 10 mm/s and 12 mm/s.
    let out = write_run_figures(
        &dir,
        &[
            trace("open loop", 500, 0.010),
            trace("closed loop", 400, 0.012),
        ],
    )
    .unwrap();
    assert!(out.by_path_position);
    let names: Vec<String> = out
        .figures
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into())
        .collect();
    assert_eq!(
        names,
        [
            "forces.png",
            "correction.png",
            "path_error.png",
            "state.png"
        ]
    );
    let html = std::fs::read_to_string(&out.page).unwrap();
    assert!(html.contains("open loop vs closed loop"));
    assert!(html.contains("SIMULATED"));
    assert_eq!(html.matches("data:image/png;base64,").count(), 4);
    // Without a path position, by time.
    let mut t = trace("run", 100, 0.01);
    t.path_s_m = None;
    assert!(!write_run_figures(&dir, &[t]).unwrap().by_path_position);
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn mismatched_columns_and_run_counts_are_errors() {
    let dir = std::env::temp_dir();
    let mut t = trace("short", 50, 0.01);
    t.force_n.z.pop();
    let e = write_run_figures(&dir, &[t]).unwrap_err().to_string();
    assert!(e.contains("force") && e.contains("short.csv"), "{e}");
    let e = write_run_figures(&dir, &[]).unwrap_err().to_string();
    assert!(e.contains("0 runs"), "{e}");
}

#[test]
fn thinning_keeps_spikes() {
    let n = 200_000;
    let x: Vec<f64> = (0..n).map(|i| i as f64).collect();
    let mut y = vec![0.0; n];
    y[123_457] = 9.0;
    y[77_777] = -4.0;
    let (tx, ty) = thin_series(&x, &y);
    assert!(tx.len() <= MAX_POINTS + 2);
    assert!(ty.contains(&9.0) && ty.contains(&-4.0));
    assert!(tx.windows(2).all(|w| w[1] >= w[0]));
}

//! Any run log read as a trace: a `deflex sim isf` log, a `deflex run` CSV log (its path column,
//! or the arc length of the program TCP from the robot model), a recording; the errors name the
//! file, the line and the column.

use deflex_model::Data;
use deflex_record::trace::{arc_length, read_run_log};
use deflex_telemetry::CycleSample;
use nalgebra::Vector3;

fn dir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("deflex-trace-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn a_sim_isf_log_gives_arc_length_and_millimetres_in_metres() {
    let d = dir("isf");
    let p = d.join("log.csv");
    let header = "time_s,des_x_mm,des_y_mm,des_z_mm,err_x_mm,err_y_mm,err_z_mm,fx_N,fy_N,fz_N,\
                  corr_x_mm,corr_y_mm,corr_z_mm,penetration_mm,sensor_saturated";
    std::fs::write(
        &p,
        format!(
            "# SIMULATED deflex digital twin forming log\n{header}\n\
             0.00,0,0,0,0.1,0,0,1,2,3,0,0,0.5,0,0\n\
             0.02,3,4,0,0.2,0,0,1,2,300,0,0,0.6,0.1,0\n\
             0.04,3,4,-12,0.3,0,0,1,2,400,0,0,0.7,0.2,1\n"
        ),
    )
    .unwrap();
    let t = read_run_log(&p, "open", None).unwrap();
    assert!(t.simulated);
    assert_eq!(t.path_s_m.as_ref().unwrap(), &[0.0, 0.005, 0.017]);
    assert_eq!(t.force_n.z, [3.0, 300.0, 400.0]);
    assert!((t.correction_m.as_ref().unwrap().z[1] - 0.6e-3).abs() < 1e-15);
    assert!((t.path_error_m.as_ref().unwrap().x[2] - 0.3e-3).abs() < 1e-15);
    assert_eq!(t.states[0].1, [false, true, true]);
    assert_eq!(t.states[1].1, [false, false, true]);
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn a_run_log_uses_its_path_column_or_none() {
    let d = dir("run");
    let p = d.join("run.csv");
    let mut header = deflex_record::run_log::RunLogFormat::cell(2).header();
    header.push('\n');
    let row = |t: f64, s: &str| {
        let mut cells = vec![format!("{t}"), "0.1".into(), "0.2".into()];
        cells.extend(std::iter::repeat_n("0".to_string(), 18)); // raw, ws, w
        cells.extend(std::iter::repeat_n("0.001".to_string(), 24)); // ds, xi, eps, ff
        cells.extend([
            s.to_string(),
            String::new(),
            "350.5".into(),
            "1048576".into(),
            "active".into(),
        ]);
        cells.join(",") + "\n"
    };
    std::fs::write(&p, header.clone() + &row(0.0, "0.0") + &row(0.01, "0.0001")).unwrap();
    let t = read_run_log(&p, "run", None).unwrap();
    assert_eq!(t.path_s_m.unwrap(), [0.0, 0.0001]);
    assert_eq!(t.cycle_time_s.unwrap(), [350.5e-6, 350.5e-6]);
    assert!(
        t.states
            .iter()
            .any(|(n, on)| n.starts_with("correcting") && on.iter().all(|b| *b))
    );
    std::fs::write(&p, header + &row(0.0, "") + &row(0.01, "")).unwrap();
    assert!(read_run_log(&p, "run", None).unwrap().path_s_m.is_none());
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn a_run_log_with_a_robot_gets_the_program_arc_length() {
    let d = dir("fk");
    let p = d.join("run.csv");
    let robot = deflex_model::builtin("tx200").unwrap();
    let n = robot.joint_count();
    let mut text = deflex_record::run_log::RunLogFormat::cell(n).header() + "\n";
    let mut data = Data::new();
    let mut expected = Vec::new();
    let mut previous: Option<Vector3<f64>> = None;
    let mut s = 0.0;
    for k in 0..5 {
        let q: Vec<f64> = (0..n)
            .map(|j| 0.3 + 0.01 * k as f64 * (j as f64 + 1.0))
            .collect();
        let xi = [0.001 * k as f64, 0.0, -0.0005 * k as f64];
        robot.forward_kinematics(&mut data, &q).unwrap();
        let program = data.tcp_position() - Vector3::from(xi);
        if let Some(prev) = previous {
            s += (program - prev).norm();
        }
        previous = Some(program);
        expected.push(s);
        let mut cells = vec![format!("{}", k as f64 * 0.01)];
        cells.extend(q.iter().map(|v| format!("{v:.12}")));
        cells.extend(std::iter::repeat_n("0".to_string(), 18));
        cells.extend(std::iter::repeat_n("0".to_string(), 6)); // ds
        cells.extend(xi.iter().map(|v| format!("{v}")));
        cells.extend(std::iter::repeat_n("0".to_string(), 3 + 12)); // xi rot, eps, ff
        cells.extend([
            String::new(),
            String::new(),
            "300".into(),
            "0".into(),
            String::new(),
        ]);
        text += &(cells.join(",") + "\n");
    }
    std::fs::write(&p, text).unwrap();
    let t = read_run_log(&p, "fk", Some(&robot)).unwrap();
    for (a, b) in t.path_s_m.unwrap().iter().zip(&expected) {
        assert!((a - b).abs() < 1e-9, "{a} {b}");
    }
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn bad_and_foreign_files_name_the_place() {
    let d = dir("bad");
    let p = d.join("x.csv");
    std::fs::write(&p, "a,b,c\n1,2,3\n").unwrap();
    let e = read_run_log(&p, "x", None).unwrap_err().to_string();
    assert!(
        e.contains("x.csv") && e.contains("line 1") && e.contains("not a deflex log"),
        "{e}"
    );
    std::fs::write(
        &p,
        "# SIMULATED\ntime_s,des_x_mm,des_y_mm,des_z_mm,err_x_mm,err_y_mm,err_z_mm,fx_N,fy_N,fz_N,corr_x_mm,corr_y_mm,corr_z_mm,penetration_mm\n\
         0,0,0,0,0,0,0,0,0,0,0,0,0,0\n0.02,1,oops,0,0,0,0,0,0,0,0,0,0,0\n",
    )
    .unwrap();
    let e = read_run_log(&p, "x", None).unwrap_err().to_string();
    assert!(
        e.contains("line 4, column des_y_mm") && e.contains("\"oops\""),
        "{e}"
    );
    std::fs::write(&p, "time_s,des_x_mm\n0,0\n0,0,0\n").unwrap();
    let e = read_run_log(&p, "x", None).unwrap_err().to_string();
    assert!(e.contains("x.csv: line 3"), "{e}");
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn a_recording_reads_as_a_trace() {
    let d = dir("mcap");
    let p = d.join("run.mcap");
    let mut cell = deflex_telemetry::synthetic::SyntheticCell::new(0.01, 2, true);
    let info = cell.session_info();
    let mut sink = deflex_record::McapSink::new(
        Vec::new(),
        "mem",
        &info,
        deflex_record::RecordOptions::default(),
    )
    .unwrap();
    let samples: Vec<CycleSample> = (0..300).map(|_| cell.next_sample()).collect();
    for s in &samples {
        sink.write(s).unwrap();
    }
    std::fs::write(&p, sink.finish().unwrap().0).unwrap();
    let t = read_run_log(&p, "rec", None).unwrap();
    assert!(t.simulated);
    assert_eq!(t.time_s.len(), 300);
    let expected = arc_length(samples.iter().map(|s| s.program_position_m()));
    assert_eq!(t.path_s_m.unwrap(), expected);
    // A helix of 40 mm radius at 1 rad/s for 3 s: about 120 mm.
    assert!(
        (expected[299] - 0.04 * 2.99).abs() < 1e-3,
        "{}",
        expected[299]
    );
    assert!(t.path_error_m.is_some());
    let _ = std::fs::remove_dir_all(d);
}

//! The joint path of a FANUC Stream Motion link from `deflex compensate`'s table: a compensated
//! cone on a built-in six-axis arm, its joints streamed from the table's first to its last row.

use deflex_app::cell::stream_path::{StreamPathError, stream_trajectory_of};
use deflex_app::compensate::*;
use deflex_app::option_names::OptionNames;
use deflex_app::table::{TableColumn, parse};
use deflex_io::fanuc_stream::motion::{SMOOTHING_CYCLES, StreamLimits};

/// The arm streamed: a built-in six-axis arm (the FANUC-like built-in arm, once there, is a
/// one-line change here).
const ARM: &str = "kr210-r2700";
const T: f64 = 0.008;

fn table() -> String {
    let options = Options {
        length_mm: Some(20.0),
        ..Options::default()
    };
    let robot = RobotChoice::load("--robot", ARM).unwrap();
    let s = setup(
        robot,
        &PathSpec::named("cone"),
        WrenchSpec::Process,
        &options,
        OptionNames::Cli,
    )
    .unwrap();
    table_csv(&compensate(s, &mut |_| {}).unwrap())
}

fn column<'a>(t: &'a deflex_app::table::CsvTable, name: &str) -> &'a [f64] {
    match &t.columns.iter().find(|(n, _)| n == name).unwrap().1 {
        TableColumn::Number(v) => v,
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_compensated_path_streams_from_its_first_to_its_last_joints() {
    let text = table();
    let t = parse(&text, "compensated_path.csv").unwrap();
    let limits = StreamLimits::uniform(2.0, 10.0, 200.0).scaled(0.75);
    let traj = stream_trajectory_of(&t, "compensated_path.csv", T, 0.3, &limits).unwrap();
    let time = column(&t, "t_s");
    let span = time[t.rows - 1] - time[0];
    let held = 6.0 * (SMOOTHING_CYCLES / 2) as f64 * T;
    assert!((traj.duration_s() - (span + 0.3 + held)).abs() < T);
    let first = traj.points()[0];
    let last = traj.points()[traj.len() - 1];
    for (i, name) in ["q1_rad", "q2_rad", "q3_rad", "q4_rad", "q5_rad", "q6_rad"]
        .iter()
        .enumerate()
    {
        let q = column(&t, name);
        assert!((first[i] - q[0]).abs() < 1e-12, "{name}");
        assert!((last[i] - q[t.rows - 1]).abs() < 1e-12, "{name}");
        // Every sample within the joints the table visits.
        let (lo, hi) = q
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(*v), b.max(*v)));
        assert!(
            traj.points()
                .iter()
                .all(|p| p[i] >= lo - 1e-12 && p[i] <= hi + 1e-12)
        );
    }
}

#[test]
fn a_failed_point_or_another_arm_is_not_streamed() {
    let text = table();
    let limits = StreamLimits::uniform(2.0, 10.0, 200.0);
    // The last point's status says the compensation failed there.
    let cut = text.trim_end().rfind(",ok").unwrap();
    let failed = format!("{},unreachable\n", &text[..cut]);
    let t = parse(&failed, "f.csv").unwrap();
    match stream_trajectory_of(&t, "f.csv", T, 0.3, &limits) {
        Err(StreamPathError::NotCompensated { index, status, .. }) => {
            assert_eq!(index, t.rows - 1);
            assert_eq!(status, "unreachable");
        }
        other => panic!("{other:?}"),
    }
    // A seven-joint table.
    let seven = "t_s,q1_rad,q2_rad,q3_rad,q4_rad,q5_rad,q6_rad,q7_rad,status\n\
                 0,0,0,0,0,0,0,0,ok\n1,0,0,0,0,0,0,0,ok\n";
    let t = parse(seven, "7.csv").unwrap();
    assert!(matches!(
        stream_trajectory_of(&t, "7.csv", T, 0.3, &limits),
        Err(StreamPathError::JointCount { joints: 7, .. })
    ));
    // Too fast for the limits: the axis is named.
    let fast = "t_s,q1_rad,q2_rad,q3_rad,q4_rad,q5_rad,q6_rad,status\n\
                0,0,0,0,0,0,0,ok\n0.1,0,0,1,0,0,0,ok\n";
    let t = parse(fast, "fast.csv").unwrap();
    let e = stream_trajectory_of(&t, "fast.csv", T, 0.05, &limits).unwrap_err();
    assert!(e.to_string().starts_with("fast.csv: axis 3"), "{e}");
}

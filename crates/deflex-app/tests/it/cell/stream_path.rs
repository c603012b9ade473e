//! The joint path of a FANUC Stream Motion link from `deflex compensate`'s table: a compensated
//! cone on a built-in six-axis arm, its joints streamed from the table's first to its last row.

use deflex_app::cell::stream_path::{StreamPathError, stream_trajectory_of};
use deflex_app::compensate::*;
use deflex_app::option_names::OptionNames;
use deflex_app::table::{TableColumn, parse};
use deflex_io::fanuc_stream::motion::{SMOOTHING_CYCLES, StreamLimits};

/// The arm streamed: the FANUC-like built-in arm.
const ARM: &str = "r2000ic-165f";
const T: f64 = 0.008;

/// `compensated_path.csv` of `deflex compensate --robot ARM --path cone --length-mm L` (the
/// twin's process model), in memory; the Stream Motion twin tests stream it too.
pub(crate) fn compensated_cone(arm: &str, length_mm: f64) -> String {
    let options = Options {
        length_mm: Some(length_mm),
        ..Options::default()
    };
    let robot = RobotChoice::load("--robot", arm).unwrap();
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

fn table() -> String {
    compensated_cone(ARM, 20.0)
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

/// `kind = "fanuc-stream"` in a CELL.toml: the controller's address and the path are required
/// (each error names its field), and the link it opens streams the table's joints to a
/// controller at `robot.peer`.
#[test]
fn a_cell_file_opens_a_stream_motion_link() {
    use deflex_app::cell::config::CellFile;
    use deflex_io::fanuc_stream::robot::FanucStreamRobotEndpoint;
    use deflex_io::{RobotSideLink, RobotState};
    use std::time::Duration;
    let dir = std::env::temp_dir().join(format!("deflex-stream-cell-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = table();
    std::fs::write(dir.join("compensated_path.csv"), &text).unwrap();
    let t = parse(&text, "t").unwrap();
    let q0: [f64; 6] = std::array::from_fn(|i| column(&t, &format!("q{}_rad", i + 1))[0]);
    let limits = StreamLimits::uniform(2.0, 10.0, 200.0);
    let mut robot = FanucStreamRobotEndpoint::bind("127.0.0.1:0", T, limits).unwrap();
    let cell = |extra: &str| {
        format!(
            "[robot]\nkind = \"fanuc-stream\"\nbind = \"127.0.0.1:0\"\ncycle_s = 0.008\n\
             timeout_s = 0.5\nstream_velocity_rad_s = [2.0, 2.0, 2.0, 2.0, 2.0, 2.0]\n{extra}\
             [sensor]\nkind = \"netft\"\naddress = \"127.0.0.1:49152\"\n[model]\nfile = \"{ARM}\"\n"
        )
    };
    let peer = format!("peer = \"{}\"\n", robot.local_addr().unwrap());
    let path = "stream_path = \"compensated_path.csv\"\n";
    for (extra, field) in [
        (path.to_string(), "robot.peer"),
        (peer.clone(), "robot.stream_path"),
    ] {
        let e = CellFile::parse(&cell(&extra), "cell.toml", dir.clone())
            .unwrap_err()
            .to_string();
        assert!(e.contains(field), "{e}");
    }
    let file = CellFile::parse(&cell(&format!("{peer}{path}")), "cell.toml", dir.clone()).unwrap();
    let traj = file.stream_trajectory().unwrap();
    assert_eq!(traj.period_s(), T);
    // The late-status rule: five cycles by default, `robot.stream_late_after_s` when given.
    assert_eq!(
        file.stream_config().unwrap().late_after,
        Duration::from_secs_f64(5.0 * T)
    );
    let late = CellFile::parse(
        &cell(&format!("{peer}{path}stream_late_after_s = 0.25\n")),
        "cell.toml",
        dir.clone(),
    )
    .unwrap();
    assert_eq!(
        late.stream_config().unwrap().late_after,
        Duration::from_millis(250)
    );
    // The robot side the twin plays listens at the peer with the file's cycle and limits.
    let side = file.robot_side(6).stream.unwrap();
    assert_eq!(side.address, robot.local_addr().unwrap());
    assert_eq!((side.period_s, side.limits), (T, file.stream_limits()));
    let mut link = file.open_robot_link(6).unwrap();
    assert!(link.answers_in_joint_space());
    // The robot stands at the path's start: the first commands hold it there.
    assert!(link.receive(Duration::from_millis(1)).unwrap().is_none());
    for _ in 0..3 {
        robot.send_state(&RobotState::with_joints(&q0)).unwrap();
        let s = link.receive(Duration::from_secs(2)).unwrap().unwrap();
        assert_eq!(s.joint_count, 6);
        link.send_joint_correction(&[0.0; 6]).unwrap();
        assert!(
            robot
                .receive_correction(Duration::from_secs(2))
                .unwrap()
                .is_some()
        );
        let c = robot.commanded_rad().unwrap();
        for i in 0..6 {
            assert!((c[i] - q0[i]).abs() < 1e-4, "axis {i}");
        }
    }
    assert_eq!(robot.counts().1, 0);
    let _ = std::fs::remove_dir_all(&dir);
}

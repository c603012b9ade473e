//! Every built-in robot's twin cell: its forming pose reaches the part origin with the tool
//! pointing down and keeps the arm clear of the floor and of the part's plane (the UR10e's
//! elbow once sat 174 mm below its mounting plane).

use deflex_sim::CellConfig;
use deflex_sim::profile::POSE_CLEARANCE_M;

#[test]
fn every_cell_has_a_clear_forming_pose() {
    for robot in ["tx200", "ur10", "ur10e", "kr210-r2700", "irb4600"] {
        let cell = CellConfig::for_robot(robot).unwrap();
        let summary = cell.summary().unwrap();
        println!("{summary}");
        assert!(
            summary.clearance_m >= POSE_CLEARANCE_M - 1e-9,
            "{robot}: {:.1} mm",
            summary.clearance_m * 1e3
        );
        // The forming pose puts the TCP on the part origin with the tool pointing down (check:
        // the model's FK, the tool z axis against −z).
        let nominal = cell.nominal_robot().unwrap();
        let tcp = nominal
            .tcp_pose(&summary.forming_q_deg.map(f64::to_radians))
            .unwrap();
        let origin = nalgebra::Vector3::from(cell.part.origin_mm) * 1e-3;
        assert!((tcp.translation.vector - origin).norm() < 1e-6, "{robot}");
        let axis = tcp.rotation * nalgebra::Vector3::z();
        assert!(axis.z < -0.999, "{robot}: tool axis {axis:?}");
        // The part is above the floor.
        assert!(
            cell.part.origin_mm[2] * 1e-3 - 0.02 >= summary.floor_z_m + POSE_CLEARANCE_M - 1e-9,
            "{robot}"
        );
        let text = summary.to_string();
        assert!(
            text.contains("--part-xyz-mm") && text.contains("--seed-deg"),
            "{text}"
        );
    }
}

//! Every built-in robot's twin cell: its forming pose reaches the part origin with the tool
//! pointing down and keeps the arm clear of the floor and of the part's plane (the UR10e's
//! elbow once sat 174 mm below its mounting plane).

use deflex_sim::CellConfig;
use deflex_sim::profile::POSE_CLEARANCE_M;

#[test]
fn every_cell_has_a_clear_forming_pose() {
    for robot in [
        "tx200",
        "ur10",
        "ur10e",
        "kr210-r2700",
        "irb4600",
        "r2000ic-165f",
        "gp180",
    ] {
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

/// The FANUC-like and the Motoman-like built-ins: the model's tool is the twin cell's (a user
/// finds one TCP: `deflex model show`, `compensate` and `sim` agree), and the twin plant's own
/// chain (deflex-sim's product of exponentials, no deflex-model kinematics) puts the unloaded
/// TCP where the model does.
#[test]
fn fanuc_and_motoman_cells_use_the_models_tool() {
    for robot in ["r2000ic-165f", "gp180"] {
        let model = deflex_model::builtin(robot).unwrap();
        let cell = CellConfig::for_robot(robot).unwrap();
        let tool = cell.tool();
        assert!(
            (tool.translation.vector - model.tool.translation.vector).norm() < 1e-12
                && tool.rotation == model.tool.rotation,
            "{robot}: the cell's tool {tool:?}, the model's {:?}",
            model.tool
        );
        let nominal = cell.nominal_robot().unwrap();
        assert_eq!(nominal.tool, model.tool, "{robot}");
        assert_eq!(nominal.base_pivot, model.base_pivot, "{robot}");
        let chain = deflex_sim::chain::Chain::new(
            &nominal,
            &deflex_sim::chain::GeometryErrors::default(),
            &[],
            &[0.0; 6],
            &nalgebra::Vector3::zeros(),
            &nominal.flange,
        );
        let mut state = deflex_sim::chain::ChainState::default();
        for q in [
            [0.0; 6],
            [0.3, -0.4, 1.1, 0.7, -0.9, 2.0],
            [-2.0, 1.2, -0.5, -1.5, 1.7, -0.3],
        ] {
            chain.evaluate(&q, &[], &mut state);
            let model_tcp = nominal.tcp_pose(&q).unwrap();
            assert!(
                (state.tcp.translation.vector - model_tcp.translation.vector).norm() < 1e-10
                    && (state.tcp.rotation.matrix() - model_tcp.rotation.matrix()).norm() < 1e-10,
                "{robot} at {q:?}: {:?} vs {:?}",
                state.tcp,
                model_tcp
            );
        }
    }
}

use deflex_model::*;
use deflex_sim::CellConfig;
use deflex_sim::plant::*;
fn main() {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse().unwrap())
        .collect();
    let cell = CellConfig::default();
    let robot = cell.nominal_robot().unwrap();
    let mut config = cell.plant.clone();
    if args.len() >= 6 {
        config.joint_stiffness[0][2] = args[0];
        config.joint_stiffness[1][2] = args[1];
        config.joint_stiffness[2][0] = args[2];
        config.joint_stiffness[2][2] = args[3];
        config.joint_stiffness[3][2] = args[4];
        config.joint_stiffness[4][2] = args[5];
    }
    let mut plant = Plant::new(&config, &robot, &Pose::identity(), true).unwrap();
    let part = cell.part_frame();
    let q0 = cell.seed_q_rad();
    let rot = robot.tcp_pose(&q0).unwrap().rotation;
    let mut worst: f64 = 0.0;
    let mut zmax: f64 = 0.0;
    for k in 0..36 {
        let th = k as f64 * 10f64.to_radians();
        let r = 0.005;
        let p =
            part.translation.vector + nalgebra::Vector3::new(r * th.cos(), r * th.sin(), -0.015);
        let sol = robot
            .inverse_kinematics(&Pose::from_parts(p.into(), rot), &q0, &IkOptions::default())
            .unwrap();
        let mut q = [0.0; 6];
        q.copy_from_slice(&sol.q);
        plant.set_configuration(&q);
        let fz = 1250.0;
        let inward = nalgebra::Vector3::new(-th.cos(), -th.sin(), 0.0);
        let feed = nalgebra::Vector3::new(-th.sin(), th.cos(), 0.0);
        let f = inward * 0.36 * fz - feed * 0.12 * fz + nalgebra::Vector3::new(0.0, 0.0, fz);
        let d = plant.solve_tcp(&Wrench::new(f.x, f.y, f.z, 0.0, 0.0, 0.0));
        let dp = d.fixed_rows::<3>(0).norm();
        worst = worst.max(dp);
        zmax = zmax.max(d[2]);
        if k % 9 == 0 {
            println!(
                "θ {:3.0}: δ = {:.3} {:.3} {:.3} mm",
                th.to_degrees(),
                d[0] * 1e3,
                d[1] * 1e3,
                d[2] * 1e3
            );
        }
    }
    println!(
        "max |δp| {:.3} mm, max δz {:.3} mm",
        worst * 1e3,
        zmax * 1e3
    );
}

//! Offline compensation of a tool path: a 60 mm circle pressed 2 mm into a surface on the
//! paper's TX200. The process pushes the tool back up with a force proportional to how deep
//! the commanded tool lies (SIMULATED process, 500 N/mm); deflex finds the commanded path whose
//! deflected tool lands on the desired circle (commanded = desired − δs(commanded), iterated).
//!
//! `cargo run -p deflex --example compensate_path`
use deflex::compensate::{
    CompensationOptions, DepthProportional, TcpPath, WrenchSource, compensate,
};
use deflex::{Pose, builtin};
use nalgebra::{Translation3, Vector3};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let robot = builtin("tx200").ok_or("tx200 is a built-in robot")?;
    let seed: Vec<f64> = [0.0, 49.7, 89.3, 0.0, 41.0, 0.0]
        .iter()
        .map(|d: &f64| d.to_radians())
        .collect();
    let centre = robot.tcp_pose(&seed)?;
    let depth_m = 0.002;
    let surface_m = centre.translation.vector.z + depth_m;
    // 360 points on a 30 mm radius circle around the seed's TCP, tool orientation held, 20 mm/s.
    let poses = (0..=360).map(|i| {
        let a = (i as f64).to_radians();
        let offset = Vector3::new(0.03 * a.cos() - 0.03, 0.03 * a.sin(), 0.0);
        let pose = Pose::from_parts(
            Translation3::from(centre.translation.vector + offset),
            centre.rotation,
        );
        (pose, Some(0.02))
    });
    let path = TcpPath::new("circle 60 mm", poses, 0.25)?;
    let mut process = DepthProportional {
        direction: Vector3::z(),
        surface_m,
        stiffness_n_m: 5.0e5,
    };
    let result = compensate(
        &robot,
        &path,
        &seed,
        WrenchSource::Process(&mut process),
        &CompensationOptions::default(),
        &mut |_| {},
    )?;
    println!(
        "{} points, process: {} (SIMULATED)",
        path.len(),
        result.source
    );
    for it in &result.iterations {
        println!(
            "  iteration {:2}: max force {:7.1} N, max deflection {:.3} mm, predicted error {:.4} mm",
            it.iteration,
            it.max_force_n,
            it.max_deflection_m * 1e3,
            it.max_predicted_error_m * 1e3
        );
    }
    println!(
        "converged: {}, largest compensation {:.3} mm, predicted error left {:.2} µm, {} points not compensated",
        result.converged,
        result.max_compensation_m * 1e3,
        result.final_max_error_m * 1e6,
        result.failure_count()
    );
    if !result.converged || result.failure_count() > 0 {
        return Err("the compensation did not converge on every point".into());
    }
    Ok(())
}

//! The deflection of a pose under a wrench (eq. 15, δs = J K⁻¹ Jᵀ w) and the Cartesian
//! compliance it comes from, on the paper's Stäubli TX200 (Table 1 stiffnesses).
//!
//! `cargo run -p deflex --example deflect_pose`
use deflex::{Data, Wrench, builtin};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let robot = builtin("tx200").ok_or("tx200 is a built-in robot")?;
    // The forming pose of the paper's cell (degrees → rad).
    let q: Vec<f64> = [0.0, 49.7, 89.3, 0.0, 41.0, 0.0]
        .iter()
        .map(|d: &f64| d.to_radians())
        .collect();
    let mut data = Data::new();
    robot.forward_kinematics(&mut data, &q)?;
    let tcp = data.tcp_position();
    println!(
        "{} at q = [0, 49.7, 89.3, 0, 41, 0] deg: TCP at ({:.1}, {:.1}, {:.1}) mm",
        robot.name,
        tcp.x * 1e3,
        tcp.y * 1e3,
        tcp.z * 1e3
    );
    // 1 kN pushing the tool up (the sheet's reaction in incremental forming).
    let wrench = Wrench::new(0.0, 0.0, 1000.0, 0.0, 0.0, 0.0);
    let ds = robot.tcp_deflection(&data, &wrench);
    println!(
        "under Fz = +1000 N: δs = ({:.3}, {:.3}, {:.3}) mm, ({:.3}, {:.3}, {:.3}) mrad",
        ds[0] * 1e3,
        ds[1] * 1e3,
        ds[2] * 1e3,
        ds[3] * 1e3,
        ds[4] * 1e3,
        ds[5] * 1e3
    );
    let c = robot.compliance_matrix(&data);
    println!("translational compliance (µm/N), rows x, y, z:");
    for i in 0..3 {
        println!(
            "  {:8.4} {:8.4} {:8.4}",
            c[(i, 0)] * 1e6,
            c[(i, 1)] * 1e6,
            c[(i, 2)] * 1e6
        );
    }
    // The compliance matrix applied to the wrench is the deflection (identity of eq. 15).
    let gap = (c * wrench - ds).norm();
    println!("|C w − δs| = {gap:.1e} (should be ~1e-16)");
    if gap > 1e-12 {
        return Err("compliance and deflection disagree".into());
    }
    Ok(())
}

//! Sheet tests: the Aerens level, the pass memory, plastic flow.
use super::*;

#[test]
fn aerens_numbers() {
    // The paper's cone: Rm 300 MPa, t = 1 mm, d = 15 mm, Δz = 0.24 mm, α = 45°.
    let dh = scallop_height_mm(7.5, 0.24, 45.0);
    let s: f64 = 0.24 / 45f64.to_radians().sin();
    assert!((dh - (7.5 - (56.25 - s * s / 4.0).sqrt())).abs() < 1e-15);
    assert!((dh - 1.92e-3).abs() < 2e-5, "{dh}");
    let fz = aerens_fz(300.0, 1.0, 15.0, dh, 45.0);
    // 0.0716·300·15^0.41·Δh^0.09·45·cos45 by hand: 21.48 · 3.035 · 0.5695 · 31.82 ≈ 1181 N.
    assert!((fz - 1181.0).abs() < 10.0, "{fz}");
    assert!((1100.0..1300.0).contains(&fz));
    // Force grows with thickness and strength, weakly with step-down.
    assert!(aerens_fz(300.0, 1.2, 15.0, dh, 45.0) > 1.3 * fz);
    let deeper_steps = aerens_fz(300.0, 1.0, 15.0, scallop_height_mm(7.5, 0.5, 45.0), 45.0);
    assert!(deeper_steps > fz && deeper_steps < 1.2 * fz);
}

/// Feeds a helical cone's positions (as formed by a robot whose error grows with depth) to
/// the pass memory: it recovers the actual step-down and wall angle, and the level follows.
#[test]
fn the_pass_memory_measures_the_actual_step_down_and_wall_angle() {
    let design = Sheet::new(&SheetConfig::default(), 0.24, 45.0).unwrap();
    let run = |shallower: f64| {
        let mut sheet = design.clone();
        let turns = 30.0;
        let steps = (turns * 2000.0) as usize;
        for k in 0..steps {
            let u = k as f64 / 2000.0; // turns
            let theta = 2.0 * PI * u;
            let programmed = 0.24e-3 * u;
            // The tool reaches only (1 − shallower) of the programmed depth; radius as programmed.
            let depth = programmed * (1.0 - shallower);
            let r = 0.020 - programmed;
            let p = Vector3::new(r * theta.cos(), r * theta.sin(), -depth - 0.0075 + 0.0075);
            sheet.observe_pass(&p, depth);
        }
        sheet
    };
    let exact = run(0.0);
    let (step, angle) = exact.actual_step_and_angle();
    assert!(
        (step - 0.24).abs() < 0.005 && (angle - 45.0).abs() < 0.5,
        "{step} {angle}"
    );
    assert!((exact.level_force_n() / exact.steady_force_n() - 1.0).abs() < 0.01);
    let shallow = run(0.25);
    let (step, angle) = shallow.actual_step_and_angle();
    let expected = (0.75f64).atan().to_degrees();
    assert!(
        (step - 0.18).abs() < 0.005 && (angle - expected).abs() < 0.5,
        "{step} {angle}"
    );
    assert!(shallow.level_force_n() < 0.95 * exact.level_force_n());
}

#[test]
fn pushing_deeper_raises_the_force() {
    let sheet = Sheet::new(&SheetConfig::default(), 0.24, 45.0).unwrap();
    let mut last = 0.0;
    for k in 1..40 {
        let z = -0.0002 * k as f64;
        let mut s = sheet.clone();
        let p = Vector3::new(0.015, 0.0, z);
        let c = s.contact(&p);
        s.form(&p, &c);
        assert!(
            c.force_n >= last,
            "force fell at z = {z}: {} < {last}",
            c.force_n
        );
        last = c.force_n;
    }
    // At 7.8 mm: 96 % built up, growth 1 + κ (7.8 − 12) = 0.87.
    assert!(last > 0.8 * sheet.steady_force_n());
}

#[test]
fn a_plastic_pass_leaves_the_part_at_the_tool_depth_minus_springback() {
    let mut sheet = Sheet::new(&SheetConfig::default(), 0.24, 45.0).unwrap();
    let p = Vector3::new(0.015, 0.0, -0.005);
    let c = sheet.contact(&p);
    assert!(sheet.form(&p, &c));
    let after = sheet.contact(&p);
    assert!((after.penetration_m - c.force_n / 2.0e6).abs() < 1e-9);
    let depth = sheet.max_depth_m();
    assert!(
        (depth - (0.005 - c.force_n / 2.0e6)).abs() < 1e-6,
        "{depth}"
    );
    // Lifting the tool unloads it elastically.
    let lifted = sheet.contact(&Vector3::new(0.015, 0.0, -0.0049));
    assert!(lifted.force_n < c.force_n);
}

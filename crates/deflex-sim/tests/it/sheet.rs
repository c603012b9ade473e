//! Sheet tests: the Aerens level, the pass memory, plastic flow.

use deflex_sim::sheet::{Sheet, SheetConfig, aerens_fz, scallop_height_mm};
use nalgebra::Vector3;
use std::f64::consts::PI;

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

/// The programmed profile of the paper's cone against the envelope worked out by hand: spheres
/// of radius R whose centres run down a 45° line leave a parallel line R/cos α below the centre
/// line, i.e. depth(r) = (r₀ − r)·tan α − R + R/cos α where the tangent point (R sin α further
/// in) lies on the wall; below the wall's foot the last turn's sphere rounds the corner; the floor
/// inside the last turn sits at the programmed depth; the sheet beyond r₀ + R is untouched.
#[test]
fn the_programmed_profile_of_a_cone_is_the_swept_sphere_envelope() {
    let config = SheetConfig::default();
    let sheet = Sheet::new(&config, 0.24, 45.0).unwrap();
    let r_tool = config.tool_diameter_mm / 2.0 * 1e-3;
    let path = deflex_sim::toolpath::ToolPath::paper_cone();
    // The path's waypoints (mm) as tool centres (m); 5° apart, interpolated by the method.
    let centres: Vec<Vector3<f64>> = path
        .waypoints
        .iter()
        .map(|w| Vector3::new(w.p_mm[0], w.p_mm[1], w.p_mm[2]) * 1e-3)
        .collect();
    let profile = sheet.programmed_profile(&centres);
    assert_eq!(profile.len(), sheet.profile(0.0).len());
    let (r0, depth, tan) = (0.020, 0.015, 1.0f64);
    let cos = 45f64.to_radians().cos();
    let r_bottom = r0 - depth / tan;
    let mut checked = 0;
    for &(r, d) in &profile {
        let sin = cos; // 45°
        let expected = if r < r_bottom - 1e-4 {
            Some(depth)
        } else if r > r_bottom + 1e-4 && r < r_bottom + r_tool * sin - 1e-4 {
            // Outside the last turn, below the wall's foot: the last turn's sphere.
            let u = r - r_bottom;
            Some(depth - r_tool + (r_tool * r_tool - u * u).sqrt())
        } else if r > r_bottom + r_tool * sin + 1e-4 && r < r0 + r_tool * sin - 1e-4 {
            // Tangent points on the wall: the parallel line.
            Some(((r0 - r) * tan - r_tool + r_tool / cos).max(0.0))
        } else if r > r0 + r_tool + 1e-4 {
            Some(0.0)
        } else {
            None
        };
        if let Some(e) = expected {
            // The helix steps 0.24 mm per turn: the scallops between passes are ~2 µm deep
            // (scallop_height_mm), the 5° chords a few µm.
            assert!(
                (d - e).abs() < 2e-5,
                "r {:.2} mm: {:.4} mm, expected {:.4} mm",
                r * 1e3,
                d * 1e3,
                e * 1e3
            );
            checked += 1;
        }
    }
    assert!(checked > 200, "{checked}");
}

/// One circle of tool centres at a depth: the floor inside it at that depth only near the ray
/// (as `form` lowers it), the sphere's cross-section around its radius.
#[test]
fn the_programmed_profile_of_one_circle() {
    let config = SheetConfig::default();
    let sheet = Sheet::new(&config, 0.24, 45.0).unwrap();
    let r_tool = config.tool_diameter_mm / 2.0 * 1e-3;
    let (rho, d) = (0.015, 0.002);
    let top = sheet.top_m();
    let circle: Vec<Vector3<f64>> = (0..=720)
        .map(|k| {
            let t = k as f64 * PI / 360.0;
            Vector3::new(rho * t.cos(), rho * t.sin(), top + r_tool - d)
        })
        .collect();
    let profile = sheet.programmed_profile(&circle);
    for &(r, depth) in &profile {
        let u = r - rho;
        let expected = if r < rho {
            d
        } else if u < r_tool {
            (d - r_tool + (r_tool * r_tool - u * u).sqrt()).max(0.0)
        } else {
            0.0
        };
        assert!(
            (depth - expected).abs() < 2e-6,
            "r {r}: {depth} vs {expected}"
        );
    }
    // Non-finite positions are skipped, not spread.
    let mut with_nan = circle.clone();
    with_nan[100] = Vector3::new(f64::NAN, 0.0, 0.0);
    assert_eq!(sheet.programmed_profile(&with_nan), profile);
}

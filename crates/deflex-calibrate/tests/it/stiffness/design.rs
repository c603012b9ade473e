//! The design (eqs. 13–15) against the model crate's point displacement, through the public
//! fixed-structure calibration that is built on it.

use deflex_calibrate::measurements::MeasuredRotation;
use deflex_calibrate::stiffness::stiffness_fit::{Status, Structure, calibrate_fixed};
use deflex_calibrate::stiffness::synthetic::random_campaign;
use deflex_calibrate::stiffness::validation::predict_full;
use deflex_model::{Axis, EdofSite, builtin};
use nalgebra::Vector3;

/// The design's prediction at the robot's own compliances and centre shifts reproduces
/// `Robot::point_displacement`: rows 0..3 for positions, rows 3..6 for rotations, for
/// points and loads on several links, with moments and a shifted x/y eDoF centre.
///
/// Checked through `calibrate_fixed` (the design's basis and prediction are internal): the rows
/// carry the model's exact displacements and rotations, and the fit of the robot's own structure
/// (its centre shifts fixed) must return the robot's compliances and leave every position and
/// rotation component unexplained by no more than 1e-9 of that row's displacement or rotation.
/// Both together hold exactly when the design predicts every equation of the model at the
/// robot's compliances.
#[test]
fn rotation_rows_match_point_displacement() {
    let mut robot = builtin("tx200").unwrap();
    robot.set_stiffness(EdofSite::Base, Axis::Y, Some(6.0e6));
    robot.set_stiffness(EdofSite::Joint(2), Axis::X, Some(9.0e6));
    robot.joints[1].center_shift = -0.15;
    let mut rows = random_campaign(&robot, 8, (600.0, 1400.0), 5);
    for (i, row) in rows.iter_mut().enumerate() {
        row.wrench[3] = 40.0 * (i as f64 - 3.0);
        row.wrench[5] = -25.0;
        if i % 4 == 1 {
            row.load_link = 3;
        }
        if i % 3 != 2 {
            row.rotation_rad = Some(MeasuredRotation {
                value_rad: [0.0; 3],
                sigma_rad: (i % 2 == 0).then_some(5e-6),
            });
        }
    }
    let nrot = rows.iter().filter(|r| r.rotation_rad.is_some()).count();
    // The model's deflection of every row: the measured displacement, and the measured rotation
    // where the row has one.
    let deflections = predict_full(&robot, &rows).unwrap();
    let (mut min_position, mut min_rotation) = (f64::INFINITY, f64::INFINITY);
    let mut checked = 0;
    for (row, d) in rows.iter_mut().zip(&deflections) {
        row.displacement_m = Some([d[0], d[1], d[2]]);
        min_position = min_position.min(Vector3::new(d[0], d[1], d[2]).norm());
        if let Some(rotation) = &mut row.rotation_rad {
            let angular = Vector3::new(d[3], d[4], d[5]);
            assert!(angular.norm() > 0.0);
            rotation.value_rad = [angular[0], angular[1], angular[2]];
            min_rotation = min_rotation.min(angular.norm());
            checked += 1;
        }
    }
    assert_eq!(checked, nrot);
    assert!(nrot > 0);

    let structure = Structure::from_robot(&robot);
    let cal = calibrate_fixed(&robot, &rows, &structure).unwrap();
    assert_eq!(cal.rotation_rows, nrot);
    // Every equation: 3 per row, 3 more per row with a rotation.
    assert_eq!(
        cal.dof + cal.parameter_labels.len(),
        3 * rows.len() + 3 * nrot
    );
    assert_eq!(cal.parameter_labels.len(), robot.edofs().count());
    // The robot's own compliances, every one identified.
    for e in robot.edofs() {
        let est = cal.edofs.iter().find(|x| x.id == (e.site, e.axis)).unwrap();
        assert_eq!(est.status, Status::Identified, "{}", e.label());
        let c = 1.0 / e.stiffness;
        assert!(
            (est.compliance - c).abs() <= 1e-9 * c,
            "{}: fitted {:e}, model {c:e}",
            e.label(),
            est.compliance
        );
    }
    // No component left unexplained: the largest position residual (per axis) and every
    // rotation residual (bounded by the RMS times the square root of their number) within 1e-9
    // of the smallest row's displacement or rotation.
    for ax in 0..3 {
        let r = cal.residuals.position.max_abs[ax];
        assert!(r <= 1e-9 * min_position, "axis {ax}: {r:e} m");
    }
    let rotation_rms = cal.residuals.rotation_rms_rad.unwrap();
    let rotation_max = rotation_rms * ((3 * nrot) as f64).sqrt();
    assert!(
        rotation_max <= 1e-9 * min_rotation,
        "rotation residual up to {rotation_max:e} rad"
    );
}

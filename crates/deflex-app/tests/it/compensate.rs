//! The compensation engine ([`deflex_app::compensate`]): a path given as an array, compensated and
//! written as a program.

use deflex_app::compensate::*;
use deflex_cam::program::{Format, ProgramSettings};

fn options() -> Options {
    Options {
        twin_config: None,
        part_xyz_m: None,
        seed_q: None,
        length_m: None,
        max_segment_m: None,
        position_only: false,
        include_gravity: false,
        tolerance_m: 1e-6,
        max_iterations: 30,
    }
}

#[test]
fn a_constant_wrench_on_an_array_path_is_compensated_to_the_tolerance() {
    let robot = deflex_app::robot::builtin("tx200").unwrap();
    // 20 mm along x in the part frame, 1 mm steps.
    let values: Vec<f64> = (0..=20).flat_map(|i| [i as f64 * 1e-3, 0.0, 0.0]).collect();
    let spec = PathSpec::Array {
        values,
        cols: 3,
        frame: Frame::Part,
        feed_m_s: Some(0.02),
    };
    let wrench = WrenchSpec::Array(vec![0.0, 0.0, 1000.0, 0.0, 0.0, 0.0]);
    let run = compensate(&robot, &spec, &wrench, &options()).unwrap();
    assert!(run.result.converged);
    assert_eq!(run.result.points.len(), 21);
    assert!(run.result.final_max_error_m < 1e-6);
    let files = programs(&run, Format::UrScript, &ProgramSettings::default()).unwrap();
    assert!(files[0].contents.contains("movel"));
    let e = compensate(&robot, &spec, &WrenchSpec::Array(vec![0.0; 12]), &options())
        .err()
        .unwrap();
    assert!(
        e.to_string().contains("2 wrenches for the 21 points"),
        "{e}"
    );
}

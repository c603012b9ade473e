//! The twin following a joint stream (FANUC Stream Motion): a cell fed, cycle by cycle, the
//! joints another cell's own program commands deflects and forms exactly as that cell does, its
//! error measured from the path's closest point to the true tool (never further than the
//! time's desired point), and it ends only when the stream does.

use deflex_sim::{Cell, CellConfig, CellStep, ToolPath};

#[test]
fn a_cell_following_streamed_joints_forms_as_its_program_does() {
    let config = CellConfig::for_robot("r2000ic-165f").unwrap();
    let path = ToolPath::paper_cone().truncated(20.0);
    let mut program = Cell::new(&config, path.clone(), 3).unwrap();
    let mut stream = Cell::new(&config, path, 3).unwrap();
    stream.follow_joint_stream();
    let (mut a, mut b) = (CellStep::default(), CellStep::default());
    let mut cycles = 0u64;
    let mut max_force = 0.0f64;
    // The feed direction comes from the segment of the last cycle's closest point rather than
    // the clock's: the contact force's direction may differ for a cycle at a segment's end.
    let (mut max_true, mut max_wrench) = (0.0f64, 0.0f64);
    loop {
        program.step_into(&mut a);
        stream.set_joint_command(a.q_measured_rad);
        if a.finished {
            stream.end_joint_stream();
        }
        stream.step_into(&mut b);
        cycles += 1;
        assert_eq!(a.q_measured_rad, b.q_measured_rad, "cycle {cycles}");
        let (ta, tb) = (program.truth().unwrap(), stream.truth().unwrap());
        max_true = max_true.max((ta.true_m - tb.true_m).norm());
        max_wrench = max_wrench.max((ta.wrench - tb.wrench).fixed_rows::<3>(0).norm());
        // The closest point of the path is never further than the time's point.
        assert!(
            tb.path_error_m().norm() <= ta.path_error_m().norm() + 1e-12,
            "cycle {cycles}: {} vs {}",
            tb.path_error_m().norm(),
            ta.path_error_m().norm()
        );
        max_force = max_force.max(tb.force_norm_n());
        assert_eq!(a.finished, b.finished, "cycle {cycles}");
        if a.finished {
            break;
        }
    }
    assert!(stream.is_finished() && max_force > 1.0, "{max_force} N");
    let (sa, sb) = (program.stats(), stream.stats());
    println!(
        "{cycles} cycles, max |F| {max_force:.1} N; true TCP within {:.3} µm, force within {:.3} N; \
         max error by time {:.4} mm, by projection {:.4} mm",
        max_true * 1e6,
        max_wrench,
        sa.max_error_norm_m * 1e3,
        sb.max_error_norm_m * 1e3
    );
    assert!(
        max_true < 1e-6 && max_wrench < 0.05 * max_force,
        "{max_true} m, {max_wrench} N"
    );
    assert!(sb.max_error_norm_m > 0.0 && sb.max_error_norm_m <= sa.max_error_norm_m);
}

#[test]
fn a_cell_without_commands_holds_its_start_pose_until_the_stream_ends() {
    let config = CellConfig::default();
    let path = ToolPath::paper_cone().truncated(10.0);
    let mut cell = Cell::new(&config, path, 1).unwrap();
    cell.follow_joint_stream();
    let first = cell.step();
    for _ in 0..50 {
        let s = cell.step();
        assert_eq!(s.q_measured_rad, first.q_measured_rad);
        assert!(!s.finished);
    }
    // A non-finite command is ignored.
    cell.set_joint_command([f64::NAN; 6]);
    assert_eq!(cell.step().q_measured_rad, first.q_measured_rad);
    cell.end_joint_stream();
    assert!(cell.step().finished && cell.is_finished());
}

//! The calibration engine ([`deflex_app::calibrate`]): measurement rows read from an in-memory
//! table.

use deflex_app::calibrate::*;

#[test]
fn a_bad_row_of_an_in_memory_table_is_named_by_its_index() {
    let robot = deflex_app::robot::builtin("tx200").unwrap();
    let text = "load_case,q1_rad,q2_rad,q3_rad,q4_rad,q5_rad,q6_rad,fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm,load_link,load_x_m,load_y_m,load_z_m,point,point_link,x_m,y_m,z_m,dx_m,dy_m,dz_m\n\
        a,0,0.5,1,0,0.5,0,0,0,-100,0,0,0,6,1,0,0,TCP,6,1,0,0,0,0,1e-4\n\
        a,0,0.5,1,0,0.5,0,0,0,-100,0,0,0,6,1,0,0,TCP,6,1,0,0,0,0,x\n";
    let source = Source::Table {
        text: text.into(),
        origin: "DataFrame".into(),
    };
    let e = read_rows(&source, robot.joint_count(), true).unwrap_err();
    assert!(
        e.to_string().starts_with("DataFrame row 1: column `dz_m`"),
        "{e}"
    );
    let e = read_rows(&source, 5, true).unwrap_err();
    assert!(e.to_string().contains("the robot has 5 joints"), "{e}");
}

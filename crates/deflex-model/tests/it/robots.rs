//! Robot descriptions beyond the TX200: standard DH (checked against textbook matrices written
//! out here, and against the same robot in modified DH), Hayati β, the KUKA and ABB built-ins
//! (against their reference poses and against URDFs written from the ROS-Industrial origins),
//! gravity deflection (against the existing point-load transfer and a hand-derived case), the
//! geometry fingerprint, URDF paths that survive writing the robot elsewhere, bounds on file
//! values, and hostile URDFs.

use deflex_model::{
    Data, Wrench, builtin, robot_from_toml_and_urdf_str, robot_from_toml_str, robot_to_toml,
};
use nalgebra::{Matrix4, Vector3};
use std::f64::consts::{FRAC_PI_2, PI};

type M4 = Matrix4<f64>;

fn rot_x(a: f64) -> M4 {
    let (s, c) = a.sin_cos();
    M4::new(1., 0., 0., 0., 0., c, -s, 0., 0., s, c, 0., 0., 0., 0., 1.)
}
fn rot_y(a: f64) -> M4 {
    let (s, c) = a.sin_cos();
    M4::new(c, 0., s, 0., 0., 1., 0., 0., -s, 0., c, 0., 0., 0., 0., 1.)
}
fn rot_z(a: f64) -> M4 {
    let (s, c) = a.sin_cos();
    M4::new(c, -s, 0., 0., s, c, 0., 0., 0., 0., 1., 0., 0., 0., 0., 1.)
}
fn trans(x: f64, y: f64, z: f64) -> M4 {
    M4::new(1., 0., 0., x, 0., 1., 0., y, 0., 0., 1., z, 0., 0., 0., 1.)
}

/// Textbook standard DH link transform with Hayati's β appended.
fn standard_dh(theta: f64, d: f64, a: f64, alpha: f64, beta: f64) -> M4 {
    let (st, ct) = theta.sin_cos();
    let (sa, ca) = alpha.sin_cos();
    #[rustfmt::skip]
    let textbook = M4::new(
        ct, -st * ca, st * sa, a * ct,
        st, ct * ca, -ct * sa, a * st,
        0., sa, ca, d,
        0., 0., 0., 1.,
    );
    textbook * rot_y(beta)
}

fn pose_matrix(pose: &deflex_model::Pose) -> M4 {
    pose.to_homogeneous()
}

fn q_samples(n: usize) -> Vec<[f64; 6]> {
    // Deterministic spread of configurations (no RNG dependency needed).
    (0..n)
        .map(|k| {
            let t = k as f64 + 1.0;
            [
                (0.7 * t).sin() * 2.0,
                (1.3 * t).sin() * 1.5,
                (0.9 * t).cos() * 1.5,
                (2.1 * t).sin() * 2.5,
                (1.7 * t).cos() * 1.5,
                (0.4 * t).sin() * 3.0,
            ]
        })
        .collect()
}

const UR10_DH: [(f64, f64, f64); 6] = [
    // (d, a, alpha)
    (0.1273, 0.0, FRAC_PI_2),
    (0.0, -0.612, 0.0),
    (0.0, -0.5723, 0.0),
    (0.163941, 0.0, FRAC_PI_2),
    (0.1157, 0.0, -FRAC_PI_2),
    (0.0922, 0.0, 0.0),
];

#[test]
fn ur10_standard_dh_matches_the_textbook_product_and_ur_zero_pose() {
    let robot = builtin("ur10").unwrap();
    let mut data = Data::new();
    for q in q_samples(20) {
        robot.forward_kinematics(&mut data, &q).unwrap();
        let mut expected = M4::identity();
        for (i, (d, a, alpha)) in UR10_DH.iter().enumerate() {
            expected *= standard_dh(q[i], *d, *a, *alpha, 0.0);
        }
        let got = pose_matrix(&data.flange);
        assert!(
            (got - expected).norm() < 1e-12,
            "q {q:?}: {got} vs {expected}"
        );
    }
    // UR's zero pose: (a2 + a3, −(d4 + d6), d1 − d5).
    robot.forward_kinematics(&mut data, &[0.0; 6]).unwrap();
    let p = data.flange.translation.vector;
    assert!(
        (p - Vector3::new(-1.1843, -0.256141, 0.0116)).norm() < 1e-12,
        "{p}"
    );
}

#[test]
fn standard_dh_equals_the_same_robot_written_in_modified_dh() {
    // The UR10 by hand in modified DH: (α, a) move one row down; d and θ stay; the last row's
    // (a, α) would go to the flange (both 0 on a UR).
    let mut toml = String::from("name = \"ur10 in modified DH\"\n");
    let mut previous = (0.0, 0.0); // (alpha, a) of the previous standard row
    for (d, a, alpha) in UR10_DH {
        toml += &format!(
            "[[joint]]\nalpha = {:?}\na = {:?}\nd = {d:?}\ntheta_offset = 0.0\nstiffness = {{ x = 1e6, y = 2e6, z = 3e6 }}\n",
            previous.0, previous.1
        );
        previous = (alpha, a);
    }
    let modified = robot_from_toml_str(&toml, "ur10-mdh", None).unwrap();
    let mut standard = builtin("ur10").unwrap();
    for joint in &mut standard.joints {
        joint.stiffness = modified.joints[0].stiffness;
    }
    let (mut a, mut b) = (Data::new(), Data::new());
    let wrench = Wrench::new(30.0, -80.0, 120.0, 2.0, -1.0, 3.0);
    for q in q_samples(20) {
        standard.forward_kinematics(&mut a, &q).unwrap();
        modified.forward_kinematics(&mut b, &q).unwrap();
        // Same joint frames R_i, hence the same eDoFs and the same deflection.
        for i in 0..6 {
            let diff = pose_matrix(&a.joint_frames[i]) - pose_matrix(&b.joint_frames[i]);
            assert!(diff.norm() < 1e-12, "joint frame {i} at {q:?}");
        }
        assert!((pose_matrix(&a.tcp) - pose_matrix(&b.tcp)).norm() < 1e-12);
        let da = standard.tcp_deflection(&a, &wrench);
        let db = modified.tcp_deflection(&b, &wrench);
        assert!((da - db).norm() < 1e-15 + 1e-12 * da.norm());
    }
}

#[test]
fn hayati_beta_enters_both_conventions_as_a_rotation_about_y() {
    let rows = [
        (0.3, 0.2, 0.4, 0.01),
        (0.05, 0.6, 0.0, -0.02),
        (0.0, 0.5, 1.2, 0.03),
    ];
    let mut standard = String::from("name = \"s\"\ndh = \"standard\"\n");
    let mut modified = String::from("name = \"m\"\n");
    for (d, a, alpha, beta) in rows {
        let row = format!(
            "[[joint]]\nalpha = {alpha:?}\na = {a:?}\nd = {d:?}\nbeta = {beta:?}\ntheta_offset = 0.0\n"
        );
        standard += &row;
        modified += &row;
    }
    let standard = robot_from_toml_str(&standard, "s", None).unwrap();
    let modified = robot_from_toml_str(&modified, "m", None).unwrap();
    let q = [0.3, -0.7, 1.1];
    let mut data = Data::new();
    let mut expected_standard = M4::identity();
    let mut expected_modified = M4::identity();
    for (i, (d, a, alpha, beta)) in rows.iter().enumerate() {
        expected_standard *= standard_dh(q[i], *d, *a, *alpha, *beta);
        expected_modified *= rot_x(*alpha) * rot_y(*beta) * trans(*a, 0.0, *d) * rot_z(q[i]);
    }
    standard.forward_kinematics(&mut data, &q).unwrap();
    assert!((pose_matrix(&data.flange) - expected_standard).norm() < 1e-12);
    modified.forward_kinematics(&mut data, &q).unwrap();
    assert!((pose_matrix(&data.flange) - expected_modified).norm() < 1e-12);
    // β survives writing and reading the file.
    let again = robot_from_toml_str(&robot_to_toml(&standard), "again", None).unwrap();
    again.forward_kinematics(&mut data, &q).unwrap();
    assert!((pose_matrix(&data.flange) - expected_standard).norm() < 1e-12);
    assert_eq!(
        again.geometry_fingerprint(),
        standard.geometry_fingerprint()
    );
}

/// A URDF chain from `(name, origin xyz, axis, lower, upper)` rows plus a fixed `tool0` with
/// `tool_rpy`; loaded through a TOML that names each joint.
fn urdf_robot(
    name: &str,
    joints: &[(&str, [f64; 3], [f64; 3])],
    tool_rpy: [f64; 3],
) -> deflex_model::Robot {
    let mut xml = String::from("<robot name=\"r\"><link name=\"base_link\"/>");
    let mut toml = format!("name = \"{name} from URDF\"\nurdf = \"r.urdf\"\n");
    let mut parent = "base_link".to_string();
    for (i, (joint, xyz, axis)) in joints.iter().enumerate() {
        let child = format!("link_{}", i + 1);
        xml += &format!(
            "<link name=\"{child}\"/><joint name=\"{joint}\" type=\"revolute\"><parent link=\"{parent}\"/><child link=\"{child}\"/>\
             <origin xyz=\"{} {} {}\" rpy=\"0 0 0\"/><axis xyz=\"{} {} {}\"/><limit lower=\"-7\" upper=\"7\" effort=\"0\" velocity=\"1\"/></joint>",
            xyz[0], xyz[1], xyz[2], axis[0], axis[1], axis[2]
        );
        toml += &format!("[[joint]]\nname = \"{joint}\"\n");
        parent = child;
    }
    xml += &format!(
        "<link name=\"tool0\"/><joint name=\"flange\" type=\"fixed\"><parent link=\"{parent}\"/><child link=\"tool0\"/>\
         <origin xyz=\"0 0 0\" rpy=\"{} {} {}\"/></joint></robot>",
        tool_rpy[0], tool_rpy[1], tool_rpy[2]
    );
    robot_from_toml_and_urdf_str(&toml, &xml, &format!("{name}.toml")).unwrap()
}

fn assert_same_flange(a: &deflex_model::Robot, b: &deflex_model::Robot, qs: &[[f64; 6]]) {
    let (mut da, mut db) = (Data::new(), Data::new());
    for q in qs {
        a.forward_kinematics(&mut da, q).unwrap();
        b.forward_kinematics(&mut db, q).unwrap();
        let diff = pose_matrix(&da.flange) - pose_matrix(&db.flange);
        assert!(
            diff.norm() < 1e-9,
            "{} vs {} at {q:?}: {diff}",
            a.name,
            b.name
        );
    }
}

#[test]
fn kuka_kr210_matches_its_urdf_and_home_pose_with_kuka_joint_senses() {
    let kuka = builtin("kr210-r2700").unwrap();
    let urdf = urdf_robot(
        "kr210",
        &[
            ("joint_a1", [0.0, 0.0, 0.675], [0.0, 0.0, -1.0]),
            ("joint_a2", [0.350, 0.0, 0.0], [0.0, 1.0, 0.0]),
            ("joint_a3", [1.150, 0.0, 0.0], [0.0, 1.0, 0.0]),
            ("joint_a4", [0.0, 0.0, -0.041], [-1.0, 0.0, 0.0]),
            ("joint_a5", [1.200, 0.0, 0.0], [0.0, 1.0, 0.0]),
            ("joint_a6", [0.215, 0.0, 0.0], [-1.0, 0.0, 0.0]),
        ],
        [0.0, FRAC_PI_2, 0.0],
    );
    assert_same_flange(&kuka, &urdf, &q_samples(25));
    // KUKA home (0, −90°, 90°, 0, 0, 0): upper arm up, forearm forward, $FLANGE z forward.
    let home = [0.0, -FRAC_PI_2, FRAC_PI_2, 0.0, 0.0, 0.0];
    let flange = kuka.tcp_pose(&home).unwrap();
    assert!((flange.translation.vector - Vector3::new(1.765, 0.0, 1.784)).norm() < 1e-12);
    let r = flange.rotation.matrix();
    assert!(
        (r.column(2) - Vector3::x()).norm() < 1e-12,
        "z out of the flange"
    );
    assert!((r.column(0) + Vector3::z()).norm() < 1e-12, "x down");
    // A1 positive turns the arm clockwise seen from above (towards −y), as on the controller.
    let turned = kuka
        .tcp_pose(&[0.3, -FRAC_PI_2, FRAC_PI_2, 0.0, 0.0, 0.0])
        .unwrap();
    assert!(turned.translation.vector.y < -0.5);
}

#[test]
fn abb_irb4600_matches_its_urdf_and_zero_pose() {
    let abb = builtin("irb4600").unwrap();
    let urdf = urdf_robot(
        "irb4600",
        &[
            ("joint_1", [0.0, 0.0, 0.495], [0.0, 0.0, 1.0]),
            ("joint_2", [0.175, 0.0, 0.0], [0.0, 1.0, 0.0]),
            ("joint_3", [0.0, 0.0, 0.9], [0.0, 1.0, 0.0]),
            ("joint_4", [0.0, 0.0, 0.175], [1.0, 0.0, 0.0]),
            ("joint_5", [0.960, 0.0, 0.0], [0.0, 1.0, 0.0]),
            ("joint_6", [0.135, 0.0, 0.0], [1.0, 0.0, 0.0]),
        ],
        [0.0, FRAC_PI_2, 0.0],
    );
    assert_same_flange(&abb, &urdf, &q_samples(25));
    let flange = abb.tcp_pose(&[0.0; 6]).unwrap();
    assert!((flange.translation.vector - Vector3::new(1.270, 0.0, 1.570)).norm() < 1e-12);
    assert!((flange.rotation.matrix().column(2) - Vector3::x()).norm() < 1e-12);
}

#[test]
fn gravity_deflection_equals_the_sum_of_point_loads_at_the_centres_of_mass() {
    for name in ["ur10", "ur10e"] {
        let mut robot = builtin(name).unwrap();
        for joint in &mut robot.joints {
            joint.stiffness.0 = [Some(4e6), Some(5e6), joint.stiffness.0[2]];
        }
        robot.payload = Some(deflex_model::LinkInertia {
            mass_kg: 5.0,
            com: Vector3::new(0.01, -0.02, 0.08),
        });
        let mut data = Data::new();
        for q in q_samples(10) {
            robot.forward_kinematics(&mut data, &q).unwrap();
            for link in [3, 6] {
                let point =
                    data.joint_frames[link - 1].translation.vector + Vector3::new(0.1, 0.0, 0.0);
                let mut expected = deflex_model::Displacement::zeros();
                for (i, joint) in robot.joints.iter().enumerate() {
                    let inertia = joint.inertia.unwrap();
                    let com = data.joint_frames[i]
                        .transform_point(&inertia.com.into())
                        .coords;
                    let force = robot.gravity * inertia.mass_kg;
                    let w = Wrench::new(force.x, force.y, force.z, 0.0, 0.0, 0.0);
                    expected += robot.point_displacement(&data, &point, link, &com, i + 1, &w);
                }
                let payload = robot.payload.unwrap();
                let com = data.flange.transform_point(&payload.com.into()).coords;
                let force = robot.gravity * payload.mass_kg;
                let w = Wrench::new(force.x, force.y, force.z, 0.0, 0.0, 0.0);
                expected += robot.point_displacement(&data, &point, link, &com, 6, &w);
                let got = robot.gravity_displacement(&data, &point, link);
                assert!(
                    (got - expected).norm() < 1e-12 * expected.norm().max(1e-9),
                    "{name} link {link}: {got} vs {expected}"
                );
                assert!(
                    expected.norm() > 1e-5,
                    "{name}: gravity sags the arm visibly"
                );
            }
        }
    }
}

#[test]
fn gravity_sag_of_a_horizontal_one_joint_arm_by_hand() {
    // Joint axis horizontal (α = π/2 turns z onto −y), link along x, mass m at L, tip at 2L:
    // τ = −m g L, δθ = τ/k, tip dz = 2L·δθ = −2 m g L²/k.
    let (m, l, k) = (12.0, 0.4, 2.0e5);
    let toml = format!(
        "name = \"arm\"\n[[joint]]\nalpha = {FRAC_PI_2:?}\na = 0.0\nd = 0.0\ntheta_offset = 0.0\nstiffness = {{ z = {k:e} }}\nmass = {m}\ncom = [{l}, 0.0, 0.0]\n[tool]\nxyz = [{}, 0.0, 0.0]\n",
        2.0 * l
    );
    let robot = robot_from_toml_str(&toml, "arm", None).unwrap();
    let mut data = Data::new();
    robot.forward_kinematics(&mut data, &[0.0]).unwrap();
    let sag = robot.gravity_displacement(&data, &data.tcp_position(), 1);
    let expected = -2.0 * m * 9.80665 * l * l / k;
    assert!(
        (sag[2] - expected).abs() < 1e-15,
        "{} vs {expected}",
        sag[2]
    );
    assert!(sag[0].abs() < 1e-15 && sag[1].abs() < 1e-15);
}

#[test]
fn urdf_inertials_are_summed_per_moving_body_in_the_joint_frame() {
    // Joint 1 about z; its child link_1 (2 kg at x = 0.1) carries a fixed bracket (3 kg at its
    // own (0, 0, 0.2), the bracket frame 0.5 m along x). Body 1: 5 kg, com x = (0.2 + 1.5)/5.
    let xml = r#"<robot name="r"><link name="base"/>
      <link name="link_1"><inertial><origin xyz="0.1 0 0"/><mass value="2"/></inertial></link>
      <link name="bracket"><inertial><origin xyz="0 0 0.2"/><mass value="3"/></inertial></link>
      <joint name="j1" type="revolute"><parent link="base"/><child link="link_1"/>
        <origin xyz="0 0 1"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="0" velocity="1"/></joint>
      <joint name="fix" type="fixed"><parent link="link_1"/><child link="bracket"/><origin xyz="0.5 0 0"/></joint>
    </robot>"#;
    let robot = robot_from_toml_and_urdf_str(
        "name = \"r\"\nurdf = \"r.urdf\"\ntip_link = \"bracket\"\n[[joint]]\nname = \"j1\"\n",
        xml,
        "r.toml",
    )
    .unwrap();
    let inertia = robot.joints[0].inertia.unwrap();
    assert!((inertia.mass_kg - 5.0).abs() < 1e-15);
    assert!((inertia.com - Vector3::new(1.7 / 5.0, 0.0, 0.6 / 5.0)).norm() < 1e-15);
    // The fixed bracket is the flange: 0.5 m along x.
    assert!((robot.flange.translation.vector - Vector3::new(0.5, 0.0, 0.0)).norm() < 1e-15);
}

#[test]
fn fingerprints_tell_robots_apart_and_survive_a_round_trip() {
    let mut seen = std::collections::BTreeSet::new();
    for (name, _) in deflex_model::BUILTIN_ROBOTS {
        let robot = builtin(name).unwrap();
        let again = robot_from_toml_str(&robot_to_toml(&robot), "again", None).unwrap();
        assert_eq!(
            robot.geometry_fingerprint(),
            again.geometry_fingerprint(),
            "{name}"
        );
        assert_eq!(robot.geometry_fingerprint().len(), 16);
        seen.insert((robot.geometry_fingerprint(), name.starts_with("tx200")));
    }
    // tx200 and tx200-1edof share their geometry; every other robot differs.
    assert_eq!(seen.len(), 7);
    let mut moved = builtin("ur10").unwrap();
    moved.joints[2].dh.as_mut().unwrap().a += 1e-6;
    moved.rebuild_dh_geometry();
    assert_ne!(
        moved.geometry_fingerprint(),
        builtin("ur10").unwrap().geometry_fingerprint()
    );
}

// A URDF robot written to another folder still finding its URDF: the tests of deflex_app::load.

fn error_of(text: &str) -> String {
    robot_from_toml_str(text, "robots/bad.toml", None)
        .unwrap_err()
        .to_string()
}

#[test]
fn absurd_values_are_refused_with_the_field_named() {
    for (extra, field) in [
        (
            "stiffness = { z = 5e-324 }\n",
            "joint[1] (joint_1).stiffness.z",
        ),
        ("center_shift = 1e308\n", "joint[1] (joint_1).center_shift"),
        ("alpha = 1e308\n", "joint[1] (joint_1).alpha"),
        ("beta = nan\n", "joint[1] (joint_1).beta"),
        ("d = -1e9\n", "joint[1] (joint_1).d"),
        ("mass = -1.0\n", "joint[1] (joint_1).mass"),
        ("com = [0.1, 0.0, 0.0]\n", "joint[1] (joint_1).mass"),
        (
            "mass = 1.0\ncom = [1e300, 0.0, 0.0]\n",
            "joint[1] (joint_1).com.x",
        ),
        ("theta_offset = inf\n", "joint[1] (joint_1).theta_offset"),
        ("limits = [-1e9, 1.0]\n", "joint[1] (joint_1).limits"),
    ] {
        let e = error_of(&format!(
            "name = \"r\"\n{}",
            crate::dh_joint(&format!("a = 0.5\n{extra}"))
        ));
        assert!(
            e.contains("robots/bad.toml") && e.contains(field),
            "{extra}: {e}"
        );
    }
    let joint = crate::dh_joint("");
    let e = error_of(&format!("name = \"r\"\ngravity = [0.0, 0.0, nan]\n{joint}"));
    assert!(e.contains("gravity.z"), "{e}");
    let e = error_of(&format!(
        "name = \"r\"\n{joint}[tool]\nxyz = [1e300, 0.0, 0.0]\n"
    ));
    assert!(e.contains("tool.xyz"), "{e}");
    let e = error_of(&format!(
        "name = \"r\"\n{joint}[[setup]]\nname = \"A\"\n[[setup]]\nname = \"A\"\n"
    ));
    assert!(e.contains("listed twice"), "{e}");
}

fn urdf_error(xml: &str, toml_extra: &str) -> String {
    robot_from_toml_and_urdf_str(
        &format!("name = \"r\"\nurdf = \"r.urdf\"\n{toml_extra}[[joint]]\nname = \"j1\"\n"),
        xml,
        "r.toml",
    )
    .unwrap_err()
    .to_string()
}

/// The URDF reader bounds the element nesting (`MAX_URDF_DEPTH`, 64) before the recursive XML
/// parser sees the text, counting elements only: the XML declaration, a self-closing tag,
/// comments, processing instructions and CDATA holding `<…>`, and quoted attribute values
/// holding `>` or `/>`, add no level. A document exactly 64 deep with all of them loads; one
/// level more, or 1000, is refused as nested.
#[test]
fn nesting_depth_skips_comments_quotes_and_self_closing_tags() {
    let document = |depth: usize| {
        // <robot> is level 1; the chain below it fills the rest, its innermost element holding
        // every construct that is not a level.
        let chain = depth - 1;
        format!(
            "<?xml version='1.0'?><robot name=\"r\"><link name=\"a\"/><link name=\"b\"/>\
             <joint name=\"j1\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/>\
             <axis xyz=\"0 0 1\"/></joint>{}<c x='>'><e/><!-- <d> --><?pi <f>?>\
             <![CDATA[<g>]]></c>{}</robot>",
            "<x a='/>'>".repeat(chain - 1),
            "</x>".repeat(chain - 1)
        )
    };
    let toml = "name = \"r\"\nurdf = \"r.urdf\"\n[[joint]]\nname = \"j1\"\n";
    let robot = robot_from_toml_and_urdf_str(toml, &document(64), "r.toml").unwrap();
    assert_eq!(robot.joint_count(), 1);
    let e = urdf_error(&document(65), "");
    assert!(e.contains("nested more than 64 levels"), "{e}");
    let deep = format!("<robot name=\"r\">{}</robot>", "<a>".repeat(1000));
    let e = urdf_error(&deep, "");
    assert!(e.contains("nested more than 64 levels"), "{e}");
}

#[test]
fn hostile_urdfs_get_errors_not_hangs() {
    let joint = |name: &str, parent: &str, child: &str, kind: &str| {
        format!(
            "<link name=\"{child}\"/><joint name=\"{name}\" type=\"{kind}\"><parent link=\"{parent}\"/><child link=\"{child}\"/><axis xyz=\"0 0 1\"/></joint>"
        )
    };
    // A link cycle with no root.
    let cycle = format!(
        "<robot name=\"r\">{}{}</robot>",
        joint("j1", "a", "b", "revolute"),
        joint("j2", "b", "a", "revolute")
    );
    let e = urdf_error(&cycle, "");
    assert!(e.contains("cycle"), "{e}");
    // A cycle below a named base.
    let e = urdf_error(&cycle, "base_link = \"a\"\n");
    assert!(e.contains("cycle"), "{e}");
    // 30 000 nesting levels: refused before the XML parser recurses.
    let deep = format!(
        "<robot name=\"r\">{}{}</robot>",
        "<x>".repeat(30_000),
        "</x>".repeat(30_000)
    );
    let e = urdf_error(&deep, "");
    assert!(e.contains("nested"), "{e}");
    // 100 000 fixed joints then one revolute joint: found in linear time.
    let mut xml = String::from("<robot name=\"r\"><link name=\"l0\"/>");
    for i in 0..100_000 {
        xml += &joint(
            &format!("f{i}"),
            &format!("l{i}"),
            &format!("l{}", i + 1),
            "fixed",
        );
    }
    xml += &joint("j1", "l100000", "tip", "revolute");
    xml += "</robot>";
    let robot = robot_from_toml_and_urdf_str(
        "name = \"r\"\nurdf = \"r.urdf\"\n[[joint]]\nname = \"j1\"\n",
        &xml,
        "r.toml",
    )
    .unwrap();
    assert_eq!(robot.joint_count(), 1);
    let _ = PI;
    // Issue 18: a duplicated link name and a joint whose child link is not declared.
    let two = format!(
        "<robot name=\"r\"><link name=\"base\"/><link name=\"base\"/>{}</robot>",
        joint("j1", "base", "tip", "revolute")
    );
    let e = urdf_error(&two, "");
    assert!(e.contains("\"base\" appears twice"), "{e}");
    let dangling = "<robot name=\"r\"><link name=\"base\"/><joint name=\"j1\" type=\"revolute\"><parent link=\"base\"/><child link=\"ghost\"/><axis xyz=\"0 0 1\"/></joint></robot>";
    let e = urdf_error(dangling, "");
    assert!(e.contains("\"ghost\" is not declared"), "{e}");
}

#[test]
fn ik_search_reaches_poses_from_a_singular_seed_on_every_builtin() {
    use deflex_model::IkOptions;
    for (name, _) in deflex_model::BUILTIN_ROBOTS {
        let robot = builtin(name).unwrap();
        let mut reached = 0;
        for q in q_samples(12) {
            // A reachable target: FK of a configuration inside the limits.
            let mut q = q.to_vec();
            robot.clamp_to_limits(&mut q);
            let target = robot.tcp_pose(&q).unwrap();
            // The all-zero seed is singular (stretched arm, straight wrist) on every one of them.
            let solution = robot
                .inverse_kinematics_search(&target, Some(&[0.0; 6]), &IkOptions::default())
                .unwrap_or_else(|e| panic!("{name} {q:?}: {e}"));
            let got = robot.tcp_pose(&solution.q).unwrap();
            assert!(
                (pose_matrix(&got) - pose_matrix(&target)).norm() < 1e-7,
                "{name}"
            );
            reached += 1;
        }
        assert_eq!(reached, 12);
    }
}

#[test]
fn ik_search_tells_out_of_reach_from_not_converged() {
    use deflex_model::{IkOptions, ModelError, spatial::pose_from_xyz_rpy};
    let robot = builtin("tx200").unwrap();
    let far = pose_from_xyz_rpy([5.0, 0.0, 0.0], [0.0, PI, 0.0]);
    match robot.inverse_kinematics_search(&far, None, &IkOptions::default()) {
        Err(ModelError::OutOfReach {
            distance_m,
            reach_m,
        }) => {
            assert!((distance_m - 5.0).abs() < 1e-12);
            // 0.25 + 0.95 + 0.8 + 0.194 m of links beyond joint 1.
            assert!((reach_m - 2.194).abs() < 1e-9, "{reach_m}");
        }
        other => panic!("{other:?}"),
    }
    // Within the arm's length but joint 2 locked far from what the pose needs.
    let mut locked = robot.clone();
    locked.joints[1].limits = Some([1.5, 1.51]);
    let target = robot.tcp_pose(&[0.0, 0.87, 1.56, 0.0, 0.7, 0.0]).unwrap();
    let err = locked
        .inverse_kinematics_search(&target, None, &IkOptions::default())
        .unwrap_err();
    assert!(
        matches!(err, ModelError::NotConverged { seeds: 36, .. }),
        "{err:?}"
    );
    assert!(
        err.to_string().contains("not reached from 36 seeds"),
        "{err}"
    );
}

#[test]
fn the_base_tilts_about_its_pivot() {
    // A base eDoF about x0 through a pivot 0.642 m below R0 (the TX200's baseplate), loaded by a
    // horizontal force at the TCP: τ = (x × (A − c))·F, δ(P) = x × (P − c)·τ/k, by hand.
    let k = 8.0e6;
    let toml = format!(
        "name = \"r\"\n[base]\nstiffness = {{ x = {k:e} }}\npivot = [0.0, 0.0, -0.642]\n[[joint]]\nalpha = 0.0\na = 0.0\nd = 0.0\ntheta_offset = 0.0\n[tool]\nxyz = [1.2, 0.0, 0.3]\n"
    );
    let robot = robot_from_toml_str(&toml, "r", None).unwrap();
    let again = robot_from_toml_str(&robot_to_toml(&robot), "again", None).unwrap();
    assert_eq!(again.base_pivot, robot.base_pivot);
    let mut data = Data::new();
    robot.forward_kinematics(&mut data, &[0.0]).unwrap();
    let tcp = data.tcp_position();
    let force = Vector3::new(0.0, 1000.0, 0.0);
    let d = robot.tcp_deflection(&data, &Wrench::new(0.0, 1000.0, 0.0, 0.0, 0.0, 0.0));
    let c = Vector3::new(0.0, 0.0, -0.642);
    let axis = Vector3::x();
    let torque = axis.cross(&(tcp - c)).dot(&force);
    let expected = axis.cross(&(tcp - c)) * (torque / k);
    assert!(
        (d.fixed_rows::<3>(0) - expected).norm() < 1e-15,
        "{d} vs {expected}"
    );
    // 0.942 m lever instead of 0.3 m: about 10× the deflection a tilt about R0 would give.
    assert!(expected.y > 1e-4);
}

#[test]
fn rebuilding_the_dh_geometry_keeps_centres_of_mass_where_they_are() {
    // Change a standard-DH row (as calibration does), rebuild, write and read back: the centre
    // of mass in R_i (what gravity uses) must survive the round trip.
    let mut robot = builtin("ur10").unwrap();
    robot.joints[1].dh.as_mut().unwrap().a += 0.003;
    robot.joints[1].dh.as_mut().unwrap().alpha += 0.002;
    robot.rebuild_dh_geometry();
    let again = robot_from_toml_str(&robot_to_toml(&robot), "again", None).unwrap();
    for (a, b) in robot.joints.iter().zip(&again.joints) {
        let (a, b) = (a.inertia.unwrap(), b.inertia.unwrap());
        assert!((a.com - b.com).norm() < 1e-12, "{} vs {}", a.com, b.com);
    }
}

/// The FANUC-like and the Motoman-like built-ins against their ROS-Industrial URDF chains (R0 at
/// the J2 height: the URDF's `base`, so J1's origin is at z = 0 here), and at zero joint
/// values the faceplate (`tool0`: z forward, x up) where the data sheet's dimensions put it.
#[test]
fn fanuc_and_motoman_built_ins_match_their_urdfs_and_zero_poses() {
    for (name, a1, a2, a3, d4, d6) in [
        ("r2000ic-165f", 0.312, 1.075, 0.225, 1.280, 0.215),
        ("gp180", 0.325, 1.150, 0.300, 1.225, 0.225),
    ] {
        let robot = builtin(name).unwrap();
        let urdf = urdf_robot(
            name,
            &[
                ("j1", [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
                ("j2", [a1, 0.0, 0.0], [0.0, 1.0, 0.0]),
                ("j3", [0.0, 0.0, a2], [0.0, -1.0, 0.0]),
                ("j4", [0.0, 0.0, a3], [-1.0, 0.0, 0.0]),
                ("j5", [d4, 0.0, 0.0], [0.0, -1.0, 0.0]),
                ("j6", [d6, 0.0, 0.0], [-1.0, 0.0, 0.0]),
            ],
            [std::f64::consts::PI, -FRAC_PI_2, 0.0],
        );
        assert_same_flange(&robot, &urdf, &q_samples(25));
        let mut data = Data::new();
        robot.forward_kinematics(&mut data, &[0.0; 6]).unwrap();
        let flange = data.flange;
        let want = Vector3::new(a1 + d4 + d6, 0.0, a2 + a3);
        assert!((flange.translation.vector - want).norm() < 1e-12, "{name}");
        let r = flange.rotation.matrix();
        assert!(
            (r.column(2) - Vector3::x()).norm() < 1e-12,
            "{name}: z forward"
        );
        assert!((r.column(0) - Vector3::z()).norm() < 1e-12, "{name}: x up");
        // J2 positive leans the arm forward, J1 positive turns it towards +y.
        let mut leaned = Data::new();
        robot
            .forward_kinematics(&mut leaned, &[0.3, 0.2, 0.0, 0.0, 0.0, 0.0])
            .unwrap();
        assert!(leaned.flange.translation.vector.y > 0.3, "{name}");
        // The tool is the twin cell's: 200 mm along the flange z.
        assert!((robot.tool.translation.vector - Vector3::new(0.0, 0.0, 0.2)).norm() < 1e-15);
        // The mounting face is the base pivot, below R0.
        assert!((robot.base_pivot.z + if name == "gp180" { 0.650 } else { 0.670 }).abs() < 1e-12);
    }
}

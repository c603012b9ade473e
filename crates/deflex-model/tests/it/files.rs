//! Robot files: URDF against modified DH, validation errors that name file and field, and the
//! built-in robots.

use deflex_model::spatial::{rotation_from_rpy, rpy_from_rotation};
use deflex_model::{BUILTIN_ROBOTS, builtin, robot_from_toml_and_urdf_str, robot_from_toml_str};
use nalgebra::{Rotation3, Vector3};

/// A URDF written from the TX200's modified-DH table (each origin = RotX(α)·TransX(a)·TransZ(d)·RotZ(θ0)),
/// with an extra fixed flange link, must give the same forward kinematics as the DH file.
#[test]
fn urdf_chain_matches_modified_dh() {
    let dh = builtin("tx200").unwrap();
    let mut joints_xml = String::new();
    let mut links_xml = String::from("<link name=\"base\"/>");
    for (i, joint) in dh.joints.iter().enumerate() {
        let p = joint.dh.unwrap();
        let xyz = Vector3::new(p.a, -p.d * p.alpha.sin(), p.d * p.alpha.cos());
        let rotation = Rotation3::from_axis_angle(&Vector3::x_axis(), p.alpha)
            * Rotation3::from_axis_angle(&Vector3::z_axis(), joint.theta_offset);
        let rpy = rpy_from_rotation(&rotation);
        assert!((rotation_from_rpy(rpy).matrix() - rotation.matrix()).norm() < 1e-12);
        let parent = if i == 0 {
            "base".to_string()
        } else {
            format!("link{i}")
        };
        joints_xml += &format!(
            "<joint name=\"j{}\" type=\"revolute\"><parent link=\"{parent}\"/><child link=\"link{}\"/>\
             <origin xyz=\"{} {} {}\" rpy=\"{} {} {}\"/><axis xyz=\"0 0 1\"/><limit lower=\"-3\" upper=\"3\" effort=\"1\" velocity=\"1\"/></joint>",
            i + 1,
            i + 1,
            xyz.x,
            xyz.y,
            xyz.z,
            rpy[0],
            rpy[1],
            rpy[2]
        );
        links_xml += &format!("<link name=\"link{}\"/>", i + 1);
    }
    joints_xml += "<joint name=\"flange_fix\" type=\"fixed\"><parent link=\"link6\"/><child link=\"flange\"/><origin xyz=\"0 0 0.05\" rpy=\"0 0 0\"/></joint>";
    links_xml += "<link name=\"flange\"/>";
    let xml = format!("<robot name=\"arm\">{links_xml}{joints_xml}</robot>");
    let mut toml = String::from("name = \"urdf arm\"\nurdf = \"arm.urdf\"\n");
    for i in 1..=6 {
        toml += &format!("[[joint]]\nname = \"j{i}\"\nstiffness = {{ z = 1.0e6 }}\n");
    }
    let urdf = robot_from_toml_and_urdf_str(&toml, &xml, "arm.toml").unwrap();
    assert_eq!(urdf.joint_count(), 6);
    assert_eq!(urdf.joints[3].limits, Some([-3.0, 3.0]));
    for q in [[0.0; 6], [0.3, -0.5, 1.1, 0.7, -0.4, 2.0]] {
        let a = dh.tcp_pose(&q).unwrap();
        let b = urdf.tcp_pose(&q).unwrap();
        // The URDF has a 50 mm fixed flange extension along the last z axis.
        let expected = a.translation.vector + a.rotation.matrix().column(2) * 0.05;
        assert!((b.translation.vector - expected).norm() < 1e-12);
        assert!((b.rotation.matrix() - a.rotation.matrix()).norm() < 1e-12);
    }
    // A joint count that does not match the URDF is named with both numbers.
    let short: String = toml.lines().take(2 + 3 * 5).collect::<Vec<_>>().join("\n");
    let err = robot_from_toml_and_urdf_str(&short, &xml, "short.toml")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("6 revolute joints") && err.contains("5 [[joint]]"),
        "{err}"
    );
}

fn error_of(text: &str) -> String {
    robot_from_toml_str(text, "robots/bad.toml", None)
        .unwrap_err()
        .to_string()
}

const ONE_JOINT: &str =
    "name = \"r\"\n[[joint]]\na = 0.5\nalpha = 0.0\nd = 0.0\ntheta_offset = 0.0\n";

#[test]
fn validation_errors_name_file_and_field() {
    let e = error_of(&format!("{ONE_JOINT}stiffness = {{ z = -5.0 }}\n"));
    assert!(
        e.contains("robots/bad.toml")
            && e.contains("joint[1] (joint_1).stiffness.z")
            && e.contains("positive"),
        "{e}"
    );
    let e = error_of(&format!("{ONE_JOINT}stiffness = {{ z = 0.0 }}\n"));
    assert!(e.contains("stiffness.z"), "{e}");
    let e = error_of(&format!("{ONE_JOINT}stiffness = {{ z = nan }}\n"));
    assert!(e.contains("stiffness.z"), "{e}");
    let e = error_of(&format!("{ONE_JOINT}stiffness = {{ w = 1.0 }}\n"));
    assert!(
        e.contains("unknown field") && e.contains("`w`") && e.contains("line"),
        "{e}"
    );
    let e = error_of(&format!("{ONE_JOINT}center_shift = \"abc\"\n"));
    assert!(e.contains("robots/bad.toml") && e.contains("line 7"), "{e}");
    let e = error_of(&format!(
        "name = \"r\"\n[base]\nstiffness = {{ x = inf }}\n{}",
        crate::dh_joint("")
    ));
    assert!(e.contains("base.stiffness.x"), "{e}");
    let e = error_of("name = \"r\"\n");
    assert!(e.contains("1 to 8 motorised joints"), "{e}");
    let e = error_of(&format!("{ONE_JOINT}limits = [1.0, -1.0]\n"));
    assert!(e.contains("limits"), "{e}");
    // (A robot file that does not exist is named in the error: the tests of deflex_app::load.)
}

#[test]
fn builtins_parse_and_differ_as_documented() {
    let names: Vec<&str> = BUILTIN_ROBOTS.iter().map(|(n, _)| *n).collect();
    assert_eq!(
        names,
        [
            "tx200",
            "tx200-1edof",
            "ur10",
            "ur10e",
            "kr210-r2700",
            "irb4600",
            "r2000ic-165f",
            "gp180"
        ]
    );
    for (name, text) in BUILTIN_ROBOTS {
        let robot = builtin(name).unwrap();
        assert_eq!(robot.joint_count(), 6, "{name}");
        if !name.starts_with("tx200") {
            assert!(
                text.contains("PLACEHOLDER") && robot.name.contains("placeholder stiffness"),
                "{name}: the stiffness of a built-in robot from a datasheet is labelled a placeholder"
            );
            assert!(
                text.contains("github.com") || text.contains("universal-robots.com"),
                "{name} cites its source"
            );
        }
    }
    let full = builtin("tx200").unwrap();
    let one = builtin("tx200-1edof").unwrap();
    assert_eq!(full.edof_count(), 6);
    assert_eq!(one.edof_count(), 5);
    assert!((full.joints[2].center_shift - 0.4).abs() < 1e-15);
    assert_eq!(one.joints[2].center_shift, 0.0);
    assert_eq!(
        full.joints[2].stiffness.0,
        [Some(1.45e6), None, Some(2.04e6)]
    );
    assert!(builtin("nope").is_none());
}

#[test]
fn a_dh_joint_missing_a_required_field_is_refused_naming_file_joint_and_field() {
    // Issue 18: a left-out `alpha`, `a`, `d` or `theta_offset` was read as 0.
    for field in ["alpha", "a", "d", "theta_offset"] {
        let second: String = crate::dh_joint("a = 0.4\nalpha = 1.5707963267948966\n")
            .lines()
            .filter(|l| l.split('=').next().map(str::trim) != Some(field))
            .map(|l| format!("{l}\n"))
            .collect();
        let text = format!(
            "name = \"r\"\n{}{}name = \"elbow\"\n",
            crate::dh_joint(""),
            second
        );
        let e = error_of(&text);
        assert!(
            e.contains("robots/bad.toml")
                && e.contains("joint[2] (elbow)")
                && e.contains(&format!("missing `{field}`")),
            "{field}: {e}"
        );
    }
    // β (the Hayati tilt) stays optional; the four stated, the file reads.
    robot_from_toml_str(
        &format!("name = \"r\"\n{}", crate::dh_joint("")),
        "ok.toml",
        None,
    )
    .unwrap();
}

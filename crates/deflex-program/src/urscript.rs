//! Universal Robots URScript (CB3 / e-Series): `NAME.script`, one function and its call.
//!
//! ```text
//! def deflex_path():
//!   set_tcp(p[0.0000000, 0.0000000, 0.0000000, 0.00000000, 0.00000000, 0.00000000])
//!   deflex_frame = p[1.5000000, 0.0000000, -0.1830000, 0.00000000, 0.00000000, 0.00000000]
//!   movej(pose_trans(deflex_frame, p[0.0200000, …]), a=0.5, v=0.2)
//!   movel(pose_trans(deflex_frame, p[0.0199239, 0.0017431, -0.0000033, 0.00000000, 3.14159265, 0.00000000]), a=0.2, v=0.01000, r=0.0002000)
//!   …
//! end
//! deflex_path()
//! ```
//!
//! * Poses `p[x, y, z, rx, ry, rz]`: metres and a rotation vector in radians (URScript manual,
//!   module *motion*), relative to `deflex_frame`, the program frame in the robot base frame
//!   (`pose_trans(frame, pose)` composes them); `set_tcp` installs the model's TCP.
//! * `movel(pose, a, v, r)`: `a` in m/s², `v` in m/s, blend radius `r` in m, at most 45 % of the
//!   shorter neighbouring segment (UR refuses overlapping blends) and 0 on the last move.
//! * The first move is a slow `movej` to the first pose (inverse kinematics on the controller).

use crate::ProgramFile;
use crate::common::{blend_radii, check_lines, check_points, comment_text, header_lines, num};
use crate::error::ProgramError;
use crate::names::{URSCRIPT, sanitize};
use crate::orientation::ur_rotation_vector;
use crate::settings::ProgramSettings;
use crate::{Pose, ProgramInput};
use std::fmt::Write as _;

const FORMAT: &str = "URScript";

fn pose_text(position_m: [f64; 3], r: [f64; 3]) -> String {
    format!(
        "p[{}, {}, {}, {}, {}, {}]",
        num(position_m[0], 7),
        num(position_m[1], 7),
        num(position_m[2], 7),
        num(r[0], 8),
        num(r[1], 8),
        num(r[2], 8)
    )
}

fn frame_text(pose: &Pose) -> String {
    let t = pose.translation.vector;
    pose_text([t.x, t.y, t.z], ur_rotation_vector(&pose.rotation, None))
}

pub(crate) fn export(
    input: &ProgramInput,
    settings: &ProgramSettings,
) -> Result<Vec<ProgramFile>, ProgramError> {
    let points = check_points(FORMAT, input, settings)?;
    let name = sanitize(&settings.program.name, &URSCRIPT);
    let u = &settings.ur;
    let blends = blend_radii(&points, settings.program.blend_mm);
    let mut out = String::with_capacity(points.len() * 150 + 2048);
    for line in header_lines(input) {
        let _ = writeln!(out, "# {}", comment_text(&line, &[]));
    }
    let _ = writeln!(out, "def {name}():");
    let _ = writeln!(out, "  set_tcp({})", frame_text(&input.tool_in_flange));
    let _ = writeln!(
        out,
        "  deflex_frame = {}",
        frame_text(&input.frame_in_robot)
    );
    let mut previous: Option<[f64; 3]> = None;
    for (i, p) in points.iter().enumerate() {
        let r = ur_rotation_vector(&p.rotation, previous);
        previous = Some(r);
        let position = p.position_mm * 1e-3;
        let pose = pose_text(position.into(), r);
        if i == 0 {
            let _ = writeln!(
                out,
                "  movej(pose_trans(deflex_frame, {pose}), a={}, v={})",
                num(u.approach_joint_acceleration_rad_s2, 3),
                num(u.approach_joint_speed_rad_s, 3)
            );
            continue;
        }
        let _ = writeln!(
            out,
            "  movel(pose_trans(deflex_frame, {pose}), a={}, v={}, r={})",
            num(u.acceleration_m_s2, 3),
            num(p.speed_mm_s * 1e-3, 5),
            num(blends[i] * 1e-3, 7)
        );
    }
    let _ = writeln!(out, "end");
    let _ = writeln!(out, "{name}()");
    check_lines(FORMAT, &out)?;
    Ok(vec![ProgramFile {
        path: format!("{name}.script"),
        contents: out,
    }])
}

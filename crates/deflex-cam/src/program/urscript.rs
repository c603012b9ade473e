//! Universal Robots URScript (CB3 / e-Series): `NAME.script`, one function and its call.
//!
//! ```text
//! def deflex_path():
//!   set_tcp(p[0.0000000, 0.0000000, 0.1500000, 0.00000000, 0.00000000, 0.00000000])
//!   set_payload(1.050, [0.0020, -0.0010, 0.0850])
//!   deflex_frame = p[0.7200000, 0.0000000, 0.0200000, 0.00000000, 0.00000000, 0.00000000]
//!   movej([0.1, -1.9, 2.0, -1.6, -1.57, 0.1], a=0.5, v=0.2)      start joint move
//!   movel(pose_trans(deflex_frame, p[0.0250000, 0, 0.0250000, …]), a=0.2, v=0.01000, r=0)  clearance
//!   movel(pose_trans(deflex_frame, p[0.0250000, 0, 0.0050000, …]), …)                      approach
//!   movel(pose_trans(deflex_frame, p[0.0199239, 0.0017431, -0.0000033, 0.00000000, 3.14159265, 0.00000000]), a=0.2, v=0.01000, r=0.0002000)
//!   …
//!   movel(…)                                                                               retract
//! end
//! deflex_path()
//! ```
//!
//! * Poses `p[x, y, z, rx, ry, rz]`: metres and a rotation vector in radians (URScript manual,
//!   module *motion*), relative to `deflex_frame`, the program frame in the robot base frame
//!   (`pose_trans(frame, pose)` composes them); `set_tcp` installs the model's TCP and
//!   `set_payload` the tool load (mass kg, centre of gravity m in the flange frame).
//! * `movel(pose, a, v, r)`: `a` in m/s², `v` in m/s, blend radius `r` in m, at most 45 % of the
//!   shorter neighbouring segment (UR refuses overlapping blends) and 0 on the approach, rapids,
//!   the last move and the retract.
//! * The start joint move `movej([q1 … q6])` goes to the joint values of the clearance point
//!   above the start (the model's IK), so the controller does not choose a configuration.
//! * URScript cannot call another file: a long path is split into complete scripts
//!   `NAME_p01.script` … run one after the other (each part continues from where the previous
//!   one ended; the first holds the start and the approach, the last the retract).

use crate::program::ProgramInput;
use crate::program::common::{Checked, comment_text, header_lines, num};
use crate::program::error::ProgramError;
use crate::program::names::{URSCRIPT, sanitize};
use crate::program::plan::{part_name, plan};
use crate::program::settings::ProgramSettings;
use crate::program::sink::{ProgramSink, emit};
use deflex_model::Pose;
use deflex_model::conventions::rotation_vector;
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
    pose_text([t.x, t.y, t.z], rotation_vector(&pose.rotation, None))
}

/// Longest motion line.
const LINE_BYTES: usize = 170;

/// Write the scripts to `sink`, each as soon as it is complete; returns them in the order they
/// run.
pub(crate) fn export(
    input: &ProgramInput,
    settings: &ProgramSettings,
    sink: &mut dyn ProgramSink,
) -> Result<Vec<String>, ProgramError> {
    let plan = plan(FORMAT, input, settings, LINE_BYTES)?;
    let name = sanitize(&settings.program.name, &URSCRIPT);
    let u = &settings.ur;
    let a = num(u.acceleration_m_s2, 3);
    let mut files = Vec::new();
    let mut previous: Option<[f64; 3]> = None;
    let count = plan.parts.len();
    for (part, range) in plan.parts.iter().enumerate() {
        let (first, last) = (part == 0, part + 1 == count);
        let function = if plan.split() {
            part_name(&name, part)
        } else {
            name.clone()
        };
        let mut out = String::with_capacity(range.len() * 160 + 4096);
        for line in header_lines(input) {
            let _ = writeln!(out, "# {}", comment_text(&line, &[]));
        }
        if plan.split() {
            let _ = writeln!(
                out,
                "# part {} of {count} of {name}: path points {} to {}; run the parts in order \
                 (URScript cannot call another file)",
                part + 1,
                range.start,
                range.end - 1
            );
        }
        let _ = writeln!(out, "def {function}():");
        let _ = writeln!(out, "  set_tcp({})", frame_text(&input.tool_in_flange));
        if let Some(l) = &plan.tool_load_in_flange {
            let _ = writeln!(
                out,
                "  set_payload({}, [{}, {}, {}])",
                num(l.mass_kg, 3),
                num(l.centre_of_mass_m[0], 4),
                num(l.centre_of_mass_m[1], 4),
                num(l.centre_of_mass_m[2], 4)
            );
        }
        let _ = writeln!(
            out,
            "  deflex_frame = {}",
            frame_text(&input.frame_in_robot)
        );
        let movel = |out: &mut String, p: &Checked, r: [f64; 3], v_mm_s: f64, blend_mm: f64| {
            let position = p.position_mm * 1e-3;
            let _ = writeln!(
                out,
                "  movel(pose_trans(deflex_frame, {}), a={a}, v={}, r={})",
                pose_text(position.into(), r),
                num(v_mm_s * 1e-3, 5),
                num(blend_mm * 1e-3, 7)
            );
        };
        if first {
            let r = rotation_vector(&plan.clear[0].rotation, previous);
            previous = Some(r);
            match &plan.clear[0].config {
                Some(c) => {
                    let q = c.joints_rad;
                    let _ = writeln!(
                        out,
                        "  # start joint move: the clearance point above the start\n  movej([{}, {}, {}, {}, {}, {}], a={}, v={})",
                        num(q[0], 6),
                        num(q[1], 6),
                        num(q[2], 6),
                        num(q[3], 6),
                        num(q[4], 6),
                        num(q[5], 6),
                        num(u.approach_joint_acceleration_rad_s2, 3),
                        num(u.approach_joint_speed_rad_s, 3)
                    );
                }
                None => {
                    let position = plan.clear[0].position_mm * 1e-3;
                    let _ = writeln!(
                        out,
                        "  movej(pose_trans(deflex_frame, {}), a={}, v={})",
                        pose_text(position.into(), r),
                        num(u.approach_joint_acceleration_rad_s2, 3),
                        num(u.approach_joint_speed_rad_s, 3)
                    );
                }
            }
            if plan.clear[0].config.is_some() {
                // The clearance point as a Cartesian motion too (the readers compare it).
                movel(&mut out, &plan.clear[0], r, plan.clear[0].speed_mm_s, 0.0);
            }
            let _ = writeln!(out, "  # approach");
            let first = plan.point(0);
            let r = rotation_vector(&first.rotation, previous);
            previous = Some(r);
            movel(&mut out, &first, r, plan.clear[0].speed_mm_s, 0.0);
        }
        for i in range.clone() {
            let p = &plan.point(i);
            let r = rotation_vector(&p.rotation, previous);
            previous = Some(r);
            let blend = if p.rapid {
                0.0
            } else {
                plan.blend_radius(i, settings.program.blend_mm)
            };
            movel(&mut out, p, r, p.speed_mm_s, blend);
        }
        if last {
            let _ = writeln!(out, "  # retract");
            let r = rotation_vector(&plan.clear[1].rotation, previous);
            movel(&mut out, &plan.clear[1], r, plan.clear[1].speed_mm_s, 0.0);
        }
        let _ = writeln!(out, "end");
        let _ = writeln!(out, "{function}()");
        let path = format!("{function}.script");
        emit(sink, FORMAT, &path, &out)?;
        files.push(path);
    }
    Ok(files)
}

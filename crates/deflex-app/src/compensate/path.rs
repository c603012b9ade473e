//! The tool path of a compensation placed in the world: read (a built-in path, a G-code file,
//! an array), cut and split, its tool orientation from the seed configuration (along −Z of the
//! part frame for a 3-axis program), and every point within the arm's reach.

use super::setup::degrees;
use super::{Frame, Options, PathSpec};
use crate::error::{Error, Result};
use crate::option_names::OptionNames;
use deflex_compensate::TcpPath;
use deflex_model::{Pose, Robot};
use deflex_sim::{ToolPath, Waypoint};
use nalgebra::{Rotation3, Translation3, Unit, Vector3};

/// Largest angle between the seed's tool axis and the path's (deg).
pub const MAX_TOOL_AXIS_DEG: f64 = 1.0;

/// The desired path of a compensation.
pub(super) struct PlacedPath {
    /// The tool path without its waypoints (the process model reads its step-down and wall
    /// angle).
    pub tool_path: ToolPath,
    /// The desired TCP path in the world.
    pub path: TcpPath,
    /// The work offset the G-code names (`G54` …), if any.
    pub frame_name: Option<String>,
    /// The G-code reader's notes, each after the path's name.
    pub notes: Vec<String>,
}

/// The spec's tool path, cut to [`Options::length_mm`], its moves split to
/// [`Options::max_segment_mm`], placed in the world at `part_frame` with the seed's tool
/// orientation (a 3-axis program's tool axis; an array's own orientations or the seed's).
#[allow(clippy::too_many_arguments)]
pub(super) fn placed_path(
    robot: &Robot,
    robot_shown: &str,
    spec: &PathSpec,
    options: &Options,
    seed: &[f64],
    part_frame: &Pose,
    rapid_feed_mm_s: f64,
    names: OptionNames,
) -> Result<PlacedPath> {
    let (mut tool_path, program) = tool_path(spec, options, part_frame, names)?;
    if let Some(l) = options.length_mm {
        tool_path = tool_path.truncated(l);
    }
    if let Some(max) = options.max_segment_mm {
        tool_path = tool_path
            .subdivided(max)
            .map_err(|e| Error::invalid(names.name("max_segment_m"), e.to_string()))?;
    }
    let frame_name = program
        .as_ref()
        .and_then(|p| p.work_offset)
        .map(|w| w.name().to_string());
    let notes = program.as_ref().map_or_else(Vec::new, |p| {
        p.notes
            .iter()
            .map(|n| format!("{}: {n}", spec.shown()))
            .collect()
    });
    let path = match spec {
        PathSpec::Array { .. } => {
            let held = robot
                .tcp_pose(seed)
                .map_err(|e| Error::invalid(names.name("seed_q"), e.to_string()))?
                .rotation;
            array_tcp_path(spec, &tool_path, part_frame, &held, rapid_feed_mm_s)?
        }
        _ => {
            let rotation = tool_rotation(
                robot,
                seed,
                part_frame,
                frame_name.as_deref(),
                robot_shown,
                names,
            )?;
            deflex_sim::tcp_path(&tool_path, part_frame, &rotation, rapid_feed_mm_s).map_err(
                |source| Error::PathSpec {
                    flag: names.name("path"),
                    spec: spec.shown(),
                    source: Box::new(source),
                },
            )?
        }
    };
    // The process model reads only the step-down and the wall angle: free the waypoints.
    tool_path.waypoints = Vec::new();
    Ok(PlacedPath {
        tool_path,
        path,
        frame_name,
        notes,
    })
}

/// The tool path (part frame, mm): a built-in one, a G-code file read with its notes, or an
/// array's positions mapped into the part frame.
fn tool_path(
    spec: &PathSpec,
    options: &Options,
    part_frame: &Pose,
    names: OptionNames,
) -> Result<(ToolPath, Option<deflex_sim::gcode::GcodeProgram>)> {
    let path_error = |source| Error::PathSpec {
        flag: names.name("path"),
        spec: spec.shown(),
        source: Box::new(source),
    };
    match spec {
        PathSpec::Builtin(name) => Ok((
            crate::load::gcode_file::tool_path_by_name(name).map_err(path_error)?,
            None,
        )),
        PathSpec::Gcode(file) => {
            let read = deflex_sim::gcode::ReadOptions {
                chord_tolerance_mm: options.chord_tolerance_mm,
                ..deflex_sim::gcode::default_options()
            };
            let (path, program) =
                crate::load::gcode_file::read_gcode_with(file, &read).map_err(path_error)?;
            Ok((path, Some(program)))
        }
        PathSpec::Array {
            values,
            cols,
            frame,
            feed_m_s,
        } => {
            if *cols == 6 && (options.length_mm.is_some() || options.max_segment_mm.is_some()) {
                return Err(Error::invalid(
                    names.name("length_m"),
                    format!(
                        "{} and {} apply to paths of positions; an (N, 6) path of poses is compensated as given",
                        names.name("length_m"),
                        names.name("max_segment_m")
                    ),
                ));
            }
            let to_part = match frame {
                Frame::Part => Pose::identity(),
                Frame::World => part_frame.inverse(),
            };
            let waypoints = values
                .chunks(*cols)
                .enumerate()
                .map(|(i, r)| {
                    let p = to_part * nalgebra::Point3::new(r[0], r[1], r[2]) * 1e3;
                    Waypoint {
                        p_mm: [p.x, p.y, p.z],
                        feed_mm_s: if i == 0 {
                            None
                        } else {
                            feed_m_s.map(|f| f * 1e3)
                        },
                    }
                })
                .collect();
            let path = ToolPath {
                name: "array path".into(),
                waypoints,
                step_down_mm: None,
                wall_angle_deg: None,
            };
            Ok((path, None))
        }
    }
}

/// The TCP path of an array: a `(rows × 6)` array keeps its orientations, positions take the
/// orientation `held` of the seed configuration.
fn array_tcp_path(
    spec: &PathSpec,
    tool_path: &ToolPath,
    part_frame: &Pose,
    held: &Rotation3<f64>,
    rapid_feed_mm_s: f64,
) -> Result<TcpPath> {
    if let PathSpec::Array {
        values,
        cols: 6,
        frame,
        feed_m_s,
    } = spec
    {
        let to_world = match frame {
            Frame::Part => *part_frame,
            Frame::World => Pose::identity(),
        };
        let poses = values.chunks(6).enumerate().map(|(i, r)| {
            let local = Pose::from_parts(
                Translation3::new(r[0], r[1], r[2]),
                Rotation3::from_scaled_axis(Vector3::new(r[3], r[4], r[5])),
            );
            (to_world * local, if i == 0 { None } else { *feed_m_s })
        });
        return Ok(TcpPath::new("array path", poses, rapid_feed_mm_s * 1e-3)?);
    }
    Ok(deflex_sim::tcp_path(
        tool_path,
        part_frame,
        held,
        rapid_feed_mm_s,
    )?)
}

/// The path's tool orientation: the tool axis (TCP z) exactly along −Z of the part frame (the
/// tool axis of a 3-axis program), turned about it as the seed holds the tool. A seed more than
/// [`MAX_TOOL_AXIS_DEG`] off is refused.
fn tool_rotation(
    robot: &Robot,
    seed: &[f64],
    part: &Pose,
    frame_name: Option<&str>,
    robot_shown: &str,
    names: OptionNames,
) -> Result<Rotation3<f64>> {
    let held = robot
        .tcp_pose(seed)
        .map_err(|e| Error::invalid(names.name("seed_q"), e.to_string()))?
        .rotation;
    let axis = held * Vector3::z();
    let want = part.rotation * -Vector3::z();
    let angle = axis.angle(&want);
    if angle.to_degrees() > MAX_TOOL_AXIS_DEG {
        return Err(Error::ToolAxis {
            seed: degrees(seed),
            angle_deg: angle.to_degrees(),
            frame: frame_name.map_or(String::new(), |n| format!(" {n}")),
            seed_flag: names.name("seed_q"),
            robot: robot_shown.to_string(),
        });
    }
    // The smallest rotation taking the held axis onto the path's.
    let align = Rotation3::rotation_between(&axis, &want).unwrap_or_else(|| {
        Rotation3::from_axis_angle(
            &Unit::new_normalize(axis.cross(&Vector3::x())),
            std::f64::consts::PI,
        )
    });
    Ok(align * held)
}

/// Every path point within the arm's reach (the sum of its link lengths from joint 1).
pub(super) fn check_reach(
    robot: &Robot,
    path: &TcpPath,
    part_origin_mm: &[f64; 3],
    names: OptionNames,
) -> Result<()> {
    let shoulder = (robot.base * robot.joints[0].placement).translation.vector;
    let reach = robot.reach_bound();
    let mut count = 0;
    let mut first = None;
    for (i, p) in path.points().iter().enumerate() {
        let d = (p.pose.translation.vector - shoulder).norm();
        if d > reach {
            count += 1;
            first.get_or_insert((i, d));
        }
    }
    match first {
        None => Ok(()),
        Some((i, d)) => Err(Error::OutOfReach {
            count,
            points: path.len(),
            first: i,
            distance_mm: d * 1e3,
            reach_mm: reach * 1e3,
            x: part_origin_mm[0],
            y: part_origin_mm[1],
            z: part_origin_mm[2],
            part_flag: names.name("part_xyz_m"),
        }),
    }
}

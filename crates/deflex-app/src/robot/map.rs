//! The deflection map (`deflex map`): the predicted TCP deflection over a square grid of TCP
//! positions with the tool pointing down (the paper's Fig. 10 set-up), written as a CSV table and
//! two heatmaps into a folder built aside and swapped in whole.

use crate::error::{Error, Result, bounded};
use deflex_model::{Data, Displacement, IkOptions, Robot, Wrench};
use serde_json::json;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Largest grid side (m).
pub const MAX_MAP_SIZE_M: f64 = 20.0;
/// Most nodes per grid side (the grid holds the square of it).
pub const MAX_MAP_NODES_PER_SIDE: usize = 1001;

/// The square grid of a deflection map, SI.
#[derive(Clone, Debug)]
pub struct MapGrid {
    /// Height of the horizontal plane (m, world).
    pub z_m: f64,
    /// Centre x, y (m, world).
    pub center_m: [f64; 2],
    /// Side length (m), at most [`MAX_MAP_SIZE_M`].
    pub size_m: f64,
    /// Step between nodes (m): at most [`MAX_MAP_NODES_PER_SIDE`] nodes per side.
    pub step_m: f64,
    /// Wrench at the TCP, world axes: fx, fy, fz (N), mx, my, mz (N·m).
    pub wrench: [f64; 6],
}

impl MapGrid {
    /// Nodes per side the step and size ask for, before the limit (a fraction: the caller
    /// rounds down and adds one).
    pub fn steps_per_side(size_m: f64, step_m: f64) -> f64 {
        size_m / step_m + 1e-9
    }

    /// Nodes per side, or why the grid cannot be drawn (the front ends check their flags, in
    /// their units, first).
    fn nodes_per_side(&self) -> Result<usize> {
        if !(self.step_m > 0.0 && self.size_m >= 0.0) {
            return Err(Error::invalid(
                "step_m",
                format!(
                    "expected a positive step over a non-negative size, got {} m over {} m",
                    self.step_m, self.size_m
                ),
            ));
        }
        bounded("size_m", self.size_m, 0.0, MAX_MAP_SIZE_M, "m")?;
        let per_side = Self::steps_per_side(self.size_m, self.step_m);
        if per_side >= MAX_MAP_NODES_PER_SIDE as f64 {
            return Err(Error::invalid(
                "step_m",
                format!("at most {MAX_MAP_NODES_PER_SIDE} nodes per side"),
            ));
        }
        Ok(per_side.floor() as usize + 1)
    }
}

/// One grid node of a deflection map.
#[derive(Clone, Debug)]
pub struct MapNode {
    /// TCP position (m, world).
    pub position_m: [f64; 3],
    /// Joint values reaching it (rad).
    pub q_rad: Vec<f64>,
    /// Predicted deflection `[δp; δφ]` (m, rad).
    pub deflection: Displacement,
}

/// Deflection over a square grid of TCP positions with the tool pointing down (the orientation
/// of the paper's forming configuration), IK seeded along a serpentine so neighbours share a
/// branch. Nodes out of reach are skipped and counted: returns the nodes and that count.
pub fn deflection_grid(robot: &Robot, grid: &MapGrid) -> Result<(Vec<MapNode>, usize)> {
    let count = grid.nodes_per_side()?;
    let (z_m, center_m, step_m) = (grid.z_m, grid.center_m, grid.step_m);
    let wrench = Wrench::from_row_slice(&grid.wrench);
    let seed = super::default_seed(robot);
    let reference = robot
        .tcp_pose(&seed)
        .map_err(deflex_model::ModelError::from)?;
    let mut data = Data::new();
    let mut nodes = Vec::with_capacity(count * count);
    let mut unreachable = 0;
    let mut previous = seed.clone();
    let offset = (count as f64 - 1.0) * step_m / 2.0;
    for row in 0..count {
        let y = center_m[1] - offset + row as f64 * step_m;
        let mut row_seed = previous.clone();
        for k in 0..count {
            let col = if row % 2 == 0 { k } else { count - 1 - k };
            let x = center_m[0] - offset + col as f64 * step_m;
            let mut target = reference;
            target.translation.vector = nalgebra::Vector3::new(x, y, z_m);
            match robot.inverse_kinematics(&target, &row_seed, &IkOptions::default()) {
                Ok(solution) => {
                    robot
                        .forward_kinematics(&mut data, &solution.q)
                        .map_err(deflex_model::ModelError::from)?;
                    let deflection = robot.tcp_deflection(&data, &wrench);
                    row_seed = solution.q.clone();
                    nodes.push(MapNode {
                        position_m: [x, y, z_m],
                        q_rad: solution.q,
                        deflection,
                    });
                }
                Err(_) => unreachable += 1,
            }
        }
        previous = row_seed;
    }
    Ok((nodes, unreachable))
}

/// A deflection map computed and written (`deflex map`).
#[derive(Clone, Debug)]
pub struct DeflectionMap {
    /// The nodes reached.
    pub nodes: Vec<MapNode>,
    /// Nodes out of reach.
    pub unreachable: usize,
    /// Time the grid took (s), writing left out.
    pub elapsed_s: f64,
    /// The CSV table written.
    pub csv: PathBuf,
    /// The heatmaps written.
    pub png: Vec<PathBuf>,
}

/// Compute the map of `grid` for `robot` and write it into the folder `out` (built aside and
/// swapped in whole: a failed run leaves the earlier map as it was, and a second run on the
/// same folder is refused while this one writes). A grid none of whose nodes the arm reaches
/// writes nothing. The folder holds two heatmaps: without the `report` feature the map is
/// refused before it is computed ([`deflection_grid`] computes it in every build).
pub fn write_map(robot: &Robot, grid: &MapGrid, out: &Path) -> Result<DeflectionMap> {
    let drawing = crate::report::require("the deflection map with its heatmaps (`deflex map`)")?;
    let started = Instant::now();
    let (nodes, unreachable) = deflection_grid(robot, grid)?;
    let elapsed_s = started.elapsed().as_secs_f64();
    if nodes.is_empty() {
        return Err(Error::NoReachableNode);
    }
    let folder = deflex_files::AtomicDir::create(out).map_err(Error::io_on(out))?;
    let csv = out.join("deflection_map.csv");
    deflex_files::write_atomic(
        folder.path().join("deflection_map.csv"),
        map_csv(&nodes, robot.joint_count()),
    )
    .map_err(Error::io_on(&csv))?;
    let png = drawing
        .map_plots(folder.path(), &nodes, &robot.name, &grid.wrench)?
        .iter()
        .filter_map(|p| p.file_name().map(|name| out.join(name)))
        .collect();
    folder.commit().map_err(Error::io_on(out))?;
    Ok(DeflectionMap {
        nodes,
        unreachable,
        elapsed_s,
        csv,
        png,
    })
}

/// `deflection_map.csv`: position, joint values and deflection of every node (SI).
fn map_csv(nodes: &[MapNode], joints: usize) -> String {
    let mut csv = String::from("x_m,y_m,z_m,");
    for i in 1..=joints {
        let _ = write!(csv, "q{i}_rad,");
    }
    csv.push_str("dx_m,dy_m,dz_m,drx_rad,dry_rad,drz_rad\n");
    for node in nodes {
        let _ = write!(
            csv,
            "{:?},{:?},{:?},",
            node.position_m[0], node.position_m[1], node.position_m[2]
        );
        for q in &node.q_rad {
            let _ = write!(csv, "{q:?},");
        }
        let d = &node.deflection;
        let _ = writeln!(
            csv,
            "{:e},{:e},{:e},{:e},{:e},{:e}",
            d[0], d[1], d[2], d[3], d[4], d[5]
        );
    }
    csv
}

impl DeflectionMap {
    /// Largest and mean `|δp|` over the nodes (m).
    fn norms(&self) -> (f64, f64) {
        let norms: Vec<f64> = self
            .nodes
            .iter()
            .map(|n| n.deflection.fixed_rows::<3>(0).norm())
            .collect();
        let max = norms.iter().cloned().fold(0.0, f64::max);
        let mean = norms.iter().sum::<f64>() / norms.len() as f64;
        (max, mean)
    }

    /// As JSON (SI): node counts, the largest and mean `|δp|`, the files and the time.
    pub fn to_json(&self) -> serde_json::Value {
        let (max, mean) = self.norms();
        json!({
            "nodes": self.nodes.len(),
            "unreachable": self.unreachable,
            "max_dp_norm_m": max,
            "mean_dp_norm_m": mean,
            "csv": self.csv,
            "png": self.png,
            "elapsed_s": self.elapsed_s,
        })
    }

    /// As text (mm, ms), with the files written.
    pub fn text(&self) -> String {
        let (max, mean) = self.norms();
        let mut out = String::new();
        let _ = writeln!(
            out,
            "{} grid nodes ({} unreachable) in {:.1} ms; |δp| max {:.4} mm, mean {:.4} mm",
            self.nodes.len(),
            self.unreachable,
            self.elapsed_s * 1e3,
            max * 1e3,
            mean * 1e3
        );
        let _ = writeln!(out, "wrote {}", self.csv.display());
        for png in &self.png {
            let _ = writeln!(out, "wrote {}", png.display());
        }
        out
    }
}

/// Heatmaps of δz and |δp| over the grid (mm), one cell per node, into `out`; returns the files.
/// With the `report` feature.
#[cfg(feature = "report")]
pub fn map_plots(
    out: &Path,
    nodes: &[MapNode],
    robot_name: &str,
    wrench: &[f64; 6],
) -> std::result::Result<Vec<PathBuf>, crate::report::DrawError> {
    let mut xs: Vec<f64> = nodes.iter().map(|n| n.position_m[0] * 1e3).collect();
    let mut ys: Vec<f64> = nodes.iter().map(|n| n.position_m[1] * 1e3).collect();
    for v in [&mut xs, &mut ys] {
        v.sort_by(f64::total_cmp);
        v.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
    }
    let index = |values: &[f64], v: f64| values.iter().position(|x| (x - v).abs() < 1e-6);
    let mut dz = vec![f64::NAN; xs.len() * ys.len()];
    let mut norm = vec![f64::NAN; xs.len() * ys.len()];
    for node in nodes {
        if let (Some(ix), Some(iy)) = (
            index(&xs, node.position_m[0] * 1e3),
            index(&ys, node.position_m[1] * 1e3),
        ) {
            dz[iy * xs.len() + ix] = node.deflection[2] * 1e3;
            norm[iy * xs.len() + ix] = node.deflection.fixed_rows::<3>(0).norm() * 1e3;
        }
    }
    let load = format!(
        "F = ({:.0}, {:.0}, {:.0}) N",
        wrench[0], wrench[1], wrench[2]
    );
    let z_mm = nodes.first().map(|n| n.position_m[2] * 1e3).unwrap_or(0.0);
    let mut written = Vec::new();
    for (name, values, label) in [
        ("deflection_dz.png", &dz, "δz [mm]"),
        ("deflection_norm.png", &norm, "|δp| [mm]"),
    ] {
        let path = out.join(name);
        let spec = deflex_plot::PlotSpec::new(
            format!("{robot_name}: predicted {label} at z = {z_mm:.0} mm, {load}"),
            "x [mm]",
            "y [mm]",
        )
        .size(1000, 800);
        crate::report::draw::heatmap(&path, &spec, &xs, &ys, values, label)?;
        written.push(path);
    }
    Ok(written)
}

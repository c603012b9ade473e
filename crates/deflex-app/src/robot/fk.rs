//! `deflex model fk`: the model's forward kinematics over a table of joint values — a joint log
//! a controller wrote (LinuxCNC's, docs/linuxcnc/), or a `compensated_path.csv` — as a CSV of
//! TCP poses in deflex's own columns.
//!
//! The input is a CSV table ([`crate::table`]) with the columns `q1_rad … qN_rad` (the names of
//! `compensated_path.csv`) or `q1_deg … qN_deg`, N the robot's joint count; other columns are
//! ignored. The output has one row per input row: `index,x_m,y_m,z_m,rx_rad,ry_rad,rz_rad`, the
//! TCP of the model's tool in the robot's world frame, the orientation as a rotation vector (the
//! columns of `compensated_path.csv`).

use super::batch::{check_finite, poses};
use crate::error::{Error, Result};
use crate::table::{self, CsvTable, TableColumn};
use deflex_model::Robot;
use nalgebra::{Matrix3, Rotation3};
use serde_json::json;
use std::fmt::Write as _;
use std::path::Path;

/// The unit of a joint table's columns, from their names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JointUnit {
    /// `q1_rad …`
    Rad,
    /// `q1_deg …`
    Deg,
}

/// The TCP poses of a joint table.
#[derive(Clone, Debug, PartialEq)]
pub struct FkTable {
    /// The unit the joint columns were read in.
    pub unit: JointUnit,
    /// One row per input row: position (m) and rotation vector (rad), world frame.
    pub poses: Vec<[f64; 6]>,
}

/// The joint values of `table` in radians, `rows × n` row-major, and their unit.
pub fn joint_rows(table: &CsvTable, n: usize, origin: &str) -> Result<(Vec<f64>, JointUnit)> {
    let column = |name: &str| {
        table
            .columns
            .iter()
            .find(|(c, _)| c == name)
            .map(|(_, v)| v)
    };
    let unit = if column("q1_rad").is_some() {
        JointUnit::Rad
    } else if column("q1_deg").is_some() {
        JointUnit::Deg
    } else {
        return Err(Error::invalid(
            origin,
            format!("no joint columns: expected q1_rad … q{n}_rad or q1_deg … q{n}_deg"),
        ));
    };
    let suffix = match unit {
        JointUnit::Rad => "rad",
        JointUnit::Deg => "deg",
    };
    let mut q = vec![0.0; table.rows * n];
    for j in 0..n {
        let name = format!("q{}_{suffix}", j + 1);
        let values = match column(&name) {
            Some(TableColumn::Number(v)) => v,
            Some(TableColumn::Text(_)) => {
                return Err(Error::invalid(
                    origin,
                    format!("column {name} holds text: every cell must be a number"),
                ));
            }
            None => {
                return Err(Error::invalid(
                    origin,
                    format!("column {name} is missing (the robot has {n} joints)"),
                ));
            }
        };
        for (i, v) in values.iter().enumerate() {
            q[i * n + j] = match unit {
                JointUnit::Rad => *v,
                JointUnit::Deg => v.to_radians(),
            };
        }
    }
    check_finite("q", &q, Some(n)).map_err(Error::in_context(origin))?;
    Ok((q, unit))
}

impl FkTable {
    /// The poses of the joint rows of `table`.
    pub fn of(robot: &Robot, table: &CsvTable, origin: &str) -> Result<FkTable> {
        let n = robot.joint_count();
        let (q, unit) = joint_rows(table, n, origin)?;
        let m = poses(robot, &q, table.rows)?;
        let poses = m
            .chunks(16)
            .map(|m| {
                let r = Matrix3::new(m[0], m[1], m[2], m[4], m[5], m[6], m[8], m[9], m[10]);
                let v = Rotation3::from_matrix_unchecked(r).scaled_axis();
                [m[3], m[7], m[11], v.x, v.y, v.z]
            })
            .collect();
        Ok(FkTable { unit, poses })
    }

    /// The poses of the joint table in the file at `path`.
    pub fn read(robot: &Robot, path: &Path) -> Result<FkTable> {
        let origin = path.display().to_string();
        let table = table::read(path)?;
        FkTable::of(robot, &table, &origin)
    }

    /// As CSV: a header, then `index,x_m,y_m,z_m,rx_rad,ry_rad,rz_rad` (0.1 nm, 0.1 nrad).
    pub fn csv(&self) -> String {
        let mut out = String::from("index,x_m,y_m,z_m,rx_rad,ry_rad,rz_rad\n");
        for (i, p) in self.poses.iter().enumerate() {
            let _ = writeln!(
                out,
                "{i},{:.10},{:.10},{:.10},{:.10},{:.10},{:.10}",
                p[0], p[1], p[2], p[3], p[4], p[5]
            );
        }
        out
    }

    /// As JSON: the unit read and the poses (m, rad).
    pub fn to_json(&self) -> serde_json::Value {
        json!({
            "joint_unit": match self.unit { JointUnit::Rad => "rad", JointUnit::Deg => "deg" },
            "columns": ["x_m", "y_m", "z_m", "rx_rad", "ry_rad", "rz_rad"],
            "poses": self.poses,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ur10() -> Robot {
        crate::robot::builtin("ur10").unwrap()
    }

    #[test]
    fn degrees_and_radians_give_the_pose_of_deflex_pose() {
        let robot = ur10();
        let q_deg: [f64; 6] = [166.54, -58.46, 91.35, 57.12, 90.0, 76.54];
        let deg = format!(
            "step,q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg\n7,{}\n",
            q_deg.map(|v| v.to_string()).join(",")
        );
        let rad = format!(
            "q1_rad,q2_rad,q3_rad,q4_rad,q5_rad,q6_rad\n{}\n",
            q_deg.map(|v| format!("{:.17}", v.to_radians())).join(",")
        );
        let a = FkTable::of(&robot, &table::parse(&deg, "deg").unwrap(), "deg").unwrap();
        let b = FkTable::of(&robot, &table::parse(&rad, "rad").unwrap(), "rad").unwrap();
        assert_eq!(a.unit, JointUnit::Deg);
        assert_eq!(b.unit, JointUnit::Rad);
        let q: Vec<f64> = q_deg.iter().map(|v| v.to_radians()).collect();
        let one = crate::robot::single::PoseReport::at(&robot, &q).unwrap();
        let p = one.pose.translation.vector;
        for pose in [&a.poses[0], &b.poses[0]] {
            assert!((pose[0] - p.x).abs() < 1e-12 && (pose[1] - p.y).abs() < 1e-12);
            assert!((pose[2] - p.z).abs() < 1e-12);
            let v = one.pose.rotation.scaled_axis();
            assert!((pose[3] - v.x).abs() < 1e-9 && (pose[5] - v.z).abs() < 1e-9);
        }
        assert!(
            a.csv()
                .starts_with("index,x_m,y_m,z_m,rx_rad,ry_rad,rz_rad\n0,")
        );
    }

    #[test]
    fn a_missing_joint_column_is_named() {
        let robot = ur10();
        let text = "q1_deg,q2_deg,q3_deg,q4_deg,q5_deg\n0,0,0,0,0\n";
        let e = FkTable::of(&robot, &table::parse(text, "log").unwrap(), "log").unwrap_err();
        assert!(e.to_string().contains("q6_deg is missing"), "{e}");
        let e =
            FkTable::of(&robot, &table::parse("a,b\n1,2\n", "log").unwrap(), "log").unwrap_err();
        assert!(e.to_string().contains("no joint columns"), "{e}");
    }
}

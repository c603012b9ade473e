//! The ground-truth log of a forming run (evaluation only, at the configured log rate) and the
//! running statistics of every cycle.

use crate::cell::{SensorSample, TruthState};
use nalgebra::Vector3;
use std::fmt::Write as _;

/// One logged row (ground truth plus what the sensors reported).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FormingLogRow {
    /// Simulated time (s).
    pub time_s: f64,
    /// Ground truth of the cycle.
    pub truth: TruthState,
    /// Laser-tracker reading of the TCP, R_p (m).
    pub tracked_m: Vector3<f64>,
    /// Last raw F/T sample of the cycle.
    pub sensor: SensorSample,
}

/// The ground-truth log of a run, at the configured log rate (evaluation only).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FormingLog {
    /// Path name.
    pub path_name: String,
    /// The robot the twin played.
    pub robot: String,
    /// Seed of the run.
    pub seed: u64,
    /// Rows, in time order.
    pub rows: Vec<FormingLogRow>,
}

impl FormingLog {
    pub(crate) fn with_capacity(
        path_name: &str,
        robot: &str,
        seed: u64,
        rows: usize,
    ) -> FormingLog {
        FormingLog {
            path_name: path_name.to_string(),
            robot: robot.to_string(),
            seed,
            rows: Vec::with_capacity(rows),
        }
    }

    pub(crate) fn push(&mut self, row: FormingLogRow) {
        self.rows.push(row);
    }

    /// What the log is, as its first header comment says (without the `# `): simulated, the
    /// robot, the path and the seed.
    pub fn title(&self) -> String {
        format!(
            "SIMULATED deflex digital twin forming log (not a measurement). robot: {}; path: {}; seed: {}",
            self.robot, self.path_name, self.seed
        )
    }

    /// The log as CSV text (mm, N, N·m, mrad), with a `# SIMULATED` header comment.
    pub fn to_csv(&self) -> String {
        let mut s = String::with_capacity(self.rows.len() * 400 + 512);
        let _ = writeln!(s, "# {}", self.title());
        let _ = writeln!(
            s,
            "# positions in the part frame R_p (mm); wrench on the tool at the TCP, R_p axes (N, N·m); \
             sensor = last raw F/T sample of the cycle, sensor frame; error = true − desired"
        );
        s.push_str(
            "time_s,des_x_mm,des_y_mm,des_z_mm,cmd_x_mm,cmd_y_mm,cmd_z_mm,true_x_mm,true_y_mm,true_z_mm,\
             tracked_x_mm,tracked_y_mm,tracked_z_mm,err_x_mm,err_y_mm,err_z_mm,err_norm_mm,\
             fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm,sensor_fx_N,sensor_fy_N,sensor_fz_N,sensor_tx_Nm,\
             sensor_ty_Nm,sensor_tz_Nm,sensor_saturated,corr_x_mm,corr_y_mm,corr_z_mm,corr_rx_mrad,\
             corr_ry_mrad,corr_rz_mrad,penetration_mm,flow_level_N,tool_depth_mm\n",
        );
        for r in &self.rows {
            let t = &r.truth;
            let e = t.path_error_m();
            let _ = write!(s, "{:.4}", r.time_s);
            for v in [t.desired_m, t.commanded_m, t.true_m, r.tracked_m, e] {
                let _ = write!(s, ",{:.5},{:.5},{:.5}", v.x * 1e3, v.y * 1e3, v.z * 1e3);
            }
            let _ = write!(s, ",{:.5}", e.norm() * 1e3);
            for v in t.wrench.iter() {
                let _ = write!(s, ",{v:.3}");
            }
            for v in r.sensor.wrench_sensor {
                let _ = write!(s, ",{v:.3}");
            }
            let _ = write!(s, ",{}", r.sensor.saturated as u8);
            // m → mm and rad → mrad.
            for v in t.correction.iter() {
                let _ = write!(s, ",{:.5}", v * 1e3);
            }
            let _ = writeln!(
                s,
                ",{:.5},{:.2},{:.4}",
                t.contact.penetration_m * 1e3,
                t.contact.flow_n,
                t.contact.depth_m * 1e3
            );
        }
        s
    }

    /// Column of a per-row quantity.
    pub fn column(&self, f: impl Fn(&FormingLogRow) -> f64) -> Vec<f64> {
        self.rows.iter().map(f).collect()
    }
}

/// Statistics over every controller cycle.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunningStats {
    /// Cycles counted.
    pub cycles: u64,
    /// Cycles with the tool in contact.
    pub contact_cycles: u64,
    sum_sq_error: f64,
    /// Largest error norm (m).
    pub max_error_norm_m: f64,
    /// Largest |error| per axis (m).
    pub max_error_abs_m: [f64; 3],
    /// Largest force norm (N).
    pub max_force_norm_n: f64,
    /// Largest vertical force (N).
    pub max_fz_n: f64,
    /// Largest in-plane force norm (N).
    pub max_fxy_n: f64,
    /// Largest correction norm (m).
    pub max_correction_m: f64,
}

impl RunningStats {
    pub(crate) fn add(&mut self, t: &TruthState) {
        let e = t.path_error_m();
        let n = e.norm();
        self.cycles += 1;
        if t.wrench[2] > 0.0 {
            self.contact_cycles += 1;
        }
        self.sum_sq_error += n * n;
        self.max_error_norm_m = self.max_error_norm_m.max(n);
        for i in 0..3 {
            self.max_error_abs_m[i] = self.max_error_abs_m[i].max(e[i].abs());
        }
        let f = t.wrench.fixed_rows::<3>(0);
        self.max_force_norm_n = self.max_force_norm_n.max(f.norm());
        self.max_fz_n = self.max_fz_n.max(f[2]);
        self.max_fxy_n = self.max_fxy_n.max(f[0].hypot(f[1]));
        let c = &t.correction;
        self.max_correction_m = self
            .max_correction_m
            .max((c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt());
    }

    /// RMS of the error norm over all cycles (m).
    pub fn rms_error_norm_m(&self) -> f64 {
        if self.cycles == 0 {
            0.0
        } else {
            (self.sum_sq_error / self.cycles as f64).sqrt()
        }
    }
}

//! The plant's spring compliances: linear springs, the J2/J3 coupling and the wrist lost motion
//! with its play-operator hysteresis.

use crate::chain::MAX_SPRINGS;

/// The spring compliances: linear springs, the J2/J3 coupling, the wrist lost motion with its
/// play-operator hysteresis state.
#[derive(Clone, Debug)]
pub(super) struct Springs {
    pub(super) count: usize,
    pub(super) stiffness: [f64; MAX_SPRINGS],
    /// J2.z and J3.z indices with the off-diagonal compliance.
    pub(super) coupling: Option<(usize, usize, f64)>,
    /// J4.z, J5.z, J6.z indices and their lost motion (rad).
    pub(super) wrist: [(Option<usize>, f64); 3],
    pub(super) takeup_nm: f64,
    pub(super) hysteresis_nm: f64,
    /// Play-operator states (N·m).
    pub(super) play: [f64; 3],
}

impl Springs {
    fn play_output(&self, k: usize, torque: f64) -> f64 {
        let h = self.hysteresis_nm;
        self.play[k].clamp(torque - h, torque + h)
    }

    /// Spring rotations for torques `tau` (uses, does not change, the hysteresis state).
    pub(super) fn rotations(&self, tau: &[f64; MAX_SPRINGS], out: &mut [f64; MAX_SPRINGS]) {
        for i in 0..self.count {
            out[i] = tau[i] / self.stiffness[i];
        }
        if let Some((a, b, c)) = self.coupling {
            out[a] += c * tau[b];
            out[b] += c * tau[a];
        }
        for (k, &(index, lost)) in self.wrist.iter().enumerate() {
            if let Some(i) = index
                && lost > 0.0
            {
                out[i] += lost * (self.play_output(k, tau[i]) / self.takeup_nm).tanh();
            }
        }
    }

    pub(super) fn commit(&mut self, tau: &[f64; MAX_SPRINGS]) {
        for k in 0..3 {
            if let Some(i) = self.wrist[k].0 {
                self.play[k] = self.play_output(k, tau[i]);
            }
        }
    }

    pub(super) fn at_rest(&self) -> bool {
        self.play.iter().all(|p| *p == 0.0)
    }
}

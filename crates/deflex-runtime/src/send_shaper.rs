//! The last limiter before the wire: it acts on what was last **sent** to the robot, once per
//! robot telegram, so the robot never sees a correction step larger than the rate limit times
//! its own cycle, whatever happened in between.
//!
//! The controller's [`deflex_control::Limiter`] bounds the rate of ξ in control time. That is
//! not enough at the robot: while the robot is silent (a link glitch of 50 ms to 1 s, inside
//! RSI's own break-off budget) the controller latches `robot_link_lost` and ramps ξ out on its
//! own clock, so the first answer after the pause would jump by everything the ramp did in the
//! meantime. [`SendShaper`] runs in the robot-link thread instead: each answer moves at most
//! `max_rate × robot_cycle` per axis from the previous answer, and faults that come from the
//! robot link itself ramp out **in robot cycles** (a smoothstep over `ramp_out_s / robot_cycle`
//! answers, from the value last sent), i.e. only as the robot hears them. The same ramp ends a
//! session whose control thread has failed.

use deflex_control::limiter::smoothstep;

/// What the robot-link thread does with the controller's correction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LinkDirective {
    /// Follow the controller's ξ (rate-limited per robot cycle).
    #[default]
    Follow,
    /// Ramp what was last sent to zero over the ramp-out, counted in answers (a fault of the
    /// robot link with safe action "zero", or the control thread failed).
    RampOut,
    /// Keep sending what was last sent (a fault of the robot link with safe action "hold").
    Hold,
}

impl LinkDirective {
    /// As a byte for an atomic.
    pub fn to_u8(self) -> u8 {
        match self {
            LinkDirective::Follow => 0,
            LinkDirective::RampOut => 1,
            LinkDirective::Hold => 2,
        }
    }
    /// From [`LinkDirective::to_u8`] (unknown values follow).
    pub fn from_u8(v: u8) -> Self {
        match v {
            1 => LinkDirective::RampOut,
            2 => LinkDirective::Hold,
            _ => LinkDirective::Follow,
        }
    }
}

/// Bounds of the shaper, per axis `[x, y, z, rx, ry, rz]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SendShaperConfig {
    /// Largest change between two consecutive answers (m, rad): max rate × robot cycle.
    pub max_step: [f64; 6],
    /// Largest |value| (m, rad).
    pub max_abs: [f64; 6],
    /// Length of the ramp-out in answers (≥ 1).
    pub ramp_out_answers: u32,
}

impl SendShaperConfig {
    /// From the controller's rate and size limits, the robot cycle and the ramp-out duration.
    pub fn new(max_rate: [f64; 6], max_abs: [f64; 6], robot_cycle_s: f64, ramp_out_s: f64) -> Self {
        let cycle = if robot_cycle_s.is_finite() && robot_cycle_s > 0.0 {
            robot_cycle_s
        } else {
            0.004
        };
        let answers = (ramp_out_s / cycle).ceil();
        SendShaperConfig {
            max_step: max_rate.map(|r| {
                if r.is_finite() && r >= 0.0 {
                    r * cycle
                } else {
                    0.0
                }
            }),
            max_abs: max_abs.map(|a| if a.is_finite() && a >= 0.0 { a } else { 0.0 }),
            ramp_out_answers: if answers.is_finite() && answers >= 1.0 {
                answers.min(f64::from(u32::MAX)) as u32
            } else {
                1
            },
        }
    }
}

/// Per-answer limiter on the values sent (see the module documentation). Allocation-free.
#[derive(Clone, Debug)]
pub struct SendShaper {
    config: SendShaperConfig,
    last: [f64; 6],
    ramp: Option<([f64; 6], u32)>,
}

impl SendShaper {
    /// Nothing sent yet (zero).
    pub fn new(config: SendShaperConfig) -> Self {
        SendShaper {
            config,
            last: [0.0; 6],
            ramp: None,
        }
    }

    /// The value last sent.
    pub fn last(&self) -> [f64; 6] {
        self.last
    }

    /// True when the value last sent is zero.
    pub fn is_zero(&self) -> bool {
        self.last.iter().all(|v| *v == 0.0)
    }

    /// The value to send with this answer, given the controller's current ξ and the directive.
    #[inline]
    pub fn next(&mut self, target: &[f64; 6], directive: LinkDirective) -> [f64; 6] {
        let desired = match directive {
            LinkDirective::Follow => {
                self.ramp = None;
                *target
            }
            LinkDirective::Hold => {
                self.ramp = None;
                self.last
            }
            LinkDirective::RampOut => {
                let (from, k) = self.ramp.get_or_insert((self.last, 0));
                *k = k.saturating_add(1);
                let u = f64::from(*k) / f64::from(self.config.ramp_out_answers.max(1));
                let s = 1.0 - smoothstep(u);
                from.map(|v| s * v)
            }
        };
        let c = &self.config;
        for i in 0..6 {
            let d = if desired[i].is_finite() {
                desired[i]
            } else {
                0.0
            };
            let step = (d - self.last[i]).clamp(-c.max_step[i], c.max_step[i]);
            self.last[i] = (self.last[i] + step).clamp(-c.max_abs[i], c.max_abs[i]);
        }
        self.last
    }
}

//! A control cycle as a telemetry sample ([`deflex_telemetry::CycleSample`]): what the law
//! computed, written into the sample the runtime (or the twin) publishes.

use crate::{Controller, CycleOutput};
use deflex_model::Wrench;
use deflex_telemetry::CycleSample;

/// Writing a control cycle into a [`CycleSample`].
pub trait RecordCycle {
    /// Records one cycle of `controller`: the joint values `q_rad` it was given, the raw reading
    /// `wrench_raw` (sensor frame), what it produced (`out`: time, wrenches, δŝ, ξ, ε,
    /// feed-forward, arc length, loop gain, flags), the TCP from its forward kinematics of
    /// `q_rad` (base frame), its phase and latched fault. Leaves the counters, the cycle number,
    /// the cycle time and the truth untouched (the publisher's). Allocation-free.
    fn record_cycle(
        &mut self,
        controller: &Controller,
        q_rad: &[f64],
        wrench_raw: &Wrench,
        out: &CycleOutput,
    );

    /// Records what a control cycle produced (`out`: time, wrenches, δŝ, ξ, ε, feed-forward,
    /// arc length, loop gain, flags). Allocation-free.
    fn record_output(&mut self, out: &CycleOutput);
}

impl RecordCycle for CycleSample {
    #[inline]
    fn record_cycle(
        &mut self,
        controller: &Controller,
        q_rad: &[f64],
        wrench_raw: &Wrench,
        out: &CycleOutput,
    ) {
        self.set_q(q_rad);
        self.wrench_raw = (*wrench_raw).into();
        self.record_output(out);
        self.tcp_position_m = controller.tcp_position_in_base().into();
        self.set_tcp_rotation(&controller.tcp_rotation_in_base());
        self.phase_code = CycleSample::phase_to_code(controller.phase());
        self.fault = CycleSample::fault_to_code(controller.fault().map(|f| f.kind));
    }

    #[inline]
    fn record_output(&mut self, out: &CycleOutput) {
        self.time_s = out.time_s;
        self.wrench_sensor = out.wrench_sensor;
        self.wrench_tcp = out.wrench_tcp;
        self.deflection = out.delta_s_hat;
        self.correction = out.xi;
        self.error = out.epsilon;
        self.feedforward = out.feedforward;
        self.path_s_m = out.path_s_m;
        self.loop_gain = out.loop_gain;
        self.flags = out.flags.0;
    }
}

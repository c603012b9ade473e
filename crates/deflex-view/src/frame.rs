//! Server-side decimation and the wire format of the page's data.
//!
//! The control thread publishes every cycle (100–250 Hz); the page gets one **bucket** per
//! [`BUCKET_S`] of session time (25 per second): the last sample of the bucket for every value,
//! except the peaks a person must not miss, which are the bucket's maxima (force norm, cycle
//! time) or the union of its status bits (flags). Ten minutes are 15 000 buckets.
//!
//! A binary WebSocket message is a 16-byte header of four little-endian `u32` — kind
//! ([`KIND_HISTORY`] or [`KIND_LIVE`]), bucket count, values per bucket ([`FIELDS`]`.len()`),
//! frames dropped for this client so far (saturating) — followed by the buckets, each
//! [`FIELDS`]`.len()` little-endian `f64` in the order of [`FIELDS`] (NaN: unknown).

use deflex_telemetry::{CycleSample, LATE_UNKNOWN};

/// Session time covered by one bucket (s): 25 updates a second.
pub const BUCKET_S: f64 = 0.04;
/// Scrolling window the server keeps and the page shows (s).
pub const WINDOW_S: f64 = 600.0;
/// Buckets in the window.
pub const HISTORY_BUCKETS: usize = (WINDOW_S / BUCKET_S) as usize;
/// Most buckets in one message (history is sent in several).
pub const MAX_BUCKETS_PER_MESSAGE: usize = 1000;
/// Cycles over which the p99 cycle time is taken (a sliding window).
pub const P99_WINDOW: usize = 1000;

/// History message (sent once, in pieces, when a page connects).
pub const KIND_HISTORY: u32 = 1;
/// Live message.
pub const KIND_LIVE: u32 = 2;
/// Header length of a binary message (bytes).
pub const HEADER_BYTES: usize = 16;

/// Names of the values of a bucket, in wire order (units in the names; sent to the page in the
/// hello message).
pub const FIELDS: [&str; 44] = [
    "t_s",
    "cycle",
    "fx_n",
    "fy_n",
    "fz_n",
    "mx_nm",
    "my_nm",
    "mz_nm",
    "f_norm_n",
    "f_norm_max_n",
    "ds_x_m",
    "ds_y_m",
    "ds_z_m",
    "ds_rx_rad",
    "ds_ry_rad",
    "ds_rz_rad",
    "xi_x_m",
    "xi_y_m",
    "xi_z_m",
    "xi_rx_rad",
    "xi_ry_rad",
    "xi_rz_rad",
    "err_x_m",
    "err_y_m",
    "err_z_m",
    "err_norm_m",
    "tcp_x_m",
    "tcp_y_m",
    "tcp_z_m",
    "prog_x_m",
    "prog_y_m",
    "prog_z_m",
    "phase",
    "flags",
    "fault",
    "cycle_time_s",
    "cycle_time_max_s",
    "cycle_time_p99_s",
    "late_answers",
    "robot_late",
    "samples",
    "view_lost",
    "path_s_m",
    "loop_gain",
];

/// Values per bucket.
pub const NFIELDS: usize = FIELDS.len();

/// One bucket, in wire order.
pub type Bucket = [f64; NFIELDS];

/// Builds buckets from samples and keeps the p99 window. Allocation-free after construction.
pub struct Decimator {
    open: Option<Bucket>,
    bucket_start: f64,
    times: Box<[f64; P99_WINDOW]>,
    times_len: usize,
    times_next: usize,
    scratch: Box<[f64; P99_WINDOW]>,
}

impl Default for Decimator {
    fn default() -> Self {
        Decimator {
            open: None,
            bucket_start: f64::NEG_INFINITY,
            times: Box::new([0.0; P99_WINDOW]),
            times_len: 0,
            times_next: 0,
            scratch: Box::new([0.0; P99_WINDOW]),
        }
    }
}

impl Decimator {
    /// Adds a sample; returns the bucket it closed, if any (a sample beyond the open bucket's
    /// span, or earlier than its start — a new session clock — closes it).
    pub fn push(&mut self, s: &CycleSample, view_lost: u64) -> Option<Bucket> {
        if s.cycle_time_s.is_finite() {
            self.times[self.times_next] = s.cycle_time_s;
            self.times_next = (self.times_next + 1) % P99_WINDOW;
            self.times_len = (self.times_len + 1).min(P99_WINDOW);
        }
        let closes = self.open.is_some()
            && (s.time_s >= self.bucket_start + BUCKET_S - 1e-9 || s.time_s < self.bucket_start);
        let closed = if closes { self.open.take() } else { None };
        let previous = self.open.take();
        if previous.is_none() {
            self.bucket_start = if s.time_s.is_finite() { s.time_s } else { 0.0 };
        }
        let mut b = sample_values(s, view_lost);
        if let Some(p) = previous {
            b[9] = b[9].max(p[9]); // f_norm_max_n
            b[33] = f64::from(b[33] as u32 | p[33] as u32); // flags
            b[36] = b[36].max(p[36]); // cycle_time_max_s
            b[40] += p[40]; // samples
        }
        b[37] = self.p99();
        self.open = Some(b);
        closed
    }

    /// Closes the open bucket (at the end of a server tick), if any.
    pub fn flush(&mut self) -> Option<Bucket> {
        self.open.take()
    }

    /// 99th percentile of the cycle times in the window (nearest rank), NaN when empty.
    fn p99(&mut self) -> f64 {
        let n = self.times_len;
        if n == 0 {
            return f64::NAN;
        }
        let data = &mut self.scratch[..n];
        data.copy_from_slice(&self.times[..n]);
        // Nearest rank: the ⌈0.99 n⌉-th smallest value.
        let rank = ((0.99 * n as f64).ceil() as usize).clamp(1, n) - 1;
        let (_, v, _) = data.select_nth_unstable_by(rank, |a, b| a.total_cmp(b));
        *v
    }
}

fn sample_values(s: &CycleSample, view_lost: u64) -> Bucket {
    let mut b = [f64::NAN; NFIELDS];
    b[0] = s.time_s;
    b[1] = s.cycle as f64;
    b[2..8].copy_from_slice(&s.wrench_tcp);
    b[8] = s.force_norm_n();
    b[9] = b[8];
    b[10..16].copy_from_slice(&s.deflection);
    b[16..22].copy_from_slice(&s.correction);
    b[22..25].copy_from_slice(&s.truth_error_m);
    let e = &s.truth_error_m;
    b[25] = (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt();
    b[26..29].copy_from_slice(&s.tcp_position_m);
    let p = s.program_position_m();
    b[29..32].copy_from_slice(&[p.x, p.y, p.z]);
    b[32] = f64::from(s.phase_code);
    b[33] = f64::from(s.flags);
    b[34] = f64::from(s.fault);
    b[35] = s.cycle_time_s;
    b[36] = s.cycle_time_s;
    b[38] = s.late_answers as f64;
    b[39] = if s.robot_late == LATE_UNKNOWN {
        f64::NAN
    } else {
        s.robot_late as f64
    };
    b[40] = 1.0;
    b[41] = view_lost as f64;
    b[42] = s.path_s_m;
    b[43] = s.loop_gain;
    b
}

/// Encodes buckets as one binary message of `kind` (see the module docs).
pub fn encode(kind: u32, buckets: &[Bucket], dropped: u64) -> Vec<u8> {
    let mut out = Vec::with_capacity(HEADER_BYTES + buckets.len() * NFIELDS * 8);
    for v in [
        kind,
        buckets.len() as u32,
        NFIELDS as u32,
        dropped.min(u64::from(u32::MAX)) as u32,
    ] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for b in buckets {
        for v in b {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
}

/// Sets the dropped-frames word of an encoded message (per client, at send time).
pub fn set_dropped(message: &mut [u8], dropped: u64) {
    if message.len() >= HEADER_BYTES {
        message[12..16].copy_from_slice(&(dropped.min(u64::from(u32::MAX)) as u32).to_le_bytes());
    }
}

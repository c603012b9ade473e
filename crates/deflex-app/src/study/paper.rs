//! The numbers Johra et al. (2022) published, for the "paper vs deflex" tables. Each constant
//! names where it comes from.

/// Table 1 stiffnesses (N·m/rad) as `(label, k)`.
pub const TABLE1: [(&str, f64); 6] = [
    ("J1.z", 2.32e6),
    ("J2.z", 1.76e6),
    ("J3.x", 1.45e6),
    ("J3.z", 2.04e6),
    ("J4.z", 0.09e6),
    ("J5.z", 0.02e6),
];

/// Section 3.1: the centre of joint 3 is shifted 400 mm along z3 (δr3, m).
pub const DELTA_R3_M: f64 = 0.400;

/// Section 3.2 (Figs. 11a, 13a): one-eDoF-per-joint model, maximum δz error (mm) at 600 / 1100 N.
pub const ONE_EDOF_MAX_MM: [f64; 2] = [0.18, 0.34];
/// Section 3.2: one-eDoF-per-joint model, RMS δz error (mm) at 600 / 1100 N.
pub const ONE_EDOF_RMS_MM: [f64; 2] = [0.16, 0.11];
/// Section 3.2 (Figs. 11b, 13b): the paper's model, maximum δz error (mm) at 600 / 1100 N.
pub const MODEL_MAX_MM: [f64; 2] = [0.08, 0.16];
/// Section 3.2: the paper's model, RMS δz error (mm) at 600 / 1100 N.
pub const MODEL_RMS_MM: [f64; 2] = [0.04, 0.05];

/// Section 4.3: maximum path error norm without correction (mm).
pub const FORMING_OPEN_MAX_MM: f64 = 3.84;
/// Section 4.3: maximum path error norm with correction (mm).
pub const FORMING_CLOSED_MAX_MM: f64 = 1.13;
/// Section 4.3: improvement of the maximum error norm (%).
pub const FORMING_IMPROVEMENT_PERCENT: f64 = 70.0;
/// Section 4.3: vertical force without correction, "up to" (N).
pub const FORMING_OPEN_FZ_N: f64 = 1200.0;
/// Section 4.3: in-plane force without correction, "up to" (N).
pub const FORMING_OPEN_FXY_N: f64 = 500.0;

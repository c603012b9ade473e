//! Each vendor's configuration data from an [`ArmConfiguration`] (joint values and where the
//! wrist centre lies), as their manuals define it. The joint values are the model's, which must
//! be the controller's axis values (zeros and senses): true for the built-in KUKA, ABB and UR
//! descriptions, to be checked for a user's own file. None of this has been checked on a
//! controller yet.
//!
//! * **KUKA Status** (KSS 8 *Expert programming*, "Status"): bit 0 = 1 when the wrist root point
//!   (intersection of A4, A5, A6) has a negative x in the A1 coordinate system (the "overhead
//!   area"); bit 1 = 1 when A3 ≥ φ, φ the A3 angle at which the arm is stretched (the wrist
//!   root point on the line of A2 and A3; computed from the model's geometry); bit 2 = 1 when
//!   A5 ≤ 0. **Turn**: bit i = 1 when axis i+1 is negative (A1 … A6). Only a `PTP` to a Cartesian
//!   point uses them; `LIN` keeps the configuration it starts in.
//! * **ABB `robconf` [cf1, cf4, cf6, cfx]** (RAPID reference, `confdata`, serial robots): cf1,
//!   cf4, cf6 the quadrants of axes 1, 4 and 6 (`floor(angle / 90°)`, −1 for −90° … 0°); cfx =
//!   4 × (wrist centre behind axis 1) + 2 × (wrist centre behind the lower arm) + (axis 5 < 0),
//!   0 … 7. Written with `ConfJ \On` and `ConfL \On`, so the controller checks the configuration
//!   at every target instead of taking the nearest one.
//! * **Stäubli `config`** (VAL3 reference, `config` type for 6-axis arms): `shoulder` `righty`
//!   when the wrist centre is in front of axis 1, `lefty` behind; `elbow` `epositive` when
//!   joint 3 ≥ 0, `enegative` otherwise; `wrist` `wpositive` when joint 5 ≥ 0, `wnegative`
//!   otherwise.
//! * **FANUC `CONFIG`** (`'F U T, t1, t4, t6'` in a TP position): flip `F` when J5 < 0, else `N`
//!   (no flip); `U` (elbow up) when the elbow lies above the line from axis 2 to the wrist
//!   centre ([`ArmConfiguration::elbow_up`]), else `D`; `T` (front, "toward") when
//!   the wrist centre is in front of axis 1, else `B` (back); the turn numbers of J1, J4 and J6
//!   are `floor((q + 180°) / 360°)`, 0 within −180° … 180°.
//! * **Yaskawa `///RCONF l,m,n,o,p,q,0,0`** (DX100 / NX100 *Interface with an Easy Offline
//!   Teaching System*, 4.1 "Job Data Format", `RCONF`: `<l>` 0 flip, 1 no-flip; `<m>` 0 upper
//!   arm, 1 lower arm; `<n>` 0 front, 1 rear; `<o>` 0 R < 180, 1 R ≥ 180; `<p>` the same for T;
//!   `<q>` the same for S; the rest unused, written 0): flip when B (axis 5) ≥ 0; upper arm when
//!   the elbow lies above the line from axis 2 to the wrist centre (as FANUC's `U`); rear when the wrist centre is
//!   behind axis 1; R, T, S (axes 4, 6, 1) "≥ 180" when |q| ≥ 180°. The flip sense follows the
//!   manual's manipulator-type figure for arms whose B axis has the ROS-Industrial sense (the
//!   built-in `gp180`); check one taught point on your controller.

use crate::program::ArmConfiguration;

/// KUKA Status and Turn (see the module documentation).
pub fn kuka_status_turn(c: &ArmConfiguration) -> (u32, u32) {
    let status = u32::from(c.wrist_behind_axis_1)
        | (u32::from(c.elbow_beyond_stretched) << 1)
        | (u32::from(c.joints_rad[4] <= 0.0) << 2);
    let turn = c
        .joints_rad
        .iter()
        .enumerate()
        .fold(0, |t, (i, q)| t | (u32::from(*q < 0.0) << i));
    (status, turn)
}

/// The quadrant of an angle: `floor(angle / 90°)`.
fn quadrant(angle_rad: f64) -> i32 {
    (angle_rad / std::f64::consts::FRAC_PI_2).floor() as i32
}

/// ABB `robconf` (see the module documentation).
pub fn abb_robconf(c: &ArmConfiguration) -> [i32; 4] {
    let q = &c.joints_rad;
    let cfx = 4 * i32::from(c.wrist_behind_axis_1)
        + 2 * i32::from(c.wrist_behind_lower_arm)
        + i32::from(q[4] < 0.0);
    [quadrant(q[0]), quadrant(q[3]), quadrant(q[5]), cfx]
}

/// Stäubli `config`: `(shoulder, elbow, wrist)` (see the module documentation).
pub fn staubli_config(c: &ArmConfiguration) -> (&'static str, &'static str, &'static str) {
    (
        if c.wrist_behind_axis_1 {
            "lefty"
        } else {
            "righty"
        },
        if c.joints_rad[2] >= 0.0 {
            "epositive"
        } else {
            "enegative"
        },
        if c.joints_rad[4] >= 0.0 {
            "wpositive"
        } else {
            "wnegative"
        },
    )
}

/// FANUC `CONFIG` text `'F U T, t1, t4, t6'` (see the module documentation); `None`: the
/// default `N U T, 0, 0, 0`.
pub fn fanuc_config(c: Option<&ArmConfiguration>) -> String {
    let Some(c) = c else {
        return "N U T, 0, 0, 0".into();
    };
    let q = c.joints_rad.map(f64::to_degrees);
    let turn = |v: f64| ((v + 180.0) / 360.0).floor() as i32;
    format!(
        "{} {} {}, {}, {}, {}",
        if q[4] < 0.0 { 'F' } else { 'N' },
        if c.elbow_up { 'U' } else { 'D' },
        if c.wrist_behind_axis_1 { 'B' } else { 'T' },
        turn(q[0]),
        turn(q[3]),
        turn(q[5])
    )
}

/// Yaskawa `///RCONF` fields `l,m,n,o,p,q,0,0` (see the module documentation); `None`: flip,
/// upper arm, front, all axes within ±180° (`0,0,0,0,0,0,0,0`).
pub fn yaskawa_rconf(c: Option<&ArmConfiguration>) -> [u8; 8] {
    let Some(c) = c else {
        return [0; 8];
    };
    let q = c.joints_rad.map(f64::to_degrees);
    let beyond = |v: f64| u8::from(v.abs() >= 180.0);
    [
        u8::from(q[4] < 0.0),
        u8::from(!c.elbow_up),
        u8::from(c.wrist_behind_axis_1),
        beyond(q[3]),
        beyond(q[5]),
        beyond(q[0]),
        0,
        0,
    ]
}

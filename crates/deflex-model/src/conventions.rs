//! Every vendor's orientation convention, from and to a rotation matrix: the one place where
//! deflex writes them, used by the programs (`deflex_cam::program`) and by the wire protocols
//! (`deflex_io`).
//!
//! Every function here maps a rotation `R` (the TCP frame's axes as columns, expressed in the
//! program or base frame) to the angles a controller expects and back. The three-angle
//! conventions come in **radians** (the protocols' SI side) and in **degrees** (what the
//! controllers print and read); the rotation vector is in **radians**.
//!
//! | vendor | convention | composition | where deflex uses it | source |
//! | --- | --- | --- | --- | --- |
//! | KUKA (KRL `A, B, C`) | intrinsic Z-Y'-X'' | `R = Rz(A)·Ry(B)·Rx(C)` | KRL programs; KUKA RSI (`RIst`, `RSol`, `RKorr`, in degrees on the wire); ABB EGM's `euler` feedback (`z, y, x`) | KUKA KRL: A about Z, B about Y, C about X, "rotation convention z-y'-x''", `r_z(A) r_y(B) r_x(C)` (Roboception/Basler, *KUKA XYZ-ABC format*, <https://docs.baslerweb.com/stereovisard/rc_visard/en/pose_format_kuka.html>; javaKUKA *Hello, ABC!*, <http://javakuka.org/26.html>) |
//! | ABB (RAPID `orient`) | unit quaternion, `q1` = scalar part | `[q1, q2, q3, q4] = [w, x, y, z]` | RAPID programs; ABB EGM's `orient` (`u0` … `u3`) | RAPID reference manual, data type `orient`: "q1=1, q2–q4=0 corresponds to no rotation", must be normalised; Basler *ABB pose format*: "(x y z w) = (Q2 Q3 Q4 Q1)" (<https://doc.rc-visard-ng.com/v25.10/en/pose_format_abb.html>) |
//! | Universal Robots (URScript pose) | rotation vector (axis × angle, rad) | `R = exp([r]×)` | URScript programs; the rotation part of every protocol's correction | URScript manual, module *motion*: "the last three [coordinates of a pose form] an axis-angle" (<https://www.universal-robots.com/manuals/EN/HTML/SW10_13/Content/prod-scriptmanual/all_scripts/Module_otion.htm>) |
//! | Stäubli (VAL3 `trsf`) | intrinsic X-Y'-Z'' | `R = Rx(rx)·Ry(ry)·Rz(rz)` | VAL3 programs; deflex's Stäubli protocol (`docs/staubli/PROTOCOL.md`, radians on the wire) | VAL3 reference manual, type `trsf` (rx about x, then ry about the new y', then rz about the new z''); the same convention is used by public VAL3 post-processors (`sin ry = R[0][2]`) |
//! | FANUC (TP `W, P, R`) | fixed axes X, Y, Z (= intrinsic Z-Y'-X'') | `R = Rz(R)·Ry(P)·Rx(W)` | FANUC TP programs (`/POS`) | FANUC's `xyzwpr`: W (yaw) about the fixed x axis, then P (pitch) about the fixed y axis, then R (roll) about the fixed z axis (RoboDK's API, `xyzwpr_2_pose`, <https://robodk.com/doc/en/PythonAPI/robodk.html>; the same matrix as KUKA's with `(A, B, C) = (R, P, W)`) |
//! | Yaskawa (INFORM `Rx, Ry, Rz`) | fixed axes X, Y, Z (= intrinsic Z-Y'-X'') | `R = Rz(Rz)·Ry(Ry)·Rx(Rx)` | Yaskawa INFORM jobs (`.JBI`, `C00000=` positions) | Yaskawa DX100 *Interface with an Easy Offline Teaching System*, 4.3.1.1 "Robot Axis": "by rotating the specified coordinate system in the order of Rz, Ry and Rx, it takes the coordinate system posture of the control point"; Basler *Yaskawa pose format*: "computed by r_z(Rz) r_y(Ry) r_x(Rx)" (<https://docs.baslerweb.com/stereovisard/rc_cube/en/pose_format_yaskawa>); the same matrix as FANUC's W, P, R |
//!
//! **Gimbal lock.** The three-angle conventions are singular when the middle angle is ±90°:
//! only the sum (or difference) of the outer angles is defined. The extraction takes the first
//! angle from `atan2` of two matrix elements and then the other two from the *remaining* rotation
//! (`Rz(−A)·R` for KUKA, `R·Rz(−rz)` for Stäubli), so the three angles always rebuild `R`
//! to rounding, however close to the lock; at the lock itself (cos of the middle angle below
//! [`GIMBAL_LOCK_COS`]) the first angle is taken from the previous point of the path (or 0), so
//! the split of the outer angles stays continuous along a path.
//!
//! **Quaternion and rotation-vector signs.** `q` and `−q` are the same rotation, as are the rotation
//! vectors `θ·n` and `−(2π − θ)·n`. The first point of a path gets `q1 ≥ 0` and `|r| ≤ π`; every
//! later point gets the representative closest to the previous one, so printed values do not
//! flip sign between neighbouring points (near 180° rotations, e.g. a tool pointing down, the
//! canonical choice would flip at every small wobble).
//!
//! **Values that name no rotation.** A quaternion of zero (or non-finite) norm gives the
//! identity (it carries no orientation, e.g. an EGM message that leaves it unset); a rotation
//! vector with a non-finite component gives a rotation of non-finite entries, so the caller's
//! finiteness check refuses it instead of sending a silent identity.
//!
//! Nothing here allocates: the hot path of the protocols calls these functions every cycle.

use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};
use std::f64::consts::PI;

/// Below this value of the middle angle's cosine the outer angles of a three-angle convention
/// are not separable from the matrix in floating point; the first one is then taken from the
/// previous point (see the module documentation).
pub const GIMBAL_LOCK_COS: f64 = 1e-9;

/// KUKA `A, B, C` (radians) of a rotation: `R = Rz(A)·Ry(B)·Rx(C)`, `B ∈ [−π/2, π/2]`,
/// `A, C ∈ [−π, π]` (from `atan2`). `previous` (radians) resolves the gimbal lock at
/// `B = ±π/2`.
pub fn kuka_abc_rad(rotation: &Rotation3<f64>, previous: Option<[f64; 3]>) -> [f64; 3] {
    let m = rotation.matrix();
    let cos_b = m[(0, 0)].hypot(m[(1, 0)]);
    let a = if cos_b < GIMBAL_LOCK_COS {
        previous.map_or(0.0, |p| p[0])
    } else {
        m[(1, 0)].atan2(m[(0, 0)])
    };
    // Ry(B)·Rx(C) = Rz(−A)·R = [[cB, sB sC, sB cC], [0, cC, −sC], [−sB, cB sC, cB cC]].
    let rest = rot_z(-a) * m;
    let b = (-rest[(2, 0)]).atan2(rest[(0, 0)]);
    let c = (-rest[(1, 2)]).atan2(rest[(1, 1)]);
    [a, b, c]
}

/// KUKA `A, B, C` (degrees) of a rotation: `R = Rz(A)·Ry(B)·Rx(C)`, `B ∈ [−90°, 90°]`,
/// `A, C ∈ (−180°, 180°]`. `previous` (degrees) resolves the gimbal lock at `B = ±90°`.
pub fn kuka_abc_deg(rotation: &Rotation3<f64>, previous: Option<[f64; 3]>) -> [f64; 3] {
    let [a, b, c] = kuka_abc_rad(rotation, previous.map(|p| p.map(f64::to_radians)));
    [
        wrap_deg(a.to_degrees()),
        b.to_degrees(),
        wrap_deg(c.to_degrees()),
    ]
}

/// Rotation of KUKA angles `A, B, C` (radians): `Rz(A)·Ry(B)·Rx(C)`.
pub fn rotation_from_kuka_abc_rad(abc: [f64; 3]) -> Rotation3<f64> {
    Rotation3::from_matrix_unchecked(rot_z(abc[0]) * rot_y(abc[1]) * rot_x(abc[2]))
}

/// Rotation of KUKA angles `A, B, C` (degrees): `Rz(A)·Ry(B)·Rx(C)`.
pub fn rotation_from_kuka_abc_deg(abc: [f64; 3]) -> Rotation3<f64> {
    rotation_from_kuka_abc_rad(abc.map(f64::to_radians))
}

/// FANUC `W, P, R` (degrees) of a rotation: fixed-axis rotations about X, Y, Z, i.e.
/// `R = Rz(R)·Ry(P)·Rx(W)`, `P ∈ [−90°, 90°]`, `W, R ∈ (−180°, 180°]`. `previous` (degrees,
/// `[W, P, R]`) resolves the gimbal lock at `P = ±90°` (R is then kept from it).
pub fn fanuc_wpr_deg(rotation: &Rotation3<f64>, previous: Option<[f64; 3]>) -> [f64; 3] {
    let [r, p, w] = kuka_abc_deg(rotation, previous.map(|[w, p, r]| [r, p, w]));
    [w, p, r]
}

/// Rotation of FANUC angles `W, P, R` (degrees): `Rz(R)·Ry(P)·Rx(W)`.
pub fn rotation_from_fanuc_wpr_deg(wpr: [f64; 3]) -> Rotation3<f64> {
    rotation_from_kuka_abc_deg([wpr[2], wpr[1], wpr[0]])
}

/// Yaskawa `Rx, Ry, Rz` (degrees) of a rotation: fixed-axis rotations about X, then Y, then Z,
/// i.e. `R = Rz(Rz)·Ry(Ry)·Rx(Rx)`, `Ry ∈ [−90°, 90°]`, `Rx, Rz ∈ (−180°, 180°]`. `previous`
/// (degrees, `[Rx, Ry, Rz]`) resolves the gimbal lock at `Ry = ±90°` (Rz is then kept from it).
/// Numerically FANUC's `W, P, R` ([`fanuc_wpr_deg`]): both vendors name the same matrix.
pub fn yaskawa_rxryrz_deg(rotation: &Rotation3<f64>, previous: Option<[f64; 3]>) -> [f64; 3] {
    fanuc_wpr_deg(rotation, previous)
}

/// Rotation of Yaskawa angles `Rx, Ry, Rz` (degrees): `Rz(Rz)·Ry(Ry)·Rx(Rx)`.
pub fn rotation_from_yaskawa_rxryrz_deg(rxryrz: [f64; 3]) -> Rotation3<f64> {
    rotation_from_fanuc_wpr_deg(rxryrz)
}

/// Stäubli `rx, ry, rz` (radians) of a rotation: `R = Rx(rx)·Ry(ry)·Rz(rz)`,
/// `ry ∈ [−π/2, π/2]`, `rx, rz ∈ [−π, π]` (from `atan2`). `previous` (radians) resolves the
/// gimbal lock at `ry = ±π/2`.
pub fn staubli_rxryrz_rad(rotation: &Rotation3<f64>, previous: Option<[f64; 3]>) -> [f64; 3] {
    let m = rotation.matrix();
    // First row of Rx·Ry·Rz: [cy cz, −cy sz, sy].
    let cos_y = m[(0, 0)].hypot(m[(0, 1)]);
    let rz = if cos_y < GIMBAL_LOCK_COS {
        previous.map_or(0.0, |p| p[2])
    } else {
        (-m[(0, 1)]).atan2(m[(0, 0)])
    };
    // Rx(rx)·Ry(ry) = R·Rz(−rz) = [[cy, 0, sy], [sx sy, cx, −sx cy], [−cx sy, sx, cx cy]].
    let rest = m * rot_z(-rz);
    let ry = rest[(0, 2)].atan2(rest[(0, 0)]);
    let rx = rest[(2, 1)].atan2(rest[(1, 1)]);
    [rx, ry, rz]
}

/// Stäubli `rx, ry, rz` (degrees) of a rotation: `R = Rx(rx)·Ry(ry)·Rz(rz)`,
/// `ry ∈ [−90°, 90°]`, `rx, rz ∈ (−180°, 180°]`. `previous` (degrees) resolves the gimbal lock
/// at `ry = ±90°`.
pub fn staubli_rxryrz_deg(rotation: &Rotation3<f64>, previous: Option<[f64; 3]>) -> [f64; 3] {
    let [rx, ry, rz] = staubli_rxryrz_rad(rotation, previous.map(|p| p.map(f64::to_radians)));
    [
        wrap_deg(rx.to_degrees()),
        ry.to_degrees(),
        wrap_deg(rz.to_degrees()),
    ]
}

/// Rotation of Stäubli angles `rx, ry, rz` (radians): `Rx(rx)·Ry(ry)·Rz(rz)`.
pub fn rotation_from_staubli_rxryrz_rad(r: [f64; 3]) -> Rotation3<f64> {
    Rotation3::from_matrix_unchecked(rot_x(r[0]) * rot_y(r[1]) * rot_z(r[2]))
}

/// Rotation of Stäubli angles `rx, ry, rz` (degrees): `Rx(rx)·Ry(ry)·Rz(rz)`.
pub fn rotation_from_staubli_rxryrz_deg(r: [f64; 3]) -> Rotation3<f64> {
    rotation_from_staubli_rxryrz_rad(r.map(f64::to_radians))
}

/// ABB quaternion `[q1, q2, q3, q4] = [w, x, y, z]` (unit) of a rotation. Without `previous`,
/// `q1 ≥ 0`; with it, the sign that makes the quaternion closest to `previous`.
pub fn abb_quaternion(rotation: &Rotation3<f64>, previous: Option<[f64; 4]>) -> [f64; 4] {
    let q = UnitQuaternion::from_rotation_matrix(rotation);
    let mut out = [q.w, q.i, q.j, q.k];
    let flip = match previous {
        Some(p) => out.iter().zip(p).map(|(a, b)| a * b).sum::<f64>() < 0.0,
        None => out[0] < 0.0,
    };
    if flip {
        out.iter_mut().for_each(|v| *v = -*v);
    }
    out
}

/// Rotation of an ABB quaternion `[q1, q2, q3, q4] = [w, x, y, z]` (normalised here, since a
/// printed quaternion is only unit to its printed precision). A quaternion of zero or
/// non-finite norm names no rotation: the identity.
pub fn rotation_from_abb_quaternion(q: [f64; 4]) -> Rotation3<f64> {
    let quaternion = nalgebra::Quaternion::new(q[0], q[1], q[2], q[3]);
    let norm = quaternion.norm();
    if !norm.is_finite() || norm <= 1e-300 {
        return Rotation3::identity();
    }
    UnitQuaternion::from_quaternion(quaternion).to_rotation_matrix()
}

/// Rotation vector (axis × angle, rad) of a rotation: Universal Robots' pose orientation and
/// the rotation part of every protocol's correction. Without `previous`, `|r| ≤ π`; with it,
/// whichever of `θ·n` and `−(2π − θ)·n` is closer to `previous`.
pub fn rotation_vector(rotation: &Rotation3<f64>, previous: Option<[f64; 3]>) -> [f64; 3] {
    let q = UnitQuaternion::from_rotation_matrix(rotation);
    // w ≥ 0 gives θ = 2·atan2(|v|, w) ∈ [0, π]; atan2 keeps small angles accurate.
    let (w, v) = if q.w < 0.0 {
        (-q.w, -q.imag())
    } else {
        (q.w, q.imag())
    };
    let sin_half = v.norm();
    let angle = 2.0 * sin_half.atan2(w);
    let r = if sin_half < 1e-300 {
        Vector3::zeros()
    } else {
        v * (angle / sin_half)
    };
    let r = match previous {
        Some(p) if angle > 1e-12 => {
            let p = Vector3::from(p);
            let other = -r * ((2.0 * PI - angle) / angle);
            if (other - p).norm() < (r - p).norm() {
                other
            } else {
                r
            }
        }
        _ => r,
    };
    [r.x, r.y, r.z]
}

/// Rotation of a rotation vector (axis × angle, rad). A vector with a non-finite component
/// gives a rotation whose entries are all NaN (see the module documentation).
pub fn rotation_from_rotation_vector(r: [f64; 3]) -> Rotation3<f64> {
    if !r.iter().all(|v| v.is_finite()) {
        return Rotation3::from_matrix_unchecked(Matrix3::repeat(f64::NAN));
    }
    Rotation3::from_scaled_axis(Vector3::from(r))
}

/// Angle (rad) of the rotation between two orientations: the distance used by the round-trip
/// checks. `atan2` of the skew and symmetric parts, accurate near 0 (the `acos` of the trace
/// is not: it cannot resolve angles below ~1e-8 rad).
pub fn rotation_distance(a: &Rotation3<f64>, b: &Rotation3<f64>) -> f64 {
    let m = a.matrix().transpose() * b.matrix();
    let skew = Vector3::new(
        m[(2, 1)] - m[(1, 2)],
        m[(0, 2)] - m[(2, 0)],
        m[(1, 0)] - m[(0, 1)],
    );
    (0.5 * skew.norm()).atan2(0.5 * (m.trace() - 1.0))
}

/// An angle in degrees brought into (−180°, 180°].
pub fn wrap_deg(angle: f64) -> f64 {
    let wrapped = angle - 360.0 * ((angle + 180.0) / 360.0).ceil() + 360.0;
    if wrapped <= -180.0 {
        wrapped + 360.0
    } else {
        wrapped
    }
}

fn rot_x(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c)
}

fn rot_y(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}

fn rot_z(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

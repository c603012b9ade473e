//! The plant's own kinematics, written independently of `deflex-model`'s: a product of
//! exponentials (Brockett 1984; Lynch & Park, *Modern Robotics*, ch. 4) over the screws of the
//! home configuration, with the elastic springs as extra revolute screws in the chain.
//!
//! The robot description is read as data only: the world → R0 placement `base`, each joint's
//! fixed `placement` and `theta_offset`, the flange placement and the tool. At the home
//! configuration (every joint value 0, every spring relaxed) the link frames are
//!
//! `M_0 = base`,  `M_i = M_{i−1} · placement_i · RotZ(theta_offset_i)`  (i = 1..6),
//!
//! and every motor joint and every spring is a revolute screw `S = (ω, c)`: a unit axis ω and a
//! point c on it, world axes. Motor joint i turns about z of `M_i` through its origin; a spring
//! of joint i turns about x, y or z of `M_i` through the spring centre (the origin shifted along
//! z_i by the joint's centre shift, the paper's δr); a base spring turns about R0's axes through
//! the base pivot (a point on the floor, not R0's origin). The world pose of link k for joint
//! values q and spring rotations θ is
//!
//! `T_k(q, θ) = Π_{elements e of links 0..k, in chain order} exp([S_e] x_e) · M_k`,
//!
//! `exp([S] x) = (R(ω, x), (I − R(ω, x)) c)` (Rodrigues), where the chain order is: the base
//! springs, then for each joint its motor rotation followed by its own springs. A spring thus
//! turns everything beyond it about its own axis as carried along by everything before it:
//! finite rotations, exact for any deflection, so the static equilibrium built on this
//! ([`crate::plant`]) includes the load-dependent geometric stiffness.
//!
//! The spring screws in the deformed configuration, `S'_e = Ad_{G_e} S_e` with `G_e` the product
//! of the exponentials before e, are what a load acting beyond the spring twists it about:
//! axis `R_G ω`, point `G c`.

use deflex_model::{Pose, Robot};
use nalgebra::{Rotation3, Translation3, Vector3, Vector6};

/// The twin's robots have six motorised joints.
pub const JOINTS: usize = 6;
/// Largest number of springs: three at the base, three per joint.
pub const MAX_SPRINGS: usize = 3 + 3 * JOINTS;
const MAX_ELEMENTS: usize = JOINTS + MAX_SPRINGS;

/// A revolute screw: unit axis and a point on it (world, m).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Screw {
    /// Unit axis.
    pub axis: Vector3<f64>,
    /// A point on the axis (m).
    pub point: Vector3<f64>,
}

impl Screw {
    /// `exp([S] angle)`: the rigid motion of turning by `angle` (rad) about this screw
    /// (Rodrigues' formula).
    #[inline(always)]
    pub fn exp(&self, angle: f64) -> Pose {
        // R = cos x I + sin x [ω]× + (1 − cos x) ω ωᵀ for a unit ω.
        let (s, c) = sin_cos(angle);
        let w = &self.axis;
        let v = 1.0 - c;
        #[rustfmt::skip]
        let matrix = nalgebra::Matrix3::new(
            c + v * w.x * w.x,       v * w.x * w.y - s * w.z, v * w.x * w.z + s * w.y,
            v * w.y * w.x + s * w.z, c + v * w.y * w.y,       v * w.y * w.z - s * w.x,
            v * w.z * w.x - s * w.y, v * w.z * w.y + s * w.x, c + v * w.z * w.z,
        );
        let rotation = Rotation3::from_matrix_unchecked(matrix);
        let translation = self.point - rotation * self.point;
        Pose::from_parts(Translation3::from(translation), rotation)
    }

    /// The screw carried by a rigid motion `g`: `Ad_g S`.
    #[inline]
    pub fn moved(&self, g: &Pose) -> Screw {
        Screw {
            axis: g.rotation * self.axis,
            point: (g * nalgebra::Point3::from(self.point)).coords,
        }
    }

    /// Small motion of world point `p` per radian about this screw, with the rotation:
    /// `[ω × (p − c); ω]`. Its dot product with a wrench at `p` is the torque about the screw.
    #[inline]
    pub fn twist_at(&self, p: &Vector3<f64>) -> Vector6<f64> {
        let v = self.axis.cross(&(p - self.point));
        Vector6::new(v.x, v.y, v.z, self.axis.x, self.axis.y, self.axis.z)
    }

    /// Torque about this screw of a force `force` applied at world point `p` plus a pure moment
    /// `moment` (N·m): `ω · ((p − c) × F + M)`.
    #[inline]
    pub fn torque(&self, p: &Vector3<f64>, force: &Vector3<f64>, moment: &Vector3<f64>) -> f64 {
        self.axis.dot(&((p - self.point).cross(force) + moment))
    }
}

/// `(sin x, cos x)`; for the small angles of the springs (|x| < 0.01 rad) their Taylor series,
/// exact to rounding (the first omitted terms are below 10⁻²⁰ relative), which is several times
/// faster than the library call.
#[inline]
fn sin_cos(x: f64) -> (f64, f64) {
    const S3: f64 = 1.0 / 6.0;
    const S5: f64 = 1.0 / 20.0;
    const S7: f64 = 1.0 / 42.0;
    const S9: f64 = 1.0 / 72.0;
    const C4: f64 = 1.0 / 12.0;
    const C6: f64 = 1.0 / 30.0;
    const C8: f64 = 1.0 / 56.0;
    const C10: f64 = 1.0 / 90.0;
    if x.abs() < 0.01 {
        let x2 = x * x;
        let sin = x * (1.0 - x2 * S3 * (1.0 - x2 * S5 * (1.0 - x2 * S7 * (1.0 - x2 * S9))));
        // 1 − cos x = x²/2 (1 − x²/12 (1 − x²/30 (1 − x²/56 (1 − x²/90))))
        let one_minus_cos =
            0.5 * x2 * (1.0 - x2 * C4 * (1.0 - x2 * C6 * (1.0 - x2 * C8 * (1.0 - x2 * C10))));
        (sin, 1.0 - one_minus_cos)
    } else {
        x.sin_cos()
    }
}

/// Where a spring sits and about which axis it turns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpringSpec {
    /// 0 = base, i = joint i (1-based).
    pub link: usize,
    /// 0, 1, 2 = x, y, z of the site's frame.
    pub axis: usize,
}

/// Geometric deviations of the true robot from its description (a calibrated robot's residual
/// errors), applied when the home configuration is built.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GeometryErrors {
    /// Added to each joint's `theta_offset` (rad).
    pub joint_offset_rad: [f64; JOINTS],
    /// Added to the translation of each joint's placement, in the previous joint frame (m).
    pub placement_m: [[f64; 3]; JOINTS],
    /// Added to the tool's translation, in the flange frame (m).
    pub tool_m: [f64; 3],
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Element {
    /// Motor joint (0-based index).
    Joint(usize),
    /// Spring (index into the spring list).
    Spring(usize),
}

/// The home configuration of a spring chain: screws of the motor joints and springs in chain
/// order, home link frames, flange and tool.
#[derive(Clone, Debug)]
pub struct Chain {
    elements: [(Element, Screw, usize); MAX_ELEMENTS],
    element_count: usize,
    spring_count: usize,
    spring_link: [usize; MAX_SPRINGS],
    home_links: [Pose; JOINTS + 1],
    link_to_flange: Pose,
    flange_to_tcp: Pose,
}

/// The world poses of a deformed (or undeformed) chain and its spring screws there.
#[derive(Clone, Debug)]
pub struct ChainState {
    /// Pose of link k (0 = R0, i = joint frame R_i).
    pub links: [Pose; JOINTS + 1],
    /// Flange pose.
    pub flange: Pose,
    /// TCP pose.
    pub tcp: Pose,
    /// Current screw of every spring.
    pub springs: [Screw; MAX_SPRINGS],
}

impl Default for ChainState {
    fn default() -> Self {
        ChainState {
            links: [Pose::identity(); JOINTS + 1],
            flange: Pose::identity(),
            tcp: Pose::identity(),
            springs: [Screw::default(); MAX_SPRINGS],
        }
    }
}

impl Chain {
    /// The home configuration of `robot` (six joints) with the given geometric errors, springs
    /// (in any order; they are placed in chain order, base first) with their centre shifts along
    /// z of their joint frame (`center_shift_m[i]` for joint i+1), the base pivot in R0 (m) and
    /// the flange placement after the last joint frame.
    pub fn new(
        robot: &Robot,
        errors: &GeometryErrors,
        springs: &[SpringSpec],
        center_shift_m: &[f64; JOINTS],
        base_pivot_in_r0: &Vector3<f64>,
        flange: &Pose,
    ) -> Chain {
        assert_eq!(robot.joints.len(), JOINTS, "the plant needs six joints");
        assert!(springs.len() <= MAX_SPRINGS);
        let mut home_links = [Pose::identity(); JOINTS + 1];
        home_links[0] = robot.base;
        for (i, joint) in robot.joints.iter().enumerate() {
            let mut placement = joint.placement;
            placement.translation.vector += Vector3::from(errors.placement_m[i]);
            let offset = joint.theta_offset + errors.joint_offset_rad[i];
            let turn = Pose::from_parts(
                Translation3::identity(),
                Rotation3::from_axis_angle(&Vector3::z_axis(), offset),
            );
            home_links[i + 1] = home_links[i] * placement * turn;
        }
        let mut tool = robot.tool;
        tool.translation.vector += Vector3::from(errors.tool_m);
        let column = |pose: &Pose, axis: usize| -> Vector3<f64> {
            pose.rotation.matrix().column(axis).into_owned()
        };
        let spring_screw = |spec: &SpringSpec| -> Screw {
            let frame = &home_links[spec.link];
            let point = if spec.link == 0 {
                frame * nalgebra::Point3::from(*base_pivot_in_r0)
            } else {
                nalgebra::Point3::from(
                    frame.translation.vector + column(frame, 2) * center_shift_m[spec.link - 1],
                )
            };
            Screw {
                axis: column(frame, spec.axis),
                point: point.coords,
            }
        };
        let mut elements = [(Element::Joint(0), Screw::default(), 0); MAX_ELEMENTS];
        let mut count = 0;
        let mut spring_link = [0; MAX_SPRINGS];
        let mut push = |element: Element, screw: Screw, link: usize| {
            elements[count] = (element, screw, link);
            count += 1;
        };
        for (link, frame) in home_links.iter().enumerate() {
            if link > 0 {
                push(
                    Element::Joint(link - 1),
                    Screw {
                        axis: column(frame, 2),
                        point: frame.translation.vector,
                    },
                    link,
                );
            }
            for (s, spec) in springs.iter().enumerate() {
                if spec.link == link {
                    push(Element::Spring(s), spring_screw(spec), link);
                    spring_link[s] = link;
                }
            }
        }
        Chain {
            elements,
            element_count: count,
            spring_count: springs.len(),
            spring_link,
            home_links,
            link_to_flange: *flange,
            flange_to_tcp: tool,
        }
    }

    /// Number of springs.
    pub fn spring_count(&self) -> usize {
        self.spring_count
    }

    /// Link carrying spring `s` (0 = base): the spring turns links ≥ this one.
    pub fn spring_link(&self, s: usize) -> usize {
        self.spring_link[s]
    }

    /// Flange → TCP (the tool, with its error).
    pub fn tool(&self) -> &Pose {
        &self.flange_to_tcp
    }

    /// Last joint frame → flange.
    pub fn flange(&self) -> &Pose {
        &self.link_to_flange
    }

    /// The exponentials of the motor joints for joint values `q` (rad), for
    /// [`Chain::evaluate_with`] (constant while only the springs change).
    pub fn joint_motions(&self, q: &[f64; JOINTS]) -> [Pose; JOINTS] {
        let mut out = [Pose::identity(); JOINTS];
        for &(element, screw, _) in &self.elements[..self.element_count] {
            if let Element::Joint(i) = element {
                out[i] = screw.exp(q[i]);
            }
        }
        out
    }

    /// Poses for joint values `q` (rad) and spring rotations `theta` (rad, one per spring):
    /// the product of exponentials. Allocation-free.
    pub fn evaluate(&self, q: &[f64; JOINTS], theta: &[f64], state: &mut ChainState) {
        self.evaluate_with(&self.joint_motions(q), theta, state);
    }

    /// [`Chain::evaluate`] with the joints' exponentials given ([`Chain::joint_motions`]).
    pub fn evaluate_with(&self, joints: &[Pose; JOINTS], theta: &[f64], state: &mut ChainState) {
        let mut g = Pose::identity();
        let mut closed = 0; // links 0..closed have their pose
        for &(element, screw, link) in &self.elements[..self.element_count] {
            while closed < link {
                state.links[closed] = g * self.home_links[closed];
                closed += 1;
            }
            match element {
                Element::Joint(i) => g *= joints[i],
                Element::Spring(s) => {
                    state.springs[s] = screw.moved(&g);
                    let angle = theta[s];
                    if angle != 0.0 {
                        g *= screw.exp(angle);
                    }
                }
            }
        }
        while closed <= JOINTS {
            state.links[closed] = g * self.home_links[closed];
            closed += 1;
        }
        state.flange = state.links[JOINTS] * self.link_to_flange;
        state.tcp = state.flange * self.flange_to_tcp;
    }
}

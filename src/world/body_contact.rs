//! Bodies resting on the floor and on obstacles: contact spheres and capsules declared
//! on a body ([`BodyShape`]), by a penalty in the body's own potential
//! ([`System::add_body_potential`](splinerod_integrators::System::add_body_potential), solved in the same Newton system).
//!
//! A shape is a body-fixed segment `a`–`b` (a sphere when `a = b`) of radius `r`. Against
//! a surface (the floor or an `[[obstacles]]` entry, [`Obstacle::distance`]) its gap is
//! \\(g = d(p) - r\\) at the point `p` of the segment nearest the surface (the projection of a
//! sphere's centre, the closest points of a capsule's axis and the segment; against a plane both ends count, so a capsule
//! lying on it rests on both), and it adds
//!
//! \\[ E = \tfrac12 k\, \min(g, 0)^2, \qquad \nabla_x E = k g\, n, \qquad
//! \nabla_\theta E = (p - x)\times (k g\, n), \\]
//!
//! with the Hessian \\(k\, J^T J\\), \\(J = \[\,n^T,\ ((p - x)\times n)^T\,\]\\) (the
//! surface's and the segment's curvature left out: definite). The stiffness of a body is
//! chosen, not asked: its weight (at least under 9.81 m/s²) on one shape sinks it by 1 %
//! of its smallest radius, \\(k = M \max(|g|, 9.81) / (0.01\, r_{min})\\). Friction:
//! [`crate::world::body_friction`].

use crate::RodSystem;
use nalgebra::{Matrix6, UnitQuaternion, Vector3, Vector6};
use splinerod_core::proximity::closest_on_segments;
use splinerod_core::Real;
use splinerod_energies::Obstacle;

/// How far a body's weight on one of its shapes sinks it, as a fraction of the shape's
/// radius (the penalty's stiffness, module docs).
pub const SINK_FRACTION: Real = 0.01;

/// A contact shape on a body: the segment `a`–`b` in the body frame (a sphere when equal)
/// and its radius.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyShape {
    /// Index of the body.
    pub body: usize,
    /// One end (the centre of a sphere), body frame, m.
    pub a: Vector3<Real>,
    /// The other end, body frame, m.
    pub b: Vector3<Real>,
    /// Radius, m (> 0).
    pub radius: Real,
}

/// Default sliding speed below which a body's friction sticks (smoothed), m/s (as the
/// rods' `[contact] slip_speed`).
pub const DEFAULT_SLIP_SPEED: Real = 1e-3;

/// The bodies' shapes, the surfaces they meet, each body's penalty stiffness and the
/// friction ([`crate::world::body_friction`]).
#[derive(Debug, Clone, PartialEq)]
pub struct BodyContact {
    /// The shapes.
    pub shapes: Vec<BodyShape>,
    /// The floor and the (static) obstacles.
    pub surfaces: Vec<Obstacle>,
    /// Penalty stiffness per body, N/m.
    pub stiffness: Vec<Real>,
    /// Coulomb coefficient per surface (≥ 0; missing entries: none).
    pub friction: Vec<Real>,
    /// Sliding speed below which friction sticks (smoothed), m/s (> 0).
    pub slip_speed: Real,
    /// The slip `ε` of the current step, m (`slip_speed · dt`).
    pub slip: Real,
    /// The contacts frozen at the current step's start.
    pub lags: Vec<crate::world::body_friction::BodyLag>,
}

impl Default for BodyContact {
    fn default() -> Self {
        Self {
            shapes: Vec::new(),
            surfaces: Vec::new(),
            stiffness: Vec::new(),
            friction: Vec::new(),
            slip_speed: DEFAULT_SLIP_SPEED,
            slip: 0.0,
            lags: Vec::new(),
        }
    }
}

impl BodyContact {
    /// The stiffness of every body from its mass and smallest shape (module docs).
    pub fn set_stiffness(&mut self, masses: &[Real], gravity: Real) {
        let g = gravity.max(9.81);
        self.stiffness = masses
            .iter()
            .enumerate()
            .map(|(k, m)| {
                let mine = self.shapes.iter().filter(|s| s.body == k);
                let r = mine.map(|s| s.radius).fold(Real::INFINITY, Real::min);
                if r.is_finite() {
                    m * g / (SINK_FRACTION * r)
                } else {
                    0.0
                }
            })
            .collect();
    }
}

/// The contacts of `shape` on the body at the pose `(x, r)` with `surface`: each point
/// of its axis that touches (module docs), its gap (< 0, m) and the surface's normal.
pub(crate) fn touching<'a>(
    shape: &BodyShape,
    (x, r): (&Vector3<Real>, &UnitQuaternion<Real>),
    surface: &'a Obstacle,
) -> impl Iterator<Item = (Vector3<Real>, Real, Vector3<Real>)> + 'a {
    let (a, b, radius) = (x + r * shape.a, x + r * shape.b, shape.radius);
    points(a, b, surface).filter_map(move |(surface, p)| {
        let (d, n) = surface.distance(&p);
        (d < radius).then_some((p, d - radius, n))
    })
}

/// The points of the segment `a`–`b` that touch `surface`: both ends against a plane (a
/// capsule lying on it rests on both), else the point nearest the surface.
fn points(
    a: Vector3<Real>,
    b: Vector3<Real>,
    surface: &Obstacle,
) -> impl Iterator<Item = (&Obstacle, Vector3<Real>)> {
    let sphere = a == b;
    let pair = match surface {
        Obstacle::Plane { .. } => [Some(a), (!sphere).then_some(b)],
        _ => [Some(nearest(a, b, surface)), None],
    };
    pair.into_iter().flatten().map(move |p| (surface, p))
}

/// The point of the segment `a`–`b` nearest a sphere's or capsule's core.
fn nearest(a: Vector3<Real>, b: Vector3<Real>, surface: &Obstacle) -> Vector3<Real> {
    let core = match *surface {
        Obstacle::Plane { .. } => return a,
        Obstacle::Sphere { centre, .. } => (centre, centre),
        Obstacle::Capsule { a, b, .. } => (a, b),
    };
    let (s, _, _) = closest_on_segments((a, b), core);
    a + (b - a) * s
}

impl RodSystem {
    /// Body `body`'s contact potential at the pose `(x, r)` (module docs), adding its
    /// gradient and Hessian.
    pub(crate) fn body_contact(
        &self,
        body: usize,
        (x, r): (&Vector3<Real>, &UnitQuaternion<Real>),
        grad: &mut Vector6<Real>,
        hess: &mut Matrix6<Real>,
    ) -> Real {
        let contact = &self.bodies.contact;
        let k = contact.stiffness.get(body).copied().unwrap_or(0.0);
        let mut energy = 0.0;
        for shape in contact.shapes.iter().filter(|s| s.body == body) {
            let touches = contact
                .surfaces
                .iter()
                .flat_map(|s| touching(shape, (x, r), s));
            for (p, gap, n) in touches {
                energy += 0.5 * k * gap * gap;
                let moment = (p - x).cross(&n);
                let jac = Vector6::new(n.x, n.y, n.z, moment.x, moment.y, moment.z);
                *grad += jac * (k * gap);
                *hess += jac * jac.transpose() * k;
            }
        }
        energy
    }
}

//! Coulomb friction on the bodies' contact shapes ([`crate::world::body_contact`]), as a
//! lagged dissipative potential, the form the rods' friction takes
//! (`splinerod_energies` `contact::friction`). At the start of every time step each
//! touching contact is frozen as a [`BodyLag`]: the body-fixed point `ℓ` of the contact
//! (on the shape's surface, \\(c - r n\\) for the axis point `c` the penalty uses; from
//! the centre of mass, body frame), where that point was \\(p_0\\), the tangent
//! projector \\(T = I - n n^T\\) and the bound \\(\mu\lambda\\) (the surface's coefficient
//! times the penalty's normal force then). During the step the point is at
//! \\(p = x + R\ell\\) and slips \\(u = T (p - p_0)\\); the potential
//!
//! \\[ D = \mu\lambda\, f_0(|u|), \qquad
//! f_0(y) = \begin{cases} y^2 / (2\epsilon) & y < \epsilon \\\\ y - \epsilon/2 & y \ge \epsilon \end{cases} \\]
//!
//! with \\(\epsilon\\) = `[contact] slip_speed` × dt resists with \\(\mu\lambda\\) once the
//! point slides more than ε in the step (Coulomb) and sticks (smoothed) below. Its force
//! on the point \\(F = \mu\lambda f_0'(|u|)\,\hat u\\) enters the body's gradient as
//! \\((F,\ (p - x) \times F)\\), and its Hessian \\(J^T H_u J\\) with
//! \\(J = [\,I,\ -[p - x]_\times]\\), \\(H_u = \mu\lambda T/\epsilon\\) sticking,
//! \\(\mu\lambda (T - \hat u \hat u^T)/|u|\\) sliding (positive semi-definite; the
//! rotation's second derivative of `p` left out, as for the penalty). Static solves have
//! no step and no friction.

use crate::world::body_contact::{touching, BodyContact};
use crate::RodSystem;
use nalgebra::{Matrix3, Matrix3x6, Matrix6, UnitQuaternion, Vector3, Vector6};
use splinerod_core::body::skew;
use splinerod_core::Real;

/// One frozen contact of a body's shape.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyLag {
    /// Index of the body.
    pub body: usize,
    /// The contact point in the body frame, from the centre of mass, m.
    pub lever: Vector3<Real>,
    /// Where that point was at the step's start, m.
    pub start: Vector3<Real>,
    /// Tangent projector of the surface there.
    pub tangent: Matrix3<Real>,
    /// Largest friction force `μ λ`, N.
    pub bound: Real,
}

impl BodyContact {
    /// Freezes every touching contact of the bodies `bodies` (poses at the step's start)
    /// for a step of `dt` seconds; clears the lags when no surface has friction.
    pub fn begin_step(&mut self, bodies: &[splinerod_core::RigidBody], dt: Real) {
        self.lags.clear();
        self.slip = self.slip_speed * dt;
        if self.friction.iter().all(|&mu| mu == 0.0) {
            return;
        }
        for shape in &self.shapes {
            let Some(body) = bodies.get(shape.body) else {
                continue;
            };
            let k = self.stiffness.get(shape.body).copied().unwrap_or(0.0);
            let (x, r) = (&body.position, &body.orientation);
            for (i, surface) in self.surfaces.iter().enumerate() {
                let mu = self.friction.get(i).copied().unwrap_or(0.0);
                if mu == 0.0 {
                    continue;
                }
                for (c, gap, n) in touching(shape, (x, r), surface) {
                    let p = c - n * shape.radius;
                    self.lags.push(BodyLag {
                        body: shape.body,
                        lever: r.inverse() * (p - x),
                        start: p,
                        tangent: Matrix3::identity() - n * n.transpose(),
                        bound: mu * k * -gap,
                    });
                }
            }
        }
    }
}

impl RodSystem {
    /// Body `body`'s friction potential at the pose `(x, r)` (module docs), adding its
    /// gradient and Hessian.
    pub(crate) fn body_friction(
        &self,
        body: usize,
        (x, r): (&Vector3<Real>, &UnitQuaternion<Real>),
        grad: &mut Vector6<Real>,
        hess: &mut Matrix6<Real>,
    ) -> Real {
        let contact = &self.bodies.contact;
        let eps = contact.slip;
        let mut energy = 0.0;
        for lag in contact.lags.iter().filter(|l| l.body == body) {
            let arm = r * lag.lever;
            let u = lag.tangent * (x + arm - lag.start);
            let y = u.norm();
            let (e, force, h_u) = if y < eps {
                let force = u * (lag.bound / eps);
                (
                    lag.bound * y * y / (2.0 * eps),
                    force,
                    lag.tangent * (lag.bound / eps),
                )
            } else {
                let dir = u / y;
                let h = (lag.tangent - dir * dir.transpose()) * (lag.bound / y);
                (lag.bound * (y - 0.5 * eps), dir * lag.bound, h)
            };
            energy += e;
            let moment = arm.cross(&force);
            *grad += Vector6::new(force.x, force.y, force.z, moment.x, moment.y, moment.z);
            let mut jac = Matrix3x6::zeros();
            jac.fixed_view_mut::<3, 3>(0, 0)
                .copy_from(&Matrix3::identity());
            jac.fixed_view_mut::<3, 3>(0, 3).copy_from(&-skew(&arm));
            *hess += jac.transpose() * h_u * jac;
        }
        energy
    }
}

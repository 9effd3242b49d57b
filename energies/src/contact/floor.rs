//! The floor plane \\(n_f \cdot x = h\\) of [`Contact`] (module docs of `contact`): the
//! penalty at the rod's quadrature points with gap \\(g(s) = n_f \cdot C(s) - h - r\\)
//! and energy per unit rest length \\(\tfrac{1}{2r} \phi(g)\\), its gradient, its
//! Hessian (exact: a plane has no curvature term) and its friction data.

use super::Contact;
use nalgebra::{Matrix3, Vector3};
use splinerod_core::basis::MAX_ORDER;
use splinerod_core::{BlockBanded, Real, Rod};

impl Contact {
    /// Calls `f(point, weight, basis row)` at every quadrature point with the floor gap.
    fn for_each_floor_point(&self, rod: &Rod, mut f: impl FnMut(Real, Real, usize, &[Real])) {
        let Some((normal, height)) = self.params.floor else {
            return;
        };
        let table = rod.quadrature();
        for p in 0..table.len() {
            let q = table.point(p);
            let x: Vector3<Real> = (0..q.value.len())
                .map(|k| rod.positions[q.first + k] * q.value[k])
                .sum();
            let gap = normal.dot(&x) - height - self.params.radius;
            if gap < self.params.onset {
                f(gap, q.weight / (2.0 * self.params.radius), q.first, q.value);
            }
        }
    }

    /// The floor's energy, J.
    pub(crate) fn floor_energy(&self, rod: &Rod) -> Real {
        let mut e = 0.0;
        self.for_each_floor_point(rod, |g, w, _, _| e += w * self.penalty.value(g));
        e
    }

    /// Adds the floor's gradient.
    pub(crate) fn add_floor_gradient(&self, rod: &Rod, gradient: &mut [Vector3<Real>]) {
        let normal = self.params.floor.map_or(Vector3::zeros(), |f| f.0);
        self.for_each_floor_point(rod, |g, w, first, value| {
            let force = normal * (w * self.penalty.slope(g));
            for (k, b) in value.iter().enumerate() {
                gradient[first + k] += force * *b;
            }
        });
    }

    /// Adds the floor's Hessian.
    pub(crate) fn add_floor_hessian(&self, rod: &Rod, hessian: &mut BlockBanded) {
        let nn: Matrix3<Real> = self
            .params
            .floor
            .map_or(Matrix3::zeros(), |f| f.0 * f.0.transpose());
        self.for_each_floor_point(rod, |g, w, first, value| {
            let c = w * self.penalty.curvature(g);
            for (a, ba) in value.iter().enumerate() {
                for (b, bb) in value.iter().enumerate().skip(a) {
                    hessian.add_block(first + a, first + b, &(nn * (c * ba * bb)));
                }
            }
        });
    }

    /// Freezes the floor's friction data for a step (normal forces and directions).
    pub(crate) fn push_floor_friction(
        &self,
        rod: &Rod,
        mut push: impl FnMut(&[(usize, Real)], &Vector3<Real>, Real),
    ) {
        let normal = self.params.floor.map_or(Vector3::zeros(), |f| f.0);
        self.for_each_floor_point(rod, |g, w, first, value| {
            let mut rows = [(0, 0.0); 2 * MAX_ORDER];
            for (row, (k, &b)) in rows.iter_mut().zip(value.iter().enumerate()) {
                *row = (first + k, b);
            }
            push(&rows[..value.len()], &normal, -w * self.penalty.slope(g));
        });
    }
}

//! The rod against rigid surfaces — the floor and the [`super::obstacle`]s — in one
//! place: each visits [`PenaltyPoint`]s (a point of the rod within the penalty's reach,
//! its gap, weight over `2r`, surface normal and basis row), and energy, gradient,
//! Hessian and friction are summed over them the same way,
//!
//! \\[ E = \sum_p w_p\, \phi(g_p), \quad \frac{\partial E}{\partial q_i} = \sum_p w_p\,
//! \phi'(g_p)\, b_i(s_p)\, n_p, \quad H_{ij} \mathrel{+}= w_p\, \phi''(g_p)\, b_i b_j\,
//! n_p n_p^T. \\]
//!
//! The floor plane \\(n_f \cdot x = h\\) is visited at the rod's quadrature points
//! (weight: the quadrature weight over `2r`, gap \\(n_f \cdot C(s) - h - r\\));
//! obstacles at the contact detection's material samples.

use super::Contact;
use nalgebra::{Matrix3, Vector3};
use splinerod_core::basis::MAX_ORDER;
use splinerod_core::{BlockBanded, CoreError, HessianKind, Real, Rod};

/// A point of the rod within the penalty's reach of a surface.
pub(crate) struct PenaltyPoint<'a> {
    /// Gap `d − r`, m.
    pub gap: Real,
    /// Rest arclength weight over `2r`.
    pub weight: Real,
    /// The surface's outward unit normal there.
    pub normal: Vector3<Real>,
    /// First control point of the basis row.
    pub first: usize,
    /// Basis values there.
    pub row: &'a [Real],
    /// The obstacle it touches (`None`: the floor).
    pub obstacle: Option<usize>,
    /// The rod's radius there, m.
    pub radius: Real,
    /// Its material coordinate, m.
    pub s: Real,
    /// Its position, m.
    pub at: Vector3<Real>,
}

impl Contact {
    /// Calls `f` at every quadrature point within the penalty's reach of the floor.
    fn for_each_floor_point(&self, rod: &Rod, mut f: impl FnMut(&PenaltyPoint<'_>)) {
        let Some((normal, height)) = self.params.floor else {
            return;
        };
        let table = rod.quadrature();
        for p in 0..table.len() {
            let q = table.point(p);
            let x: Vector3<Real> = (0..q.value.len())
                .map(|k| rod.positions[q.first + k] * q.value[k])
                .sum();
            let r = self.radius_at(q.s);
            let gap = normal.dot(&x) - height - r;
            if gap < self.params.onset {
                f(&PenaltyPoint {
                    gap,
                    weight: q.weight / (2.0 * r),
                    normal,
                    first: q.first,
                    row: q.value,
                    obstacle: None,
                    radius: r,
                    s: q.s,
                    at: x,
                });
            }
        }
    }

    /// Calls `f` at every point of the rod within reach of the floor, then of an obstacle.
    pub(crate) fn for_each_surface_point(
        &self,
        rod: &Rod,
        mut f: impl FnMut(&PenaltyPoint<'_>),
    ) -> Result<(), CoreError> {
        self.for_each_floor_point(rod, &mut f);
        self.for_each_obstacle_point(rod, f)
    }

    /// The surfaces' energy, J.
    pub(crate) fn surface_energy(&self, rod: &Rod) -> Result<Real, CoreError> {
        let mut e = 0.0;
        self.for_each_surface_point(rod, |p| e += p.weight * self.penalty.value(p.gap))?;
        Ok(e)
    }

    /// Adds the surfaces' gradient.
    pub(crate) fn add_surface_gradient(
        &self,
        rod: &Rod,
        gradient: &mut [Vector3<Real>],
    ) -> Result<(), CoreError> {
        self.for_each_surface_point(rod, |p| {
            let force = p.normal * (p.weight * self.penalty.slope(p.gap));
            for (k, b) in p.row.iter().enumerate() {
                gradient[p.first + k] += force * *b;
            }
        })
    }

    /// Adds the surfaces' Hessian: exact for the floor and planes; for curved obstacles
    /// the negative semi-definite surface-curvature term only with
    /// [`HessianKind::Exact`] ([`super::obstacle`]).
    pub(crate) fn add_surface_hessian(
        &self,
        rod: &Rod,
        kind: HessianKind,
        hessian: &mut BlockBanded,
    ) -> Result<(), CoreError> {
        self.for_each_surface_point(rod, |p| {
            let mut m: Matrix3<Real> =
                p.normal * p.normal.transpose() * (p.weight * self.penalty.curvature(p.gap));
            if let (HessianKind::Exact, Some(i)) = (kind, p.obstacle) {
                let turning = self.obstacles[i].normal_derivative(&p.at);
                m += turning * (p.weight * self.penalty.slope(p.gap));
            }
            for (a, ba) in p.row.iter().enumerate() {
                for (b, bb) in p.row.iter().enumerate().skip(a) {
                    hessian.add_block(p.first + a, p.first + b, &(m * (ba * bb)));
                }
            }
        })
    }

    /// Freezes the surfaces' friction data for a step of `dt` seconds (largest friction
    /// forces `μ λ` with their derivatives by the gap, directions and, for a moving obstacle, how far its surface moves in
    /// the step); contacts of coefficient 0 are left out.
    pub(crate) fn push_surface_friction(
        &self,
        rod: &Rod,
        dt: Real,
        mut push: impl FnMut(
            &[(usize, Real)],
            &Vector3<Real>,
            (Real, Real),
            Vector3<Real>,
            Option<usize>,
        ),
    ) -> Result<(), CoreError> {
        let mut rows = [(0, 0.0); 2 * MAX_ORDER];
        self.for_each_surface_point(rod, |p| {
            let len = p.row.len().min(2 * MAX_ORDER);
            for (k, (row, b)) in rows.iter_mut().zip(p.row).enumerate() {
                *row = (p.first + k, *b);
            }
            let mu = self.friction_at(p.s).min(self.surface_friction(p.obstacle));
            if mu == 0.0 {
                return;
            }
            let lambda = -p.weight * self.penalty.slope(p.gap);
            let slope = -mu * p.weight * self.penalty.curvature(p.gap);
            let moved = p
                .obstacle
                .map_or(Vector3::zeros(), |i| self.motion.step(i, dt));
            push(
                &rows[..len],
                &p.normal,
                (mu * lambda, slope),
                moved,
                p.obstacle,
            );
        })
    }
}

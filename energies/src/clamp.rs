//! A clamp as a stiff penalty on the tangent direction at a material point `s`:
//!
//! \\[ E_c = \frac{k}{2}\, |P\, C'(s)|^2, \qquad P = I - t t^T, \\]
//!
//! with `t` the unit clamp direction. Only the tangent's component across `t` is
//! penalised, so the clamp resists rotation of the tangent, not stretching. Together with
//! a [`Pin`](splinerod_core::Pin) at the same `s` it is a built-in (clamped) end.
//!
//! \\(C'(s) = \sum_i b_i'(s) q_i\\) is linear in the control points, so the energy is
//! quadratic: \\(\partial E/\partial q_i = k\, b_i'(s)\, P C'(s)\\) and the Hessian block
//! is \\(k\, b_i'(s) b_j'(s)\, P\\), constant and positive semi-definite (exact and
//! definite Hessians coincide). Knot insertion does not move \\(C'(s)\\): the energy is
//! exactly invariant.
//!
//! **Penalty error.** A clamp moment `M` rotates the tangent by \\(\theta \approx M/k\\)
//! (`k` in N·m per radian). For a cantilever of length `L` and stiffness `EI`, the tip
//! deflection's relative error is about \\(\theta L / \delta\\), i.e.
//! \\(3EI/(kL)\\) for a tip load and \\(4EI/(kL)\\) for a uniform load:
//! [`Clamp::stiffness_for`] returns \\(k = 10^6\, EI/L\\) (error ≈ 4·10⁻⁶). Much larger
//! `k` only worsens the conditioning of the Newton matrix.

use crate::Energy;
use nalgebra::{Matrix3, Vector3};
use splinerod_core::{BasisValues, BlockBanded, CoreError, HessianKind, Real, Rod};

/// Holds the tangent at material point `at` parallel to `direction` (penalty `k`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Clamp {
    /// Material coordinate `s ∈ [0, L]`, m.
    pub at: Real,
    /// Unit clamp direction `t`.
    direction: Vector3<Real>,
    /// Penalty stiffness `k`, N·m (energy per squared tangent deviation).
    pub stiffness: Real,
}

impl Clamp {
    /// A clamp at `at` along `direction` (any non-zero length; normalised) with penalty
    /// `stiffness > 0`. `at` must lie in the rod's domain `[0, L]`, otherwise the energy
    /// and its gradient are NaN (which integrators reject); [`Clamp::here`] checks it.
    pub fn new(at: Real, direction: Vector3<Real>, stiffness: Real) -> Result<Self, CoreError> {
        splinerod_core::rod::positive("clamp_stiffness", stiffness)?;
        splinerod_core::rod::non_negative("clamp_at", at)?;
        Ok(Self {
            at,
            direction: splinerod_core::check::unit("clamp_direction", direction)?,
            stiffness,
        })
    }

    /// Clamps material point `at` of `rod` along its current tangent.
    pub fn here(rod: &Rod, at: Real, stiffness: Real) -> Result<Self, CoreError> {
        Self::new(at, rod.tangent(at)?, stiffness)
    }

    /// Penalty \\(k = 10^6\, EI / L\\) for a rod of bending stiffness `EI` and length `L`:
    /// the clamp's compliance changes a cantilever's deflection by ≈ 4·10⁻⁶ relative.
    pub fn stiffness_for(bending_stiffness: Real, rest_length: Real) -> Real {
        1e6 * bending_stiffness / rest_length
    }

    /// The unit clamp direction `t`.
    pub fn direction(&self) -> Vector3<Real> {
        self.direction
    }

    /// The projector \\(P = I - t t^T\\).
    fn projector(&self) -> Matrix3<Real> {
        Matrix3::identity() - self.direction * self.direction.transpose()
    }

    /// Basis at the clamp and \\(P C'(s)\\), or `None` if `at` is outside the domain.
    fn deviation(&self, rod: &Rod) -> Option<(BasisValues, Vector3<Real>)> {
        let b = rod.basis_at(self.at).ok()?;
        let c1 = b.combine(&b.d1, &rod.positions);
        Some((b, self.projector() * c1))
    }
}

impl Energy for Clamp {
    fn name(&self) -> &str {
        "clamp"
    }

    fn energy(&self, rod: &Rod) -> Real {
        match self.deviation(rod) {
            Some((_, e)) => 0.5 * self.stiffness * e.norm_squared(),
            None => Real::NAN,
        }
    }

    fn add_gradient(&self, rod: &Rod, gradient: &mut [Vector3<Real>]) {
        let Some((b, e)) = self.deviation(rod) else {
            gradient
                .iter_mut()
                .for_each(|g| *g = Vector3::repeat(Real::NAN));
            return;
        };
        for k in 0..b.order {
            gradient[b.first + k] += e * (self.stiffness * b.d1[k]);
        }
    }

    fn add_hessian(&self, rod: &Rod, _kind: HessianKind, hessian: &mut BlockBanded) {
        let Ok(b) = rod.basis_at(self.at) else {
            return;
        };
        let p = self.projector() * self.stiffness;
        for i in 0..b.order {
            for j in i..b.order {
                hessian.add_block(b.first + i, b.first + j, &(p * (b.d1[i] * b.d1[j])));
            }
        }
    }

    /// Its [`Parameters`](crate::Parameters): the rest length.
    fn capabilities(&self) -> crate::capabilities::Capabilities<'_> {
        crate::capabilities::Capabilities {
            parameters: Some(self),
            ..crate::capabilities::Capabilities::default()
        }
    }
}

//! A spring pulling one material point toward a target (a grab, paper §4.2's
//! interactions): \\(E = \tfrac{k}{2}\,|C(s) - p|^2\\), with gradient
//! \\(k\,(C(s) - p)\, b_i(s)\\) and Hessian \\(k\, b_i(s) b_j(s)\, I_3\\) — non-zero only
//! for the `d + 1` control points whose functions are non-zero at `s`.
//!
//! The target `p` is a public field: whoever drives the grab moves it between steps.
//! If `s` is outside the rod, the energy is NaN (and the step fails cleanly).

use crate::Energy;
use nalgebra::{Matrix3, Vector3};
use splinerod_core::{BlockBanded, CoreError, HessianKind, Real, Rod};

/// A point spring of stiffness `k` (N/m) between material point `at` and `target`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointSpring {
    /// Material coordinate, m of rest arclength.
    pub at: Real,
    /// Where the point is pulled, m.
    pub target: Vector3<Real>,
    /// Stiffness, N/m.
    pub stiffness: Real,
}

impl PointSpring {
    /// A spring at `at` toward `target`; `stiffness > 0`, everything finite.
    pub fn new(at: Real, target: Vector3<Real>, stiffness: Real) -> Result<Self, CoreError> {
        splinerod_core::rod::positive("stiffness", stiffness)?;
        if !at.is_finite() {
            return Err(CoreError::NonFiniteState {
                what: "spring material coordinate",
                index: 0,
            });
        }
        splinerod_core::rod::check_finite("spring target", &[target])?;
        Ok(Self {
            at,
            target,
            stiffness,
        })
    }

    /// Material point position and the basis row at `at`.
    fn stretch(&self, rod: &Rod) -> Option<(Vector3<Real>, splinerod_core::BasisValues)> {
        let row = rod.basis_at(self.at).ok()?;
        let p = row.combine(&row.value, &rod.positions);
        Some((p - self.target, row))
    }
}

impl Energy for PointSpring {
    fn name(&self) -> &str {
        "grab"
    }

    fn energy(&self, rod: &Rod) -> Real {
        match self.stretch(rod) {
            Some((gap, _)) => 0.5 * self.stiffness * gap.norm_squared(),
            None => Real::NAN,
        }
    }

    fn add_gradient(&self, rod: &Rod, gradient: &mut [Vector3<Real>]) {
        let Some((gap, row)) = self.stretch(rod) else {
            gradient.iter_mut().for_each(|g| g.x = Real::NAN);
            return;
        };
        for k in 0..row.order {
            gradient[row.first + k] += gap * (self.stiffness * row.value[k]);
        }
    }

    fn add_hessian(&self, rod: &Rod, _kind: HessianKind, hessian: &mut BlockBanded) {
        let Ok(row) = rod.basis_at(self.at) else {
            return;
        };
        for a in 0..row.order {
            for b in a..row.order {
                let w = self.stiffness * row.value[a] * row.value[b];
                hessian.add_block(
                    row.first + a,
                    row.first + b,
                    &Matrix3::from_diagonal_element(w),
                );
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

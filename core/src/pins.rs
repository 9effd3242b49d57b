//! [`Pin`]: a material point held at a position, a linear constraint on the control points
//! \\(G q = p\\) with one 3-row block \\(\sum_i b_i(s)\, q_i = p\\) per pin.
//!
//! Integrators enforce pins with Lagrange multipliers (a Schur complement on the few
//! constraint rows), so a pin may sit at any material point, not only on a control point.

use crate::basis::BasisValues;
use crate::rod::Rod;
use crate::{CoreError, Real};
use nalgebra::Vector3;

/// Holds material point `at` (rest arclength, m) at `position`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pin {
    /// Material coordinate `s ∈ [0, L]`, m.
    pub at: Real,
    /// Where the point is held, m. Move it between steps to drive the rod.
    pub position: Vector3<Real>,
}

impl Pin {
    /// Pins material point `at` where it currently is.
    pub fn here(rod: &Rod, at: Real) -> Result<Self, CoreError> {
        Ok(Self {
            at,
            position: rod.point(at)?,
        })
    }

    /// The constraint row: basis functions non-zero at the pinned point.
    pub fn row(&self, rod: &Rod) -> Result<BasisValues, CoreError> {
        if !self.position.iter().all(|x| x.is_finite()) {
            return Err(CoreError::NonFiniteState {
                what: "pin position",
                index: 0,
            });
        }
        rod.basis_at(self.at)
    }

    /// Constraint violation \\(C(s) - p\\) at the rod's current positions.
    pub fn violation(&self, rod: &Rod) -> Result<Vector3<Real>, CoreError> {
        Ok(rod.point(self.at)? - self.position)
    }
}

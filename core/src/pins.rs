//! [`Pin`]: a material point held at a position, a linear constraint on the control points
//! \\(G q = p\\) with one 3-row block \\(\sum_i b_i(s)\, q_i = p\\) per pin.
//!
//! Integrators enforce pins with Lagrange multipliers (a Schur complement on the few
//! constraint rows), so a pin may sit at any material point, not only on a control point.
//!
//! A pin may **slide** along an axis `a`: it then holds only the components across it,
//! \\(P(\sum_i b_i q_i - p) = 0\\) with \\(P = I - a a^T\\), and its force has no
//! component along `a` (a bead on a frictionless rail).
//!
//! A **tangent** pin holds the control point next to an end of a rod with clamped knots
//! on the line through `position` along its axis: with the end point pinned at `position`
//! too, the tangent there, \\(C'(0) \propto q_1 - q_0\\), keeps its direction exactly (an
//! exact clamp; knot insertion keeps that control point on the line, since the curve
//! does not move).

use crate::basis::BasisValues;
use crate::rod::Rod;
use crate::{CoreError, Real};
use nalgebra::{Matrix3, Vector3};

/// Holds material point `at` (rest arclength, m) at `position`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pin {
    /// Material coordinate `s ∈ [0, L]`, m.
    pub at: Real,
    /// Where the point is held, m. Move it between steps to drive the rod.
    pub position: Vector3<Real>,
    /// Unit axis the pin slides along (`None`: held in all three directions).
    pub slides_along: Option<Vector3<Real>>,
    /// Whether this pin holds the control point next to the end `at` (an exact clamp's
    /// tangent) instead of the material point.
    pub tangent: bool,
}

impl Pin {
    /// Pins material point `at` where it currently is.
    pub fn here(rod: &Rod, at: Real) -> Result<Self, CoreError> {
        Ok(Self {
            at,
            position: rod.point(at)?,
            slides_along: None,
            tangent: false,
        })
    }

    /// The control point next to the end `at` (0 or L) held on the line through the end
    /// point along the rod's current tangent there: with [`Pin::here`] at the same end, an
    /// exact clamp. Needs clamped end knots (multiplicity `d + 1`), where the end tangent
    /// is \\(\propto q_1 - q_0\\).
    pub fn tangent_at(rod: &Rod, at: Real) -> Result<Self, CoreError> {
        let knots = rod.basis().knots();
        let d = rod.basis().degree();
        let (start, end) = rod.basis().domain();
        let clamped = knots[..=d].iter().all(|k| *k == start)
            && knots[knots.len() - d - 1..].iter().all(|k| *k == end);
        if !(clamped && rod.segment_end(at).is_some()) {
            return Err(CoreError::InvalidParameter {
                name: "clamp",
                value: at,
                reason: "an exact clamp needs an end of a rod with clamped knots",
            });
        }
        let axis = rod.tangent(at)?;
        Self::here(rod, at)?.sliding(axis).map(|pin| Self {
            tangent: true,
            ..pin
        })
    }

    /// This pin sliding along `axis` (normalised; finite and non-zero).
    pub fn sliding(self, axis: Vector3<Real>) -> Result<Self, CoreError> {
        Ok(Self {
            slides_along: Some(crate::check::unit("slides_along", axis)?),
            ..self
        })
    }

    /// The projector `P` onto the held directions (`I`, or \\(I - a a^T\\) sliding).
    pub fn projector(&self) -> Matrix3<Real> {
        match self.slides_along {
            Some(a) => Matrix3::identity() - a * a.transpose(),
            None => Matrix3::identity(),
        }
    }

    /// Number of held directions (3, or 2 sliding).
    pub fn rank(&self) -> usize {
        if self.slides_along.is_some() {
            2
        } else {
            3
        }
    }

    /// An error if the pin's position is not finite.
    pub fn check_position(&self) -> Result<(), CoreError> {
        if self.position.iter().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(CoreError::NonFiniteState {
                what: "pin position",
                index: 0,
            })
        }
    }

    /// The constraint row: basis functions non-zero at the pinned point (for a tangent
    /// pin, the control point next to the end, with weight 1).
    pub fn row(&self, rod: &Rod) -> Result<BasisValues, CoreError> {
        self.check_position()?;
        if self.tangent {
            let mut row = BasisValues::default();
            // The control point next to the end of the pin's rod (its segment).
            let points = rod.segment_points(rod.segment_at(self.at));
            row.first = if rod.segment_end(self.at) == Some(true) {
                points.start + 1
            } else {
                points.end.saturating_sub(2)
            };
            row.order = 1;
            row.value[0] = 1.0;
            return Ok(row);
        }
        if !rod.segments().is_empty() && rod.segment_end(self.at) == Some(false) {
            // The end of a joined rod's segment: its last control point, exactly (the
            // basis just below the junction matches it only to round-off).
            let mut row = BasisValues {
                first: rod.segment_points(rod.segment_at(self.at)).end - 1,
                order: 1,
                ..BasisValues::default()
            };
            row.value[0] = 1.0;
            return Ok(row);
        }
        rod.basis_at(self.at)
    }

    /// Constraint violation \\(P(\sum_i b_i q_i - p)\\) at the rod's current positions.
    pub fn violation(&self, rod: &Rod) -> Result<Vector3<Real>, CoreError> {
        let row = self.row(rod)?;
        let held = row.combine(&row.value, &rod.positions);
        Ok(self.projector() * (held - self.position))
    }
}

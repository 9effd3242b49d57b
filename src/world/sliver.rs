//! Cuts next to a knot: a cut at `s` just beside an existing knot `t` would leave a
//! sliver span `[t, s]` (or `[s, t]`) at the new free end. Its control points carry
//! almost no mass while its stretching and bending stiffnesses grow like `1/ℓ` and
//! `1/ℓ³` in its length `ℓ`: a mode far stiffer than the rest of the rod. The
//! energy-conserving implicit midpoint rule then cannot step the piece even at
//! sub-steps of 1e-8 s (a cut 4.3e-4 m from a knot of a 10-control-point rod:
//! `knot_changes::midpoint_step_after_cut_then_insertion`), and every scheme pays for
//! it in Newton iterations.
//!
//! [`RodSystem::cut`] therefore merges the sliver into its neighbour: when the cut lies
//! closer to a simple interior knot than [`SLIVER`] times the span it falls in, that knot
//! is removed after the cut, provided the curve moves by at most [`SLIVER_TOLERANCE`]
//! times the rod's length (the sliver's cubic differs from its neighbour's extension by
//! about the jump of the third derivative times `ℓ³/6`, far below that). A cut away
//! from knots, or one whose sliver cannot be merged within the tolerance, is exactly
//! the plain [`Rod::cut`].

use crate::world::system::RodSystem;
#[cfg(doc)]
use splinerod_core::Rod;
use splinerod_core::{CoreError, Real};

/// A cut closer to a simple interior knot than this fraction of the span it falls in
/// merges the resulting sliver span (module docs).
pub const SLIVER: Real = 0.05;

/// How far, relative to the rod's length, merging a sliver may move the curve.
pub const SLIVER_TOLERANCE: Real = 1e-6;

impl RodSystem {
    /// The simple interior knot a cut at `s` would leave a sliver span against, if any
    /// (module docs); read before the cut.
    pub(crate) fn sliver_knot(&self, s: Real) -> Option<Real> {
        let basis = self.rod.basis();
        let (start, end) = basis.domain();
        if !(s > start && s < end) || self.rod.knot_multiplicity(s) > 0 {
            return None;
        }
        let knots = basis.knots();
        let above = knots.partition_point(|&t| t <= s);
        let (left, right) = (*knots.get(above.checked_sub(1)?)?, *knots.get(above)?);
        let span = right - left;
        let near = if s - left <= right - s { left } else { right };
        let simple = near > start && near < end && self.rod.knot_multiplicity(near) == 1;
        ((s - near).abs() < SLIVER * span && simple).then_some(near)
    }

    /// Removes the knot `t` a cut has just left a sliver span against, if the curve
    /// moves by at most [`SLIVER_TOLERANCE`] times the rod's length; otherwise keeps the
    /// sliver. Returns whether it was merged.
    pub(crate) fn merge_sliver(&mut self, t: Real) -> Result<bool, CoreError> {
        let knots = self.rod.basis().knots();
        let Some(index) = knots.iter().position(|&k| k == t) else {
            return Ok(false);
        };
        let (start, end) = self.rod.basis().domain();
        let tolerance = SLIVER_TOLERANCE * (end - start);
        match self.remove_knot(index, tolerance) {
            Ok(()) => Ok(true),
            Err(CoreError::RemovalNotWithinTolerance { .. }) => Ok(false),
            Err(e) => Err(e),
        }
    }
}

//! The interaction criterion: wherever something acts on the rod at a material point —
//! a grab, a point force, a contact — the rod needs a knot there to bend locally. It
//! proposes a knot at each interaction coordinate `s` unless one lies within `radius`,
//! and vetoes removing knots within `radius` of an active interaction.

use crate::{AdaptError, Refinement, RefinementCriterion};
use splinerod_core::{Real, Rod};

/// Refines at interaction points and keeps them refined while the interaction lasts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InteractionCriterion {
    /// A knot closer than this (m of rest arclength) to an interaction is good enough.
    pub radius: Real,
}

impl InteractionCriterion {
    /// A criterion with the given `radius > 0` (m).
    pub fn new(radius: Real) -> Result<Self, AdaptError> {
        crate::error::positive("interaction_radius", radius)?;
        Ok(Self { radius })
    }

    fn knot_near(&self, rod: &Rod, s: Real) -> bool {
        let knots = rod.basis().knots();
        let i = knots.partition_point(|&t| t < s);
        let near = |j: usize| knots.get(j).is_some_and(|&t| (t - s).abs() <= self.radius);
        near(i) || (i > 0 && near(i - 1))
    }
}

impl RefinementCriterion for InteractionCriterion {
    fn name(&self) -> &str {
        "interaction"
    }

    fn mark(&self, rod: &Rod, interactions: &[Real], out: &mut Vec<Refinement>) {
        let (start, end) = rod.basis().domain();
        for &s in interactions {
            if s > start && s < end && !self.knot_near(rod, s) {
                out.push(Refinement::Insert { at: s });
            }
        }
    }

    fn vetoes_removal(&self, _rod: &Rod, interactions: &[Real], knot: Real) -> bool {
        interactions
            .iter()
            .any(|&s| (s - knot).abs() <= self.radius)
    }
}
